"""Timing and memory primitives: best-of-repeats, interleaved across contenders.

The machine is shared and noisy, so every comparison is made inside one run, and the
contenders of one workload are timed round-robin (A, B, C, A, B, C, ...) so a burst of
background load hits them all rather than one of them. The reported time is the best
(minimum) sample: noise only ever adds time.
"""

from __future__ import annotations

import gc
import math
import time
import tracemalloc
from collections.abc import Callable
from dataclasses import dataclass, field

__all__ = ["Policy", "Contender", "time_round_robin", "peak_traced_bytes", "full_policy"]


@dataclass(frozen=True)
class Policy:
    """How long and how often to time one contender.

    Attributes
    ----------
    min_sample : float
        A sample runs the call ``number`` times, with ``number`` chosen so one sample
        lasts at least this many seconds (tiny inputs are timed in loops, like timeit).
    budget : float
        Seconds of timing per contender; the repeat count is ``budget / sample time``,
        clamped to ``[min_repeats, max_repeats]``.
    min_repeats, max_repeats : int
        Bounds on the number of samples.
    """

    min_sample: float = 0.05
    budget: float = 3.0
    min_repeats: int = 3
    max_repeats: int = 7


@dataclass
class Contender:
    """One thing to time: a label, a zero-argument call, and its timing state.

    `max_repeats` overrides the policy's (``1`` times it exactly once, for calls that
    take minutes). After `time_round_robin`, `samples` holds seconds per call, `number`
    the calls per sample, and `last` the result of the first call.
    """

    label: str
    call: Callable[[], object]
    max_repeats: int | None = None
    samples: list[float] = field(default_factory=list)
    number: int = 1
    last: object = None

    @property
    def best(self) -> float:
        """Return the best (minimum) seconds per call."""
        return min(self.samples)


def _timed(call: Callable[[], object], number: int) -> tuple[float, object]:
    """Return (seconds per call, the last result) over `number` calls, with GC paused."""
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        result = None
        start = time.perf_counter()
        for _ in range(number):
            result = call()
        elapsed = time.perf_counter() - start
    finally:
        if gc_was_enabled:
            gc.enable()
    return elapsed / number, result


def time_round_robin(contenders: list[Contender], policy: Policy) -> None:
    """Time every contender, interleaved; fill their `samples`, `number` and `last`.

    Each contender must already be compiled (warmed up): the first call here is a
    sample. It also calibrates ``number`` and the repeat count for that contender.
    """
    targets: dict[int, int] = {}
    for k, c in enumerate(contenders):
        first, c.last = _timed(c.call, 1)
        cap = policy.max_repeats if c.max_repeats is None else c.max_repeats
        if first >= policy.min_sample:
            c.number = 1
            c.samples.append(first)
        else:
            c.number = max(1, math.ceil(policy.min_sample / max(first, 1e-7)))
        sample = first * c.number
        wanted = int(policy.budget / max(sample, 1e-9))
        targets[k] = max(min(policy.min_repeats, cap), min(cap, wanted))
    while True:
        pending = [k for k, c in enumerate(contenders) if len(c.samples) < targets[k]]
        if not pending:
            break
        for k in pending:
            c = contenders[k]
            seconds, _ = _timed(c.call, c.number)
            c.samples.append(seconds)


def peak_traced_bytes(call: Callable[[], object]) -> tuple[int, object]:
    """Return (peak bytes allocated during `call` and still or once alive, its result).

    Uses tracemalloc, which sees Python objects and NumPy array buffers (NumPy reports
    its allocations to it). It does not see memory that Numba's runtime allocates inside
    a compiled function, nor GEOS's allocations inside Shapely. The peak includes the
    returned arrays, which the caller receives.
    """
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        before, _ = tracemalloc.get_traced_memory()
        result = call()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak - before, result


def full_policy(n: int) -> Policy:
    """Return the timing policy of a full run for an input of `n` segments."""
    if n >= 10_000_000:
        return Policy(min_sample=0.05, budget=10.0, min_repeats=2, max_repeats=3)
    if n >= 1_000_000:
        return Policy(min_sample=0.05, budget=3.0, min_repeats=3, max_repeats=5)
    return Policy(min_sample=0.05, budget=1.5, min_repeats=3, max_repeats=7)
