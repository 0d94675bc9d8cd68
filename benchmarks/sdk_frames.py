"""The SDK's collections over HTTP: GeoArrow against GeoJSON, and clip_many's batching.

Usage::

    python -m benchmarks.sdk_frames                       # starts `rnsca serve` on a free port
    python -m benchmarks.sdk_frames --url http://127.0.0.1:8000 --polygons 10000 --rounds 5

Builds a seeded ``GeoDataFrame`` of star polygons with one hole each (41 + 11 vertices,
`benchmarks.datasets.star_polygons`), two property columns and string index labels, in a
window that covers half the extent, and times, client and server together on loopback:

``clip via=geoarrow`` / ``clip via=geojson``
    ``Client.clip(frame, window, via=..., verify=False)``: one request, the frame back.
``clip_many batch_size=B concurrency=C``
    The same frame in batches of B rows, C requests at once (GeoArrow).
``raw geoarrow request, answer gzip`` / ``identity``
    The GeoArrow request alone, its answer gzip-compressed by the server or not (the
    SDK asks for ``identity``: compressing float64 coordinates costs more than it saves).

Each case runs once to warm up, then `--rounds` times, the cases in turn in each round;
the best and the median are printed and written (with the machine's description) to
``benchmarks/results/sdk-<UTC timestamp>.json``. Both ways give the same frame (checked
each round). The default of ``Client.clip`` (``DEFAULT_VIA``) is the faster of the two.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.datasets import centred_window, star_polygons
from benchmarks.load import _free_port, _start_server, _wait_ready, stop_server
from benchmarks.machine import describe_machine

ROOT = Path(__file__).resolve().parent.parent


def polygon_frame(n: int):
    """Return a GeoDataFrame of `n` polygons with holes, properties and string labels."""
    import geopandas
    import shapely

    coords, rings, geoms = star_polygons(n)
    polygons = shapely.from_ragged_array(shapely.GeometryType.POLYGON, coords, (rings, geoms))
    return geopandas.GeoDataFrame(
        {"name": [f"p{i}" for i in range(n)], "value": np.arange(n, dtype=np.float64)},
        geometry=polygons, index=[f"id-{i}" for i in range(n)], crs="EPSG:3857")


def _time(runs: dict, rounds: int) -> dict:
    """Return the best and median seconds of each run, the runs interleaved.

    Each round runs every case in turn, so a change of the machine's load falls on every
    case alike.
    """
    for run in runs.values():
        run()  # warm-up: connections, imports
    seconds: dict = {name: [] for name in runs}
    for _ in range(rounds):
        for name, run in runs.items():
            started = time.perf_counter()
            run()
            seconds[name].append(time.perf_counter() - started)
    return {name: {"best_s": min(s), "median_s": statistics.median(s), "rounds": rounds}
            for name, s in seconds.items()}


def _raw_request(client, frame, window, encoding: str):
    """Return a run that posts the frame's GeoArrow stream, the answer in `encoding`.

    What the SDK sends, with the server's gzip asked for or not (the SDK asks for
    ``identity``: see `rnsca_client.calls`); the time to read the answer, not decode it.
    """
    from rnsca_client import calls
    from rnsca_client.geoarrow import geometry_table

    geometries = frame.geometry.to_numpy()
    call = calls.clip_geoarrow(geometry_table(geometries, np.arange(len(geometries))),
                               window, column="geometry", verify=False, options={})
    headers = {**call.headers, "Accept-Encoding": encoding}

    def run() -> None:
        answer = client._http.post(call.path, content=call.content, params=call.params,
                                   headers=headers)
        assert answer.status_code == 200 and answer.content
    return run


def measure(url: str, n: int, rounds: int, batch_sizes: list[int],
            concurrencies: list[int]) -> dict:
    """Return the timings of every case against the server at `url`."""
    import shapely

    from rnsca_client import Client

    frame = polygon_frame(n)
    window = centred_window(0.5)
    runs = {}
    with Client(url, timeout=600) as client:
        reference = client.clip(frame, window, via="geojson", verify=False).data

        def check(out) -> None:
            assert out.index.equals(reference.index)
            assert shapely.equals_exact(out.geometry.values, reference.geometry.values,
                                        tolerance=1e-9).all()

        for via in ("geoarrow", "geojson"):
            check(client.clip(frame, window, via=via, verify=False).data)
            runs[f"clip via={via}"] = \
                lambda via=via: client.clip(frame, window, via=via, verify=False)
        for size in batch_sizes:
            for concurrency in concurrencies:
                check(client.clip_many(frame, window, batch_size=size,
                                       concurrency=concurrency, verify=False).data)
                runs[f"clip_many batch_size={size} concurrency={concurrency}"] = \
                    lambda size=size, concurrency=concurrency: client.clip_many(
                        frame, window, batch_size=size, concurrency=concurrency,
                        verify=False)
        runs["raw geoarrow request, answer gzip"] = _raw_request(client, frame, window, "gzip")
        runs["raw geoarrow request, answer identity"] = _raw_request(client, frame, window,
                                                                     "identity")
        cases = _time(runs, rounds)
    return {"polygons": n, "vertices": int(shapely.get_num_coordinates(
        frame.geometry.values).sum()), "window": list(window), "kept": len(reference),
        "cases": cases}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--url", help="a running server (default: start one)")
    parser.add_argument("--polygons", type=int, default=10_000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--batch-sizes", default="2500,10000")
    parser.add_argument("--concurrency", default="1,2,4")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    process = None
    url = args.url
    if url is None:
        port = _free_port()
        url = f"http://127.0.0.1:{port}"
        log = Path(tempfile.gettempdir()) / f"rnsca-sdk-bench-{port}.log"
        process = _start_server(1, port, log, "warning")
        _wait_ready(url, process, in_a_row=1)
    try:
        result = measure(url, args.polygons, args.rounds,
                         [int(s) for s in args.batch_sizes.split(",")],
                         [int(c) for c in args.concurrency.split(",")])
    finally:
        if process is not None:
            stop_server(process)
    result["machine"] = describe_machine(ROOT)
    print(f"{result['polygons']} polygons, {result['vertices']} vertices, "
          f"{result['kept']} kept")
    for name, timing in result["cases"].items():
        print(f"  {name:45s} best {timing['best_s'] * 1e3:8.1f} ms   "
              f"median {timing['median_s'] * 1e3:8.1f} ms")
    args.out.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    (args.out / f"sdk-{stamp}.json").write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
