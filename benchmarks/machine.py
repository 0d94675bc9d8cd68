"""The machine description stored with every result file."""

from __future__ import annotations

import hashlib
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

__all__ = ["describe_machine", "load_average", "source_digest", "run_header"]

_PACKAGES = ("rnsca", "numba", "llvmlite", "numpy", "shapely", "matplotlib")


def _cpu_model() -> str | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def _memory_bytes() -> int | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def _version(name: str) -> str | None:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def _git(project_root: Path) -> dict:
    def run(*args):
        proc = subprocess.run(["git", *args], cwd=project_root, capture_output=True, text=True,
                              check=False)
        return proc.stdout.strip() if proc.returncode == 0 else None
    status = run("status", "--porcelain", "--", "rnsca")
    return {"commit": run("rev-parse", "HEAD"),
            "rnsca_dirty": None if status is None else bool(status),
            "rnsca_source_sha256": source_digest(project_root)}


def source_digest(project_root: Path) -> str:
    """Return a SHA-256 over the paths and contents of ``rnsca/**/*.py``.

    Taken at the start and the end of a run: if they differ, the library was edited while
    it was being measured (the run's own process keeps what it imported first).
    """
    digest = hashlib.sha256()
    for path in sorted((project_root / "rnsca").rglob("*.py")):
        digest.update(str(path.relative_to(project_root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def load_average() -> list[float] | None:
    """Return the 1, 5 and 15 minute load averages (None where unsupported)."""
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return None


def describe_machine(project_root: Path) -> dict:
    """Return the CPU, cores, memory, Python and library versions, and Numba's threading."""
    import numba

    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = None
    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel has run yet
        layer = None
    return {
        "cpu_model": _cpu_model(),
        "cpu_count": os.cpu_count(),
        "cpus_usable": affinity,
        "memory_bytes": _memory_bytes(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "python_implementation": platform.python_implementation(),
        "versions": {name: _version(name) for name in _PACKAGES},
        "numba_threads": numba.get_num_threads(),
        "numba_threading_layer": layer,
        "load_average_at_start": load_average(),
        "git": _git(project_root),
    }


def run_header(schema: int, stamp: str, quick: bool, machine: dict, project_root: Path) -> dict:
    """Return the keys every suite's JSON starts with: schema, time, machine and load.

    `machine` is `describe_machine` of the run's start; ``rnsca_changed_during_run`` says
    whether the sources differ now (a run whose figures mix two versions).
    """
    digest = source_digest(project_root)
    return {"schema": schema, "created": stamp, "quick": quick, "machine": machine,
            "load_average_at_end": load_average(), "rnsca_source_sha256_at_end": digest,
            "rnsca_changed_during_run": digest != machine["git"]["rnsca_source_sha256"]}
