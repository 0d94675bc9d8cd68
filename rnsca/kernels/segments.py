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
from typing import NamedTuple

import numpy as np
from numba import prange

# Method ids, N's bounds and the stack size are defined in rnsca.constants (shared with
# clip.cl and the service); importable from here as before.
from rnsca.constants import (
    AUTO_N_BASE,
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
    clamp,
    common_end_point,
    direction,
    end_point,
    interpolated_point,
    is_piece,
    outcode,
    wide,
)
from rnsca.kernels.records import Fragment
from rnsca.kernels.validate import finite_span

# Stack rows: floats (ta, tb, xa, ya, xb, yb); ints (ca, cb, level).
_TA, _TB, _XA, _YA, _XB, _YB = 0, 1, 2, 3, 4, 5
_CA, _CB, _LEVEL = 0, 1, 2
# Below this shift (rows), `move_rows` copies on one thread.
MIN_PARALLEL_SHIFT = 16384
# `SegmentOutput.block_count` of a block with a segment that is not finite (or whose
# differences overflow): nothing of it is clipped, and the caller raises.
INVALID_BLOCK = -1


def auto_n(piece_length, tol, levels_left):
    """Return the ``n="auto"`` split count of a piece: bisection, unless it falls short.

    Approx mode refines each boundary crossing like a search, for which halving costs
    fewest outcode tests per level (measured: see `AUTO_N_BASE`). Only where
    `levels_left` halvings cannot bring the piece down to `tol` (a segment millions of
    windows long), N is the smallest that can, ``ceil((length / tol) ** (1 / levels))``,
    at most N_MAX. Plain arithmetic, shared by the kernel (jitted below) and the
    service's work bound.
    """
    if not piece_length > tol * 2.0 ** levels_left:
        return AUTO_N_BASE  # the common case (and tol = inf), without the power
    k = (piece_length / tol) ** (1.0 / levels_left)
    return N_MAX if not k < N_MAX else max(AUTO_N_BASE, int(math.ceil(k)))


_auto_n = scalar(auto_n)


class SegmentStack(NamedTuple):
    """RNSCA's depth-first stack of pending pieces, scratch space owned by one block.

    Row ``i`` is one piece: ``floats[i]`` holds (ta, tb, xa, ya, xb, yb) and
    ``ints[i]`` (ca, cb, level), both `STACK_CAPACITY` rows (see `segment_stack`).
    """

    floats: np.ndarray
    ints: np.ndarray


class SegmentOutput(NamedTuple):
    """What the segment drivers fill: the pieces, and per block their count and counters.

    Attributes
    ----------
    pieces, source, t : float64 (n, 4), int64 (n,), float64 (n, 2)
        The pieces (ends clamped into the window), the input row of each, and its
        parameter interval: one row per input segment, of which each chunk of blocks
        fills the first rows of its own range (see `clip_segment_blocks`).
    block_start : int64 (n_blocks,)
        The row of block ``k``'s first piece, written by the driver.
    block_count : int64 (n_blocks,)
        Pieces per block.
    counters : int64 (n_blocks, counters.WIDTH)
        One counter row per block (``rnsca.kernels.counters``).
    """

    pieces: np.ndarray
    source: np.ndarray
    t: np.ndarray
    block_start: np.ndarray
    block_count: np.ndarray
    counters: np.ndarray


@scalar
def segment_stack():
    """Return a new, empty `SegmentStack` for `rnsca_segment`."""
    return SegmentStack(np.empty((STACK_CAPACITY, 6), dtype=np.float64),
                        np.empty((STACK_CAPACITY, 3), dtype=np.int64))


@borrowing
def _push(stack, sp, fragment, level):
    """Write `fragment` (a `Fragment`) at level `level` into row `sp` of `stack`."""
    stack.floats[sp, _TA] = fragment.ta
    stack.floats[sp, _TB] = fragment.tb
    stack.floats[sp, _XA] = fragment.xa
    stack.floats[sp, _YA] = fragment.ya
    stack.floats[sp, _XB] = fragment.xb
    stack.floats[sp, _YB] = fragment.yb
    stack.ints[sp, _CA] = fragment.ca
    stack.ints[sp, _CB] = fragment.cb
    stack.ints[sp, _LEVEL] = level


@borrowing
def _pop(stack, sp):
    """Return (fragment, level): the `Fragment` in row `sp` of `stack` and its level."""
    fragment = Fragment(stack.floats[sp, _TA], stack.floats[sp, _XA], stack.floats[sp, _YA],
                  stack.ints[sp, _CA], stack.floats[sp, _TB], stack.floats[sp, _XB],
                  stack.floats[sp, _YB], stack.ints[sp, _CB])
    return fragment, stack.ints[sp, _LEVEL]


@borrowing
def _clip_leaf(x0, y0, x1, y1, leaf, window, st):
    """Clip the `leaf` (a `Fragment`) of a segment; return (ok, u0, ax, ay, u1, bx, by)."""
    ok, u0, ax, ay, u1, bx, by, divisions = liang_barsky_leaf(x0, y0, x1, y1, leaf, window)
    st[C.INTERSECTIONS] += divisions
    return ok and is_piece(False, u0, u1, ax, ay, bx, by), u0, ax, ay, u1, bx, by


@borrowing
def rnsca_segment(x0, y0, x1, y1, window, options, st, stack):
    """Clip one segment with RNSCA; return (keep, t0, t1, ax, ay, bx, by).

    Parameters
    ----------
    x0, y0, x1, y1 : float
        The segment, finite, with finite differences.
    window : Window
    options : CoreOptions
        Its subdivision fields are read: `n_fixed` is N, or 0 for auto (`auto_n`).
    st : int64 (counters.WIDTH,)
        The block's counter row.
    stack : SegmentStack
        Scratch space owned by the caller's block.
    """
    c0 = outcode(x0, y0, window.xmin, window.ymin, window.xmax, window.ymax)
    c1 = outcode(x1, y1, window.xmin, window.ymin, window.xmax, window.ymax)
    st[C.EVALUATED] += 1
    if (c0 | c1) == 0:
        st[C.ACCEPTED] += 1
        st[C.LEVELS] += 1
        return True, 0.0, 1.0, x0, y0, x1, y1
    if c0 & c1:
        st[C.REJECTED] += 1
        st[C.LEVELS] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    length = math.hypot(x1 - x0, y1 - y0)
    # Children's ends are interpolated: classify them, and the ends, with wide codes
    # (see outcode.py).
    whole = Fragment(0.0, x0, y0, wide(c0), 1.0, x1, y1, wide(c1))
    if options.max_depth == 0 or length <= options.tol:
        # The whole segment is the leaf.
        st[C.LEVELS] += 1
        if not options.exact:
            st[C.DROPPED] += 1
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        st[C.CLIPPED] += 1
        ok, u0, ax, ay, u1, bx, by = _clip_leaf(x0, y0, x1, y1, whole, window, st)
        return ok, u0, u1, ax, ay, bx, by
    st[C.SUBDIVIDED] += 1
    return _subdivide(x0, y0, x1, y1, whole, length, window, options, st, stack)


@borrowing
def _subdivide(x0, y0, x1, y1, whole, length, window, options, st, stack):
    """Split an ambiguous segment depth-first; return (keep, t0, t1, ax, ay, bx, by).

    `whole` is the segment as a `Fragment`, `length` its length; the other parameters are
    those of `rnsca_segment`. The accepted children and clipped leaves are merged into
    one interval as they come.
    """
    d = direction(x0, y0, x1, y1)
    # ``n="auto"`` bisects every piece of this segment when bisection reaches the tolerance
    # within max_depth (`auto_n` then returns 2 at every level): decided once, here, since
    # `auto_n`'s power (or ldexp) per piece cost ~10% of approx mode (1M uniform, 1 thread).
    bisect = length <= options.tol * 2.0 ** options.max_depth
    # The merged interval and its end points.
    lo_t = math.inf
    lo_x = lo_y = 0.0
    hi_t = -math.inf
    hi_x = hi_y = 0.0
    _push(stack, 0, whole, 0)
    sp = 1
    while sp > 0:
        sp -= 1
        fragment, level = _pop(stack, sp)
        level += 1
        step = fragment.tb - fragment.ta
        n = options.n_fixed if options.n_fixed > 0 else (2 if bisect else _auto_n(
            step * length, options.tol, options.max_depth - level + 1))
        # Walk the n children left to right; (pt, px, py, pc) is the current child's start.
        pt = fragment.ta
        px = fragment.xa
        py = fragment.ya
        pc = fragment.ca
        if level > st[C.DEEPEST]:
            st[C.DEEPEST] = level
        for j in range(1, n + 1):
            if j == n:
                t, x, y, c = fragment.tb, fragment.xb, fragment.yb, fragment.cb
            else:
                t = fragment.ta + step * j / n
                x, y, c = interpolated_point(x0, y0, d, t, window)
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
            elif (level >= options.max_depth or (t - pt) * length <= options.tol or pc == c
                  or sp >= STACK_CAPACITY):
                # A leaf; ``pc == c``: both ends within rounding of the same edges (the
                # child hugs the boundary), which splitting could not resolve.
                st[C.LEVELS + level] += 1
                if options.exact:
                    st[C.CLIPPED] += 1
                    ok, u0, ax, ay, u1, bx, by = _clip_leaf(
                        x0, y0, x1, y1, Fragment(pt, px, py, pc, t, x, y, c), window, st)
                    if ok:
                        if u0 < lo_t:
                            lo_t, lo_x, lo_y = u0, ax, ay
                        if u1 > hi_t:
                            hi_t, hi_x, hi_y = u1, bx, by
                else:
                    st[C.DROPPED] += 1
            else:
                st[C.SUBDIVIDED] += 1
                _push(stack, sp, Fragment(pt, px, py, pc, t, x, y, c), level)
                sp += 1
            pt, px, py, pc = t, x, y, c
    if not lo_t <= hi_t:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return is_piece(False, lo_t, hi_t, lo_x, lo_y, hi_x, hi_y), lo_t, hi_t, lo_x, lo_y, hi_x, hi_y


@scalar
def clip_one(x0, y0, x1, y1, window, options, st):
    """Clip one segment with the baseline ``options.method``; return (keep, t0, t1, ax, ay, bx, by).

    Every method returns so: whether the segment leaves a piece, the piece's parameter
    interval and its end points (in the window). `window` is a `Window`, `options` a
    `CoreOptions` (read by midpoint subdivision only), `st` the block's counter row,
    which the method counts into. RNSCA is not here: it runs block-wise (`_rnsca_block`).
    """
    method = options.method
    if method == COHEN_SUTHERLAND:
        return cohen_sutherland_segment(x0, y0, x1, y1, window, st)
    if method == LIANG_BARSKY:
        return liang_barsky_segment(x0, y0, x1, y1, window, st)
    if method == NICHOLL_LEE_NICHOLL:
        return nicholl_lee_nicholl_segment(x0, y0, x1, y1, window, st)
    return midpoint_segment(x0, y0, x1, y1, window, options, st)


@borrowing
def _write_piece(out, k, i, t0, t1, ax, ay, bx, by, window):
    """Write piece `k` of `out`: segment `i`'s interval [t0, t1], ends clamped into `window`."""
    out.pieces[k, 0] = clamp(ax, window.xmin, window.xmax)
    out.pieces[k, 1] = clamp(ay, window.ymin, window.ymax)
    out.pieces[k, 2] = clamp(bx, window.xmin, window.xmax)
    out.pieces[k, 3] = clamp(by, window.ymin, window.ymax)
    out.source[k] = i
    out.t[k, 0] = t0
    out.t[k, 1] = t1


@scalar
def _rnsca_block(segments, first, last, window, options, st, k, out):
    """Clip segments ``first:last`` with RNSCA, writing from row `k` on; return the next row.

    Returns `INVALID_BLOCK` instead, having clipped nothing, if one of the segments is
    not finite or its differences overflow.

    Most segments are decided at level 0: accepted, rejected, or (short enough) a
    leaf. That case runs as a few simple branch-free loops over the block, one per
    step, on block-sized scratch columns that stay in cache: loops LLVM vectorizes.
    Segments that need splitting are marked and go through the depth-first
    `rnsca_segment`. The pieces are then written into `out` in input order.
    """
    xmin, ymin, xmax, ymax = window
    max_depth = options.max_depth
    tol = options.tol
    exact = options.exact
    size = last - first
    n_invalid = 0
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
        # The input check, fused into this pass (selects only: the loop still vectorizes).
        n_invalid += 0 if finite_span(x0[j], y0[j], x1[j], y1[j]) else 1
    if n_invalid:
        return INVALID_BLOCK  # before anything is counted, split or written
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
                bit, flags[j], u0[j], e0[j], u1[j], e1[j], x0[j], y0[j], x1[j], y1[j], window)
    # Each end once, by the common path (selects only, vectorized); the rows that may
    # give a piece but need the double-double cut or snapping are marked for `end_point`.
    candidate = np.empty(size, dtype=np.bool_)
    uncommon = np.empty(size, dtype=np.bool_)
    for j in range(size):
        ax[j], ay[j], sure_a = common_end_point(
            x0[j], y0[j], x1[j], y1[j], e0[j], x0[j], y0[j], window)
        bx[j], by[j], sure_b = common_end_point(
            x0[j], y0[j], x1[j], y1[j], e1[j], x1[j], y1[j], window)
        candidate[j] = (u0[j] <= u1[j]) & (not rejected[j]) & (not split[j]) & (
            exact | (not ambiguous[j]))
        uncommon[j] = candidate[j] & ((not sure_a) | (not sure_b))
    for j in range(size):
        if uncommon[j]:
            ax[j], ay[j] = end_point(x0[j], y0[j], x1[j], y1[j], e0[j], x0[j], y0[j], window)
            bx[j], by[j] = end_point(x0[j], y0[j], x1[j], y1[j], e1[j], x1[j], y1[j], window)
    keep = np.empty(size, dtype=np.bool_)
    for j in range(size):
        keep[j] = candidate[j] & is_piece(
            (x0[j] == x1[j]) & (y0[j] == y1[j]), u0[j], u1[j], ax[j], ay[j], bx[j], by[j])
    # Deeper levels, for the few segments that need them.
    stack = segment_stack()
    for j in range(size):
        if split[j]:
            i = first + j
            keep[j], u0[j], u1[j], ax[j], ay[j], bx[j], by[j] = rnsca_segment(
                segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3],
                window, options, st, stack)
    # Compact the kept rows' indices without branches (the slot past the last kept row
    # is always inside the scratch), then copy those rows out.
    kept = np.empty(size, dtype=np.int64)
    count = 0
    for j in range(size):
        kept[count] = j
        count += 1 if keep[j] else 0
    for r in range(count):
        j = kept[r]
        _write_piece(out, k + r, first + j, u0[j], u1[j], ax[j], ay[j], bx[j], by[j], window)
    return k + count


@scalar
def _clip_block(blk, segments, window, options, block_size, out):
    """Write block `blk`'s pieces into `out` from row ``out.block_start[blk]`` on.

    Its count is `INVALID_BLOCK` if a segment of it is not finite: the check of the
    input, fused into the clip (the classic methods stop at that segment).
    """
    first = blk * block_size
    clip_block_rows(blk, segments, first, min(first + block_size, segments.shape[0]),
                    window, options, out)


@scalar
def clip_block_rows(blk, segments, first, last, window, options, out):
    """Clip rows ``first:last`` to `window` as block `blk` (its counters, start, count).

    Shared by the one-window driver and the many-window one (`windows.clip_pairs`).
    """
    st = out.counters[blk]
    k = out.block_start[blk]
    if options.method == RNSCA:
        k = _rnsca_block(segments, first, last, window, options, st, k, out)
        if k == INVALID_BLOCK:
            out.block_count[blk] = INVALID_BLOCK
            return
    else:
        for i in range(first, last):
            if not finite_span(segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3]):
                out.block_count[blk] = INVALID_BLOCK
                return
            keep, t0, t1, ax, ay, bx, by = clip_one(
                segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3],
                window, options, st)
            if keep:
                _write_piece(out, k, i, t0, t1, ax, ay, bx, by, window)
                k += 1
    out.block_count[blk] = k - out.block_start[blk]


@scalar
def chunk_blocks(chunk, n_chunks, n_blocks):
    """Return (first, last): the blocks of chunk `chunk` of `n_chunks` (equal shares)."""
    return chunk * n_blocks // n_chunks, (chunk + 1) * n_blocks // n_chunks


@scalar
def _clip_chunk(chunk, n_chunks, segments, window, options, block_size, out):
    """Clip the blocks of one chunk in order, their pieces one after another.

    The chunk's pieces start at the row of its first segment: a segment gives at most
    one piece, so they never reach the next chunk's rows.
    """
    first, last = chunk_blocks(chunk, n_chunks, out.block_count.shape[0])
    k = first * block_size
    for blk in range(first, last):
        out.block_start[blk] = k
        _clip_block(blk, segments, window, options, block_size, out)
        k += max(out.block_count[blk], 0)


@parallel
def move_rows(out, start, to, count):
    """Move rows ``start:start + count`` of `out`'s pieces, source and t up to row `to`.

    ``to < start``. In rounds of ``start - to`` rows: each round reads rows that no
    earlier round has written and writes only rows an earlier round has read, so
    the rows of one round are copied in parallel. A short shift is copied forward on
    one thread instead (too many rounds to pay for waking the others).
    """
    shift = start - to
    if shift < MIN_PARALLEL_SHIFT:
        for r in range(count):
            _copy_row(out, start + r, to + r)
        return
    done = 0
    while done < count:
        rows = min(shift, count - done)
        for r in prange(rows):
            _copy_row(out, start + done + r, to + done + r)
        done += rows


@scalar
def _copy_row(out, row, to):
    """Copy row `row` of `out`'s pieces, source and t to row `to`."""
    for c in range(4):
        out.pieces[to, c] = out.pieces[row, c]
    out.source[to] = out.source[row]
    out.t[to, 0] = out.t[row, 0]
    out.t[to, 1] = out.t[row, 1]


@parallel
def clip_segment_blocks(segments, window, options, block_size, n_chunks, out):
    """Clip every segment, one prange iteration per chunk of consecutive blocks.

    Block ``k`` covers segments ``k * block_size`` on. Each chunk (give one per thread:
    prange shares iterations out equally) writes its pieces one after another from the
    row of its first segment, and ``out.block_start``, ``out.block_count`` and
    ``out.counters`` (one row per block) of its own blocks: race-free. The caller then
    moves each chunk's rows up behind the previous chunk's (`move_rows`): only the
    chunks after the first move, none on one thread.

    Parameters
    ----------
    segments : float64 (n, 4)
        C-contiguous, finite, with finite differences.
    window : Window
    options : CoreOptions
    block_size : int
        Segments per block; ``out.block_count`` has one slot per block.
    n_chunks : int
        Chunks of blocks (`chunk_blocks`).
    out : SegmentOutput
    """
    for chunk in prange(n_chunks):
        # int64, as the serial driver passes it: one specialisation, not two
        _clip_chunk(np.int64(chunk), n_chunks, segments, window, options, block_size, out)


@scalar
def clip_segment_blocks_serial(segments, window, options, block_size, out):
    """Do what `clip_segment_blocks` does, as one chunk on the calling thread.

    Waking the worker threads costs more than clipping a few thousand segments, and
    far more when the machine is busy. The pieces are compact: nothing to move.
    """
    _clip_chunk(0, 1, segments, window, options, block_size, out)
