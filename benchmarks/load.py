"""Service throughput on loopback: `wrk` against ``rnsca serve --workers 2``.

Usage::

    python -m benchmarks.load                   # 10 s per case, 32 connections
    python -m benchmarks.load --quick           # 1 s per case, 4 connections (smoke test)
    python -m benchmarks.run --suite load       # the same, as a suite of make bench

Starts ``rnsca serve`` on a free port of 127.0.0.1 (its kernels load from the cache; the
first call waits for ``/readyz``), then runs ``wrk --latency`` (Debian's ``wrk`` package)
once per case, each request a fixed POST body set by a Lua script:

``healthz``
    ``GET /healthz``: the server's own ceiling (no clipping, no body).
``geojson_verified`` and ``geojson``
    A one-Feature GeoJSON LineString of 100 vertices crossing the window, with the
    default verification (Shapely's intersection compared), and with ``verify: false``.
``svg``
    Five short SVG paths (lines and cubics) crossing the window, not verified.
``segments_binary``
    100 segments as little-endian float64, window and options in the query.
``healthz_while_busy``
    Not wrk: `/healthz` probed one request after another while 50 GeoJSON requests of
    5.7 MB (200,000 vertices, verified by default) run at once: its p50, p99 and max.

It records requests per second, the latency percentiles wrk reports (50, 75, 90, 99) and
the errors (non-2xx answers, socket errors) in ``load-<UTC timestamp>.json``; the issue's
targets (3,000 requests/s without verification, 1,500 with, p99 under 20 ms at 32
connections) are evaluated there.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

from benchmarks.machine import describe_machine, load_average

__all__ = ["CASES", "run_load", "parse_wrk", "stop_server", "main"]

ROOT = Path(__file__).resolve().parent.parent
WINDOW = [0.0, 0.0, 10.0, 10.0]


def _line(vertices: int = 100) -> dict:
    x = np.linspace(-5.0, 15.0, vertices)
    y = 5.0 + 4.0 * np.sin(np.linspace(0.0, 6.0, vertices))
    return {"type": "Feature", "properties": {"name": "road"},
            "geometry": {"type": "LineString", "coordinates": np.column_stack([x, y]).tolist()}}


def _segments(count: int = 100) -> bytes:
    a = np.random.default_rng(3).uniform(-5.0, 15.0, (count, 4))
    return a.astype("<f8").tobytes()


#: name -> (method, path, content type, body)
CASES: dict[str, tuple[str, str, str | None, bytes]] = {
    "healthz": ("GET", "/healthz", None, b""),
    "geojson_verified": ("POST", "/v1/clip/geojson", "application/json", json.dumps(
        {"window": WINDOW, "geojson": _line()}).encode()),
    "geojson": ("POST", "/v1/clip/geojson", "application/json", json.dumps(
        {"window": WINDOW, "geojson": _line(), "verify": False}).encode()),
    "svg": ("POST", "/v1/clip/svg", "application/json", json.dumps(
        {"window": WINDOW, "verify": False,
         "paths": ["M-5 5 L15 5", "M5 -5 C0 5 10 5 5 15", "M-1 -1 L11 11 L-1 11 Z",
                   "M2 2 Q5 20 8 2", "M-5 8 C0 0 10 0 15 8"]}).encode()),
    "segments_binary": ("POST", "/v1/clip/segments?xmin=0&ymin=0&xmax=10&ymax=10&verify=false",
                        "application/octet-stream", _segments()),
}


def _lua(method: str, content_type: str | None, body_path: Path | None) -> str:
    lines = [f'wrk.method = "{method}"']
    if content_type:
        lines.append(f'wrk.headers["Content-Type"] = "{content_type}"')
    if body_path is not None:
        lines += [f'local f = assert(io.open("{body_path}", "rb"))', "wrk.body = f:read('*a')",
                  "f:close()"]
    return "\n".join(lines) + "\n"


_UNITS = {"us": 1e-6, "ms": 1e-3, "s": 1.0, "m": 60.0}


def _seconds(text: str) -> float:
    number, unit = re.fullmatch(r"([\d.]+)(us|ms|s|m)", text.strip()).groups()  # type: ignore[union-attr]
    return float(number) * _UNITS[unit]


def parse_wrk(output: str) -> dict:
    """Return requests/s, latency percentiles (seconds) and error counts from wrk's output.

    Examples
    --------
    >>> text = '''Latency Distribution
    ...      50%    1.20ms
    ...      99%   15.00ms
    ...   12345 requests in 10.00s, 1.00MB read
    ...   Non-2xx or 3xx responses: 7
    ... Requests/sec:   1234.50'''
    >>> r = parse_wrk(text)
    >>> r["requests_per_s"], r["latency_s"]["p99"], r["requests"], r["non_2xx"]
    (1234.5, 0.015, 12345, 7)
    """
    percentiles = {f"p{p}": _seconds(v) for p, v in
                   re.findall(r"^\s+(50|75|90|99)%\s+(\S+)$", output, re.MULTILINE)}
    rate = re.search(r"Requests/sec:\s+([\d.]+)", output)
    requests = re.search(r"(\d+) requests in", output)
    non_2xx = re.search(r"Non-2xx or 3xx responses: (\d+)", output)
    socket_errors = re.search(r"Socket errors: connect (\d+), read (\d+), write (\d+), "
                              r"timeout (\d+)", output)
    return {"requests_per_s": float(rate.group(1)) if rate else 0.0,
            "latency_s": percentiles,
            "requests": int(requests.group(1)) if requests else 0,
            "non_2xx": int(non_2xx.group(1)) if non_2xx else 0,
            "socket_errors": sum(map(int, socket_errors.groups())) if socket_errors else 0}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _start_server(workers: int, port: int, log_path: Path, log_level: str) -> subprocess.Popen:
    env = {k: v for k, v in os.environ.items() if not k.startswith("RNSCA_")}
    env.update({"RNSCA_LOG_LEVEL": log_level})  # info: one JSON line per request
    rnsca = Path(sys.executable).parent / "rnsca"
    command = [str(rnsca)] if rnsca.exists() else [sys.executable, "-m", "rnsca.cli"]
    return subprocess.Popen(command + ["serve", "--host", "127.0.0.1", "--port", str(port),
                                       "--workers", str(workers)],
                            cwd=ROOT, env=env, stdout=log_path.open("wb"),
                            stderr=subprocess.STDOUT)


def _wait_ready(url: str, process: subprocess.Popen, timeout: float = 900.0,
                in_a_row: int = 20) -> None:
    """Return once `in_a_row` ``/readyz`` probes, each on a new connection, answer 200.

    One 200 comes from whichever worker accepted that connection: another may still be
    loading its kernels and answer 503 ``not-ready``. Each new connection goes to a worker
    the kernel picks, so 20 in a row make it very likely that every worker is ready.
    """
    deadline = time.monotonic() + timeout
    ready = 0
    while ready < in_a_row:
        if time.monotonic() > deadline:
            raise RuntimeError(f"rnsca serve not ready within {timeout} s")
        if process.poll() is not None:
            raise RuntimeError(f"rnsca serve exited with {process.returncode}")
        try:
            ok = httpx.get(url + "/readyz", timeout=10).status_code == 200
        except httpx.TransportError:
            ok = False
        ready = ready + 1 if ok else 0
        if not ok:
            time.sleep(0.2)


def health_while_busy(url: str, busy: int, vertices: int) -> dict:
    """Return `/healthz` latencies (s) while `busy` large GeoJSON requests run at once.

    Each busy request is a FeatureCollection of one LineString per 100 vertices, about
    28 bytes a vertex (200,000 vertices: 5.7 MB), verification on by default; one refused
    with 503 (the memory budget full) is sent again after its ``Retry-After`` until it is
    clipped. Probes are sent one after another on a connection of their own until all
    have answered.
    """
    import threading
    from concurrent.futures import ThreadPoolExecutor

    features = [_line(100) for _ in range(max(1, vertices // 100))]
    body = json.dumps({"window": WINDOW, "geojson": {"type": "FeatureCollection",
                                                     "features": features}}).encode()
    done = threading.Event()
    statuses: list[int] = []

    refused: list[int] = []

    def big() -> None:
        # As a client should (the SDK does): a 503 is sent again after its Retry-After,
        # so the load lasts until every request is clipped, admission notwithstanding.
        with httpx.Client(timeout=600) as client:
            while True:
                r = client.post(url + "/v1/clip/geojson", content=body,
                                headers={"Content-Type": "application/json"})
                if r.status_code != 503:
                    statuses.append(r.status_code)
                    return
                refused.append(1)
                time.sleep(float(r.headers.get("Retry-After", "1")))

    latencies = []
    with ThreadPoolExecutor(busy) as pool:
        futures = [pool.submit(big) for _ in range(busy)]
        threading.Thread(target=lambda: ([f.result() for f in futures], done.set()),
                         daemon=True).start()
        with httpx.Client(timeout=60) as probe:
            while not done.is_set():
                started = time.perf_counter()
                probe.get(url + "/healthz")
                latencies.append(time.perf_counter() - started)
                time.sleep(0.01)
    ordered = sorted(latencies)

    def at(q: float) -> float:
        return ordered[min(len(ordered) - 1, int(q * len(ordered)))] if ordered else 0.0

    return {"busy_requests": busy, "busy_bytes": len(body), "probes": len(ordered),
            "latency_s": {"p50": at(0.5), "p99": at(0.99), "max": ordered[-1] if ordered else 0.0},
            "busy_statuses": {str(code): statuses.count(code) for code in set(statuses)},
            "busy_503_retried": len(refused)}


def run_load(seconds: int, connections: int, threads: int, workers: int = 2,
             cases: list[str] | None = None, log_level: str = "info",
             busy: tuple[int, int] | None = None, log=print) -> dict:
    """Start the server, run wrk on every case; return the figures per case.

    `busy` ``(requests, vertices)`` adds ``healthz_while_busy`` (`health_while_busy`).
    """
    wrk = shutil.which("wrk")
    if wrk is None:
        raise RuntimeError("wrk is not installed (Debian: apt-get install wrk)")
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    results = {}
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        process = _start_server(workers, port, folder / "server.log", log_level)
        try:
            _wait_ready(url, process)
            for name in cases or list(CASES):
                method, path, content_type, body = CASES[name]
                body_path = None
                if body:
                    body_path = folder / f"{name}.body"
                    body_path.write_bytes(body)
                script = folder / f"{name}.lua"
                script.write_text(_lua(method, content_type, body_path))
                check = httpx.request(method, url + path, content=body or None,
                                      headers={"Content-Type": content_type}
                                      if content_type else None, timeout=30)
                if check.status_code != 200:
                    raise RuntimeError(f"{name}: {check.status_code} {check.text[:300]}")
                done = subprocess.run(
                    [wrk, "--latency", "-t", str(threads), "-c", str(connections),
                     "-d", f"{seconds}s", "-s", str(script), url + path],
                    capture_output=True, text=True, check=True, timeout=seconds + 60)
                figures = parse_wrk(done.stdout)
                figures["bytes_sent"] = len(body)
                results[name] = figures
                log(f"  {name:18s} {figures['requests_per_s']:9.0f} req/s   p50 "
                    f"{figures['latency_s'].get('p50', 0) * 1e3:7.2f} ms   p99 "
                    f"{figures['latency_s'].get('p99', 0) * 1e3:7.2f} ms   non-2xx "
                    f"{figures['non_2xx']}")
            if busy is not None:
                figures = health_while_busy(url, *busy)
                results["healthz_while_busy"] = figures
                log(f"  healthz while {busy[0]} requests of {figures['busy_bytes'] / 1e6:.1f} MB "
                    f"run: p50 {figures['latency_s']['p50'] * 1e3:.1f} ms, p99 "
                    f"{figures['latency_s']['p99'] * 1e3:.1f} ms, max "
                    f"{figures['latency_s']['max'] * 1e3:.1f} ms ({figures['probes']} probes); "
                    f"busy answers {figures['busy_statuses']}")
        finally:
            stop_server(process)
    return results


def stop_server(process: subprocess.Popen) -> None:
    """Stop ``rnsca serve`` as SIGTERM asks (requests in flight finish); kill it past 30 s."""
    process.terminate()
    try:
        process.wait(30)
    except subprocess.TimeoutExpired:
        process.kill()


def evaluate_load_targets(results: dict, connections: int) -> list[dict]:
    """Return issue 16's throughput targets, each with its value and verdict."""
    def target(key, case, value, limit, op):
        met = None if value is None else (value >= limit if op == ">=" else value <= limit)
        return {"key": key, "case": case, "value": value, "limit": limit, "op": op,
                "met": met, "connections": connections}

    def rate(case):
        return results.get(case, {}).get("requests_per_s")

    def p99(case):
        return results.get(case, {}).get("latency_s", {}).get("p99")

    return [target("rate_unverified", "geojson", rate("geojson"), 3000.0, ">="),
            target("rate_verified", "geojson_verified", rate("geojson_verified"), 1500.0, ">="),
            target("p99_unverified", "geojson", p99("geojson"), 0.020, "<="),
            target("p99_verified", "geojson_verified", p99("geojson_verified"), 0.020, "<=")]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1 s per case, 4 connections")
    parser.add_argument("--seconds", type=int, default=None)
    parser.add_argument("--connections", type=int, default=None)
    parser.add_argument("--threads", type=int, default=2, help="wrk threads")
    parser.add_argument("--workers", type=int, default=2, help="uvicorn worker processes")
    parser.add_argument("--busy", type=int, default=None,
                        help="large requests at once for healthz_while_busy (default 50; "
                             "quick: 4)")
    parser.add_argument("--busy-vertices", type=int, default=None,
                        help="vertices per large request (default 200,000, about 5.7 MB; "
                             "quick: 5,000)")
    parser.add_argument("--log-level", default="info",
                        help="the server's RNSCA_LOG_LEVEL (info, as deployed: a line per "
                             "request)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    seconds = args.seconds or (1 if args.quick else 10)
    connections = args.connections or (4 if args.quick else 32)
    print(f"load: wrk, {connections} connections, {seconds} s per case, rnsca serve "
          f"--workers {args.workers}, log level {args.log_level}", flush=True)
    busy = (args.busy or (4 if args.quick else 50),
            args.busy_vertices or (5_000 if args.quick else 200_000))
    results = run_load(seconds, connections, args.threads, args.workers,
                       log_level=args.log_level, busy=busy)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"load-{stamp}.json"
    path.write_text(json.dumps({
        "created": stamp, "quick": args.quick, "machine": describe_machine(ROOT),
        "seconds": seconds, "connections": connections, "wrk_threads": args.threads,
        "workers": args.workers, "log_level": args.log_level, "cases": results,
        "targets": evaluate_load_targets(results, connections),
        "load_average_at_end": load_average()}, indent=2))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
