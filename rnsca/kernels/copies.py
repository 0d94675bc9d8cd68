"""Memory copies on every core: the host side of the OpenCL backend's staged transfers.

The OpenCL backend moves large inputs and outputs through page-locked (pinned) staging
buffers, because a device copies from and to pinned memory at full bus speed and from
pageable memory at a fraction of it (an H100's driver: 3-4.6 GB/s pageable). The copy
between the caller's arrays and the staging buffers is then host work on the critical
path; one thread copies at a few GB/s (less into fresh pages, which fault on first
touch), so it runs on every core, in blocks, here.
"""

from __future__ import annotations

import numba
import numpy as np

from rnsca.kernels.jit import parallel

__all__ = ["copy_into", "copy_ranges", "COPY_BLOCK"]

#: Elements per block of a parallel copy (a few hundred KB: large enough that a
#: block's overhead vanishes, small enough that every thread gets several).
COPY_BLOCK = 1 << 15


@parallel
def _copy_blocks(source, target):
    n = source.shape[0]
    blocks = (n + COPY_BLOCK - 1) // COPY_BLOCK
    for b in numba.prange(blocks):
        first = b * COPY_BLOCK
        last = min(first + COPY_BLOCK, n)
        target[first:last] = source[first:last]


def copy_into(target: np.ndarray, source: np.ndarray) -> None:
    """Copy `source` into `target` (same dtype and size, both C-contiguous) on every core.

    Small copies (a few blocks) run in NumPy: starting the threads would cost more.
    """
    if source.size != target.size or source.dtype != target.dtype:
        raise ValueError(f"copy of {source.dtype}[{source.size}] into "
                         f"{target.dtype}[{target.size}]")
    if source.size <= 4 * COPY_BLOCK:
        target.reshape(-1)[...] = source.reshape(-1)
        return
    _copy_blocks(source.reshape(-1), target.reshape(-1))


@parallel
def copy_ranges(source, starts, counts, out_starts, target):
    """Copy rows ``source[starts[j]:starts[j] + counts[j]]`` to ``target[out_starts[j]:]``.

    `source` and `target` are 2-D with the same columns; ranges may repeat or overlap
    in `source` (a gather of whole geometries, `rnsca.arrays.Ragged.take`).
    """
    for j in numba.prange(starts.shape[0]):
        first = starts[j]
        out = out_starts[j]
        for k in range(counts[j]):
            for c in range(source.shape[1]):
                target[out + k, c] = source[first + k, c]
