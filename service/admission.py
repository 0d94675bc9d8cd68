"""Admission by memory: requests in flight stay within a budget; the excess gets 503.

A clip's peak memory grows with its body: parsed JSON is Python objects (a position of
two floats is about 120 bytes against some 36 bytes of text), then come the arrays, the
clipped arrays and the answer. `PEAK_BYTES_PER_BODY_BYTE` holds the measured ratio of
peak memory to body size per kind of request (`python -m benchmarks.memory`); a request
reserves ``BASE_BYTES`` plus its body times that ratio before its body is read (from
``Content-Length``; a body without one reserves as it arrives). A request whose
reservation does not fit next to those in flight is answered 503 with ``Retry-After`` at
once, its body unread; one that could never fit, even alone, is 413.

A streamed body (``POST /v1/clip/geojson-seq``) is clipped a chunk at a time: it reserves
what a JSON body of its largest chunk would, ``stream_bytes``
(`Settings.stream_chunk_bytes` or `Settings.stream_max_record_bytes`, the larger),
whatever its length.

The reservation lasts until the clip's thread has finished with the request, not only
until the answer is sent: a request answered 503 past its time limit still runs in its
thread (threads cannot be stopped), and its memory is still in use.
"""

from __future__ import annotations

import threading
from contextvars import ContextVar

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import ServiceError
from service.middleware import STREAMED_PATHS, send_problem

__all__ = ["MemoryBudget", "Reservation", "AdmissionMiddleware", "OverMemoryBudgetError",
           "MemoryBudgetFullError", "PEAK_BYTES_PER_BODY_BYTE", "BASE_BYTES",
           "current_reservation", "estimate_bytes"]

#: Peak memory of a request over its body's size, by endpoint and body media type,
#: measured with ``python -m benchmarks.memory`` on 1M-vertex bodies (verification as the
#: service does it by default at that size: none) and rounded up: GeoJSON lines 21.4,
#: polygons 17.8, SVG cubics 22.2, JSON segments 16.1, binary segments 8.2. Verification
#: asked for explicitly can take more: ``verify: "all"`` measured 31 for segments.
#: GeoArrow streams (`application/vnd.apache.arrow.stream`) are their buffers, so the ratio
#: is low: 3.1 lines (interleaved), 3.7 polygons (separated), 5.9 WKB lines as the
#: benchmark sends them (a quarter of the vertices inside the window); with every vertex
#: inside (the answer as large as the body) 5.5, 7.7 and 8.8.
PEAK_BYTES_PER_BODY_BYTE = {
    ("geojson", "json"): 24.0,
    ("svg", "json"): 24.0,
    ("segments", "json"): 18.0,
    ("segments", "binary"): 10.0,
    ("geoarrow", "arrow"): 12.0,
}
#: Memory a request costs whatever its size (buffers, response, Shapely's verification
#: on by default for small inputs): measured 7-13 MB of peak growth for 0.3-0.5 MB bodies.
BASE_BYTES = 16 << 20


class OverMemoryBudgetError(ServiceError):
    """The request would need more memory than the whole budget: it can never be served."""

    status, slug, title = 413, "over-memory-budget", "Request needs too much memory"


class MemoryBudgetFullError(ServiceError):
    """The requests in flight hold the memory budget; this one may be sent again later."""

    status, slug, title = 503, "memory-budget-full", "Server busy"


def estimate_bytes(endpoint: str, media: str, body_bytes: int) -> int:
    """Return the peak memory expected of a request with a body of `body_bytes`."""
    ratio = PEAK_BYTES_PER_BODY_BYTE[(endpoint, media)]
    return BASE_BYTES + int(ratio * body_bytes)


class Reservation:
    """Memory held for one request, released when its last holder lets go."""

    def __init__(self, budget: MemoryBudget) -> None:
        self._budget = budget
        self.nbytes = 0
        self._holders = 1

    def grow(self, nbytes: int) -> bool:
        """Reserve `nbytes` more; return False (reserving nothing) if they do not fit."""
        if not self._budget.take(nbytes):
            return False
        self.nbytes += nbytes
        return True

    def hold(self) -> None:
        """Add a holder (a thread that works for the request); `release` once each."""
        with self._budget.lock:
            self._holders += 1

    def release(self) -> None:
        """Let go of the memory once every holder has released it."""
        with self._budget.lock:
            self._holders -= 1
            if self._holders == 0:
                self._budget.in_use -= self.nbytes
                self.nbytes = 0


class MemoryBudget:
    """The memory that requests in flight may use, in bytes, shared by the process."""

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self.in_use = 0
        self.lock = threading.Lock()

    def take(self, nbytes: int) -> bool:
        """Reserve `nbytes` if they fit beside what is in use; return whether they did."""
        with self.lock:
            if self.in_use + nbytes > self.capacity:
                return False
            self.in_use += nbytes
            return True


#: The reservation of the request being handled (read by `ClipRunner.run`, which holds
#: it until the clip's thread is done).
current_reservation: ContextVar[Reservation | None] = ContextVar("current_reservation",
                                                                  default=None)

_ENDPOINTS = {"/v1/clip/geojson": "geojson", "/v1/clip/svg": "svg",
              "/v1/clip/segments": "segments", "/v1/clip/geoarrow": "geoarrow"}
#: Body media types with a ratio of their own (any other is reserved as JSON).
_MEDIA = {b"application/octet-stream": "binary",
          b"application/vnd.apache.arrow.stream": "arrow"}


class AdmissionMiddleware:
    """Reserve each clip request's memory from `budget` before its body is read.

    A request to one of the `STREAMED_PATHS` reserves that of a GeoJSON body of
    `stream_bytes` (its largest chunk), its body's length aside.
    """

    def __init__(self, app: ASGIApp, budget: MemoryBudget, retry_after: int = 1,
                 stream_bytes: int = 8 << 20) -> None:
        self.app = app
        self.budget = budget
        self.retry_after = retry_after
        self.stream_bytes = stream_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:  # noqa: D102
        path = scope.get("path", "") if scope["type"] == "http" else None
        if path in STREAMED_PATHS and scope["method"] == "POST":
            return await self._streamed(scope, receive, send)
        endpoint = _ENDPOINTS.get(path or "")
        if endpoint is None or scope["method"] != "POST":
            return await self.app(scope, receive, send)
        length = None
        media = "json"
        for name, value in scope["headers"]:
            if name == b"content-length" and value.isdigit():
                length = int(value)
            elif name == b"content-type":
                media = _MEDIA.get(value.split(b";")[0].strip().lower(), "json")
        if (endpoint, media) not in PEAK_BYTES_PER_BODY_BYTE:
            # The route refuses the media type itself (geoarrow: every body is reserved
            # at its own ratio, the highest).
            media = "arrow" if endpoint == "geoarrow" else "json"
        reservation = Reservation(self.budget)
        token = current_reservation.set(reservation)
        try:
            try:
                self._reserve(reservation, estimate_bytes(endpoint, media, length or 0))
            except ServiceError as exc:  # outside the app: its handlers cannot answer
                return await send_problem(send, exc.status, exc.slug, exc.title, exc.detail,
                                          scope["path"], exc.headers, **exc.extensions)
            ratio = PEAK_BYTES_PER_BODY_BYTE[(endpoint, media)]

            async def reserving_receive() -> Message:
                message = await receive()
                if length is None and message["type"] == "http.request":
                    self._reserve(reservation, int(ratio * len(message.get("body", b""))))
                return message

            await self.app(scope, reserving_receive if length is None else receive, send)
        finally:
            current_reservation.reset(token)
            reservation.release()

    async def _streamed(self, scope: Scope, receive: Receive, send: Send) -> None:
        reservation = Reservation(self.budget)
        token = current_reservation.set(reservation)
        try:
            try:
                self._reserve(reservation,
                              estimate_bytes("geojson", "json", self.stream_bytes))
            except ServiceError as exc:
                return await send_problem(send, exc.status, exc.slug, exc.title, exc.detail,
                                          scope["path"], exc.headers, **exc.extensions)
            await self.app(scope, receive, send)
        finally:
            current_reservation.reset(token)
            reservation.release()

    def _reserve(self, reservation: Reservation, nbytes: int) -> None:
        if reservation.nbytes + nbytes > self.budget.capacity:
            raise OverMemoryBudgetError(
                f"the request needs about {(reservation.nbytes + nbytes) / 2**20:.0f} MiB of "
                f"memory, more than this server's budget of "
                f"{self.budget.capacity / 2**20:.0f} MiB; send a smaller body",
                headers={"Connection": "close"}, budget_bytes=self.budget.capacity)
        if not reservation.grow(nbytes):
            raise MemoryBudgetFullError(
                f"the requests in flight hold this server's memory budget "
                f"({self.budget.capacity / 2**20:.0f} MiB); retry shortly",
                headers={"Retry-After": str(self.retry_after), "Connection": "close"})
