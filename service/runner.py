"""Where clipping runs: a thread pool off the event loop, safe for Numba's parallel kernels.

The kernels release the GIL (``nogil=True``), so requests clipped in different threads run
in parallel while the event loop keeps answering (`/healthz` included). Numba's parallel
kernels need a threading layer that accepts concurrent callers: the default ``workqueue``
layer aborts the process when two threads enter ``parallel=True`` code at once. So
`ClipRunner.prepare` selects a thread-safe layer before any parallel kernel runs (``tbb``
or ``omp``, by `Settings.threading_layer`, unless ``NUMBA_THREADING_LAYER`` is set), and
after warm-up reads back the layer that was actually loaded: if it is ``workqueue`` (no
TBB and no OpenMP runtime here, or the process had already started it), every call is
serialized by a lock instead. `/v1/capabilities` reports which.
"""

from __future__ import annotations

import asyncio
import gc
import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from concurrent.futures import TimeoutError as FutureTimeout
from contextlib import nullcontext
from typing import Any, TypeVar

from rnsca.runtime import numba_threads_started
from service.admission import current_reservation
from service.errors import NotReadyError, RequestTimeoutError, TimeLimitError
from service.warmup import COLD_SECONDS, Step, compile_step, step_lock

__all__ = ["ClipRunner"]

_log = logging.getLogger("rnsca.service")
_T = TypeVar("_T")

#: The cyclic collector's thresholds once warm (see `ClipRunner.warm_up`).
GC_THRESHOLDS = (100_000, 50, 1000)
#: Layers that accept concurrent callers (Numba's own classification).
THREAD_SAFE_LAYERS = ("tbb", "omp")


class ClipRunner:
    """Run library calls in a bounded thread pool, with a time limit per request.

    Parameters
    ----------
    threads : int
        Calls that run at once; later ones wait in the pool's queue.
    time_limit : float
        Seconds a call may wait and run before the request is answered with 503 (the call
        itself finishes in the background: threads cannot be interrupted).
    """

    def __init__(self, threads: int, time_limit: float) -> None:
        self._threads = threads
        self._pool: ThreadPoolExecutor | None = None
        self.time_limit = time_limit
        self.ready = threading.Event()
        # Set while `start` warms up: requests meanwhile get 503 at once, not after a wait.
        self.warming = False
        self.threading_layer: str | None = None
        self.warm_up_seconds: float | None = None
        self.failure: str | None = None
        # Warm-up's progress: the steps done, and the endpoints served before `ready`.
        self._done: set[str] = set()
        self._endpoint_steps: dict[str, set[str]] = {}
        self.served: frozenset[str] = frozenset()
        # One call at a time until the loaded threading layer is known to be thread-safe.
        self._serial: threading.Lock | None = threading.Lock()
        self._settled = False

    @property
    def serialized(self) -> bool:
        """Whether calls run one at a time (the loaded threading layer is not thread-safe)."""
        return self._serial is not None

    def prepare(self, layer: str) -> None:
        """Ask Numba for threading layer `layer` unless its layer is already started."""
        import numba

        if "NUMBA_THREADING_LAYER" in os.environ or numba_threads_started():
            return
        numba.config.THREADING_LAYER = layer

    def warm_up(self, steps: Sequence[Step], endpoints: Mapping[str, Sequence[str]],
                processes: int = 0) -> None:
        """Run each warm-up step; serve each endpoint of `endpoints` once its steps are done.

        Runs in a pool thread at start-up. The first step runs in a thread of its own; if
        it is not done within `service.warmup.COLD_SECONDS`, the kernel cache is cold, and
        the other steps are compiled meanwhile in up to `processes` child processes, each
        loaded here as its child finishes (see `service.warmup`). Then settles how calls
        may overlap, and sets `ready`.
        """
        started = time.perf_counter()
        self._endpoint_steps = {name: set(needs) for name, needs in endpoints.items()}
        self._serve_ready_endpoints()
        pending = list(steps)
        if pending:
            with ThreadPoolExecutor(1, thread_name_prefix="rnsca-warm-up") as alone:
                first = alone.submit(self._run_step, pending.pop(0))
                try:
                    first.result(timeout=COLD_SECONDS)
                    cold = False
                except FutureTimeout:  # still compiling (or waiting for another worker)
                    cold = not _jit_disabled()
                if cold and processes > 0 and pending:
                    # The children start now, beside the first step: on a cold start the
                    # other cores would otherwise idle through it (measured: 17 s).
                    _log.info("the kernel cache is cold: compiling in child processes",
                              extra={"fields": {"processes": min(processes, len(pending)),
                                                "steps": [s.name for s in pending]}})
                    self._compile_in_children(pending, processes, first)
                    pending = []
                first.result()
        for step in pending:
            self._run_step(step)
        self.settle()
        # What start-up and warm-up made lives as long as the process: out of the cyclic
        # collector's sight, its full collections stop walking it (they were the long
        # tail of request latencies under load).
        gc.collect()
        gc.freeze()
        # Collections are rarer too: a large request makes a million objects (its parsed
        # JSON), freed by reference counting, and the collections they trigger each walk
        # every object of the requests in flight with the GIL held. `/healthz` while 50
        # GeoJSON requests of 8.3 MB ran (benchmarks.load): p99 113 ms with the default
        # thresholds (700, 10, 10), 60 ms with these, 52 ms with the collector off.
        gc.set_threshold(*GC_THRESHOLDS)
        self.warm_up_seconds = time.perf_counter() - started
        self.ready.set()
        _log.info("kernels ready", extra={"fields": {
            "warm_up_seconds": round(self.warm_up_seconds, 3),
            "threading_layer": self.threading_layer, "serialized": self.serialized}})

    def _run_step(self, step: Step) -> float:
        """Run `step` here under its lock, log it, serve what it completes.

        Returns the seconds it took, waiting for its lock included.
        """
        # One line before and one after each step: a cold start compiles for minutes,
        # and the log says what it is doing.
        _log.info("warming up", extra={"fields": {"step": step.name}})
        asked = time.perf_counter()
        with step_lock(step.name), self._serial or nullcontext():
            step_started = time.perf_counter()
            step.run()
            seconds = time.perf_counter() - step_started
        if not self._settled:  # the first step has run a parallel kernel: which layer?
            self.settle()
        waited = step_started - asked
        _log.info("warmed up", extra={"fields": {"step": step.name,
                                                 "seconds": round(seconds, 3),
                                                 "waited_seconds": round(waited, 3)}})
        self._done.add(step.name)
        self._serve_ready_endpoints()
        # A long wait for the step's lock means another process was compiling it: the
        # cache is cold for this worker too.
        return seconds + waited

    def _compile_in_children(self, steps: Sequence[Step], processes: int,
                             first: Future) -> None:
        """Compile `steps` in child processes; load each here as soon as its child is done.

        At most `processes` children run at once, each on the first of `steps` (in order)
        whose `needs` are compiled: a child never sits waiting for another's lock while a
        step it could compile is left. Loading waits for `first` (the step running here),
        so one step at a time is run and recorded in this process.
        """
        names = {step.name for step in steps}
        compiled = {need for step in steps for need in step.needs if need not in names}
        waiting = list(steps)
        running: dict[Future, Step] = {}
        finished_steps: list[Step] = []
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=min(processes, len(steps)),
                                 mp_context=context) as pool:

            def start_ready() -> None:
                while waiting and len(running) < processes:
                    ready = next((s for s in waiting if set(s.needs) <= compiled), None)
                    if ready is None:
                        return
                    waiting.remove(ready)
                    running[pool.submit(compile_step, ready.name)] = ready

            start_ready()
            while running:
                done, _ = wait([*running, *([] if first.done() else [first])],
                               return_when=FIRST_COMPLETED)
                for future in done - {first}:
                    step = running.pop(future)
                    if (error := future.exception()) is not None:  # compiled here instead
                        _log.warning("compiling in a child process failed",
                                     extra={"fields": {"step": step.name,
                                                       "error": repr(error)}})
                    compiled.add(step.name)
                    finished_steps.append(step)
                start_ready()
                if first.done():
                    while finished_steps:
                        self._run_step(finished_steps.pop(0))
            wait([first])
            for step in finished_steps:
                self._run_step(step)

    def _serve_ready_endpoints(self) -> None:
        for name, needs in self._endpoint_steps.items():
            if name not in self.served and needs <= self._done:
                # A new set, not changed in place: the event loop reads it meanwhile.
                self.served = self.served | {name}
                _log.info("serving", extra={"fields": {"endpoint": name}})

    def endpoint_ready(self, endpoint: str) -> bool:
        """Whether requests to `endpoint` are served (its kernels are warm, or all are)."""
        return self.ready.is_set() or endpoint in self.served

    def settle(self) -> None:
        """Read the threading layer that runs; serialize calls unless it is thread-safe."""
        import numba

        if numba.config.DISABLE_JIT:  # plain Python: nothing parallel to protect
            self._serial, self._settled = None, True
            return
        try:
            self.threading_layer = numba.threading_layer()
        except ValueError:  # not started yet: no parallel kernel has run; decide later
            return
        if self.threading_layer not in THREAD_SAFE_LAYERS:
            _log.warning("Numba threading layer %r is not thread-safe: clipping calls are "
                         "serialized", self.threading_layer)
        self._serial = None if self.threading_layer in THREAD_SAFE_LAYERS else self._serial
        self._settled = True

    async def start(self, steps: Sequence[Step], endpoints: Mapping[str, Sequence[str]],
                    processes: int = 0) -> None:
        """Warm up in the pool, off the event loop (so `/healthz` answers meanwhile)."""
        loop = asyncio.get_running_loop()
        self.warming = True
        try:
            # Not through `_call`: each step takes the serializing lock itself, so the
            # endpoints served early are not held up behind the whole warm-up.
            await loop.run_in_executor(self._executor(), self.warm_up, steps, endpoints,
                                       processes)
        except Exception as exc:  # reported by /readyz; the process keeps answering
            self.failure = f"{type(exc).__name__}: {exc}"
            _log.error("warming up the kernels failed", exc_info=exc)
        finally:
            self.warming = False

    async def read_body(self, request: Any) -> tuple[bytes, float]:
        """Return the request's body and the time the request has left, within the limit.

        The time limit runs from here, so it covers reading the body: a client that sends
        slowly (or not at all) gets `RequestTimeoutError` (408) and the connection closed.
        """
        started = time.monotonic()
        try:
            body = await asyncio.wait_for(request.body(), self.time_limit)
        except TimeoutError:
            raise RequestTimeoutError(
                f"the request body did not arrive within the time limit of "
                f"{self.time_limit:g} s", headers={"Connection": "close"}) from None
        return body, self.time_limit - (time.monotonic() - started)

    async def run(self, function: Callable[..., _T], *args: Any,
                  time_left: float | None = None, endpoint: str | None = None) -> _T:
        """Return ``function(*args)`` run in the pool; raise `TimeLimitError` past the limit.

        `time_left` is what is left of the request's limit after reading its body
        (`read_body`); by default the whole limit.

        While the kernels of `endpoint` (all of them, if None) warm up, raise
        `NotReadyError` (503, ``Retry-After``) at once: a request would otherwise wait
        behind the compilation and time out.
        """
        if self.warming and not (self.ready.is_set() if endpoint is None
                                 else self.endpoint_ready(endpoint)):
            raise NotReadyError(
                f"the server is compiling or loading the kernels "
                f"{'it needs' if endpoint is None else 'of ' + endpoint} (see /readyz); "
                "retry shortly", headers={"Retry-After": "2"},
                served=sorted(self.served))
        loop = asyncio.get_running_loop()
        # The request's memory stays reserved until the thread is done with it, even
        # if the request is answered first (past its time limit).
        reservation = current_reservation.get()
        if reservation is not None:
            reservation.hold()
        future = loop.run_in_executor(self._executor(), self._call, function, args,
                                      reservation)
        try:
            return await asyncio.wait_for(
                future, self.time_limit if time_left is None else max(time_left, 0.001))
        except TimeoutError:
            raise TimeLimitError(
                f"the request did not finish within the time limit of {self.time_limit:g} s "
                "(the server is busy); retry later",
                headers={"Retry-After": str(max(1, round(self.time_limit / 2)))}) from None

    def _call(self, function, args, reservation=None):
        try:
            with self._serial or nullcontext():
                try:
                    return function(*args)
                finally:
                    if not self._settled:
                        self.settle()
        finally:
            if reservation is not None:
                reservation.release()

    def _executor(self) -> ThreadPoolExecutor:
        # Made on first use, so an app whose lifespan ends and starts again (test clients
        # do that) gets a new pool instead of a closed one.
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=self._threads,
                                            thread_name_prefix="rnsca-clip")
        return self._pool

    def shutdown(self) -> None:
        """Wait for running calls to finish, then stop the threads."""
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=False)


def _jit_disabled() -> bool:
    import numba

    return bool(numba.config.DISABLE_JIT)
