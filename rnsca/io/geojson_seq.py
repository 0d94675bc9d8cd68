"""GeoJSON text sequences: one GeoJSON text per record, read and written incrementally.

Two framings are read and written:

- `Framing.RS`, GeoJSON text sequences (RFC 8142, ``application/geo+json-seq``, files
  ``.geojsons``): each text is preceded by the record separator RS (0x1E) and followed
  by a line feed. A text may span lines (it is delimited by the next RS); runs of RS
  and texts of JSON whitespace only are skipped (RFC 7464, 2.1).
- `Framing.LINES`, newline-delimited GeoJSON (``application/x-ndjson``, files
  ``.geojsonl``, ``.ndjson``): one text per line, ended by LF (a CR before it is JSON
  whitespace); lines of whitespace only are skipped.

Each text holds one GeoJSON object: a Feature, a Geometry or a FeatureCollection
(RFC 8142 allows a mix). `RecordSplitter` cuts a byte stream that arrives in pieces of
any size into the texts, holding at most one unfinished text between pieces, so memory
is bounded by the longest record, not by the stream. Records are numbered from 0 in
the order they come, skipped whitespace not counted; errors name that number
(``record`` attribute). Knows nothing of clipping.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from enum import Enum
from typing import IO, Any

import orjson

from rnsca.errors import InvalidOptionError, LimitExceededError, ParseError, RnscaError

__all__ = ["RS", "Framing", "RecordSplitter", "split_records", "read_records",
           "parse_record", "record_bytes", "write_records", "framing_of_path"]

#: The record separator that opens every text of a GeoJSON text sequence.
RS = b"\x1e"
_LF = b"\n"
# The first byte that is not JSON whitespace.
_NON_SPACE = re.compile(rb"[^ \t\r\n]")


class Framing(str, Enum):
    """How the texts of a sequence are delimited."""

    RS = "rs"
    """RFC 8142: RS before each text, LF after it (``application/geo+json-seq``)."""
    LINES = "lines"
    """One text per line (newline-delimited GeoJSON, ``application/x-ndjson``)."""

    @classmethod
    def _missing_(cls, value: object) -> Framing:
        raise InvalidOptionError(
            f"unknown framing {value!r}; expected one of {', '.join(f.value for f in cls)}")

    @property
    def media_type(self) -> str:
        """Return the media type of a sequence in this framing."""
        return "application/geo+json-seq" if self is Framing.RS else "application/x-ndjson"


def framing_of_path(name: str) -> Framing | None:
    """Return the framing a file name's ending stands for, or None for another ending.

    Examples
    --------
    >>> framing_of_path("roads.geojsons"), framing_of_path("roads.GEOJSONL")
    (<Framing.RS: 'rs'>, <Framing.LINES: 'lines'>)
    >>> framing_of_path("roads.geojson") is None
    True
    """
    lowered = name.lower()
    if lowered.endswith((".geojsons", ".geojsonseq")):
        return Framing.RS
    if lowered.endswith((".geojsonl", ".geojsonld", ".ndjson", ".jsonl")):
        return Framing.LINES
    return None


class RecordSplitter:
    r"""Cut a byte stream, fed in pieces of any size, into the texts of a sequence.

    Parameters
    ----------
    framing : Framing or None
        How texts are delimited; None decides from the first byte that is not
        whitespace (RS: `Framing.RS`, anything else: `Framing.LINES`).
    max_record_bytes : int, optional
        Refuse (`LimitExceededError`) a text longer than this, as soon as that many of
        its bytes have arrived: the splitter then holds at most this much.

    Attributes
    ----------
    records : int
        Texts returned so far (the next one's number).
    error : RnscaError or None
        A problem met after texts that `feed` returned: it is raised by the next call
        (`feed` or `finish`), so that the texts before a bad one are never lost.

    Examples
    --------
    >>> splitter = RecordSplitter(Framing.RS)
    >>> splitter.feed(b'\x1e{"type": "Point", "coordinates": [1, 2]}\n\x1e{"ty')
    [b'{"type": "Point", "coordinates": [1, 2]}\n']
    >>> splitter.feed(b'pe": "Point", "coordinates": [3, 4]}\n')
    []
    >>> splitter.finish()
    [b'{"type": "Point", "coordinates": [3, 4]}\n']
    >>> splitter.records
    2
    """

    def __init__(self, framing: Framing | str | None = None, *,
                 max_record_bytes: int | None = None) -> None:
        self.framing = None if framing is None else Framing(framing)
        self.max_record_bytes = max_record_bytes
        self.records = 0
        self._pending: list[bytes] = []   # the unfinished text, in the pieces it came in
        self._pending_bytes = 0
        self._started = False             # RS framing: whether the first RS has been met
        self.error: RnscaError | None = None

    def feed(self, data: bytes | bytearray | memoryview) -> list[bytes]:
        """Return the texts that `data` completes, in order (possibly none).

        Raises
        ------
        ParseError
            RS framing: something other than whitespace before the first RS.
        LimitExceededError
            A text is longer than `max_record_bytes`.
        """
        out: list[bytes] = []
        try:
            self._feed(bytes(data), out)
        except RnscaError as exc:
            if not out:
                raise
            self.error = exc
        return out

    def _feed(self, data: bytes, out: list[bytes]) -> None:
        if self.error is not None:
            raise self.error
        if not data:
            return
        if self.framing is None:
            first = _NON_SPACE.search(data)
            if first is None:
                return  # whitespace only, so far: nothing decided
            self.framing = Framing.RS if data[first.start():first.start() + 1] == RS \
                else Framing.LINES
        delimiter = RS if self.framing is Framing.RS else _LF
        parts = data.split(delimiter)
        if self.framing is Framing.RS and not self._started:
            # Before the first RS only whitespace may come: it is no text of the sequence.
            if _NON_SPACE.search(parts[0]):
                self._not_a_sequence()
            if len(parts) == 1:
                return
            self._started = True
            parts[0] = b""
            self._pending, self._pending_bytes = [], 0
        if len(parts) > 1:
            self._pending.append(parts[0])
            self._complete(b"".join(self._pending), out)
            self._pending, self._pending_bytes = [], 0
            for part in parts[1:-1]:
                self._complete(part, out)
        last = parts[-1]
        if last:
            self._pending.append(last)
            self._pending_bytes += len(last)
            self._check_length()

    def finish(self) -> list[bytes]:
        """Return the last text (the stream has ended), if there is one."""
        if self.error is not None:
            raise self.error
        out: list[bytes] = []
        if self._pending:
            text, self._pending, self._pending_bytes = b"".join(self._pending), [], 0
            self._complete(text, out)
        return out

    def _complete(self, text: bytes, out: list[bytes]) -> None:
        """Append `text` to `out` unless it is whitespace only."""
        if self.framing is Framing.RS and not self._started:
            if text and not text.isspace():
                self._not_a_sequence()   # the stream ended before any RS
            return
        if text and not text.isspace():
            if self.max_record_bytes is not None and len(text) > self.max_record_bytes:
                self._too_long()
            self.records += 1
            out.append(text)

    def _not_a_sequence(self) -> None:
        error = ParseError(
            "a GeoJSON text sequence (RFC 8142) starts each text with the record separator "
            "RS (0x1E); this one starts with something else (send one text per line as "
            "newline-delimited GeoJSON instead)")
        error.record, error.position = 0, 0
        raise error

    def _check_length(self) -> None:
        if self.max_record_bytes is not None and self._pending_bytes > self.max_record_bytes:
            self._too_long()

    def _too_long(self) -> None:
        error = LimitExceededError(
            f"record {self.records} is longer than the limit of {self.max_record_bytes} "
            f"bytes for one GeoJSON text")
        error.record = self.records
        raise error


def split_records(pieces: Iterable[bytes], framing: Framing | str | None = None, *,
                  max_record_bytes: int | None = None) -> Iterator[bytes]:
    r"""Yield the texts of a sequence that arrives as `pieces` of bytes (see `RecordSplitter`).

    Examples
    --------
    >>> list(split_records([b'{"a": 1}\n{"a"', b': 2}\n\n']))
    [b'{"a": 1}', b'{"a": 2}']
    """
    splitter = RecordSplitter(framing, max_record_bytes=max_record_bytes)
    for piece in pieces:
        yield from splitter.feed(piece)
    yield from splitter.finish()


def _pieces(source: IO[bytes] | Iterable[bytes], block: int) -> Iterator[bytes]:
    read = getattr(source, "read", None)
    if read is None:
        yield from source
        return
    while piece := read(block):
        yield piece


def read_records(source: IO[bytes] | Iterable[bytes], framing: Framing | str | None = None,
                 *, max_record_bytes: int | None = None,
                 block: int = 1 << 20) -> Iterator[Any]:
    r"""Yield the JSON value of each text of a sequence, parsed with orjson.

    Parameters
    ----------
    source : binary file or iterable of bytes
        A file opened ``"rb"`` (read `block` bytes at a time), or the pieces of a stream.
    framing : Framing, optional
        None: decided from the first byte (see `RecordSplitter`).
    max_record_bytes : int, optional
        Refuse a text longer than this.

    Raises
    ------
    ParseError
        A text is not JSON; its ``record`` attribute is the record's number, ``position``
        the offset of the problem in it.
    LimitExceededError
        A text is longer than `max_record_bytes`.

    Examples
    --------
    >>> import io
    >>> text = b'\x1e{"type": "Point", "coordinates": [1, 2]}\n'
    >>> list(read_records(io.BytesIO(text)))
    [{'type': 'Point', 'coordinates': [1, 2]}]
    """
    for number, text in enumerate(split_records(_pieces(source, block), framing,
                                                max_record_bytes=max_record_bytes)):
        yield parse_record(text, number)


def parse_record(text: bytes | bytearray | memoryview | str, number: int) -> Any:
    """Return the JSON value of record `number`'s `text`; raise `ParseError` naming it."""
    try:
        return orjson.loads(text)
    except orjson.JSONDecodeError as exc:
        error = ParseError(f"record {number} is not valid JSON: {exc}")
        error.record, error.position = number, exc.pos
        raise error from None


def record_bytes(obj: object, framing: Framing | str) -> bytes:
    r"""Return `obj` as one text of a sequence in `framing`: JSON, framed.

    NumPy arrays (``arrays=True`` output of the GeoJSON writer) are written as arrays.

    Examples
    --------
    >>> record_bytes({"type": "Point", "coordinates": [1.0, 2.0]}, Framing.RS)
    b'\x1e{"type":"Point","coordinates":[1.0,2.0]}\n'
    >>> record_bytes({"type": "Point", "coordinates": [1.0, 2.0]}, "lines")
    b'{"type":"Point","coordinates":[1.0,2.0]}\n'
    """
    text = orjson.dumps(obj, option=orjson.OPT_SERIALIZE_NUMPY | orjson.OPT_APPEND_NEWLINE)
    return RS + text if Framing(framing) is Framing.RS else text


def write_records(objs: Iterable[object], stream: IO[bytes], framing: Framing | str) -> int:
    """Write each of `objs` to `stream` as a text of a sequence; return how many."""
    framing = Framing(framing)
    count = 0
    for obj in objs:
        stream.write(record_bytes(obj, framing))
        count += 1
    return count
