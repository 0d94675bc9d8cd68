"""Many windows at once: the windows' table, and which segments or boxes each window gets.

`assign` pairs every segment with every window its bounding box touches, sorted by
window then segment, without a windows-by-segments loop (`rnsca.kernels.windows`): a
regular grid of windows is recognised (`grid_of`) and found by arithmetic on the edges;
any other set by a sweep over the windows sorted by ``xmin``. The backends clip the
pairs (`ClipBackend.clip_segment_windows`); both use this one assignment. Lines and
polygons are assigned by the bounding boxes of their geometries (`vertex_boxes`,
`assign_boxes`, the same kernels: a box is its own bounding box) and clipped with one
window per pair (`rnsca.clip_ragged(..., windows=)`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt

from rnsca.errors import InvalidWindowError
from rnsca.kernels import windows as K

__all__ = ["WindowPairs", "as_windows", "assign", "assign_boxes", "grid_of", "vertex_boxes",
           "window_finder"]


@dataclass(frozen=True, slots=True)
class WindowPairs:
    """The (segment, window) pairs to clip, sorted by window then segment.

    Attributes
    ----------
    segment : ndarray of int64, shape (p,)
        The segment (or, from `assign_boxes`, the box) of each pair.
    window_offsets : ndarray of int64, shape (k + 1,)
        Window ``w``'s pairs are ``window_offsets[w]:window_offsets[w + 1]``.
    """

    segment: np.ndarray
    window_offsets: np.ndarray

    def window(self) -> np.ndarray:
        """Return the window of each pair (int32: the device reads it so)."""
        k = self.window_offsets.shape[0] - 1
        return np.repeat(np.arange(k, dtype=np.int32), np.diff(self.window_offsets))


def as_windows(windows: npt.ArrayLike) -> np.ndarray:
    """Return `windows` as a checked float64 (k, 4) C-contiguous table.

    Raises
    ------
    InvalidWindowError
        For another shape, no windows, more than 2**31 - 1 of them, a bound that is not
        finite, or ``min >= max``; the message names the first bad row.
    """
    try:
        table = np.ascontiguousarray(windows, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidWindowError(
            f"windows must be a (k, 4) array of [xmin, ymin, xmax, ymax] rows, got "
            f"{windows!r:.80}") from None
    if table.ndim != 2 or table.shape[1] != 4 or table.shape[0] == 0:
        raise InvalidWindowError(
            f"windows must be a (k, 4) array of [xmin, ymin, xmax, ymax] rows, k >= 1; got "
            f"shape {table.shape}")
    if table.shape[0] >= 2**31:
        raise InvalidWindowError(f"at most 2**31 - 1 windows, got {table.shape[0]}")
    good = (np.isfinite(table).all(axis=1) & (table[:, 0] < table[:, 2])
            & (table[:, 1] < table[:, 3]))
    if not good.all():
        row = int(np.argmin(good))
        raise InvalidWindowError(
            f"window {row} {table[row].tolist()} must be finite with xmin < xmax and "
            "ymin < ymax")
    return table


def grid_of(windows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Return ``(xs, ys, cell_window)`` if the windows are exactly the cells of a grid.

    A grid: sorted distinct x edges ``xs`` and y edges ``ys`` such that the windows are
    the ``(len(xs) - 1) * (len(ys) - 1)`` cells ``[xs[c], ys[r], xs[c + 1], ys[r + 1]]``,
    each once, in any order; ``cell_window[r, c]`` is the window of cell (r, c).
    Otherwise None.
    """
    xs = np.unique(windows[:, [0, 2]])
    ys = np.unique(windows[:, [1, 3]])
    cols, rows = xs.shape[0] - 1, ys.shape[0] - 1
    if cols * rows != windows.shape[0]:
        return None
    c = np.searchsorted(xs, windows[:, 0])
    r = np.searchsorted(ys, windows[:, 1])
    if not (np.array_equal(xs[np.minimum(c + 1, cols)], windows[:, 2])
            and np.array_equal(ys[np.minimum(r + 1, rows)], windows[:, 3])
            and (c < cols).all() and (r < rows).all()):
        return None
    cell_window = np.full((rows, cols), -1, dtype=np.int64)
    cell_window[r, c] = np.arange(windows.shape[0])
    if (cell_window < 0).any():  # two windows on one cell
        return None
    return xs, ys, cell_window


def _equally_spaced(edges: np.ndarray) -> bool:
    """Return whether the arithmetic guess of a cell is within one of the right cell.

    Exactness does not depend on it (the kernel corrects the guess against the edges);
    speed does: for uneven edges the guess could be far off, and binary search is used.
    """
    steps = np.diff(edges)
    return bool(steps.size and np.ptp(steps) <= 1e-9 * steps.mean())


def window_finder(windows: np.ndarray) -> K.WindowFinder:
    """Return how `assign` finds the windows of a box: a grid's edges, or the sweep's order.

    `windows` is a table from `as_windows`. Small (the size of the table) and cheap: the
    OpenCL backend computes it here and runs the same search on the device, so the two
    find the same pairs.
    """
    grid = grid_of(windows)
    if grid is not None:
        xs, ys, cell_window = grid
        order = np.empty(0, dtype=np.int64)
        xmins = np.empty(0)
        widest = 0.0
    else:
        xs = ys = np.empty(0)
        cell_window = np.empty((0, 0), dtype=np.int64)
        order = np.argsort(windows[:, 0], kind="stable").astype(np.int64)
        xmins = np.ascontiguousarray(windows[order, 0])
        # Rounded up: a width rounded down (a window from -1e-67 to 1 is "1.0" wide) would
        # make the sweep miss the windows that reach furthest west.
        widest = float(np.nextafter((windows[:, 2] - windows[:, 0]).max(), np.inf))
    uniform = grid is not None and _equally_spaced(xs) and _equally_spaced(ys)
    # Cells per unit. On a grid a few subnormals wide it overflows to inf, which the
    # guess clamps to the last cell (and the edges correct): no warning for it.
    with np.errstate(over="ignore"):
        x_scale = (xs.shape[0] - 1) / (xs[-1] - xs[0]) if uniform else 0.0
        y_scale = (ys.shape[0] - 1) / (ys[-1] - ys[0]) if uniform else 0.0
    return K.WindowFinder(grid is not None, uniform, x_scale, y_scale, xs, ys, cell_window,
                          windows, order, xmins, widest)


def assign(segments: np.ndarray, windows: np.ndarray) -> WindowPairs:
    """Return the pairs of every segment with every window its box touches.

    `segments` is float64 (n, 4), finite; `windows` a table from `as_windows`.
    """
    k = windows.shape[0]
    finder = window_finder(windows)
    n = segments.shape[0]
    threads = max(1, min(numba.get_num_threads(), -(-n // 65536)))
    counts = np.zeros((threads, k), dtype=np.int64)
    K.assign_counts(segments, finder, threads, counts)
    per_window = counts.sum(axis=0)
    offsets = np.zeros(k + 1, dtype=np.int64)
    np.cumsum(per_window, out=offsets[1:])
    # Each (thread, window)'s first slot: window-major, threads in segment order.
    cursor = np.ascontiguousarray(offsets[:-1][None, :] + (np.cumsum(counts, axis=0) - counts))
    pairs = np.empty(int(offsets[-1]), dtype=np.int64)
    K.assign_write(segments, finder, threads, cursor, pairs)
    return WindowPairs(pairs, offsets)


def vertex_boxes(xy: np.ndarray, vertex_offsets: np.ndarray) -> np.ndarray:
    """Return the bounding box of each run of vertices, float64 (n, 4).

    `xy` is float64 (v, 2), finite; run ``g`` is ``xy[vertex_offsets[g]:vertex_offsets[g
    + 1]]`` (int64 offsets). An empty run's box is NaN: `assign_boxes` pairs it with no
    window.

    Examples
    --------
    >>> xy = np.array([[0.0, 1.0], [4.0, -1.0], [2.0, 2.0]])
    >>> vertex_boxes(xy, np.array([0, 3, 3])).tolist()
    [[0.0, -1.0, 4.0, 2.0], [nan, nan, nan, nan]]
    """
    boxes = np.empty((vertex_offsets.shape[0] - 1, 4))
    K.vertex_boxes(np.ascontiguousarray(xy[:, :2]), np.ascontiguousarray(vertex_offsets,
                                                                         dtype=np.int64), boxes)
    return boxes


def assign_boxes(boxes: np.ndarray, windows: np.ndarray) -> WindowPairs:
    """Return the pairs of every box with every window it touches (closed), by window.

    `boxes` is float64 (n, 4) ``[xmin, ymin, xmax, ymax]`` rows (NaN rows, empty
    geometries, touch nothing); `windows` a table from `as_windows`. The same assignment
    as `assign` (a box is its own bounding box): a grid by arithmetic on its edges, any
    other set by the sweep. Pairs are sorted by window, then box.

    Examples
    --------
    >>> windows = np.array([[0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 2.0, 1.0]])
    >>> pairs = assign_boxes(np.array([[0.5, 0.2, 1.5, 0.4], [1.2, 0.1, 1.3, 0.2]]), windows)
    >>> pairs.segment.tolist(), pairs.window_offsets.tolist()
    ([0, 0, 1], [0, 1, 3])
    """
    return assign(np.ascontiguousarray(boxes, dtype=np.float64), windows)
