"""Bézier paths on an OpenCL device: classes, run decisions and flattened points, by range.

The device's share of a path call (`CurveCall`): ``classify_bezier`` (one work-item per
segment: its class by its control points' outcodes, and the step count of the segments
to flatten), ``classify_bezier_runs`` (one work-item per run of 16 segments: the box of
its control points) and, after a prefix sum of the step counts, ``flatten_bezier``
(each segment's points into its slots). The host's share, the Numba path kernel,
reads them (`NumbaBackend.clip_paths` with `DevicePaths`).

A call goes in ranges of subpaths of one window each (`OpenCLBackend.clip_paths`), the
same three steps as the lines' (`runs.pipelined`): `CurveCall.start` (the range sent
up, classified, reads enqueued without waiting), `CurveCall.clip` (flattening: once
the count of points is back, their write and read) and `CurveCall.finish` (the reads
awaited; on a float32 device the host decides what the device left open). While the
host's path kernel counts one range, the device works on the next two.

On a float32 device the device's classes are conservative (`windows32`): "inside" and
"beyond an edge" only where that holds for the float64 input too; the host decides the
rest from the float64 input (`decide_ambiguous`) and flattens in float64, so the
classes, decisions and points are exactly the float64 ones.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import pyopencl as cl

from rnsca import constants
from rnsca.arrays import exclusive_sum
from rnsca.backends.opencl.runs import Ledger
from rnsca.backends.opencl.segments import _Raw
from rnsca.kernels import bezier as BZ
from rnsca.kernels.outcode import BOTTOM, LEFT, RIGHT, TOP
from rnsca.options import Precision
from rnsca.stats import DeviceStats
from rnsca.window import Window

__all__ = ["CurveCall", "CurveTables", "decide_ambiguous", "run_bounds", "windows32"]

_F32 = np.finfo(np.float32)
# `flatten` as clip.cl numbers it (FLATTEN_*).
_FLATTEN = {"none": constants.FLATTEN_NONE, "accepted": constants.FLATTEN_ACCEPTED_CURVES,
            "all": constants.FLATTEN_ALL}


class CurveTables(NamedTuple):
    """What the device decided for a range's segments (indexed from its first segment).

    `segment_class` (uint8, `bezier.SEGMENT_*`); `run_decision` (int8: each run's
    ``bezier._RUN_*`` at its first segment, 0 elsewhere; empty without subpaths);
    `point_start` (int64, m + 1) and `points` (float64): segment i's flattened points are
    ``points[point_start[i]:point_start[i + 1]]``.
    """

    segment_class: np.ndarray
    run_decision: np.ndarray
    point_start: np.ndarray
    points: np.ndarray


@dataclass
class _Range:
    """One range of segments in flight."""

    controls: np.ndarray
    degree: np.ndarray
    bounds: tuple[float, ...]
    has_window: bool
    tolerance: float
    flatten: str
    has_runs: bool
    run_first: np.ndarray
    run_end: np.ndarray
    m: int  # segments the device classifies (0: a float32 device only flattening)
    held: list = field(default_factory=list)
    device: dict = field(default_factory=dict)
    reads: dict = field(default_factory=dict)
    events: list = field(default_factory=list)
    point_end: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    point_end_read: list = field(default_factory=list)


class CurveCall:
    """One path (or flatten) call's device work: its device, precision and ledger."""

    def __init__(self, device: Any, precision: Precision, real: Any) -> None:
        self.device = device
        self.precision = precision
        self.real = real
        self.double = precision is Precision.FLOAT64
        self.ledger = Ledger()
        with device.call_lock:
            self.kernels = device.program(self.double)

    def start(self, controls: np.ndarray, degree: np.ndarray, window: Window | None,
              tolerance: float, flatten: str,
              subpath_offsets: np.ndarray | None = None) -> _Range:
        """Send a range of segments up and classify them; return it in flight.

        Parameters are those of `OpenCLBackend.classify_curves`.
        """
        bounds = (0.0, 0.0, 0.0, 0.0) if window is None else window.bounds
        run_first, run_end = run_bounds(subpath_offsets if subpath_offsets is not None
                                        else np.zeros(1, np.int64))
        controls = np.ascontiguousarray(controls, np.float64)
        degree = np.ascontiguousarray(degree, np.int8)
        m = degree.shape[0]
        if self.double:
            accept = reject = tuple(np.float64(b) for b in bounds)
            device_flatten = flatten
        else:
            accept, reject = windows32(bounds)
            device_flatten = "none"  # the host flattens, in float64 (`finish`)
            if window is None:  # flattening only: nothing for the device to decide
                m = 0
        r = _Range(controls, degree, bounds, window is not None, tolerance, flatten,
                   subpath_offsets is not None, run_first, run_end, m)
        n_runs = run_first.shape[0] if m else 0
        ledger = self.ledger
        device = self.device
        queue = device.queue
        kernels = self.kernels
        reads_from = len(ledger.copy_events)
        with device.call_lock:
            alloc = device.allocator
            with np.errstate(over="ignore"):  # float32: beyond its range is ±inf, which
                # still orders the points against the window (`windows32`)
                device_controls: np.ndarray = controls[:m].astype(self.real).reshape(-1)
            # Not waited for: the host arrays live as long as the range (`r.held`).
            r.held = [device_controls, degree[:m].copy(), run_first, run_end]
            d = r.device
            d["controls"] = ledger.upload(queue, r.held[0], alloc)
            d["degree"] = ledger.upload(queue, r.held[1], alloc)
            d["class"] = alloc(max(8, m))
            d["n_points"] = alloc(max(8, 8 * m))
            if m:
                ledger.kernel_events.append(kernels.classify_bezier(
                    queue, (m,), None, d["controls"], d["degree"], np.int64(m), *accept,
                    *reject,
                    np.float64(tolerance) if self.double else np.float32(0),  # float32: unused
                    np.int32(_FLATTEN[device_flatten]), d["class"], d["n_points"]))
            if m and device_flatten != "none":
                d["point_end"] = alloc(8 * m)
                ledger.kernel_events.append(device.scan()(
                    _Raw(d["n_points"], queue, alloc), _Raw(d["point_end"], queue, alloc),
                    queue=queue, size=m, allocator=alloc))
                r.point_end = ledger.read(queue, d["point_end"], np.int64, m)
                r.point_end_read = ledger.copy_events[-1:]
            r.reads["run_class"] = np.zeros(0, dtype=np.int8)
            if n_runs:
                d["run_first"] = ledger.upload(queue, run_first, alloc)
                d["run_end"] = ledger.upload(queue, run_end, alloc)
                d["run_class"] = alloc(max(8, n_runs))
                ledger.kernel_events.append(kernels.classify_bezier_runs(
                    queue, (n_runs,), None, d["controls"], d["run_first"], d["run_end"],
                    np.int64(n_runs), *accept, *reject, np.int32(flatten != "none"),
                    d["run_class"]))
                r.reads["run_class"] = ledger.read(queue, d["run_class"], np.int8, n_runs)
            r.reads["classes"] = ledger.read(queue, d["class"], np.uint8, m)
            r.events = ledger.copy_events[reads_from:]
            queue.flush()
        return r

    def clip(self, r: _Range) -> None:
        """Flatten the range's curves once their count of points is back (if the device does)."""
        r.reads["points"] = np.zeros((0,), self.real)
        if not r.point_end_read:
            return
        cl.wait_for_events(r.point_end_read)
        total = int(r.point_end[-1])
        if not total:
            return
        ledger = self.ledger
        device = self.device
        queue = device.queue
        d = r.device
        with device.call_lock:
            d["points"] = device.allocator(2 * np.dtype(self.real).itemsize * total)
            ledger.kernel_events.append(self.kernels.flatten_bezier(
                queue, (r.m,), None, d["controls"], d["degree"], d["n_points"],
                d["point_end"], np.int64(r.m), d["points"]))
            r.reads["points"] = ledger.read(queue, d["points"], self.real, 2 * total)
            r.events += ledger.copy_events[-1:]
            queue.flush()

    def finish(self, r: _Range) -> CurveTables:
        """Wait for the range's reads; return its tables (float32: completed on the host)."""
        if r.events:
            cl.wait_for_events(r.events)
        classes = r.reads["classes"]
        run_class = r.reads["run_class"]
        flat = r.reads["points"].reshape(-1, 2)
        controls, degree, m = r.controls, r.degree, r.degree.shape[0]
        point_start = np.zeros(m + 1, dtype=np.int64)
        if not self.double:
            if not r.has_window:  # flattening only: the classes mean nothing here
                classes = np.full(m, BZ.SEGMENT_AMBIGUOUS, dtype=np.uint8)
                run_class = np.full(r.run_first.shape[0], BZ._RUN_SEGMENTED, dtype=np.int8)
            else:
                decide_ambiguous(classes, run_class, controls, degree, r.run_first,
                                 r.run_end, r.bounds, r.flatten != "none")
            if r.flatten != "none":
                wanted = (r.flatten == "all") | ((classes == BZ.SEGMENT_ACCEPTED)
                                                 & (degree > 1))
                steps = np.where(wanted, BZ.flatten_steps(controls, degree,
                                                          float(r.tolerance)), 0)
                np.cumsum(steps, out=point_start[1:])
                flat = np.empty((int(point_start[-1]), 2))
                BZ.flatten_segments(controls, degree, point_start, flat)
        elif r.point_end.shape[0]:
            point_start[1:] = r.point_end
        run_decision = np.zeros(m if r.has_runs else 0, dtype=np.int8)
        run_decision[r.run_first] = run_class
        r.device.clear()
        r.held.clear()
        return CurveTables(classes, run_decision, point_start,
                           flat.astype(np.float64, copy=False))

    def whole(self, *args: Any) -> CurveTables:
        """Return the tables of one range, start to finish (`start`'s arguments)."""
        r = self.start(*args)
        self.clip(r)
        return self.finish(r)

    def totals(self, name: str) -> DeviceStats:
        """Return the call's transfers and device times, once every range is finished."""
        return self.ledger.stats(name, self.precision)


def run_bounds(subpath_offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the first and end segments of the runs `bezier.clip_path_blocks` tests.

    Runs of `bezier.RUN_SEGMENTS` segments from each subpath's first one; a last run
    of a single segment is not a run (its segment is tested alone).
    """
    first = subpath_offsets[:-1]
    last = subpath_offsets[1:]
    per_subpath = -(-(last - first) // BZ.RUN_SEGMENTS)
    subpath = np.repeat(np.arange(first.shape[0]), per_subpath)
    index = np.arange(subpath.shape[0]) - np.repeat(exclusive_sum(per_subpath)[:-1],
                                                    per_subpath)
    run_first = first[subpath] + index * BZ.RUN_SEGMENTS
    run_end = np.minimum(run_first + BZ.RUN_SEGMENTS, last[subpath])
    kept = run_end - run_first >= 2
    return (np.ascontiguousarray(run_first[kept], np.int64),
            np.ascontiguousarray(run_end[kept], np.int64))


def windows32(bounds: tuple[float, ...] | np.ndarray) -> tuple[tuple, tuple]:
    """Return the (accept, reject) float32 windows that make the device's curve classes sure.

    Rounding to float32 keeps order (``x <= y`` gives ``f(x) <= f(y)``, also where it
    overflows to ±inf or a device flushes subnormals to zero), so ``f(x) < f(xmin)``
    proves ``x < xmin`` and ``f(x) > f(xmin)`` proves ``x > xmin``. The reject window:
    each bound rounded to nearest (moved outward to a normal float32 where that is
    subnormal), so a point beyond one of its edges is beyond the float64 edge. The
    accept window: the nearest normal float32 strictly inside each rounded bound, so a
    point inside it is inside the float64 window (none is where a bound overflows
    inward). Points between the two are ambiguous and go to the host.
    """
    tiny = np.float32(_F32.tiny)  # the smallest normal: subnormals may be flushed to 0
    inf = np.float32(np.inf)
    with np.errstate(over="ignore"):
        rounded = np.asarray(bounds, np.float64).astype(np.float32)

    def above(h):  # the smallest normal float32 > h
        return tiny if -tiny <= h < tiny else np.nextafter(h, inf)

    def not_above(h):  # the largest normal float32 (or -inf) <= h
        return -tiny if -tiny < h < tiny else h

    xmin, ymin, xmax, ymax = rounded
    reject = (not_above(xmin), not_above(ymin), -not_above(-xmax), -not_above(-ymax))
    if np.isposinf(xmin) or np.isposinf(ymin) or np.isneginf(xmax) or np.isneginf(ymax):
        accept = (_F32.max, _F32.max, -_F32.max, -_F32.max)  # no point is inside it
    else:
        accept = (above(xmin), above(ymin), -above(-xmax), -above(-ymax))
    return tuple(map(np.float32, accept)), tuple(map(np.float32, reject))


def _outcodes(x, y, bounds):
    xmin, ymin, xmax, ymax = bounds
    return ((x < xmin) * LEFT) | ((x > xmax) * RIGHT) | ((y < ymin) * BOTTOM) | (
        (y > ymax) * TOP)


def decide_ambiguous(classes: np.ndarray, run_class: np.ndarray, controls: np.ndarray,
                      degree: np.ndarray, run_first: np.ndarray, run_end: np.ndarray,
                      bounds: tuple[float, ...], flatten: bool) -> None:
    """Decide, in float64 and in place, the segments and runs a float32 device left open.

    The same tests as `bezier.clip_path_blocks` (control points' outcodes, a run's box),
    on the float64 input: the result is the float64 device's.
    """
    rows = np.flatnonzero(classes == BZ.SEGMENT_AMBIGUOUS)
    if rows.size:
        codes = _outcodes(controls[rows, :, 0], controls[rows, :, 1], bounds)
        d = degree[rows]
        used = np.ones(codes.shape, dtype=bool)
        used[:, 2] = d >= 2
        used[:, 3] = d == 3
        c_or = np.bitwise_or.reduce(np.where(used, codes, 0), axis=1)
        c_and = np.bitwise_and.reduce(np.where(used, codes, LEFT | RIGHT | BOTTOM | TOP),
                                      axis=1)
        classes[rows] = np.where(c_or == 0, BZ.SEGMENT_ACCEPTED, np.where(
            c_and != 0, BZ.SEGMENT_REJECTED, BZ.SEGMENT_AMBIGUOUS))
    runs = np.flatnonzero(run_class == BZ._RUN_SEGMENTED)
    if runs.size:
        first, end = run_first[runs], run_end[runs]
        # Each run's segments (its last repeated up to RUN_SEGMENTS), slots 1..3, and
        # slot 0 of its first (`bezier._run_box`).
        members = np.minimum(first[:, None] + np.arange(BZ.RUN_SEGMENTS), end[:, None] - 1)
        points = controls[members][:, :, 1:, :].reshape(runs.size, -1, 2)
        lo = np.minimum(points.min(axis=1), controls[first, 0])
        hi = np.maximum(points.max(axis=1), controls[first, 0])
        c_lo = _outcodes(lo[:, 0], lo[:, 1], bounds)
        c_hi = _outcodes(hi[:, 0], hi[:, 1], bounds)
        run_class[runs] = np.where(((c_lo | c_hi) == 0) & (not flatten), BZ._RUN_ACCEPTED,
                                   np.where((c_lo & c_hi) != 0, BZ._RUN_REJECTED,
                                            BZ._RUN_SEGMENTED))
