"""Clipping whole collections: the requests a clip takes, and its result put back together.

Free of I/O, like `calls`: a `Plan` splits what `Client.clip` or ``clip_many`` was given
into batches of rows, builds each batch's `Call`, decodes each answer into a `Piece`, and
puts the pieces back together in the input's kind. The clients only send the calls
(each with its retries), one after another or several at once, so the sync and the async
client cannot drift apart.

A collection's geometries travel as GeoArrow (``POST /v1/clip/geoarrow``, the default:
binary coordinates, no JSON) or as a GeoJSON FeatureCollection (``POST /v1/clip/geojson``),
each row's position beside it (the `ROW_COLUMN`, or the feature's id), so the answer says
which rows are left; the other columns stay here and are taken from the input. A GeoArrow
column holds one family of geometries (points, lines or polygons, single and multi), so a
batch that mixes families goes as one request per family, and the pieces are put back in
row order; geometry collections (and linear rings), which no GeoArrow column the server
reads can hold, go as GeoJSON, which takes them.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rnsca_client import calls
from rnsca_client.containers import (
    GeometryCollection,
    TableCollection,
    collection_of,
    is_collection,
)
from rnsca_client.errors import ApiError, BatchError, InvalidInputError, RnscaClientError
from rnsca_client.results import ClipResult, ClipStats, GeoArrowResult, GeoJSONResult

__all__ = ["VIAS", "DEFAULT_VIA", "DEFAULT_BATCH_SIZE", "FAMILIES", "Batch", "Piece", "Plan",
           "plan"]

#: The endpoints a collection can travel through.
VIAS = ("geoarrow", "geojson")
#: GeoArrow: a GeoDataFrame of 10,000 polygons with holes (520,000 vertices) is clipped
#: in 0.1 to 0.25 s, against 3.7 to 4.7 s as GeoJSON, with the same result (best and
#: median of 7, client and server on one loopback of a loaded 2-core machine;
#: benchmarks/sdk_frames.py).
DEFAULT_VIA = "geoarrow"
#: Rows per request of ``clip_many``.
DEFAULT_BATCH_SIZE = 10_000
_ROW_IN_PATH = re.compile(r"\[(\d+)\]")
#: The family of each Shapely type id: what one GeoArrow column can hold together
#: (0 points, 1 lines, 2 polygons; 3 anything else, which goes as GeoJSON).
FAMILIES = {0: 0, 4: 0, 1: 1, 5: 1, 3: 2, 6: 2}
_OTHER = 3
_MISSING = -1


@dataclass(frozen=True)
class Batch:
    """One request of a plan: rows ``start:stop`` of item `item` (None: the one input).

    `family` (GeoArrow only) narrows the rows to the geometries of one family
    (`FAMILIES`); the missing ones of the span go with its first family.
    """

    number: int
    item: int | None
    start: int | None
    stop: int | None
    family: int | None = None


@dataclass(frozen=True)
class Piece:
    """One answered batch of a collection, decoded.

    `rows` are positions in the collection; `geometries` an object array of Shapely
    geometries, or for a table the answer's geometry column (with its `field`).
    """

    rows: Any
    geometries: Any
    field: Any
    stats: ClipStats
    verification: Any
    sent: bool = True


def _require_pyarrow(what: str) -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise ImportError(f"pyarrow is needed to send {what} as GeoArrow: pip install "
                          "'rnsca-client[geopandas]' (or [arrow]), or pass "
                          "via='geojson'") from None


class _CollectionClip:
    """One collection's requests and result."""

    def __init__(self, collection: GeometryCollection | TableCollection, window: Any,
                 via: str, verify: bool | str | None, options: Mapping[str, Any]) -> None:
        if isinstance(collection, TableCollection) and via != "geoarrow":
            raise InvalidInputError("a pyarrow table goes as GeoArrow (via='geoarrow'), "
                                    f"not via={via!r}")
        if via == "geoarrow":
            _require_pyarrow("a collection")
        self.collection = collection
        self.window = window
        self.via = via
        self.verify = verify
        self.options = dict(options)
        self._family_codes: Any = None

    def spans(self, batch_size: int | None) -> list[tuple[int, int, int | None]]:
        """Return ``(start, stop, family)`` of each request: `batch_size` rows (None: all).

        Shapely geometries going as GeoArrow make one request per family in each span.
        """
        length = len(self.collection)
        size = length if batch_size is None else batch_size
        spans = [(start, min(start + size, length)) for start in range(0, length, size or 1)]
        if isinstance(self.collection, TableCollection) or self.via != "geoarrow":
            return [(start, stop, None) for start, stop in spans]
        import numpy as np

        families = self._families()
        return [(start, stop, int(family)) for start, stop in spans
                for family in (np.unique(families[start:stop][families[start:stop] >= 0])
                               if (families[start:stop] >= 0).any() else [_MISSING])]

    def _families(self) -> Any:
        if self._family_codes is None:
            import numpy as np
            import shapely

            assert isinstance(self.collection, GeometryCollection)
            geometries = self.collection.geometries
            type_ids = shapely.get_type_id(geometries)        # -1: missing
            codes = np.full(len(geometries), _OTHER, dtype=np.int64)
            for type_id, family in FAMILIES.items():
                codes[type_ids == type_id] = family
            codes[type_ids < 0] = _MISSING
            self._family_codes = codes
        return self._family_codes

    def positions(self, batch: Batch) -> Any:
        """Return the positions in the collection of the rows `batch` sends, in order."""
        import numpy as np

        assert batch.start is not None and batch.stop is not None
        span = np.arange(batch.start, batch.stop, dtype=np.int64)
        if batch.family is None or batch.family == _MISSING:
            return span
        families = self._families()[batch.start:batch.stop]
        first = int(families[families >= 0].min())
        return span[(families == batch.family)
                    | ((families == _MISSING) & (batch.family == first))]

    def local(self, batch: Batch) -> Piece | None:
        """Return the answer of a batch that needs no request (only missing geometries).

        There is nothing to clip in it: its rows are dropped, or kept missing where the
        clip keeps empty rows (as the server would answer).
        """
        if batch.family != _MISSING:
            return None
        import numpy as np

        rows = (self.positions(batch) if self.options.get("keep_empty")
                else np.empty(0, dtype=np.int64))
        return Piece(rows, np.full(len(rows), None, dtype=object), None,
                     ClipStats.combine([]), None, sent=False)

    def call(self, batch: Batch) -> calls.Call:
        """Return the request of `batch` (its geometries encoded here)."""
        assert batch.start is not None and batch.stop is not None
        start, stop = batch.start, batch.stop
        collection = self.collection
        if isinstance(collection, TableCollection):
            import numpy as np
            import pyarrow as pa

            from rnsca_client.geoarrow import ROW_COLUMN

            table = collection.table.select([collection.index]).slice(start, stop - start)
            table = table.append_column(pa.field(ROW_COLUMN, pa.int64(), nullable=False),
                                        pa.array(np.arange(start, stop, dtype=np.int64)))
            return calls.clip_geoarrow(table, self.window, column=table.schema.names[0],
                                       verify=self.verify, options=self.options)
        positions = self.positions(batch)
        if self.via == "geoarrow" and batch.family != _OTHER:
            from rnsca_client.geoarrow import GEOMETRY_COLUMN, geometry_table

            table = geometry_table(collection.geometries[positions], positions)
            return calls.clip_geoarrow(table, self.window, column=GEOMETRY_COLUMN,
                                       verify=self.verify, options=self.options)
        from rnsca_client.features import feature_collection

        return calls.clip_feature_collection(
            feature_collection(collection.geometries[positions], positions),
            self.window, verify=self.verify, options=self.options)

    def decode(self, batch: Batch, answer: GeoArrowResult | GeoJSONResult) -> Piece:
        """Return the answer of `batch`: the rows left and their geometries."""
        if isinstance(answer, GeoJSONResult):
            from rnsca_client.features import read_features

            rows, geometries = read_features(answer.geojson)
            return Piece(rows, geometries, None, answer.stats, answer.verification)
        from rnsca_client.geoarrow import (
            ROW_COLUMN,
            is_single,
            read_geometries,
            read_stream,
            single_again,
        )

        table = read_stream(answer.stream)
        rows = table.column(ROW_COLUMN).to_numpy()
        if isinstance(self.collection, TableCollection):
            return Piece(rows, table.column(0), table.schema.field(0), answer.stats,
                         answer.verification)
        geometries = read_geometries(table.column(0), table.schema.field(0))
        import shapely

        given = self.collection.geometries[rows]
        geometries = single_again(geometries, is_single(given))
        geometries[shapely.is_missing(given)] = None   # sent as empties, kept (keep_empty)
        # 2D beside 3D goes as WKB; servers before 0.1 wrote it all 3D (Z NaN where none
        # was): each geometry is given back in its own dimension whichever answers.
        flat = shapely.has_z(geometries) & ~shapely.has_z(given)
        if flat.any():
            geometries[flat] = shapely.force_2d(geometries[flat])
        return Piece(rows, geometries, None, answer.stats, answer.verification)

    def assemble(self, pieces: Sequence[Piece]) -> ClipResult:
        """Return the clipped collection in its kind, from its pieces in order."""
        import numpy as np

        rows = (np.concatenate([p.rows for p in pieces]) if pieces
                else np.empty(0, dtype=np.int64))
        collection = self.collection
        if isinstance(collection, TableCollection):
            import pyarrow as pa

            field = pieces[0].field if pieces else collection.table.schema.field(
                collection.index)
            chunks = [chunk for p in pieces for chunk in _chunks(p.geometries)]
            column = pa.chunked_array(chunks, field.type) if chunks else \
                collection.table.column(collection.index).slice(0, 0)
            data = collection.rebuild(rows, column, field)
        else:
            geometries = (np.concatenate([p.geometries for p in pieces]) if pieces
                          else np.empty(0, dtype=object))
            if len(pieces) > 1:       # one request per family: back into row order
                order = np.argsort(rows, kind="stable")
                rows, geometries = rows[order], geometries[order]
            data = collection.rebuild(rows, geometries)
        sent = [p for p in pieces if p.sent]
        return ClipResult(data, rows, ClipStats.combine([p.stats for p in sent]),
                          tuple(p.verification for p in sent), self.via)


def _chunks(column: Any) -> list[Any]:
    return list(column.chunks) if hasattr(column, "chunks") else [column]


class _DocumentClip:
    """A GeoJSON document (or anything `Client.clip_geojson` takes): one request."""

    def __init__(self, document: Any, window: Any, verify: bool | str | None,
                 options: Mapping[str, Any]) -> None:
        self.document = document
        self.window = window
        self.verify = verify
        self.options = dict(options)

    def spans(self, batch_size: int | None) -> list[tuple[int | None, int | None, None]]:
        """Return the one request's span (a document is not split)."""
        return [(None, None, None)]

    def local(self, batch: Batch) -> None:
        """Return None: a document is always sent."""
        return None

    def call(self, batch: Batch) -> calls.Call:
        """Return the request of the document."""
        return calls.clip_geojson(self.document, self.window, verify=self.verify,
                                  approx_bound=None, options=self.options)

    def decode(self, batch: Batch, answer: GeoJSONResult) -> GeoJSONResult:
        """Return the answer as it is."""
        return answer

    def assemble(self, pieces: Sequence[GeoJSONResult]) -> GeoJSONResult:
        """Return the one answer."""
        return pieces[0]


class Plan:
    """The batches of a clip and the jobs they belong to.

    `batches` are numbered in input order; `assemble` takes each batch's decoded answer
    (by number) and returns the result: one `ClipResult` where one collection was
    given, else a list with one result per item.
    """

    def __init__(self, jobs: list[Any], batches: list[Batch], single: bool) -> None:
        self.jobs = jobs
        self.batches = batches
        self.single = single

    def _job(self, batch: Batch) -> Any:
        return self.jobs[0 if batch.item is None else batch.item]

    def local(self, batch: Batch) -> Any:
        """Return the decoded answer of `batch` where it needs no request, else None."""
        return self._job(batch).local(batch)

    def call(self, batch: Batch) -> calls.Call:
        """Return the request of `batch`."""
        return self._job(batch).call(batch)

    def decode(self, batch: Batch, answer: Any) -> Any:
        """Return the decoded answer of `batch`."""
        return self._job(batch).decode(batch, answer)

    def assemble(self, pieces: Mapping[int, Any]) -> Any:
        """Return the result, from every batch's decoded answer by batch number."""
        by_item: dict[int | None, list[Any]] = {}
        for batch in self.batches:
            by_item.setdefault(batch.item, []).append(pieces[batch.number])
        if self.single:
            return self.jobs[0].assemble(by_item.get(None, []))
        return [job.assemble(by_item.get(i, [])) for i, job in enumerate(self.jobs)]

    def failure(self, failures: Mapping[int, RnscaClientError]) -> BatchError:
        """Return the error to raise: the first failed batch's, naming the others."""
        errors = [self._batch_error(self.batches[n], failures[n]) for n in sorted(failures)]
        first = errors[0]
        first.others = errors[1:]
        return first

    def locate(self, batch: Batch, error: RnscaClientError) -> None:
        """Set ``error.row``: the position in its collection of the row the server names.

        The server names a row of the request (``geometry[3]``, ``features[3]``); its
        position in the caller's collection is the batch's row there.
        """
        job = self._job(batch)
        if not isinstance(error, ApiError) or isinstance(job, _DocumentClip):
            return
        path = error.path
        if not isinstance(path, str):
            return
        named = _ROW_IN_PATH.search(path)
        if named is None:
            return
        index = int(named.group(1))
        if isinstance(job.collection, GeometryCollection):
            positions = job.positions(batch)
            error.row = int(positions[index]) if index < len(positions) else None
        else:
            assert batch.start is not None
            error.row = batch.start + index

    def _batch_error(self, batch: Batch, error: RnscaClientError) -> BatchError:
        self.locate(batch, error)
        error_out = BatchError(error, batch=batch.number, item=batch.item,
                               start=batch.start, stop=batch.stop,
                               row=getattr(error, "row", None))
        error_out.__cause__ = error
        return error_out


def _via(via: str | None) -> str:
    if via is None:
        return DEFAULT_VIA
    if via not in VIAS:
        raise InvalidInputError(f"via must be one of {', '.join(VIAS)}, got {via!r}")
    return via


def _job(data: Any, window: Any, via: str, column: str | None, verify: bool | str | None,
         options: Mapping[str, Any], documents: bool) -> Any:
    if documents and not is_collection(data):
        if column is not None:
            raise InvalidInputError("column= names the geometry column of frames and "
                                    "tables; a GeoJSON document has none")
        return _DocumentClip(data, window, verify, options)
    return _CollectionClip(collection_of(data, column), window, via, verify, options)


def plan(data: Any, window: Any, *, via: str | None = None, column: str | None = None,
         verify: bool | str | None = None, options: Mapping[str, Any] | None = None,
         batch_size: int | None = None, many: bool = False) -> Plan:
    """Return the plan of clipping `data`: one collection, or (`many`) a list of items.

    Parameters
    ----------
    data
        A collection (see `rnsca_client.containers`), or where `many` is true also a
        list (any iterable) of items, each a collection or a GeoJSON document.
    batch_size : int, optional
        Rows per request (None: one request per collection).
    via, column, verify, options
        As `Client.clip` takes them.

    Raises
    ------
    InvalidInputError
        Something that cannot be sent, or a `batch_size` under 1.
    """
    if batch_size is not None and (isinstance(batch_size, bool)
                                   or not isinstance(batch_size, int) or batch_size < 1):
        raise InvalidInputError(f"batch_size must be a whole number >= 1, got {batch_size!r}")
    chosen = _via(via)
    options = options or {}
    single = not many or is_collection(data)
    items = [data] if single else list(data)
    jobs = [_job(item, window, chosen, column, verify, options, documents=not single)
            for item in items]
    spans = [(None if single else i, start, stop, family)
             for i, job in enumerate(jobs) for start, stop, family in job.spans(batch_size)]
    batches = [Batch(n, *span) for n, span in enumerate(spans)]
    return Plan(jobs, batches, single)
