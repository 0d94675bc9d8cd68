"""Compare two checkouts of rnsca on the same inputs, interleaved: before/after a change.

Usage::

    python -m benchmarks.compare --base /path/to/old/checkout          # this one is "head"
    python -m benchmarks.compare --base ../base --head . --rounds 3 --quick

The machines this project runs on are noisy, so a before/after figure taken in two runs
means little. Here the inputs are built once (the seeded sets of `make bench`: uniform,
mostly-outside and long segments, smooth polylines, polygons with holes, a GeoJSON
collection, glyph-like SVG paths, long cubic curves) and saved; then each round starts a
fresh process per checkout, base and head in turn, which times every workload through the
public API (``rnsca.clip_segments``, ``clip_ragged``, ``clip_geojson``, ``parse_paths``,
``write_paths``, ``clip_svg``, ``clip_paths``) after a warm-up call. A workload's figure
is its best (minimum) time over every sample of every round; the ratio is head / base.

Writes ``<out>/compare-<timestamp>.json`` and prints one line per workload, slowest
ratio first.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CHILD = HERE / "compare_child.py"
DEFAULT_OUT = HERE / "results"


def build_inputs(folder: Path, quick: bool) -> list[dict]:
    """Write the inputs into `folder`; return the workloads (name, kind, file, options)."""
    import orjson
    import shapely

    from benchmarks import bench_curves, bench_svg, datasets

    n_segments = 100_000 if quick else 1_000_000
    n_approx = 10_000 if quick else 100_000
    workloads: list[dict] = []

    def segments(name: str, data: np.ndarray, window, methods, mode: str = "exact",
                 backend: str = "numba") -> None:
        path = folder / f"{name}.npy"
        if not path.exists():
            np.save(path, np.ascontiguousarray(data))
        for method in methods:
            workloads.append({"name": f"segments:{name}:{backend}:{method}:{mode}",
                              "kind": "segments", "file": path.name, "window": list(window),
                              "options": {"method": method, "mode": mode, "backend": backend}})

    every = ["rnsca", "cohen_sutherland", "liang_barsky", "nicholl_lee_nicholl", "midpoint"]
    uniform = datasets.uniform_segments(n_segments)
    segments(f"uniform-{n_segments}", uniform, datasets.UNIFORM_WINDOW, every)
    for shaped in datasets.shaped(n_segments):
        if shaped.family != "mostly_inside":
            segments(shaped.name, shaped.segments(), shaped.window, ["rnsca"])
    segments(f"uniform-{n_approx}", datasets.uniform_segments(n_approx),
             datasets.UNIFORM_WINDOW, ["rnsca", "midpoint"], mode="approx")
    segments(f"uniform-{n_segments}", uniform, datasets.UNIFORM_WINDOW, ["rnsca"],
             backend="opencl")

    def ragged(name: str, geometry_type, coords, offsets, window, **options) -> None:
        path = folder / f"{name}.npz"
        np.savez(path, coords=coords, **{f"offsets{k}": o for k, o in enumerate(offsets)})
        for backend in ("numba", "opencl"):
            workloads.append({"name": f"geometry:{name}:{backend}", "kind": "ragged",
                              "file": path.name, "geometry_type": int(geometry_type),
                              "window": list(window),
                              "options": {**options, "backend": backend}})

    n_lines = 2_000 if quick else 20_000
    raw_coords, raw_offsets = datasets.smooth_polylines(n_lines)
    lines = shapely.from_ragged_array(shapely.GeometryType.LINESTRING, raw_coords,
                                      (raw_offsets,))
    window = datasets.CURVE_WINDOWS[sorted(datasets.CURVE_WINDOWS)[0]]
    ragged(f"lines-{n_lines}", *shapely.to_ragged_array(lines), window)
    n_polygons = 10_000 if quick else 100_000
    raw = datasets.star_polygons(n_polygons)
    polygons = shapely.from_ragged_array(shapely.GeometryType.POLYGON, raw[0], raw[1:])
    ragged(f"polygons-{n_polygons}", *shapely.to_ragged_array(polygons),
           datasets.POLYGON_WINDOW)

    n_features = (20, 1_500) if quick else (136, 14_500)
    document = folder / "collection.geojson"
    document.write_bytes(orjson.dumps(datasets.geojson_collection(*n_features)))
    workloads.append({"name": f"geojson:{sum(n_features)}-features", "kind": "geojson",
                      "file": document.name, "window": list(datasets.POLYGON_WINDOW),
                      "options": {}})

    n_paths = 5_000 if quick else 50_000
    corpus = folder / "glyphs.json"
    corpus.write_bytes(orjson.dumps(bench_svg.glyph_corpus(n_paths)))
    svg_window = [200.0, 200.0, 800.0, 800.0]
    for kind in ("parse", "write", "clip_svg"):
        workloads.append({"name": f"svg:{kind}:{n_paths}-paths", "kind": kind,
                          "file": corpus.name, "window": svg_window, "options": {}})
    page, page_window = bench_curves.glyph_page(300 if quick else 3_000)
    long = bench_curves.long_curves(20 if quick else 200, 500)
    for name, paths, path_window in (("glyph_page", page, page_window),
                                     ("long_curves", long, bench_curves.WINDOWS["10%"])):
        path = folder / f"{name}.npz"
        np.savez(path, controls=paths.controls, degree=paths.degree,
                 subpath_offsets=paths.subpath_offsets, closed=paths.closed,
                 start=paths.start, path_offsets=paths.path_offsets)
        for options in ({}, {"fill": "nonzero"}, {"curves": "flatten"}):
            label = ",".join(f"{k}={v}" for k, v in options.items()) or "preserve"
            workloads.append({"name": f"curves:{name}:{label}", "kind": "paths",
                              "file": path.name, "window": list(path_window),
                              "options": options})
    return workloads


def run_round(checkout: Path, folder: Path, budget: float) -> dict[str, list[float]]:
    """Time every workload in a fresh process on `checkout`; return samples by name."""
    environment = dict(os.environ)
    environment["PYTHONPATH"] = str(checkout)
    # The same process settings for both, whichever of them sets them itself.
    environment.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    done = subprocess.run([sys.executable, str(CHILD), str(checkout), str(folder),
                           str(budget)], env=environment, capture_output=True, text=True,
                          check=False)
    if done.returncode != 0:
        raise SystemExit(f"{checkout}: the timing process failed:\n{done.stderr[-4000:]}")
    return json.loads(done.stdout.splitlines()[-1])


def _revision(checkout: Path) -> str:
    done = subprocess.run(["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True, check=False)
    dirty = subprocess.run(["git", "-C", str(checkout), "status", "--porcelain",
                            "--untracked-files=no"], capture_output=True, text=True,
                           check=False).stdout.strip()
    return done.stdout.strip() + ("+changes" if dirty else "")


def main(argv: list[str] | None = None) -> int:
    """Run the comparison; print and write the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", type=Path, required=True, help="the checkout before")
    parser.add_argument("--head", type=Path, default=HERE.parent, help="the checkout after")
    parser.add_argument("--rounds", type=int, default=3, help="processes per checkout")
    parser.add_argument("--budget", type=float, default=1.0,
                        help="seconds of samples per workload and round (at least 2)")
    parser.add_argument("--quick", action="store_true", help="small inputs (a smoke test)")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    started = time.monotonic()
    checkouts = {"base": args.base.resolve(), "head": args.head.resolve()}
    samples: dict[str, dict[str, list[float]]] = {"base": {}, "head": {}}
    with tempfile.TemporaryDirectory(prefix="rnsca-compare-") as scratch:
        folder = Path(scratch)
        workloads = build_inputs(folder, args.quick)
        (folder / "workloads.json").write_text(json.dumps(workloads))
        for number in range(args.rounds):
            # Alternate which goes first, so neither always runs on a cooler machine.
            order = ("base", "head") if number % 2 == 0 else ("head", "base")
            for side in order:
                print(f"round {number + 1}/{args.rounds}: {side}", file=sys.stderr, flush=True)
                for name, values in run_round(checkouts[side], folder, args.budget).items():
                    samples[side].setdefault(name, []).extend(values)
    rows = []
    for workload in workloads:
        name = workload["name"]
        base, head = samples["base"].get(name), samples["head"].get(name)
        row = {"workload": name, "base_seconds": min(base) if base else None,
               "head_seconds": min(head) if head else None}
        if base and head:
            row["ratio"] = row["head_seconds"] / row["base_seconds"]
        rows.append(row)
    result = {
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "base": {"path": str(checkouts["base"]), "revision": _revision(checkouts["base"])},
        "head": {"path": str(checkouts["head"]), "revision": _revision(checkouts["head"])},
        "rounds": args.rounds, "budget_seconds": args.budget, "quick": args.quick,
        "load_average_at_end": os.getloadavg(), "cpu_count": os.cpu_count(),
        "timing": "best (minimum) over every sample of every round; GC paused per sample",
        "elapsed_seconds": time.monotonic() - started, "workloads": rows,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    target = args.out / f"compare-{stamp}.json"
    target.write_text(json.dumps(result, indent=1))
    print(f"base {result['base']['revision']}  head {result['head']['revision']}  "
          f"load {result['load_average_at_end'][0]:.2f}  -> {target}")
    for row in sorted(rows, key=lambda r: -(r.get("ratio") or 0.0)):
        if "ratio" in row:
            print(f"{row['ratio']:6.3f}  {row['workload']:58s} "
                  f"{row['base_seconds'] * 1e3:10.2f} ms -> {row['head_seconds'] * 1e3:10.2f} ms")
        else:
            print(f"   n/a  {row['workload']:58s} (not run on both)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
