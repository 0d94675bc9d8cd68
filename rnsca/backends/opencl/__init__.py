"""The OpenCL backend: the kernels of ``clip.cl`` run through pyopencl.

Segments: one work-item clips one segment (RNSCA with its depth-first stack, or a
baseline) and the output, at most one piece per segment, is compacted in three steps,
as a GPU wants it: ``clip_segments`` stores each segment's result and a 0/1 count,
pyopencl's prefix sum (``pyopencl.array.cumsum``) turns the counts into slots, and
``write_pieces`` copies the kept results there. Only the segments go to the device and
only the pieces (and one counter row per work-group) come back.

Many windows (`OpenCLBackend.clip_segment_windows`): the (segment, window) pairs are
made on the device, where the segments are (`windows.assign_on_device`: the host's
assignment ported, the same pairs in the same order), and clipped as segments are,
each item a pair; only the pairs' count comes back before the clip.

Vector tiles of segment pieces (`OpenCLBackend.encode_segment_tiles`, `tiles.py`): the
pieces of a many-window clip, on the device where it left them, are sized as MVT
features, placed by a prefix sum and written, one work-item per piece, and each tile
framed there; only the per-tile byte counts and the tiles' bytes come back.

Lines and rings (`runs.RunCall`): ``chunk_boxes`` (one work-item per chunk of 16
segments), ``classify_runs`` (RNSCA over runs of chunks, one work-item per line or ring)
and ``clip_chunk_segments`` (the segments of undecided chunks, one work-item per chunk,
into slots from a prefix sum) run on the device; the chains, and for polygons the walk
along the window, are assembled on the host by the Numba kernels that do it for the
Numba backend (`polylines.assemble_line_blocks`, `polygons.clip_polygon_blocks` with
decided chunks). The split keeps the sequential, data-dependent assembly (output order,
joins, the boundary walk) on the host, and the per-segment work on the device; a large
call goes in ranges of parts, so the host assembles one range while the device works on
the next (`runs.pipelined`).

Bézier paths (`curves.CurveCall`, for `rnsca.clip_paths` and `rnsca.flatten_paths`):
``classify_bezier`` (one work-item per segment: its class by its control points'
outcodes, and the step count of the segments to flatten), ``classify_bezier_runs`` (one
work-item per run of 16 segments: the box of its control points) and, after a prefix
sum of the step counts, ``flatten_bezier`` (each segment's points into its slots) run
on the device; the Numba path kernel (`bezier.clip_path_blocks` with decisions) reads
the classes, run decisions and points and does the ambiguous segments and the output
on the host, as it does for the Numba backend; a large call goes in ranges of subpaths
(`PIPELINE_SEGMENTS`), the host's count pass of one overlapping the device's work on
the next. On a float32 device the device's classes are conservative (inside, or beyond
an edge, only where that is sure for the float64 input: `curves.windows32`); the host
decides the rest from the float64 input and flattens in float64, so the output is the
float64 output exactly (only the device's share differs).

Devices and programs: the device is picked once per backend (`select_device`); each
device gets one context and one profiling queue per process, and ``clip.cl`` is built
once per (context, build options) and kept (`_Device.program`). The build options give
it the precision, the work-group size and every constant it shares with the Numba
kernels (`constant_options`: ``rnsca.constants``, which ``clip.cl`` never defines
itself). pyopencl and the OpenCL driver also cache built binaries on disk (keyed on
the source and the options), so a second process builds fast.

Precision: float64 where the device has ``cl_khr_fp64``, else float32 (or float32 when
asked for, on any device). The float32 path clips the input rounded to float32; see
the README ("OpenCL backend") for its error bound, which the tests check.

This module imports pyopencl at import time; only `rnsca.backends.registry` imports
it, and turns a failure into `BackendUnavailableError`.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from importlib import resources
from typing import Any, cast

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
import pyopencl.tools
from pyopencl.scan import GenericScanKernel

from rnsca import constants
from rnsca.arrays import (
    PathArrays,
    Ragged,
    check_segment_values,
    exclusive_sum,
    group_offsets,
    segment_error,
    tile_piece_error,
)
from rnsca.backends.base import (
    METHOD_ID,
    Capabilities,
    GeometryPieces,
    Operation,
    PathPieces,
    Polylines,
    SegmentPieces,
    TileBytes,
    TileLayer,
)
from rnsca.backends.numba_cpu import (
    DevicePaths,
    DevicePolygons,
    NumbaBackend,
    PathRange,
    PolygonRange,
    polygon_geometry,
    polyline_layout,
    warm_up_geometry,
    warm_up_paths,
    warm_up_segments,
    warm_up_tiles,
)
from rnsca.backends.opencl import segments as _segments
from rnsca.backends.opencl import windows as _windows
from rnsca.backends.opencl.curves import CurveCall
from rnsca.backends.opencl.runs import (
    Ledger,
    RunCall,
    buffer_of,
    event_seconds,
    pipelined,
    ranges_by_vertices,
)
from rnsca.backends.opencl.tiles import encode_on_device
from rnsca.errors import BackendUnavailableError, InvalidGeometryError, InvalidWindowError
from rnsca.kernels import bezier as BZ
from rnsca.kernels import counters as C
from rnsca.kernels import polygons as PG
from rnsca.kernels import polylines as PL
from rnsca.kernels import records as R
from rnsca.kernels.copies import copy_ranges
from rnsca.many_windows import assign, window_finder
from rnsca.options import Backend, Curves, Mode, PathOptions, Precision, SegmentOptions
from rnsca.stats import ClipStats, DeviceStats
from rnsca.window import Window, WindowTable

__all__ = ["OpenCLBackend", "list_devices", "select_device", "constant_options",
           "FLOAT32_RELATIVE_BOUND", "LOCAL_SIZE"]

# The host half of the OpenCL backend's lines, polygons and paths: the Numba backend's
# passes, fed with the device's decisions.
_HOST = NumbaBackend()

#: Work-items per group: the stats are summed per group in local memory.
LOCAL_SIZE = 64
#: float32 mode: each piece end lies within this many units of the float32 rounding
#: (2**-24) of ``max(|coordinates of its segment|, |window bounds|)`` of the exact clip
#: of the input rounded to float32 (README, "OpenCL backend"). Tested.
FLOAT32_RELATIVE_BOUND = 16 * 2.0 ** -24

# Counters the segment kernel fills: the head of the row (rnsca.kernels.counters).
_SEGMENT_COUNTERS = constants.SEGMENT_COUNTERS
_F32 = np.finfo(np.float32)
#: Segments per range of a pipelined path call (`clip_paths`): the host's path kernel
#: costs far more per segment than the line assembly per vertex.
PIPELINE_SEGMENTS = 1 << 17


def constant_options() -> list[str]:
    """Return the build options that give ``clip.cl`` the constants it shares with Numba.

    One ``-DNAME=value`` per name in `rnsca.constants.__all__`, in that order; a
    negative value is parenthesized, as a ``#define`` would write it.

    Raises
    ------
    TypeError
        If one of them is not an int (``clip.cl`` takes only ints from there: a float
        literal would be a double, which a float32 device may not have).
    """
    options = []
    for name in constants.__all__:
        value = getattr(constants, name)
        if type(value) is not int:
            raise TypeError(f"rnsca.constants.{name} = {value!r} is not an int")
        options.append(f"-D{name}={value}" if value >= 0 else f"-D{name}=({value})")
    return options


def _build_options(double: bool) -> tuple[str, ...]:
    """Return the options ``clip.cl`` is built with for float64 (`double`) or float32."""
    options = (f"-DREAL_IS_DOUBLE={int(double)}", f"-DLOCAL_SIZE={LOCAL_SIZE}",
               *constant_options())
    if not double:  # OpenCL's float32 division may be 2.5 ulp otherwise
        options += ("-cl-fp32-correctly-rounded-divide-sqrt",)
    return options


# Per precision, made once: `_Device.program` looks them up on every call.
_BUILD_OPTIONS = {double: _build_options(double) for double in (False, True)}


def list_devices() -> list[dict]:
    """Return every OpenCL device found: platform and device index, names, type, fp64.

    Raises
    ------
    BackendUnavailableError
        If the OpenCL runtime finds no platform (no driver installed).
    """
    try:
        platforms = cl.get_platforms()
    except cl.Error as exc:  # the ICD loader's "no platform" is an error, not []
        raise BackendUnavailableError(
            f"no OpenCL platform found ({exc}); install a driver, or PoCL for the CPU: "
            "pip install 'rnsca[opencl]'") from None
    found = []
    for p, platform in enumerate(platforms):
        try:
            devices = platform.get_devices()
        except cl.Error:  # a platform without devices
            continue
        for d, device in enumerate(devices):
            found.append({
                "id": f"{p}:{d}",
                "platform": platform.name.strip(),
                "device": device.name.strip(),
                "type": _device_type(device.type),
                "fp64": "cl_khr_fp64" in device.extensions,
                "max_work_group_size": int(device.max_work_group_size),
                "version": device.version.strip(),
            })
    if not found:
        raise BackendUnavailableError(
            "no OpenCL device found; install a driver, or PoCL for the CPU: "
            "pip install 'rnsca[opencl]'")
    return found


def _device_type(bits: int) -> str:
    """Return "gpu", "cpu", "accelerator" or "other" (drivers may set several bits)."""
    for name in ("gpu", "cpu", "accelerator"):
        if bits & getattr(cl.device_type, name.upper()):
            return name
    return "other"


def select_device(spec: str | None = None) -> dict:
    """Return the entry of `list_devices` that `spec` names.

    `spec` is ``"platform:device"`` (indices, as `list_devices` numbers them), or a
    case-insensitive substring of ``"<platform> <device> <version>"`` (the first match);
    None picks the first GPU, else the first device.

    Raises
    ------
    BackendUnavailableError
        If no device is found, or none matches `spec` (the message lists them).
    """
    devices = list_devices()
    if spec is None or not spec.strip():
        gpus = [d for d in devices if d["type"] == "gpu"]
        return (gpus or devices)[0]
    spec = spec.strip()
    for entry in devices:
        if entry["id"] == spec:
            return entry
    for entry in devices:
        if spec.lower() in f"{entry['platform']} {entry['device']} {entry['version']}".lower():
            return entry
    listing = "; ".join(f"{d['id']} {d['platform']} / {d['device']}" for d in devices)
    raise BackendUnavailableError(
        f"no OpenCL device matches {spec!r} (give 'platform:device' or part of a name); "
        f"found: {listing}")


@dataclass
class _Device:
    """One device's context, profiling queue and built programs (one per process)."""

    name: str
    context: cl.Context
    queue: cl.CommandQueue
    programs: dict = field(default_factory=dict)
    # A second in-order queue: a pipelined segment call alternates its chunks between
    # the two, so one chunk's transfers overlap the other's kernels (`segments.py`).
    second_queue: cl.CommandQueue | None = None
    staging: _segments.Staging | None = None
    # Device scratch and the outputs kept on the device come from a pool, not one
    # allocation per call.
    allocator: cl.tools.MemoryPool | None = None
    scans: dict = field(default_factory=dict)
    # An 8-byte buffer for the kernels' unused buffer arguments.
    nowhere: cl.Buffer | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)
    # Kernel objects hold their arguments and are shared by every backend on this
    # device: one call at a time sets and enqueues them.
    call_lock: threading.Lock = field(default_factory=threading.Lock)

    def program(self, double: bool) -> _Kernels:
        """Return the kernels of ``clip.cl`` built for float64 (`double`) or float32.

        Built once per set of build options (`_build_options`), the key they are kept by.
        """
        options = _BUILD_OPTIONS[double]
        with self.lock:
            if options not in self.programs:
                source = resources.files(__package__).joinpath("clip.cl").read_text()
                program = _build_program(self.context, self.name, source, list(options))
                # Kernel objects hold their arguments: one per program, used under `call_lock`.
                self.programs[options] = _Kernels(
                    program.clip_segments, program.write_pieces, program.chunk_boxes,
                    program.classify_runs, program.clip_chunk_segments,
                    program.classify_bezier, program.flatten_bezier,
                    program.classify_bezier_runs, program.reduce_counters,
                    program.assign_pairs, program.reduce_first_bad, program.window_starts,
                    program.segment_feature_sizes, program.tile_feature_starts,
                    program.write_segment_features, program.write_tile_frames)
            return self.programs[options]

    def scan(self) -> GenericScanKernel:
        """Return the inclusive int64 prefix sum of the segment pipeline (built once)."""
        with self.lock:
            if "int64" not in self.scans:
                self.scans["int64"] = GenericScanKernel(
                    self.context, np.int64,
                    arguments="__global const long *keep, __global long *position",
                    input_expr="keep[i]", scan_expr="a+b", neutral="0",
                    output_statement="position[i] = item;")
            return self.scans["int64"]

    def table_scan(self) -> GenericScanKernel:
        """Return the in-place exclusive int64 prefix sum of the many-window assignment.

        Each entry becomes the sum of those before it, and ``summary[0]`` the sum of all
        (`windows.assign_on_device`; built once).
        """
        with self.lock:
            if "table" not in self.scans:
                self.scans["table"] = GenericScanKernel(
                    self.context, np.int64,
                    arguments="__global long *table, __global long *summary",
                    input_expr="table[i]", scan_expr="a+b", neutral="0",
                    output_statement="table[i] = prev_item; if (i == 0) summary[0] = last_item;")
            return self.scans["table"]


def _build_program(context: cl.Context, name: str, source: str, options: list) -> cl.Program:
    """Return `source` built, or BackendUnavailableError with the compiler's errors."""
    try:
        with warnings.catch_warnings():
            # Drivers log progress ("Compilation done"); a failure raises.
            warnings.simplefilter("ignore", cl.CompilerWarning)
            return cl.Program(context, source).build(options=options)
    except cl.Error as exc:
        errors = [line.strip() for line in str(exc).splitlines()
                  if "error" in line.lower() and "clBuildProgram" not in line]
        raise BackendUnavailableError(
            f"the OpenCL device {name!r} could not build the kernels: "
            f"{'; '.join(errors) or str(exc).strip()}") from None


@dataclass(frozen=True)
class _Kernels:
    """The kernels of one built ``clip.cl``."""

    clip_segments: cl.Kernel
    write_pieces: cl.Kernel
    chunk_boxes: cl.Kernel
    classify_runs: cl.Kernel
    clip_chunk_segments: cl.Kernel
    classify_bezier: cl.Kernel
    flatten_bezier: cl.Kernel
    classify_bezier_runs: cl.Kernel
    reduce_counters: cl.Kernel
    assign_pairs: cl.Kernel
    reduce_first_bad: cl.Kernel
    window_starts: cl.Kernel
    segment_feature_sizes: cl.Kernel
    tile_feature_starts: cl.Kernel
    write_segment_features: cl.Kernel
    write_tile_frames: cl.Kernel


_DEVICES: dict[str, _Device] = {}
_DEVICES_LOCK = threading.Lock()


def _device(entry: dict) -> _Device:
    """Return the process's `_Device` for a `list_devices` entry, created once."""
    with _DEVICES_LOCK:
        if entry["id"] not in _DEVICES:
            p, d = (int(i) for i in entry["id"].split(":"))
            device = cl.get_platforms()[p].get_devices()[d]
            context = cl.Context([device])
            queues = tuple(cl.CommandQueue(
                context, properties=cl.command_queue_properties.PROFILING_ENABLE)
                for _ in range(2))
            _DEVICES[entry["id"]] = _Device(
                f"{entry['platform']} / {entry['device']}", context, queues[0],
                second_queue=queues[1], staging=_segments.Staging(context, queues),
                allocator=cl.tools.MemoryPool(cl.tools.ImmediateAllocator(queues[0])),
                nowhere=cl.Buffer(context, cl.mem_flags.READ_WRITE, 8))
        return _DEVICES[entry["id"]]


class OpenCLBackend:
    """Run the kernels of segments, and of the runs of lines and rings, on an OpenCL device.

    Parameters
    ----------
    device : str, optional
        ``"platform:device"`` or part of a device's name (`select_device`); default:
        the first GPU, else the first device.
    precision : Precision or str
        ``"auto"`` (float64 if the device has it, else float32), ``"float64"`` or
        ``"float32"``.

    Raises
    ------
    BackendUnavailableError
        No device, none matching `device`, or float64 asked of a device without it.
    """

    kind = Backend.OPENCL

    def __init__(self, device: str | None = None, precision: Precision | str = Precision.AUTO):
        self.device = select_device(device)
        precision = Precision(precision)
        if precision is Precision.FLOAT64 and not self.device["fp64"]:
            raise BackendUnavailableError(
                f"OpenCL device {self.device['device']!r} has no float64 (cl_khr_fp64); "
                "ask for precision='float32' or 'auto'")
        if self.device["max_work_group_size"] < LOCAL_SIZE:
            raise BackendUnavailableError(
                f"OpenCL device {self.device['device']!r} runs at most "
                f"{self.device['max_work_group_size']} work-items per group; the kernels "
                f"need {LOCAL_SIZE}")
        if precision is Precision.AUTO:
            precision = Precision.FLOAT64 if self.device["fp64"] else Precision.FLOAT32
        self.precision = precision
        self.name = f"{self.device['platform']} / {self.device['device']}"
        self._device = _device(self.device)
        self._device.program(self.precision is Precision.FLOAT64)  # a build error shows now

    @property
    def capabilities(self) -> Capabilities:
        """Return what this backend runs: every operation, both modes, on its device.

        In float32, every operation but tiles: their quantisation is float64's, the
        same bit for bit on every backend (`encode_segment_tiles`).
        """
        operations = frozenset(Operation)
        if self.precision is not Precision.FLOAT64:
            operations -= {Operation.TILES}
        return Capabilities(Backend.OPENCL, operations, precision=self.precision,
                            devices=(self.device["id"],), device_arrays=True)

    @property
    def real(self) -> type:
        """Return the NumPy dtype of device coordinates."""
        return np.float64 if self.precision is Precision.FLOAT64 else np.float32

    @property
    def queue(self) -> cl.CommandQueue:
        """Return the backend's command queue: make device inputs on it (its context).

        For example ``pyopencl.array.to_device(backend.queue, segments)``.
        """
        return self._device.queue

    def empty_pinned(self, shape: int | tuple[int, ...], dtype: Any = np.float64) -> np.ndarray:
        """Return an uninitialised host array in page-locked memory for this device.

        Segments filled in here go up at full bus speed without the copy into the
        staging buffers (the float64 results of host calls are such arrays too, so a
        result fed to the next call goes up as it is). The memory returns to the
        backend's pool when the array and its views are gone.
        """
        assert self._device.staging is not None
        shape = (shape,) if isinstance(shape, int) else tuple(shape)
        return self._device.staging.outputs.empty(shape, dtype)

    def clip_segments(self, segments: np.ndarray | cl_array.Array, window: Window,
                      options: SegmentOptions, *, source: bool = True,
                      t: bool = True) -> SegmentPieces:
        """Return the visible piece of each segment; see `ClipBackend.clip_segments`.

        Host arrays stream through the device in pipelined chunks (`segments.clip_host`);
        a `pyopencl.array.Array` of this backend's context and dtype stays there, and so
        do the pieces (`segments.clip_device`: device arrays back, nothing copied but
        the count and the counters). `source` and `t` False leave those outputs out
        (None): less to write and copy back. ``stats.device`` holds the device, the
        precision, and the transfers and times.

        Raises
        ------
        InvalidGeometryError, InvalidWindowError
            A segment that is not finite (found on the device: nothing is returned), or
            in float32 coordinates (or their differences) beyond float32's range, or a
            window that collapses when rounded to float32.
        ValueError
            A device array of another context, dtype or shape.
        """
        real = self.real
        on_device = isinstance(segments, cl_array.Array)
        host_data: np.ndarray | None = None
        if isinstance(segments, cl_array.Array):
            self._check_device_segments(segments)
            n = int(segments.shape[0])
        else:
            with np.errstate(over="ignore"):  # float32: checked below, with the row named
                host_data = np.ascontiguousarray(segments, dtype=real)
            n = int(host_data.shape[0])
        bounds: np.ndarray = np.array(window.bounds, dtype=real)
        if real is np.float32 and host_data is not None:
            _check_float32(host_data, bounds)
        device = self._device
        with device.call_lock:
            run = self._segment_run(bounds if n else None, options, source, t)
            if isinstance(segments, cl_array.Array):
                outputs, totals, m = _segments.clip_device(run, device.queue, segments, n,
                                                           device.allocator)
            else:
                assert device.staging is not None
                host, totals, m = _segments.clip_host(run, device.staging, host_data,
                                                      _segments.CHUNK_SEGMENTS)
            device_stats = self._run_stats(run)
        bad = totals[:, -1].min() if totals.shape[0] else n
        if bad < n:
            self._raise_invalid(segments, int(bad), on_device)
        rows = np.zeros((max(1, totals.shape[0]), C.WIDTH), dtype=np.int64)
        rows[:totals.shape[0], :_SEGMENT_COUNTERS] = totals[:, :-1]
        stats = ClipStats.from_counters(rows, n, m, device=device_stats)
        if on_device:
            return SegmentPieces(outputs["pieces"], outputs["source"], outputs["t"], stats)
        pieces = host.pieces
        if real is np.float32:
            # The float32 window may reach an ulp past the float64 one: no output point
            # lies outside the window the caller gave.
            np.clip(pieces[:, 0::2], window.xmin, window.xmax, out=pieces[:, 0::2])
            np.clip(pieces[:, 1::2], window.ymin, window.ymax, out=pieces[:, 1::2])
        return SegmentPieces(pieces, host.source, host.t, stats)

    def clip_segment_windows(self, segments: np.ndarray | cl_array.Array, windows: np.ndarray,
                             options: SegmentOptions, *, source: bool = True,
                             t: bool = True) -> SegmentPieces:
        """Return each segment's piece in each window; see `ClipBackend.clip_segment_windows`.

        In float64 the (segment, window) pairs are made on the device, where the segments
        are (`windows.assign_on_device`: `many_windows.assign`'s pairs, in its order);
        only their count comes back before the clip. Host segments go up once, whole,
        and the pairs are clipped in pipelined chunks (`segments.clip_host` with
        ``pairs``), each piece written with its window. A `pyopencl.array.Array` of this
        backend's context and dtype stays on the device, and so do the pieces, `source`,
        `t` and ``window`` (`segments.clip_device`); ``window_offsets`` (int64, on the
        host) is found there too: only it and the counts come back.

        The host assigns instead (`many_windows.assign`, the pairs then sent up; device
        segments are read back for it) on a float32 device, whose coordinates cannot
        give the float64 boxes' pairs exactly, and for more windows than
        `windows.assign_items` takes.

        Raises
        ------
        InvalidGeometryError, InvalidWindowError
            A segment that is not finite (on the device, found before anything is
            clipped); in float32, as `clip_segments`.
        ValueError
            A device array of another context, dtype or shape.
        """
        real = self.real
        on_device = isinstance(segments, cl_array.Array)
        if isinstance(segments, cl_array.Array):
            self._check_device_segments(segments)
        n = int(segments.shape[0])
        k = windows.shape[0]
        items = _windows.assign_items(n, k) if real is np.float64 and n else 0
        with np.errstate(over="ignore"):
            bounds: np.ndarray = np.ascontiguousarray(windows, dtype=real)
        pairs = None
        data: np.ndarray | None = None
        if items == 0:
            host = np.ascontiguousarray(
                segments.get() if isinstance(segments, cl_array.Array) else segments,
                dtype=np.float64)
            check_segment_values(host)  # the assignment reads the boxes
            if real is np.float32:
                with np.errstate(over="ignore"):
                    data = host.astype(np.float32)
                _check_float32(data, bounds[0])
                _check_float32_lines(data.reshape(-1, 2), bounds)
            else:
                data = host
            pairs = assign(host, windows)
        elif not on_device:
            data = np.ascontiguousarray(segments, dtype=np.float64)
        device = self._device
        assert device.staging is not None
        chunk = _segments.CHUNK_SEGMENTS
        with device.call_lock:
            run = self._segment_run(bounds, options, source, t)
            if isinstance(segments, cl_array.Array):
                whole = buffer_of(segments)
            else:
                assert data is not None
                whole = _segments.upload_whole(run, device.staging, data, chunk)
            if pairs is None:
                p = self._device_pairs(run, whole, segments, windows, items) if n else 0
            else:
                p = int(pairs.segment.shape[0])
                if p:
                    run.pair_segment = _segments.upload_whole(run, device.staging,
                                                              pairs.segment, chunk)
                    run.pair_window = _segments.upload_whole(run, device.staging,
                                                             pairs.window(), chunk)
            if run.pair_segment is None:  # no pairs: still a pair run (a window output)
                run.pair_segment = run.pair_window = device.nowhere
            window_offsets = None
            if isinstance(segments, cl_array.Array):
                outputs, totals, m = _segments.clip_device(run, device.queue, segments, p,
                                                           device.allocator)
                window_offsets = _windows.window_offsets_on_device(
                    run, device.queue, outputs["window"], m, k)
            elif p:
                host_out, totals, m = _segments.clip_host(run, device.staging, None, chunk,
                                                          pairs=p, segments=whole)
            else:
                host_out = _segments.HostOutputs.empty(0, source, t, True)
                totals, m = np.zeros((0, _SEGMENT_COUNTERS + 1), np.int64), 0
            device_stats = self._run_stats(run)
        rows = np.zeros((max(1, totals.shape[0]), C.WIDTH), dtype=np.int64)
        rows[:totals.shape[0], :_SEGMENT_COUNTERS] = totals[:, :-1]
        stats = ClipStats.from_counters(rows, p, m, device=device_stats)
        if window_offsets is not None:
            return SegmentPieces(outputs["pieces"], outputs["source"], outputs["t"], stats,
                                 outputs["window"], window_offsets)
        assert host_out.window is not None
        if real is np.float32:
            bounds64 = windows[host_out.window]
            for axis in (0, 1):
                np.clip(host_out.pieces[:, axis::2], bounds64[:, [axis]],
                        bounds64[:, [axis + 2]], out=host_out.pieces[:, axis::2])
        # The pieces are sorted by window: k + 1 binary searches, not a pass over them
        # (12M pieces: 0.8 ms against bincount's 40 ms on this project's 2-core host).
        window_offsets = np.searchsorted(host_out.window, np.arange(k + 1, dtype=np.int32)
                                         ).astype(np.int64)
        return SegmentPieces(host_out.pieces, host_out.source, host_out.t, stats,
                             host_out.window, window_offsets)

    def assign_windows(self, segments: np.ndarray | cl_array.Array,
                       windows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the (segment, window) pairs `clip_segment_windows` clips, read back.

        ``(pair_segment, pair_window)``, int64 and int32, sorted by window then segment:
        made on the device where `clip_segment_windows` makes them (float64, windows
        `windows.assign_items` takes), else by `many_windows.assign`; equal either way.
        `segments` as for `clip_segment_windows`, finite; `windows` a table from
        `many_windows.as_windows`. For checking the device's assignment.
        """
        n = int(segments.shape[0])
        items = _windows.assign_items(n, windows.shape[0]) if self.real is np.float64 else 0
        if items == 0 or n == 0:
            host = np.ascontiguousarray(
                segments.get() if isinstance(segments, cl_array.Array) else segments,
                dtype=np.float64)
            pairs = assign(host, windows)
            return pairs.segment, pairs.window()
        device = self._device
        assert device.staging is not None
        with device.call_lock:
            # The clip settings are unused: only the window table is needed.
            run = self._segment_run(windows, SegmentOptions.resolve(Window(*windows[0])),
                                    False, False)
            whole = (buffer_of(segments) if isinstance(segments, cl_array.Array) else
                     _segments.upload_whole(run, device.staging,
                                            np.ascontiguousarray(segments, np.float64),
                                            _segments.CHUNK_SEGMENTS))
            p = self._device_pairs(run, whole, segments, windows, items)
            pair_segment = np.empty(p, np.int64)
            pair_window = np.empty(p, np.int32)
            if p:
                assert run.pair_segment is not None and run.pair_window is not None
                run.download(device.queue, pair_segment, run.pair_segment, run.ready)
                run.download(device.queue, pair_window, run.pair_window, run.ready)
            self._run_stats(run)
        return pair_segment, pair_window

    def _device_pairs(self, run: _segments.SegmentRun, whole: cl.Buffer,
                      segments: np.ndarray | cl_array.Array, windows: np.ndarray,
                      items: int) -> int:
        """Make the pairs of the `whole` segments on the device (`run`'s tables); their count.

        Raises the error of the first segment that is not finite, before anything is
        clipped.
        """
        n = int(segments.shape[0])
        device = self._device
        p, bad = _windows.assign_on_device(run, device.queue, device.table_scan(), whole, n,
                                           window_finder(windows), items)
        if bad < n:
            self._raise_invalid(segments, bad, isinstance(segments, cl_array.Array))
        return p

    def _segment_run(self, bounds: np.ndarray | None, options: SegmentOptions, source: bool,
                     t: bool) -> _segments.SegmentRun:
        """Return the settings of one segment call, its window table uploaded.

        `bounds` None: nothing to clip, nothing uploaded.
        """
        device = self._device
        real = self.real
        kernels = device.program(real is np.float64)
        windows: np.ndarray = np.ascontiguousarray(
            bounds if bounds is not None else [], dtype=real).reshape(-1)
        assert device.allocator is not None
        run = _segments.SegmentRun(
            kernels, device.scan(), real, LOCAL_SIZE,
            cast(cl.Buffer, device.allocator(max(8, windows.nbytes))),
            METHOD_ID[options.method], options.n, options.max_depth, options.tolerance,
            int(options.mode is Mode.EXACT), source, t, nowhere=device.nowhere,
            allocator=device.allocator)
        if windows.size:
            run.ready.append(run.upload(device.queue, run.windows, windows))
        return run

    def _run_stats(self, run: _segments.SegmentRun) -> DeviceStats:
        events = run.copy_events + run.kernel_events
        if events:
            cl.wait_for_events(events)
        return DeviceStats(device=self.name, precision=self.precision.value,
                           transfers=len(run.copy_events),
                           bytes_to_device=run.bytes_to_device,
                           bytes_from_device=run.bytes_from_device,
                           transfer_seconds=event_seconds(run.copy_events),
                           kernel_seconds=event_seconds(run.kernel_events))

    def _check_device_segments(self, segments: cl_array.Array) -> None:
        if segments.context != self._device.context:
            raise ValueError("the segments are on another OpenCL context than the backend's "
                             f"device {self.name!r}")
        if segments.dtype != self.real or segments.ndim != 2 or segments.shape[1] != 4:
            raise ValueError(
                f"device segments must be (n, 4) {np.dtype(self.real).name} (the device's "
                f"precision), got {segments.shape} {segments.dtype}")
        if not segments.flags.c_contiguous:
            raise ValueError("device segments must be C-contiguous")

    @staticmethod
    def _raise_invalid(segments: Any, row: int, on_device: bool) -> None:
        """Raise the error of segment `row`, which the device found not finite."""
        values = segments[row].get() if on_device else np.asarray(segments[row])
        raise segment_error(row, values)

    def clip_lines(self, lines: Ragged, windows: WindowTable, options: SegmentOptions,
                   drop_edge_runs: bool) -> GeometryPieces:
        """Return the chains of each line geometry; see `ClipBackend.clip_lines`.

        On the device (`runs.RunCall`): the chunk boxes, RNSCA over runs of chunks (one
        work-item per part) and the clip of the segments of undecided chunks (one
        work-item per chunk); on the host, with the Numba kernel that does it for the
        Numba backend, the chains: accepted chunks copied, clipped pieces joined. A large
        call goes in ranges of parts (`runs.pipelined`): the host counts one range's
        chains while the device prunes the next.

        Raises
        ------
        InvalidGeometryError, InvalidWindowError
            In float32, for coordinates beyond its range or a window that collapses.
        """
        lines.check_finite()  # the device kernels take finite coordinates
        xy, z = lines.split_z()
        part_offsets, geometry_parts = lines.item_offsets()
        part_geometry = np.repeat(np.arange(lines.count, dtype=np.int64),
                                  np.diff(geometry_parts))
        part_window = windows.of_items(part_geometry)
        call = self._run_call(windows.bounds, options, drop_edge_runs)
        data = self._device_coordinates(xy, call)

        def start(part_range: tuple[int, int]) -> Any:
            a, b = part_range
            v0, v1 = part_offsets[a], part_offsets[b]
            return call.start(data[v0:v1], xy[v0:v1], part_offsets[a:b + 1] - v0,
                              part_window[a:b])

        assembly = _LineAssembly(R.vertices(xy, z), part_offsets, part_window,
                                 windows.bounds, drop_edge_runs)
        for part_range, tables in pipelined(
                call, ranges_by_vertices(part_offsets[1:] - part_offsets[0]), start):
            assembly.count(part_range, PL.Decisions(True, *tables))
        out_xy, out_z, chain_offsets = assembly.write()
        counters, device_stats = call.totals(self.name, self.precision)
        return GeometryPieces(out_xy, out_z, (
            chain_offsets, group_offsets(assembly.n_chains, geometry_parts)),
            counters if counters.shape[0] else np.zeros((1, C.WIDTH), dtype=np.int64),
            device_stats)

    def _run_call(self, windows: np.ndarray, options: SegmentOptions,
                  drop_edge_runs: bool) -> RunCall:
        return RunCall(self._device, self.real, windows, options, drop_edge_runs, LOCAL_SIZE)

    def _device_coordinates(self, xy: np.ndarray, call: RunCall) -> np.ndarray:
        """Return `xy` in the device's dtype, checked to fit it (float32)."""
        with np.errstate(over="ignore"):
            data: np.ndarray = np.ascontiguousarray(xy, dtype=self.real)
        if self.real is np.float32:
            _check_float32_lines(data, call.bounds)
        return data

    def clip_polygon_pairs(self, polygons: Ragged, geometry: np.ndarray, windows: np.ndarray,
                           options: SegmentOptions) -> GeometryPieces:
        """Return each (geometry, window) pair clipped; see `ClipBackend.clip_polygon_pairs`.

        The pairs' geometries are gathered and clipped by `clip_polygons`, one window each.
        """
        n = geometry.shape[0]
        return self.clip_polygons(polygons.take(geometry),
                                  WindowTable(np.ascontiguousarray(windows, dtype=np.float64),
                                              np.arange(n, dtype=np.int64)), options)

    def clip_polygons(self, polygons: Ragged, windows: WindowTable,
                      options: SegmentOptions) -> GeometryPieces:
        """Return the output polygons of each geometry; see `ClipBackend.clip_polygons`.

        The shells' boxes classify the polygons on the host
        (`polygons.classify_polygons`); the rings of the ambiguous ones are pruned and
        their undecided segments clipped on the device (`runs.RunCall`, rings broken
        along the window's edges); the rings are closed along the window on the host by
        the Numba polygon kernel, from the device's decisions and pieces. Polygons go in
        ranges of about `runs.PIPELINE_VERTICES` ambiguous vertices: the host's count
        pass of one range runs while the device prunes the next (`runs.pipelined`).
        """
        xy, z = polygons.split_z()
        ring_offsets = polygons.offsets[0]
        polygon_offsets, geometry_polygons = polygons.item_offsets()
        polygon_window = windows.of_items(polygon_geometry(geometry_polygons))
        n_polygons = polygon_offsets.shape[0] - 1
        polygon_class = np.empty(n_polygons, dtype=np.int8)
        PG.classify_polygons(R.vertices(xy, z), PG.Polygons(ring_offsets, polygon_offsets,
                                                            windows.bounds, polygon_window),
                             polygon_class)
        ring_polygon = np.repeat(np.arange(n_polygons, dtype=np.int64),
                                 np.diff(polygon_offsets))
        ring_window = np.ascontiguousarray(polygon_window[ring_polygon])
        active = polygon_class[ring_polygon] == PG.AMBIGUOUS
        call = self._run_call(windows.bounds, options, True)
        active_ends = np.concatenate([[0], np.cumsum(np.where(active, np.diff(ring_offsets), 0))])
        ranges = ranges_by_vertices(active_ends[polygon_offsets[1:]])
        xy64 = np.ascontiguousarray(xy, dtype=np.float64)
        # Each ring's first chunk in its range's tables; only the active rings' are read.
        chunk_start = np.zeros(ring_offsets.shape[0] - 1, dtype=np.int64)

        range_rings: dict[tuple[int, int], np.ndarray] = {}

        def start(polygon_range: tuple[int, int]) -> Any:
            # Only the rings of ambiguous polygons go to the device (gathered on every
            # core): the polygons wholly inside or outside the window are most of a
            # large input (1M scattered stars: 84%), and their vertices were most of
            # the call's transfers.
            a, b = polygon_range
            rings = polygon_offsets[a] + np.flatnonzero(
                active[polygon_offsets[a]:polygon_offsets[b]])
            range_rings[polygon_range] = rings
            sub_xy, sub_offsets = _gather_rings(xy64, ring_offsets, rings)
            return call.start(self._device_coordinates(sub_xy, call), sub_xy, sub_offsets,
                              ring_window[rings])

        def decided() -> Iterator[PolygonRange]:
            for (a, b), tables in pipelined(call, ranges, start):
                chunk_start[range_rings.pop((a, b))] = tables.chunk_start
                yield PolygonRange(a, b, PL.Decisions(True, chunk_start, *tables[1:]))

        return _HOST.clip_polygons(polygons, windows, options, device=DevicePolygons(
            True, polygon_class, decided(), lambda: call.totals(self.name, self.precision)))

    def clip_paths(self, paths: PathArrays, windows: WindowTable,
                   options: PathOptions) -> PathPieces:
        """Return each path clipped to its window; see `ClipBackend.clip_paths`.

        The device classifies every segment by its control points, and runs of segments
        by their box, and flattens the curves accepted whole (flatten mode); the
        ambiguous segments and the output are done on the host by the Numba kernel, from
        those decisions: the output is the Numba backend's. With one window per path
        (many windows), the device classifies each stretch of consecutive paths that
        share a window in turn (one stretch per window for `rnsca.clip_paths`'s pairs,
        which are sorted by window); the host assembles them all in one call.
        """
        flatten = "accepted" if options.curves is Curves.FLATTEN else "none"
        sub = paths.subpath_offsets
        call = CurveCall(self._device, self.precision, self.real)
        # Ranges of subpaths of one window, of about PIPELINE_SEGMENTS segments each.
        ranges = []
        for row, p0, p1 in _window_stretches(windows, len(paths)):
            s0, s1 = int(paths.path_offsets[p0]), int(paths.path_offsets[p1])
            ranges += [(s0 + a, s0 + b, row) for a, b in ranges_by_vertices(
                sub[s0 + 1:s1 + 1] - sub[s0], PIPELINE_SEGMENTS)]

        def start(item: tuple[int, int, int]) -> Any:
            a, b, row = item
            g0, g1 = int(sub[a]), int(sub[b])
            return call.start(paths.controls[g0:g1], paths.degree[g0:g1],
                              Window(*windows.bounds[row]), options.tolerance, flatten,
                              sub[a:b + 1] - g0)

        def decided() -> Iterator[PathRange]:
            for (a, b, _), tables in pipelined(call, ranges, start):
                yield PathRange(a, b, BZ.Decisions(True, tables.run_decision,
                                                   tables.segment_class, tables.point_start,
                                                   tables.points))

        return _HOST.clip_paths(paths, windows, options, device=DevicePaths(
            decided(), lambda: call.totals(self.name)))

    def flatten_paths(self, paths: PathArrays, tolerance: float, close: bool) -> Polylines:
        """Return the paths as polylines within `tolerance`; see `ClipBackend.flatten_paths`.

        The device computes every segment's points (a float32 device: the host computes
        them in float64, the same points); the host puts them after each subpath's start.
        """
        sub = paths.subpath_offsets
        _, _, segment_points, points, _ = self.classify_curves(
            paths.controls, paths.degree, None, float(tolerance), "all")
        steps = np.diff(segment_points)
        lines, closes, line_offsets = polyline_layout(paths, segment_points, close)
        coords = np.empty((int(line_offsets[-1]), 2))
        # The device's points are the segments' in order; each line adds its start
        # point before them (and its start again after them where it closes).
        has_line = np.diff(sub) > 0
        segment_subpath = np.repeat(np.arange(sub.shape[0] - 1), np.diff(sub))
        line_of_subpath = np.cumsum(has_line) - 1
        shift = (line_offsets[:-1][line_of_subpath[segment_subpath]] + 1
                 - segment_points[sub[:-1]][segment_subpath])
        coords[np.repeat(shift, steps) + np.arange(points.shape[0])] = points
        coords[line_offsets[:-1]] = paths.start[lines]
        closing = closes[lines]
        coords[line_offsets[1:][closing] - 1] = paths.start[lines[closing]]
        line_path = np.repeat(np.arange(len(paths), dtype=np.int64), np.diff(paths.path_offsets))
        return Polylines(coords, line_offsets, line_path[lines])

    def classify_curves(self, controls: np.ndarray, degree: np.ndarray, window: Window | None,
                        tolerance: float, flatten: str, subpath_offsets: np.ndarray | None = None,
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, DeviceStats]:
        """Classify Bézier segments and runs of them, and flatten some segments, on the device.

        Parameters
        ----------
        controls : ndarray, shape (m, 4, 2)
            Control points, unused slots repeating the end (`PathArrays`).
        degree : ndarray of int8, shape (m,)
        window : Window or None
            The window the classes refer to; None when only flattening (the classes
            are then meaningless).
        tolerance : float
            Flattening tolerance (`bezier.flatten_count`).
        flatten : {"none", "accepted", "all"}
            Which segments are flattened: none, the curves (degree > 1) accepted whole
            (flatten mode: runs are then never accepted whole), or every segment.
        subpath_offsets : ndarray of int64, optional
            The subpaths, whose runs of `bezier.RUN_SEGMENTS` segments are classified
            by their control points' box as `bezier.clip_path_blocks` does; None: no
            runs.

        Returns
        -------
        segment_class : ndarray of uint8, shape (m,)
            `bezier.SEGMENT_REJECTED`, `SEGMENT_ACCEPTED` or `SEGMENT_AMBIGUOUS`.
        run_decision : ndarray of int8, shape (m,)
            Each run's decision (bezier's ``_RUN_*``) at its first segment, as
            `bezier.clip_path_blocks` reads them; 0 elsewhere (empty without
            `subpath_offsets`).
        point_start : ndarray of int64, shape (m + 1,)
            Segment i's points are ``points[point_start[i]:point_start[i + 1]]``: the
            `bezier.flatten_count` points after its start, its end point last.
        points : ndarray, shape (point_start[-1], 2)
        device_stats : DeviceStats

        In float32 the device's classes are conservative (`curves.windows32`): "inside" and
        "beyond an edge" only where that holds for the float64 input too; the host
        decides the rest (ambiguous segments, segmented runs) from the float64 input and
        flattens in float64, so the classes, decisions and points returned are exactly
        the float64 ones.
        """
        call = CurveCall(self._device, self.precision, self.real)
        tables = call.whole(controls, degree, window, tolerance, flatten, subpath_offsets)
        return (*tables, call.totals(self.name))

    def encode_segment_tiles(self, pieces: np.ndarray | cl_array.Array,
                             source: np.ndarray | cl_array.Array | None,
                             layer: TileLayer) -> TileBytes:
        """Return each window's pieces as a vector tile; see `ClipBackend.encode_segment_tiles`.

        On the device (`tiles.encode_on_device`): the features' sizes, a prefix sum and
        their writes, one work-item per piece, and each tile's framing; the host reads
        back only the tiles' feature byte counts (k + 2 numbers) to lay the tiles out,
        then the tiles' bytes. Device arrays (float64 pieces, int64 source) are read
        where they are; host arrays are sent up first. The bytes are the Numba
        backend's.

        Raises
        ------
        BackendUnavailableError
            On a float32 device (the quantisation is float64's).
        InvalidGeometryError
            For a piece that does not quantise into MVT's range (found on the device).
        ValueError
            A device array of another context, dtype or shape.
        """
        if self.precision is not Precision.FLOAT64:
            raise BackendUnavailableError(
                f"the OpenCL backend runs float32 here ({self.name!r}): encoding tiles "
                "needs float64, so that every backend quantises the pieces alike; use a "
                "float64 device, or backend='numba' on the pieces brought to the host")
        m = int(pieces.shape[0])
        device = self._device
        ledger = Ledger()
        chunk = _segments.CHUNK_SEGMENTS
        with device.call_lock:
            if isinstance(pieces, cl_array.Array):
                self._check_device_segments(pieces)
                device_pieces = buffer_of(pieces)
            else:
                pieces = np.ascontiguousarray(pieces, dtype=np.float64)
                device_pieces = ledger.staged(device, pieces, chunk)
            device_source = None
            if isinstance(source, cl_array.Array):
                if (source.context != device.context or source.dtype != np.int64
                        or source.shape != (m,)):
                    raise ValueError(f"device sources must be ({m},) int64 on the backend's "
                                     f"context, got {source.shape} {source.dtype}")
                device_source = buffer_of(source)
            elif source is not None:
                source = np.ascontiguousarray(source, dtype=np.int64)
                device_source = ledger.staged(device, source, chunk)
            encoded = encode_on_device(device, device.program(True), ledger, device_pieces,
                                       device_source, m, layer, LOCAL_SIZE)
            device_stats = ledger.stats(self.name, self.precision)
        if encoded.first_bad < m:
            row = encoded.first_bad
            tile = int(np.searchsorted(layer.window_offsets, row, "right")) - 1
            values = pieces[row].get() if isinstance(pieces, cl_array.Array) else pieces[row]
            raise tile_piece_error(row, tile, values)
        return TileBytes(encoded.data, encoded.offsets, device_stats)

    def warm_up(self) -> None:
        """Build the program (or load it from the caches), run every method, lines, rings.

        Also compiles (or loads from Numba's cache) the host kernels that assemble lines
        and polygons, and those that clip and flatten curves from the device's decisions.
        """
        warm_up_segments(self)
        warm_up_geometry(self)
        # Curves: every flatten choice of the device, and the host kernel that reads
        # the device's decisions (compiled or loaded here).
        warm_up_paths(self)
        if Operation.TILES in self.capabilities.operations:
            warm_up_tiles(self)


def _window_stretches(windows: WindowTable, n: int) -> list[tuple[int, int, int]]:
    """Return ``(row, first, end)`` for each stretch of consecutive paths of one window.

    One stretch of all `n` paths for a table of one window (and none for no paths).
    """
    if n == 0:
        return []
    if windows.bounds.shape[0] == 1:
        return [(0, 0, n)]
    index = np.asarray(windows.index, dtype=np.int64)
    cuts = np.flatnonzero(index[1:] != index[:-1]) + 1
    first = np.concatenate([[0], cuts])
    end = np.concatenate([cuts, [n]])
    return [(int(index[a]), int(a), int(b)) for a, b in zip(first, end, strict=True)]


class _LineAssembly:
    """The host's half of a line call: the chains, counted range by range, then written.

    `count` runs the count pass of `polylines.assemble_line_blocks` over parts
    ``first..end-1`` with their range's device tables (while the device works on the
    next range); `write` sums the counts and runs the write pass of every range.
    """

    def __init__(self, line: R.Vertices, part_offsets: np.ndarray, part_window: np.ndarray,
                 windows: np.ndarray, drop_edge_runs: bool) -> None:
        self.line = line
        self.part_offsets = part_offsets
        self.part_window = part_window
        self.windows = windows
        self.drop_edge_runs = drop_edge_runs
        n_parts = part_offsets.shape[0] - 1
        self.n_vertices = np.zeros(n_parts, dtype=np.int64)
        self.n_chains = np.zeros(n_parts, dtype=np.int64)
        self.ranges: list[tuple[int, int, PL.Decisions]] = []

    def count(self, part_range: tuple[int, int], decisions: PL.Decisions) -> None:
        """Count the chains of parts ``first..end-1`` from their range's decisions."""
        a, b = part_range
        self.ranges.append((a, b, decisions))
        nothing = np.empty(0, dtype=np.int64)
        nowhere = np.empty((0, 2))
        self._pass(a, b, decisions, False, (nothing, nothing),
                   PL.ChainsOut(nowhere, nowhere.reshape(-1), np.empty(0), nothing))

    def write(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``(xy, z, chain_offsets)`` of every range counted."""
        vertex_start = exclusive_sum(self.n_vertices)
        chain_start = exclusive_sum(self.n_chains)
        out_xy = np.empty((int(vertex_start[-1]), 2))
        out_z = np.empty(int(vertex_start[-1]) if self.line.has_z else 0)
        chain_offsets = np.empty(int(chain_start[-1]) + 1, dtype=np.int64)
        chain_offsets[-1] = out_xy.shape[0]
        out = PL.ChainsOut(out_xy, out_xy.reshape(-1), out_z, chain_offsets)
        for a, b, decisions in self.ranges:
            self._pass(a, b, decisions, True, (vertex_start, chain_start), out)
        return out_xy, out_z, chain_offsets

    def _pass(self, a: int, b: int, decisions: PL.Decisions, write: bool,
              starts: tuple[np.ndarray, np.ndarray], out: PL.ChainsOut) -> None:
        # Parts a..b-1 alone: vertex offsets and output slots stay the call's.
        PL.assemble_line_blocks(
            self.line, self.part_offsets[a:b + 1], self.windows, self.part_window[a:b],
            self.drop_edge_runs, max(1, min(1024, -(-(b - a) // 64))), write, decisions,
            PL.PartCounts(self.n_vertices[a:b], self.n_chains[a:b],
                          *(s[a:b] for s in starts)), out)


def _gather_rings(xy: np.ndarray, ring_offsets: np.ndarray, rings: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Return the vertices of `rings` one after the other (on every core), and their offsets."""
    starts = ring_offsets[rings]
    sizes = ring_offsets[rings + 1] - starts
    offsets = exclusive_sum(sizes)
    gathered = np.empty((int(offsets[-1]), 2))
    copy_ranges(xy, starts, sizes, offsets[:-1], gathered)
    return gathered, offsets


def _check_float32_lines(xy: np.ndarray, windows: np.ndarray) -> None:
    """Refuse float32 lines whose coordinates, steps or windows do not fit float32."""
    with np.errstate(over="ignore", invalid="ignore"):
        bad = ~np.isfinite(xy).all(axis=1)
        bad[1:] |= ~np.isfinite(np.diff(xy, axis=0)).all(axis=1)
    if bad.any():
        raise InvalidGeometryError(
            f"coordinate {int(np.argmax(bad))} does not fit float32, the OpenCL backend's "
            f"precision here (|coordinates| and their differences must stay below "
            f"{_F32.max:.3g})")
    good = (np.isfinite(windows).all(axis=1) & (windows[:, 0] < windows[:, 2])
            & (windows[:, 1] < windows[:, 3]))
    if not good.all():
        row = int(np.argmin(good))
        raise InvalidWindowError(
            f"window {row} {windows[row].tolist()} is empty or infinite in float32, the "
            "OpenCL backend's precision here; use a float64 device or another backend")


def _check_float32(data: np.ndarray, bounds: np.ndarray) -> None:
    """Refuse float32 input whose coordinates, differences or window do not fit float32."""
    with np.errstate(over="ignore", invalid="ignore"):
        rows = data.reshape(-1, 4)
        finite = np.isfinite(rows).all(axis=1) & np.isfinite(rows[:, 2:] - rows[:, :2]).all(axis=1)
    if not finite.all():
        row = int(np.argmin(finite))
        error = InvalidGeometryError(
            f"segment {row} does not fit float32, the OpenCL backend's precision here "
            f"(|coordinates| and their differences must stay below {_F32.max:.3g})")
        error.row = row
        raise error
    if not (np.isfinite(bounds).all() and bounds[0] < bounds[2] and bounds[1] < bounds[3]):
        raise InvalidWindowError(
            f"the window {bounds.tolist()} is empty or infinite in float32, the OpenCL "
            "backend's precision here; use a float64 device or another backend")
