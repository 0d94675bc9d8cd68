"""Streamed GeoJSON (``POST /v1/clip/geojson-seq``): sent as made, read as clipped.

The records go as newline-delimited GeoJSON, a piece of about `PIECE_BYTES` at a time,
made from the caller's iterable while it is sent; the answer is read a line at a time.
The server clips a chunk of records at a time, so neither side holds the whole stream.
The server ends the answer with a summary record (asked for here), taken as the stats,
or with a problem record, raised as the `ApiError` it describes.

A streamed request is not retried: its records cannot be sent again.
"""

from __future__ import annotations

import json
from collections.abc import AsyncIterable, AsyncIterator, Iterable, Iterator
from typing import Any

from rnsca_client.errors import (
    PROBLEM_TYPE_PREFIX,
    InvalidInputError,
    ResponseFormatError,
    problem_error,
)
from rnsca_client.inputs import encode_json, geojson_document
from rnsca_client.results import ClipStats

__all__ = ["ClippedRecords", "AsyncClippedRecords", "record_pieces", "async_record_pieces",
           "SEQ_PATH", "NDJSON", "SEQ_OPTIONS", "SUMMARY_TYPE", "PIECE_BYTES"]

#: The endpoint.
SEQ_PATH = "/v1/clip/geojson-seq"
#: The media type the records are sent and read in.
NDJSON = "application/x-ndjson"
#: Options the endpoint takes as query parameters.
SEQ_OPTIONS = ("method", "n", "max_depth", "tolerance", "mode", "backend", "resolution",
               "boundary", "keep_empty", "check_validity")
#: The ``type`` of the server's summary record.
SUMMARY_TYPE = "urn:rnsca:summary"
#: Records are sent in pieces of about this many bytes.
PIECE_BYTES = 1 << 16


def _line(record: Any, number: int) -> bytes:
    try:
        return encode_json(geojson_document(record)) + b"\n"
    except InvalidInputError as exc:
        raise InvalidInputError(f"record {number}: {exc}") from None


def record_pieces(records: Iterable[Any]) -> Iterator[bytes]:
    r"""Yield `records` (GeoJSON dicts, their text, Shapely geometries) as NDJSON pieces.

    Examples
    --------
    >>> list(record_pieces([{"type": "Point", "coordinates": [1, 2]}]))
    [b'{"type":"Point","coordinates":[1,2]}\n']
    """
    batch: list[bytes] = []
    size = 0
    for number, record in enumerate(records):
        line = _line(record, number)
        batch.append(line)
        size += len(line)
        if size >= PIECE_BYTES:
            yield b"".join(batch)
            batch, size = [], 0
    if batch:
        yield b"".join(batch)


async def async_record_pieces(records: Iterable[Any] | AsyncIterable[Any]
                              ) -> AsyncIterator[bytes]:
    """Yield `records`, given as an iterable or an async iterable, as NDJSON pieces."""
    if not isinstance(records, AsyncIterable):
        for piece in record_pieces(records):
            yield piece
        return
    batch: list[bytes] = []
    size = 0
    number = 0
    async for record in records:
        line = _line(record, number)
        number += 1
        batch.append(line)
        size += len(line)
        if size >= PIECE_BYTES:
            yield b"".join(batch)
            batch, size = [], 0
    if batch:
        yield b"".join(batch)


class _Reader:
    """What the answer's lines have said so far: records, the summary, a problem."""

    def __init__(self) -> None:
        self.records_out = 0
        self.records_in: int | None = None
        self.stats: ClipStats | None = None
        self.summary: dict[str, Any] | None = None

    def take(self, line: str | bytes) -> dict[str, Any] | None:
        """Return the record `line` holds (None for a blank line or the summary)."""
        if not line.strip():
            return None
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            raise ResponseFormatError(
                f"{SEQ_PATH} answered a line that is not JSON ({exc}): {line[:200]!r}"
            ) from None
        kind = record.get("type") if isinstance(record, dict) else None
        if kind == SUMMARY_TYPE:
            self.summary = record
            self.records_in = record.get("records_in")
            self.stats = ClipStats.from_dict(record.get("stats", {}))
            return None
        if isinstance(kind, str) and kind.startswith(PROBLEM_TYPE_PREFIX):
            raise problem_error(record)
        self.records_out += 1
        return record


class ClippedRecords(_Reader):
    """The clipped records of `Client.clip_geojson_seq`, in input order, as they arrive.

    Iterate it once. The request is sent when the first record is asked for; the
    connection is held until the last one is read (or `close`).

    Attributes
    ----------
    records_out : int
        Records read so far.
    records_in : int or None
        Records the server read, once the answer is read whole.
    stats : ClipStats or None
        The stats of the whole stream, once the answer is read whole.

    Raises
    ------
    ApiError
        While iterating: the server refused the request (its status), or a record (the
        problem record that ends the answer; ``record`` names it). The records before
        it have been given out.
    """

    def __init__(self, lines: Iterator[str]) -> None:
        super().__init__()
        self._lines = lines

    def __iter__(self) -> ClippedRecords:
        return self

    def __next__(self) -> dict[str, Any]:
        for line in self._lines:
            record = self.take(line)
            if record is not None:
                return record
        raise StopIteration

    def close(self) -> None:
        """Stop reading and release the connection."""
        close = getattr(self._lines, "close", None)
        if close is not None:
            close()

    def __enter__(self) -> ClippedRecords:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class AsyncClippedRecords(_Reader):
    """The clipped records of `AsyncClient.clip_geojson_seq` (see `ClippedRecords`)."""

    def __init__(self, lines: AsyncIterator[str]) -> None:
        super().__init__()
        self._lines = lines

    def __aiter__(self) -> AsyncClippedRecords:
        return self

    async def __anext__(self) -> dict[str, Any]:
        async for line in self._lines:
            record = self.take(line)
            if record is not None:
                return record
        raise StopAsyncIteration

    async def aclose(self) -> None:
        """Stop reading and release the connection."""
        close = getattr(self._lines, "aclose", None)
        if close is not None:
            await close()
