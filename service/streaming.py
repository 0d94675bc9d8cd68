"""Streamed GeoJSON (``POST /v1/clip/geojson-seq``): clipped and answered a chunk at a time.

Records are read as the body arrives and answered as soon as their chunk is clipped.

Three parts, each holding a bounded amount:

- `StreamedClip` reads the body's pieces as they arrive (``receive``), cuts them into
  records (`rnsca.io.geojson_seq.RecordSplitter`: at most one unfinished record between
  pieces), gathers the records into chunks (`Settings.stream_chunk_bytes` or
  `Settings.stream_chunk_records`, whichever is reached first; a chunk is also cut when
  the body pauses for `IDLE_FLUSH_SECONDS`, so that records sent slowly are answered as
  they come), and clips each chunk in the clipping pool (`service.convert.clip_records`).
  It reads the next chunk only once the last one is clipped: the body waits in the
  network buffers meanwhile (uvicorn stops reading the socket), and memory holds one
  chunk.
- `Spool` carries the answer from the clipping to the client. A client that reads the
  answer while it sends (curl, browsers' fetch with streams, aiohttp) takes each chunk's
  answer as it comes. One that sends its whole body before it reads (httpx, requests,
  ``urllib``) would otherwise deadlock the connection once the answer fills the socket's
  buffers: the server could not write, so it would stop reading, and the client could
  not finish writing. So what the client has not taken yet waits in the spool: in memory
  up to `Settings.stream_chunk_bytes` (or one chunk's answer, if larger), then in an
  anonymous temporary file, read back as the client reads.
- `SequenceResponse` sends the spool's bytes while `StreamedClip` fills it.

Errors. The first chunk is read and clipped before the answer starts: a problem in it
(or in the options) is answered with its status and an ``application/problem+json``
document, as on the other endpoints, naming the ``record``. Past the first chunk the
status (200) is sent: a problem then ends the answer with the records before the bad one,
then one problem record (an RFC 9457 document, ``type`` ``urn:rnsca:problem:...``, in the
answer's framing) and nothing after it. A client must look at the ``type`` of the last
record (the SDK raises the problem as an exception).
"""

from __future__ import annotations

import asyncio
import logging
import tempfile
from collections import deque
from collections.abc import AsyncIterator
from typing import IO, Any

import anyio
from starlette.requests import ClientDisconnect
from starlette.responses import Response, StreamingResponse
from starlette.types import Receive, Scope, Send

from rnsca.clip_geojson import combine_stats
from rnsca.errors import RnscaError
from rnsca.io.geojson_seq import Framing, RecordSplitter, record_bytes
from rnsca.stats import ClipStats
from rnsca.window import Window
from service import convert
from service.config import Settings
from service.errors import (
    RequestTimeoutError,
    ServiceError,
    problem,
    problem_document,
    problem_fields,
)
from service.metrics import Metrics
from service.runner import ClipRunner
from service.schemas import GeometryOptions

__all__ = ["StreamedClip", "Spool", "SequenceResponse", "refusal", "IDLE_FLUSH_SECONDS",
           "SUMMARY_TYPE"]

_log = logging.getLogger("rnsca.service")

#: A chunk not yet full is clipped when no more of the body arrives for this long.
IDLE_FLUSH_SECONDS = 0.2
#: The ``type`` of the summary record (``summary=true``).
SUMMARY_TYPE = "urn:rnsca:summary"
# Bytes read back from the spool's file per piece sent.
_READ_BACK = 1 << 20
# What `StreamedClip._receive` returns when no piece arrived within its timeout.
_IDLE = object()


class Spool:
    """The bytes of an answer between its producer and the client, in order.

    Up to `memory_bytes` wait in memory (more, for a single piece put while none
    waits); past that, pieces go to an anonymous temporary file and are read back, in
    order, as the client takes them. The file is dropped once read back whole.

    Attributes
    ----------
    peak_memory : int
        The most bytes held in memory at once.
    spilled : int
        Bytes that went through the file.
    """

    def __init__(self, memory_bytes: int) -> None:
        self.memory_bytes = memory_bytes
        self.peak_memory = 0
        self.spilled = 0
        self._blocks: deque[bytes] = deque()
        self._in_memory = 0
        self._file: IO[bytes] | None = None
        self._read_at = 0
        self._write_at = 0
        self._closed = False
        self._changed = asyncio.Event()

    def put(self, data: bytes) -> None:
        """Append `data` to the answer."""
        if not data:
            return
        if self._file is None and (not self._blocks
                                   or self._in_memory + len(data) <= self.memory_bytes):
            self._blocks.append(data)
            self._in_memory += len(data)
            self.peak_memory = max(self.peak_memory, self._in_memory)
        else:
            if self._file is None:
                self._file = tempfile.TemporaryFile(prefix="rnsca-answer-")
            self._file.seek(self._write_at)
            self._file.write(data)
            self._write_at += len(data)
            self.spilled += len(data)
        self._changed.set()

    def close(self) -> None:
        """Mark the answer complete: `get` returns None once all is taken."""
        self._closed = True
        self._changed.set()

    def discard(self) -> None:
        """Drop what is held (the client is gone)."""
        self._blocks.clear()
        self._in_memory = 0
        if self._file is not None:
            self._file.close()
            self._file = None

    async def get(self) -> bytes | None:
        """Return the next bytes of the answer, waiting for them; None at its end."""
        while True:
            if self._blocks:
                data = self._blocks.popleft()
                self._in_memory -= len(data)
                return data
            if self._file is not None:
                self._file.seek(self._read_at)
                data = self._file.read(min(_READ_BACK, self._write_at - self._read_at))
                self._read_at += len(data)
                if self._read_at == self._write_at:  # read back whole: memory again
                    self._file.close()
                    self._file, self._read_at, self._write_at = None, 0, 0
                return data
            if self._closed:
                return None
            self._changed.clear()
            await self._changed.wait()

    async def __aiter__(self) -> AsyncIterator[bytes]:
        """Yield the answer's bytes as they come, until it is complete."""
        while (data := await self.get()) is not None:
            yield data


class StreamedClip:
    """One streamed request: its body read, cut into records, clipped a chunk at a time.

    Parameters
    ----------
    receive : callable
        The request's ASGI ``receive``; nothing else may read it.
    framing, answer_framing : Framing
        How the body's records and the answer's are delimited.
    window, options
        The clip's window and options (the request's query).
    summary : bool
        End the answer with a summary record (`SUMMARY_TYPE`).
    settings, runner, metrics, instance
        The app's; `instance` is the request's path, for problem documents.

    Attributes
    ----------
    records_in, records_out, chunks : int
        Records clipped, records answered, chunks clipped, so far.
    largest_chunk : int
        The most record bytes held in one chunk.
    """

    def __init__(self, receive: Receive, framing: Framing, answer_framing: Framing,
                 window: Window, options: GeometryOptions, summary: bool,
                 settings: Settings, runner: ClipRunner, metrics: Metrics,
                 instance: str) -> None:
        self._receive_message = receive
        self.answer_framing = answer_framing
        self.window = window
        self.options = options
        self.summary = summary
        self.settings = settings
        self.runner = runner
        self.metrics = metrics
        self.instance = instance
        self.splitter = RecordSplitter(framing,
                                       max_record_bytes=settings.stream_max_record_bytes)
        self.spool = Spool(settings.stream_chunk_bytes)
        self.records_in = 0
        self.records_out = 0
        self.chunks = 0
        self.largest_chunk = 0
        self._stats: list[ClipStats] = []
        self._pending: deque[bytes] = deque()   # whole records not in a chunk yet
        self._body_ended = False
        self._failure: RnscaError | ServiceError | None = None  # met while reading
        self._receiving: asyncio.Future | None = None

    @property
    def body_ended(self) -> bool:
        """Whether the whole body has been read."""
        return self._body_ended

    async def start(self) -> None:
        """Read and clip the first chunk (the options are checked even with no record).

        Raises what the first chunk meets (`RnscaError`, `ServiceError`,
        `ClientDisconnect`): the answer has not started, so it is the request's status.
        """
        try:
            chunk = await self._next_chunk()
            await self._clip(chunk or [])
            if self._failure is not None and not self._pending:  # the next record is bad
                raise self._failure
        except BaseException:
            self.close()
            raise

    async def produce(self) -> None:
        """Clip the rest of the body into the spool; close the spool at the end.

        A problem met now ends the answer with a problem record (see the module
        docstring); the client going away ends it silently.
        """
        try:
            while (chunk := await self._next_chunk()) is not None:
                if (error := await self._clip_or_fail(chunk)) is not None:
                    return self._put_problem(error)
            if self._failure is not None:  # met while reading, after the records clipped
                return self._put_problem(self._failure)
            if self.summary:
                self.spool.put(record_bytes(self._summary(), self.answer_framing))
        except (RnscaError, ServiceError) as exc:
            self._put_problem(exc)
        except ClientDisconnect:
            _log.info("client disconnected during a streamed request",
                      extra={"fields": {"path": self.instance, "records": self.records_in}})
        except Exception as exc:  # a bug: answered as the handler would, logged
            _log.error("unhandled error in a streamed request", exc_info=exc)
            self.spool.put(record_bytes(self._problem(
                500, "internal-error", "Internal server error",
                "the server failed on this request; it keeps serving", {}),
                self.answer_framing))
        finally:
            self.close()

    def close(self) -> None:
        """Stop reading the body; mark the answer complete."""
        if self._receiving is not None:
            self._receiving.cancel()
            self._receiving = None
        self.spool.close()

    # --- reading -----------------------------------------------------------------

    async def _next_chunk(self) -> list[bytes] | None:
        """Return the next chunk of whole records, or None once every record is clipped.

        A problem while reading (a record too long, not a sequence, the body not coming)
        ends the chunk before it and is kept in `_failure`, so that the records before it
        are clipped and answered first.
        """
        limit_records = self.settings.stream_chunk_records
        limit_bytes = self.settings.stream_chunk_bytes
        chunk: list[bytes] = []
        size = 0
        while True:
            while self._pending:
                record = self._pending[0]
                if chunk and size + len(record) > limit_bytes:
                    return self._taken(chunk, size)
                chunk.append(self._pending.popleft())
                size += len(record)
                if len(chunk) >= limit_records or size >= limit_bytes:
                    return self._taken(chunk, size)
            if self._body_ended or self._failure is not None:
                return self._taken(chunk, size) if chunk else None
            try:
                piece = await self._receive(IDLE_FLUSH_SECONDS if chunk else
                                            self.runner.time_limit)
                if piece is _IDLE:
                    if chunk:  # the body pauses: answer what has come
                        return self._taken(chunk, size)
                    raise RequestTimeoutError(
                        f"no more of the body arrived within the time limit of "
                        f"{self.runner.time_limit:g} s", headers={"Connection": "close"})
                assert isinstance(piece, bytes)
                self._pending.extend(self.splitter.feed(piece))
                if self.splitter.error is not None:  # after the records just cut
                    raise self.splitter.error
                if self._body_ended:
                    self._pending.extend(self.splitter.finish())
            except (RnscaError, ServiceError) as exc:
                self._failure = exc

    def _taken(self, chunk: list[bytes], size: int) -> list[bytes]:
        self.largest_chunk = max(self.largest_chunk, size)
        return chunk

    async def _receive(self, timeout: float) -> bytes | object:
        """Return the next piece of the body (b"" at its end), or `_IDLE` after `timeout`.

        A receive not answered in time is kept for the next call, not cancelled: the
        piece it brings is not lost.
        """
        if self._receiving is None:
            self._receiving = asyncio.ensure_future(self._receive_message())
        done, _ = await asyncio.wait({self._receiving}, timeout=timeout)
        if not done:
            return _IDLE
        message, self._receiving = self._receiving.result(), None
        if message["type"] == "http.disconnect":
            raise ClientDisconnect()
        if not message.get("more_body", False):
            self._body_ended = True
        return bytes(message.get("body", b""))

    # --- clipping ----------------------------------------------------------------

    async def _clip(self, chunk: list[bytes]) -> None:
        """Clip `chunk` (records numbered from `records_in`), spool its answer."""
        outcome = await self.runner.run(
            convert.clip_records, chunk, self.records_in, self.window, self.options,
            self.answer_framing, self.settings, endpoint="geojson")
        self.metrics.observe_clip(outcome.stats)
        self._stats.append(outcome.stats)
        self.spool.put(outcome.content)
        self.records_in += len(chunk)
        self.records_out += outcome.records_out
        self.chunks += 1

    async def _clip_or_fail(self, chunk: list[bytes]) -> RnscaError | None:
        """Clip `chunk`; return the problem met, having answered the records before it."""
        try:
            await self._clip(chunk)
        except RnscaError as exc:
            record = exc.record
            if record is not None and 0 < record - self.records_in < len(chunk):
                try:
                    await self._clip(chunk[:record - self.records_in])
                except RnscaError:
                    pass  # answered with the first problem alone
            return exc
        return None

    # --- answer records ----------------------------------------------------------

    def _put_problem(self, exc: RnscaError | ServiceError) -> None:
        status, slug, title, detail, extensions = problem_fields(exc)
        self.spool.put(record_bytes(self._problem(status, slug, title, detail, extensions),
                                    self.answer_framing))

    def _problem(self, status: int, slug: str, title: str, detail: str,
                 extensions: dict[str, Any]) -> dict:
        return problem_document(status, slug, title, detail, instance=self.instance,
                                **extensions)

    def _summary(self) -> dict:
        return {"type": SUMMARY_TYPE, "records_in": self.records_in,
                "records_out": self.records_out, "chunks": self.chunks,
                "stats": combine_stats(self._stats).to_dict()}


def refusal(exc: RnscaError | ServiceError, instance: str, body_ended: bool) -> Response:
    """Return the problem response of a stream refused before its answer started.

    The connection is closed after it unless the whole body was read: what is left of
    it would otherwise be read as the next request.
    """
    status, slug, title, detail, extensions = problem_fields(exc)
    headers = dict(getattr(exc, "headers", None) or {})
    if not body_ended:
        headers["Connection"] = "close"
    return problem(status, slug, title, detail, instance=instance, headers=headers,
                   **extensions)


class SequenceResponse(StreamingResponse):
    """The answer of a `StreamedClip`: its spool sent while it clips the rest of the body.

    Not `StreamingResponse`'s own ``__call__``: that one reads ``receive`` to watch for
    the client leaving, and ``receive`` is the body the clip reads. The clip sees the
    client leave itself (``http.disconnect``); a server whose ``send`` raises `OSError`
    once the client is gone stops the clip too, and the answer ends with a log line.
    """

    def __init__(self, clip: StreamedClip, media_type: str) -> None:
        super().__init__(clip.spool, media_type=media_type)
        self.clip = clip

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:  # noqa: D102
        gone = False
        try:
            async with anyio.create_task_group() as group:
                group.start_soon(self.clip.produce)
                try:
                    await self.stream_response(send)
                except OSError:  # the client went away (a server that says so)
                    gone = True
                    group.cancel_scope.cancel()
        finally:
            self.clip.close()
            self.clip.metrics.stream_spilled.inc(self.clip.spool.spilled)
            self.clip.spool.discard()
        if gone:  # nothing more to send, and no status to change: only a log line
            _log.info("client disconnected during a streamed answer",
                      extra={"fields": {"path": self.clip.instance,
                                        "records": self.clip.records_in}})

