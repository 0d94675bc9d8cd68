"""Soak: the service under mixed load for half an hour, memory and tail latency per minute.

Usage::

    python -m benchmarks.soak                     # 30 minutes, 32 connections (make soak)
    python -m benchmarks.soak --minutes 10        # shorter
    python -m benchmarks.soak --minutes 3 --minute-seconds 2 --warm-in 1   # smoke test

Starts ``rnsca serve --workers 2`` on a free port of 127.0.0.1 as `benchmarks.load` does
(same start, same wait for ``/readyz``, same small bodies), checks that every request of
the mix gets the status it should, then runs ``wrk`` once per "minute" (``--minute-seconds``,
60 by default) with a Lua script that rotates through the mix, one request after another
on each connection:

==================  ======  =========================================================
request             weight  expected
==================  ======  =========================================================
healthz                  2  200: ``GET /healthz``
geojson_verified         3  200: a LineString of 100 vertices, default verification
geojson                  3  200: the same, ``verify: false``
svg                      2  200: five short SVG paths
segments_binary          2  200: 100 binary segments
geojson_large            1  200: 20 LineStrings of 100 vertices, default verification
bad_json                 1  400: the body stops in the middle of the JSON
bad_window               1  422: xmin > xmax
unclosed_ring            1  422: a Polygon whose ring is not closed
wrong_content_type       1  415: the GeoJSON body sent as ``text/plain``
not_found                1  404: ``GET`` of a path that does not exist
==================  ======  =========================================================

After each minute it records wrk's figures (requests, requests/s, p50/p99 latency), the
answers by status (expected 4xx from the bad requests, anything else unexpected, 5xx
separately), socket errors, the load average, and the resident memory (``VmRSS``) of the
server's process tree: the uvicorn supervisor and each worker, sampled every few seconds
during the minute (the peak) and once after wrk has stopped (the figure the verdict uses:
the same moment of every minute, no request in flight).

Verdict (issue 16: "no growth over 10% after the first 5 minutes"): the baseline is the
median of the last warm-in minute and the one after it (minutes 5 and 6); every later
minute is compared with it. RSS must stay within 10% of the baseline in every minute and
in the least-squares trend over the run; p99 must stay within 10% in the trend (Theil–Sen,
which one slow minute cannot tilt) and in the median of the last five minutes. A single
minute's p99 is reported against the baseline too but does not decide the verdict: on a
shared 2-core machine one busy minute of some other process moves it by far more than
10% (the load average per minute shows when).
No answer may be a 5xx or an unexpected status, and no socket may fail.

Writes ``soak-<UTC timestamp>.json`` (``--out``, default ``benchmarks/results/``) with the
header of every suite (`benchmarks.machine.run_header`) and prints a summary.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import httpx
import numpy as np

from benchmarks.load import (
    CASES,
    WINDOW,
    _free_port,
    _line,
    _start_server,
    _wait_ready,
    parse_wrk,
    stop_server,
)
from benchmarks.machine import describe_machine, load_average, run_header

__all__ = ["MIX", "process_tree_rss", "evaluate_soak", "run_soak", "main"]

ROOT = Path(__file__).resolve().parent.parent
SCHEMA = "rnsca-bench-soak/1"
GROWTH_LIMIT = 0.10
#: wrk's reply timeout: a verified large request on a saturated 2-core machine can take a
#: second or more, and a timeout would be counted as a socket error.
WRK_TIMEOUT_S = 10


def _geojson(document: dict, **options) -> bytes:
    return json.dumps({"window": WINDOW, "geojson": document, **options}).encode()


_UNCLOSED = {"type": "Polygon", "coordinates": [[[-1.0, -1.0], [11.0, -1.0], [11.0, 11.0],
                                                 [-1.0, 11.0]]]}

#: name -> (weight, expected status, method, path, content type, body). The good requests
#: are `benchmarks.load.CASES`, so a soak minute and a load case measure the same bodies.
MIX: dict[str, tuple[int, int, str, str, str | None, bytes]] = {
    "healthz": (2, 200, *CASES["healthz"]),
    "geojson_verified": (3, 200, *CASES["geojson_verified"]),
    "geojson": (3, 200, *CASES["geojson"]),
    "svg": (2, 200, *CASES["svg"]),
    "segments_binary": (2, 200, *CASES["segments_binary"]),
    "geojson_large": (1, 200, "POST", "/v1/clip/geojson", "application/json", _geojson(
        {"type": "FeatureCollection", "features": [_line(100) for _ in range(20)]})),
    "bad_json": (1, 400, "POST", "/v1/clip/geojson", "application/json",
                 CASES["geojson"][3][:40]),
    "bad_window": (1, 422, "POST", "/v1/clip/geojson", "application/json", json.dumps(
        {"window": [10.0, 0.0, 0.0, 10.0], "geojson": _line(), "verify": False}).encode()),
    "unclosed_ring": (1, 422, "POST", "/v1/clip/geojson", "application/json",
                      _geojson(_UNCLOSED, verify=False)),
    "wrong_content_type": (1, 415, "POST", "/v1/clip/geojson", "text/plain",
                           CASES["geojson"][3]),
    "not_found": (1, 404, "GET", "/v1/clip/nothing-here", None, b""),
}


def _lua_string(text: str) -> str:
    return json.dumps(text)  # a JSON string literal is a valid Lua string literal here


def _lua(mix: dict, folder: Path) -> str:
    """Return the wrk script: the mix in rotation, answers counted by status per thread.

    Each wrk thread has its own Lua state, so the counters live there and ``done`` (run
    once, in the main state) adds them up through ``thread:get`` and prints one JSON line
    prefixed ``SOAK`` after wrk's own report.
    """
    entries = []
    for name, (weight, _, method, path, content_type, body) in mix.items():
        body_file = "nil"
        if body:
            body_path = folder / f"{name}.body"
            body_path.write_bytes(body)
            body_file = _lua_string(str(body_path))
        headers = ("{}" if content_type is None
                   else f'{{["Content-Type"] = {_lua_string(content_type)}}}')
        entries.append(f"  {{name = {_lua_string(name)}, weight = {weight}, method = "
                       f"{_lua_string(method)}, path = {_lua_string(path)}, headers = "
                       f"{headers}, body_file = {body_file}}},")
    return "\n".join([
        "-- generated by benchmarks.soak",
        "local entries = {", *entries, "}",
        "local threads = {}",
        "local counter = 0",
        "function setup(thread)",
        "  counter = counter + 1",
        "  thread:set('offset', counter)",
        "  table.insert(threads, thread)",
        "end",
        "function init(args)",
        "  rotation = {}",
        "  sent = {}",
        "  statuses = {}",
        "  for _, e in ipairs(entries) do",
        "    local body = nil",
        "    if e.body_file then",
        "      local f = assert(io.open(e.body_file, 'rb'))",
        "      body = f:read('*a')",
        "      f:close()",
        "    end",
        "    local request = wrk.format(e.method, e.path, e.headers, body)",
        "    for _ = 1, e.weight do table.insert(rotation, {e.name, request}) end",
        "    sent[e.name] = 0",
        "  end",
        "  -- Threads start at different places, so the first requests of a minute are mixed.",
        "  position = (offset * 7) % #rotation",
        "end",
        "function request()",
        "  position = position % #rotation + 1",
        "  local item = rotation[position]",
        "  sent[item[1]] = sent[item[1]] + 1",
        "  return item[2]",
        "end",
        "function response(status, headers, body)",
        "  local key = tostring(status)",
        "  statuses[key] = (statuses[key] or 0) + 1",
        "end",
        "local function encode(t)",
        "  local parts = {}",
        "  for k, v in pairs(t) do table.insert(parts, string.format('\"%s\": %d', k, v)) end",
        "  return '{' .. table.concat(parts, ', ') .. '}'",
        "end",
        "function done(summary, latency, requests)",
        "  local all_sent, all_statuses = {}, {}",
        "  for _, thread in ipairs(threads) do",
        "    for k, v in pairs(thread:get('sent')) do all_sent[k] = (all_sent[k] or 0) + v end",
        "    for k, v in pairs(thread:get('statuses')) do",
        "      all_statuses[k] = (all_statuses[k] or 0) + v",
        "    end",
        "  end",
        "  io.write(string.format('SOAK {\"sent\": %s, \"statuses\": %s, \"latency_us\": "
        "{\"p50\": %d, \"p90\": %d, \"p99\": %d, \"p99.9\": %d, \"max\": %d}}\\n', "
        "encode(all_sent), encode(all_statuses), latency:percentile(50), "
        "latency:percentile(90), latency:percentile(99), latency:percentile(99.9), "
        "latency.max))",
        "end",
        ""])


def _read_status(pid: int) -> dict[str, str]:
    fields = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, value = line.partition(":")
        fields[key] = value.strip()
    return fields


def process_tree_rss(root: int) -> dict:
    """Return the resident memory (bytes) of `root` and every process below it.

    Reads ``VmRSS`` from ``/proc/<pid>/status``. The role of each process is ``supervisor``
    for `root` (uvicorn's master process), ``worker`` for a child that runs Python's
    ``multiprocessing`` spawn (a uvicorn worker), and ``other`` otherwise (for example
    ``multiprocessing``'s resource tracker). A process that exits while the tree is read
    is left out.

    Returns
    -------
    dict
        ``total_bytes``, ``workers_bytes`` (the workers' sum) and ``processes``: a list of
        ``{pid, ppid, role, rss_bytes}``, the supervisor first, then by pid.
    """
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            # The command name in /proc/<pid>/stat may contain spaces: ppid follows the ')'.
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        parents[int(entry.name)] = int(stat.rpartition(")")[2].split()[1])
    tree = [root]
    for pid in tree:  # breadth-first; the list grows as children are found
        tree.extend(sorted(child for child, parent in parents.items() if parent == pid))
    processes = []
    for pid in tree:
        try:
            status = _read_status(pid)
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ")
        except OSError:
            continue
        rss = int(status.get("VmRSS", "0 kB").split()[0]) * 1024
        role = ("supervisor" if pid == root
                else "worker" if b"multiprocessing.spawn" in cmdline
                and b"resource_tracker" not in cmdline else "other")
        processes.append({"pid": pid, "ppid": parents.get(pid), "role": role,
                          "rss_bytes": rss})
    return {"total_bytes": sum(p["rss_bytes"] for p in processes),
            "workers_bytes": sum(p["rss_bytes"] for p in processes if p["role"] == "worker"),
            "processes": processes}


def _check_mix(url: str, mix: dict) -> None:
    """Raise RuntimeError unless every request of the mix gets its expected status.

    Each request is sent twice, on new connections, so that both workers are likely to
    have answered one of each kind before the load starts.
    """
    for name, (_, expected, method, path, content_type, body) in mix.items():
        for _ in range(2):
            answer = httpx.request(method, url + path, content=body or None,
                                   headers={"Content-Type": content_type} if content_type
                                   else None, timeout=60)
            if answer.status_code != expected:
                raise RuntimeError(f"{name}: expected {expected}, got "
                                   f"{answer.status_code} {answer.text[:300]}")


def _classify(statuses: dict[str, int], sent: dict[str, int], mix: dict) -> dict:
    """Split the answers of a minute into 2xx, expected 4xx, 5xx and unexpected ones.

    An answer with a status that only the bad requests should get (400, 404, 415, 422
    here) is expected, up to the number of bad requests sent; more of them than that means
    a good request was refused, and the excess is counted as unexpected.
    """
    expected_codes = {str(e[1]) for e in mix.values() if e[1] >= 400}
    bad_sent = sum(n for name, n in sent.items() if mix[name][1] >= 400)
    ok = sum(n for code, n in statuses.items() if code.startswith("2"))
    expected = sum(n for code, n in statuses.items() if code in expected_codes)
    server_errors = sum(n for code, n in statuses.items() if code.startswith("5"))
    other = sum(statuses.values()) - ok - expected - server_errors
    excess = max(0, expected - bad_sent)
    return {"ok": ok, "expected_4xx": expected - excess, "bad_sent": bad_sent,
            "5xx": server_errors, "unexpected": other + excess + server_errors}


def _sample_during(process: subprocess.Popen, root: int, every: float) -> list[dict]:
    samples = []
    while True:
        try:
            process.wait(every)
            return samples
        except subprocess.TimeoutExpired:
            samples.append(process_tree_rss(root))


def run_minute(wrk: str, script: Path, url: str, seconds: int, connections: int,
               threads: int, server: int, mix: dict, sample_every: float) -> dict:
    """Run wrk for `seconds` and return the minute's figures and the server's memory."""
    started = time.monotonic()
    process = subprocess.Popen(
        [wrk, "--latency", "-t", str(threads), "-c", str(connections), "-d", f"{seconds}s",
         "--timeout", f"{WRK_TIMEOUT_S}s", "-s", str(script), url],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # wrk's output is small (a few lines), so the pipes cannot fill while we sample.
    peaks = _sample_during(process, server, min(sample_every, max(0.5, seconds / 4)))
    stdout, stderr = process.communicate()
    if process.returncode != 0:
        raise RuntimeError(f"wrk exited with {process.returncode}: {stderr[-2000:]}")
    after = process_tree_rss(server)
    figures = parse_wrk(stdout)
    counted = next(json.loads(line[5:]) for line in stdout.splitlines()
                   if line.startswith("SOAK "))
    samples = [*peaks, after]
    return {
        "seconds": round(time.monotonic() - started, 3),
        "requests": figures["requests"],
        "requests_per_s": figures["requests_per_s"],
        "latency_s": {k: v / 1e6 for k, v in counted["latency_us"].items()},
        "non_2xx": figures["non_2xx"],
        "socket_errors": figures["socket_errors"],
        "statuses": counted["statuses"],
        "sent": counted["sent"],
        "answers": _classify(counted["statuses"], counted["sent"], mix),
        "rss_bytes": after["total_bytes"],
        "rss_workers_bytes": after["workers_bytes"],
        "rss_peak_bytes": max(s["total_bytes"] for s in samples),
        "processes": after["processes"],
        "load_average": load_average(),
    }


def _growth(values: list[float], warm_in: int) -> dict:
    """Return a series' baseline and its growth after the warm-in (minutes are 1-based).

    The baseline is the median of minutes `warm_in` and `warm_in` + 1; "later" is every
    minute after `warm_in`, and the tail the last five of them (fewer in a short run).
    The trend is a line through minutes `warm_in` .. end: its slope per minute and the
    growth it implies over that span relative to the baseline, by least squares
    (``slope_per_minute``, ``trend_growth``) and by Theil–Sen, the median of the slopes
    between every two minutes (``robust_*``), which one slow minute cannot tilt: on a
    shared machine a single p99 three times the others is common, and would move the
    least-squares growth over 25 minutes by about 20%.
    """
    baseline = statistics.median(values[warm_in - 1:warm_in + 1])
    later = values[warm_in:]
    minutes = np.arange(warm_in, len(values) + 1, dtype=float)
    judged = np.asarray(values[warm_in - 1:], float)
    slope = float(np.polyfit(minutes, judged, 1)[0])
    i, j = np.triu_indices(len(judged), k=1)
    robust = float(np.median((judged[j] - judged[i]) / (minutes[j] - minutes[i])))
    span = len(values) - warm_in
    tail = statistics.median(values[max(warm_in, len(values) - 5):])

    def ratio(v: float) -> float:
        return v / baseline - 1.0 if baseline else 0.0

    return {"first": values[0], "baseline": baseline, "max": max(later),
            "max_minute": warm_in + 1 + later.index(max(later)), "last": values[-1],
            "median_last_5": tail, "max_growth": ratio(max(later)), "last_growth":
            ratio(values[-1]), "median_last_5_growth": ratio(tail), "slope_per_minute": slope,
            "trend_growth": slope * span / baseline if baseline else 0.0,
            "robust_slope_per_minute": robust,
            "robust_trend_growth": robust * span / baseline if baseline else 0.0}


def evaluate_soak(minutes: list[dict], warm_in: int, limit: float = GROWTH_LIMIT) -> dict:
    """Return the RSS and p99 series' growth and the verdict, criterion by criterion.

    Parameters
    ----------
    minutes : list of dict
        `run_minute` results, in order; at least ``warm_in + 2``.
    warm_in : int
        Minutes not judged: the server fills its caches, pools and arenas.
    limit : float
        Growth allowed over the baseline (0.10: 10%).

    Returns
    -------
    dict
        ``rss``, ``rss_peak``, ``rss_workers`` and ``p99``: `_growth` of each series;
        ``answers`` and ``socket_errors`` summed over the minutes; ``criteria`` (the RSS
        trend by least squares, the p99 trend by Theil–Sen): ``{key, value, limit, met,
        gates}``, ``gates`` false for those reported only; ``passed``: every gating
        criterion met.
    """
    series = {"rss": [m["rss_bytes"] for m in minutes],
              "rss_peak": [m["rss_peak_bytes"] for m in minutes],
              "rss_workers": [m["rss_workers_bytes"] for m in minutes],
              "p99": [m["latency_s"]["p99"] for m in minutes]}
    growth = {name: _growth(values, warm_in) for name, values in series.items()}
    answers = {key: sum(m["answers"][key] for m in minutes)
               for key in ("ok", "expected_4xx", "bad_sent", "5xx", "unexpected")}
    sockets = sum(m["socket_errors"] for m in minutes)

    def criterion(key, value, op, bound, gates=True):
        met = value <= bound if op == "<=" else value == bound
        return {"key": key, "value": value, "op": op, "limit": bound, "met": met,
                "gates": gates}

    criteria = [
        criterion("rss_max_growth", growth["rss"]["max_growth"], "<=", limit),
        criterion("rss_trend_growth", growth["rss"]["trend_growth"], "<=", limit),
        criterion("rss_peak_max_growth", growth["rss_peak"]["max_growth"], "<=", limit,
                  gates=False),
        criterion("p99_trend_growth", growth["p99"]["robust_trend_growth"], "<=", limit),
        criterion("p99_median_last_5_growth", growth["p99"]["median_last_5_growth"], "<=",
                  limit),
        criterion("p99_max_growth", growth["p99"]["max_growth"], "<=", limit, gates=False),
        criterion("no_5xx", answers["5xx"], "==", 0),
        criterion("no_unexpected_status", answers["unexpected"], "==", 0),
        criterion("no_socket_errors", sockets, "==", 0),
    ]
    return {**growth, "answers": answers, "socket_errors": sockets, "criteria": criteria,
            "passed": all(c["met"] for c in criteria if c["gates"])}


def _log_summary(log_path: Path) -> dict:
    """Return the server log's size and its error lines (the first five kept)."""
    lines = errors = 0
    first: list[str] = []
    with log_path.open("rb") as log:
        for raw in log:
            lines += 1
            if b'"level":"error"' in raw or b'"level":"critical"' in raw or b"Traceback" in raw:
                errors += 1
                if len(first) < 5:
                    first.append(raw.decode(errors="replace")[:500])
    return {"bytes": log_path.stat().st_size, "lines": lines, "error_lines": errors,
            "first_errors": first}


def _mb(n: float) -> str:
    return f"{n / 2**20:.1f}"


def run_soak(minutes: int, minute_seconds: int, connections: int, threads: int,
             workers: int = 2, log_level: str = "info", sample_every: float = 5.0,
             log: Callable[[str], None] = print) -> tuple[list[dict], dict]:
    """Start the server, check the mix, run `minutes` wrk minutes; return them and the log.

    Returns
    -------
    tuple of (list of dict, dict)
        The minutes (`run_minute`, numbered from 1) and `_log_summary` of the server's log.
    """
    wrk = shutil.which("wrk")
    if wrk is None:
        raise RuntimeError("wrk is not installed (Debian: apt-get install wrk)")
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    results = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        server_log = folder / "server.log"
        process = _start_server(workers, port, server_log, log_level)
        try:
            _wait_ready(url, process)
            _check_mix(url, MIX)
            script = folder / "soak.lua"
            script.write_text(_lua(MIX, folder))
            at_start = process_tree_rss(process.pid)
            log(f"  ready: {len(at_start['processes'])} processes, RSS "
                f"{_mb(at_start['total_bytes'])} MiB")
            for minute in range(1, minutes + 1):
                figures = run_minute(wrk, script, url, minute_seconds, connections, threads,
                                     process.pid, MIX, sample_every)
                figures["minute"] = minute
                results.append(figures)
                workers_mb = "/".join(_mb(p["rss_bytes"]) for p in figures["processes"]
                                      if p["role"] == "worker")
                a = figures["answers"]
                log(f"  minute {minute:3d}  {figures['requests_per_s']:7.0f} req/s  p50 "
                    f"{figures['latency_s']['p50'] * 1e3:6.1f} ms  p99 "
                    f"{figures['latency_s']['p99'] * 1e3:6.1f} ms  4xx {a['expected_4xx']:6d}"
                    f"  5xx {a['5xx']}  unexpected {a['unexpected']}  sockets "
                    f"{figures['socket_errors']}  RSS {_mb(figures['rss_bytes'])} MiB "
                    f"(workers {workers_mb})  load {figures['load_average'][0]:.2f}")
                if process.poll() is not None:
                    raise RuntimeError(f"rnsca serve exited with {process.returncode}")
        finally:
            stop_server(process)
        return results, _log_summary(server_log)


def print_soak_summary(result: dict) -> None:
    """Print the per-minute table and the verdict with rich."""
    from rich.table import Table

    from benchmarks.report import make_console

    console = make_console()
    table = Table(title=f"Soak: {len(result['minutes'])} x {result['minute_seconds']} s, "
                        f"{result['connections']} connections")
    for column in ("min", "req/s", "p50 ms", "p99 ms", "4xx", "5xx", "unexp.", "sock.",
                   "RSS MiB", "workers MiB", "peak MiB", "load"):
        table.add_column(column, justify="right")
    for m in result["minutes"]:
        a = m["answers"]
        table.add_row(str(m["minute"]), f"{m['requests_per_s']:.0f}",
                      f"{m['latency_s']['p50'] * 1e3:.1f}", f"{m['latency_s']['p99'] * 1e3:.1f}",
                      str(a["expected_4xx"]), str(a["5xx"]), str(a["unexpected"]),
                      str(m["socket_errors"]), _mb(m["rss_bytes"]),
                      " / ".join(_mb(p["rss_bytes"]) for p in m["processes"]
                                 if p["role"] == "worker"),
                      _mb(m["rss_peak_bytes"]), f"{m['load_average'][0]:.2f}")
    console.print(table)
    verdict = result["verdict"]
    checks = Table(title=f"Verdict (baseline: median of minutes {result['warm_in']} and "
                         f"{result['warm_in'] + 1}): "
                         f"{'PASS' if verdict['passed'] else 'FAIL'}")
    for column in ("criterion", "value", "limit", "met", "decides"):
        checks.add_column(column)
    for c in verdict["criteria"]:
        value = c["value"] if isinstance(c["value"], int) else f"{c['value'] * 100:+.1f}%"
        limit = c["limit"] if c["op"] == "==" else f"{c['limit'] * 100:.0f}%"
        checks.add_row(c["key"], str(value), f"{c['op']} {limit}", "yes" if c["met"] else "NO",
                       "yes" if c["gates"] else "reported")
    console.print(checks)
    rss, p99 = verdict["rss"], verdict["p99"]
    console.print(f"RSS: first {_mb(rss['first'])} MiB, baseline {_mb(rss['baseline'])}, max "
                  f"{_mb(rss['max'])} (minute {rss['max_minute']}), last {_mb(rss['last'])}; "
                  f"trend {rss['slope_per_minute'] / 2**20:+.3f} MiB/min.  p99: baseline "
                  f"{p99['baseline'] * 1e3:.1f} ms, max {p99['max'] * 1e3:.1f} ms (minute "
                  f"{p99['max_minute']}), last 5 median {p99['median_last_5'] * 1e3:.1f} ms, "
                  f"trend {p99['robust_slope_per_minute'] * 1e3:+.3f} ms/min (Theil–Sen; least "
                  f"squares {p99['slope_per_minute'] * 1e3:+.3f}).")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=int, default=30)
    parser.add_argument("--minute-seconds", type=int, default=60,
                        help="length of a 'minute' in seconds (shorter for a smoke test)")
    parser.add_argument("--warm-in", type=int, default=5,
                        help="minutes before the baseline, not judged")
    parser.add_argument("--connections", type=int, default=32)
    parser.add_argument("--threads", type=int, default=2, help="wrk threads")
    parser.add_argument("--workers", type=int, default=2, help="uvicorn worker processes")
    parser.add_argument("--sample-seconds", type=float, default=5.0,
                        help="RSS sampling interval during a minute (for the peak)")
    parser.add_argument("--log-level", default="info",
                        help="the server's RNSCA_LOG_LEVEL (info, as deployed: a line per "
                             "request)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    if args.warm_in < 1 or args.minutes < args.warm_in + 2:
        parser.error("need --warm-in >= 1 and --minutes >= warm-in + 2 (a baseline of two "
                     "minutes)")
    machine = describe_machine(ROOT)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    print(f"soak: {args.minutes} x {args.minute_seconds} s of mixed load, wrk "
          f"{args.connections} connections, rnsca serve --workers {args.workers}, log level "
          f"{args.log_level}", flush=True)
    started = time.monotonic()
    minutes, server_log = run_soak(args.minutes, args.minute_seconds, args.connections,
                                   args.threads, args.workers, args.log_level,
                                   args.sample_seconds,
                                   log=lambda line: print(line, flush=True))
    quick = args.minute_seconds < 60 or args.minutes < 30
    result = {
        **run_header(SCHEMA, stamp, quick, machine, ROOT),
        "minutes_planned": args.minutes, "minute_seconds": args.minute_seconds,
        "warm_in": args.warm_in, "growth_limit": GROWTH_LIMIT,
        "connections": args.connections, "wrk_threads": args.threads,
        "wrk_timeout_s": WRK_TIMEOUT_S, "workers": args.workers, "log_level": args.log_level,
        "mix": {name: {"weight": e[0], "expected_status": e[1], "method": e[2], "path": e[3],
                       "content_type": e[4], "bytes": len(e[5])} for name, e in MIX.items()},
        "minutes": minutes,
        "verdict": evaluate_soak(minutes, args.warm_in),
        "server_log": server_log,
        "elapsed_seconds": round(time.monotonic() - started, 1),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"soak-{stamp}.json"
    path.write_text(json.dumps(result, indent=2))
    print_soak_summary(result)
    print(f"wrote {path}")
    return 0 if result["verdict"]["passed"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
