"""Many windows at once: which segments each window gets, and the clip of those pairs.

Assignment (`assign_counts` then `assign_write`): each segment goes to every window its
bounding box touches (closed windows: a box that only touches an edge is a candidate;
the clip decides). Candidates are found without a windows-by-segments loop:

- a regular grid (the windows are the cells between sorted x edges and y edges, in any
  order): the column and row range of a box by binary search on the edges (the
  extended outcode of each end, as the paper names it);
- any other set: a sweep over the windows sorted by ``xmin`` (a box's candidates are
  the windows with ``xmin`` in ``[box.xmin - widest, box.xmax]``, found by binary
  search), then the exact box test.

The pairs come out sorted by window, then by segment, in two parallel passes: each
thread counts the pairs of its own chunk of segments per window, a window-major prefix
sum gives every (window, thread) its first slot, and each thread writes its pairs in
order (a stable counting sort, no sort call).

The per-segment helpers are inlined into the passes: called, they cost 145 ns a segment
(the finder's arrays passed on every call), inlined 43 ns (the count pass, 1M short
segments on a 32 x 32 grid, one thread).

`clip_pairs` clips the pairs, gathered so each window's segments are consecutive rows,
in blocks that never span two windows, with the segment kernel's block clip.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels.jit import borrowing, inlined, parallel, scalar
from rnsca.kernels.records import Window
from rnsca.kernels.segments import clip_block_rows

__all__ = ["WindowFinder", "assign_counts", "assign_write", "clip_pairs", "gather_rows",
           "vertex_boxes"]


@inlined
def _box(segments, i):
    x0, y0, x1, y1 = segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3]
    return min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1)


@borrowing
def _first_not_below(edges, value):
    """Return the first index of the sorted `edges` whose value is >= `value`."""
    lo, hi = 0, edges.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if edges[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@borrowing
def _first_above(edges, value):
    """Return the first index of the sorted `edges` whose value is > `value`."""
    lo, hi = 0, edges.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if edges[mid] <= value:
            lo = mid + 1
        else:
            hi = mid
    return lo


class WindowFinder(NamedTuple):
    """How a segment's candidate windows are found (`_visit`): a grid, or a sweep.

    Attributes
    ----------
    grid : bool
    uniform : bool
        The grid's edges are equally spaced: a coordinate's cell is found by arithmetic
        (``(x - xs[0]) * x_scale``, corrected against the edges), else by binary search.
    x_scale, y_scale : float
        Cells per unit (uniform grids).
    xs, ys : float64 (cols + 1,), (rows + 1,)
        The grid's sorted edges (grid only).
    cell_window : int64 (rows, cols)
        The window of each cell (grid only).
    windows : float64 (k, 4)
    order : int64 (k,)
        The windows sorted by xmin (sweep only).
    xmins : float64 (k,)
        Their xmin, in that order (sweep only).
    widest : float
        The largest window width (sweep only).
    """

    grid: bool
    uniform: bool
    x_scale: float
    y_scale: float
    xs: np.ndarray
    ys: np.ndarray
    cell_window: np.ndarray
    windows: np.ndarray
    order: np.ndarray
    xmins: np.ndarray
    widest: float


@inlined
def _guess(edges, value, scale):
    """Return the cell of `value` on equally spaced `edges` by arithmetic.

    A guess: the rounding may miss by one, which the callers correct against the edges.
    """
    cells = edges.shape[0] - 1
    g = (value - edges[0]) * scale
    if not g > 0.0:  # below the first edge, or NaN
        return 0
    if g >= cells - 1:
        return cells - 1
    return int(g)


@inlined
def _low_cell(edges, value, scale):
    """Return the first cell whose right edge is >= `value` (0 if none is below)."""
    g = _guess(edges, value, scale)
    while g > 0 and edges[g] >= value:
        g -= 1
    while g < edges.shape[0] - 2 and edges[g + 1] < value:
        g += 1
    return g


@inlined
def _high_cell(edges, value, scale):
    """Return the last cell whose left edge is <= `value` (-1 if none)."""
    g = _guess(edges, value, scale)
    while g < edges.shape[0] - 2 and edges[g + 1] <= value:
        g += 1
    while g >= 0 and edges[g] > value:
        g -= 1
    return g


@inlined
def _visit(segments, i, finder, table, t, pairs, write):
    """Count segment `i`'s pairs in ``table[t, w]`` or (`write`) write them.

    Writing, ``table[t, w]`` is thread `t`'s next slot of window `w` in `pairs`.
    """
    bx0, by0, bx1, by1 = _box(segments, i)
    if finder.grid:
        xs = finder.xs
        ys = finder.ys
        cols = xs.shape[0] - 1
        rows = ys.shape[0] - 1
        # Columns c with xs[c] <= bx1 and xs[c + 1] >= bx0 (closed cells).
        if finder.uniform:
            c0 = _low_cell(xs, bx0, finder.x_scale)
            c1 = _high_cell(xs, bx1, finder.x_scale)
            r0 = _low_cell(ys, by0, finder.y_scale)
            r1 = _high_cell(ys, by1, finder.y_scale)
        else:
            c0 = max(_first_not_below(xs, bx0) - 1, 0)
            c1 = min(_first_above(xs, bx1) - 1, cols - 1)
            r0 = max(_first_not_below(ys, by0) - 1, 0)
            r1 = min(_first_above(ys, by1) - 1, rows - 1)
        for r in range(r0, r1 + 1):
            for c in range(c0, c1 + 1):
                if xs[c] <= bx1 and xs[c + 1] >= bx0 and ys[r] <= by1 and ys[r + 1] >= by0:
                    _take(table, t, finder.cell_window[r, c], pairs, i, write)
        return
    # Sweep: the windows sorted by xmin; candidates have xmin in [bx0 - widest, bx1].
    windows = finder.windows
    hi = _first_above(finder.xmins, bx1)
    # One ulp below the rounded difference: never above the exact bx0 - widest.
    lo = _first_not_below(finder.xmins, np.nextafter(bx0 - finder.widest, -np.inf))
    for s in range(lo, hi):
        w = finder.order[s]
        if (windows[w, 0] <= bx1 and windows[w, 2] >= bx0 and windows[w, 1] <= by1
                and windows[w, 3] >= by0):
            _take(table, t, w, pairs, i, write)


@inlined
def _take(table, t, w, pairs, i, write):
    if write:
        pairs[table[t, w]] = i
    table[t, w] += 1


@parallel
def assign_counts(segments, finder, n_threads, counts):
    """Count each thread's pairs per window: ``counts[t, w]`` (zeroed by the caller)."""
    nowhere = np.empty(0, dtype=np.int64)
    for t in prange(n_threads):
        _assign_share(segments, finder, np.int64(t), n_threads, counts, nowhere, False)


@parallel
def assign_write(segments, finder, n_threads, cursor, pairs):
    """Write each pair's segment at its slot.

    `cursor` holds each (thread, window)'s first slot (a window-major exclusive prefix
    sum of the counts) and is advanced.
    """
    for t in prange(n_threads):
        _assign_share(segments, finder, np.int64(t), n_threads, cursor, pairs, True)


@inlined
def _assign_share(segments, finder, t, n_threads, table, pairs, write):
    """Count or write the pairs of thread `t`'s share of the segments, in order."""
    n = segments.shape[0]
    for i in range(t * n // n_threads, (t + 1) * n // n_threads):
        _visit(segments, i, finder, table, t, pairs, write)


@parallel
def gather_rows(source, rows, target):
    """Set ``target[j] = source[rows[j]]`` for 2-D rows, on every core.

    (NumPy's fancy indexing runs on one.)
    """
    columns = source.shape[1]
    for j in prange(rows.shape[0]):
        r = rows[j]
        for c in range(columns):
            target[j, c] = source[r, c]


@scalar
def _clip_pair_block(blk, segments, windows, block_window, block_first, block_end, options,
                     out):
    """Clip the rows ``block_first[blk]:block_end[blk]`` to window ``block_window[blk]``.

    As `segments._clip_block` does, from row ``out.block_start[blk]`` on.
    """
    w = block_window[blk]
    clip_block_rows(blk, segments, block_first[blk], block_end[blk],
                    Window(windows[w, 0], windows[w, 1], windows[w, 2], windows[w, 3]),
                    options, out)


@scalar
def _clip_pair_chunk(chunk, n_chunks, segments, windows, block_window, block_first,
                     block_end, options, out):
    """Clip the blocks of one chunk in order, their pieces one after another.

    From the chunk's first block's first row on.
    """
    n_blocks = block_window.shape[0]
    first = chunk * n_blocks // n_chunks
    last = (chunk + 1) * n_blocks // n_chunks
    if first >= last:
        return
    k = block_first[first]
    for blk in range(first, last):
        out.block_start[blk] = k
        _clip_pair_block(blk, segments, windows, block_window, block_first, block_end,
                         options, out)
        k += max(out.block_count[blk], 0)


@parallel
def clip_pairs(segments, windows, block_window, block_first, block_end, options, n_chunks,
               out):
    """Clip every block of pairs, one prange iteration per chunk of consecutive blocks.

    `segments` holds the pairs' segments gathered (row j: pair j's segment), so a
    window's pairs are consecutive rows; each block lies in one window. A chunk writes
    its pieces one after another from its first block's first row (a pair gives at most
    one piece), as `segments.clip_segment_blocks` does; the caller compacts. The body is
    one call, as there: with the chunk's loop written in the prange body, Numba's
    parfor lowering (0.68) passed the wrong arrays to the block clip (block_start got
    block_end's values; memory was corrupted).
    """
    for chunk in prange(n_chunks):
        _clip_pair_chunk(np.int64(chunk), n_chunks, segments, windows, block_window,
                         block_first, block_end, options, out)


@parallel
def vertex_boxes(xy, vertex_offsets, boxes):
    """Write the bounding box of each run of vertices into ``boxes[g]``.

    Run ``g`` is ``xy[vertex_offsets[g]:vertex_offsets[g + 1]]``; an empty run's box is
    NaN (no window's box test passes with it). ``boxes`` is float64 (n, 4), rows
    ``[xmin, ymin, xmax, ymax]``: a box is its own bounding box, so the assignment
    (`assign_counts`, `assign_write`) takes it as it takes a segment.
    """
    for g in prange(vertex_offsets.shape[0] - 1):
        first = vertex_offsets[g]
        last = vertex_offsets[g + 1]
        if first == last:
            for c in range(4):
                boxes[g, c] = np.nan
            continue
        x0 = x1 = xy[first, 0]
        y0 = y1 = xy[first, 1]
        for v in range(first + 1, last):
            x = xy[v, 0]
            y = xy[v, 1]
            if x < x0:
                x0 = x
            elif x > x1:
                x1 = x
            if y < y0:
                y0 = y
            elif y > y1:
                y1 = y
        boxes[g, 0] = x0
        boxes[g, 1] = y0
        boxes[g, 2] = x1
        boxes[g, 3] = y1
