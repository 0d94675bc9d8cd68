"""Segments on an OpenCL device: staged, overlapped transfers, and inputs kept on the device.

A call on host arrays streams the segments in chunks through two slots, each with its
own in-order queue, page-locked (pinned) staging buffers and device buffers, all kept
for the next call. While one slot's chunk is copied up, clipped and compacted, the
other's pieces are copied down and into the caller's arrays: upload, kernels, download
and the host's copies overlap. Per chunk, on the device:

1. ``clip_segments``: each item's result and a 0/1 keep count, the counters summed per
   work-group (few groups: a grid-stride loop), the first non-finite segment;
2. an inclusive scan of the counts (the slots of the kept pieces);
3. ``reduce_counters``: the groups' counter rows to one row, with the first non-finite
   item and the count of kept items;
4. ``write_pieces``: the kept results to their slots, in the output's dtype and layout
   (``source`` and ``t`` only where asked for).

Only that row comes back before the pieces (`clip_host` says in which order the chunks'
steps interleave). The host copies between the caller's arrays and the staging buffers
on every core (`rnsca.kernels.copies`).

A call on a `pyopencl.array.Array` of segments runs the same kernels in one pass and
returns device arrays: nothing crosses the bus but the window and the row.

An item is a segment and the window, or a (segment, window) pair of a many-window call
(``pairs``): the kernels read the window of each pair from a table on the device.
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
import pyopencl.tools
from pyopencl.scan import GenericScanKernel

from rnsca import constants
from rnsca.kernels.copies import copy_into

__all__ = ["SegmentRun", "Staging", "MAX_GROUPS", "CHUNK_SEGMENTS"]

#: Work-groups per clip launch at most: enough to fill a large GPU (132 SMs x 2,048
#: work-items on an H100 is 4,224 groups of 64), few enough that the counter rows stay
#: small (the grid-stride loop gives each group many items).
MAX_GROUPS = 4096
#: Items per chunk of a host input: each slot's share of a pipelined call.
CHUNK_SEGMENTS = 1 << 22
_WIDTH = constants.SEGMENT_COUNTERS
_NONE = np.iinfo(np.int64).max


def groups_for(n: int, local_size: int) -> int:
    """Return the work-groups of a clip launch over `n` items."""
    return max(1, min(-(-n // local_size), MAX_GROUPS))


class _Pinned:
    """A page-locked host buffer, mapped once for the process.

    The device copies to and from its NumPy view at full bus speed (``ALLOC_HOST_PTR``:
    the driver pins it).
    """

    def __init__(self, context: cl.Context, queue: cl.CommandQueue, nbytes: int) -> None:
        self.nbytes = max(nbytes, 8)
        self.buffer = cl.Buffer(context, cl.mem_flags.READ_WRITE | cl.mem_flags.ALLOC_HOST_PTR,
                                self.nbytes)
        # Kept mapped: its host pointer is the source and target of the transfers
        # (the pattern NVIDIA's OpenCL guide gives for pinned staging).
        mapped = cl.enqueue_map_buffer(
            queue, self.buffer, cast(cl.map_flags, cl.map_flags.READ | cl.map_flags.WRITE), 0,
            (self.nbytes,), np.dtype(np.uint8), is_blocking=True)
        self.view: np.ndarray = mapped[0]

    def array(self, offset: int, dtype: Any, count: int) -> np.ndarray:
        """Return `count` items of `dtype` from byte `offset` on, a view."""
        dtype = np.dtype(dtype)
        return self.view[offset:offset + count * dtype.itemsize].view(dtype)


class _Lease:
    """The owner of one pinned buffer handed to a caller: NumPy arrays are views of it.

    NumPy makes an object with ``__array_interface__`` the ``base`` of the array it
    wraps, so the lease lives exactly as long as some view of it does; then its
    finalizer gives the buffer back to the pool (`PinnedPool`).
    """

    def __init__(self, pinned: _Pinned, pool: PinnedPool) -> None:
        self.pool = pool
        self.__array_interface__ = {
            "data": (pinned.view.__array_interface__["data"][0], False),
            "shape": (pinned.nbytes,), "typestr": "|u1", "version": 3}


class PinnedPool:
    """Page-locked host memory for a call's outputs, taken back once the caller drops them.

    A device copies into pinned memory at full bus speed and into pageable memory at a
    fraction of it (an H100's driver: 3-4.6 GB/s against about 25); the pieces of a
    host call were therefore copied down into pinned staging and from there, on every
    core, into the caller's arrays (10M segments: 462 MB, 12.5 ms on 16 cores, a third
    of the call). Here the caller's arrays are themselves pinned, so the pieces land
    where they stay: no host copy after the device. Pinning memory is slow (the driver
    locks every page: about 1.6 GB/s on the H100's host, run D), so buffers are kept:
    an array handed out returns its buffer to the pool when its last view is gone, and
    the next call of that size class reuses it. At most `keep_bytes` are kept free, the
    most recently returned: a return beyond that releases the oldest free buffers, so
    buffers of one large call never crowd out the sizes in use after it.

    Parameters
    ----------
    context, queue
        The device's context, and a queue to map the buffers with.
    keep_bytes : int
        Free pinned bytes kept for later calls at most.
    """

    def __init__(self, context: cl.Context, queue: cl.CommandQueue,
                 keep_bytes: int = 1 << 31) -> None:
        self.context = context
        self.queue = queue
        self.keep_bytes = keep_bytes
        # Free buffers, oldest return first (dicts keep insertion order).
        self.free: dict[int, _Pinned] = {}
        self.free_bytes = 0
        self.allocated = 0  # buffers pinned so far (a test reads it: reuse pins none)
        self._lock = threading.Lock()

    @staticmethod
    def size_class(nbytes: int) -> int:
        """Return the bytes of the buffer that holds `nbytes`: powers of two from 64 KiB."""
        return 1 << max(16, (max(nbytes, 1) - 1).bit_length())

    def reusable(self, nbytes: int) -> bool:
        """Return whether a call's outputs of `nbytes` (in size classes) can be reused.

        Pinning costs more than copying the same bytes out of staging many times over
        (run D: 50M segments' 3.5 GB of outputs, pinned anew each call, took 2.1 s against
        0.15 s copied out), so outputs are pinned only where two calls' sets (the one the
        caller holds and the next) fit in what the pool keeps.
        """
        return 2 * nbytes <= self.keep_bytes

    def empty(self, shape: tuple[int, ...], dtype: Any) -> np.ndarray:
        """Return an uninitialised C-contiguous array in pinned memory."""
        dtype = np.dtype(dtype)
        nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
        size = self.size_class(nbytes)
        pinned = None
        with self._lock:
            for key, kept in self.free.items():
                if kept.nbytes == size:
                    pinned = self.free.pop(key)
                    self.free_bytes -= size
                    break
        if pinned is None:
            pinned = _Pinned(self.context, self.queue, size)
            self.allocated += 1
        lease = _Lease(pinned, self)
        weakref.finalize(lease, self._give_back, pinned)
        return np.asarray(lease)[:nbytes].view(dtype).reshape(shape)

    def owns(self, array: np.ndarray) -> bool:
        """Return whether `array` is a view of memory this pool handed out (and is pinned)."""
        base: Any = array
        while isinstance(base, np.ndarray):
            base = base.base
        return isinstance(base, _Lease) and base.pool is self

    def _give_back(self, pinned: _Pinned) -> None:
        with self._lock:
            if pinned.nbytes > self.keep_bytes:
                return
            self.free[id(pinned)] = pinned
            self.free_bytes += pinned.nbytes
            while self.free_bytes > self.keep_bytes:  # release the oldest returns
                oldest = next(iter(self.free))
                self.free_bytes -= self.free.pop(oldest).nbytes


@dataclass
class _Slot:
    """One lane of the pipeline: a queue, staging and device buffers for one chunk."""

    queue: cl.CommandQueue
    capacity: int
    real: Any
    pinned_in: _Pinned
    pinned_out: _Pinned
    segments: cl.Buffer
    buffers: dict
    # The scan's scratch: a pool of the slot's own. A pool hands freed memory out again
    # at once; shared by the two queues, the scratch of one slot's scan, freed while it
    # still runs, went to the other's (garbage slots, pieces written out of bounds, when
    # the pair clip's chunks overlapped). In one in-order queue, reuse waits its turn.
    allocator: Any = None
    # The last copy out of `pinned_in`: its staging memory is free once that is done.
    staged: cl.Event | None = None

    def stage(self, source: np.ndarray, offset: int = 0) -> np.ndarray:
        """Copy `source` into the input staging buffer (once its last upload is done)."""
        if self.staged is not None:
            self.staged.wait()
            self.staged = None
        raw = source.reshape(-1).view(np.uint8)
        staged = self.pinned_in.view[offset:offset + raw.nbytes]
        copy_into(staged, raw)
        return staged


def _device_buffers(context: cl.Context, capacity: int, real: Any) -> dict:
    item = np.dtype(real).itemsize
    size = max(1, capacity)

    def buffer(nbytes: int) -> cl.Buffer:
        return cl.Buffer(context, cl.mem_flags.READ_WRITE, max(8, nbytes))

    return {"result": buffer(6 * item * size), "keep": buffer(8 * size),
            "position": buffer(8 * size), "counters": buffer(8 * _WIDTH * MAX_GROUPS),
            "first_bad": buffer(8 * MAX_GROUPS), "total": buffer(8 * (_WIDTH + 2)),
            "pieces": buffer(4 * item * size), "source": buffer(8 * size),
            "t": buffer(2 * item * size), "window": buffer(4 * size)}


class Staging:
    """The slots of one device and precision, grown to the largest chunk asked for."""

    def __init__(self, context: cl.Context, queues: tuple[cl.CommandQueue, ...]) -> None:
        self.context = context
        self.queues = queues
        self.slots: dict[Any, list[_Slot]] = {}
        # The callers' outputs of float64 calls (`HostOutputs.pinned`).
        self.outputs = PinnedPool(context, queues[0])
        # Device buffers of whole uploads (`upload_whole`), kept for the next call.
        self.uploads = cl.tools.MemoryPool(cl.tools.ImmediateAllocator(queues[0]))

    def slots_for(self, real: Any, chunk: int) -> list[_Slot]:
        """Return the slots for `real` coordinates, each holding at least `chunk` items.

        Capacities are powers of two from 2**12, so a few sizes serve every call.
        """
        capacity = 1 << max(12, (chunk - 1).bit_length())
        slots = self.slots.get(real)
        if slots is None or slots[0].capacity < capacity:
            item = np.dtype(real).itemsize
            slots = [_Slot(queue, capacity, real,
                           _Pinned(self.context, queue, 4 * item * capacity),
                           _Pinned(self.context, queue, (6 * item + 12) * capacity),
                           cl.Buffer(self.context, cl.mem_flags.READ_ONLY,
                                     4 * item * capacity),
                           _device_buffers(self.context, capacity, real),
                           cl.tools.MemoryPool(cl.tools.ImmediateAllocator(queue)))
                     for queue in self.queues]
            self.slots[real] = slots
        return slots


@dataclass
class _Raw:
    """A buffer as pyopencl's scan takes an array argument, without an `Array` object.

    (An `Array` checks its shape with NumPy on creation: about 40 us each, eight per call,
    most of a small device-resident call's host time.)
    """

    base_data: cl.Buffer
    queue: cl.CommandQueue
    allocator: Any
    offset: int = 0
    events: tuple = ()


@dataclass
class SegmentRun:
    """One clip call's kernels and settings: everything but the data."""

    kernels: Any
    scan: GenericScanKernel
    real: Any
    local_size: int
    windows: cl.Buffer
    method: int
    n_fixed: int
    max_depth: int
    tolerance: Any
    exact: int
    want_source: bool
    want_t: bool
    pair_segment: cl.Buffer | None = None
    pair_window: cl.Buffer | None = None
    nowhere: cl.Buffer | None = None
    # Where the scan's scratch and the device outputs come from (the device's pool).
    allocator: Any = None
    # The uploads every clip waits for (the window table), whichever queue it runs on.
    ready: list = field(default_factory=list)
    kernel_events: list = field(default_factory=list)
    copy_events: list = field(default_factory=list)
    bytes_to_device: int = 0
    bytes_from_device: int = 0

    @property
    def pairs(self) -> bool:
        """Return whether the items are (segment, window) pairs."""
        return self.pair_segment is not None

    def clip(self, queue: cl.CommandQueue, segments: cl.Buffer, n: int, first: int,
             buffers: dict, wait_for: list, allocator: Any = None) -> cl.Event:
        """Enqueue the clip, scan and counter reduction of items first..first+n-1.

        Returns the reduction's event: after it, ``buffers["total"]`` holds the counters,
        the first non-finite item and the count of pieces (one row to read back).
        `allocator` gives the scan's scratch: one used by `queue` alone (a slot's), or
        the run's where everything runs on one queue.
        """
        real = self.real
        groups = groups_for(n, self.local_size)
        clip = self.kernels.clip_segments(
            queue, (groups * self.local_size,), (self.local_size,), segments, np.int64(n),
            self.windows, np.int32(self.pairs), np.int64(first), *self._pair_buffers(),
            np.int32(self.method), np.int32(self.n_fixed), np.int32(self.max_depth),
            real(self.tolerance), np.int32(self.exact), buffers["result"], buffers["keep"],
            buffers["counters"], buffers["first_bad"], wait_for=wait_for + self.ready)
        allocator = allocator or self.allocator
        keep = _Raw(buffers["keep"], queue, allocator)
        position = _Raw(buffers["position"], queue, allocator)
        scan = self.scan(keep, position, queue=queue, size=n, allocator=allocator,
                         wait_for=[clip])
        reduce = self.kernels.reduce_counters(
            queue, ((_WIDTH + 1) * self.local_size,), (self.local_size,), buffers["counters"],
            buffers["first_bad"], np.int64(groups), buffers["position"], np.int64(n),
            buffers["total"], wait_for=[scan])
        self.kernel_events += [clip, scan, reduce]
        return reduce

    def write(self, queue: cl.CommandQueue, n: int, first: int, buffers: dict,
              segment_base: int, out: dict) -> cl.Event:
        """Enqueue the write of the kept items' pieces into `out`'s buffers."""
        event = self.kernels.write_pieces(
            queue, (n,), None, buffers["result"], buffers["keep"], buffers["position"],
            np.int64(n), self.windows, np.int32(self.pairs), np.int64(first),
            *self._pair_buffers(),
            np.int64(segment_base), np.int32(self.want_source), np.int32(self.want_t),
            out["pieces"], out["source"], out["t"], out["window"])
        self.kernel_events.append(event)
        return event

    def _pair_buffers(self) -> tuple[cl.Buffer | None, cl.Buffer | None]:
        if not self.pairs:
            return self.nowhere, self.nowhere
        return self.pair_segment, self.pair_window

    def upload(self, queue: cl.CommandQueue, target: cl.Buffer, source: np.ndarray) -> cl.Event:
        """Enqueue a copy of `source` to the device, counted in the call's stats."""
        event = cl.enqueue_copy(queue, target, source, is_blocking=False)
        self.copy_events.append(event)
        self.bytes_to_device += source.nbytes
        return event

    def download(self, queue: cl.CommandQueue, target: np.ndarray, source: cl.Buffer,
                 wait_for: list | None = None, offset: int = 0) -> cl.Event:
        """Enqueue a copy from the device (from byte `offset`), counted in the stats."""
        event = cl.enqueue_copy(queue, target, source, src_offset=offset, is_blocking=False,
                                wait_for=wait_for)
        self.copy_events.append(event)
        self.bytes_from_device += target.nbytes
        return event


@dataclass
class HostOutputs:
    """The caller's arrays, sized for every item kept, cut to the count at the end.

    `direct`: the arrays are pinned (`PinnedPool`) and in the device's dtype, and each
    chunk's pieces are copied straight into them; otherwise they go through the slot's
    pinned staging and are copied (converted, from float32) into ordinary arrays.
    """

    pieces: np.ndarray
    source: np.ndarray | None
    t: np.ndarray | None
    window: np.ndarray | None
    direct: bool = False

    @classmethod
    def empty(cls, n: int, want_source: bool, want_t: bool, pairs: bool,
              pool: PinnedPool | None = None) -> HostOutputs:
        """Return arrays for `n` items: pinned from `pool` if one is given."""
        # np.empty: pages are touched only where pieces land (mapped lazily).
        if pool is not None and not pool.reusable(sum(
                PinnedPool.size_class(n * width) for width, wanted in (
                    (32, True), (8, want_source), (16, want_t), (4, pairs)) if wanted)):
            pool = None  # too large to keep: staged and copied out instead
        new: Any = np.empty if pool is None else pool.empty
        return cls(new((n, 4), np.float64),
                   new((n,), np.int64) if want_source else None,
                   new((n, 2), np.float64) if want_t else None,
                   new((n,), np.int32) if pairs else None, pool is not None)

    def shrink(self, m: int) -> None:
        """Keep the first `m` items."""
        if self.direct:
            self._cut(m)
            return
        # Arrays no one else holds: realloc shrinks them where they are.
        self.pieces.resize((m, 4), refcheck=False)
        if self.source is not None:
            self.source.resize(m, refcheck=False)
        if self.t is not None:
            self.t.resize((m, 2), refcheck=False)
        if self.window is not None:
            self.window.resize(m, refcheck=False)

    def _cut(self, m: int) -> None:
        # Views of the pinned arrays, which stay pinned while the caller holds them;
        # where most items were dropped, the few kept are copied out and the pinned
        # memory goes back to the pool at once (a copy of at most a quarter of it).
        n = self.pieces.shape[0]
        keep_pinned = 4 * m > n

        def cut(array: np.ndarray | None) -> np.ndarray | None:
            if array is None:
                return None
            return array[:m] if keep_pinned else array[:m].copy()

        self.pieces = cast(np.ndarray, cut(self.pieces))
        self.source, self.t, self.window = cut(self.source), cut(self.t), cut(self.window)


def _out_views(slot: _Slot, m: int) -> dict[str, np.ndarray]:
    """Return the slot's pinned output regions for `m` pieces."""
    item = np.dtype(slot.real).itemsize
    c = slot.capacity
    return {"pieces": slot.pinned_out.array(0, slot.real, 4 * m),
            "source": slot.pinned_out.array(4 * item * c, np.int64, m),
            "t": slot.pinned_out.array((4 * item + 8) * c, slot.real, 2 * m),
            "window": slot.pinned_out.array((6 * item + 8) * c, np.int32, m)}


def upload_whole(run: Any, staging: Staging, array: np.ndarray, chunk: int,
                 real: Any = None) -> cl.Buffer:
    """Return a device copy of `array`, streamed through the slots' staging buffers.

    `run` records the copies (``copy_events``, ``bytes_to_device``, ``ready``): a
    `SegmentRun`, or another call's ledger, which then names the slots' `real`.

    The copies of successive pieces alternate between the slots' queues (one piece's
    host copy overlaps the other's transfer); the clips wait for them (``run.ready``).
    An array in the pool's pinned memory (`PinnedPool.owns`: a result of an earlier
    call, or `PinnedPool.empty`) goes up without the host copy.

    The buffer comes from a memory pool (``staging.uploads``): releasing a buffer to
    NVIDIA's driver waits for the whole device (as ``cudaFree`` does), so a pipelined
    call that freed each range's coordinates stalled on the ranges still in flight
    (run D: 16 ms of 59 in a line call, 41 of 326 in a polygon call, in ``dict.clear``).
    A pool of their own: a caller drops such a buffer only once every command that
    reads it is done, whereas the device's pool gets scratch back (a scan's) while its
    kernels still run, and these copies go on either queue.
    """
    slots = staging.slots_for(real or run.real, chunk)
    raw = np.ascontiguousarray(array).reshape(-1).view(np.uint8)
    buffer = cast(cl.Buffer, staging.uploads(max(8, raw.nbytes)))
    step = slots[0].pinned_in.nbytes
    pinned = staging.outputs.owns(raw)  # already page-locked: sent up as it is
    for c, offset in enumerate(range(0, raw.nbytes, step)):
        slot = slots[c % len(slots)]
        staged = raw[offset:offset + step] if pinned else slot.stage(raw[offset:offset + step])
        sent = cl.enqueue_copy(slot.queue, buffer, staged, dst_offset=offset,
                               is_blocking=False)
        if not pinned:
            slot.staged = sent
        run.copy_events.append(sent)
        run.bytes_to_device += staged.nbytes
        run.ready.append(sent)
    return buffer


@dataclass
class _Chunk:
    """One chunk of a pipelined call: its items, its slot, and what came back of it."""

    slot: _Slot
    n: int
    first: int
    # Its counter row as the device reduced it: SEGMENT_COUNTERS counters, the first
    # non-finite item, and the count of pieces (`reduce_counters`).
    row: np.ndarray = field(default_factory=lambda: np.zeros(_WIDTH + 2, np.int64))
    m: int = 0
    offset: int = 0
    events: list = field(default_factory=list)


def clip_host(run: SegmentRun, staging: Staging, data: np.ndarray | None,
              chunk: int, pairs: int = 0,
              segments: cl.Buffer | None = None) -> tuple[HostOutputs, np.ndarray, int]:
    """Clip host segments (or pairs) in pipelined chunks; return outputs, totals, count.

    `data` holds the segments (n, 4) in the device's dtype, streamed up chunk by chunk.
    For pairs, `data` is None: the segments are already on the device whole
    (`segments`, from `upload_whole`), and so are the pair tables (in `run`); the
    chunks are `pairs` items long. Returns the caller's arrays (shrunk), the counter
    totals of each chunk (rows of SEGMENT_COUNTERS + 1, the last the call's first
    non-finite item, or the largest int) and the count of pieces.

    Chunk c, in the slot c % 2: its input is copied into the slot's staging buffer and
    sent up (from where it is, if it is pinned already), and its kernels enqueued; then
    chunk c - 1's count is awaited and its pieces written and sent down (float64:
    straight into the caller's pinned arrays); then chunk c - 2's pieces, down by now,
    are copied into the caller's arrays (float32: converted; float64: nothing to do but
    wait), while the device works on chunks c and c - 1.
    """
    n = data.shape[0] if data is not None else pairs
    slots = staging.slots_for(run.real, min(max(n, 1), chunk))
    outputs = HostOutputs.empty(n, run.want_source, run.want_t, run.pairs,
                                staging.outputs if run.real is np.float64 else None)
    # Input already page-locked (an earlier call's pieces, `PinnedPool.empty`): sent up
    # from where it is, without the copy into the staging buffer.
    pinned_input = data is not None and staging.outputs.owns(data)
    chunks: list[_Chunk] = []
    m = 0
    chunk = slots[0].capacity
    for c, start in enumerate(range(0, n, chunk)):
        slot = slots[c % len(slots)]
        item = _Chunk(slot, min(chunk, n - start), start)
        if data is not None:
            if pinned_input:
                sent = run.upload(slot.queue, slot.segments, data[start:start + item.n])
            else:
                slot.staged = sent = run.upload(slot.queue, slot.segments,
                                                slot.stage(data[start:start + item.n]))
            _start(run, item, slot.segments, [sent])
        else:
            assert segments is not None
            _start(run, item, segments, [])
        chunks.append(item)
        if c >= 1:
            m = _finish(run, chunks[c - 1], m, outputs)
        if c >= 2:
            _drain(chunks[c - 2], outputs)
    if chunks:
        m = _finish(run, chunks[-1], m, outputs)
    for item in chunks[-2:]:
        _drain(item, outputs)
    outputs.shrink(m)
    totals = np.array([item.row[:_WIDTH + 1] for item in chunks], np.int64)
    return outputs, totals.reshape(-1, _WIDTH + 1), m


def _start(run: SegmentRun, chunk: _Chunk, segments: cl.Buffer, wait_for: list) -> None:
    """Enqueue the chunk's clip, scan and reduction, and the download of its row."""
    slot = chunk.slot
    reduced = run.clip(slot.queue, segments, chunk.n, chunk.first if run.pairs else 0,
                       slot.buffers, wait_for, slot.allocator)
    chunk.events = [run.download(slot.queue, chunk.row, slot.buffers["total"],
                                 wait_for=[reduced])]


def _finish(run: SegmentRun, chunk: _Chunk, m: int, outputs: HostOutputs) -> int:
    """Wait for the chunk's row, enqueue its write and downloads; return the new count.

    The pieces go down into the caller's arrays where they are pinned (`direct`), else
    into the slot's staging (`_drain` copies them on).
    """
    cl.wait_for_events(chunk.events)
    row = chunk.row
    # The call's index of the chunk's first non-finite item, or none (the largest int).
    row[_WIDTH] = row[_WIDTH] + chunk.first if row[_WIDTH] < chunk.n else _NONE
    chunk.m = int(row[_WIDTH + 1])
    chunk.offset = m
    chunk.events = []
    slot = chunk.slot
    if chunk.m:
        base = 0 if run.pairs else chunk.first
        write = run.write(slot.queue, chunk.n, chunk.first, slot.buffers, base, slot.buffers)
        views = _out_views(slot, chunk.m)
        if outputs.direct:
            a, b = m, m + chunk.m
            views = {name: array[a:b] for name, array in (
                ("pieces", outputs.pieces), ("source", outputs.source), ("t", outputs.t),
                ("window", outputs.window)) if array is not None}
        wanted = ["pieces"] + (["source"] if run.want_source else []) + (
            ["t"] if run.want_t else []) + (["window"] if run.pairs else [])
        chunk.events = [run.download(slot.queue, views[name], slot.buffers[name],
                                     wait_for=[write]) for name in wanted]
    return m + chunk.m


def _drain(chunk: _Chunk, outputs: HostOutputs) -> None:
    """Wait for the chunk's downloads; copy its pieces into the caller's arrays if staged."""
    if chunk.events:
        cl.wait_for_events(chunk.events)
    m, a = chunk.m, chunk.offset
    if m and not outputs.direct:
        views = _out_views(chunk.slot, m)
        _land(outputs.pieces[a:a + m], views["pieces"])
        if outputs.source is not None:
            copy_into(outputs.source[a:a + m], views["source"])
        if outputs.t is not None:
            _land(outputs.t[a:a + m], views["t"])
        if outputs.window is not None:
            copy_into(outputs.window[a:a + m], views["window"])
    chunk.events = []


def _land(target: np.ndarray, staged: np.ndarray) -> None:
    """Copy device reals into float64 output rows (a conversion on a float32 device)."""
    if staged.dtype == np.float64:
        copy_into(target.reshape(-1), staged)
    else:
        target.reshape(-1)[...] = staged


def clip_device(run: SegmentRun, queue: cl.CommandQueue, segments: cl_array.Array, n: int,
                allocator: Any) -> tuple[dict, np.ndarray, int]:
    """Clip segments (or pairs) already on the device; return device outputs, totals, m.

    The outputs are `pyopencl.array.Array` objects of exactly the pieces kept; only the
    count and the counter row come back to the host.
    """
    item = np.dtype(run.real).itemsize
    size = max(1, n)

    def scratch(nbytes: int) -> cl.Buffer:
        return allocator(max(8, nbytes))

    buffers = {"result": scratch(6 * item * size), "keep": scratch(8 * size),
               "position": scratch(8 * size), "counters": scratch(8 * _WIDTH * MAX_GROUPS),
               "first_bad": scratch(8 * MAX_GROUPS), "total": scratch(8 * (_WIDTH + 2))}
    row = np.zeros(_WIDTH + 2, np.int64)
    row[_WIDTH] = n
    m = 0
    if n:
        reduced = run.clip(queue, cast(cl.Buffer, segments.data), n, 0, buffers, [])
        run.download(queue, row, buffers["total"], wait_for=[reduced]).wait()
        m = int(row[_WIDTH + 1])
    out_arrays = {
        "pieces": cl_array.empty(queue, (m, 4), run.real, allocator=allocator),
        "source": cl_array.empty(queue, m, np.int64, allocator=allocator)
        if run.want_source else None,
        "t": cl_array.empty(queue, (m, 2), run.real, allocator=allocator)
        if run.want_t else None,
        "window": cl_array.empty(queue, m, np.int32, allocator=allocator)
        if run.pairs else None}
    if m:
        out = {name: (array.data if array is not None and array.size else run.nowhere)
               for name, array in out_arrays.items()}
        run.write(queue, n, 0, buffers, 0, out).wait()
    return out_arrays, row[:_WIDTH + 1].reshape(1, -1), m
