"""Cold start: from ``rnsca serve`` to each endpoint's first answered clip, no kernel cache.

Usage::

    python -m benchmarks.coldstart               # one worker, as `make serve` runs it
    python -m benchmarks.coldstart --workers 2   # two workers sharing the cache
    python -m benchmarks.coldstart --warm        # the cache left from a cold run: a restart

Starts ``rnsca serve`` on a free port of 127.0.0.1 with ``NUMBA_CACHE_DIR`` an empty
folder (so every kernel is compiled, as on a fresh machine; ``--warm`` compiles once
first and then measures a second start on that cache), and sends one small clip per
endpoint every 0.25 s until each is answered 200. Records for each endpoint the seconds
from the start of the process to its first 200 (and how many 503 ``not-ready`` answers came
first, each of which must have come at once), the seconds to ``/readyz`` 200, and the
warm-up steps the server logged with their seconds, in ``coldstart-<UTC timestamp>.json``.
The issue's target: a fresh start answers its first clip within 60 s on this machine.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

from benchmarks.load import _free_port, stop_server
from benchmarks.machine import describe_machine, run_header

__all__ = ["PROBES", "measure_start", "main"]

ROOT = Path(__file__).resolve().parent.parent
WINDOW = [0.0, 0.0, 10.0, 10.0]
#: One small clip per endpoint.
PROBES = {
    "segments": ("/v1/clip/segments", {"window": WINDOW, "segments": [[-5, 5, 15, 5]]}),
    "geojson": ("/v1/clip/geojson", {"window": WINDOW, "geojson": {
        "type": "LineString", "coordinates": [[-5, 5], [15, 5]]}}),
    "svg": ("/v1/clip/svg", {"window": WINDOW, "paths": ["M -5 5 C 0 0 10 10 15 5"]}),
}
TARGET_SECONDS = 60.0


def measure_start(cache: Path, workers: int, timeout: float, log_path: Path) -> dict:
    """Start the server on `cache`; return the seconds to each endpoint's first 200."""
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    env = {k: v for k, v in os.environ.items() if not k.startswith("RNSCA_")}
    env["NUMBA_CACHE_DIR"] = str(cache)
    rnsca = Path(sys.executable).parent / "rnsca"
    command = [str(rnsca)] if rnsca.exists() else [sys.executable, "-m", "rnsca.cli"]
    started = time.monotonic()
    process = subprocess.Popen(command + ["serve", "--host", "127.0.0.1", "--port", str(port),
                                          "--workers", str(workers)],
                               cwd=ROOT, env=env, stdout=log_path.open("wb"),
                               stderr=subprocess.STDOUT)
    first_200: dict[str, float] = {}
    not_ready = {name: 0 for name in PROBES}
    slowest_503 = 0.0
    ready = None
    try:
        with httpx.Client(base_url=url, timeout=30) as client:
            while (len(first_200) < len(PROBES) or ready is None) \
                    and time.monotonic() - started < timeout:
                if process.poll() is not None:
                    raise RuntimeError(f"rnsca serve exited with {process.returncode}")
                for name, (path, body) in PROBES.items():
                    if name in first_200:
                        continue
                    try:
                        asked = time.monotonic()
                        r = client.post(path, json=body)
                    except httpx.TransportError:
                        continue
                    if r.status_code == 200:
                        first_200[name] = round(time.monotonic() - started, 2)
                    elif r.status_code == 503:
                        not_ready[name] += 1
                        slowest_503 = max(slowest_503, time.monotonic() - asked)
                    else:
                        raise RuntimeError(f"{path}: {r.status_code} {r.text}")
                if ready is None:
                    try:
                        if client.get("/readyz").status_code == 200:
                            ready = round(time.monotonic() - started, 2)
                    except httpx.TransportError:
                        pass
                time.sleep(0.25)
    finally:
        stop_server(process)
    steps = []
    for line in log_path.read_text(errors="replace").splitlines():
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if record.get("message") in ("warmed up", "serving", "kernels ready",
                                     "the kernel cache is cold: compiling in child processes"):
            steps.append({k: v for k, v in record.items() if k not in ("time", "level",
                                                                       "logger")})
    return {"first_200_seconds": first_200, "readyz_seconds": ready,
            "not_ready_answers": not_ready, "slowest_not_ready_seconds": round(slowest_503, 3),
            "first_clip_seconds": min(first_200.values(), default=None), "log": steps}


def main(argv: list[str] | None = None) -> int:
    """Measure one start (cold, or warm after a cold one), print it, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--warm", action="store_true",
                        help="measure a start on the cache a cold start left")
    parser.add_argument("--timeout", type=float, default=1800.0)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    machine = describe_machine(ROOT)
    folder = Path(tempfile.mkdtemp(prefix="rnsca-coldstart-"))
    try:
        cache = folder / "numba-cache"
        cache.mkdir()
        if args.warm:
            measure_start(cache, args.workers, args.timeout, folder / "first.log")
        figures = measure_start(cache, args.workers, args.timeout, folder / "server.log")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    first = figures["first_clip_seconds"]
    result = {**run_header(1, stamp, False, machine, ROOT), "workers": args.workers,
              "cache": "warm" if args.warm else "cold", **figures,
              "target": {"first_clip_within_s": TARGET_SECONDS,
                         "met": first is not None and first <= TARGET_SECONDS}}
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"coldstart-{stamp}.json"
    path.write_text(json.dumps(result, indent=2))
    print(json.dumps({k: result[k] for k in ("cache", "workers", "first_200_seconds",
                                              "readyz_seconds", "not_ready_answers",
                                              "slowest_not_ready_seconds")}, indent=1))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
