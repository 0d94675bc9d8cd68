"""Records the kernels pass around: named tuples of arrays and scalars.

Values that travel together (a window's four bounds, the segment core's six options,
a geometry's coordinates and offsets) go into one record instead of one parameter each.
Numba passes a named tuple by its members: a call that is not inlined receives them as
separate arguments (no allocation, no indirection), and an inlined helper reads a member
as it would a local. A record of arrays keeps what the jit preset of the function it is
given to says of arrays (`rnsca.kernels.jit`): a ``borrowing`` function counts no
references to them, a ``scalar`` one counts each, as it would the arrays passed one by one.
Records are immutable; what a kernel writes goes into the arrays they hold.

Built on the host (the backends) or in the kernels, and under ``NUMBA_DISABLE_JIT=1``
they are plain named tuples. Scalars must have one type per field wherever a record is
built (float64 bounds, int64 counts), or the kernels compile once per mix. A record a
``prange`` loop reads must be flat (arrays and scalars only: Numba's parallel lowering
refuses a record inside a record) and built outside the loop (Numba 0.68 fails to lower
one built inside); the loop body hands it to a per-block function, which may nest it.

Numba's on-disk cache names each record class in its index: after renaming or removing
one, a stale index fails to load (``AttributeError: Can't get attribute ...`` at the
first call, numba#6018), so clear the cache (``find rnsca -name '*.nb[ic]' -delete``).
"""

from typing import NamedTuple

import numpy as np

from rnsca.kernels.jit import inlined

__all__ = ["CoreOptions", "Direction", "Fragment", "Vertices", "Window", "WindowRows", "vertices",
           "window_of"]


class Window(NamedTuple):
    """The closed clip window ``[xmin, xmax] x [ymin, ymax]`` (float64 bounds)."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float


class CoreOptions(NamedTuple):
    """The segment core's resolved options (`segments.rnsca_segment`, `segments.clip_one`)."""

    method: int         #: method id (`segments.RNSCA`, ...)
    n_fixed: int        #: N, or 0 for auto
    max_depth: int      #: deepest subdivision level
    tol: float          #: pieces no longer than this are leaves
    exact: bool         #: clip undecided leaves exactly (else drop them: approx mode)


class Vertices(NamedTuple):
    """Input coordinates: ``xy`` (n, 2) float64 C-contiguous, `flat` the same as one row.

    `flat` is ``xy.reshape(-1)``: copies run over views of it from index 0, which LLVM
    vectorizes. `z` is float64 (n,), or empty when `has_z` is False.
    """

    xy: np.ndarray
    flat: np.ndarray
    z: np.ndarray
    has_z: bool


def vertices(xy, z):
    """Return the `Vertices` of `xy` and `z` (host side: kernels get it built)."""
    return Vertices(xy, xy.reshape(-1), z, z.shape[0] > 0)


class WindowRows(NamedTuple):
    """The window of each of many items: a table of windows and the row of each item.

    The kernels' form of `rnsca.window.WindowTable`: item ``g`` (a path, a geometry) is
    clipped against ``window_of(rows.bounds, rows.index, g)``.
    """

    bounds: np.ndarray  # float64 (w, 4): [xmin, ymin, xmax, ymax] rows
    index: np.ndarray   # int64 (n,): the row of each item, or empty: row 0 for all


@inlined
def window_of(windows, index, g):
    """Return the `Window` geometry `g` is clipped against: row ``index[g]`` of `windows`.

    `windows` is float64 (w, 4), ``[xmin, ymin, xmax, ymax]`` rows; `index` int64, the
    row of each geometry (or part, or polygon), or empty: row 0 for all.
    """
    w = index[g] if index.shape[0] > 0 else 0
    return Window(windows[w, 0], windows[w, 1], windows[w, 2], windows[w, 3])


class Fragment(NamedTuple):
    """A fragment ``[ta, tb]`` of a segment: its parameters, end points and ends' wide codes.

    The codes are wide codes (``rnsca.kernels.outcode``): an input end point has
    ``wide(outcode)``, an interpolated one `wide_outcode`. The subdivision methods
    (RNSCA, midpoint) keep their pending fragments in this form and hand their undecided
    leaves to the leaf clip (`liang_barsky.liang_barsky_leaf`) as one.
    """

    ta: float
    xa: float
    ya: float
    ca: int
    tb: float
    xb: float
    yb: float
    cb: int


class Direction(NamedTuple):
    """A segment's direction ``P1 - P0``, each component rounded, with its rounding error.

    ``dx + dx_err == x1 - x0`` exactly, likewise for y (`outcode.direction`): the
    subdivision methods interpolate points along it (`outcode.interpolated_point`).
    """

    dx: float
    dx_err: float
    dy: float
    dy_err: float
