"""How long a fresh process takes to reach its first clipping result.

A child ``python -c`` imports rnsca and clips a small array; the parent takes the time
from just before it spawns the child to the moment the child has its result (both read
``time.monotonic()``, which on Linux is one system-wide clock). The child also reports
when its imports finished, so interpreter start, import and first call are separable.

Figures:

``project_cache``
    The first child of this run, using Numba's cache where the kernels normally keep it
    (``__pycache__`` next to the sources). Whatever was there is used and nothing is
    deleted; the number of cache index files seen beforehand is reported, so a cold
    figure is recognisable (0 files: every kernel compiled in this child).
``warm``
    Further children with the same cache: the figure the target is about.
``empty_cache``
    (full runs only) a child pointed at a new, empty ``NUMBA_CACHE_DIR``: a true cold
    start that compiles every kernel, then a second child on that cache, which shows
    the on-disk cache working.
``interpreter``
    ``python -c pass``: the part no library can remove.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

__all__ = ["measure_startup", "CHILD_CODE"]

CHILD_CODE = """\
import time
import numpy as np
import rnsca
imported = time.monotonic()
segments = np.array([[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0], [1.0, 1.0, 2.0, 2.0]])
result = rnsca.clip_segments(segments, (0.0, 0.0, 10.0, 10.0))
done = time.monotonic()
assert len(result) == 2
import json
print(json.dumps({"imported": imported, "first_result": done}))
"""


def _cache_index_files(root: Path) -> int:
    return sum(1 for _ in root.rglob("*.nbi"))


def _spawn(env: dict[str, str], cwd: Path, code: str = CHILD_CODE) -> dict:
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=cwd, capture_output=True,
                          text=True, timeout=600, check=False)
    end = time.monotonic()
    if proc.returncode != 0:
        raise RuntimeError(f"startup child failed ({proc.returncode}): {proc.stderr[-2000:]}")
    out = {"process_seconds": end - start}
    if proc.stdout.strip():
        marks = json.loads(proc.stdout.strip().splitlines()[-1])
        out["import_seconds"] = marks["imported"] - start
        out["first_result_seconds"] = marks["first_result"] - start
        out["first_call_seconds"] = marks["first_result"] - marks["imported"]
    return out


def _series(samples: list[dict]) -> dict:
    firsts = [s["first_result_seconds"] for s in samples]
    return {"samples": samples, "first_result_seconds_min": min(firsts),
            "first_result_seconds_median": statistics.median(firsts)}


def measure_startup(project_root: Path, warm_runs: int = 3, empty_cache: bool = True) -> dict:
    """Return the startup figures described in the module docstring."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT")}
    package = project_root / "rnsca"
    result = {"child_code": CHILD_CODE, "clock": "time.monotonic (system-wide on Linux)"}
    result["interpreter"] = _spawn(env, project_root, "pass")
    seen = _cache_index_files(package)
    first = _spawn(env, project_root)
    result["project_cache"] = {"cache_index_files_before": seen,
                               "cache_index_files_after": _cache_index_files(package),
                               **first}
    result["warm"] = _series([_spawn(env, project_root) for _ in range(warm_runs)])
    if empty_cache:
        with tempfile.TemporaryDirectory(prefix="rnsca-numba-cache-") as cache:
            cold_env = {**env, "NUMBA_CACHE_DIR": cache}
            cold = _spawn(cold_env, project_root)
            second = _spawn(cold_env, project_root)
        result["empty_cache"] = {"cold": cold, "second": second}
    else:
        result["empty_cache"] = None
    return result
