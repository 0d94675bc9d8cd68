"""The two jit presets every kernel uses.

``scalar`` is for small per-primitive functions that LLVM inlines into the drivers;
``parallel`` is for drivers that ``prange`` over blocks of primitives. Both cache to
disk (a second process loads instead of compiling), release the GIL (the service runs
kernels from a thread pool), and use NumPy's error model so a division does not carry a
Python-style zero check (every division in the kernels is guarded where it matters).
Under ``NUMBA_DISABLE_JIT=1`` both become the plain Python function.
"""

import numba

__all__ = ["scalar", "parallel"]

scalar = numba.njit(cache=True, nogil=True, error_model="numpy")
parallel = numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
