"""One round of `benchmarks.compare` in a fresh process: time every workload on one checkout.

Run as a script (``python compare_child.py CHECKOUT INPUTS BUDGET``) so that `rnsca` is
imported from CHECKOUT, whatever checkout this file comes from; it uses nothing of the
project but the public API. Prints one JSON line: ``{workload: [seconds, ...]}``.
"""

import gc
import json
import sys
import time
from pathlib import Path


def _timed(call) -> float:
    gc.disable()
    try:
        start = time.perf_counter()
        call()
        return time.perf_counter() - start
    finally:
        gc.enable()


def _samples(call, budget: float) -> list[float]:
    """Return the seconds of each call: at least 2, until `budget` seconds are spent."""
    call()  # warm-up: fills the caches
    seconds = [_timed(call)]
    while len(seconds) < 2 or (sum(seconds) < budget and len(seconds) < 50):
        seconds.append(_timed(call))
    return seconds


def _call(rnsca, workload: dict, folder: Path):
    """Return a zero-argument call that runs `workload` (inputs read now, not timed)."""
    import numpy as np
    import orjson

    kind, window, options = workload["kind"], tuple(workload["window"]), workload["options"]
    source = folder / workload["file"]
    if kind == "segments":
        segments = np.load(source)
        return lambda: rnsca.clip_segments(segments, window, **options)
    if kind == "ragged":
        import shapely

        data = np.load(source)
        offsets = tuple(data[f"offsets{k}"] for k in range(len(data.files) - 1))
        geometry_type = shapely.GeometryType(workload["geometry_type"])
        coords = data["coords"]
        return lambda: rnsca.clip_ragged(geometry_type, coords, offsets, window, **options)
    if kind == "geojson":
        document = orjson.loads(source.read_bytes())
        return lambda: rnsca.clip_geojson(document, window, **options)
    if kind in ("parse", "write", "clip_svg"):
        corpus = orjson.loads(source.read_bytes())
        if kind == "parse":
            return lambda: rnsca.parse_paths(corpus)
        if kind == "write":
            parsed = rnsca.parse_paths(corpus)
            return lambda: rnsca.write_paths(parsed, precision=None)
        return lambda: rnsca.clip_svg(corpus, window, **options)
    if kind == "paths":
        data = np.load(source)
        paths = rnsca.PathArrays(**{name: data[name] for name in data.files})
        return lambda: rnsca.clip_paths(paths, window, **options)
    raise ValueError(f"unknown workload kind {kind!r}")


def main() -> None:
    """Time the workloads listed in INPUTS/workloads.json; print their samples as JSON."""
    checkout, folder, budget = Path(sys.argv[1]), Path(sys.argv[2]), float(sys.argv[3])
    sys.path.insert(0, str(checkout))
    import rnsca

    if Path(rnsca.__file__).resolve().parent.parent != checkout.resolve():
        raise SystemExit(f"rnsca was imported from {rnsca.__file__}, not from {checkout}")
    from rnsca.errors import BackendUnavailableError

    try:  # what the CLI, service and benchmarks do; older checkouts did it at import
        from rnsca.runtime import configure_process
    except ImportError:
        pass
    else:
        configure_process()

    calls = {}
    for workload in json.loads((folder / "workloads.json").read_text()):
        try:
            call = _call(rnsca, workload, folder)
            # Every workload once before any is timed: the kernels compile or load, and
            # the allocator settles (glibc raises its mmap threshold after the first
            # large frees), so the first workload timed is not penalised.
            call()
        except BackendUnavailableError as exc:  # no OpenCL device here: not compared
            print(f"{workload['name']}: {exc}", file=sys.stderr)
        else:
            calls[workload["name"]] = call
    results = {name: _samples(call, budget) for name, call in calls.items()}
    print(json.dumps(results))


if __name__ == "__main__":
    main()
