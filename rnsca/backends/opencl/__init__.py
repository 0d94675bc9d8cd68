"""The OpenCL backend: the segment kernels of ``clip.cl`` run through pyopencl.

One work-item clips one segment (RNSCA with its depth-first stack, or a baseline) and
the output, at most one piece per segment, is compacted in three steps, as a GPU wants
it: ``clip_segments`` stores each segment's result and a 0/1 count, pyopencl's prefix
sum (``pyopencl.array.cumsum``) turns the counts into slots, and ``write_pieces``
copies the kept results there. Only the segments go to the device and only the pieces
(and one counter row per work-group) come back.

Devices and programs: the device is picked once per backend (`select_device`); each
device gets one context and one profiling queue per process, and ``clip.cl`` is built
once per (context, precision) and kept (`_Device.program`). pyopencl and the OpenCL
driver also cache built binaries on disk, so a second process builds fast.

Precision: float64 where the device has ``cl_khr_fp64``, else float32 (or float32 when
asked for, on any device). The float32 path clips the input rounded to float32; see
the README ("OpenCL backend") for its error bound, which the tests check.

This module imports pyopencl at import time; only `rnsca.backends.registry` imports
it, and turns a failure into `BackendUnavailableError`.
"""

from __future__ import annotations

import threading
import warnings
from dataclasses import dataclass, field
from importlib import resources

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from rnsca.errors import BackendUnavailableError, InvalidGeometryError, InvalidWindowError
from rnsca.kernels import counters as C
from rnsca.kernels import segments as K
from rnsca.options import Backend, Method, Mode, Precision, SegmentOptions
from rnsca.stats import ClipStats, DeviceStats
from rnsca.window import Window

__all__ = ["OpenCLBackend", "list_devices", "select_device", "FLOAT32_RELATIVE_BOUND",
           "LOCAL_SIZE"]

#: Work-items per group: the stats are summed per group in local memory.
LOCAL_SIZE = 64
#: float32 mode: each piece end lies within this many units of the float32 rounding
#: (2**-24) of ``max(|coordinates of its segment|, |window bounds|)`` of the exact clip
#: of the input rounded to float32 (README, "OpenCL backend"). Tested.
FLOAT32_RELATIVE_BOUND = 16 * 2.0 ** -24

_METHOD_ID = {
    Method.RNSCA: K.RNSCA,
    Method.COHEN_SUTHERLAND: K.COHEN_SUTHERLAND,
    Method.LIANG_BARSKY: K.LIANG_BARSKY,
    Method.NICHOLL_LEE_NICHOLL: K.NICHOLL_LEE_NICHOLL,
    Method.MIDPOINT: K.MIDPOINT,
}
# Counters the segment kernel fills: the head of the row (rnsca.kernels.counters).
_SEGMENT_COUNTERS = C.LEVELS + C.N_LEVELS
_F32 = np.finfo(np.float32)


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
    lock: threading.Lock = field(default_factory=threading.Lock)

    def program(self, double: bool) -> cl.Program:
        """Return ``clip.cl`` built for float64 (`double`) or float32, built once."""
        with self.lock:
            if double not in self.programs:
                source = resources.files(__package__).joinpath("clip.cl").read_text()
                options = [f"-DREAL_IS_DOUBLE={int(double)}", f"-DLOCAL_SIZE={LOCAL_SIZE}"]
                if not double:  # OpenCL's float32 division may be 2.5 ulp otherwise
                    options.append("-cl-fp32-correctly-rounded-divide-sqrt")
                program = _build_program(self.context, self.name, source, options)
                # Kernel objects hold their arguments: one per program, used under `call_lock`.
                self.programs[double] = (program.clip_segments, program.write_pieces)
            return self.programs[double]


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


_DEVICES: dict[str, _Device] = {}
_DEVICES_LOCK = threading.Lock()


def _device(entry: dict) -> _Device:
    """Return the process's `_Device` for a `list_devices` entry, created once."""
    with _DEVICES_LOCK:
        if entry["id"] not in _DEVICES:
            p, d = (int(i) for i in entry["id"].split(":"))
            device = cl.get_platforms()[p].get_devices()[d]
            context = cl.Context([device])
            queue = cl.CommandQueue(
                context, properties=cl.command_queue_properties.PROFILING_ENABLE)
            _DEVICES[entry["id"]] = _Device(
                f"{entry['platform']} / {entry['device']}", context, queue)
        return _DEVICES[entry["id"]]


class _Ledger:
    """Transfers and kernel runs of one call, timed by OpenCL event profiling."""

    def __init__(self):
        self.transfers = 0
        self.bytes_to_device = 0
        self.bytes_from_device = 0
        self.copy_events = []
        self.kernel_events = []

    def to_device(self, queue, array: np.ndarray):
        buffer = cl_array.empty(queue, array.shape, array.dtype)
        if array.nbytes:
            self.copy_events.append(cl.enqueue_copy(queue, buffer.data, array))
            self.transfers += 1
            self.bytes_to_device += array.nbytes
        return buffer

    def from_device(self, queue, buffer) -> np.ndarray:
        out = np.empty(buffer.shape, buffer.dtype)
        if out.nbytes:
            self.copy_events.append(cl.enqueue_copy(queue, out, buffer.base_data,
                                                    src_offset=buffer.offset))
            self.transfers += 1
            self.bytes_from_device += out.nbytes
        return out

    def stats(self, device: str, precision: Precision) -> DeviceStats:
        cl.wait_for_events(self.copy_events + self.kernel_events)
        return DeviceStats(device=device, precision=precision.value, transfers=self.transfers,
                           bytes_to_device=self.bytes_to_device,
                           bytes_from_device=self.bytes_from_device,
                           transfer_seconds=_seconds(self.copy_events),
                           kernel_seconds=_seconds(self.kernel_events))


def _seconds(events) -> float:
    return sum(e.profile.end - e.profile.start for e in events) * 1e-9


class OpenCLBackend:
    """Run the segment kernels on one OpenCL device.

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
        if precision is Precision.AUTO:
            precision = Precision.FLOAT64 if self.device["fp64"] else Precision.FLOAT32
        self.precision = precision
        self.name = f"{self.device['platform']} / {self.device['device']}"
        self._device = _device(self.device)
        self._device.program(self.precision is Precision.FLOAT64)  # a build error shows now
        # Kernel arguments are set on shared kernel objects: one call at a time.
        self._call_lock = threading.Lock()

    @property
    def real(self) -> type:
        """Return the NumPy dtype of device coordinates."""
        return np.float64 if self.precision is Precision.FLOAT64 else np.float32

    def clip_segments(self, segments: np.ndarray, window: Window, options: SegmentOptions):
        """Return ``(pieces, source, t, stats)``; see `ClipBackend.clip_segments`.

        ``stats.device`` holds the device, the precision, and the transfers and times.

        Raises
        ------
        InvalidGeometryError, InvalidWindowError
            In float32, for coordinates (or their differences) beyond float32's range,
            or a window that collapses when rounded to float32.
        """
        real = self.real
        n = segments.shape[0]
        with np.errstate(over="ignore"):  # float32: checked below, with the row named
            data = np.ascontiguousarray(segments, dtype=real)
        bounds = np.array(window.bounds, dtype=real)
        if real is np.float32:
            _check_float32(data, bounds)
        xmin, ymin, xmax, ymax = (real(b) for b in bounds)
        queue = self._device.queue
        ledger = _Ledger()
        groups = max(1, -(-n // LOCAL_SIZE))
        with self._call_lock:
            clip_kernel, write_kernel = self._device.program(real is np.float64)
            device_segments = ledger.to_device(queue, data.reshape(-1))
            result = cl_array.empty(queue, max(1, 6 * n), real)
            keep = cl_array.empty(queue, max(1, n), np.int64)
            counters = cl_array.empty(queue, groups * _SEGMENT_COUNTERS, np.int64)
            ledger.kernel_events.append(clip_kernel(
                queue, (groups * LOCAL_SIZE,), (LOCAL_SIZE,), device_segments.data,
                np.int64(n), xmin, ymin, xmax, ymax, np.int32(_METHOD_ID[options.method]),
                np.int32(options.n), np.int32(options.max_depth), real(options.tolerance),
                real(options.auto_piece), np.int32(options.mode is Mode.EXACT), result.data,
                keep.data, counters.data, wait_for=ledger.copy_events))
            m = 0
            if n:
                event, position = cl_array.cumsum(keep[:n], queue=queue, return_event=True,
                                                  wait_for=ledger.kernel_events)
                ledger.kernel_events.append(event)
                m = int(ledger.from_device(queue, position[n - 1:n])[0])
            pieces = cl_array.empty(queue, max(1, 4 * m), real)
            source = cl_array.empty(queue, max(1, m), np.int64)
            t = cl_array.empty(queue, max(1, 2 * m), real)
            if m:
                ledger.kernel_events.append(write_kernel(
                    queue, (n,), None, result.data, keep.data, position.data, np.int64(n),
                    xmin, ymin, xmax, ymax, pieces.data, source.data, t.data,
                    wait_for=ledger.kernel_events[-1:]))
            rows = ledger.from_device(queue, counters).reshape(groups, _SEGMENT_COUNTERS)
            out_pieces = ledger.from_device(queue, pieces[:4 * m]).reshape(m, 4)
            out_source = ledger.from_device(queue, source[:m])
            out_t = ledger.from_device(queue, t[:2 * m]).reshape(m, 2)
            device_stats = ledger.stats(self.name, self.precision)
        out_pieces = out_pieces.astype(np.float64)
        if real is np.float32:
            # The float32 window may reach an ulp past the float64 one: no output point
            # lies outside the window the caller gave.
            np.clip(out_pieces[:, 0::2], window.xmin, window.xmax, out=out_pieces[:, 0::2])
            np.clip(out_pieces[:, 1::2], window.ymin, window.ymax, out=out_pieces[:, 1::2])
        full = np.zeros((groups, C.WIDTH), dtype=np.int64)
        full[:, :_SEGMENT_COUNTERS] = rows
        stats = ClipStats.from_counters(full, n, m, device=device_stats)
        return out_pieces, out_source, out_t.astype(np.float64), stats

    def warm_up(self) -> None:
        """Build the program (or load it from the on-disk caches) and run every method."""
        window = Window(0.0, 0.0, 1.0, 1.0)
        segments = np.array([[-1.0, 0.5, 2.0, 0.5], [0.2, 0.2, 0.8, 0.8]])
        for method in Method:
            self.clip_segments(segments, window, SegmentOptions.resolve(window, method=method))


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
