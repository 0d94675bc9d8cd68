"""The records the kernels pass around: a window's bounds, the resolved options, a piece.

Values that always travel together travel as one named tuple. Numba passes a named
tuple to a compiled function as its fields, one argument each, so a record costs
nothing at a call, and a record of scalars built inside a kernel (``Bounds(...)``) is
no more than its fields in registers. A record of arrays is borrowed like the arrays
it holds: a ``borrowing`` function (``rnsca.kernels.jit``) counts no references to
them either. Under ``NUMBA_DISABLE_JIT=1`` these are plain named tuples.

The host (``rnsca.backends.numba_cpu``) builds them once per call, with the field
types below, so each kernel compiles one specialisation.
"""

from typing import NamedTuple

__all__ = ["Bounds", "Options", "Piece"]


class Bounds(NamedTuple):
    """The clip window, closed: ``[xmin, xmax] x [ymin, ymax]``, finite, float64."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float


class Options(NamedTuple):
    """The resolved options of a segment clip (``rnsca.options.SegmentOptions``).

    Attributes
    ----------
    method : int
        The method id (``rnsca.kernels.segments.RNSCA``, ``COHEN_SUTHERLAND``, ...).
    n : int
        Pieces per subdivision, 2..64, or 0 for ``"auto"``.
    max_depth : int
        Deepest subdivision level, 0..32.
    tolerance : float
        A piece no longer than this is not subdivided further; may be infinite.
    auto_piece : float
        The piece length that ``n="auto"`` aims for (the window's longer side).
    exact : bool
        Exact mode (undecided leaves are clipped), else approx mode (they are dropped).
    """

    method: int
    n: int
    max_depth: int
    tolerance: float
    auto_piece: float
    exact: bool


class Piece(NamedTuple):
    """A piece ``[ta, tb]`` of a segment: its parameters, end points and ends' wide codes.

    The codes are wide codes (``rnsca.kernels.outcode``): an input end point has
    ``wide(outcode)``, an interpolated one ``wide_outcode``. Subdivision methods hand
    their undecided leaves to the leaf clip as a Piece.
    """

    ta: float
    xa: float
    ya: float
    ca: int
    tb: float
    xb: float
    yb: float
    cb: int
