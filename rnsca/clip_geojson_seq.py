"""Clip GeoJSON text sequences: records read, clipped and written a chunk at a time.

A sequence (RFC 8142, or newline-delimited GeoJSON; see `rnsca.io.geojson_seq`) holds
Features, Geometries and FeatureCollections, one per record. `clip_records` clips one
chunk of records with `rnsca.clip_geojson` (the Features and Geometries of a chunk in
one call, a FeatureCollection record in a call of its own) and gives each record back in
the kind it came in; `clip_geojson_seq` does so over a stream of any length, holding one
chunk at a time. Every geometry is clipped on its own, so how records are cut into
chunks changes nothing in the output.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rnsca.clip_geojson import clip_geojson, combine_stats
from rnsca.errors import InvalidGeometryError, InvalidOptionError, RnscaError
from rnsca.io.geojson import GEOMETRY_TYPES
from rnsca.io.geojson_seq import parse_record
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["RecordsClipResult", "SequenceClip", "clip_records", "clip_geojson_seq",
           "CHUNK_RECORDS", "CHUNK_BYTES"]

#: Records clipped together by `clip_geojson_seq`, at most (unless `chunk_records`).
CHUNK_RECORDS = 5000
#: Bytes of record text clipped together by `clip_geojson_seq`, about (a chunk is cut
#: before the record that would take it past this; unless `chunk_bytes`).
CHUNK_BYTES = 4 << 20

_KINDS = frozenset(("Feature", "FeatureCollection", *GEOMETRY_TYPES))


@dataclass(frozen=True, slots=True)
class RecordsClipResult:
    """The records of a chunk, clipped.

    Attributes
    ----------
    records : list
        The clipped records in input order, each of its input's kind (Feature, Geometry
        or FeatureCollection); records left empty are dropped unless ``keep_empty``.
    source : ndarray of int64
        The number of the input record of each of `records` (``first`` counted in).
    stats : ClipStats
        The stats of the chunk's clips, added up.
    """

    records: list
    source: np.ndarray
    stats: ClipStats


def clip_records(records: Sequence[Any], window: Window | Iterable[float], *,
                 first: int = 0, keep_empty: bool = False, max_vertices: int | None = None,
                 arrays: bool = False, **options: Any) -> RecordsClipResult:
    """Return GeoJSON records (Features, Geometries, FeatureCollections) clipped to a window.

    Each record is clipped as `rnsca.clip_geojson` clips it alone: Features keep their
    ``properties``, ``id`` and foreign members, a Geometry comes back as a Geometry, a
    FeatureCollection as a FeatureCollection.

    Parameters
    ----------
    records : sequence
        GeoJSON objects (dicts), or the JSON text of each (bytes or str), as
        `rnsca.io.geojson_seq.RecordSplitter` cuts them.
    window : Window or sequence of 4 floats
        ``[xmin, ymin, xmax, ymax]``.
    first : int
        The number of ``records[0]`` in its sequence: errors and `source` count from it.
    keep_empty : bool
        False (default): a Feature or Geometry left empty (a Feature with a null
        geometry too) is dropped, and so is a FeatureCollection left without features.
        True: kept, with empty coordinates (as `rnsca.clip_geojson` keeps them).
    max_vertices : int, optional
        Refuse a chunk with more positions than this (all its records together).
    arrays : bool
        Coordinates as NumPy arrays (see `rnsca.clip_geojson`); write each record with
        `rnsca.io.geojson_seq.record_bytes`.
    **options
        As for `rnsca.clip_geojson` (``boundary``, ``method``, ``mode``, ...).

    Returns
    -------
    RecordsClipResult

    Raises
    ------
    ParseError
        A record's text is not JSON; ``record`` names it, ``position`` the offset in it.
    InvalidGeometryError
        A record is not a GeoJSON object, or not valid GeoJSON; the message names the
        record, ``record`` its number and ``path`` the JSON path inside it. The first
        record at fault is named, whatever is wrong with it.
    LimitExceededError
        More than `max_vertices` positions.
    InvalidWindowError, InvalidOptionError
        A bad window or option.

    Examples
    --------
    >>> records = [b'{"type": "LineString", "coordinates": [[-5, 5], [5, 5]]}',
    ...            b'{"type": "Feature", "id": 1, "properties": null, "geometry": '
    ...            b'{"type": "Point", "coordinates": [20, 20]}}',
    ...            b'{"type": "Feature", "id": 2, "properties": {"a": 1}, "geometry": '
    ...            b'{"type": "Point", "coordinates": [1, 2]}}']
    >>> result = clip_records(records, [0, 0, 10, 10], first=100)
    >>> result.records[0]
    {'type': 'LineString', 'coordinates': [[0.0, 5.0], [5.0, 5.0]]}
    >>> result.records[1]["id"], result.source.tolist()
    (2, [100, 102])
    """
    window = Window.of(window)
    parsed: list[dict] = []
    for i, record in enumerate(records):
        try:
            parsed.append(_checked(record, first + i))
        except RnscaError:
            if parsed:  # a problem in the geometry of an earlier record comes first
                try:
                    clip_records(parsed, window, first=first, keep_empty=keep_empty,
                                 max_vertices=max_vertices, **options)
                except InvalidGeometryError as earlier:
                    raise earlier from None
            raise
    out: list[tuple[int, Any]] = []
    stats: list[ClipStats] = []
    budget = max_vertices
    batch: list[int] = []   # indices of the Features and Geometries clipped together

    def clip(document: dict, numbers: list[int]) -> tuple[dict, np.ndarray]:
        nonlocal budget
        try:
            result = clip_geojson(document, window, keep_empty=keep_empty,
                                  max_vertices=budget, arrays=arrays, **options)
        except InvalidGeometryError as exc:
            raise _located(exc, numbers, parsed, first) from None
        stats.append(result.stats)
        if budget is not None:
            budget -= result.stats.vertices_in
        return result.document, result.feature_source

    def flush() -> None:
        if not batch:
            return
        features = [parsed[i] if parsed[i]["type"] == "Feature" else
                    {"type": "Feature", "properties": None, "geometry": parsed[i]}
                    for i in batch]
        document, source = clip({"type": "FeatureCollection", "features": features}, batch)
        for feature, k in zip(document["features"], source.tolist(), strict=True):
            i = batch[k]
            out.append((i, feature if parsed[i]["type"] == "Feature" else feature["geometry"]))
        batch.clear()

    for i, record in enumerate(parsed):
        if record["type"] != "FeatureCollection":
            batch.append(i)
            continue
        flush()
        document, _ = clip(record, [i])
        if keep_empty or document["features"]:
            out.append((i, document))
    flush()
    if not stats:  # no record: still check the window and the options
        clip({"type": "FeatureCollection", "features": []}, [])
    return RecordsClipResult([record for _, record in out],
                             np.array([first + i for i, _ in out], dtype=np.int64),
                             combine_stats(stats))


def _checked(record: Any, number: int) -> dict:
    """Return the record parsed, refusing what is no GeoJSON object."""
    if isinstance(record, (bytes, bytearray, memoryview, str)):
        record = parse_record(record, number)
    if isinstance(record, dict):
        kind = record.get("type")
        if isinstance(kind, str) and kind in _KINDS:
            return record
        problem = "no \"type\" member" if kind is None else f"type {kind!r}"
    else:
        problem = f"a JSON {type(record).__name__}"
    error = InvalidGeometryError(
        f"record {number}: expected a GeoJSON Feature, Geometry or FeatureCollection, "
        f"got {problem}")
    error.record, error.path = number, ""
    error.detail = f"expected a GeoJSON Feature, Geometry or FeatureCollection, got {problem}"
    raise error


def _located(exc: InvalidGeometryError, numbers: list[int], parsed: list[dict],
             first: int) -> RnscaError:
    """Return `exc` with its JSON path and message made relative to the record at fault.

    `numbers` are the indices (in `parsed`) of the records the clipped document holds:
    its features, in order, or the one FeatureCollection record.
    """
    path = exc.path
    if path is None or not numbers:
        return exc
    reason = str(exc)
    prefix = f"invalid GeoJSON at {path or '<top level>'}: "
    if reason.startswith(prefix):
        reason = reason[len(prefix):]
    if len(numbers) == 1 and parsed[numbers[0]]["type"] == "FeatureCollection":
        index, inner = numbers[0], path
    else:
        head, _, inner = path.partition("]")
        if not head.startswith("features["):
            return exc
        index = numbers[int(head.removeprefix("features["))]
        inner = inner.removeprefix(".")
        if parsed[index]["type"] != "Feature":  # a Geometry record, wrapped in a Feature
            inner = inner.removeprefix("geometry").removeprefix(".")
    number = first + index
    error = InvalidGeometryError(
        f"record {number}: invalid GeoJSON at {inner or '<top level>'}: {reason}")
    error.record, error.path, error.detail = number, inner, reason
    return error


class SequenceClip:
    """An iterator over the records of a sequence, clipped a chunk at a time.

    Made by `clip_geojson_seq`; after (or during) the iteration, `stats` holds the
    stats of the chunks clipped so far.

    Attributes
    ----------
    records_in, records_out : int
        Records read and records given out, so far.
    chunks : int
        Chunks clipped so far.
    """

    def __init__(self, records: Iterable[Any], window: Window, chunk_records: int,
                 chunk_bytes: int, options: dict) -> None:
        self.records_in = 0
        self.records_out = 0
        self.chunks = 0
        self._stats: list[ClipStats] = []
        self._iterator = self._clipped(iter(records), window, chunk_records, chunk_bytes,
                                       options)

    @property
    def stats(self) -> ClipStats | None:
        """Return the chunks' stats added up (None before the first chunk is clipped)."""
        return combine_stats(self._stats) if self._stats else None

    def __iter__(self) -> SequenceClip:
        return self

    def __next__(self) -> Any:
        """Return the next clipped record."""
        record = next(self._iterator)
        self.records_out += 1
        return record

    def _clipped(self, records: Iterator[Any], window: Window, chunk_records: int,
                 chunk_bytes: int, options: dict) -> Iterator[Any]:
        chunk: list[Any] = []
        size = 0
        for record in records:
            length = len(record) if isinstance(record, (bytes, bytearray, str)) else 0
            if chunk and (len(chunk) >= chunk_records or size + length > chunk_bytes):
                yield from self._clip(chunk, window, options)
                chunk, size = [], 0
            chunk.append(record)
            size += length
        if chunk or not self.chunks:
            yield from self._clip(chunk, window, options)

    def _clip(self, chunk: list[Any], window: Window, options: dict) -> Iterator[Any]:
        """Yield the chunk's records clipped; at a bad record, those before it first."""
        try:
            result = clip_records(chunk, window, first=self.records_in, **options)
        except RnscaError as exc:
            before = -1 if exc.record is None else exc.record - self.records_in
            if 0 < before < len(chunk):
                yield from self._clip(chunk[:before], window, options)
            raise
        self.records_in += len(chunk)
        self.chunks += 1
        self._stats.append(result.stats)
        yield from result.records


def clip_geojson_seq(records: Iterable[Any], window: Window | Iterable[float], *,
                     chunk_records: int = CHUNK_RECORDS, chunk_bytes: int = CHUNK_BYTES,
                     keep_empty: bool = False, arrays: bool = False,
                     **options: Any) -> SequenceClip:
    r"""Return an iterator over the records of a GeoJSON sequence, clipped to a window.

    The records are read lazily and clipped a chunk at a time, so memory holds one
    chunk, whatever the length of the sequence; records come out in input order,
    those left empty dropped (unless `keep_empty`). Feed it
    `rnsca.io.geojson_seq.split_records` (texts) or `read_records` (parsed objects),
    and write what it yields with `rnsca.io.geojson_seq.write_records`.

    Parameters
    ----------
    records : iterable
        GeoJSON objects (Features, Geometries, FeatureCollections), or their texts.
    window : Window or sequence of 4 floats
        ``[xmin, ymin, xmax, ymax]``.
    chunk_records : int
        Records clipped together, at most.
    chunk_bytes : int
        For records given as text: a chunk ends before the record that would take its
        text past this many bytes (a longer record makes a chunk of its own).
    keep_empty, arrays, **options
        As for `clip_records`.

    Returns
    -------
    SequenceClip
        Yields the clipped records; its ``stats`` add up the chunks clipped so far.

    Raises
    ------
    ParseError, InvalidGeometryError, LimitExceededError, InvalidWindowError,
    InvalidOptionError
        As `clip_records`, while iterating, once the records before the bad one have
        been given out.

    Examples
    --------
    >>> from rnsca.io.geojson_seq import split_records
    >>> text = (b'\x1e{"type": "Point", "coordinates": [1, 1]}\n'
    ...         b'\x1e{"type": "Point", "coordinates": [20, 1]}\n')
    >>> clipped = clip_geojson_seq(split_records([text]), [0, 0, 10, 10])
    >>> list(clipped), clipped.records_in
    ([{'type': 'Point', 'coordinates': [1.0, 1.0]}], 2)
    """
    if isinstance(chunk_records, bool) or not isinstance(chunk_records, int) \
            or chunk_records < 1:
        raise InvalidOptionError(f"chunk_records must be a positive int, got {chunk_records!r}")
    if isinstance(chunk_bytes, bool) or not isinstance(chunk_bytes, int) or chunk_bytes < 1:
        raise InvalidOptionError(f"chunk_bytes must be a positive int, got {chunk_bytes!r}")
    return SequenceClip(records, Window.of(window), chunk_records, chunk_bytes,
                        dict(options, keep_empty=keep_empty, arrays=arrays))
