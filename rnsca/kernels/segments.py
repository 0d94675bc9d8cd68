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

from rnsca.baselines.cohen_sutherland import cohen_sutherland_segment
from rnsca.baselines.liang_barsky import liang_barsky_interval, liang_barsky_segment
from rnsca.baselines.midpoint import midpoint_segment
from rnsca.baselines.nicholl_lee_nicholl import nicholl_lee_nicholl_segment
from rnsca.kernels import counters as C
from rnsca.kernels.jit import parallel, scalar
from rnsca.kernels.outcode import clamp, end_point, is_piece, outcode

# Method ids as the driver knows them (rnsca.backends.numba_cpu maps the enum).
RNSCA = 0
COHEN_SUTHERLAND = 1
LIANG_BARSKY = 2
NICHOLL_LEE_NICHOLL = 3
MIDPOINT = 4

N_MAX = 64
# Along a segment each of the four edge lines is crossed at most once, and computed
# points are monotone in t, so at most four children of a piece are ambiguous: the
# depth-first stack holds at most three pending siblings per level plus the current one.
STACK_CAPACITY = 4 * (C.N_LEVELS + 1)
# Stack rows: floats (ta, tb, xa, ya, xb, yb); ints (ca, cb, level).
_TA, _TB, _XA, _YA, _XB, _YB = 0, 1, 2, 3, 4, 5
_CA, _CB, _LEVEL = 0, 1, 2


@scalar
def auto_n(piece_length, auto_piece):
    """Return the ``n="auto"`` split count for a piece: ``ceil(length / auto_piece)`` in 2..64.

    A piece longer than the window is cut into window-sized pieces in one step, so the
    pieces far from the window are rejected at once; a piece up to twice the window's
    size is bisected.
    """
    if not piece_length > 2.0 * auto_piece:
        return 2  # the common case, without the division
    k = math.ceil(piece_length / auto_piece)
    return N_MAX if k > N_MAX else int(k)


@scalar
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
        if exact:
            st[C.CLIPPED] += 1
            st[C.LEVELS] += 1
            ok, u0, e0, u1, e1 = liang_barsky_interval(x0, y0, dx, dy, 0.0, 1.0,
                                                       xmin, ymin, xmax, ymax, st)
            if not ok:
                return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            ax, ay = end_point(x0, y0, dx, dy, u0, e0, x0, y0, xmin, ymin, xmax, ymax)
            bx, by = end_point(x0, y0, dx, dy, u1, e1, x1, y1, xmin, ymin, xmax, ymax)
            return is_piece(False, u0, u1, ax, ay, bx, by), u0, u1, ax, ay, bx, by
        st[C.DROPPED] += 1
        st[C.LEVELS] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    st[C.SUBDIVIDED] += 1
    stack_f[0, _TA] = 0.0
    stack_f[0, _TB] = 1.0
    stack_f[0, _XA] = x0
    stack_f[0, _YA] = y0
    stack_f[0, _XB] = x1
    stack_f[0, _YB] = y1
    stack_i[0, _CA] = c0
    stack_i[0, _CB] = c1
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
                x = x0 + t * dx
                y = y0 + t * dy
                c = outcode(x, y, xmin, ymin, xmax, ymax)
            st[C.EVALUATED] += 1
            if (pc | c) == 0:
                st[C.ACCEPTED] += 1
                st[C.LEVELS + level] += 1
                if pt < lo_t:
                    lo_t, lo_x, lo_y = pt, px, py
                if t > hi_t:
                    hi_t, hi_x, hi_y = t, x, y
            elif pc & c:
                st[C.REJECTED] += 1
                st[C.LEVELS + level] += 1
            elif level >= max_depth or (t - pt) * length <= tol or sp >= STACK_CAPACITY:
                st[C.LEVELS + level] += 1
                if exact:
                    st[C.CLIPPED] += 1
                    ok, u0, e0, u1, e1 = liang_barsky_interval(x0, y0, dx, dy, pt, t,
                                                               xmin, ymin, xmax, ymax, st)
                    if ok:
                        if u0 < lo_t:
                            lo_t = u0
                            lo_x, lo_y = end_point(x0, y0, dx, dy, u0, e0, px, py,
                                                   xmin, ymin, xmax, ymax)
                        if u1 > hi_t:
                            hi_t = u1
                            hi_x, hi_y = end_point(x0, y0, dx, dy, u1, e1, x, y,
                                                   xmin, ymin, xmax, ymax)
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
def clip_one(method, x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol,
             auto_piece, exact, st, stack_f, stack_i):
    """Clip one segment with the method of id `method`; return (keep, t0, t1, ax, ay, bx, by)."""
    if method == RNSCA:
        return rnsca_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol,
                             auto_piece, exact, st, stack_f, stack_i)
    if method == COHEN_SUTHERLAND:
        return cohen_sutherland_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st)
    if method == LIANG_BARSKY:
        return liang_barsky_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st)
    if method == NICHOLL_LEE_NICHOLL:
        return nicholl_lee_nicholl_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st)
    return midpoint_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, max_depth, tol, exact, st)


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
    n = segments.shape[0]
    n_blocks = block_count.shape[0]
    for blk in prange(n_blocks):
        st = counters[blk]
        stack_f = np.empty((STACK_CAPACITY, 6), dtype=np.float64)
        stack_i = np.empty((STACK_CAPACITY, 3), dtype=np.int64)
        first = blk * block_size
        last = min(first + block_size, n)
        k = block_start[blk]
        for i in range(first, last):
            keep, t0, t1, ax, ay, bx, by = clip_one(
                method, segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3],
                xmin, ymin, xmax, ymax, n_fixed, max_depth, tol, auto_piece, exact,
                st, stack_f, stack_i)
            if keep:
                if write:
                    out_segments[k, 0] = clamp(ax, xmin, xmax)
                    out_segments[k, 1] = clamp(ay, ymin, ymax)
                    out_segments[k, 2] = clamp(bx, xmin, xmax)
                    out_segments[k, 3] = clamp(by, ymin, ymax)
                    out_source[k] = i
                    out_t[k, 0] = t0
                    out_t[k, 1] = t1
                k += 1
        block_count[blk] = k - block_start[blk]
