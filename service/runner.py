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
import os
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from typing import Any, TypeVar

from rnsca.runtime import numba_threads_started
from service.errors import NotReadyError, RequestTimeoutError, TimeLimitError

__all__ = ["ClipRunner"]

_log = logging.getLogger("rnsca.service")
_T = TypeVar("_T")

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

    def warm_up(self, backends: Iterable[object],
                extra: Iterable[Callable[[], object]] = ()) -> None:
        """Compile (or load) the kernels: `backends`, then each warm-up function of `extra`.

        Then settle how calls may overlap. Runs in a pool thread at start-up; sets
        `ready` when done.
        """
        started = time.perf_counter()
        steps = [(f"{type(engine).__name__}.warm_up", engine.warm_up) for engine in backends
                 if hasattr(engine, "warm_up")]
        steps += [(getattr(function, "__name__", repr(function)), function)
                  for function in extra]
        for name, step in steps:
            # One line before and one after each step: a cold start compiles for minutes,
            # and the log says what it is doing.
            _log.info("warming up", extra={"fields": {"step": name}})
            step_started = time.perf_counter()
            step()
            _log.info("warmed up", extra={"fields": {
                "step": name, "seconds": round(time.perf_counter() - step_started, 3)}})
        self.settle()
        # What start-up and warm-up made lives as long as the process: out of the cyclic
        # collector's sight, its full collections stop walking it (they were the long
        # tail of request latencies under load).
        gc.collect()
        gc.freeze()
        self.warm_up_seconds = time.perf_counter() - started
        self.ready.set()
        _log.info("kernels ready", extra={"fields": {
            "warm_up_seconds": round(self.warm_up_seconds, 3),
            "threading_layer": self.threading_layer, "serialized": self.serialized}})

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

    async def start(self, backends: Iterable[object],
                    extra: Iterable[Callable[[], object]] = ()) -> None:
        """Warm up in the pool, off the event loop (so `/healthz` answers meanwhile)."""
        loop = asyncio.get_running_loop()
        self.warming = True
        try:
            await loop.run_in_executor(self._executor(), self._call, self.warm_up,
                                       (backends, extra))
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
                  time_left: float | None = None) -> _T:
        """Return ``function(*args)`` run in the pool; raise `TimeLimitError` past the limit.

        `time_left` is what is left of the request's limit after reading its body
        (`read_body`); by default the whole limit.

        While the kernels warm up, raise `NotReadyError` (503, ``Retry-After``) at once:
        a request would otherwise wait behind the compilation and time out.
        """
        if self.warming and not self.ready.is_set():
            raise NotReadyError(
                "the server is compiling or loading its kernels (see /readyz); retry shortly",
                headers={"Retry-After": "2"})
        loop = asyncio.get_running_loop()
        future = loop.run_in_executor(self._executor(), self._call, function, args)
        try:
            return await asyncio.wait_for(
                future, self.time_limit if time_left is None else max(time_left, 0.001))
        except TimeoutError:
            raise TimeLimitError(
                f"the request did not finish within the time limit of {self.time_limit:g} s "
                "(the server is busy); retry later",
                headers={"Retry-After": str(max(1, round(self.time_limit / 2)))}) from None

    def _call(self, function, args):
        with self._serial or nullcontext():
            try:
                return function(*args)
            finally:
                if not self._settled:
                    self.settle()

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
