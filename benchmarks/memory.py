"""Peak memory of one clip request over its body's size: the ratios admission reserves by.

Usage::

    python -m benchmarks.memory                  # 1M vertices per body
    python -m benchmarks.memory --vertices 20000 # smaller (the smoke test)

For each kind of request (`KINDS`: GeoJSON lines and polygons, SVG paths, JSON and binary
segments; each with the service's default verification for that size and with
``verify: "all"``) a body is written to a file, then a fresh Python process that has
imported the service and compiled its kernels on a tiny input reads it and runs the
service's own conversion function on it (`service.convert`, as a request's thread does),
and reports the growth of its peak resident memory (``ru_maxrss``) over its size before
the call. The ratio peak growth / body size of each kind is what
`service.admission.PEAK_BYTES_PER_BODY_BYTE` must bound: the JSON says, per endpoint,
the highest ratio measured with default verification and whether the reservation
(`service.admission.estimate_bytes`) covers every growth measured.
Results go to ``memory-<UTC timestamp>.json``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import orjson

from benchmarks.machine import describe_machine, run_header

__all__ = ["KINDS", "make_body", "measure", "main"]

ROOT = Path(__file__).resolve().parent.parent
WINDOW = [0.0, 0.0, 10.0, 10.0]
#: kind: (endpoint, media type of the admission table)
KINDS = {"geojson_lines": ("geojson", "json"), "geojson_polygons": ("geojson", "json"),
         "svg": ("svg", "json"), "segments_json": ("segments", "json"),
         "segments_binary": ("segments", "binary"),
         "geoarrow_lines": ("geoarrow", "arrow"), "geoarrow_polygons": ("geoarrow", "arrow"),
         "geoarrow_wkb": ("geoarrow", "arrow")}


def make_body(kind: str, vertices: int, verify: bool | str | None) -> bytes:
    """Return a request body of `kind` with about `vertices` vertices, crossing the window.

    Lines wander (a random walk), so they cross the window edges now and then as real
    lines do; polygons are 50-vertex circles; paths are cubic Béziers. GeoArrow bodies are
    Arrow IPC streams of an id column and lines (interleaved coordinates), polygons
    (separated) or lines as WKB.
    """
    rng = np.random.default_rng(1)
    extra = {} if verify is None else {"verify": verify}
    if kind.startswith("geoarrow"):
        return _geoarrow_body(kind, vertices, rng)
    if kind in ("geojson_lines", "geojson_polygons"):
        features = []
        for _ in range(max(1, vertices // (100 if kind == "geojson_lines" else 50))):
            if kind == "geojson_lines":
                walk = rng.uniform(-5, 15, 2) + np.cumsum(rng.normal(0, 0.3, (100, 2)), 0)
                geometry = {"type": "LineString", "coordinates": walk.round(6).tolist()}
            else:
                t = np.linspace(0, 2 * np.pi, 50)
                c, r = rng.uniform(-5, 15, 2), rng.uniform(0.5, 3)
                ring = np.c_[c[0] + r * np.cos(t), c[1] + r * np.sin(t)].round(6)
                ring[-1] = ring[0]
                geometry = {"type": "Polygon", "coordinates": [ring.tolist()]}
            features.append({"type": "Feature", "properties": {"id": len(features)},
                             "geometry": geometry})
        return orjson.dumps({"window": WINDOW, "geojson": {
            "type": "FeatureCollection", "features": features}, **extra})
    if kind == "svg":
        paths = []
        for _ in range(max(1, vertices // 19)):
            p = (rng.uniform(-5, 15, 2) + np.cumsum(rng.normal(0, 0.5, (19, 2)), 0)).round(4)
            paths.append(f"M{p[0, 0]} {p[0, 1]}C" + " ".join(f"{x} {y}" for x, y in p[1:]))
        return orjson.dumps({"window": WINDOW, "paths": paths, **extra})
    segments = rng.uniform(-5, 15, (max(1, vertices // 2), 4))
    if kind == "segments_json":
        return orjson.dumps({"window": WINDOW, "segments": segments.round(6).tolist(),
                             **extra})
    return segments.tobytes()


def _geoarrow_body(kind: str, vertices: int, rng: np.random.Generator) -> bytes:
    import pyarrow as pa
    import shapely

    if kind == "geoarrow_polygons":
        count = max(1, vertices // 50)
        t = np.linspace(0, 2 * np.pi, 50)
        c, r = rng.uniform(-5, 15, (count, 1, 2)), rng.uniform(0.5, 3, (count, 1, 1))
        rings = c + r * np.stack([np.cos(t), np.sin(t)], -1)
        rings[:, -1] = rings[:, 0]
        xy = rings.reshape(-1, 2)
        vertex = pa.StructArray.from_arrays([pa.array(xy[:, 0]), pa.array(xy[:, 1])],
                                            names=["x", "y"])
        ring = pa.ListArray.from_arrays(pa.array(np.arange(count + 1, dtype=np.int32) * 50),
                                        vertex)
        column = pa.ListArray.from_arrays(pa.array(np.arange(count + 1, dtype=np.int32)), ring)
        extension = "geoarrow.polygon"
    else:
        count = max(1, vertices // 100)
        walks = rng.uniform(-5, 15, (count, 1, 2)) + np.cumsum(
            rng.normal(0, 0.3, (count, 100, 2)), 1)
        offsets = np.arange(count + 1, dtype=np.int32) * 100
        if kind == "geoarrow_wkb":
            lines = shapely.from_ragged_array(shapely.GeometryType.LINESTRING,
                                              walks.reshape(-1, 2), (offsets,))
            column, extension = pa.array(shapely.to_wkb(lines), pa.binary()), "geoarrow.wkb"
        else:
            vertex = pa.FixedSizeListArray.from_arrays(pa.array(walks.reshape(-1)), 2)
            column = pa.ListArray.from_arrays(pa.array(offsets), vertex)
            extension = "geoarrow.linestring"
    field = pa.field("geometry", column.type, metadata={"ARROW:extension:name": extension})
    table = pa.Table.from_arrays([pa.array(np.arange(count)), column], schema=pa.schema(
        [pa.field("id", pa.int64()), field]))
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as writer:
        writer.write_table(table)
    return sink.getvalue().to_pybytes()


_CHILD = r"""
import resource, sys, time
from rnsca.runtime import configure_process
configure_process()
from rnsca.window import Window
from service import convert
from service.config import Settings
from service.schemas import ClipOptions, GeometryOptions
kind, verify, path = sys.argv[1], sys.argv[2], sys.argv[3]
verify = {"none": None, "all": "all"}[verify]
settings = Settings(max_vertices=10**9, work_budget=10**13, max_body_bytes=2**40)
def call(body):
    if kind == "segments_binary":
        return convert.clip_segments_binary(body, Window(*%(window)r), ClipOptions(), verify,
                                            settings)
    if kind.startswith("geoarrow"):
        return convert.clip_geoarrow(body, Window(*%(window)r), GeometryOptions(), None,
                                     verify, settings)
    function = {"geojson_lines": convert.clip_geojson, "geojson_polygons": convert.clip_geojson,
                "svg": convert.clip_svg, "segments_json": convert.clip_segments_json}[kind]
    return function(body, settings)
call(open(path + ".tiny", "rb").read())  # compile or load the kernels first
body = open(path, "rb").read()
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
started = time.perf_counter()
outcome = call(body)
seconds = time.perf_counter() - started
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(peak - before, seconds, len(outcome.content))
"""


def measure(kind: str, vertices: int, verify: str, folder: Path) -> dict:
    """Return the peak memory growth of one request of `kind` (see the module docstring)."""
    asked = {"none": None, "all": "all"}[verify]
    path = folder / f"{kind}-{verify}"
    body = make_body(kind, vertices, asked)
    path.write_bytes(body)
    Path(str(path) + ".tiny").write_bytes(make_body(kind, 40, asked))
    out = subprocess.run([sys.executable, "-c", _CHILD % {"window": tuple(WINDOW)}, kind,
                          verify, str(path)], capture_output=True, text=True, cwd=ROOT,
                         check=True)
    growth, seconds, answer = out.stdout.split()
    return {"kind": kind, "verify": asked, "vertices": vertices, "body_bytes": len(body),
            "peak_growth_bytes": int(growth), "ratio": round(int(growth) / len(body), 2),
            "seconds": round(float(seconds), 3), "answer_bytes": int(answer)}


def main(argv: list[str] | None = None) -> int:
    """Measure every kind, print a table, write the JSON."""
    from service.admission import PEAK_BYTES_PER_BODY_BYTE, estimate_bytes

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vertices", type=int, default=1_000_000)
    parser.add_argument("--verify-all", action="store_true",
                        help='also measure verify: "all" (can take minutes and gigabytes)')
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    machine = describe_machine(ROOT)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for kind in KINDS:
            for verify in ("none", "all") if args.verify_all else ("none",):
                row = measure(kind, args.vertices, verify, Path(folder))
                rows.append(row)
                print(f"{kind:18} verify={verify:4} body {row['body_bytes'] / 1e6:7.1f} MB  "
                      f"peak +{row['peak_growth_bytes'] / 1e6:7.0f} MB  ratio {row['ratio']:5.1f}"
                      f"  {row['seconds']:.2f} s", flush=True)
    # Admission reserves BASE_BYTES plus the table's ratio times the body: does that
    # cover each growth measured with the default verification?
    covered = {}
    for (endpoint, media), ratio in PEAK_BYTES_PER_BODY_BYTE.items():
        mine = [r for r in rows if KINDS[r["kind"]] == (endpoint, media) and r["verify"] is None]
        covered[f"{endpoint}/{media}"] = {
            "table": ratio, "measured_max": max((r["ratio"] for r in mine), default=None),
            "covered": all(r["peak_growth_bytes"] <= estimate_bytes(endpoint, media,
                                                                    r["body_bytes"])
                           for r in mine)}
    result = {**run_header(1, stamp, args.vertices < 1_000_000, machine, ROOT),
              "rows": rows, "admission_table": covered}
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"memory-{stamp}.json"
    path.write_text(json.dumps(result, indent=2))
    print(f"wrote {path}")
    return 0 if all(c["covered"] for c in covered.values()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
