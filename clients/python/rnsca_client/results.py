"""Typed results of the API's answers: clipped data with its stats and verification.

Every dataclass is built by ``from_dict`` from the server's JSON; members this release
of the SDK does not know (a newer server) are kept in `extra` rather than refused.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

__all__ = [
    "ClipStats",
    "Verification",
    "GeoJSONResult",
    "GeoJSONWindowsResult",
    "SVGResult",
    "SVGWindowsResult",
    "VectorTile",
    "TileArchive",
    "SegmentsResult",
    "GeoArrowResult",
    "ClipResult",
    "Backend",
    "Limits",
    "Capabilities",
    "Health",
]


def _split(cls: Any, data: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Return `data` split into the fields of dataclass `cls` and the rest."""
    names = {f.name for f in dataclasses.fields(cls)} - {"extra"}
    return ({k: v for k, v in data.items() if k in names},
            {k: v for k, v in data.items() if k not in names})


_T = TypeVar("_T")


class _FromDict:
    @classmethod
    def from_dict(cls: type[_T], data: dict[str, Any]) -> _T:
        """Return an instance from the server's JSON object."""
        known, extra = _split(cls, data)
        return cls(**known, extra=extra)  # type: ignore[call-arg]  # the dataclass's


@dataclass(frozen=True)
class ClipStats(_FromDict):
    """What the clip did (the library's ``rnsca.ClipStats``; see the service's README).

    ``accepted + rejected + subdivided + clipped + dropped == fragments_evaluated``;
    the ``*_per_level`` lists count per subdivision level 0..32.
    """

    segments_in: int
    pieces_out: int
    fragments_evaluated: int
    accepted: int
    rejected: int
    subdivided: int
    clipped: int
    dropped: int
    intersections: int
    deepest_level: int
    decided_per_level: list[int]
    geometries_in: int = 0
    geometries_out: int = 0
    vertices_in: int = 0
    vertices_out: int = 0
    runs_evaluated: int = 0
    runs_accepted: int = 0
    runs_rejected: int = 0
    runs_subdivided: int = 0
    runs_segmented: int = 0
    runs_deepest_level: int = 0
    runs_decided_per_level: list[int] = field(default_factory=list)
    segments_decided_per_level: list[int] = field(default_factory=list)
    invalid_polygons: int = 0
    decided_shallow_fraction: float = 1.0
    extra: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def combine(cls, parts: Sequence[ClipStats]) -> ClipStats:
        """Return the stats of several requests taken as one (the library's ``combine``).

        Counters and per-level lists add up; the deepest levels are the deepest of any
        part, and `decided_shallow_fraction` is that of the summed levels. No parts give
        all-zero stats.

        Examples
        --------
        >>> a = ClipStats(2, 1, 3, 1, 1, 1, 0, 0, 2, 1, [1, 2])
        >>> b = ClipStats(1, 1, 1, 1, 0, 0, 0, 0, 0, 0, [1])
        >>> both = ClipStats.combine([a, b])
        >>> both.segments_in, both.deepest_level, both.decided_per_level
        (3, 1, [2, 2])
        >>> both.decided_shallow_fraction
        1.0
        """
        values: dict[str, Any] = {}
        for f in dataclasses.fields(cls):
            if f.name in ("extra", "decided_shallow_fraction"):
                continue
            present = [getattr(part, f.name) for part in parts]
            if f.name in ("deepest_level", "runs_deepest_level"):
                values[f.name] = max(present, default=0)
            elif f.name.endswith("_per_level"):
                width = max((len(levels) for levels in present), default=0)
                values[f.name] = [sum(levels[i] for levels in present if i < len(levels))
                                  for i in range(width)]
            else:
                values[f.name] = sum(present)
        decided = values["decided_per_level"]
        values["decided_shallow_fraction"] = (sum(decided[:2]) / sum(decided)
                                              if sum(decided) else 1.0)
        return cls(**values)


@dataclass(frozen=True)
class Verification(_FromDict):
    """The server's comparison of the clip with Shapely's exact intersection.

    `passed` says whether the result keeps its mode's promise; `max_deviation` is the
    Hausdorff distance to Shapely's clip, `ratio` the output's length (or area, or
    count) over Shapely's, `false_positives` the output vertices outside the window.
    `checked` of `inputs` were compared (`sampling`: ``"all"``, or the random sample the
    server's verification budget allowed). Comparing stops at the request's time limit
    (`timed_out`), and inputs too costly for GEOS are `skipped`; `note` says what was
    left. `passed` is then None (no verdict) unless a compared input failed.
    """

    max_deviation: float
    false_positives: int
    ratio: float
    passed: bool | None
    allowed_deviation: float
    mode: str
    valid: bool = True
    invalid_inputs: int = 0
    inputs: int = 0
    checked: int = 0
    sampling: str = "all"
    skipped: int = 0
    timed_out: bool = False
    note: str = ""
    extra: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)


def _verification(data: dict[str, Any] | None) -> Verification | None:
    return None if data is None else Verification.from_dict(data)


@dataclass(frozen=True)
class GeoJSONResult:
    """``POST /v1/clip/geojson``: the clipped document, as sent back (a dict).

    Properties, ids and foreign members are kept; a geometry takes the type of what is
    left (a LineString cut in two becomes a MultiLineString).
    """

    geojson: dict[str, Any]
    stats: ClipStats
    verification: Verification | None

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> GeoJSONResult:
        """Return the result of the endpoint's JSON answer."""
        return cls(data["geojson"], ClipStats.from_dict(data["stats"]),
                   _verification(data.get("verification")))

    def to_shapely(self):
        """Return the clipped geometry as Shapely: one geometry, or a list for a collection.

        A Geometry or Feature gives one geometry (None for a Feature without one); a
        FeatureCollection gives the list of its features' geometries.

        Raises
        ------
        ImportError
            Shapely is not installed (``pip install 'rnsca-client[shapely]'``).
        """
        from rnsca_client.inputs import geometry_from_geojson

        document = self.geojson
        if document.get("type") == "FeatureCollection":
            return [geometry_from_geojson(f.get("geometry")) for f in document["features"]]
        if document.get("type") == "Feature":
            return geometry_from_geojson(document.get("geometry"))
        return geometry_from_geojson(document)


@dataclass(frozen=True)
class SVGResult:
    """``POST /v1/clip/svg``: one path data string per input path ("" if nothing is left)."""

    paths: list[str]
    stats: ClipStats
    verification: Verification | None

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SVGResult:
        """Return the result of the endpoint's JSON answer."""
        return cls(list(data["paths"]), ClipStats.from_dict(data["stats"]),
                   _verification(data.get("verification")))


@dataclass(frozen=True)
class GeoJSONWindowsResult:
    """``POST /v1/clip/geojson`` with ``windows``: one clipped document per window.

    ``geojson[w]`` is the document clipped to window ``w`` (in the order sent), as
    `GeoJSONResult.geojson` would be for that window alone; ``results()`` gives them as
    one `GeoJSONResult` each (the stats and verification are of the request, all windows
    together: ``verification.inputs`` counts the (geometry, window) pairs compared).
    """

    geojson: list[dict[str, Any]]
    stats: ClipStats
    verification: Verification | None

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> GeoJSONWindowsResult:
        """Return the result of the endpoint's JSON answer."""
        return cls(list(data["geojson"]), ClipStats.from_dict(data["stats"]),
                   _verification(data.get("verification")))

    def __len__(self) -> int:
        """Return the number of windows."""
        return len(self.geojson)

    def results(self) -> list[GeoJSONResult]:
        """Return one `GeoJSONResult` per window (sharing the request's stats)."""
        return [GeoJSONResult(document, self.stats, self.verification)
                for document in self.geojson]

    def to_shapely(self) -> list[Any]:
        """Return, per window, what `GeoJSONResult.to_shapely` gives for its document."""
        return [result.to_shapely() for result in self.results()]


@dataclass(frozen=True)
class SVGWindowsResult:
    """``POST /v1/clip/svg`` with ``windows``: one path list per window.

    ``paths[w][i]`` is input path ``i`` clipped to window ``w`` (``""`` where nothing of
    it is in that window); the stats and verification are of the request, all windows
    together.
    """

    paths: list[list[str]]
    stats: ClipStats
    verification: Verification | None

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SVGWindowsResult:
        """Return the result of the endpoint's JSON answer."""
        return cls([list(p) for p in data["paths"]], ClipStats.from_dict(data["stats"]),
                   _verification(data.get("verification")))

    def __len__(self) -> int:
        """Return the number of windows."""
        return len(self.paths)

    def results(self) -> list[SVGResult]:
        """Return one `SVGResult` per window (sharing the request's stats)."""
        return [SVGResult(paths, self.stats, self.verification) for paths in self.paths]


@dataclass(frozen=True)
class VectorTile:
    """``POST /v1/tiles/{z}/{x}/{y}``: one Mapbox Vector Tile.

    Attributes
    ----------
    data : bytes
        The tile, an uncompressed protobuf message (``b""``: no feature reaches the
        tile, the server's 204).
    z, x, y : int
        The tile asked for.
    features : int
        Features the body held.
    """

    data: bytes
    z: int
    x: int
    y: int
    features: int

    def __bytes__(self) -> bytes:
        return self.data


@dataclass(frozen=True)
class TileArchive:
    """``POST /v1/tiles``: a PMTiles v3 archive of a document's tiles.

    Attributes
    ----------
    data : bytes
        The archive (its tiles gzip-compressed), e.g. to write to a ``.pmtiles`` file.
    tiles : int
        Tiles in the archive.
    features : int
        Features the body held.
    """

    data: bytes
    tiles: int
    features: int

    def __bytes__(self) -> bytes:
        return self.data


@dataclass(frozen=True)
class SegmentsResult:
    """``POST /v1/clip/segments``: the visible piece of each segment that has one.

    For a NumPy input (binary endpoint) `segments` is a float64 array (m, 4), `source`
    int64 (m,) and `t` float64 (m, 2); for a list input they are lists.

    Attributes
    ----------
    segments
        The pieces ``[x0, y0, x1, y1]``, in input order and direction.
    source
        Index of the input segment of each piece.
    t
        Parameter interval ``[t0, t1]`` of each piece on its input segment.
    stats, verification
        As for every clip.
    method, mode, backend : str
        What ran (the server's default backend when none was asked for).
    """

    segments: Any
    source: Any
    t: Any
    stats: ClipStats
    verification: Verification | None
    method: str
    mode: str
    backend: str

    def __len__(self) -> int:
        return len(self.source)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SegmentsResult:
        """Return the result of the endpoint's JSON answer."""
        return cls([list(row) for row in data["segments"]], list(data["source"]),
                   [list(row) for row in data["t"]], ClipStats.from_dict(data["stats"]),
                   _verification(data.get("verification")), data["method"], data["mode"],
                   data["backend"])


@dataclass(frozen=True)
class GeoArrowResult:
    """``POST /v1/clip/geoarrow``: the table with its geometry column clipped.

    Attributes
    ----------
    stream : bytes
        The answer, an Arrow IPC stream (read it with ``pyarrow.ipc.open_stream``, or
        `table`).
    rows : int
        Rows in the answer.
    stats, verification
        As for every clip.
    """

    stream: bytes = field(repr=False)
    rows: int
    stats: ClipStats
    verification: Verification | None

    def __len__(self) -> int:
        return self.rows

    def table(self) -> Any:
        """Return the answer as a ``pyarrow.Table`` (needs pyarrow)."""
        import pyarrow as pa

        return pa.ipc.open_stream(pa.py_buffer(self.stream)).read_all()


@dataclass(frozen=True)
class ClipResult:
    """``Client.clip`` and ``clip_many``: a collection clipped, in the kind it came in.

    Attributes
    ----------
    data
        The input's kind (``GeoDataFrame``, ``GeoSeries``, NumPy array, list, tuple,
        pyarrow ``Table`` or ``RecordBatch``) holding the rows kept, in input order, each
        with its clipped geometry and everything else as it was (other columns, index
        labels, name, CRS). A row whose geometry is clipped away, empty or missing is
        dropped, unless the clip was asked to ``keep_empty`` (then it holds an empty
        geometry; a missing one stays missing).
    rows : ndarray of int64
        The position in the input of each row of `data`.
    stats : ClipStats
        Of all the requests together (`ClipStats.combine`).
    verifications : tuple of Verification or None
        The server's verification of each request, in order (None: not verified).
    via : str
        The endpoint that carried the geometries: ``"geoarrow"`` or ``"geojson"``.
    """

    data: Any = field(repr=False)
    rows: Any = field(repr=False)
    stats: ClipStats
    verifications: tuple[Verification | None, ...]
    via: str

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def requests(self) -> int:
        """Return how many requests the clip took."""
        return len(self.verifications)

    @property
    def passed(self) -> bool | None:
        """Return the verdict of the verifications together.

        False if any request failed its verification; True if every request was
        verified and passed; None otherwise (some not verified, or without a verdict).
        """
        verdicts = [None if v is None else v.passed for v in self.verifications]
        if False in verdicts:
            return False
        return True if verdicts and all(verdicts) else None


@dataclass(frozen=True)
class Backend(_FromDict):
    """A backend the API names: present here (with its devices) or not (and why)."""

    name: str
    available: bool
    devices: list[str] = field(default_factory=list)
    reason: str | None = None
    extra: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)


@dataclass(frozen=True)
class Limits(_FromDict):
    """The limits a request must stay within (the server's settings)."""

    max_body_bytes: int
    max_vertices: int
    work_budget: int
    request_time_limit: float
    verify_max_vertices: int
    #: Streamed GeoJSON's chunks and longest record (None from a server without them).
    stream_chunk_bytes: int | None = None
    stream_chunk_records: int | None = None
    stream_max_record_bytes: int | None = None
    #: Most tiles ``POST /v1/tiles`` cuts in one zoom (None from a server without it).
    max_tiles: int | None = None
    extra: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)


@dataclass(frozen=True)
class Capabilities:
    """``GET /v1/capabilities``: what the server can do."""

    version: str
    methods: list[str]
    modes: list[str]
    backends: list[Backend]
    threading_layer: str | None
    serialized: bool
    svg: bool
    limits: Limits
    extra: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @property
    def available_backends(self) -> list[str]:
        """Return the names of the backends present on the server."""
        return [b.name for b in self.backends if b.available]

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Capabilities:
        """Return the capabilities from the endpoint's JSON answer."""
        known, extra = _split(cls, data)
        known["backends"] = [Backend.from_dict(b) for b in known["backends"]]
        known["limits"] = Limits.from_dict(known["limits"])
        return cls(**known, extra=extra)


@dataclass(frozen=True)
class Health:
    """``GET /healthz`` or ``/readyz``: ``status`` is ``"ok"`` or ``"ready"``."""

    status: str
