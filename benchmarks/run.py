"""Run the benchmarks (segments, geometry, svg); print summaries, write JSON and a plot.

Usage::

    python -m benchmarks.run                    # full run of every suite (make bench)
    python -m benchmarks.run --quick            # small sizes only, a smoke test
    python -m benchmarks.run --suite svg        # one suite: segments, geometry, svg, paper, load
    RNSCA_BENCH_QUICK=1 python -m benchmarks.run
    RNSCA_OPENCL_DEVICE=1:0 python -m benchmarks.run   # OpenCL contenders on that device

The segment suite writes ``<out>/segments-<timestamp>.json`` and ``.png``, and copies
both to ``<out>/latest.json`` and ``latest.png``; a full run into the default directory
also copies the plot to ``benchmarks/figure5.png`` (the copy the README shows). The
geometry suite (issue 3: curves, polygons with holes, GeoJSON) writes
``<out>/geometry-<timestamp>.json`` and copies it to ``<out>/latest-geometry.json``. The svg
suite (issue 4: SVG path data parse and write throughput, and Bézier clipping against
flatten-then-clip) writes ``<out>/svg-<timestamp>.json`` and ``<out>/latest-svg.json``.
The paper suite (issue 15, `benchmarks.paper`: the paper's claims, reproduced) writes
``<out>/paper-<timestamp>.json``, ``latest-paper.json`` and its plots; ``--max-size``
caps its workloads.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import shutil
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numba

from benchmarks import bench_curves, bench_geometry, bench_svg, datasets, load, paper
from benchmarks.bench_segments import (
    Plan,
    backend_unavailable_reason,
    evaluate_targets,
    run_n_sweep,
    run_workload,
)
from benchmarks.machine import describe_machine, load_average, run_header, source_digest
from benchmarks.plot import draw_figure5
from benchmarks.report import print_geometry_summary, print_summary
from benchmarks.startup import measure_startup
from benchmarks.timing import Policy, full_policy
from rnsca.backends.registry import configure_opencl
from rnsca.runtime import configure_process

SCHEMA = "rnsca-bench-segments/1"
GEOMETRY_SCHEMA = "rnsca-bench-geometry/1"
SVG_SCHEMA = "rnsca-bench-svg/1"
SUITES = ("segments", "geometry", "svg", "paper", "load")
#: Environment variables that change how Numba's parallel kernels behave under load.
THREADING_ENV = ("NUMBA_NUM_THREADS", "NUMBA_THREADING_LAYER", "OMP_NUM_THREADS",
                 "OMP_WAIT_POLICY")
HERE = Path(__file__).resolve().parent
PROJECT_ROOT = HERE.parent
DEFAULT_OUT = HERE / "results"
FIGURE_COPY = HERE / "figure5.png"


def _quick_policy(n: int) -> Policy:
    return Policy(min_sample=0.002, budget=0.01, min_repeats=1, max_repeats=1)


def build_config(quick: bool, sizes: list[int] | None, shapely_10m: str) -> dict:
    """Return what to run: uniform sizes, shaped-set size, sweep sets, timing plan."""
    if quick:
        uniform = sizes or [100, 1_000]
        shaped_n = 1_000
        plan = Plan(policy_for=_quick_policy,
                    sweep_policy=Policy(min_sample=0.002, budget=0.01, min_repeats=1,
                                        max_repeats=1))
    else:
        uniform = sizes or [*datasets.PAPER_SIZES, *datasets.LARGE_SIZES]
        shaped_n = 1_000_000
        plan = Plan(policy_for=full_policy,
                    shapely_extrapolate_from=10_000_000 if shapely_10m == "extrapolate" else None)
    sweep_uniform = min(uniform, key=lambda n: abs(n - shaped_n))
    return {"uniform_sizes": sorted(uniform), "shaped_n": shaped_n, "plan": plan,
            "sweep_sets": [f"uniform-{sweep_uniform}", f"mostly_outside-{shaped_n}",
                           f"mostly_inside-{shaped_n}", f"long_segments-{shaped_n}"],
            "startup_warm_runs": 1 if quick else 3, "startup_empty_cache": not quick}


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _json_default(obj):
    if hasattr(obj, "item"):
        return obj.item()
    raise TypeError(f"cannot serialise {type(obj).__name__}")


def run(quick: bool, out_dir: Path, sizes: list[int] | None = None,
        shapely_10m: str = "measure", copy_figure: bool = True) -> dict:
    """Run every segment benchmark; write JSON and PNG into `out_dir`; return the result."""
    started = time.monotonic()
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    config = build_config(quick, sizes, shapely_10m)
    plan: Plan = config["plan"]
    machine = describe_machine(PROJECT_ROOT)

    _log("startup: spawning child processes")
    startup = measure_startup(PROJECT_ROOT, warm_runs=config["startup_warm_runs"],
                              empty_cache=config["startup_empty_cache"])

    opencl_skip = backend_unavailable_reason("opencl")
    if opencl_skip:
        _log(f"opencl backend unavailable, recorded as skipped: {opencl_skip}")

    workloads = [*datasets.table2(config["uniform_sizes"]), *datasets.shaped(config["shaped_n"])]
    by_name = {w.name: w for w in workloads}
    results = []
    shapely_per_segment: dict[str, float] = {}
    for w in workloads:
        _log(f"workload {w.name}")
        res = run_workload(w, plan, shapely_per_segment, log=_log,
                           opencl_skip=opencl_skip)
        if w.family == "uniform":
            for r in res["runs"]:
                if r["kind"] == "shapely" and r["measured"]:
                    shapely_per_segment[r["label"]] = r["seconds"] / w.n
        results.append(res)
        gc.collect()

    sweeps = []
    for name in config["sweep_sets"]:
        sweeps.append(run_n_sweep(by_name[name], plan, log=_log))
        gc.collect()

    # The threading layer is known only once a parallel kernel has run.
    machine["numba_threading_layer"] = numba.threading_layer()
    largest = max((r for r in results if r["workload"]["family"] == "uniform"),
                  key=lambda r: r["workload"]["n"])
    targets = evaluate_targets(largest, startup)

    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = out_dir / f"segments-{stamp}.json"
    png_path = out_dir / f"segments-{stamp}.png"
    result = {
        **run_header(SCHEMA, stamp, quick, machine, PROJECT_ROOT),
        "config": {
            "uniform_sizes": config["uniform_sizes"],
            "shaped_n": config["shaped_n"],
            "sweep_sets": config["sweep_sets"],
            "numpy_max_n": 100_000,
            "shapely_10m": None if quick else shapely_10m,
            "timing": ("best (min) of repeats; contenders of a workload timed round-robin; "
                       "inputs below min_sample seconds timed in loops of `number` calls; "
                       "kernels compiled before timing"),
            "policies": {str(n): vars(plan.policy_for(n))
                         for n in sorted({*config["uniform_sizes"], config["shaped_n"]})},
            "time_ratio": "this contender's seconds / the reference's seconds, same workload",
            "peak_memory": ("tracemalloc peak during one extra call (NumPy buffers and Python "
                            "objects; not Numba-runtime or GEOS allocations), over the "
                            "input array's nbytes"),
        },
        "workloads": results,
        "n_sweep": sweeps,
        "startup": startup,
        "targets": targets,
        "elapsed_seconds": None,
        "paths": {"json": str(json_path), "figure": str(png_path)},
    }
    note = f"{result['machine']['cpu_model']}, {result['machine']['cpus_usable']} cores, {stamp}"
    draw_figure5(results, png_path, title_note=note + (" (QUICK)" if quick else ""))
    result["elapsed_seconds"] = time.monotonic() - started
    text = json.dumps(result, indent=1, default=_json_default)
    json_path.write_text(text)
    (out_dir / "latest.json").write_text(text)
    shutil.copyfile(png_path, out_dir / "latest.png")
    if copy_figure and not quick:
        shutil.copyfile(png_path, FIGURE_COPY)
    return result


def run_geometry(quick: bool, out_dir: Path) -> dict:
    """Run the geometry benchmarks (issue 3); write JSON into `out_dir`; return the result."""
    started = time.monotonic()
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    plan = bench_geometry.QUICK_PLAN if quick else bench_geometry.FULL_PLAN
    machine = describe_machine(PROJECT_ROOT)
    curves = bench_geometry.run_curves(plan, log=_log)
    gc.collect()
    polygons = bench_geometry.run_polygons(plan, log=_log)
    gc.collect()
    geojson = bench_geometry.run_geojson(plan, log=_log)
    gc.collect()
    machine["numba_threading_layer"] = numba.threading_layer()

    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = out_dir / f"geometry-{stamp}.json"
    result = {
        "schema": GEOMETRY_SCHEMA,
        "created": stamp,
        "quick": quick,
        "machine": machine,
        "load_average_at_end": load_average(),
        "rnsca_source_sha256_at_end": source_digest(PROJECT_ROOT),
        "rnsca_changed_during_run": (source_digest(PROJECT_ROOT)
                                     != machine["git"]["rnsca_source_sha256"]),
        "config": {
            "n_curves": plan.n_curves,
            "curve_vertices": list(datasets.CURVE_VERTICES),
            "curve_windows": {k: list(v) for k, v in datasets.CURVE_WINDOWS.items()},
            "n_polygons": plan.n_polygons,
            "geojson_lines": plan.geojson_lines,
            "geojson_polygons": plan.geojson_polygons,
            "policy": vars(plan.policy),
            "geojson_repeats": plan.geojson_repeats,
            "environment": {name: os.environ.get(name) for name in THREADING_ENV},
            "timing": ("best (min) of repeats; contenders of a workload timed round-robin, "
                       "each called once on the whole input before timing (compiles "
                       "kernels); garbage collector paused during timed calls; GeoJSON "
                       "stages timed in order per repeat, best of each stage"),
            "time_ratio": "this contender's seconds / the reference's seconds, same workload",
            "output": ("per contender, outside the timing: output geometries and coords, "
                       "invalid polygons (shapely.is_valid), length or area against the "
                       "reference with the same boundary semantics"),
        },
        "curves": curves,
        "polygons": polygons,
        "geojson": geojson,
        "targets": bench_geometry.evaluate_geometry_targets(curves, polygons, geojson),
        "elapsed_seconds": time.monotonic() - started,
        "paths": {"json": str(json_path)},
    }
    text = json.dumps(result, indent=1, default=_json_default)
    json_path.write_text(text)
    (out_dir / "latest-geometry.json").write_text(text)
    return result


def run_svg(quick: bool, out_dir: Path) -> dict:
    """Run the SVG path data benchmarks (issue 4); write JSON into `out_dir`; return it."""
    started = time.monotonic()
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    plan = bench_svg.QUICK_PLAN if quick else bench_svg.FULL_PLAN
    machine = describe_machine(PROJECT_ROOT)
    svg = bench_svg.run_svg(plan, log=_log)
    curves = bench_curves.run_curves(bench_curves.QUICK_PLAN if quick else bench_curves.FULL_PLAN,
                                     log=_log)
    machine["numba_threading_layer"] = numba.threading_layer()
    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = out_dir / f"svg-{stamp}.json"
    result = {
        "schema": SVG_SCHEMA, "created": stamp, "quick": quick, "machine": machine,
        "load_average_at_end": load_average(),
        "config": {"n_paths": plan.n_paths, "policy": vars(plan.policy),
                   "environment": {name: os.environ.get(name) for name in THREADING_ENV},
                   "timing": bench_svg.TIMING},
        "svg": svg,
        "curves": curves,
        "targets": bench_svg.evaluate_svg_targets(svg)
        + bench_curves.evaluate_curve_targets(curves),
        "elapsed_seconds": time.monotonic() - started,
        "paths": {"json": str(json_path)},
    }
    text = json.dumps(result, indent=1, default=_json_default)
    json_path.write_text(text)
    (out_dir / "latest-svg.json").write_text(text)
    return result


def main(argv: list[str] | None = None) -> int:
    """Parse the command line, run, print the summary."""
    configure_process()  # as the CLI and the service do (see rnsca.runtime)
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        default=os.environ.get("RNSCA_BENCH_QUICK", "") not in ("", "0"),
                        help="small sizes only (smoke test); also RNSCA_BENCH_QUICK=1")
    parser.add_argument("--suite", choices=("all", *SUITES), default="all",
                        help="run every suite (default) or only one")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"directory for the JSON and PNG (default {DEFAULT_OUT})")
    parser.add_argument("--sizes", type=lambda s: [int(v) for v in s.split(",")],
                        help="comma-separated uniform sizes instead of the default ones")
    parser.add_argument("--shapely-10m", choices=("measure", "extrapolate"), default="measure",
                        help="time Shapely once at 10M, or extrapolate from the largest "
                             "smaller uniform size (marked in the JSON)")
    parser.add_argument("--max-size", type=int, default=None,
                        help="paper suite: no workload larger than this many segments")
    parser.add_argument("--no-figure-copy", action="store_true",
                        help="do not update benchmarks/figure5.png nor benchmarks/paper-*.png")
    args = parser.parse_args(argv)
    # The OpenCL device and precision, named as for the command line (README).
    configure_opencl(os.environ.get("RNSCA_OPENCL_DEVICE"),
                     os.environ.get("RNSCA_OPENCL_PRECISION", "auto"))
    copy_figure = not args.no_figure_copy and args.out.resolve() == DEFAULT_OUT
    if args.suite in ("all", "segments"):
        print_summary(run(args.quick, args.out, args.sizes, args.shapely_10m, copy_figure))
    if args.suite in ("all", "geometry"):
        print_geometry_summary(run_geometry(args.quick, args.out))
    if args.suite in ("all", "svg"):
        svg_result = run_svg(args.quick, args.out)
        bench_svg.print_svg_summary(svg_result)
        bench_curves.print_curve_summary(svg_result)
    if args.suite in ("all", "paper"):
        paper_copy = not args.no_figure_copy and args.out.resolve() == paper.DEFAULT_OUT
        paper_result = paper.run(args.quick, args.out, args.max_size, paper_copy, log=_log)
        print(paper.markdown_summary(paper_result))
    if args.suite in ("all", "load"):
        if shutil.which("wrk") is None and os.environ.get("CI") != "true" \
                and args.suite == "all":
            print("load suite not run: wrk is not installed (Debian: apt-get install wrk)")
        else:
            load.main(["--out", str(args.out)] + (["--quick"] if args.quick else []))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
