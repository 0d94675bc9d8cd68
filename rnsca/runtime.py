"""Process-wide settings, made only when an application asks: never at import.

The library changes nothing outside its own objects: importing or calling it writes no
environment variable and leaves the garbage collector alone. An application that owns
its process (the ``rnsca`` CLI, the service, the tests and benchmarks) calls
`configure_process` once at start-up, before any kernel runs:

>>> import rnsca.runtime
>>> rnsca.runtime.configure_process()        # doctest: +SKIP

Each setting it makes is also a function of its own, documented below; a value the user
already set in the environment is always kept. `collector_paused` is for an application
that writes very large GeoJSON documents as Python lists, and `numba_threads_started`
reads a private flag of Numba in one place, with a test that fails if Numba drops it.
"""

from __future__ import annotations

import gc
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = [
    "configure_process",
    "register_opencl_drivers",
    "prefer_passive_openmp_wait",
    "collector_paused",
    "numba_threads_started",
]


def configure_process() -> None:
    """Make the process-wide settings an rnsca application wants, at start-up.

    `prefer_passive_openmp_wait` and `register_opencl_drivers`; call it before the first
    kernel runs and before OpenCL is first asked for devices.
    """
    prefer_passive_openmp_wait()
    register_opencl_drivers()


def prefer_passive_openmp_wait() -> None:
    """Let Numba's OpenMP threads sleep while idle (``OMP_WAIT_POLICY=PASSIVE``).

    OpenMP spins its idle threads by default; on a loaded machine (the service beside
    other work, CI) that made parallel calls 5x slower than one thread (measured: 23.8 ms
    vs 4.8 ms, see benchmarks/README.md). Passive waiting costs nothing measurable on an
    idle machine. Takes effect only before OpenMP starts (the first parallel kernel); a
    value the user set is kept.
    """
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


def register_opencl_drivers() -> str | None:
    """Point the OpenCL ICD loader at the drivers this environment installed.

    The development install (Makefile) writes ``<venv>/opencl-vendors``: Intel's CPU
    runtime, whose wheel registers itself under a conda path, for CPUs that PoCL cannot
    build kernels for. The loader reads ``OCL_ICD_VENDORS`` at its first platform query,
    so this must run before OpenCL is first asked for devices; a value the user set is
    kept. Returns the folder used, or None if this environment has none.
    """
    vendors = os.path.join(sys.prefix, "opencl-vendors")
    if not os.path.isdir(vendors):
        return None
    os.environ.setdefault("OCL_ICD_VENDORS", vendors)
    return os.environ["OCL_ICD_VENDORS"]


@contextmanager
def collector_paused() -> Iterator[None]:
    """Pause Python's cyclic garbage collector inside the block; resume it if it ran.

    Writing GeoJSON as nested lists (`rnsca.io.geojson.to_geojson`) allocates a list per
    position beside a large parsed document, which triggers full collections, each
    traversing the whole heap: on a 68 MB FeatureCollection (1.6 M positions) writing
    took 1.9 s with the collector running and 0.37 s with it paused. Nothing the writer
    makes can form a cycle, so reference counting frees it all. The collector is
    process-wide: pause it only where no other thread depends on it (the CLI does; the
    service writes NumPy arrays and needs no pause).
    """
    running = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if running:
            gc.enable()


def numba_threads_started() -> bool:
    """Return whether Numba has started its threading layer (then it can't be changed).

    Reads Numba's private ``numba.np.ufunc.parallel._is_initialized``: there is no public
    query (``numba.threading_layer()`` raises before the start, and does not tell a
    layer that failed). A test checks the flag exists and flips when a parallel kernel
    runs, so a Numba upgrade that drops it fails there, not here.
    """
    from numba.np.ufunc import parallel

    return bool(parallel._is_initialized)
