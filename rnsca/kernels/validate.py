"""Input checks that must be fast on 10^7 rows: one parallel pass, no temporaries."""

import numpy as np
from numba import prange

from rnsca.kernels.jit import parallel, scalar

#: Rows per block; an input of one block is checked on the calling thread.
BLOCK_SIZE = 65536


@scalar
def _first_invalid_in(segments, first, last):
    """Return the first row in ``first:last`` with a non-finite span, or -1.

    ``x1 - x0`` is finite exactly when both coordinates are finite and their difference
    does not overflow, so two tests per segment cover NaN, infinity and overflow.
    """
    bad = False
    for i in range(first, last):  # branch-free, so it vectorizes
        bad |= not (np.isfinite(segments[i, 2] - segments[i, 0])
                    & np.isfinite(segments[i, 3] - segments[i, 1]))
    if bad:
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
