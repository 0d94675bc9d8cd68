"""The jit presets every kernel uses.

``scalar`` is for small per-primitive functions that LLVM inlines into the drivers;
``parallel`` is for drivers that ``prange`` over blocks of primitives. All presets cache
to disk (a second process loads instead of compiling), release the GIL (the service
runs kernels from a thread pool), and use NumPy's error model so a division does not
carry a Python-style zero check (every division in the kernels is guarded where it
matters). Under ``NUMBA_DISABLE_JIT=1`` each becomes the plain Python function.

Two presets serve the inner loops of line and ring clipping, where calls are many and
cheap. Numba increments the reference count of every array a function receives when
the function starts, and decrements it when it returns: two atomic operations per
array per call. A helper with ten array arguments called once per run of 16 segments
spent more on those than on its work (the curve workload's line clip: 1.2 ms on one
thread before, 0.58 ms after; see benchmarks/README.md). So:

``borrowing`` compiles without reference counting (Numba's ``_nrt=False``): the
function borrows the arrays its caller holds, for as long as the call lasts. It must
not allocate an array (``np.empty`` and the like need the runtime) nor keep or return
a view of an argument beyond the call; slicing arguments inside it is fine.

``inlined`` is for tiny helpers taking arrays that run per run or per segment: Numba
inlines them into each caller before compiling.
"""

import os

# Numba's OpenMP layer spins its idle threads by default; on a loaded machine (the
# service beside other work, CI) that made parallel calls 5x slower than one thread
# (measured: 23.8 ms vs 4.8 ms, see benchmarks/README.md). Passive waiting costs nothing
# measurable on an idle machine. A value the user set is kept. Must precede OpenMP's start.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numba  # noqa: E402

__all__ = ["scalar", "parallel", "borrowing", "inlined"]

scalar = numba.njit(cache=True, nogil=True, error_model="numpy")
parallel = numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
inlined = numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
borrowing = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
