"""Vector tiles on Dask (`rnsca.dask.tiles`): 1 and 2 workers against one process.

The workloads of `benchmarks.bench_tiles` (``lines``: 200 smooth polylines, 693k
vertices, zooms 0-10; ``polygons``: star polygons with holes, zooms 0-8), already read
into a `rnsca.tiles.FeatureTable`, tiled and written as PMTiles (gzip):

- ``direct``: `rnsca.tiles.tile_table` into `write_pmtiles`, in this process, Numba's
  kernels on every core (what ``rnsca tiles`` runs);
- ``dask-1``, ``dask-2``: `rnsca.dask.tiles` on a LocalCluster of 1 or 2 worker processes
  (`rnsca.batch.local_cluster`: one task thread each, the cores shared among their
  kernels), the cluster started and warmed up (kernels compiled, a small pyramid built)
  before the timing.

Every archive is checked equal, byte for byte, to the direct one. Results:
``benchmarks/results/dask_tiles-<UTC timestamp>.json``.

    .venv/bin/python -m benchmarks.dask_tiles [--polygons 20000] [--quick]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _table(name: str, quick: bool, polygons: int) -> tuple:
    import shapely

    from benchmarks import bench_tiles
    from rnsca.tiles import FeatureTable

    if name == "lines":
        geometries, maxzoom = bench_tiles._lines(quick), 10
    else:
        geometries, maxzoom = bench_tiles._polygons(True), 8
        geometries = geometries[:polygons]
    properties = [{"name": f"f{i}", "rank": i % 7} for i in range(len(geometries))]
    table = FeatureTable.of(geometries, properties, list(range(len(geometries))))
    return table, maxzoom, int(shapely.get_num_coordinates(geometries).sum())


def _direct(table, maxzoom: int, path: Path) -> float:
    from rnsca.tiles import tile_table, write_pmtiles

    started = time.perf_counter()
    write_pmtiles(path, tile_table(table, maxzoom=maxzoom, layer="features"),
                  layer="features")
    return time.perf_counter() - started


def _on_dask(workers: int, runs: list, folder: Path) -> dict:
    import distributed

    import rnsca.batch
    import rnsca.dask

    started = time.perf_counter()
    cluster = rnsca.batch.local_cluster(workers, dashboard_address=":0")
    client = distributed.Client(cluster, timeout=120)
    out: dict = {"cluster_start_s": 0.0}
    try:
        client.wait_for_workers(workers, timeout=120)
        out["cluster_start_s"] = round(time.perf_counter() - started, 3)
        threads = rnsca.batch.threads_per_task(workers)
        warm, _, _, _ = runs[0]
        rnsca.dask.tiles(warm, folder / "warm.pmtiles", client=client, maxzoom=3,
                         threads=threads)
        for table, maxzoom, name, expected in runs:
            path = folder / f"{name}-dask-{workers}.pmtiles"
            marks: list = []
            started = time.perf_counter()
            rnsca.dask.tiles(table, path, client=client, maxzoom=maxzoom, threads=threads,
                             layer="features",
                             on_part=lambda k, n, marks=marks: marks.append(time.perf_counter()))
            done = time.perf_counter()
            out[name] = {"seconds": round(done - started, 3),
                         # Until the last task ended (the split here, then the tasks), and
                         # after it (the merge and the archive's write, here).
                         "tasks_s": round(marks[-1] - started, 3),
                         "merge_write_s": round(done - marks[-1], 3), "tasks": len(marks),
                         "same_bytes": path.read_bytes() == expected.read_bytes()}
    finally:
        cluster.close(timeout=60)
        client.close(timeout=60)
    return out


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="40 polylines")
    parser.add_argument("--polygons", type=int, default=10_000,
                        help="star polygons (of bench_tiles' quick set, 10,000 at most)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    from benchmarks.machine import describe_machine

    result: dict = {"machine": describe_machine(ROOT), "workloads": {}, "runs": {}}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        runs = []
        for name in ("lines", "polygons"):
            table, maxzoom, vertices = _table(name, args.quick, args.polygons)
            path = folder / f"{name}-direct.pmtiles"
            _direct(table, 2, folder / "warm.pmtiles")  # kernels compiled
            seconds = _direct(table, maxzoom, path)
            from rnsca.tiles import tile_table, write_pmtiles

            started = time.perf_counter()
            zooms = list(tile_table(table, maxzoom=maxzoom, layer="features"))
            tiled = time.perf_counter() - started
            write_pmtiles(folder / "again.pmtiles", zooms, layer="features")
            result["runs"].setdefault("direct-parts", {})[name] = {
                "tile_s": round(tiled, 3),
                "gzip_write_s": round(time.perf_counter() - started - tiled, 3),
                "tiles": sum(len(z) for z in zooms)}
            result["workloads"][name] = {"features": table.count, "vertices": vertices,
                                         "maxzoom": maxzoom, "bytes": path.stat().st_size}
            result["runs"].setdefault("direct", {})[name] = {"seconds": round(seconds, 3)}
            runs.append((table, maxzoom, name, path))
            print(name, "direct", round(seconds, 3), file=sys.stderr)
        for workers in (1, 2):
            result["runs"][f"dask-{workers}"] = _on_dask(workers, runs, folder)
            print(workers, result["runs"][f"dask-{workers}"], file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    (args.out / f"dask_tiles-{stamp}.json").write_text(json.dumps(result, indent=1))
    print(json.dumps(result["runs"], indent=1))
    return result


if __name__ == "__main__":
    main()
