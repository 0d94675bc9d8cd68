"""The GPU issue's workloads: Numba on every host core against OpenCL, in one process.

Run on a machine with an OpenCL GPU (README, "Development"; `benchmarks/gpu_host.sh`)::

    python -m benchmarks.gpu                  # every workload, the sizes of the issue
    python -m benchmarks.gpu --small          # the same at toy sizes (a CPU check)

Each workload runs on both backends (best of ``--repeats`` after one untimed call) and
the results are compared bit for bit. For each OpenCL call the table splits the wall
time into the device's kernels and transfers (OpenCL event profiling) and the rest
(host work; negative where transfers and kernels overlap each other or the host).
Cold start: a fresh process's first call of each kind, with empty and with warm caches
(Numba's and pyopencl's), children of this one. Writes
``benchmarks/results/gpu-<stamp>.json`` (and ``$OUT/gpu.json`` where ``OUT`` is set).
Needs only the project and its wheels (numpy, numba, pyopencl, shapely).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import rnsca
from benchmarks import bench_curves as BC
from benchmarks import datasets as D

W = (250.0, 250.0, 750.0, 750.0)
HERE = Path(__file__).resolve().parent
COLD_KINDS = ("segments", "lines", "polygons", "paths")


def _best(call, repeats: int) -> tuple[float, object]:
    result = call()
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        result = call()
        best = min(best, time.perf_counter() - start)
    return best, result


def _split(result, wall: float) -> dict:
    stats = getattr(result, "stats", None)
    # A clip's device stats are in its ClipStats; encoded tiles carry theirs.
    device = getattr(stats, "device", None) if stats is not None else getattr(
        result, "device", None)
    if device is None:
        return {}
    return {"kernel_s": device.kernel_seconds, "transfer_s": device.transfer_seconds,
            "host_s": wall - device.kernel_seconds - device.transfer_seconds,
            "bytes_to_device": device.bytes_to_device,
            "bytes_from_device": device.bytes_from_device, "transfers": device.transfers}


class Table:
    """Rows of the report: printed as they come, kept for the JSON."""

    def __init__(self) -> None:
        self.rows: list[dict] = []
        print(f"{'workload':46s} {'numba':>10s} {'opencl':>10s} {'speed-up':>9s} "
              f"{'kernels':>9s} {'transfers':>10s} {'host':>9s}  equal", flush=True)

    def add(self, name: str, numba_s: float | None, opencl_s: float, split: dict,
            equal: bool | None, **extra) -> None:
        """Print and keep one row."""
        row = {"workload": name, "numba_s": numba_s, "opencl_s": opencl_s,
               "speedup": (numba_s / opencl_s) if numba_s else None, "equal": equal,
               **split, **extra}
        self.rows.append(row)

        def ms(v):
            return f"{v * 1e3:8.2f}ms" if v is not None else f"{'-':>10s}"

        speed = f"{row['speedup']:8.2f}x" if row["speedup"] else f"{'-':>9s}"
        print(f"{name:46s} {ms(numba_s)} {ms(opencl_s)} {speed} "
              f"{ms(split.get('kernel_s'))[:-2]:>9s} {ms(split.get('transfer_s'))[:-2]:>10s} "
              f"{ms(split.get('host_s'))[:-2]:>9s}  {equal}", flush=True)


def _same_segments(a, b) -> bool:
    def host(x):
        return x.get() if hasattr(x, "get") and not isinstance(x, np.ndarray) else x

    return bool(np.array_equal(host(a.segments), b.segments)
                and (a.source is None or np.array_equal(host(a.source), b.source))
                and (a.t is None or np.array_equal(host(a.t), b.t)))


def segments(table: Table, n: int, repeats: int, variants: bool, sweeps: bool = True) -> None:
    segs = D.uniform_segments(n)
    label = f"{n / 1e6:g}M" if n >= 1e6 else f"{n}"
    for method in ("rnsca", "liang_barsky") if variants else ("rnsca",):
        tn, rn = _best(lambda m=method: rnsca.clip_segments(segs, W, method=m), repeats)
        to, ro = _best(lambda m=method: rnsca.clip_segments(segs, W, method=m,
                                                            backend="opencl"), repeats)
        table.add(f"segments {label} {method}", tn, to, _split(ro, to), _same_segments(ro, rn),
                  pieces=len(rn))
    if not variants:
        return
    tn, rn = _best(lambda: rnsca.clip_segments(segs, W, outputs=("segments",)), repeats)
    to, ro = _best(lambda: rnsca.clip_segments(segs, W, backend="opencl",
                                               outputs=("segments",)), repeats)
    table.add(f"segments {label} pieces only", tn, to, _split(ro, to), _same_segments(ro, rn))
    _pinned_input(table, segs, label, repeats)
    _device_resident(table, segs, label, repeats)
    if sweeps:
        _chunk_sizes(table, segs, label)
        _copies(table, segs)


def _pinned_input(table: Table, segs: np.ndarray, label: str, repeats: int) -> None:
    """Time host segments already in page-locked memory: no copy into the staging buffers."""
    from rnsca.backends.registry import get_backend

    pinned = get_backend("opencl").empty_pinned(segs.shape)
    pinned[:] = segs
    tn, rn = _best(lambda: rnsca.clip_segments(segs, W), repeats)
    to, ro = _best(lambda: rnsca.clip_segments(pinned, W, backend="opencl"), repeats)
    table.add(f"segments {label} pinned input", tn, to, _split(ro, to), _same_segments(ro, rn))


def _device_resident(table: Table, segs: np.ndarray, label: str, repeats: int) -> None:
    import pyopencl.array as cl_array

    from rnsca.backends.registry import get_backend

    backend = get_backend("opencl")
    queue = backend.queue
    start = time.perf_counter()
    on_device = cl_array.to_device(queue, segs)
    queue.finish()
    upload = time.perf_counter() - start
    tn, rn = _best(lambda: rnsca.clip_segments(segs, W), repeats)
    to, ro = _best(lambda: rnsca.clip_segments(on_device, W, backend="opencl"), repeats)
    table.add(f"segments {label} device-resident", tn, to, _split(ro, to),
              _same_segments(ro, rn), upload_s=upload)


def _chunk_sizes(table: Table, segs: np.ndarray, label: str) -> None:
    """Time the pipeline's chunk sizes: which overlaps transfers best on this device."""
    from rnsca.backends.opencl import segments as S

    kept = S.CHUNK_SEGMENTS
    try:
        for shift in (20, 21, 22, 23):
            S.CHUNK_SEGMENTS = 1 << shift
            to, ro = _best(lambda: rnsca.clip_segments(segs, W, backend="opencl"), 2)
            table.add(f"  chunk 2**{shift} ({label})", None, to, _split(ro, to), None,
                      chunk=1 << shift)
    finally:
        S.CHUNK_SEGMENTS = kept


def _copies(table: Table, segs: np.ndarray) -> None:
    """Time host copies: one thread (NumPy) against every core (`copies.copy_into`)."""
    from rnsca.kernels.copies import copy_into

    target = np.empty_like(segs)
    tn, _ = _best(lambda: np.copyto(target, segs), 2)
    tp, _ = _best(lambda: copy_into(target, segs), 2)
    fresh_start = time.perf_counter()
    copy_into(np.empty_like(segs), segs)
    fresh = time.perf_counter() - fresh_start
    gb = segs.nbytes / 1e9
    table.add(f"  host copy {segs.nbytes / 1e6:.0f} MB (numpy | all cores)", tn, tp, {}, None,
              numpy_gbps=gb / tn, parallel_gbps=gb / tp, fresh_pages_gbps=gb / fresh)


def many_windows(table: Table, n: int, k: int, repeats: int) -> None:
    """Time a grid of `k` windows over `n` short segments.

    Short as the edges of real data: a few units in a 1000-unit extent, so most lie in
    one window.
    """
    rng = np.random.default_rng(7)
    start = rng.uniform(0.0, 1000.0, size=(n, 2))
    segs = np.ascontiguousarray(np.c_[start, start + rng.uniform(-10.0, 10.0, size=(n, 2))])
    side = int(round(k ** 0.5))
    xs = np.linspace(0.0, 1000.0, side + 1)
    ys = np.linspace(0.0, 1000.0, side + 1)
    grid = np.array([(xs[i], ys[j], xs[i + 1], ys[j + 1]) for j in range(side)
                     for i in range(side)])
    tn, rn = _best(lambda: rnsca.clip_segments(segs, windows=grid), repeats)
    to, ro = _best(lambda: rnsca.clip_segments(segs, windows=grid, backend="opencl"),
                   repeats)
    equal = _same_segments(ro, rn) and bool(np.array_equal(ro.window, rn.window))
    label = f"{len(grid)} windows over {n / 1e6:g}M segments"
    table.add(label, tn, to, _split(ro, to), equal, pieces=len(rn))
    _many_windows_device_resident(table, segs, grid, label, tn, rn, repeats)


def _many_windows_device_resident(table: Table, segs: np.ndarray, grid: np.ndarray,
                                  label: str, tn: float, rn, repeats: int) -> None:
    """Time the same grid over segments already on the device, the outputs left there.

    Beside the host row: the pairs are made and clipped on the device either way; this
    row has no segment upload and no download of the pieces (the upload is timed apart).
    """
    import pyopencl.array as cl_array

    from rnsca.backends.registry import get_backend

    queue = get_backend("opencl").queue
    start = time.perf_counter()
    on_device = cl_array.to_device(queue, segs)
    queue.finish()
    upload = time.perf_counter() - start
    to, ro = _best(lambda: rnsca.clip_segments(on_device, windows=grid, backend="opencl"),
                   repeats)
    equal = (_same_segments(ro, rn) and bool(np.array_equal(ro.window.get(), rn.window))
             and bool(np.array_equal(ro.window_offsets, rn.window_offsets)))
    table.add(f"{label} device-resident", tn, to, _split(ro, to), equal, upload_s=upload)
    _many_windows_encode(table, grid, label, rn, ro, repeats)


def _many_windows_encode(table: Table, grid: np.ndarray, label: str, rn, ro,
                         repeats: int) -> None:
    """Time the tiles' encoding (MVT), the device-resident pieces against the host's.

    The device's pieces are encoded on the device (only the per-tile counts and the
    tiles' bytes come back), the host's by the Numba backend; the bytes compared.
    """
    from rnsca.tiles import encode_segment_tiles

    tn, en = _best(lambda: encode_segment_tiles(rn, grid, backend="numba"), repeats)
    to, eo = _best(lambda: encode_segment_tiles(ro, grid, backend="opencl"), repeats)
    equal = bool(np.array_equal(en.data, eo.data) and np.array_equal(en.offsets, eo.offsets))
    table.add(f"{label} encode tiles", tn, to, _split(eo, to), equal,
              tile_bytes=int(en.data.nbytes))


def lines(table: Table, n_lines: int, repeats: int, sweeps: bool = True) -> None:
    coords, offsets = D.smooth_polylines(n_lines)
    tn, rn = _best(lambda: rnsca.clip_ragged("linestring", coords, (offsets,), W), repeats)
    to, ro = _best(lambda: rnsca.clip_ragged("linestring", coords, (offsets,), W,
                                             backend="opencl"), repeats)
    equal = bool(np.array_equal(rn.coords, ro.coords)
                 and all(np.array_equal(a, b) for a, b in zip(rn.offsets, ro.offsets,
                                                              strict=True)))
    label = f"polylines {n_lines} ({len(coords) / 1e6:.1f}M vertices)"
    table.add(label, tn, to, _split(ro, to), equal)
    if sweeps:
        _range_sizes(table, label, lambda: rnsca.clip_ragged(
            "linestring", coords, (offsets,), W, backend="opencl"))


def _range_sizes(table: Table, label: str, call) -> None:
    """Time the ranges of a pipelined line or ring call: how much overlap pays here."""
    from rnsca.backends.opencl import runs

    kept = runs.PIPELINE_VERTICES
    try:
        for shift in (19, 20, 21, 22, 40):
            runs.PIPELINE_VERTICES = 1 << shift
            to, ro = _best(call, 2)
            name = "one range" if shift == 40 else f"ranges of 2**{shift}"
            table.add(f"  {name} ({label})", None, to, _split(ro, to), None,
                      range_vertices=1 << shift)
    finally:
        runs.PIPELINE_VERTICES = kept


def polygons(table: Table, n: int, repeats: int, sweeps: bool = True) -> None:
    coords, ring_offsets, geometry_offsets = D.star_polygons(n)
    offsets = (ring_offsets, geometry_offsets)
    tn, rn = _best(lambda: rnsca.clip_ragged("polygon", coords, offsets, W), repeats)
    to, ro = _best(lambda: rnsca.clip_ragged("polygon", coords, offsets, W,
                                             backend="opencl"), repeats)
    equal = bool(np.array_equal(rn.coords, ro.coords)
                 and all(np.array_equal(a, b) for a, b in zip(rn.offsets, ro.offsets,
                                                              strict=True)))
    label = f"polygons {n / 1e3:g}k stars with holes"
    table.add(label, tn, to, _split(ro, to), equal)
    if sweeps:
        _range_sizes(table, label, lambda: rnsca.clip_ragged(
            "polygon", coords, offsets, W, backend="opencl"))


def curves(table: Table, small: bool, repeats: int) -> None:
    for label, paths, window in (
            ("glyph page", *BC.glyph_page(25 if small else 2500)),
            ("curves 200 x 500 cubics", BC.long_curves(*((5, 50) if small else (200, 500))),
             W)):
        tn, rn = _best(lambda p=paths, w=window: rnsca.clip_paths(p, w), repeats)
        to, ro = _best(lambda p=paths, w=window: rnsca.clip_paths(p, w, backend="opencl"),
                       repeats)
        equal = bool(np.array_equal(rn.paths.controls, ro.paths.controls))
        table.add(label, tn, to, _split(ro, to), equal)


def _calibration(operations: set[str] | None = None) -> dict:
    """Run backend='auto''s calibration here and print each operation's crossover."""
    from rnsca.backends import auto

    start = time.perf_counter()
    result = auto.calibrate({op: sizes for op, sizes in auto.CALIBRATED.items()
                             if operations is None or op in operations})
    result["wall_s"] = time.perf_counter() - start
    for operation, rows in result["seconds"].items():
        cells = "  ".join(f"{size}: {n * 1e3:.2f}/{o * 1e3:.2f} ms" for size, n, o in rows)
        print(f"auto {operation:9s} crossover {result['crossover'][operation]}  "
              f"(numba/opencl) {cells}", flush=True)
    print(f"auto calibration took {result['wall_s']:.1f} s", flush=True)
    return result


def _profiles(small: bool) -> dict:
    """Profile one OpenCL call of lines and of polygons: where the host time goes."""
    import cProfile
    import io
    import pstats

    coords, offsets = D.smooth_polylines(10 if small else 4000)
    polygons_data = D.star_polygons(1000 if small else 1_000_000)
    calls = {
        "lines": lambda: rnsca.clip_ragged("linestring", coords, (offsets,), W,
                                           backend="opencl"),
        "polygons": lambda: rnsca.clip_ragged("polygon", polygons_data[0],
                                              polygons_data[1:], W, backend="opencl")}
    out = {}
    for name, call in calls.items():
        call()
        profile = cProfile.Profile()
        profile.enable()
        call()
        profile.disable()
        text = io.StringIO()
        pstats.Stats(profile, stream=text).sort_stats("cumulative").print_stats(14)
        out[name] = text.getvalue()
        print(f"--- profile: {name} on OpenCL\n{out[name]}", flush=True)
    return out


# --- cold start: a fresh process's first call of each kind -------------------------------

_CHILD = """
import sys, time
start = time.perf_counter()
import numpy as np
import rnsca
from benchmarks import datasets as D
from benchmarks import bench_curves as BC
kind, backend = sys.argv[1], sys.argv[2]
W = (250.0, 250.0, 750.0, 750.0)
imported = time.perf_counter()
if kind == "segments":
    rnsca.clip_segments(D.uniform_segments(1000), W, backend=backend)
elif kind == "lines":
    c, o = D.smooth_polylines(3)
    rnsca.clip_ragged("linestring", c, (o,), W, backend=backend)
elif kind == "polygons":
    c, r, g = D.star_polygons(50)
    rnsca.clip_ragged("polygon", c, (r, g), W, backend=backend)
else:
    paths, window = BC.glyph_page(4)
    rnsca.clip_paths(paths, window, backend=backend)
done = time.perf_counter()
print(f"{imported - start:.3f} {done - imported:.3f}")
"""


def _first_call(kind: str, backend: str, env: dict) -> dict:
    start = time.perf_counter()
    run = subprocess.run([sys.executable, "-c", _CHILD, kind, backend], capture_output=True,
                         text=True, cwd=HERE.parent, timeout=400, env=env)
    wall = time.perf_counter() - start
    if run.returncode:
        return {"kind": kind, "backend": backend, "error": run.stderr[-2000:]}
    imported, first = (float(v) for v in run.stdout.split()[-2:])
    return {"kind": kind, "backend": backend, "process_s": wall, "import_s": imported,
            "first_call_s": first}


def cold_start(backends: tuple[str, ...]) -> list[dict]:
    """First calls with empty caches (all kinds at once: one child each), then warm.

    The children's caches (Numba's, pyopencl's binaries, the calibration's) live in a new
    folder, so "empty" stays empty whatever this process compiled before.
    """
    import tempfile

    jobs = [(kind, backend) for backend in backends for kind in COLD_KINDS]
    rows = []
    with tempfile.TemporaryDirectory(prefix="rnsca-cold-") as caches:
        env = {**os.environ, "NUMBA_CACHE_DIR": f"{caches}/numba",
               "XDG_CACHE_HOME": f"{caches}/xdg", "RNSCA_CACHE_DIR": f"{caches}/rnsca"}
        with ThreadPoolExecutor(len(jobs)) as pool:
            for row in pool.map(lambda job: _first_call(*job, env), jobs):
                rows.append({**row, "caches": "cold (compiled beside the other kinds)"})
        for job in jobs:
            rows.append({**_first_call(*job, env), "caches": "warm"})
    for row in rows:
        shown = (f"first call {row['first_call_s']:7.2f} s (import {row['import_s']:.2f} s)"
                 if "error" not in row else "ERROR " + row["error"][-300:])
        print(f"cold start {row['backend']:6s} {row['kind']:9s} {row['caches']:40s} {shown}",
              flush=True)
    return rows


FAMILIES = ("segments", "windows", "lines", "polygons", "curves", "cold-start")


def _guarded(report: dict, part: str, run) -> None:
    """Run one part of the report; a failure is recorded and printed, the rest still runs.

    A GPU machine is lent for minutes: one workload failing must not cost the others.
    """
    import traceback

    try:
        run()
    except Exception:
        text = traceback.format_exc()
        report["errors"].append({"part": part, "traceback": text})
        print(f"ERROR in {part}:\n{text}", flush=True)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="toy sizes (a CPU check)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--skip-cold-start", action="store_true")
    parser.add_argument("--only", default="",
                        help="comma-separated families: " + ",".join(FAMILIES))
    parser.add_argument("--out", type=Path, default=HERE / "results",
                        help="directory of the JSON (default benchmarks/results)")
    parser.add_argument("--skip-calibration", action="store_true",
                        help="skip backend='auto''s calibration (its crossover sizes)")
    parser.add_argument("--calibrate", default="",
                        help="comma-separated operations to calibrate (default: all)")
    parser.add_argument("--skip-sweeps", action="store_true",
                        help="skip the chunk and range size sweeps and the host copies")
    parser.add_argument("--profile", action="store_true",
                        help="profile one OpenCL call of lines and of polygons (host time)")
    args = parser.parse_args(argv)
    import numba

    from rnsca.backends.opencl import list_devices
    from rnsca.backends.registry import get_backend

    report: dict = {"started": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                    "host": {"cores": os.cpu_count(), "numba_threads": numba.get_num_threads(),
                             "python": platform.python_version(), "numpy": np.__version__,
                             "numba": numba.__version__, "machine": platform.processor()},
                    "devices": list_devices(), "small": args.small, "errors": []}
    print(json.dumps(report, indent=1), flush=True)
    families = set(filter(None, args.only.split(","))) or set(FAMILIES)
    if unknown := families - set(FAMILIES):
        parser.error(f"unknown families {sorted(unknown)}; known: {', '.join(FAMILIES)}")
    if args.skip_cold_start:
        families.discard("cold-start")
    small = args.small
    sweeps = not args.skip_sweeps
    workloads = {
        "segments": lambda: (
            segments(table, 20_000 if small else 10_000_000, args.repeats, variants=True,
                     sweeps=sweeps),
            segments(table, 50_000 if small else 50_000_000, args.repeats, variants=False)),
        "windows": lambda: many_windows(table, 20_000 if small else 10_000_000, 1024,
                                        args.repeats),
        "lines": lambda: lines(table, 10 if small else 4000, args.repeats, sweeps),
        "polygons": lambda: polygons(table, 1000 if small else 1_000_000, args.repeats,
                                     sweeps),
        "curves": lambda: curves(table, small, args.repeats)}
    opencl = get_backend("opencl")
    report["opencl_device"] = opencl.name
    table = Table()
    for family, run in workloads.items():
        if family in families:
            _guarded(report, family, run)
    report["rows"] = table.rows
    if not args.skip_calibration:
        _guarded(report, "calibration", lambda: report.__setitem__(
            "auto_calibration", _calibration(set(filter(None, args.calibrate.split(",")))
                                             or None)))
    if args.profile:
        _guarded(report, "profiles",
                 lambda: report.__setitem__("profiles", _profiles(small)))
    if "cold-start" in families:
        # Last: its children compile every kind with empty caches, the longest part.
        _guarded(report, "cold-start", lambda: report.__setitem__(
            "cold_start", cold_start(("numba", "opencl"))))
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    paths = [args.out / f"gpu-{stamp}.json"]
    if os.environ.get("OUT"):
        paths.append(Path(os.environ["OUT"]) / "gpu.json")
    for path in paths:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(report, indent=1, default=str))
        print(f"wrote {path}", flush=True)
    return report


if __name__ == "__main__":
    main()
