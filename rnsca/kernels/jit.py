"""The jit presets every kernel uses.

``scalar`` is for small per-primitive functions that LLVM inlines into the drivers;
``parallel`` is for drivers that ``prange`` over blocks of primitives; ``borrowing`` is
for helpers that take arrays from a driver and allocate none, ``inlined`` for tiny ones
that run per run or per segment (see below). All cache to disk (a second process loads
instead of compiling), release the GIL (the service runs kernels from a thread pool),
and use NumPy's error model so a division does not carry a Python-style zero check
(every division in the kernels is guarded where it matters). Under
``NUMBA_DISABLE_JIT=1`` all become the plain Python function.

``borrowing`` compiles without Numba's runtime (NRT), so the function borrows the arrays
it is given instead of counting references to them. With NRT, a call that is not
inlined increments and decrements the shared reference count of every array argument
(an atomic operation on a cache line both threads write): in the Bézier clip, whose
per-subpath helpers take about 15 arrays, that was half of the time and kept a second
thread from helping (measured: 2.3 -> 0.86 ms on the glyph benchmark, 2 threads); in
the line clip, whose per-run helpers take about ten, the same (the curve workload: 1.2
-> 0.58 ms on one thread); in the polygon clip's ring helpers, 141 -> 99 ms on one thread
for 100,000 polygons with holes. Such a function cannot create or return arrays (Numba
refuses to compile it if it tries), nor keep a view of an argument beyond the call.

``inlined`` helpers are inlined by Numba into each caller before compiling; inside a
``borrowing`` caller they count no references either.

``allocating`` is for helpers that allocate but are called from a ``borrowing`` one. A
function compiled for a ``borrowing`` caller inherits its no-NRT setting unless it sets
its own, so a ``scalar`` helper that allocates cannot be called there; ``allocating``
sets ``_nrt=True`` and keeps Numba's runtime whoever calls it (counting references to
the arrays it is given, once per call). The polygon clip borrows its scratch per polygon
and calls such a helper only to split a walk's loops and for the ring-by-ring fallback
(measured: 100,000 polygons with holes 7% faster than counting references per polygon).

``_nrt`` is a private option of ``numba.njit``, used here and nowhere else;
``tests/unit/kernels/test_jit.py`` fails if a Numba release stops honouring it (then
``borrowing`` functions would count references again, silently slower, or
``allocating`` ones fail to compile under a ``borrowing`` caller).

Every preset compiles one specialisation per argument *type*, not per constant: a call
from another kernel with a constant argument (``f(..., False, ...)``) would by default
compile a separate copy for each constant value (Numba types a constant as a literal),
and the service's cold start paid for each (measured: the line clip's core compiled
three times, 10 s each, on this 2-core machine). `_OneSpecialisation` unliterals the
argument types of such calls. A kernel that needs a literal (dead branches pruned by a
constant, a tuple indexed by one) cannot be written with these presets; none is.

Where a hot function's flags should fold away, the ``*_per_constant`` presets keep
Numba's default (one copy per constant value): the line clip's core
(`polylines.clip_chains`), called with ``write`` and ``break_at_boundary`` constant by the
line clip and by the polygon clip, and the line clip's passes, called with ``write``
constant by its count and write passes (`polylines._line_pass` down to `_line_parts`).
With one copy of each taking the flags as arguments, the lines benchmark was 8-20%
slower (`benchmarks.compare`, four runs); with these copies it is back to 0.98 of
before, and a cold start compiles the copies of the two callers in two processes at
once anyway. Inlining `clip_chains` into two wrappers instead cost 15-19 s of compiling
per copy against 9-10 s. A small hot helper is ``inlined`` instead (`midpoint._search`).

Nothing here changes the process: how idle OpenMP threads wait is the application's
choice (`rnsca.runtime.prefer_passive_openmp_wait`).
"""

import numba
from numba.core import types
from numba.core.registry import CPUDispatcher

__all__ = ["scalar", "parallel", "borrowing", "inlined", "allocating", "scalar_per_constant",
           "parallel_per_constant", "borrowing_per_constant"]


class _OneSpecialisation(CPUDispatcher):
    """A CPU dispatcher that compiles calls from other kernels for unliteral types."""

    def get_call_template(self, args, kws):
        args = tuple(types.unliteral(a) for a in args)
        kws = {k: types.unliteral(v) for k, v in kws.items()}
        return super().get_call_template(args, kws)


def _preset(**options):
    decorate = numba.njit(cache=True, nogil=True, error_model="numpy", **options)

    def preset(function):
        dispatcher = decorate(function)
        if type(dispatcher) is CPUDispatcher:  # not under NUMBA_DISABLE_JIT
            dispatcher.__class__ = _OneSpecialisation
        return dispatcher

    return preset


scalar = _preset()
parallel = _preset(parallel=True)
borrowing = _preset(_nrt=False)
inlined = _preset(inline="always")
allocating = _preset(_nrt=True)
scalar_per_constant = numba.njit(cache=True, nogil=True, error_model="numpy")
parallel_per_constant = numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
borrowing_per_constant = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
