"""Input checks that must be fast on 10^7 rows: one parallel pass, no temporaries."""

import math

import numba
import numpy as np
from numba import prange

from rnsca.kernels.jit import parallel, scalar

#: Rows per block; an input of one block is checked on the calling thread.
BLOCK_SIZE = 65536


@scalar
def finite_span(x0, y0, x1, y1):
    """Return whether a segment is finite with finite differences (see `_has_invalid`)."""
    return np.isfinite(x1 - x0) & np.isfinite(y1 - y0)


@scalar
def _has_invalid(segments):
    """Return whether a row of `segments` has a non-finite span.

    ``x1 - x0`` is finite exactly when both coordinates are finite and their difference
    does not overflow, so two tests per segment cover NaN, infinity and overflow. The
    loop is branch-free and runs from 0 (callers pass a view): with an arbitrary start,
    Numba's negative-index handling keeps LLVM from vectorizing it (5x slower).
    """
    bad = False
    for i in range(segments.shape[0]):
        bad |= not (np.isfinite(segments[i, 2] - segments[i, 0])
                    & np.isfinite(segments[i, 3] - segments[i, 1]))
    return bad


@scalar
def _first_invalid_in(segments, first, last):
    """Return the first row in ``first:last`` with a non-finite span, or -1."""
    if _has_invalid(segments[first:last]):
        for i in range(first, last):
            if not (np.isfinite(segments[i, 2] - segments[i, 0])
                    and np.isfinite(segments[i, 3] - segments[i, 1])):
                return i
    return -1


@parallel
def _first_invalid_parallel(segments):
    n = segments.shape[0]
    n_blocks = (n + BLOCK_SIZE - 1) // BLOCK_SIZE
    first_bad = np.empty(n_blocks, dtype=np.int64)
    for blk in prange(n_blocks):
        first = blk * BLOCK_SIZE
        first_bad[blk] = _first_invalid_in(segments, first, min(first + BLOCK_SIZE, n))
    for blk in range(n_blocks):
        if first_bad[blk] >= 0:
            return first_bad[blk]
    return -1


def first_invalid_segment(segments):
    """Return the index of the first segment with a non-finite span, or -1.

    `segments` is float64 (n, 4), C-contiguous.
    """
    if segments.shape[0] <= BLOCK_SIZE:
        return _first_invalid_in(segments, 0, segments.shape[0])
    return _first_invalid_parallel(segments)


# Reassociation only: lets LLVM vectorize the sum below. No other fast-math flag, so
# NaN and infinity keep their IEEE meaning.
_reassociating = numba.njit(cache=True, nogil=True, error_model="numpy",
                            fastmath={"reassoc"})


@_reassociating
def _nonfinite_in(values):
    """Return whether the 1-D array `values` holds a NaN or an infinity.

    ``x * 0`` is 0 for finite x and NaN otherwise, so the sum is NaN exactly when a value
    is not finite, in any order of summation (and it cannot overflow). The loop runs
    from 0 over a view: with an arbitrary start, Numba's negative-index handling keeps
    LLVM from vectorizing it (10x slower).
    """
    total = 0.0
    for i in range(values.shape[0]):
        total += values[i] * 0.0
    return total != 0.0


#: Values per block of the parallel check (a few MB: one block per thread is worth waking).
FINITE_BLOCK = 1 << 20


@parallel
def _nonfinite_blocks(values):
    n = values.shape[0]
    blocks = (n + FINITE_BLOCK - 1) // FINITE_BLOCK
    found = 0
    for b in prange(blocks):
        first = b * FINITE_BLOCK
        if _nonfinite_in(values[first:min(first + FINITE_BLOCK, n)]):
            found += 1
    return found > 0


def all_finite(coords):
    """Return whether every value of `coords` (float64, C-contiguous) is finite.

    One vectorized pass without temporaries: about twice as fast as
    ``np.isfinite(coords).all()``, which allocates a mask. Up to a few blocks it runs on
    one thread (memory speed on a 2-core machine); beyond, in blocks on every core: one
    thread reads about 9 GB/s, and a 16-core host checked 1M polygons' coordinates in
    71 ms on one (`benchmarks/gpu.py`'s profile).
    """
    values = coords.reshape(-1)
    if values.shape[0] <= 4 * FINITE_BLOCK:
        return not _nonfinite_in(values)
    return not _nonfinite_blocks(values)


@parallel
def first_open_ring(coords, ring_offsets):
    """Return the first non-empty ring whose first and last positions differ (x, y), or -1.

    One parallel pass over the rings (two rows each), in blocks; the caller has checked
    the ring sizes.
    """
    n = ring_offsets.shape[0] - 1
    n_blocks = (n + BLOCK_SIZE - 1) // BLOCK_SIZE
    first_bad = np.full(n_blocks, -1, dtype=np.int64)
    for blk in prange(n_blocks):
        for r in range(blk * BLOCK_SIZE, min((blk + 1) * BLOCK_SIZE, n)):
            a = ring_offsets[r]
            b = ring_offsets[r + 1] - 1
            if b > a and (coords[a, 0] != coords[b, 0] or coords[a, 1] != coords[b, 1]):
                first_bad[blk] = r
                break
    for blk in range(n_blocks):
        if first_bad[blk] >= 0:
            return first_bad[blk]
    return -1


# --- Bézier path layout -------------------------------------------------------------

# Codes of `check_layout` (0: valid), and what each says is wrong.
_NOT_FINITE = 1
_UNUSED_ROW = 2
_DISCONTINUOUS = 3
LAYOUT_MESSAGES = {
    _NOT_FINITE: "coordinates must be finite",
    _UNUSED_ROW: "unused control points must repeat the end point",
    _DISCONTINUOUS: ("segments must start where the previous one ends (the first at the "
                     "subpath's start)"),
}


@scalar
def _segment_problem(controls, degree, i, x, y):
    """Return the problem code of segment i that should start at (x, y), or 0."""
    for r in range(4):
        if not (math.isfinite(controls[i, r, 0]) and math.isfinite(controls[i, r, 1])):
            return _NOT_FINITE
    for r in range(degree[i], 3):
        if controls[i, r, 0] != controls[i, 3, 0] or controls[i, r, 1] != controls[i, 3, 1]:
            return _UNUSED_ROW
    if controls[i, 0, 0] != x or controls[i, 0, 1] != y:
        return _DISCONTINUOUS
    return 0


@parallel
def check_layout(controls, degree, subpath_offsets, start):
    """Return ``(subpath, segment, code)`` of the first broken rule, or (-1, -1, 0).

    Rules of `rnsca.arrays.PathArrays`: finite coordinates, unused control
    rows equal to the end point, each segment starting at the previous one's end (the
    first at its subpath's start). The caller has checked shapes, degrees and offsets.
    One parallel pass over the subpaths, no temporaries.
    """
    k = start.shape[0]
    problem = np.zeros(k, dtype=np.int64)
    at = np.full(k, -1, dtype=np.int64)
    for s in prange(k):
        x = start[s, 0]
        y = start[s, 1]
        if not (math.isfinite(x) and math.isfinite(y)):
            problem[s] = _NOT_FINITE
            continue
        for i in range(subpath_offsets[s], subpath_offsets[s + 1]):
            code = _segment_problem(controls, degree, i, x, y)
            if code != 0:
                problem[s] = code
                at[s] = i
                break
            x = controls[i, 3, 0]
            y = controls[i, 3, 1]
    for s in range(k):
        if problem[s] != 0:
            return s, at[s], problem[s]
    return -1, -1, 0
