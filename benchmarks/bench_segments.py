"""Segment clipping benchmarks: every method and backend, Shapely, and a memory floor.

For one workload the contenders are

- ``numba:<method>[:<mode>]``: `rnsca.clip_segments` on the Numba backend, every method
  in exact mode, plus rnsca and midpoint in approx mode;
- ``opencl:<method>[:<mode>]``: the same on the OpenCL backend (default device, or
  ``RNSCA_OPENCL_DEVICE``), where OpenCL is available. Its record also holds
  ``device``: the kernel time and the host-device transfer time of one more call, from
  OpenCL event profiling (`rnsca.stats.DeviceStats`), and the rest of the call's wall
  time (``host_seconds``: validation, allocation, Python), so a run on a GPU can be read
  against a run on a CPU driver;
- ``shapely:clip_by_rect`` and ``shapely:intersection``: Shapely end to end, from the
  (n, 4) array to an (m, 4) array of pieces and their (m,) source indices, through
  ``shapely.linestrings``, ``clip_by_rect`` (or ``intersection`` with a box) and
  ``get_coordinates``;
- ``part:validate``: `rnsca.clip.as_segments` alone, the input check as a pass of its own
  (not a clip: since issue 15 the Numba backend checks inside its clipping pass, and this
  shows what that pass saves; OpenCL still runs it first);
- ``floor:copy``: what any function that reads the input and returns fresh output arrays
  must at least do: copy the input's bytes into a preallocated array of the same size,
  then allocate and write arrays the size of the output (pieces (m, 4) float64, source
  (m,) int64, t (m, 2) float64), with m the number of pieces the clip gives.

Every contender is timed end to end through its public call (input validation
included), compiled beforehand, interleaved with the others (see `benchmarks.timing`).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely

import rnsca
from benchmarks.datasets import Workload, classify
from benchmarks.machine import load_average
from benchmarks.timing import Contender, Policy, peak_traced_bytes, time_round_robin
from rnsca.backends.numba_cpu import BLOCK_SIZE, SERIAL_BLOCKS
from rnsca.clip import as_segments

__all__ = [
    "SWEEP_N",
    "Plan",
    "Variant",
    "VARIANTS",
    "run_workload",
    "run_n_sweep",
    "evaluate_targets",
    "backend_unavailable_reason",
    "device_split",
]

#: Fixed N values of the sweep (compared with ``n="auto"``).
SWEEP_N = (2, 3, 4, 8, 16, 32, 64)
#: Reference contenders for the ratios.
REF_SHAPELY = "shapely:clip_by_rect"
REF_CS = "numba:cohen_sutherland"
REF_FLOOR = "floor:copy"
VALIDATE = "part:validate"
SUBJECT = "numba:rnsca:exact"


@dataclass(frozen=True)
class Variant:
    """One clip configuration of `rnsca.clip_segments` (method, mode, n)."""

    method: str
    mode: str = "exact"
    n: int | str = "auto"

    def label(self, backend: str) -> str:
        """Return the contender label, e.g. ``numba:rnsca:approx`` or ``numba:liang_barsky``."""
        if self.method in ("rnsca", "midpoint"):
            return f"{backend}:{self.method}:{self.mode}"
        return f"{backend}:{self.method}"


VARIANTS = (
    Variant("rnsca", "exact"),
    Variant("rnsca", "approx"),
    Variant("cohen_sutherland"),
    Variant("liang_barsky"),
    Variant("nicholl_lee_nicholl"),
    Variant("midpoint", "exact"),
    Variant("midpoint", "approx"),
)


@dataclass(frozen=True)
class Plan:
    """What to time and how hard; one per run (full or quick).

    Attributes
    ----------
    policy_for : callable
        ``policy_for(n) -> Policy`` for a workload of n segments.
    shapely_once_from : int
        At or above this size each Shapely contender runs exactly once.
    shapely_extrapolate_from : int or None
        At or above this size Shapely is not run; its time is the time measured at
        the largest smaller uniform size, scaled linearly (marked in the JSON).
    sweep_policy : Policy
        Timing of the n sweep.
    """

    policy_for: Callable[[int], Policy]
    shapely_once_from: int = 10_000_000
    shapely_extrapolate_from: int | None = None
    sweep_policy: Policy = Policy(min_sample=0.05, budget=2.0, min_repeats=3, max_repeats=5)


# --------------------------------------------------------------------------- contenders


def _clip_call(segments, window, variant: Variant, backend: str) -> Callable[[], object]:
    def call():
        return rnsca.clip_segments(segments, window, method=variant.method, mode=variant.mode,
                                   n=variant.n, backend=backend)
    return call


def _pieces_from_geometries(clipped: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Return ((m, 4) pieces, (m,) source) from clipped line geometries.

    A geometry with fewer than two coordinates (empty, or a point where a segment only
    touches the window) gives no piece, as in rnsca; otherwise the piece runs from its
    first to its last coordinate (a clipped segment is straight).
    """
    coords, index = shapely.get_coordinates(clipped, return_index=True)
    counts = np.bincount(index, minlength=n)
    source = np.flatnonzero(counts >= 2)
    start = np.zeros(n, dtype=np.int64)
    np.cumsum(counts[:-1], out=start[1:])
    first = start[source]
    last = first + counts[source] - 1
    pieces = np.concatenate([coords[first], coords[last]], axis=1)
    return pieces, source


def _shapely_clip_by_rect(segments, window) -> Callable[[], object]:
    xmin, ymin, xmax, ymax = window

    def call():
        lines = shapely.linestrings(segments.reshape(-1, 2, 2))
        return _pieces_from_geometries(shapely.clip_by_rect(lines, xmin, ymin, xmax, ymax),
                                       segments.shape[0])
    return call


def _shapely_intersection(segments, window) -> Callable[[], object]:
    box = shapely.box(*window)

    def call():
        lines = shapely.linestrings(segments.reshape(-1, 2, 2))
        return _pieces_from_geometries(shapely.intersection(lines, box), segments.shape[0])
    return call


def _copy_floor(segments, m: int) -> Callable[[], object]:
    scratch = np.empty_like(segments)
    np.copyto(scratch, segments)  # fault the scratch pages in outside the timed call

    def call():
        np.copyto(scratch, segments)
        pieces = np.empty((m, 4), dtype=np.float64)
        pieces.fill(0.0)
        source = np.empty(m, dtype=np.int64)
        source.fill(0)
        t = np.empty((m, 2), dtype=np.float64)
        t.fill(0.0)
        return pieces, source, t
    return call


def _pieces_out(result) -> int | None:
    if isinstance(result, rnsca.SegmentClipResult):
        return len(result)
    if isinstance(result, tuple):
        return int(result[0].shape[0])
    return None


def backend_unavailable_reason(backend: str) -> str | None:
    """Return None if `backend` clips a tiny input here, else why it cannot (recorded)."""
    try:
        rnsca.clip_segments(np.array([[-1.0, 0.5, 2.0, 0.5]]), (0, 0, 1, 1), backend=backend)
    except (rnsca.BackendUnavailableError, ImportError) as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def _warm_up(segments, window, variant: Variant, backend: str) -> None:
    """Compile (or load) the kernels for this configuration on a few rows of the input.

    Both drivers: a few rows run on the calling thread, more than `SERIAL_BLOCKS` blocks
    in parallel (otherwise the first timed call loads the parallel one).
    """
    for rows in (64, (SERIAL_BLOCKS + 1) * BLOCK_SIZE):
        rnsca.clip_segments(segments[:rows], window, method=variant.method, mode=variant.mode,
                            n=variant.n, backend=backend)


# --------------------------------------------------------------------------- one workload


def _record(workload: Workload, c: Contender, kind: dict, memory: tuple[int, object] | None,
            input_nbytes: int) -> dict:
    rec = {
        "workload": workload.name,
        "family": workload.family,
        "n": workload.n,
        "label": c.label,
        **kind,
        "seconds": c.best,
        "seconds_median": statistics.median(c.samples),
        "repeats": len(c.samples),
        "number": c.number,
        "segments_per_s": workload.n / c.best if c.best > 0 else None,
        "pieces_out": _pieces_out(c.last),
        "measured": True,
        "note": None,
        "stats": None,
        "peak_extra_bytes": None,
        "peak_extra_ratio": None,
    }
    if isinstance(c.last, rnsca.SegmentClipResult):
        rec["stats"] = c.last.stats.to_dict()
    if memory is not None:
        rec["peak_extra_bytes"] = int(memory[0])
        rec["peak_extra_ratio"] = memory[0] / input_nbytes if input_nbytes else None
    return rec


def device_split(call: Callable[[], object]) -> dict:
    """Return one more OpenCL call's wall time, kernel and transfer times, and the rest.

    The kernel and transfer times come from OpenCL event profiling; ``host_seconds`` is
    the same call's wall time minus both (validation, allocation, Python, waiting). Read
    them as shares of ``call_seconds``, not of the best time of the timed repeats.
    """
    start = time.perf_counter()
    device = call().stats.device
    wall = time.perf_counter() - start
    return {"device": device.device, "precision": device.precision,
            "call_seconds": wall, "kernel_seconds": device.kernel_seconds,
            "transfer_seconds": device.transfer_seconds,
            "bytes_to_device": device.bytes_to_device,
            "bytes_from_device": device.bytes_from_device,
            "host_seconds": max(0.0, wall - device.kernel_seconds - device.transfer_seconds)}


def run_workload(workload: Workload, plan: Plan,
                 shapely_estimate: dict[str, float] | None = None,
                 log: Callable[[str], None] = print, opencl_skip: str | None = "not asked"
                 ) -> dict:
    """Time every contender on `workload`; return ``{"workload": ..., "runs": [...]}``.

    `opencl_skip` is the reason the OpenCL backend is not timed (None: it runs).
    `shapely_estimate` maps a Shapely label to seconds per segment measured on a smaller
    uniform set, used when the plan extrapolates at this size.
    """
    segments = workload.segments()
    window = workload.window
    n = workload.n
    policy = plan.policy_for(n)
    info = workload.describe()
    info["level0"] = classify(segments, window)
    contenders: list[Contender] = []
    kinds: dict[str, dict] = {}
    traced: set[str] = set()
    skipped: list[dict] = []

    backends = ["numba"]
    if opencl_skip is None:
        backends.append("opencl")
    else:
        skipped.append({"label": "opencl:*", "reason": opencl_skip})
    for backend in backends:
        for variant in VARIANTS:
            label = variant.label(backend)
            _warm_up(segments, window, variant, backend)
            contenders.append(Contender(label, _clip_call(segments, window, variant, backend)))
            kinds[label] = {"kind": backend, "backend": backend, "method": variant.method,
                            "mode": variant.mode, "n_param": variant.n}
            traced.add(label)

    # The floor needs the output size; every exact method gives the same count.
    m = len(rnsca.clip_segments(segments, window, method="cohen_sutherland"))
    contenders.append(Contender(REF_FLOOR, _copy_floor(segments, m)))
    kinds[REF_FLOOR] = {"kind": "floor", "backend": None, "method": None, "mode": None,
                        "n_param": None}
    traced.add(REF_FLOOR)
    as_segments(segments[:64])  # compile (or load) the validation kernel, if it has one
    contenders.append(Contender(VALIDATE, lambda: as_segments(segments)))
    kinds[VALIDATE] = {"kind": "part", "backend": None, "method": None, "mode": None,
                       "n_param": None}
    traced.add(VALIDATE)

    extrapolate = (plan.shapely_extrapolate_from is not None
                   and n >= plan.shapely_extrapolate_from)
    once = 1 if n >= plan.shapely_once_from else None
    shapely_calls = {"shapely:clip_by_rect": _shapely_clip_by_rect,
                     "shapely:intersection": _shapely_intersection}
    if not extrapolate:
        for label, make in shapely_calls.items():
            make(segments[:64], window)()  # first-call overheads outside the timing
            contenders.append(Contender(label, make(segments, window), max_repeats=once))
            kinds[label] = {"kind": "shapely", "backend": None, "method": label.split(":")[1],
                            "mode": "exact", "n_param": None}

    log(f"  {workload.name}: timing {len(contenders)} contenders "
        f"(best of up to {policy.max_repeats})")
    info["load_average_before"] = load_average()
    time_round_robin(contenders, policy)
    info["load_average_after"] = load_average()

    runs = []
    for c in contenders:
        memory = None
        if c.label in traced:
            memory = peak_traced_bytes(c.call)
        rec = _record(workload, c, kinds[c.label], memory, segments.nbytes)
        if kinds[c.label]["kind"] == "opencl":
            rec["device"] = device_split(c.call)
        if kinds[c.label]["kind"] == "shapely":
            rec["note"] = ("peak memory not measured: GEOS allocations are invisible to "
                           "tracemalloc")
            if once:
                rec["note"] = "timed once (no repeats) at this size; " + rec["note"]
        runs.append(rec)

    if extrapolate:
        for label in shapely_calls:
            per_segment = (shapely_estimate or {}).get(label)
            if per_segment is None:
                skipped.append({"label": label, "reason": "no smaller size to extrapolate from"})
                continue
            seconds = per_segment * n
            runs.append({
                "workload": workload.name, "family": workload.family, "n": n, "label": label,
                "kind": "shapely", "backend": None, "method": label.split(":")[1],
                "mode": "exact", "n_param": None, "seconds": seconds, "seconds_median": seconds,
                "repeats": 0, "number": 0, "segments_per_s": n / seconds, "pieces_out": None,
                "measured": False,
                "note": "extrapolated linearly from the largest smaller uniform size",
                "stats": None, "peak_extra_bytes": None, "peak_extra_ratio": None})

    _add_ratios(runs)
    _check_pieces(runs)
    return {"workload": info, "runs": runs, "skipped": skipped}


def _add_ratios(runs: list[dict]) -> None:
    """Give each run its time ratio to the three references (this run / reference)."""
    by_label = {r["label"]: r for r in runs}
    for r in runs:
        r["time_ratio"] = {}
        for key, ref in (("shapely_clip_by_rect", REF_SHAPELY),
                         ("numba_cohen_sutherland", REF_CS), ("copy_floor", REF_FLOOR)):
            other = by_label.get(ref)
            r["time_ratio"][key] = (r["seconds"] / other["seconds"]
                                    if other and other["seconds"] > 0 else None)


def _check_pieces(runs: list[dict]) -> None:
    """Flag each exact contender whose piece count differs from numba cohen_sutherland's.

    Shapely may differ by the odd segment that only touches the window (rnsca drops a
    single-point contact; GEOS may keep it as a point, which the conversion also drops);
    approx mode may lose a piece shorter than its tolerance.
    """
    ref = next((r["pieces_out"] for r in runs if r["label"] == REF_CS), None)
    for r in runs:
        if r["kind"] in ("numba", "numpy", "opencl", "shapely") and r["pieces_out"] is not None:
            r["pieces_match_reference"] = r["pieces_out"] == ref
        else:
            r["pieces_match_reference"] = None


# --------------------------------------------------------------------------- n sweep


def run_n_sweep(workload: Workload, plan: Plan, log: Callable[[str], None] = print) -> dict:
    """Time rnsca (exact and approx) at every fixed N of `SWEEP_N` and at ``n="auto"``."""
    segments = workload.segments()
    window = workload.window
    contenders = []
    meta = {}
    for mode in ("exact", "approx"):
        for n_value in ("auto", *SWEEP_N):
            variant = Variant("rnsca", mode, n_value)
            label = f"numba:rnsca:{mode}:n={n_value}"
            _warm_up(segments, window, variant, "numba")
            contenders.append(Contender(label, _clip_call(segments, window, variant, "numba")))
            meta[label] = (mode, n_value)
    log(f"  n sweep on {workload.name}: {len(contenders)} configurations")
    time_round_robin(contenders, plan.sweep_policy)
    runs = []
    for c in contenders:
        mode, n_value = meta[c.label]
        runs.append({
            "workload": workload.name, "label": c.label, "mode": mode, "n_param": n_value,
            "seconds": c.best, "repeats": len(c.samples), "number": c.number,
            "segments_per_s": workload.n / c.best, "pieces_out": len(c.last),
            "stats": c.last.stats.to_dict(),
        })
    summary = {}
    for mode in ("exact", "approx"):
        rows = [r for r in runs if r["mode"] == mode]
        auto = next(r for r in rows if r["n_param"] == "auto")
        fixed = [r for r in rows if r["n_param"] != "auto"]
        best = min(fixed, key=lambda r: r["seconds"])
        for r in rows:
            r["ratio_to_auto"] = r["seconds"] / auto["seconds"]
        summary[mode] = {
            "auto_seconds": auto["seconds"],
            "best_fixed_n": best["n_param"],
            "best_fixed_seconds": best["seconds"],
            "auto_over_best_fixed": auto["seconds"] / best["seconds"],
        }
    info = workload.describe()
    return {"workload": info, "runs": runs, "summary": summary}


# --------------------------------------------------------------------------- targets


def evaluate_targets(workload_result: dict, startup: dict) -> list[dict]:
    """Return the issue's targets for exact rnsca on numba, each with its value and verdict.

    Measured on `workload_result` (the 10M uniform set in a full run) and the warm
    second-process figure of `startup`.
    """
    runs = {r["label"]: r for r in workload_result["runs"]}
    subject = runs.get(SUBJECT)
    name = workload_result["workload"]["name"]

    def target(key, description, value, limit, op, unit, source_note=None):
        met = None if value is None else (value >= limit if op == ">=" else
                                          value <= limit if op == "<=" else value < limit)
        out = {"key": key, "description": description, "workload": name, "value": value,
               "op": op, "limit": limit, "unit": unit, "met": met}
        if source_note:
            out["note"] = source_note
        return out

    approx = runs.get("numba:rnsca:approx")
    shapely_run = runs.get(REF_SHAPELY)
    shapely_note = None
    if shapely_run is not None and not shapely_run["measured"]:
        shapely_note = shapely_run["note"]
    ratio = subject["time_ratio"] if subject else {}
    speedup = (1.0 / ratio["shapely_clip_by_rect"]
               if ratio.get("shapely_clip_by_rect") else None)
    warm = startup.get("warm", {}).get("first_result_seconds_median")
    return [
        target("throughput", "exact rnsca on numba, segments per second",
               subject and subject["segments_per_s"], 80e6, ">=", "segments/s"),
        target("copy_floor", "time over the memory-bound copy floor",
               ratio.get("copy_floor"), 6.0, "<=", "x"),
        target("vs_shapely", "speed-up over Shapely clip_by_rect end to end",
               speedup, 50.0, ">=", "x", shapely_note),
        target("vs_cohen_sutherland", "time over numba Cohen-Sutherland",
               ratio.get("numba_cohen_sutherland"), 1.2, "<=", "x"),
        target("peak_memory", "peak extra memory during the call over the input's nbytes",
               subject and subject["peak_extra_ratio"], 3.0, "<=", "x"),
        target("second_process", "a second process reaches its first result (warm cache)",
               warm, 2.0, "<", "s"),
        # Issue 15 (the segment core): the same run, its own limits.
        target("issue15_throughput", "issue 15: exact rnsca on numba, segments per second",
               subject and subject["segments_per_s"], 60e6, ">=", "segments/s"),
        target("issue15_vs_shapely", "issue 15: speed-up over Shapely clip_by_rect",
               speedup, 60.0, ">=", "x", shapely_note),
        target("issue15_copy_floor", "issue 15: time over the plain copy of input and output",
               ratio.get("copy_floor"), 4.0, "<=", "x"),
        target("issue15_approx", "issue 15: approx rnsca (default resolution) time over exact",
               approx["seconds"] / subject["seconds"] if approx and subject else None,
               1.0, "<=", "x"),
        target("issue15_peak_memory", "issue 15: peak extra memory over the input's nbytes",
               subject and subject["peak_extra_ratio"], 2.0, "<=", "x"),
    ]
