"""Many windows on an OpenCL device: the (segment, window) pairs made where the segments are.

`rnsca.many_windows.assign` on the device, for `OpenCLBackend.clip_segment_windows`:
the host computes only what is as small as the window table
(`many_windows.window_finder`: a grid's edges and cells, or the sweep's order, xmins
and rounded-up widest width) and sends it up; ``assign_pairs`` (``clip.cl``, a line by
line port of `rnsca.kernels.windows._visit`) runs the stable counting sort of the host
over `items` work-items, each owning a contiguous range of segments:

1. count: work-item t's pairs of window w in ``table[w * items + t]`` (window-major),
   and each work-group's first segment that is not finite;
2. an exclusive scan of the table, in place: every (window, work-item)'s first slot,
   and the count of pairs; ``reduce_first_bad``: the first bad segment;
3. one read of those two numbers (the pair tables are sized by the count, and a bad
   segment is raised before anything is clipped);
4. write: each work-item puts its pairs at its slots, so the pairs are sorted by
   window, then segment: `assign`'s pairs exactly, in the same order.

The table has ``items * k`` entries (int64), at most `ASSIGN_TABLE_ENTRIES`: the more
windows, the fewer work-items. Past k = 2**18 (with the defaults) fewer than
`MIN_ASSIGN_ITEMS` would be left, too few to fill a device, and the host assigns
(`assign_items` returns 0). A device scheme for that regime (pairs per segment, then a
sort by window) was not needed yet: tiles and grids have far fewer windows per call.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import pyopencl as cl

from rnsca.backends.opencl.segments import SegmentRun, _Raw
from rnsca.kernels.windows import WindowFinder

__all__ = ["ASSIGN_TABLE_ENTRIES", "SEGMENTS_PER_ITEM", "MIN_ASSIGN_ITEMS", "assign_items",
           "assign_on_device", "window_offsets_on_device"]

#: Entries of the count table at most (int64: 128 MiB): bounds the device memory the
#: assignment takes whatever the number of windows.
ASSIGN_TABLE_ENTRIES = 1 << 24
#: Segments per work-item at least: a work-item zeroes and its scan covers k entries,
#: which fewer segments would not pay for.
SEGMENTS_PER_ITEM = 32
#: Work-items below which the device would be mostly idle: the host assigns instead.
MIN_ASSIGN_ITEMS = 64


def assign_items(n: int, k: int) -> int:
    """Return the work-items of a device assignment of `n` segments to `k` windows.

    0 where the count table would leave fewer than `MIN_ASSIGN_ITEMS` of them (very many
    windows): the caller assigns on the host then.
    """
    most = ASSIGN_TABLE_ENTRIES // k
    if most < MIN_ASSIGN_ITEMS:
        return 0
    return max(1, min(most, -(-n // SEGMENTS_PER_ITEM)))


def assign_on_device(run: SegmentRun, queue: cl.CommandQueue, scan: Any,
                     segments: cl.Buffer, n: int, finder: WindowFinder,
                     items: int) -> tuple[int, int]:
    """Make the pairs of `n` device segments on the device; return ``(pairs, first_bad)``.

    `segments` holds float64 (n, 4) rows (``run.real`` is float64); ``run.windows``
    holds `finder`'s window table and `scan` is the device's table scan
    (`_Device.table_scan`). The kernels wait for ``run.ready`` (the uploads). Sets
    ``run.pair_segment`` (int64) and ``run.pair_window`` (int32), sorted by window then
    segment, and adds the write pass to ``run.ready`` so the clips, on either queue,
    wait for it. `first_bad` is the first segment that is not finite (then nothing is
    written and the pair tables are not set), else `n`.
    """
    local = run.local_size
    k = finder.windows.shape[0]
    real = run.real
    small = [_upload(run, queue, np.ascontiguousarray(a).reshape(-1))
             for a in (finder.xs, finder.ys, finder.cell_window, finder.order, finder.xmins)]
    groups = -(-items // local)
    table = run.allocator(8 * items * k)
    first_bad = run.allocator(8 * groups)
    summary = run.allocator(16)
    kernels = run.kernels

    def launch(write: int, pair_segment: Any, pair_window: Any) -> cl.Event:
        event = kernels.assign_pairs(
            queue, (groups * local,), (local,), segments, np.int64(n), np.int64(items),
            np.int32(finder.grid), np.int32(finder.uniform), real(finder.x_scale),
            real(finder.y_scale), small[0], np.int64(finder.xs.shape[0]), small[1],
            np.int64(finder.ys.shape[0]), small[2], run.windows, np.int64(k), small[3],
            small[4], real(finder.widest), np.int32(write), table, pair_segment,
            pair_window, first_bad, wait_for=run.ready)
        run.kernel_events.append(event)
        return event

    counted = launch(0, run.nowhere, run.nowhere)
    scanned = scan(_Raw(table, queue, run.allocator), _Raw(summary, queue, run.allocator),
                   queue=queue, size=items * k, allocator=run.allocator, wait_for=[counted])
    reduced = kernels.reduce_first_bad(queue, (local,), (local,), first_bad,
                                       np.int64(groups), summary, wait_for=[scanned])
    run.kernel_events += [scanned, reduced]
    row = np.empty(2, np.int64)
    run.download(queue, row, summary, wait_for=[reduced]).wait()
    p, bad = int(row[0]), int(row[1])
    if bad < n:
        return p, bad
    pair_segment = run.allocator(max(8, 8 * p))
    pair_window = run.allocator(max(8, 4 * p))
    if p:
        run.ready.append(launch(1, pair_segment, pair_window))
    run.pair_segment = cast(cl.Buffer, pair_segment)
    run.pair_window = cast(cl.Buffer, pair_window)
    return p, n


def window_offsets_on_device(run: SegmentRun, queue: cl.CommandQueue, window: Any, m: int,
                             k: int) -> np.ndarray:
    """Return the window offsets of `m` pieces sorted by window, from their device `window`.

    `window` is the pieces' int32 `pyopencl.array.Array`.

    ``window_starts`` finds each window's first piece on the device; only the `k` + 1
    offsets come back (int64).
    """
    offsets = run.allocator(8 * (k + 1))
    event = run.kernels.window_starts(queue, (k + 1,), None,
                                      window.data if m else run.nowhere, np.int64(m),
                                      np.int64(k), offsets)
    run.kernel_events.append(event)
    out = np.empty(k + 1, np.int64)
    run.download(queue, out, offsets, wait_for=[event]).wait()
    return out


def _upload(run: SegmentRun, queue: cl.CommandQueue, array: np.ndarray) -> Any:
    """Return a device copy of a small host `array` (``run.nowhere`` for an empty one)."""
    if not array.size:
        return run.nowhere
    buffer = run.allocator(array.nbytes)
    run.ready.append(run.upload(queue, buffer, array))
    return buffer
