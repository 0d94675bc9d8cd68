"""Pure ASGI middleware: the request body limit, gzip request bodies, the access log."""

from __future__ import annotations

import logging
import time
import zlib

from starlette.types import ASGIApp, Receive, Scope, Send

from service.errors import (
    BodyTooLargeError,
    InvalidBodyError,
    UnsupportedMediaTypeError,
    problem_bytes,
)
from service.logs import ACCESS_LOGGER
from service.metrics import Metrics

__all__ = ["BodyLimitMiddleware", "InflateMiddleware", "AccessMiddleware", "send_problem",
           "STREAMED_PATHS", "INFLATED_PIECE_BYTES"]

_access = logging.getLogger(ACCESS_LOGGER)

#: Endpoints that read their body as a stream, a chunk at a time: no limit on the body's
#: length applies to them (their memory is bounded by the chunk, `service.admission`).
STREAMED_PATHS = frozenset({"/v1/clip/geojson-seq"})
#: A gzip body of a streamed endpoint reaches it inflated in pieces of at most this many
#: bytes, however much one piece of the compressed body inflates to.
INFLATED_PIECE_BYTES = 1 << 20


async def send_problem(send: Send, status: int, slug: str, title: str, detail: str,
                       instance: str, headers: dict | None = None,
                       **extensions: object) -> None:
    """Answer with a problem document from pure ASGI middleware, and close the connection.

    The body is left unread: closing the connection is the only way to be done with it.
    """
    body = problem_bytes(status, slug, title, detail, instance=instance, **extensions)
    extra = [(name.lower().encode("latin-1"), str(value).encode("latin-1"))
             for name, value in (headers or {}).items() if name.lower() != "connection"]
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/problem+json"),
                            (b"content-length", str(len(body)).encode()),
                            (b"connection", b"close"), *extra]})
    await send({"type": "http.response.body", "body": body})


class _BodyMiddleware:
    """A middleware over request bodies, bounded by `max_bytes`."""

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes


class BodyLimitMiddleware(_BodyMiddleware):
    """Refuse bodies over `max_bytes` with 413, before the application reads them whole.

    A ``Content-Length`` over the limit is refused at once, unread. A body without one
    (chunked) is counted as it arrives and refused at the first chunk past the limit:
    `BodyTooLargeError` is raised from ``receive`` inside the route, where the service's
    handler answers it (and, should the response not have started otherwise, here).
    Bodies of the `STREAMED_PATHS` are not limited.
    """

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:  # noqa: D102
        if scope["type"] != "http" or scope.get("path") in STREAMED_PATHS:
            return await self.app(scope, receive, send)
        limit = self.max_bytes
        for name, value in scope["headers"]:
            if name == b"content-length" and value.isdigit() and int(value) > limit:
                return await send_problem(
                    send, 413, BodyTooLargeError.slug, BodyTooLargeError.title,
                    f"the body has {int(value)} bytes, more than this server's limit of "
                    f"{limit}", scope["path"], limit=limit)
        received = 0
        started = False

        async def limited_receive():
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    raise BodyTooLargeError(
                        f"the body is longer than this server's limit of {limit} bytes",
                        headers={"Connection": "close"}, limit=limit)
            return message

        async def tracking_send(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except BodyTooLargeError as exc:
            if started:
                raise
            await send_problem(send, 413, exc.slug, exc.title, exc.detail, scope["path"],
                                limit=limit)


class InflateMiddleware(_BodyMiddleware):
    """Read ``Content-Encoding: gzip`` request bodies, inflated as they arrive, bounded.

    The inflated body counts against the same `max_bytes` as a plain one
    (`BodyLimitMiddleware` has already bounded the compressed bytes): inflation stops at
    the first byte past the limit, so a small "gzip bomb" costs no more than the limit
    to refuse (413). Broken or truncated gzip data is 422; another encoding is 415. The
    application sees a plain body: the encoding and length headers are taken away.

    A body of the `STREAMED_PATHS` has no limit on its length; it is inflated as the
    endpoint reads it, in pieces of at most `INFLATED_PIECE_BYTES`, so that one small
    piece of compressed body never inflates into more memory than that.
    """

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:  # noqa: D102
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        encoding = b"identity"
        for name, value in scope["headers"]:
            if name == b"content-encoding":
                encoding = value.strip().lower()
        if encoding == b"identity":
            return await self.app(scope, receive, send)
        if encoding not in (b"gzip", b"x-gzip"):
            # Answered here: outside the application, its exception handlers cannot.
            return await send_problem(
                send, 415, UnsupportedMediaTypeError.slug, UnsupportedMediaTypeError.title,
                f"request bodies may be sent with Content-Encoding gzip (or none), got "
                f"{encoding.decode('latin-1')!r}", scope["path"])
        headers = [(name, value) for name, value in scope["headers"]
                   if name not in (b"content-encoding", b"content-length")]
        scope = {**scope, "headers": headers}
        if scope.get("path") in STREAMED_PATHS:
            return await self.app(scope, _inflating_in_pieces(receive), send)
        limit = self.max_bytes
        inflater = _gzip_inflater()
        inflated = 0

        def inflate(data: bytes) -> bytes:
            nonlocal inflater, inflated
            parts = []
            while True:
                try:
                    # Never more than one byte past the limit, whatever the ratio.
                    part = inflater.decompress(data, limit - inflated + 1)
                except zlib.error as exc:
                    raise InvalidBodyError(
                        f"the gzip request body cannot be inflated: {exc}") from None
                inflated += len(part)
                parts.append(part)
                if inflated > limit or inflater.unconsumed_tail:
                    raise BodyTooLargeError(
                        f"the gzip body inflates to more than this server's limit of {limit} "
                        "bytes", headers={"Connection": "close"}, limit=limit)
                if not (inflater.eof and inflater.unused_data):
                    return b"".join(parts)
                # A gzip file may hold several members one after another (RFC 1952).
                data = inflater.unused_data
                inflater = _gzip_inflater()

        async def inflating_receive():
            message = await receive()
            if message["type"] != "http.request":
                return message
            body = inflate(message.get("body", b""))
            if not message.get("more_body", False) and not inflater.eof:
                raise InvalidBodyError("the gzip request body is truncated")
            return {**message, "body": body}

        await self.app(scope, inflating_receive, send)


def _gzip_inflater():  # gzip framing only
    return zlib.decompressobj(wbits=16 + zlib.MAX_WBITS)


def _inflating_in_pieces(receive: Receive) -> Receive:
    """Return a ``receive`` giving the gzip body of `receive` inflated, a piece at a time.

    Each message holds at most `INFLATED_PIECE_BYTES`; compressed input not inflated yet
    waits for the next call. Members of a multi-member gzip body follow one another.
    """
    inflater = _gzip_inflater()
    tail = b""          # compressed bytes not inflated yet
    last = False        # whether `receive` has given the body's last message
    done = False        # whether the last inflated message has been given

    async def inflating_receive():
        nonlocal inflater, tail, last, done
        while not done:
            if tail:
                try:
                    part = inflater.decompress(tail, INFLATED_PIECE_BYTES)
                except zlib.error as exc:
                    raise InvalidBodyError(
                        f"the gzip request body cannot be inflated: {exc}") from None
                if inflater.eof:
                    tail = inflater.unused_data
                    if tail:  # another gzip member follows (RFC 1952)
                        inflater = _gzip_inflater()
                else:
                    tail = inflater.unconsumed_tail
                if part:
                    return {"type": "http.request", "body": part,
                            "more_body": bool(tail) or not last}
                continue
            if last:
                if not inflater.eof:
                    raise InvalidBodyError("the gzip request body is truncated")
                done = True
                return {"type": "http.request", "body": b"", "more_body": False}
            message = await receive()
            if message["type"] != "http.request":
                return message
            tail = message.get("body", b"")
            last = not message.get("more_body", False)
        return await receive()

    return inflating_receive


class AccessMiddleware:
    """Log one JSON line per request and count it in the metrics.

    The line has ``method``, ``path``, ``route`` (the matched template), ``status``,
    ``duration_ms``, ``request_bytes`` and ``response_bytes`` (as sent, so after gzip).
    """

    def __init__(self, app: ASGIApp, metrics: Metrics) -> None:
        self.app = app
        self.metrics = metrics

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:  # noqa: D102
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        started = time.perf_counter()
        status, request_bytes, response_bytes = 500, 0, 0

        async def counting_receive():
            nonlocal request_bytes
            message = await receive()
            if message["type"] == "http.request":
                request_bytes += len(message.get("body", b""))
            return message

        async def counting_send(message):
            nonlocal status, response_bytes
            if message["type"] == "http.response.start":
                status = message["status"]
            elif message["type"] == "http.response.body":
                response_bytes += len(message.get("body", b""))
            await send(message)

        try:
            await self.app(scope, counting_receive, counting_send)
        finally:
            seconds = time.perf_counter() - started
            route = scope.get("route")
            template = getattr(route, "path", None) or "<unmatched>"
            self.metrics.observe_request(scope["method"], template, status, seconds)
            _access.info("request", extra={"fields": {
                "method": scope["method"], "path": scope["path"], "route": template,
                "status": status, "duration_ms": round(seconds * 1000, 3),
                "request_bytes": request_bytes, "response_bytes": response_bytes}})
