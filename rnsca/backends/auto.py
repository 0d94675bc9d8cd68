"""``backend="auto"``: OpenCL only where it measured faster than Numba on this machine.

Which backend wins depends on the device, the host's cores and the size of the call: a
GPU's kernels are 50-80x faster than 16 CPU cores, but every call pays its transfers
and the host work around them, so small calls (and, on some devices, every size) are
faster on the CPU. So the choice is measured, not guessed: at the first ``"auto"`` call
a short calibration (a few seconds) times both backends on generated inputs of a few
sizes per operation, and keeps, per operation, the smallest size from which OpenCL was
faster at every larger size measured (its crossover; none if it never was). The
result is cached on disk per device, host and kernel sources (``$RNSCA_CACHE_DIR``, default
``~/.cache/rnsca``), so later processes read it. Without a usable OpenCL device,
``"auto"`` is Numba. Asking for ``"opencl"`` by name never runs anything else.

Curves (paths, flatten) are not calibrated: the device does a small share of their
work (the host clips and writes every curve), so ``"auto"`` keeps them on Numba.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rnsca.backends.base import ClipBackend
from rnsca.backends.registry import get_backend, opencl_available
from rnsca.options import Backend

__all__ = ["AUTO", "backend_for", "choose", "calibration", "calibrate", "CALIBRATED"]

#: The backend name that asks for the measured choice.
AUTO = "auto"
#: The operations the calibration measures, and the sizes it tries (items per call).
CALIBRATED = {"segments": (1 << 12, 1 << 15, 1 << 18, 1 << 20),
              "windows": (1 << 12, 1 << 15, 1 << 18),
              "lines": (1 << 12, 1 << 15, 1 << 18),
              "polygons": (1 << 12, 1 << 15, 1 << 18)}
_LOCK = threading.Lock()
_CACHE: dict[str, dict] = {}
_WINDOW = (250.0, 250.0, 750.0, 750.0)


def backend_for(kind: Backend | str, operation: str, size: int) -> ClipBackend:
    """Return the backend `kind` names, or for ``"auto"`` the one `choose` picks.

    Raises
    ------
    BackendUnavailableError
        If a backend asked for by name cannot run here (never replaced by another).
    """
    if isinstance(kind, str) and not isinstance(kind, Backend) and kind == AUTO:
        kind = choose(operation, size)
    return get_backend(kind)


def choose(operation: str, size: int) -> Backend:
    """Return the backend for a call of `operation` on `size` items (segments, vertices).

    `operation` is an `Operation` value; one not calibrated (paths, flatten) is Numba.
    """
    if operation not in CALIBRATED or not opencl_available():
        return Backend.NUMBA
    crossover = calibration().get(operation)
    return Backend.OPENCL if crossover is not None and size >= crossover else Backend.NUMBA


def _cache_file(device: str) -> Path:
    import numba

    # The kernels' sources: a change to them measures again.
    sources = Path(__file__).parent
    kernels = [sources / "opencl" / "clip.cl", *sorted((sources.parent / "kernels").glob("*.py"))]
    digest = hashlib.sha256(b"".join(path.read_bytes() for path in kernels)).hexdigest()
    key = json.dumps([device, digest, platform.node(), os.cpu_count(),
                      numba.get_num_threads(), sorted(CALIBRATED.items())])
    folder = Path(os.environ.get("RNSCA_CACHE_DIR") or Path.home() / ".cache" / "rnsca")
    return folder / f"auto-{hashlib.sha256(key.encode()).hexdigest()[:16]}.json"


def calibration() -> dict:
    """Return the crossover size of each calibrated operation (None: OpenCL never won).

    Read from the disk cache, or measured once (`calibrate`) and written there.
    """
    device = get_backend(Backend.OPENCL).capabilities.devices[0]
    name = getattr(get_backend(Backend.OPENCL), "name", device)
    with _LOCK:
        if name in _CACHE:
            return _CACHE[name]["crossover"]
        path = _cache_file(name)
        try:
            _CACHE[name] = json.loads(path.read_text())
        except (OSError, ValueError):
            result = calibrate()
            _CACHE[name] = result
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                temporary = path.with_suffix(f".{os.getpid()}.tmp")
                temporary.write_text(json.dumps(result, indent=1))
                temporary.replace(path)
            except OSError:
                pass  # a read-only home: measured again by the next process
        return _CACHE[name]["crossover"]


def _best(call: Callable[[], object], repeats: int = 3) -> float:
    call()
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def _calls(operation: str, size: int, backend: Backend) -> Callable[[], object]:
    """Return a call of `operation` on about `size` generated items, on `backend`.

    The backends' operations themselves (this module sits below the public functions).
    """
    from rnsca.arrays import Ragged
    from rnsca.many_windows import as_windows
    from rnsca.options import SegmentOptions
    from rnsca.window import Window, WindowTable

    engine = get_backend(backend)
    window = Window(*_WINDOW)
    options = SegmentOptions.resolve(window)
    rng = np.random.default_rng(size)
    if operation == "segments":
        segments = rng.uniform(0.0, 1000.0, size=(size, 4))
        return lambda: engine.clip_segments(segments, window, options)
    if operation == "windows":
        start = rng.uniform(0.0, 1000.0, size=(size, 2))
        segments = np.ascontiguousarray(np.c_[start, start + rng.uniform(-10.0, 10.0,
                                                                          size=(size, 2))])
        edges = np.linspace(0.0, 1000.0, 9)
        grid = as_windows([(edges[i], edges[j], edges[i + 1], edges[j + 1])
                           for j in range(8) for i in range(8)])
        return lambda: engine.clip_segment_windows(segments, grid, options)
    if operation == "lines":
        steps = rng.normal(0.0, 3.0, size=(size, 2))
        coords = np.cumsum(steps, axis=0) % 1000.0
        offsets = np.unique(np.r_[np.arange(0, size, 1000), size]).astype(np.int64)
        lines = Ragged.of("linestring", coords, (offsets,))
        table = WindowTable.of(window, lines.count)
        return lambda: engine.clip_lines(lines, table, options, False)
    # Polygons: stars of 32 vertices (closed rings), scattered.
    n = max(1, size // 33)
    angle = np.linspace(0.0, 2 * np.pi, 33)[:32]
    radius = np.where(np.arange(32) % 2, 20.0, 40.0)
    ring = np.c_[radius * np.cos(angle), radius * np.sin(angle)]
    ring = np.r_[ring, ring[:1]]
    centres = rng.uniform(0.0, 1000.0, size=(n, 1, 2))
    coords = (centres + ring[None]).reshape(-1, 2)
    polygons = Ragged.of("polygon", coords, (np.arange(0, 33 * n + 1, 33, dtype=np.int64),
                                             np.arange(n + 1, dtype=np.int64)))
    table = WindowTable.of(window, polygons.count)
    return lambda: engine.clip_polygons(polygons, table, options)


def calibrate(operations: dict[str, tuple[int, ...]] | None = None) -> dict:
    """Time Numba and OpenCL per operation and size; return the crossovers and the times.

    Returns ``{"crossover": {operation: size or None}, "seconds": {operation: [[size,
    numba, opencl], ...]}}``.
    """
    crossover: dict[str, int | None] = {}
    seconds: dict[str, list] = {}
    for operation, sizes in (operations or CALIBRATED).items():
        rows: list[list[float]] = []
        for size in sizes:
            numba_s = _best(_calls(operation, size, Backend.NUMBA))
            opencl_s = _best(_calls(operation, size, Backend.OPENCL))
            rows.append([size, numba_s, opencl_s])
        seconds[operation] = rows
        wins: int | None = None
        for measured, numba_s, opencl_s in reversed(rows):
            if opencl_s >= numba_s:
                break
            wins = int(measured)
        crossover[operation] = wins
    return {"crossover": crossover, "seconds": seconds}
