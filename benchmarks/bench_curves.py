"""Bézier clipping benchmarks (issue 4): preserve mode against flatten-then-clip.

Workloads (deterministic, `glyph_page` and `long_curves`):

- ``glyphs``: 2,500 glyph-like outlines (1 to 3 closed contours of 8 to 24 cubic
  segments each, about 100,000 cubics in all) set on a 50 x 50 page of 1000-unit
  cells; the window is the page's centre quarter, cutting through many glyphs;
- ``paper``: the paper's setting, 200 smooth open curves of 500 cubic segments each
  (100,000 cubics) wandering over a 1000 x 1000 square; windows covering 25, 10 and 1%
  of it, centred.

Contenders, called once before timing (compiles or loads the kernels), then timed
round-robin (best of repeats):

- ``rnsca:preserve``: `clip_paths`, curves kept (exact crossings); the subject;
- ``rnsca:approx`` and ``rnsca:flatten`` (``curves="flatten"`` at the tolerance T);
- ``flatten+rnsca:clip_ragged``: `flatten_paths` at T, then `clip_ragged` on the lines
  (our own line core, run-level RNSCA);
- ``flatten+shapely:intersection``: `flatten_paths` at T, ``shapely.from_ragged_array``
  and ``shapely.intersection`` with the box;
- ``opencl:preserve`` and ``opencl:flatten``: ``rnsca:preserve`` and ``rnsca:flatten``
  with ``backend="opencl"`` (segment and run classes, and flatten mode's accepted
  curves, on the device; the rest on the host), where OpenCL is available, with the
  split of one more profiled call (``device``, as in the other suites).

T is 1e-4 of the window's longer side: the flattened baselines are within T of the
curves, preserve mode within about 1e-15 of the parameter (equal or better accuracy).
Strokes (``fill=None``): the baselines clip lines, not regions. Two fill rows are timed
on the glyphs for reference: ``rnsca:preserve:fill`` (clean rings, the default) and
``rnsca:preserve:fill-raw`` (``fill_output="raw"``).
"""

from __future__ import annotations

import gc
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely

from benchmarks.bench_segments import backend_unavailable_reason, device_split
from benchmarks.machine import load_average
from benchmarks.timing import Contender, Policy, time_round_robin
from rnsca import PathArrays, clip_paths, clip_ragged, flatten_paths

__all__ = ["CurvePlan", "FULL_PLAN", "QUICK_PLAN", "glyph_page", "long_curves", "run_curves",
           "evaluate_curve_targets", "print_curve_summary"]

#: Issue 4 targets: preserve mode this many times faster than each baseline.
TARGET_VS_FLATTEN_CLIP = 3.0
TARGET_VS_FLATTEN_SHAPELY = 20.0
#: Flattening tolerance of the baselines, relative to the window's longer side.
RELATIVE_TOLERANCE = 1e-4
SUBJECT = "rnsca:preserve"
FLATTEN_CLIP = "flatten+rnsca:clip_ragged"
FLATTEN_SHAPELY = "flatten+shapely:intersection"
SEED = 44


@dataclass(frozen=True)
class CurvePlan:
    """Sizes and timing of one run (full or quick)."""

    n_glyphs: int
    n_curves: int
    segments_per_curve: int
    policy: Policy


FULL_PLAN = CurvePlan(2_500, 200, 500, Policy(min_sample=0.05, budget=2.0, min_repeats=3,
                                              max_repeats=7))
QUICK_PLAN = CurvePlan(50, 10, 50, Policy(min_sample=0.002, budget=0.01, min_repeats=1,
                                          max_repeats=1))


def _cubic_contour(rng, center, radius, n_segments):
    """Return (start, controls (n, 4, 2)) of a closed blob of cubics around `center`."""
    theta = np.sort(rng.uniform(0, 2 * np.pi, n_segments))
    r = radius * rng.uniform(0.55, 1.0, n_segments)
    knots = center + np.c_[r * np.cos(theta), r * np.sin(theta)]
    nxt = np.roll(knots, -1, axis=0)
    chord = nxt - knots
    normal = np.c_[-chord[:, 1], chord[:, 0]]
    c1 = knots + chord / 3 + normal * rng.uniform(-0.3, 0.3, (n_segments, 1))
    c2 = knots + 2 * chord / 3 + normal * rng.uniform(-0.3, 0.3, (n_segments, 1))
    return np.stack([knots, c1, c2, nxt], axis=1)


def _assemble(paths_of_contours, closed: bool) -> PathArrays:
    controls, subpath_offsets, starts, path_offsets = [], [0], [], [0]
    for contours in paths_of_contours:
        for c in contours:
            controls.append(c)
            subpath_offsets.append(subpath_offsets[-1] + c.shape[0])
            starts.append(c[0, 0])
        path_offsets.append(path_offsets[-1] + len(contours))
    controls = np.concatenate(controls)
    return PathArrays(controls=controls, degree=np.full(controls.shape[0], 3, np.int8),
                      subpath_offsets=np.array(subpath_offsets, np.int64),
                      closed=np.full(len(starts), closed),
                      start=np.array(starts), path_offsets=np.array(path_offsets, np.int64))


def glyph_page(n_glyphs: int, seed: int = SEED) -> tuple[PathArrays, tuple]:
    """Return glyph-like outlines on a square page of 1000-unit cells, and the window."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n_glyphs)))
    glyphs = []
    for k in range(n_glyphs):
        cell = np.array([k % side, k // side], dtype=np.float64) * 1000.0 + 500.0
        contours = [_cubic_contour(rng, cell + rng.uniform(-150, 150, 2),
                                   rng.uniform(150, 400), int(rng.integers(8, 25)))
                    for _ in range(int(rng.integers(1, 4)))]
        glyphs.append(contours)
    page = side * 1000.0
    window = (page * 0.25 + 137.0, page * 0.25 + 211.0, page * 0.75 + 137.0, page * 0.75 + 211.0)
    return _assemble(glyphs, closed=True), window


def long_curves(n_curves: int, segments: int, seed: int = SEED) -> PathArrays:
    """Return `n_curves` smooth open paths of `segments` cubics in [0, 1000]^2."""
    rng = np.random.default_rng(seed + 1)
    curves = []
    for _ in range(n_curves):
        # A smooth random walk folded into the square: tangent-continuous cubics.
        steps = rng.normal(0, 1, (segments + 1, 2)).cumsum(axis=0) * 3.0
        heading = np.cumsum(rng.normal(0, 0.35, segments + 1))
        knots = rng.uniform(0, 1000, 2) + np.cumsum(
            np.c_[np.cos(heading), np.sin(heading)] * 12.0, axis=0) + steps
        knots = 1000.0 - np.abs(1000.0 - np.abs(knots) % 2000.0)
        tangent = np.gradient(knots, axis=0) / 3.0
        a, b = knots[:-1], knots[1:]
        curves.append([np.stack([a, a + tangent[:-1], b - tangent[1:], b], axis=1)])
    return _assemble(curves, closed=False)


WINDOWS = {"25%": (250.0, 250.0, 750.0, 750.0), "10%": (341.9, 341.9, 658.1, 658.1),
           "1%": (450.0, 450.0, 550.0, 550.0)}


def _contenders(paths: PathArrays, window) -> list[tuple[str, Callable[[], object]]]:
    size = max(window[2] - window[0], window[3] - window[1])
    tol = RELATIVE_TOLERANCE * size
    box = shapely.box(*window)

    def flatten_clip():
        coords, offsets, _ = flatten_paths(paths, tol)
        return clip_ragged(shapely.GeometryType.LINESTRING, coords, (offsets,), window)

    def flatten_shapely():
        coords, offsets, _ = flatten_paths(paths, tol)
        lines = shapely.from_ragged_array(shapely.GeometryType.LINESTRING, coords, (offsets,))
        return shapely.intersection(lines, box)

    return [
        (SUBJECT, lambda: clip_paths(paths, window)),
        ("rnsca:approx", lambda: clip_paths(paths, window, mode="approx")),
        ("rnsca:flatten", lambda: clip_paths(paths, window, curves="flatten", tolerance=tol)),
        (FLATTEN_CLIP, flatten_clip),
        (FLATTEN_SHAPELY, flatten_shapely),
    ] + ([] if backend_unavailable_reason("opencl") else [
        ("opencl:preserve", lambda: clip_paths(paths, window, backend="opencl")),
        ("opencl:flatten", lambda: clip_paths(paths, window, curves="flatten", tolerance=tol,
                                              backend="opencl")),
    ])


def _time_all(entries, policy: Policy, log) -> list[dict]:
    contenders = []
    for label, call in entries:
        log(f"curves: {label}")
        call()  # compile or load the kernels outside the timing
        contenders.append(Contender(label, call))
    time_round_robin(contenders, policy)
    return [{"label": c.label, "seconds": c.best,
             "seconds_median": float(np.median(c.samples)), "repeats": len(c.samples),
             "number": c.number,
             # One more (profiled) call's kernel, transfer and host times, as in the
             # other suites (benchmarks/README.md, "OpenCL contenders").
             **({"device": device_split(c.call)} if c.label.startswith("opencl:") else {})}
            for c in contenders]


def _ratios(runs: list[dict]) -> None:
    by = {r["label"]: r for r in runs}
    subject = by[SUBJECT]["seconds"]
    for r in runs:
        r["subject_speedup"] = r["seconds"] / subject


def _workload(name, paths: PathArrays, window, policy, log, extra=()) -> dict:
    load_before = load_average()
    entries = _contenders(paths, window) + list(extra)
    runs = _time_all(entries, policy, log)
    _ratios(runs)
    size = max(window[2] - window[0], window[3] - window[1])
    out = clip_paths(paths, window)
    return {"workload": {"name": name, "paths": len(paths),
                         "subpaths": int(paths.closed.shape[0]),
                         "segments": int(paths.degree.shape[0]), "window": list(window),
                         "tolerance": RELATIVE_TOLERANCE * size,
                         "segments_out": int(out.paths.degree.shape[0]),
                         "load_average_before": load_before,
                         "load_average_after": load_average()},
            "stats": out.stats.to_dict() if hasattr(out.stats, "to_dict") else None,
            "runs": runs}


def run_curves(plan: CurvePlan, log: Callable[[str], None] = print) -> list[dict]:
    """Time every workload; return one dict per workload and window."""
    results = []
    glyphs, window = glyph_page(plan.n_glyphs)
    fill = [("rnsca:preserve:fill", lambda: clip_paths(glyphs, window, fill="nonzero")),
            ("rnsca:preserve:fill-raw", lambda: clip_paths(glyphs, window, fill="nonzero",
                                                           fill_output="raw"))]
    results.append(_workload(f"glyphs-{plan.n_glyphs}", glyphs, window, plan.policy, log,
                             fill))
    gc.collect()
    curves = long_curves(plan.n_curves, plan.segments_per_curve)
    for share, window in WINDOWS.items():
        results.append(_workload(f"paper-{plan.n_curves}x{plan.segments_per_curve}-{share}",
                                 curves, window, plan.policy, log))
        gc.collect()
    return results


def evaluate_curve_targets(results: list[dict]) -> list[dict]:
    """Return the issue-4 speed targets with this run's values and verdicts."""
    targets = []
    for w in results:
        by = {r["label"]: r for r in w["runs"]}
        for ref, limit in ((FLATTEN_CLIP, TARGET_VS_FLATTEN_CLIP),
                           (FLATTEN_SHAPELY, TARGET_VS_FLATTEN_SHAPELY)):
            value = by[ref]["seconds"] / by[SUBJECT]["seconds"]
            targets.append({"key": f"preserve_vs_{ref}", "workload": w["workload"]["name"],
                            "description": f"{SUBJECT} speed-up over {ref}", "value": value,
                            "op": ">=", "limit": limit, "unit": "x", "met": value >= limit})
    return targets


def print_curve_summary(result: dict) -> None:
    """Print one line per contender and workload, then the targets."""
    for w in result["curves"]:
        wl = w["workload"]
        print(f"{wl['name']}: {wl['segments']:,} cubics -> {wl['segments_out']:,} out, "
              f"T = {wl['tolerance']:.3g}")
        for r in w["runs"]:
            print(f"  {r['label']:<32} {r['seconds'] * 1e3:9.2f} ms  "
                  f"{r['subject_speedup']:7.2f}x the subject's time")
    print("Issue 4 curve targets")
    for t in result["targets"]:
        if "workload" not in t or not t["key"].startswith("preserve_vs_"):
            continue
        print(f"  {t['workload']}: {t['description']}: {t['value']:.2f} {t['op']} "
              f"{t['limit']}: {'met' if t['met'] else 'NOT met'}")
