"""Lines and rings on an OpenCL device, in ranges the host assembles while the device works.

The device's share of a line or polygon call (`RunCall`): ``chunk_boxes`` (one
work-item per chunk of 16 segments), ``classify_runs`` (RNSCA over runs of chunks, one
work-item per line or ring) and ``clip_chunk_segments`` (the segments of undecided
chunks, one work-item per chunk, into slots from a prefix sum). The host's share, the
assembly of chains and of polygons along the window (the Numba kernels), reads the
device's decisions and pieces; it is most of such a call (1M stars on an H100 and its
16 cores: the Numba assembly 126 ms, the device's kernels 0.3 ms and transfers 38 ms).

So a large call is cut into ranges of parts (`ranges_by_vertices`) and pipelined
(`pipelined`): while the host assembles range i, the device has the clip of range
i + 1 and the classification of range i + 2 before it, and the host waits for the
device only at the two ends. Each range is three steps: `RunCall.start` (the range's
input staged and sent up, its chunks classified, the prefix sum of their piece counts
and a non-blocking read of it), `RunCall.clip` (once that count is back: the clip of
the undecided chunks and non-blocking reads of the decisions and pieces) and
`RunCall.finish` (the reads awaited; the tables the assembly reads). Nothing waits
for the device between `start` and `finish` but `clip`'s read of one count, which the
device has done while the host assembled the range before.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol, TypeVar, cast

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from rnsca.arrays import exclusive_sum
from rnsca.backends.base import METHOD_ID
from rnsca.backends.opencl import segments as _segments
from rnsca.backends.opencl.segments import _Raw
from rnsca.kernels import counters as C
from rnsca.kernels import polylines as PL
from rnsca.options import Method, Mode, Precision, SegmentOptions
from rnsca.stats import DeviceStats

__all__ = ["Ledger", "RunCall", "Tables", "buffer_of", "event_seconds", "exact_float32_ends",
           "pipelined", "ranges_by_vertices", "Stages", "PIPELINE_VERTICES", "MAX_RANGES"]

#: Vertices per range of a pipelined line or ring call: 64 MB of float64 coordinates.
#: Measured on an H100 (run D, `benchmarks/gpu.py`'s range sweep): 14M-vertex lines took
#: 64 / 64 / 43 / 39 ms in ranges of 2**19 / 2**20 / 2**21 / 2**22 vertices (31.5 ms in
#: one range), 1M stars 319 / 291 / 287 / 284 ms (298 in one): each range's launches,
#: reads and host passes cost more than the overlap of small ranges gains there.
PIPELINE_VERTICES = 1 << 22
#: Ranges per call at most: the host's fixed cost per range (a count and a write pass
#: of the Numba assembly, each starting the threads) stays small.
MAX_RANGES = 16

T = TypeVar("T")
Out = TypeVar("Out", covariant=True)


class Stages(Protocol[Out]):
    """A call that takes ranges in flight through its last two steps (`RunCall`, curves)."""

    def clip(self, r: Any) -> None:
        """Enqueue the range's second step once its first is far enough."""

    def finish(self, r: Any) -> Out:
        """Wait for the range and return what it gives."""


def buffer_of(array: cl_array.Array) -> cl.Buffer:
    """Return the buffer of a device array, a 1-byte placeholder for an empty one.

    pyopencl types `Array.data` as optional (an SVM array has none); these arrays are
    all allocated from buffers.
    """
    if not array.size:
        return cl.Buffer(cast(cl.Context, array.context), cl.mem_flags.READ_ONLY, 1)
    return cast(cl.Buffer, array.data)


def event_seconds(events: list[cl.Event]) -> float:
    """Return the seconds the device spent on `events` (profiled queues)."""
    return sum(e.profile.end - e.profile.start for e in events) * 1e-9


class Ledger:
    """Transfers and kernel runs of one call, timed by OpenCL event profiling."""

    def __init__(self) -> None:
        self.bytes_to_device = 0
        self.bytes_from_device = 0
        self.copy_events: list[cl.Event] = []
        self.kernel_events: list[cl.Event] = []
        # Uploads on the other queue (`staged`), which the first kernels wait for.
        self.ready: list[cl.Event] = []

    @property
    def transfers(self) -> int:
        """Return the number of host-device copies so far."""
        return len(self.copy_events)

    def staged(self, device: Any, array: np.ndarray, chunk: int) -> Any:
        """Return a device copy of `array`: a large one through the pinned staging buffers.

        On every core into page-locked memory, then at full bus speed, in pieces that
        alternate between the device's two queues (`segments.upload_whole`; the kernels
        that read it wait for ``ready``); a small one is uploaded into a pooled buffer.
        """
        if array.nbytes < (1 << 20) or device.staging is None:
            return self.upload(device.queue, array, device.allocator)
        return _segments.upload_whole(self, device.staging, array, chunk, np.float64)

    def upload(self, queue: cl.CommandQueue, array: np.ndarray, allocator: Any) -> Any:
        """Return a pooled device buffer holding `array`, copied without waiting.

        The caller keeps `array` alive until the copy is done. A raw buffer, not an
        `Array`: creating one of those costs tens of microseconds of NumPy checks, and
        a pipelined call makes a dozen per range.
        """
        buffer = allocator(max(8, array.nbytes))
        if array.nbytes:
            self.copy_events.append(cl.enqueue_copy(queue, buffer, array, is_blocking=False))
            self.bytes_to_device += array.nbytes
        return buffer

    def read(self, queue: cl.CommandQueue, buffer: Any, dtype: Any, count: int) -> np.ndarray:
        """Return `count` items of `dtype` from a raw buffer, landing later (`settle`)."""
        out = np.empty(count, dtype)
        if out.nbytes:
            self.copy_events.append(cl.enqueue_copy(queue, out, buffer, is_blocking=False))
            self.bytes_from_device += out.nbytes
        return out

    def settle(self) -> None:
        """Wait for every copy and kernel of the call so far."""
        if self.copy_events or self.kernel_events:  # OpenCL refuses an empty wait list
            cl.wait_for_events(self.copy_events + self.kernel_events)

    def stats(self, device: str, precision: Precision) -> DeviceStats:
        """Return the call's transfers and device times, once all of them are done."""
        self.settle()
        return DeviceStats(device=device, precision=precision.value, transfers=self.transfers,
                           bytes_to_device=self.bytes_to_device,
                           bytes_from_device=self.bytes_from_device,
                           transfer_seconds=event_seconds(self.copy_events),
                           kernel_seconds=event_seconds(self.kernel_events))


def ranges_by_vertices(vertex_ends: np.ndarray, target: int | None = None,
                       ) -> list[tuple[int, int]]:
    """Cut items 0..n-1 into consecutive ``(first, end)`` ranges of about `target` vertices.

    `vertex_ends[i]` is the count of vertices of items 0..i (an inclusive prefix sum).
    At most `MAX_RANGES` ranges, none empty; one range for a small call, and an empty
    list for no items. `target` defaults to `PIPELINE_VERTICES`.
    """
    target = PIPELINE_VERTICES if target is None else target
    n = int(vertex_ends.shape[0])
    if n == 0:
        return []
    total = int(vertex_ends[-1])
    k = max(1, min(MAX_RANGES, n, -(-total // max(1, target))))
    # Each cut after the first item whose prefix reaches its share of the vertices.
    shares = total * np.arange(1, k, dtype=np.int64) // k
    cuts = np.unique(np.searchsorted(vertex_ends, shares, side="left") + 1)
    cuts = cuts[(cuts > 0) & (cuts < n)]
    bounds = [0, *cuts.tolist(), n]
    return list(zip(bounds[:-1], bounds[1:], strict=True))


class Tables(NamedTuple):
    """The device's decisions for one range's parts, as `polylines.Decisions` reads them.

    Per part its first chunk (int64); per chunk its decision (uint8, ``CHUNK_*``) and
    first piece row (int64); per piece row whether it is kept (bool) and ``(t0, t1, ax,
    ay, bx, by)`` in float64 (uncut ends are the exact input vertices).
    """

    chunk_start: np.ndarray
    decision: np.ndarray
    piece_start: np.ndarray
    keep: np.ndarray
    pieces: np.ndarray


@dataclass
class _Range:
    """One range of parts in flight: its host tables and its device buffers."""

    xy: np.ndarray
    part_offsets: np.ndarray
    part_window: np.ndarray
    chunk_start: np.ndarray
    chunk_part: np.ndarray
    n_chunks: int
    part_groups: int
    device: dict = field(default_factory=dict)
    held: list = field(default_factory=list)
    # Read back without waiting; valid once `RunCall.clip` (piece_end) or
    # `RunCall.finish` (the rest) has waited for them.
    piece_end: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    piece_end_read: list = field(default_factory=list)
    reads: dict = field(default_factory=dict)
    total: int = 0


class RunCall:
    """One line or ring call's device work: its window table, settings and ledger.

    Parameters
    ----------
    device
        The backend's `_Device` (queue, staging, program, call lock).
    real
        The device's coordinate dtype.
    windows : ndarray of float64, shape (k, 4)
        The call's window table.
    options : SegmentOptions
    drop_edge_runs : bool
        Runs along an edge are not accepted whole (rings: they break there).
    local_size : int
        Work-items per group of the kernels that sum counters per group.
    """

    def __init__(self, device: Any, real: Any, windows: np.ndarray, options: SegmentOptions,
                 drop_edge_runs: bool, local_size: int) -> None:
        self.device = device
        self.local_size = local_size
        self.real = real
        self.windows = windows
        self.options = options
        self.drop_edge_runs = drop_edge_runs
        self.ledger = Ledger()
        self.counters: list[np.ndarray] = []
        with np.errstate(over="ignore"):
            self.bounds = np.ascontiguousarray(windows, dtype=real)
        with device.call_lock:
            self.kernels = device.program(real is np.float64)
            self.d_windows = self.ledger.upload(device.queue, self.bounds.reshape(-1),
                                                device.allocator)

    def start(self, data: np.ndarray, xy: np.ndarray, part_offsets: np.ndarray,
              part_window: np.ndarray) -> _Range:
        """Send a range up and classify its chunks; return it in flight.

        `data` is the range's vertices in the device's dtype, `xy` the same in float64
        (a float32 device's uncut ends are put back from it), `part_offsets` its parts'
        offsets into them (from 0) and `part_window` their rows of the window table.
        """
        ledger = self.ledger
        device = self.device
        queue = device.queue
        n_parts = part_offsets.shape[0] - 1
        segments = np.maximum(np.diff(part_offsets), 1) - 1
        chunks_per_part = -(-segments // PL.RUN_LEAF_SEGMENTS)
        chunk_start = exclusive_sum(chunks_per_part)
        n_chunks = int(chunk_start[-1])
        chunk_part = np.repeat(np.arange(n_parts, dtype=np.int64), chunks_per_part)
        local = self.local_size
        part_groups = max(1, -(-n_parts // local))
        r = _Range(xy, part_offsets, part_window, chunk_start, chunk_part, n_chunks,
                   part_groups)
        n_runs = self.options.n if self.options.n > 0 else PL.RUN_N_AUTO
        item = np.dtype(self.real).itemsize
        with device.call_lock:
            alloc = device.allocator
            d = r.device
            d["xy"] = ledger.staged(device, data.reshape(-1), _segments.CHUNK_SEGMENTS)
            # Not waited for: the host arrays live as long as the range (`r.held`).
            r.held = [np.ascontiguousarray(part_offsets, np.int64), chunk_start, chunk_part,
                      np.ascontiguousarray(part_window, np.int64)]
            for name, array in zip(("offsets", "chunk_start", "chunk_part", "part_window"),
                                   r.held, strict=True):
                d[name] = ledger.upload(queue, array, alloc)
            d["boxes"] = alloc(max(8, 4 * item * n_chunks))
            d["decision"] = alloc(max(8, n_chunks))
            d["segmented"] = alloc(max(8, 8 * n_chunks))
            d["position"] = alloc(max(8, 8 * n_chunks))
            d["run_counters"] = alloc(8 * part_groups * C.WIDTH)
            # Kernels wait for the uploads through the staging queue(s).
            ready = list(ledger.ready)
            if n_chunks:
                ledger.kernel_events.append(self.kernels.chunk_boxes(
                    queue, (n_chunks,), None, d["xy"], d["offsets"], d["chunk_start"],
                    d["chunk_part"], np.int64(n_chunks), d["boxes"], wait_for=ready))
            ledger.kernel_events.append(self.kernels.classify_runs(
                queue, (part_groups * local,), (local,), d["boxes"], d["offsets"],
                d["chunk_start"], d["part_window"], self.d_windows, np.int64(n_parts),
                np.int32(n_runs), np.int32(self.drop_edge_runs),
                np.int32(self.options.method is Method.RNSCA), device.nowhere, np.int32(1),
                d["decision"], d["segmented"], d["run_counters"], wait_for=ready))
            if n_chunks:
                # The chunks' piece rows, inclusive: the assembly's piece_start, shifted.
                ledger.kernel_events.append(device.scan()(
                    _Raw(d["segmented"], queue, alloc), _Raw(d["position"], queue, alloc),
                    queue=queue, size=n_chunks, allocator=alloc))
                r.piece_end = ledger.read(queue, d["position"], np.int64, n_chunks)
                r.piece_end_read = ledger.copy_events[-1:]
            queue.flush()
        return r

    def clip(self, r: _Range) -> None:
        """Clip the range's undecided chunks once their count is back; read all back later."""
        ledger = self.ledger
        device = self.device
        queue = device.queue
        options = self.options
        if r.piece_end_read:
            cl.wait_for_events(r.piece_end_read)
        r.total = total = int(r.piece_end[-1]) if r.n_chunks else 0
        local = self.local_size
        chunk_groups = max(1, -(-r.n_chunks // local))
        d = r.device
        item = np.dtype(self.real).itemsize
        with device.call_lock:
            alloc = device.allocator
            reads_from = len(ledger.copy_events)
            d["keep"] = alloc(max(8, total))
            d["result"] = alloc(max(8, 6 * item * total))
            d["chunk_counters"] = alloc(8 * chunk_groups * C.WIDTH)
            ledger.kernel_events.append(self.kernels.clip_chunk_segments(
                queue, (chunk_groups * local,), (local,), d["xy"], d["offsets"],
                d["chunk_start"], d["chunk_part"], d["part_window"], self.d_windows,
                np.int64(r.n_chunks), d["decision"], d["segmented"], d["position"],
                np.int32(METHOD_ID[options.method]), np.int32(options.n),
                np.int32(options.max_depth), self.real(options.tolerance),
                np.int32(options.mode is Mode.EXACT), d["keep"], d["result"],
                d["chunk_counters"]))
            r.reads = {
                "decision": ledger.read(queue, d["decision"], np.uint8, r.n_chunks),
                "keep": ledger.read(queue, d["keep"], np.uint8, total),
                "pieces": ledger.read(queue, d["result"], self.real, 6 * total),
                "run_counters": ledger.read(queue, d["run_counters"], np.int64,
                                            r.part_groups * C.WIDTH),
                "chunk_counters": ledger.read(queue, d["chunk_counters"], np.int64,
                                              chunk_groups * C.WIDTH)}
            r.reads["events"] = ledger.copy_events[reads_from:]
            queue.flush()

    def finish(self, r: _Range) -> Tables:
        """Wait for the range's reads; return its tables (and keep its counter rows)."""
        events = r.reads.pop("events")
        if events:
            cl.wait_for_events(events)
        reads = r.reads
        total = r.total
        n_chunks = r.n_chunks
        self.counters += [reads["run_counters"].reshape(-1, C.WIDTH),
                          reads["chunk_counters"].reshape(-1, C.WIDTH)]
        piece_start = np.zeros(n_chunks, dtype=np.int64)
        if n_chunks:
            piece_start[1:] = r.piece_end[:-1]
        pieces = reads["pieces"].reshape(total, 6).astype(np.float64, copy=False)
        if self.real is np.float32:
            # Each chunk's first vertex, and its rows among the pieces.
            chunk_first = (r.part_offsets[r.chunk_part] + (np.arange(n_chunks)
                           - r.chunk_start[r.chunk_part]) * PL.RUN_LEAF_SEGMENTS)
            exact_float32_ends(pieces, r.xy, self.windows, r.part_window, r.chunk_part,
                               chunk_first, np.diff(piece_start, append=total))
        r.device.clear()  # the device buffers go back
        r.held.clear()
        return Tables(r.chunk_start[:-1].copy(), reads["decision"], piece_start,
                      reads["keep"].view(np.bool_), pieces)

    def totals(self, name: str, precision: Precision) -> tuple[np.ndarray, DeviceStats]:
        """Return the call's device counter rows and stats, once every range is finished."""
        counters = (np.concatenate(self.counters) if self.counters
                    else np.zeros((0, C.WIDTH), dtype=np.int64))
        return counters, self.ledger.stats(name, precision)


def pipelined(call: Stages[Out], ranges: Sequence[T], start: Callable[[T], Any],
              ) -> Iterator[tuple[T, Out]]:
    """Yield each range with its tables, in order, the device ahead of the consumer.

    `start` sends a range up (`RunCall.start`). Range i + 1 is started and range i
    clipped before range i - 1 is yielded: while the consumer assembles range i - 1,
    the device works on those two.
    """
    previous: tuple[T, Any] | None = None
    current: tuple[T, Any] | None = None
    for item in ranges:
        upcoming = (item, start(item))
        if current is not None:
            call.clip(current[1])
            if previous is not None:
                yield previous[0], call.finish(previous[1])
            previous = current
        current = upcoming
    if current is not None:
        call.clip(current[1])
    for pending in (previous, current):
        if pending is not None:
            yield pending[0], call.finish(pending[1])


def exact_float32_ends(pieces: np.ndarray, xy: np.ndarray, windows: np.ndarray,
                       part_window: np.ndarray, chunk_part: np.ndarray,
                       chunk_first: np.ndarray, rows: np.ndarray) -> None:
    """Give float32 pieces their input vertices back, and keep them in their windows.

    An end not cut (t = 0 or 1) is an input vertex, but rounded to float32: the host
    puts the float64 vertex back, so chains join at it as on the other backends. A cut
    end lies exactly on the float32 edge line: it is put on the float64 one (the polygon
    walk compares boundary positions exactly), and every end is clamped into the window.
    """
    segment = np.repeat(chunk_first, rows) + (np.arange(pieces.shape[0])
                                              - np.repeat(np.cumsum(rows) - rows, rows))
    window = windows[part_window[np.repeat(chunk_part, rows)]]
    start = pieces[:, 0] == 0.0
    end = pieces[:, 1] == 1.0
    pieces[start, 2:4] = xy[segment[start]]
    pieces[end, 4:6] = xy[segment[end] + 1]
    rounded = window.astype(np.float32).astype(np.float64)
    for column, bound in ((2, 0), (3, 1), (4, 0), (5, 1)):
        values = pieces[:, column]
        for side in (bound, bound + 2):
            on_edge = values == rounded[:, side]
            values[on_edge] = window[on_edge, side]
        np.clip(values, window[:, bound], window[:, bound + 2], out=values)
