"""The jit presets every kernel uses.

``scalar`` is for small per-primitive functions that LLVM inlines into the drivers;
``parallel`` is for drivers that ``prange`` over blocks of primitives; ``inlined`` is
for small helpers that take arrays and run in inner loops: a call that LLVM does not
inline increments and decrements the reference count of every array argument (an
atomic operation each), which cost more than the helper itself (measured: copying an
accepted run of a line cost ~80 ns per call, of which the copy was a fraction). Numba
inlines these into each caller before compiling, so the counts disappear. Both cache to
disk (a second process loads instead of compiling), release the GIL (the service runs
kernels from a thread pool), and use NumPy's error model so a division does not carry a
Python-style zero check (every division in the kernels is guarded where it matters).
Under ``NUMBA_DISABLE_JIT=1`` both become the plain Python function.
"""

import os

# Numba's OpenMP layer spins its idle threads by default; on a loaded machine (the
# service beside other work, CI) that made parallel calls 5x slower than one thread
# (measured: 23.8 ms vs 4.8 ms, see benchmarks/README.md). Passive waiting costs nothing
# measurable on an idle machine. A value the user set is kept. Must precede OpenMP's start.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numba  # noqa: E402

__all__ = ["scalar", "parallel", "inlined"]

scalar = numba.njit(cache=True, nogil=True, error_model="numpy")
parallel = numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
inlined = numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
