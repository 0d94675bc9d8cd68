"""The public clipping functions: validate, dispatch to a backend, nothing else."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnsca.backends.registry import get_backend
from rnsca.errors import InvalidGeometryError
from rnsca.kernels.validate import first_invalid_segment
from rnsca.options import Backend, Method, Mode, SegmentOptions
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["SegmentClipResult", "clip_segments", "as_segments"]


@dataclass(frozen=True, slots=True)
class SegmentClipResult:
    """The visible pieces of clipped segments.

    Attributes
    ----------
    segments : ndarray of float64, shape (m, 4)
        ``[x0, y0, x1, y1]`` of each piece, in input order and direction, inside the window.
    source : ndarray of int64, shape (m,)
        Index of the input segment each piece came from (strictly increasing).
    t : ndarray of float64, shape (m, 2)
        Parameter interval ``[t0, t1]`` of each piece on its source segment, where
        ``P(t) = P0 + t (P1 - P0)``; use it to interpolate attributes.
    stats : ClipStats
    method, mode, backend : Method, Mode, Backend
        What ran.
    options : SegmentOptions
        The resolved options (defaults filled in).
    """

    segments: np.ndarray
    source: np.ndarray
    t: np.ndarray
    stats: ClipStats
    method: Method
    mode: Mode
    backend: Backend
    options: SegmentOptions

    def __len__(self) -> int:
        return self.segments.shape[0]


def as_segments(segments) -> np.ndarray:
    """Return `segments` as a validated float64 (n, 4) C-contiguous array.

    Accepts (n, 4) ``[x0, y0, x1, y1]`` rows or (n, 2, 2) ``[[x0, y0], [x1, y1]]``, of any
    real numeric dtype (converted to float64).

    Raises
    ------
    InvalidGeometryError
        (a ValueError) for another shape or dtype, a NaN or infinite coordinate, or a
        segment whose coordinate differences overflow float64; the message names the
        first bad row.
    """
    try:
        array = np.asarray(segments)
    except (TypeError, ValueError) as exc:
        raise InvalidGeometryError(f"segments must be a numeric array: {exc}") from None
    if array.dtype.kind not in "iuf":
        raise InvalidGeometryError(
            f"segments must have a real numeric dtype (float64 preferred), got {array.dtype}")
    if array.ndim == 3 and array.shape[1:] == (2, 2):
        array = array.reshape(array.shape[0], 4)
    elif array.ndim == 1 and array.shape[0] == 0:
        array = array.reshape(0, 4)
    elif not (array.ndim == 2 and array.shape[1] == 4):
        raise InvalidGeometryError(
            f"segments must have shape (n, 4) or (n, 2, 2), got {array.shape}")
    array = np.ascontiguousarray(array, dtype=np.float64)
    row = int(first_invalid_segment(array))
    if row >= 0:
        values = array[row].tolist()
        if not np.isfinite(array[row]).all():
            raise InvalidGeometryError(f"segment {row} has a non-finite coordinate: {values}")
        raise InvalidGeometryError(
            f"segment {row} spans more than float64 can hold (x1 - x0 or y1 - y0 overflows): "
            f"{values}")
    return array


def clip_segments(segments, window, *, method="rnsca", n="auto", max_depth=None,
                  tolerance=None, mode="exact", backend="numba") -> SegmentClipResult:
    """Return the parts of line segments inside a closed rectangular window.

    Each segment gives at most one piece (the window is convex). Boundary rules, the
    same for every method: a segment lying on an edge is inside; a segment that only
    touches the window at one point gives no piece; a zero-length segment inside is
    kept; no output coordinate lies outside the window.

    Parameters
    ----------
    segments : array_like, shape (n, 4) or (n, 2, 2)
        ``[x0, y0, x1, y1]`` per segment; finite; converted to float64.
    window : Window or sequence of 4 floats
        ``(xmin, ymin, xmax, ymax)``.
    method : {"rnsca", "cohen_sutherland", "liang_barsky", "nicholl_lee_nicholl", "midpoint"}
    n : int in 2..64 or "auto"
        Pieces per subdivision (RNSCA). ``"auto"`` picks it per piece from the piece's
        length and the window's size (see README, "Choosing N").
    max_depth : int in 0..32, default 32
        Deepest subdivision level (RNSCA, midpoint).
    tolerance : float > 0 (may be inf), optional
        A piece no longer than this is a leaf. Default: ``1e-9 * window.size`` in approx
        mode; infinite in exact mode, where splitting cannot save the clip at a boundary
        crossing, so every segment is decided at level 0 (see README, "Exact mode").
    mode : {"exact", "approx"}
        What happens to undecided leaves: clipped with Liang–Barsky, or dropped. In
        approx mode the length lost at each boundary crossing is at most one leaf,
        ``max(tolerance, length / 2**max_depth)``-ish; see README, "Approx mode".
        The analytic methods (Cohen–Sutherland, Liang–Barsky, NLN) are always exact.
    backend : {"numba", "numpy"}

    Returns
    -------
    SegmentClipResult

    Raises
    ------
    InvalidGeometryError, InvalidWindowError, InvalidOptionError
        (all ValueError) naming what is wrong.
    BackendUnavailableError
        If `backend` cannot run here.

    Examples
    --------
    >>> r = clip_segments([[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0]], (0, 0, 10, 10))
    >>> r.segments.tolist(), r.source.tolist(), r.t.tolist()
    ([[0.0, 5.0, 10.0, 5.0]], [0], [[0.25, 0.75]])
    """
    window = Window.of(window)
    options = SegmentOptions.resolve(window, method=method, n=n, max_depth=max_depth,
                                     tolerance=tolerance, mode=mode)
    engine = get_backend(backend)
    array = as_segments(segments)
    pieces, source, t, stats = engine.clip_segments(array, window, options)
    return SegmentClipResult(pieces, source, t, stats, options.method, options.mode,
                             engine.kind, options)
