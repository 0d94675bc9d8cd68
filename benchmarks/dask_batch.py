"""rnsca batch on Dask: throughput with 1 and 2 workers, and the overhead over the direct call.

Generates a seeded GeoParquet dataset of lines (random walks) and polygons (random
n-gons), half each, as files of row groups, and clips it to a window covering about a
quarter of its extent:

- ``direct``: the partitions clipped one after the other in this process by
  `rnsca.batch.run_partition` (the library call a job makes per partition, with no Dask:
  read, `rnsca.dask.clip_frame`, write), Numba's kernels on every core;
- ``dask-1``, ``dask-2``: the same job by `rnsca.batch.run` on a LocalCluster of 1 or 2
  worker processes (one task thread each; the cores divided among their kernels).

Every contender writes the same files; each gets a warm-up (kernels loaded, a small
partition clipped) before it is timed, and the cluster's start is measured apart. The
ratio ``dask-2 / direct`` is the Dask job's overhead on the same cores. Per-partition
costs (read, clip, write) are reported from the tasks' own reports, and each worker's
peak memory, for the design note in benchmarks/README.md. Results:
``benchmarks/results/dask_batch-<UTC timestamp>.json``.

    .venv/bin/python -m benchmarks.dask_batch --features 2000000
    .venv/bin/python -m benchmarks.dask_batch --quick      # 40,000 features, a smoke run
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXTENT = 1_000.0
WINDOW = (250.0, 250.0, 750.0, 750.0)


def generate(folder: Path, features: int, per_file: int, row_group: int, seed: int) -> dict:
    """Write the dataset (unless it is there already); return its description."""
    import geopandas
    import shapely

    folder.mkdir(parents=True, exist_ok=True)
    files = (features + per_file - 1) // per_file
    stamp = folder / f"_dataset-{features}-{per_file}-{row_group}-{seed}.json"
    if stamp.exists():
        return json.loads(stamp.read_text())
    for old in folder.glob("*.parquet"):
        old.unlink()
    rng = np.random.default_rng(seed)
    vertices = 0
    for number in range(files):
        count = min(per_file, features - number * per_file)
        half = count // 2
        start = rng.uniform(0, EXTENT, (count, 2))
        # Lines: random walks of 16 vertices, steps of about 4 units.
        walks = start[:half, None, :] + rng.normal(0, 4, (half, 16, 2)).cumsum(axis=1)
        lines = shapely.linestrings(walks)
        # Polygons: 12-gons of radius 2-20 (some across the window's edges).
        sides = 12
        angles = np.linspace(0, 2 * np.pi, sides + 1)
        radius = rng.uniform(2, 20, (count - half, 1))
        ring = np.stack([start[half:, :1] + radius * np.cos(angles),
                         start[half:, 1:] + radius * np.sin(angles)], axis=-1)
        polygons = shapely.polygons(ring)
        geometry = np.empty(count, dtype=object)
        geometry[0::2] = lines[: len(geometry[0::2])]
        geometry[1::2] = polygons[: len(geometry[1::2])]
        vertices += half * 16 + (count - half) * (sides + 1)
        ids = np.arange(number * per_file, number * per_file + count)
        frame = geopandas.GeoDataFrame(
            {"id": ids, "class": rng.integers(0, 8, count),
             "name": np.char.add("f", ids.astype(str)).astype(object)},
            geometry=geometry, crs="EPSG:3857")
        frame.to_parquet(folder / f"part-{number:04d}.parquet", row_group_size=row_group)
    description = {"features": features, "files": files, "row_group": row_group,
                   "vertices": vertices, "bytes": sum(p.stat().st_size
                                                      for p in folder.glob("*.parquet"))}
    stamp.write_text(json.dumps(description))
    return description


def _fresh(folder: Path) -> None:
    shutil.rmtree(folder, ignore_errors=True)


def _warm_up() -> None:
    """Load the kernels and clip a few geometries (run in each process timed)."""
    import geopandas
    import shapely

    from rnsca.dask import clip_frame

    frame = geopandas.GeoDataFrame(geometry=[shapely.box(0, 0, 600, 600),
                                             shapely.LineString([(0, 0), (900, 900)])])
    clip_frame(frame, WINDOW)


def _peak_rss() -> int:
    """Return this process's peak resident memory in bytes (Linux: ru_maxrss in KiB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def time_direct(job, partitions) -> dict:
    import rnsca.batch

    _warm_up()
    _fresh(Path(job.output))
    rnsca.batch.pending(job, partitions)
    started = time.perf_counter()
    reports = [rnsca.batch.run_partition(p, job) for p in partitions]
    return {"seconds": time.perf_counter() - started, "reports": reports}


def time_dask(job, partitions, workers: int) -> dict:
    import distributed

    import rnsca.batch

    started = time.perf_counter()
    cluster = rnsca.batch.local_cluster(workers, dashboard_address=":0")
    client = distributed.Client(cluster)
    client.wait_for_workers(workers, timeout=300)
    start_s = time.perf_counter() - started
    try:
        client.run(_warm_up)
        _fresh(Path(job.output))
        job = dataclasses.replace(job, threads=rnsca.batch.threads_per_task(workers))
        report = rnsca.batch.run(job, partitions, client)
        if report.failed:
            raise RuntimeError(report.failed)
        peaks = client.run(_peak_rss)
        return {"seconds": report.seconds, "cluster_start_s": start_s,
                "worker_peak_rss_bytes": max(peaks.values()), "reports": report.written}
    finally:
        cluster.close()
        client.close()


def _summary(result: dict, features: int, vertices: int) -> dict:
    reports = result.pop("reports")
    result["features_per_s"] = features / result["seconds"]
    result["vertices_per_s"] = vertices / result["seconds"]
    result["partitions"] = len(reports)
    result["rows_out"] = sum(r.rows_out for r in reports)
    for name in ("seconds", "read_s", "clip_s", "write_s"):
        values = [getattr(r, name) for r in reports]
        result[f"partition_{name}_median"] = statistics.median(values)
    result["partition_rows_median"] = statistics.median(r.rows_in for r in reports)
    result["partition_features_per_s_median"] = statistics.median(
        r.rows_in / r.seconds for r in reports)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--features", type=int, default=2_000_000)
    parser.add_argument("--per-file", type=int, default=500_000,
                        help="features per input file")
    parser.add_argument("--row-group", type=int, default=100_000,
                        help="rows per row group, and per partition")
    parser.add_argument("--data", type=Path, default=Path(tempfile.gettempdir())
                        / "rnsca-dask-bench", help="where the dataset is generated (kept)")
    parser.add_argument("--encoding", default="wkb")
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    if args.quick:
        args.features, args.per_file, args.row_group = 40_000, 20_000, 5_000

    import rnsca.batch
    import rnsca.runtime
    from benchmarks.machine import describe_machine

    rnsca.runtime.configure_process()
    source = args.data / "in"
    dataset = generate(source, args.features, args.per_file, args.row_group, seed=20_261_126)
    partitions = rnsca.batch.plan(rnsca.batch.find_inputs(str(source)),
                                  rows_per_partition=args.row_group)
    job = rnsca.batch.Job(output=str(args.data / "out"), window=WINDOW,
                          encoding=rnsca.batch.Encoding(args.encoding))
    print(f"{dataset['features']:,} features ({dataset['vertices']:,} vertices, "
          f"{dataset['bytes'] / 2**20:.0f} MiB) in {len(partitions)} partitions", flush=True)
    results: dict[str, dict] = {}
    results["direct"] = _summary(time_direct(job, partitions), dataset["features"],
                                 dataset["vertices"])
    print(f"  direct   {results['direct']['seconds']:7.2f} s", flush=True)
    for workers in (int(w) for w in args.workers.split(",")):
        name = f"dask-{workers}"
        results[name] = _summary(time_dask(job, partitions, workers), dataset["features"],
                                 dataset["vertices"])
        print(f"  {name:8s} {results[name]['seconds']:7.2f} s  (cluster start "
              f"{results[name]['cluster_start_s']:.1f} s)", flush=True)
    direct = results["direct"]["seconds"]
    ratios = {name: r["seconds"] / direct for name, r in results.items() if name != "direct"}
    for name, ratio in ratios.items():
        print(f"  {name} / direct = {ratio:.2f}")
    out = {"schema": 1, "created": time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()),
           "dataset": dataset, "window": WINDOW, "encoding": args.encoding,
           "cores": os.cpu_count(), "results": results, "ratio_over_direct": ratios,
           "machine": describe_machine(ROOT)}
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"dask_batch-{out['created']}.json"
    path.write_text(json.dumps(out, indent=2))
    print(f"  -> {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
