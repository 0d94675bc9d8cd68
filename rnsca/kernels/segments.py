"""RNSCA for line segments, and the parallel driver that runs every segment method.

The Recursive N-Subdivision Clipping Algorithm splits a segment into N pieces, gives
each piece end a Cohen–Sutherland outcode, accepts pieces with both codes zero, rejects
pieces whose codes share a bit, and recurses into the remaining (ambiguous) pieces until
they are decided, reach `max_depth`, or are no longer than `tol`. An undecided leaf is
clipped with Liang–Barsky (exact mode) or dropped (approx mode). The recursion is an
explicit stack, so the same logic ports to OpenCL.

Because the window is convex, the accepted pieces and clipped leaves of one segment form
one interval; the kernel merges them and returns at most one piece per segment.
"""

import math

import numpy as np
from numba import prange

# Method ids, N's bounds and the stack size are defined in rnsca.constants (shared with
# clip.cl and the service); importable from here as before.
from rnsca.constants import (
    AUTO_N_MIN,
    COHEN_SUTHERLAND,
    LIANG_BARSKY,
    N_MAX,
    NICHOLL_LEE_NICHOLL,
    RNSCA,
    STACK_CAPACITY,
)
from rnsca.constants import MIDPOINT as MIDPOINT  # re-exported (the driver's default case)
from rnsca.kernels import counters as C
from rnsca.kernels.cohen_sutherland import cohen_sutherland_segment
from rnsca.kernels.jit import borrowing, parallel, scalar
from rnsca.kernels.liang_barsky import (
    count_divisions,
    leaf_cut,
    liang_barsky_leaf,
    liang_barsky_segment,
)
from rnsca.kernels.midpoint import midpoint_segment
from rnsca.kernels.nicholl_lee_nicholl import nicholl_lee_nicholl_segment
from rnsca.kernels.outcode import (
    BOTTOM,
    LEFT,
    NO_EDGE,
    RIGHT,
    SURE_SHIFT,
    TOP,
    UNSURE_BITS,
    clamp,
    direction_error,
    end_point,
    interpolated_point,
    is_piece,
    outcode,
    wide,
    wide_outcode,
)

# Stack rows: floats (ta, tb, xa, ya, xb, yb); ints (ca, cb, level).
_TA, _TB, _XA, _YA, _XB, _YB = 0, 1, 2, 3, 4, 5
_CA, _CB, _LEVEL = 0, 1, 2


@scalar
def auto_n(piece_length, auto_piece):
    """Return the ``n="auto"`` split count: ``ceil(length / auto_piece)`` clamped to 8..64.

    `auto_piece` is the window's longer side. A piece much longer than the window is
    cut into window-sized pieces in one step, so those far from the window are rejected
    at once; shorter pieces are cut in eight.
    """
    if not piece_length > AUTO_N_MIN * auto_piece:
        return AUTO_N_MIN  # the common case, without the division
    k = piece_length / auto_piece  # capped as a float: ceil of 2**63 would wrap around
    return N_MAX if k > N_MAX else int(math.ceil(k))


@borrowing
def _clip_leaf(x0, y0, x1, y1, ta, tb, xa, ya, xb, yb, flags, xmin, ymin, xmax, ymax, st):
    """Clip the leaf [ta, tb] (ends (xa, ya), (xb, yb)); return (ok, u0, ax, ay, u1, bx, by)."""
    ok, u0, ax, ay, u1, bx, by, divisions = liang_barsky_leaf(
        x0, y0, x1, y1, ta, tb, xa, ya, xb, yb, flags, xmin, ymin, xmax, ymax)
    st[C.INTERSECTIONS] += divisions
    return ok and is_piece(False, u0, u1, ax, ay, bx, by), u0, ax, ay, u1, bx, by


@borrowing
def rnsca_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol, auto_piece,
                  exact, st, stack_f, stack_i):
    """Clip one segment with RNSCA; return (keep, t0, t1, ax, ay, bx, by).

    `n_fixed` is N, or 0 for auto (see `auto_n`); `stack_f` (STACK_CAPACITY, 6) and
    `stack_i` (STACK_CAPACITY, 3) are scratch space owned by the caller's block.
    """
    dx = x1 - x0
    dy = y1 - y0
    c0 = outcode(x0, y0, xmin, ymin, xmax, ymax)
    c1 = outcode(x1, y1, xmin, ymin, xmax, ymax)
    st[C.EVALUATED] += 1
    if (c0 | c1) == 0:
        st[C.ACCEPTED] += 1
        st[C.LEVELS] += 1
        return True, 0.0, 1.0, x0, y0, x1, y1
    if c0 & c1:
        st[C.REJECTED] += 1
        st[C.LEVELS] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    length = math.hypot(dx, dy)
    # The merged interval and its end points.
    lo_t = math.inf
    lo_x = lo_y = 0.0
    hi_t = -math.inf
    hi_x = hi_y = 0.0
    if max_depth == 0 or length <= tol:
        # The whole segment is the leaf.
        st[C.LEVELS] += 1
        if not exact:
            st[C.DROPPED] += 1
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        st[C.CLIPPED] += 1
        ok, u0, ax, ay, u1, bx, by = _clip_leaf(x0, y0, x1, y1, 0.0, 1.0, x0, y0, x1, y1,
                                                c0 | c1, xmin, ymin, xmax, ymax, st)
        return ok, u0, u1, ax, ay, bx, by
    st[C.SUBDIVIDED] += 1
    stack_f[0, _TA] = 0.0
    stack_f[0, _TB] = 1.0
    stack_f[0, _XA] = x0
    stack_f[0, _YA] = y0
    stack_f[0, _XB] = x1
    stack_f[0, _YB] = y1
    # Children's ends are interpolated: classify them with wide codes (see outcode.py).
    _, dx_err = direction_error(x1, x0)
    _, dy_err = direction_error(y1, y0)
    stack_i[0, _CA] = wide(c0)
    stack_i[0, _CB] = wide(c1)
    stack_i[0, _LEVEL] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        ta = stack_f[sp, _TA]
        tb = stack_f[sp, _TB]
        xb = stack_f[sp, _XB]
        yb = stack_f[sp, _YB]
        cb = stack_i[sp, _CB]
        level = stack_i[sp, _LEVEL] + 1
        step = tb - ta
        n = n_fixed if n_fixed > 0 else auto_n(step * length, auto_piece)
        # Walk the n children left to right; (pt, px, py, pc) is the current child's start.
        pt = ta
        px = stack_f[sp, _XA]
        py = stack_f[sp, _YA]
        pc = stack_i[sp, _CA]
        if level > st[C.DEEPEST]:
            st[C.DEEPEST] = level
        for j in range(1, n + 1):
            if j == n:
                t, x, y, c = tb, xb, yb, cb
            else:
                t = ta + step * j / n
                x, y, cx, mx, cy, my = interpolated_point(x0, y0, dx, dx_err, dy, dy_err, t)
                c = wide_outcode(x, y, cx, mx, cy, my, xmin, ymin, xmax, ymax)
                # Ends of accepted pieces are output: give them the corrected position.
                x += cx
                y += cy
            st[C.EVALUATED] += 1
            if (pc | c) == 0:
                st[C.ACCEPTED] += 1
                st[C.LEVELS + level] += 1
                # A child of zero width (t no longer resolves the piece, on a segment some
                # 1e16 windows long) carries no length: its rounded point must not stand
                # in for an end that a clipped leaf computes exactly.
                if pt < t and pt < lo_t:
                    lo_t, lo_x, lo_y = pt, px, py
                if pt < t and t > hi_t:
                    hi_t, hi_x, hi_y = t, x, y
            elif (pc & c) >> SURE_SHIFT:
                st[C.REJECTED] += 1
                st[C.LEVELS + level] += 1
            elif (level >= max_depth or (t - pt) * length <= tol or pc == c
                  or sp >= STACK_CAPACITY):
                # A leaf; ``pc == c``: both ends within rounding of the same edges (the
                # child hugs the boundary), which splitting could not resolve.
                st[C.LEVELS + level] += 1
                if exact:
                    st[C.CLIPPED] += 1
                    ok, u0, ax, ay, u1, bx, by = _clip_leaf(x0, y0, x1, y1, pt, t, px, py, x, y,
                                                            (pc | c) & UNSURE_BITS,
                                                            xmin, ymin, xmax, ymax, st)
                    if ok:
                        if u0 < lo_t:
                            lo_t, lo_x, lo_y = u0, ax, ay
                        if u1 > hi_t:
                            hi_t, hi_x, hi_y = u1, bx, by
                else:
                    st[C.DROPPED] += 1
            else:
                st[C.SUBDIVIDED] += 1
                stack_f[sp, _TA] = pt
                stack_f[sp, _TB] = t
                stack_f[sp, _XA] = px
                stack_f[sp, _YA] = py
                stack_f[sp, _XB] = x
                stack_f[sp, _YB] = y
                stack_i[sp, _CA] = pc
                stack_i[sp, _CB] = c
                stack_i[sp, _LEVEL] = level
                sp += 1
            pt, px, py, pc = t, x, y, c
    if not lo_t <= hi_t:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return is_piece(False, lo_t, hi_t, lo_x, lo_y, hi_x, hi_y), lo_t, hi_t, lo_x, lo_y, hi_x, hi_y


@scalar
def clip_one(method, x0, y0, x1, y1, xmin, ymin, xmax, ymax, max_depth, tol, exact, st):
    """Clip one segment with the baseline of id `method`; return (keep, t0, t1, ax, ay, bx, by).

    RNSCA is not here: it runs block-wise (`_rnsca_block`).
    """
    if method == COHEN_SUTHERLAND:
        return cohen_sutherland_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st)
    if method == LIANG_BARSKY:
        return liang_barsky_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st)
    if method == NICHOLL_LEE_NICHOLL:
        return nicholl_lee_nicholl_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st)
    return midpoint_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, max_depth, tol, exact, st)


@scalar
def _write_piece(out_segments, out_source, out_t, k, i, t0, t1, ax, ay, bx, by,
                 xmin, ymin, xmax, ymax):
    """Write piece `k`: segment `i`'s interval [t0, t1], ends clamped into the window."""
    out_segments[k, 0] = clamp(ax, xmin, xmax)
    out_segments[k, 1] = clamp(ay, ymin, ymax)
    out_segments[k, 2] = clamp(bx, xmin, xmax)
    out_segments[k, 3] = clamp(by, ymin, ymax)
    out_source[k] = i
    out_t[k, 0] = t0
    out_t[k, 1] = t1


@scalar
def _rnsca_block(segments, first, last, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol,
                 auto_piece, exact, st, write, k, out_segments, out_source, out_t):
    """Clip segments ``first:last`` with RNSCA; return the next output row.

    Most segments are decided at level 0: accepted, rejected, or (short enough) a
    leaf. That case runs as a few simple branch-free loops over the block, one per
    step, on block-sized scratch columns that stay in cache: loops LLVM vectorizes.
    Segments that need splitting are marked and go through the depth-first
    `rnsca_segment`. Results are then counted or written in input order.
    """
    size = last - first
    x0 = np.empty(size)
    y0 = np.empty(size)
    x1 = np.empty(size)
    y1 = np.empty(size)
    flags = np.empty(size, dtype=np.int64)
    rejected = np.empty(size, dtype=np.bool_)
    ambiguous = np.empty(size, dtype=np.bool_)
    split = np.empty(size, dtype=np.bool_)
    u0 = np.empty(size)
    e0 = np.empty(size, dtype=np.int64)
    u1 = np.empty(size)
    e1 = np.empty(size, dtype=np.int64)
    ax = np.empty(size)
    ay = np.empty(size)
    bx = np.empty(size)
    by = np.empty(size)
    n_accepted = n_rejected = n_clipped = n_dropped = n_divisions = 0
    # Level 0: classify, mark the segments to split, and start each leaf at [0, 1].
    for j in range(size):
        i = first + j
        x0[j] = segments[i, 0]
        y0[j] = segments[i, 1]
        x1[j] = segments[i, 2]
        y1[j] = segments[i, 3]
        c0 = outcode(segments[i, 0], segments[i, 1], xmin, ymin, xmax, ymax)
        c1 = outcode(segments[i, 2], segments[i, 3], xmin, ymin, xmax, ymax)
        reject = (c0 & c1) != 0
        amb = (not reject) & ((c0 | c1) != 0)
        # |dx| + |dy| >= length: a cheap test that the segment may need splitting.
        spl = amb & (max_depth > 0) & (abs(x1[j] - x0[j]) + abs(y1[j] - y0[j]) > tol)
        clip = amb & exact & (not spl)
        # An accepted segment has no flagged edge, so the leaf clip returns it whole.
        flags[j] = (c0 | c1) if clip else 0
        rejected[j] = reject
        ambiguous[j] = amb
        split[j] = spl
        u0[j] = 0.0
        e0[j] = NO_EDGE
        u1[j] = 1.0
        e1[j] = NO_EDGE
        n_accepted += 0 if reject | amb else 1
        n_rejected += 1 if reject else 0
        n_clipped += 1 if clip else 0
        n_dropped += 1 if amb & (not exact) & (not spl) else 0
        n_divisions += count_divisions(flags[j])
    decided = n_accepted + n_rejected + n_clipped + n_dropped
    st[C.EVALUATED] += decided
    st[C.LEVELS] += decided
    st[C.ACCEPTED] += n_accepted
    st[C.REJECTED] += n_rejected
    st[C.CLIPPED] += n_clipped
    st[C.DROPPED] += n_dropped
    st[C.INTERSECTIONS] += n_divisions
    # The leaf clip (Liang–Barsky on the flagged edges), one edge at a time.
    for bit in (LEFT, RIGHT, BOTTOM, TOP):
        for j in range(size):
            u0[j], e0[j], u1[j], e1[j] = leaf_cut(
                bit, flags[j], u0[j], e0[j], u1[j], e1[j],
                x0[j], y0[j], x1[j], y1[j], xmin, ymin, xmax, ymax)
    keep = np.empty(size, dtype=np.bool_)
    for j in range(size):
        # Each end once: a cut end is computed in double-double here, not per edge.
        ax[j], ay[j] = end_point(x0[j], y0[j], x1[j], y1[j], e0[j], x0[j], y0[j],
                                 xmin, ymin, xmax, ymax)
        bx[j], by[j] = end_point(x0[j], y0[j], x1[j], y1[j], e1[j], x1[j], y1[j],
                                 xmin, ymin, xmax, ymax)
        keep[j] = (u0[j] <= u1[j]) & (not rejected[j]) & (exact | (not ambiguous[j])) & is_piece(
            (x0[j] == x1[j]) & (y0[j] == y1[j]), u0[j], u1[j], ax[j], ay[j], bx[j], by[j])
    # Deeper levels, for the few segments that need them.
    stack_f = np.empty((STACK_CAPACITY, 6), dtype=np.float64)
    stack_i = np.empty((STACK_CAPACITY, 3), dtype=np.int64)
    for j in range(size):
        if split[j]:
            i = first + j
            keep[j], u0[j], u1[j], ax[j], ay[j], bx[j], by[j] = rnsca_segment(
                segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3],
                xmin, ymin, xmax, ymax, n_fixed, max_depth, tol, auto_piece, exact,
                st, stack_f, stack_i)
    # Compact the kept rows' indices without branches (the slot past the last kept row
    # is always inside the scratch), then copy those rows out.
    kept = np.empty(size, dtype=np.int64)
    count = 0
    for j in range(size):
        kept[count] = j
        count += 1 if keep[j] else 0
    if write:
        for r in range(count):
            j = kept[r]
            _write_piece(out_segments, out_source, out_t, k + r, first + j, u0[j], u1[j],
                         ax[j], ay[j], bx[j], by[j], xmin, ymin, xmax, ymax)
    return k + count


@scalar
def _clip_block(blk, segments, xmin, ymin, xmax, ymax, method, n_fixed, max_depth, tol,
                auto_piece, exact, block_size, write, block_start,
                out_segments, out_source, out_t, block_count, counters):
    """Count or write block `blk`'s pieces: the one body both drivers run."""
    st = counters[blk]
    first = blk * block_size
    last = min(first + block_size, segments.shape[0])
    k = block_start[blk]
    if method == RNSCA:
        k = _rnsca_block(segments, first, last, xmin, ymin, xmax, ymax, n_fixed,
                         max_depth, tol, auto_piece, exact, st, write, k,
                         out_segments, out_source, out_t)
    else:
        for i in range(first, last):
            keep, t0, t1, ax, ay, bx, by = clip_one(
                method, segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3],
                xmin, ymin, xmax, ymax, max_depth, tol, exact, st)
            if keep:
                if write:
                    _write_piece(out_segments, out_source, out_t, k, i, t0, t1,
                                 ax, ay, bx, by, xmin, ymin, xmax, ymax)
                k += 1
    block_count[blk] = k - block_start[blk]


@parallel
def clip_segment_blocks(segments, xmin, ymin, xmax, ymax, method, n_fixed, max_depth, tol,
                        auto_piece, exact, block_size, write, block_start,
                        out_segments, out_source, out_t, block_count, counters):
    """Clip every segment, one prange iteration per block of `block_size` segments.

    Run twice over one body: with ``write=False`` it fills `block_count` (pieces per
    block) and `counters` (one row per block); with ``write=True`` it writes block
    ``k``'s pieces from ``block_start[k]`` on. Each iteration writes only its own block's
    slots, so the passes are race-free and always agree.

    Parameters
    ----------
    segments : float64 (n, 4), C-contiguous, finite, with finite differences.
    block_start : int64 (n_blocks,), exclusive prefix sum of the counts (write pass).
    out_segments, out_source, out_t : float64 (m, 4), int64 (m,), float64 (m, 2).
    block_count : int64 (n_blocks,); counters : int64 (n_blocks, counters.WIDTH).
    """
    for blk in prange(block_count.shape[0]):
        _clip_block(blk, segments, xmin, ymin, xmax, ymax, method, n_fixed, max_depth, tol,
                    auto_piece, exact, block_size, write, block_start,
                    out_segments, out_source, out_t, block_count, counters)


@scalar
def clip_segment_blocks_serial(segments, xmin, ymin, xmax, ymax, method, n_fixed, max_depth,
                               tol, auto_piece, exact, block_size, write, block_start,
                               out_segments, out_source, out_t, block_count, counters):
    """Do what `clip_segment_blocks` does on the calling thread (for small inputs).

    Waking the worker threads costs more than clipping a few thousand segments, and
    far more when the machine is busy.
    """
    for blk in range(block_count.shape[0]):
        _clip_block(blk, segments, xmin, ymin, xmax, ymax, method, n_fixed, max_depth, tol,
                    auto_piece, exact, block_size, write, block_start,
                    out_segments, out_source, out_t, block_count, counters)
