"""GeoJSON (RFC 7946) to ragged arrays and back; knows nothing of clipping.

`from_geojson` reads a Geometry, Feature or FeatureCollection (a dict, or JSON text parsed
with orjson) into a `GeoJSONLayout`: every point-like geometry in one MULTIPOINT ragged
array, every line-like one in one MULTILINESTRING array and every polygon-like one in one
MULTIPOLYGON array, in document order, in the layout ``shapely.to_ragged_array`` uses.
`to_geojson` walks the same document again and writes each geometry from arrays aligned
with the layout (for example the clipped ones), keeping everything else.

Reading is strict. The first problem, in document order, raises `InvalidGeometryError`
(a ValueError) whose message and ``path`` attribute name its JSON path, for example
``features[12].geometry.coordinates[0][3][1]``. To stay fast on large documents the
reader does no per-coordinate Python work on valid input: it collects the coordinate
arrays of every geometry and converts their positions a chunk at a time: ormsgpack
writes the lists in C as MessagePack, which tags every number with its type, and a
compiled decoder checks and reads them (`rnsca.io.msgpack_decode.read_positions`).
Sizes, finiteness and ring closure are checked in bulk too. Only when a bulk check fails
does a second, slow walk run to find the exact path of the first problem.

Rules (where RFC 7946 leaves a choice, the choice is stated):

- Arrays may be lists or tuples (``shapely.geometry.mapping`` gives tuples); numbers are
  int or float (NumPy scalars are accepted in dicts), never bool, and must be finite.
- A position has 2 or more numbers; a position with 3 or more is 3D. Numbers after the
  third (RFC 7946 says not to use them) are validated, then dropped.
- A document may mix 2D and 3D positions (RFC 7946 allows either in any position). It is
  read as 3D when any position is 3D, with Z = NaN for the positions that came with 2
  numbers (`GeoJSONLayout.partial_z`): a missing Z is never filled in, which would
  invent data. Each position is written back with the dimension it came in, and a new
  position (a cut point, a window corner) is 3D only if every Z it is computed from
  is known: NaN propagates through the interpolation, and a position whose Z is NaN
  is written with 2 numbers (JSON has no NaN). A document of one dimension is read and
  written as before, 2D as (n, 2) arrays.
- An empty ``coordinates`` array is an empty geometry (RFC 7946, 3.1). Inside a
  MultiPoint, MultiLineString or MultiPolygon an empty member is read as nothing, so it
  is not written back. A LineString needs 2 or more positions, a ring 4 or more with the
  first and last positions equal: in x, y and z, or in x and y with both 2D (a 2D end
  and a 3D end are not equal).
- A Feature must have a ``geometry`` member; its value may be null. GeometryCollections
  nest at most `MAX_COLLECTION_DEPTH` levels.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import chain
from typing import Any, NoReturn, cast

import numpy as np
import orjson
import ormsgpack
import shapely

from rnsca.arrays import exclusive_sum
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    LimitExceededError,
    ParseError,
)
from rnsca.io.msgpack_decode import (
    HAS_Z,
    PARTIAL_Z,
    REFUSED,
    read_positions,
    same_geometries,
)

__all__ = [
    "GEOMETRY_TYPES",
    "MAX_COLLECTION_DEPTH",
    "GeoJSONLayout",
    "dumps",
    "from_geojson",
    "loads",
    "to_geojson",
    "write_geojson",
]

#: The GeoJSON geometry type names, as RFC 7946 spells them (case-sensitive).
GEOMETRY_TYPES = (
    "Point", "MultiPoint", "LineString", "MultiLineString", "Polygon", "MultiPolygon",
    "GeometryCollection",
)

#: How many GeometryCollections may enclose one another.
MAX_COLLECTION_DEPTH = 32

# The three ragged arrays a document is split into, by index.
_POINTS, _LINES, _POLYGONS = 0, 1, 2
_KIND = {"Point": _POINTS, "MultiPoint": _POINTS, "LineString": _LINES,
         "MultiLineString": _LINES, "Polygon": _POLYGONS, "MultiPolygon": _POLYGONS}
_RAGGED_TYPE = (shapely.GeometryType.MULTIPOINT, shapely.GeometryType.MULTILINESTRING,
                shapely.GeometryType.MULTIPOLYGON)
_KIND_NAME = ("points", "lines", "polygons")

_ARRAY = (list, tuple)
_ARRAY_TYPES = frozenset(_ARRAY)
_NUMBER = (int, float, np.integer, np.floating)
_BOOL = (bool, np.bool_)
_TEXT = (str, bytes, bytearray, memoryview)


@dataclass(frozen=True, slots=True)
class GeoJSONLayout:
    """A GeoJSON document taken apart into three ragged arrays.

    Each of `points`, `lines` and `polygons` is a ``(geometry_type, coords, offsets)``
    triple as ``shapely.to_ragged_array`` returns it, so ``shapely.from_ragged_array(
    *layout.lines)`` rebuilds the geometries. Geometry ``i`` of an array is the ``i``-th
    geometry of that kind met walking the document (features in order, collection members
    in order, depth first); null geometries and GeometryCollections themselves are not in
    any array.

    Attributes
    ----------
    document : dict
        The parsed input, not copied; `to_geojson` walks it again to write the output.
    points : tuple
        ``(GeometryType.MULTIPOINT, coords, (geometry_offsets,))``: Point and MultiPoint.
    lines : tuple
        ``(GeometryType.MULTILINESTRING, coords, (part_offsets, geometry_offsets))``:
        LineString and MultiLineString.
    polygons : tuple
        ``(GeometryType.MULTIPOLYGON, coords, (ring_offsets, polygon_offsets,
        geometry_offsets))``: Polygon and MultiPolygon.
    has_z : bool
        Whether some position is 3D; then every ``coords`` has shape (n, 3), else (n, 2).
    sources : tuple of three lists, or None
        For each geometry of `points`, `lines` and `polygons`, the input's own
        ``coordinates`` member where it holds exactly the positions read (lists of
        floats, as many per position as the document's dimension, no empty member),
        else None; None for all when the document was read by the slow validator.
        `to_geojson` writes a geometry its arrays leave unchanged with this member.
    partial_z : bool
        Whether the document mixes 2D and 3D positions: then `has_z` is true and the Z
        of each position that came with two numbers is NaN (so is any Z computed from
        it, for example by `rnsca.clip_ragged` with ``partial_z=True``), and
        `to_geojson` writes a position whose Z is NaN with two numbers.

    Notes
    -----
    ``coords`` are float64 and C-contiguous, offsets int64, innermost level first.
    """

    document: dict
    points: tuple
    lines: tuple
    polygons: tuple
    has_z: bool
    sources: tuple | None = None
    partial_z: bool = False

    @property
    def vertex_count(self) -> int:
        """Return the number of positions in the three arrays together."""
        return sum(ragged[1].shape[0] for ragged in (self.points, self.lines, self.polygons))

    def geometry_count(self, kind: str) -> int:
        """Return the geometry count of array ``"points"``, ``"lines"`` or ``"polygons"``."""
        return getattr(self, kind)[2][-1].shape[0] - 1


def loads(data: str | bytes | bytearray | memoryview) -> Any:
    """Return the JSON value `data` (str, bytes, bytearray or memoryview) holds.

    Raises
    ------
    ParseError
        (a ValueError) if `data` is not JSON; NaN and Infinity literals are not JSON. The
        message and the ``position`` attribute give the character offset of the problem.

    Examples
    --------
    >>> loads('{"type": "Point", "coordinates": [1, 2]}')
    {'type': 'Point', 'coordinates': [1, 2]}
    >>> loads('{"type": "Point", "coordinates": [NaN, 2]}')  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rnsca.errors.ParseError: GeoJSON text is not valid JSON: unexpected character, ...
    """
    try:
        return orjson.loads(data)
    except orjson.JSONDecodeError as exc:
        error = ParseError(f"GeoJSON text is not valid JSON: {exc}")
        error.position = exc.pos
        raise error from None


def dumps(obj: object, *, indent: bool = False) -> bytes:
    """Return `obj` (for example `to_geojson` output) as UTF-8 JSON bytes, via orjson.

    NumPy arrays (the ``arrays=True`` output of `to_geojson`) are written as JSON arrays.

    Examples
    --------
    >>> dumps({"type": "Point", "coordinates": np.array([1.0, 2.5])})
    b'{"type":"Point","coordinates":[1.0,2.5]}'
    """
    option = orjson.OPT_SERIALIZE_NUMPY | (orjson.OPT_INDENT_2 if indent else 0)
    return orjson.dumps(obj, option=option)


def from_geojson(obj: dict | str | bytes | bytearray | memoryview, *,
                 max_vertices: int | None = None) -> GeoJSONLayout:
    """Return the ragged arrays of a GeoJSON Geometry, Feature or FeatureCollection.

    Parameters
    ----------
    obj : dict or str or bytes
        The GeoJSON object, or JSON text holding it (parsed with orjson).
    max_vertices : int, optional
        Refuse documents with more positions than this (all geometries together).

    Returns
    -------
    GeoJSONLayout
        The points, lines and polygons of the document as ragged arrays, and the parsed
        document for `to_geojson`.

    Raises
    ------
    ParseError
        `obj` is text that is not JSON.
    InvalidGeometryError
        The document breaks a rule of the module docstring. The message names the JSON
        path of the first problem in document order, also given as the ``path``
        attribute (``""`` for the top level).
    LimitExceededError
        More than `max_vertices` positions.
    InvalidOptionError
        `max_vertices` is not a non-negative int.

    Examples
    --------
    >>> ring = [[0, 0], [4, 0], [4, 4], [0, 0]]
    >>> layout = from_geojson({"type": "Polygon", "coordinates": [ring]})
    >>> geometry_type, coords, offsets = layout.polygons
    >>> geometry_type.name, coords.tolist(), [level.tolist() for level in offsets]
    ('MULTIPOLYGON', [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 0.0]], [[0, 4], [0, 1], [0, 1]])
    >>> bad = {"type": "LineString", "coordinates": [[0, 0], [1, True]]}
    >>> from_geojson(bad)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rnsca.errors.InvalidGeometryError: invalid GeoJSON at coordinates[1][1]: expected a number...
    """
    if max_vertices is not None and (
            isinstance(max_vertices, bool) or not isinstance(max_vertices, int)
            or max_vertices < 0):
        raise InvalidOptionError(
            f"max_vertices must be a non-negative int or None, got {max_vertices!r}")
    document = loads(obj) if isinstance(obj, _TEXT) else obj
    reader = _Reader()
    try:
        reader.document(document)
        return reader.layout(document, max_vertices)
    except _Fallback:
        _Validator(max_vertices).document(document)
        raise AssertionError("GeoJSON reader and validator disagree on the structure") \
            from None


def to_geojson(layout: GeoJSONLayout, points: tuple | None = None, lines: tuple | None = None,
               polygons: tuple | None = None, *,
               keep_empty: bool = False, arrays: bool = False) -> dict:
    """Return the document of `layout` with its geometries taken from ragged arrays.

    Parameters
    ----------
    layout : GeoJSONLayout
        What `from_geojson` returned.
    points, lines, polygons : tuple, optional
        ``(geometry_type, coords, offsets)`` of MULTIPOINT, MULTILINESTRING and
        MULTIPOLYGON geometries, one per geometry of the same array of `layout` and in
        its order (clipped ones, say). None writes the layout's own array.
    keep_empty : bool
        False (default): an empty geometry is dropped from its GeometryCollection, and a
        Feature whose geometry is empty or null is dropped from its FeatureCollection.
        True: nothing is dropped; an empty geometry is written with an empty
        ``coordinates`` (or ``geometries``) array, which RFC 7946 allows, and a null
        geometry stays null. The top-level object is never dropped: it is written as if
        `keep_empty` were true for itself (its members still follow `keep_empty`).
    arrays : bool
        False (default): coordinates are nested lists of floats. True: each coordinate
        array (a position, or a line's or ring's positions) is a NumPy view of the
        ``coords`` given, which skips building millions of small lists; serialize with
        `dumps`. Where some Z is NaN, each position is an array of its own (of 2 or 3
        numbers) and a line's or ring's positions a list of them.

    Returns
    -------
    dict
        A document of the input's shape. Features, Geometries and the FeatureCollection
        keep every member other than the geometry (``properties``, ``id``, foreign
        members; shared with the input, not copied). A geometry gets the type of what
        it holds: a LineString holding two parts becomes a MultiLineString, a Polygon
        holding two polygons a MultiPolygon; Multi* types stay Multi*. A ``bbox`` is
        recomputed where the input had one (6 numbers if it had 6, the document is 3D
        and some position it covers has Z, else 4) and left out where the geometry is
        empty. A position whose Z is NaN is written with 2 numbers (see the module
        docstring on documents that mix 2D and 3D positions). Rings are written as
        given. With lists (``arrays=False``), a geometry the arrays hold exactly as the
        layout does (same parts, same coordinates) keeps the input's own
        ``coordinates`` member, shared and not copied, where that member is what would
        be written anyway (`GeoJSONLayout.sources`): a clip leaves most geometries
        wholly inside its window so, and building their lists again would be most of
        the cost of writing.

    Raises
    ------
    InvalidGeometryError
        An array has the wrong geometry type, or a number of geometries different from
        the layout's.

    Notes
    -----
    The output is made of many small acyclic containers (a list per position, a dict
    per geometry). Allocating them beside a large parsed document triggers full runs of
    Python's cyclic garbage collector, each traversing the whole heap: on a 68 MB
    FeatureCollection (1.6 M positions) writing took 1.9 s with the collector running and
    0.37 s with it paused (``arrays=True``: 0.18 s). The collector is process-wide, so
    this function leaves it alone: an application that owns its process may pause it
    around the call (`rnsca.runtime.collector_paused`), or ask for ``arrays=True``.

    Examples
    --------
    >>> doc = {"type": "Feature", "id": 7, "properties": {"name": "a"},
    ...        "geometry": {"type": "Point", "coordinates": [1, 2]}}
    >>> to_geojson(from_geojson(doc)) == doc
    True
    """
    return write_geojson(layout, points, lines, polygons, keep_empty=keep_empty,
                         arrays=arrays)[0]


def write_geojson(layout: GeoJSONLayout, points: tuple | None = None,
                  lines: tuple | None = None, polygons: tuple | None = None, *,
                  keep_empty: bool = False, arrays: bool = False) -> tuple[dict, np.ndarray]:
    """Return `to_geojson`'s document and, for each Feature written, its input Feature.

    Parameters are those of `to_geojson`.

    Returns
    -------
    document : dict
    feature_source : ndarray of int64
        For a FeatureCollection, the index in the input's ``features`` of each feature of
        the output's (the ones left empty are dropped unless `keep_empty`); for a Feature
        or a Geometry, ``[0]``.

    Examples
    --------
    >>> doc = {"type": "FeatureCollection", "features": [
    ...     {"type": "Feature", "properties": {}, "geometry": None},
    ...     {"type": "Feature", "properties": {}, "geometry": {"type": "Point",
    ...                                                        "coordinates": [1, 2]}}]}
    >>> written, source = write_geojson(from_geojson(doc))
    >>> len(written["features"]), source.tolist()
    (1, [1])
    """
    given = (points, lines, polygons)
    ragged, reuse = [], []
    for kind in (_POINTS, _LINES, _POLYGONS):
        own = getattr(layout, _KIND_NAME[kind])
        array = given[kind]
        coords, offsets = _checked_ragged(
            kind, own if array is None else array, own[2][-1].shape[0] - 1)
        ragged.append((coords, offsets))
        sources = None if arrays or layout.sources is None else layout.sources[kind]
        reuse.append(None if sources is None else _unchanged(
            own, None if array is None else (coords, offsets), sources))
    writer = _Writer(ragged, reuse, layout.sources, 3 if layout.has_z else 2,
                     bool(keep_empty), bool(arrays))
    document = writer.document(layout.document)
    return document, np.asarray(writer.feature_source, dtype=np.int64)


def _unchanged(own: tuple, given: tuple | None, sources: list) -> np.ndarray | None:
    """Return which geometries to write back from their `sources`, or None for none.

    Those that have one and that `given` (coords, offsets) holds as `own` does; all that
    have one if `given` is None.
    """
    reuse = np.fromiter((source is not None for source in sources), dtype=bool,
                        count=len(sources))
    if given is not None:
        _, coords, offsets = own
        given_coords, given_offsets = given
        if given_coords.shape[1] != coords.shape[1]:
            return None
        reuse &= same_geometries(coords, offsets, given_coords, given_offsets)
    return reuse if reuse.any() else None


# --------------------------------------------------------------------------- reading

class _Fallback(Exception):
    """The fast reader met something it does not check itself; the validator decides."""


def _fast_type_of(member: object) -> str:
    """Return the ``type`` of a GeoJSON object; anything else leaves the fast path."""
    if not isinstance(member, dict):
        raise _Fallback
    kind = member.get("type")
    if not isinstance(kind, str):
        raise _Fallback
    return kind


def _non_empty_members(coordinates: list | tuple) -> list:
    """Return the non-empty members of a Multi* geometry's coordinates.

    A member that is not an array leaves the fast path (`_Fallback`).
    """
    members = []
    for member in coordinates:
        if not isinstance(member, _ARRAY):
            raise _Fallback
        if member:
            members.append(member)
    return members


class _Reader:
    """Collects coordinate arrays in document order, checking structure only.

    Every condition that raises `_Fallback` here is an error for `_Validator` too, so the
    validator always names it (or an earlier problem).
    """

    def __init__(self) -> None:
        # One array of positions per point-like geometry.
        self.point_arrays: list[Sequence] = []
        self.line_parts: list[Sequence] = []  # each non-empty line part
        self.line_counts: list[int] = []      # parts per line-like geometry
        self.rings: list[Sequence] = []       # each ring
        self.ring_counts: list[int] = []      # rings per non-empty polygon
        self.polygon_counts: list[int] = []   # non-empty polygons per polygon-like geometry
        # Each geometry's coordinates member, or None if it has members read as nothing.
        self.sources: tuple[list, list, list] = ([], [], [])

    def document(self, doc: object) -> None:
        kind = _fast_type_of(doc)
        doc = cast(dict, doc)
        if kind == "FeatureCollection":
            features = doc.get("features")
            if not isinstance(features, _ARRAY):
                raise _Fallback
            for feature in features:
                self.feature(feature)
        elif kind == "Feature":
            self.feature(doc)
        else:
            self.geometry(doc, 0)

    def feature(self, feature: object) -> None:
        if not isinstance(feature, dict) or "geometry" not in feature:
            raise _Fallback
        kind = feature.get("type")
        if not isinstance(kind, str) or kind != "Feature":
            raise _Fallback
        geometry = feature["geometry"]
        if geometry is not None:
            self.geometry(geometry, 0)

    def geometry(self, geometry: object, depth: int) -> None:
        kind = _fast_type_of(geometry)
        geometry = cast(dict, geometry)
        if kind == "GeometryCollection":
            members = geometry.get("geometries")
            if depth >= MAX_COLLECTION_DEPTH or not isinstance(members, _ARRAY):
                raise _Fallback
            for member in members:
                self.geometry(member, depth + 1)
            return
        coordinates = geometry.get("coordinates")
        if not isinstance(coordinates, _ARRAY):
            raise _Fallback
        if kind == "Point":
            self.point_arrays.append([coordinates] if coordinates else [])
            self.sources[_POINTS].append(coordinates)
        elif kind == "MultiPoint":
            self.point_arrays.append(coordinates)
            self.sources[_POINTS].append(coordinates)
        elif kind == "LineString":
            if coordinates:
                self.line_parts.append(coordinates)
            self.line_counts.append(1 if coordinates else 0)
            self.sources[_LINES].append(coordinates)
        elif kind == "MultiLineString":
            parts = _non_empty_members(coordinates)
            self.line_parts.extend(parts)
            self.line_counts.append(len(parts))
            self.sources[_LINES].append(coordinates if len(parts) == len(coordinates) else None)
        elif kind == "Polygon":
            if coordinates:
                self.rings.extend(coordinates)  # rings are checked in bulk in `layout`
                self.ring_counts.append(len(coordinates))
                self.polygon_counts.append(1)
            else:
                self.polygon_counts.append(0)
            self.sources[_POLYGONS].append(coordinates)
        elif kind == "MultiPolygon":
            polygons = _non_empty_members(coordinates)
            for polygon in polygons:
                self.rings.extend(polygon)
                self.ring_counts.append(len(polygon))
            self.polygon_counts.append(len(polygons))
            self.sources[_POLYGONS].append(
                coordinates if len(polygons) == len(coordinates) else None)
        else:
            raise _Fallback

    def layout(self, document: dict, max_vertices: int | None) -> GeoJSONLayout:
        """Return the layout, checking positions and shapes in bulk."""
        if not set(map(type, self.rings)) <= _ARRAY_TYPES and not all(
                isinstance(ring, _ARRAY) for ring in self.rings):
            raise _Fallback
        arrays = self.point_arrays + self.line_parts + self.rings
        sizes = np.fromiter(map(len, arrays), np.int64, len(arrays))
        total = int(sizes.sum())
        if max_vertices is not None and total > max_vertices:
            raise LimitExceededError(
                f"GeoJSON has {total} positions, more than max_vertices={max_vertices}")
        read = _coordinates(arrays, sizes)
        if read is None:
            # A check failed, or a number is of a type the fast path does not take
            # (a NumPy scalar): the validator names the problem or vouches for the data.
            validator = _Validator(max_vertices)
            validator.document(document)
            coords = _checked_coordinates(list(chain.from_iterable(arrays)), validator.dim)
            partial_z = validator.partial_z
            sources = None
        else:
            coords, plain, partial_z = read
            sources = self.plain_sources(plain)
        n_points = len(self.point_arrays)
        n_parts = len(self.line_parts)
        point_sizes = sizes[:n_points]
        part_sizes = sizes[n_points:n_points + n_parts]
        ring_sizes = sizes[n_points + n_parts:]
        ring_offsets = exclusive_sum(ring_sizes)
        ring_coords = coords[point_sizes.sum() + part_sizes.sum():]
        if (part_sizes < 2).any() or (ring_sizes < 4).any() or not _rings_closed(
                ring_coords, ring_offsets, partial_z):
            _Validator(max_vertices).document(document)
            raise AssertionError("GeoJSON reader and validator disagree on line or ring sizes")
        n_point_coords = int(point_sizes.sum())
        n_line_coords = int(part_sizes.sum())
        points = (_RAGGED_TYPE[_POINTS], coords[:n_point_coords], (exclusive_sum(point_sizes),))
        lines = (_RAGGED_TYPE[_LINES], coords[n_point_coords:n_point_coords + n_line_coords],
                 (exclusive_sum(part_sizes), exclusive_sum(self.line_counts)))
        polygons = (_RAGGED_TYPE[_POLYGONS], ring_coords,
                    (ring_offsets, exclusive_sum(self.ring_counts),
                     exclusive_sum(self.polygon_counts)))
        return GeoJSONLayout(document, points, lines, polygons, coords.shape[1] == 3, sources,
                             partial_z)

    def plain_sources(self, plain: np.ndarray) -> tuple:
        """Return `sources`, with None for each geometry that has an array not `plain`.

        `plain` holds a flag per coordinate array, in the order of `layout`'s `arrays`.
        """
        if plain.all():  # the usual case: nothing to look up (a small request's 7 NumPy calls)
            return self.sources
        not_plain = np.concatenate(([0], np.cumsum(~plain)))
        n_points, n_parts = len(self.point_arrays), len(self.line_parts)
        ring_offsets = exclusive_sum(self.ring_counts)
        # The first array of each geometry of each kind, and the end of the last.
        firsts = (np.arange(n_points + 1),
                  n_points + exclusive_sum(self.line_counts),
                  n_points + n_parts + ring_offsets[exclusive_sum(self.polygon_counts)])
        for sources, first in zip(self.sources, firsts, strict=True):
            for geometry in np.flatnonzero(not_plain[first[1:]] != not_plain[first[:-1]]):
                sources[geometry] = None
        return self.sources


def _rings_closed(coords: np.ndarray, ring_offsets: np.ndarray, partial_z: bool) -> bool:
    """Return whether every ring's first and last positions are equal (rings not empty).

    With `partial_z`, in x, y and Z or in x and y with both Z NaN (both 2D).
    """
    firsts, lasts = coords[ring_offsets[:-1]], coords[ring_offsets[1:] - 1]
    if partial_z:
        return np.array_equal(firsts, lasts, equal_nan=True)
    return bool((firsts == lasts).all())


#: About how many positions are converted per step: the objects of a chunk stay in cache
#: from packing them to reading them.
_CHUNK = 1 << 15

#: ormsgpack packs only what it has a MessagePack type for; these options make it refuse
#: (TypeError) every other object instead of converting it: subclasses of list, int or
#: float, ints beyond 64 bits, dataclasses, enums (packed as their value otherwise),
#: dates, UUIDs. NumPy scalars and arrays are refused without an option.
_PACK_STRICT = (ormsgpack.OPT_PASSTHROUGH_SUBCLASS | ormsgpack.OPT_PASSTHROUGH_BIG_INT
                | ormsgpack.OPT_PASSTHROUGH_DATACLASS | ormsgpack.OPT_PASSTHROUGH_ENUM
                | ormsgpack.OPT_PASSTHROUGH_DATETIME | ormsgpack.OPT_PASSTHROUGH_UUID)
#: Also refuse tuples, which MessagePack cannot tell from lists: a chunk without any
#: is packed with this, so that its arrays can be plain.
_PACK_LISTS_ONLY = _PACK_STRICT | ormsgpack.OPT_PASSTHROUGH_TUPLE


def _coordinates(arrays: list, sizes: np.ndarray) -> tuple | None:
    """Return the positions of `arrays`, which arrays are plain, and whether Z is partial.

    `arrays` are lists of positions; Z is partial when some position lacks the Z others
    have. `sizes` holds the length of each array. The positions are float64 (n, 2), or (n, 3)
    if any has three or more numbers (Z NaN for those with two); an array is plain if it
    is a list of lists of floats of the document's dimension (see `read_positions`).
    Returns None if any check fails: then `_Validator` names the problem, or, for numbers
    of a type only it takes (NumPy scalars), vouches for the data.
    """
    starts = exclusive_sum(sizes)
    total = int(starts[-1])
    if total == 0:
        return np.empty((0, 2), dtype=np.float64), np.zeros(len(arrays), dtype=bool), False
    first: Any = next(chain.from_iterable(arrays), None)
    if type(first) not in _ARRAY_TYPES or len(first) < 2:
        return None
    # The first position guesses the dimension: one pass for a document of one dimension;
    # a 2D guess that meets a 3D position reads everything again in 3D.
    read = _read_chunks(arrays, sizes, starts, 3 if len(first) >= 3 else 2)
    if read is HAS_Z:
        read = _read_chunks(arrays, sizes, starts, 3)
    return read


def _read_chunks(arrays: list, sizes: np.ndarray, starts: np.ndarray, dim: int) -> Any:
    """Return `_coordinates`' triple read in `dim`, `HAS_Z` (2D only), or None if refused."""
    total = int(starts[-1])
    out = np.empty((total, dim), dtype=np.float64)
    plain = np.zeros(len(arrays), dtype=bool)
    partial_z = False
    if total <= _CHUNK:  # one chunk: a small request's bounds without four NumPy calls
        bounds = [0, len(arrays)]
    else:
        cuts = np.searchsorted(starts, np.arange(_CHUNK, total, _CHUNK), side="right")
        bounds = np.unique(np.concatenate(([0], cuts, [len(arrays)]))).tolist()
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        chunk = arrays[lo:hi]
        has_tuples = False
        try:
            packed = ormsgpack.packb(chunk, option=_PACK_LISTS_ONLY)
        except TypeError:  # ormsgpack.MsgpackEncodeError, a cycle included
            try:
                packed = ormsgpack.packb(chunk, option=_PACK_STRICT)
            except TypeError:
                return None
            has_tuples = True
        result = read_positions(np.frombuffer(packed, dtype=np.uint8), sizes[lo:hi],
                                out[starts[lo]:starts[hi]], plain[lo:hi])
        if result == REFUSED:
            return None
        if result == HAS_Z:
            return HAS_Z
        partial_z |= result == PARTIAL_Z
        if has_tuples:
            plain[lo:hi] = False
    return out, plain, partial_z


def _checked_coordinates(positions: list, dim: int) -> np.ndarray:
    """Return positions the validator has accepted as a float64 (n, dim) array.

    In 3D, a position of two numbers gets Z = NaN.
    """
    out = np.empty((len(positions), dim), dtype=np.float64)
    for row, position in enumerate(positions):
        values = [float(value) for value in position[:dim]]
        out[row] = values if len(values) == dim else values + [math.nan]
    return out


class _Validator:
    """The slow, exact walk: raises at the first problem in document order."""

    def __init__(self, max_vertices: int | None) -> None:
        self.max_vertices = max_vertices
        self.count = 0
        self.dims_seen: set[int] = set()  # 2 and 3: the dimensions of the positions met

    @property
    def dim(self) -> int:
        """Return the document's dimension: 3 if any position met has Z, else 2."""
        return 3 if 3 in self.dims_seen else 2

    @property
    def partial_z(self) -> bool:
        """Return whether both 2D and 3D positions were met."""
        return len(self.dims_seen) == 2

    def document(self, doc: object) -> None:
        if not isinstance(doc, dict):
            _fail("", f"expected a GeoJSON object, got {_describe(doc)}")
        kind = _type_of(doc, "")
        if kind == "FeatureCollection":
            features = _member(doc, "features", "", kind)
            _require_array(features, "features")
            for i, feature in enumerate(features):
                self.feature(feature, f"features[{i}]")
        elif kind == "Feature":
            self.feature(doc, "")
        elif kind in GEOMETRY_TYPES:
            self.geometry(doc, "", 0)
        else:
            _fail("type", f"unknown GeoJSON type {kind!r}; expected Feature, "
                          f"FeatureCollection or one of {', '.join(GEOMETRY_TYPES)}")

    def feature(self, feature: object, path: str) -> None:
        if not isinstance(feature, dict):
            _fail(path, f"expected a Feature object, got {_describe(feature)}")
        kind = _type_of(feature, path)
        if kind != "Feature":
            _fail(_join(path, "type"), f"expected \"Feature\", got {kind!r}")
        geometry = _member(feature, "geometry", path, kind,
                           hint=" (use null for a feature without geometry)")
        if geometry is not None:
            self.geometry(geometry, _join(path, "geometry"), 0)

    def geometry(self, geometry: object, path: str, depth: int) -> None:
        if not isinstance(geometry, dict):
            _fail(path, f"expected a geometry object, got {_describe(geometry)}")
        kind = _type_of(geometry, path)
        if kind not in GEOMETRY_TYPES:
            _fail(_join(path, "type"),
                  f"expected a geometry type ({', '.join(GEOMETRY_TYPES)}), got {kind!r}")
        if kind == "GeometryCollection":
            if depth >= MAX_COLLECTION_DEPTH:
                _fail(path, f"GeometryCollections nested more than {MAX_COLLECTION_DEPTH} "
                            f"levels deep")
            members = _member(geometry, "geometries", path, kind)
            members_path = _join(path, "geometries")
            _require_array(members, members_path)
            for i, member in enumerate(members):
                self.geometry(member, f"{members_path}[{i}]", depth + 1)
            return
        coordinates = _member(geometry, "coordinates", path, kind)
        path = _join(path, "coordinates")
        _require_array(coordinates, path)
        if kind == "Point":
            if len(coordinates):
                self.position(coordinates, path)
        elif kind == "MultiPoint":
            for i, position in enumerate(coordinates):
                self.position(position, f"{path}[{i}]")
        elif kind == "LineString":
            self.line(coordinates, path)
        elif kind == "MultiLineString":
            for i, part in enumerate(coordinates):
                _require_array(part, f"{path}[{i}]")
                self.line(part, f"{path}[{i}]")
        elif kind == "Polygon":
            self.polygon(coordinates, path)
        else:
            for i, polygon in enumerate(coordinates):
                _require_array(polygon, f"{path}[{i}]")
                self.polygon(polygon, f"{path}[{i}]")

    def line(self, positions: Sequence, path: str) -> None:
        if len(positions) == 1:
            _fail(path, "a LineString needs at least 2 positions, got 1")
        for i, position in enumerate(positions):
            self.position(position, f"{path}[{i}]")

    def polygon(self, rings: Sequence, path: str) -> None:
        for i, ring in enumerate(rings):
            ring_path = f"{path}[{i}]"
            _require_array(ring, ring_path)
            if len(ring) < 4:
                _fail(ring_path, f"a polygon ring needs at least 4 positions, got {len(ring)}")
            for j, position in enumerate(ring):
                self.position(position, f"{ring_path}[{j}]")
            # Equal in x, y and Z, or both without Z: a 2D end and a 3D end differ.
            first = [float(v) for v in ring[0][:3]]
            last = [float(v) for v in ring[-1][:3]]
            if first != last:
                _fail(ring_path, f"polygon ring is not closed: its first position {first} "
                                 f"differs from its last {last}")

    def position(self, position: object, path: str) -> None:
        if not isinstance(position, _ARRAY):
            _fail(path, f"expected a position (an array of 2 or 3 numbers), got "
                        f"{_describe(position)}")
        if len(position) < 2:
            _fail(path, f"a position needs at least 2 numbers, got {len(position)}")
        for i, value in enumerate(position):
            if isinstance(value, _BOOL) or not isinstance(value, _NUMBER):
                _fail(f"{path}[{i}]", f"expected a number, got {_describe(value)}")
            try:
                finite = math.isfinite(float(value))
            except OverflowError:
                finite = False
            if not finite:
                _fail(f"{path}[{i}]", f"expected a finite number, got {value!r}")
        self.dims_seen.add(3 if len(position) >= 3 else 2)
        self.count += 1
        if self.max_vertices is not None and self.count > self.max_vertices:
            raise LimitExceededError(
                f"GeoJSON has more than max_vertices={self.max_vertices} positions")


def _fail(path: str, reason: str) -> NoReturn:
    """Raise InvalidGeometryError for the problem at JSON `path`."""
    error = InvalidGeometryError(f"invalid GeoJSON at {path or '<top level>'}: {reason}")
    error.path = path
    raise error


def _join(path: str, member: str) -> str:
    return f"{path}.{member}" if path else member


def _type_of(obj: dict, path: str) -> str:
    if "type" not in obj:
        _fail(path, "missing member \"type\"")
    kind = obj["type"]
    if not isinstance(kind, str):
        _fail(_join(path, "type"), f"expected a string, got {_describe(kind)}")
    return kind


def _member(obj: dict, name: str, path: str, kind: str, hint: str = "") -> Any:
    if name not in obj:
        _fail(path, f"{kind} has no \"{name}\" member{hint}")
    return obj[name]


def _require_array(value: object, path: str) -> None:
    if not isinstance(value, _ARRAY):
        _fail(path, f"expected an array, got {_describe(value)}")


def _describe(value: object) -> str:
    """Name a JSON value's type for a message, with the value when it is short."""
    if value is None:
        return "null"
    if isinstance(value, _BOOL):
        return f"boolean {bool(value)}"
    if isinstance(value, str):
        text = value if len(value) <= 20 else value[:20] + "..."
        return f"string {text!r}"
    if isinstance(value, _ARRAY):
        return f"an array of {len(value)}"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, _NUMBER):
        return f"number {value!r}"
    return type(value).__name__


# --------------------------------------------------------------------------- writing

def _checked_ragged(kind: int, ragged: tuple, count: int) -> tuple:
    """Return ``(coords, offsets as lists)`` of a ragged triple, checked against the layout."""
    try:
        geometry_type, coords, offsets = ragged
        name = geometry_type.upper() if isinstance(geometry_type, str) else \
            shapely.GeometryType(geometry_type).name
        depth = len(offsets)
    except (TypeError, ValueError):
        raise InvalidGeometryError(
            f"{_KIND_NAME[kind]} must be a (geometry_type, coords, offsets) triple") from None
    expected = _RAGGED_TYPE[kind]
    if name != expected.name or depth != kind + 1:
        raise InvalidGeometryError(
            f"{_KIND_NAME[kind]} must be {expected.name} with {kind + 1} offset arrays, got "
            f"{name} with {depth}")
    coords = np.ascontiguousarray(coords, dtype=np.float64)
    offsets = tuple(np.ascontiguousarray(level, dtype=np.int64) for level in offsets)
    if offsets[-1].ndim != 1 or offsets[-1].shape[0] - 1 != count:
        raise InvalidGeometryError(
            f"{_KIND_NAME[kind]} holds {offsets[-1].shape[0] - 1} geometries, the layout {count}")
    below = coords.shape[0] if coords.ndim == 2 else -1
    for level, level_offsets in enumerate(offsets):
        if level_offsets.ndim != 1 or level_offsets.shape[0] == 0 or level_offsets[0] != 0 \
                or level_offsets[-1] != below or (np.diff(level_offsets) < 0).any():
            raise InvalidGeometryError(
                f"{_KIND_NAME[kind]}: offsets[{level}] must rise from 0 to the length of "
                + ("coords" if level == 0 else f"offsets[{level - 1}] minus one"))
        below = level_offsets.shape[0] - 1
    return coords, offsets


class _Writer:
    """Walks a document in `_Reader` order, writing each geometry from the arrays."""

    def __init__(self, ragged: list, reuse: list, sources: tuple | None, dim: int,
                 keep_empty: bool, arrays: bool) -> None:
        self.coords = [coords for coords, _ in ragged]
        (points,), (parts, lines), (rings, polygons, shapes) = (
            offsets for _, offsets in ragged)
        # The positions of geometry i are bounds[i]:bounds[i + 1] in its array.
        bounds = [points, parts[lines], rings[polygons[shapes]]]
        # Indexed only where `reuse` flags a geometry, which has a source then.
        self.sources: tuple = sources if sources is not None else ((), (), ())
        self.reuse = [None if flags is None else flags.tolist() for flags in reuse]
        # The positions of geometries written back from their source are not converted:
        # `values` holds the others, and `starts` the innermost offsets into it.
        self.values: list = []
        starts: list[np.ndarray] = []
        # Positions whose Z is NaN (2D ones of a document that mixes dimensions, and what
        # was computed from them) are written with two numbers: a test per array here,
        # and the slower writing of positions one by one only where there is one.
        self.missing_z = any(coords.shape[1] == 3 and np.isnan(coords[:, 2]).any()
                             for coords, _ in ragged)
        for (coords, (innermost, *_)), flags, rows in zip(ragged, reuse, bounds, strict=True):
            if flags is None:
                self.values.append(_positions(coords, arrays, self.missing_z))
                starts.append(innermost)
                continue
            edges = np.bincount(rows[:-1][flags], minlength=coords.shape[0] + 1) \
                - np.bincount(rows[1:][flags], minlength=coords.shape[0] + 1)
            convert = np.cumsum(edges[:-1]) == 0
            self.values.append(_positions(coords[convert], False, self.missing_z))
            starts.append(np.concatenate(([0], np.cumsum(convert)))[innermost])
        self.offsets = [[level.tolist() for level in offsets] for _, offsets in ragged]
        self.starts = [level.tolist() for level in starts]
        # Every line part and polygon written once, up front: a slice per part, ring and
        # polygon in three comprehensions costs less than nested ones per geometry.
        self.parts = _split(self.values[_LINES], self.starts[_LINES])
        self.polygon_rings = _split(_split(self.values[_POLYGONS], self.starts[_POLYGONS]),
                                    self.offsets[_POLYGONS][1])
        self.bounds = [level.tolist() for level in bounds]
        self.next = [0, 0, 0]
        self.keep_empty = keep_empty
        self.dim = dim
        # The input feature of each feature written (a single Feature or Geometry: [0]).
        self.feature_source = [0]

    def document(self, doc: dict) -> dict:
        kind = doc["type"]
        if kind != "FeatureCollection":
            top = self.feature(doc, True, False)[0] if kind == "Feature" \
                else self.geometry(doc, True, False)[0]
            assert top is not None  # kept: the top-level object is never dropped
            return top
        want = "bbox" in doc
        features, box = [], None
        self.feature_source = []
        for index, feature in enumerate(doc["features"]):
            out, feature_box = self.feature(feature, self.keep_empty, want)
            if out is not None:
                features.append(out)
                self.feature_source.append(index)
                box = _union(box, feature_box, self.missing_z)
        return self.replace(doc, "features", features, box)

    def feature(self, feature: dict, keep: bool,
                want: bool) -> tuple[dict | None, tuple | None]:
        """Return the written feature (None if dropped) and its bbox (None if empty or unwanted)."""
        want = want or "bbox" in feature
        geometry = feature["geometry"]
        if geometry is None:
            if not keep:
                return None, None
            out, box = None, None
        else:
            out, box, _ = self.geometry(geometry, keep, want)
            if out is None:
                return None, None
        return self.replace(feature, "geometry", out, box), box

    def geometry(self, geometry: dict, keep: bool,
                 want: bool) -> tuple[dict | None, tuple | None, bool]:
        """Return the written geometry (None if dropped), its bbox and whether it is empty."""
        want = want or "bbox" in geometry
        kind = geometry["type"]
        if kind == "GeometryCollection":
            members, box, empty = [], None, True
            for member in geometry["geometries"]:
                out, member_box, member_empty = self.geometry(member, self.keep_empty, want)
                if out is not None:
                    members.append(out)
                if not member_empty:
                    empty = False
                    box = _union(box, member_box, self.missing_z)
            if empty and not keep:
                return None, None, True
            return self.replace(geometry, "geometries", members, box), box, empty
        index = _KIND[kind]
        i = self.next[index]
        self.next[index] = i + 1
        lo, hi = self.bounds[index][i], self.bounds[index][i + 1]
        if hi == lo:
            if not keep:
                return None, None, True
            coordinates, box = [], None
        else:
            reuse = self.reuse[index]
            if reuse is not None and reuse[i]:
                coordinates = self.sources[index][i]  # the same positions, and type
            else:
                kind, coordinates = _WRITE[index](self, kind, i)
            box = None
            if want:
                rows = self.coords[index][lo:hi]
                if self.missing_z:  # Z over the positions that have one (NaN if none)
                    box = (np.fmin.reduce(rows, axis=0), np.fmax.reduce(rows, axis=0))
                else:
                    box = (rows.min(axis=0), rows.max(axis=0))
        out = dict(geometry)  # members keep their order when set again
        out["type"] = kind
        out["coordinates"] = coordinates
        if "bbox" in out:  # then `want` is true: `box` is None only if the geometry is empty
            self.set_bbox(out, box)
        return out, box, hi == lo

    # The type and coordinates of non-empty geometry i of each array, given its input type.

    def points(self, kind: str, i: int) -> tuple[str, list]:
        starts = self.starts[_POINTS]
        lo, hi = starts[i], starts[i + 1]
        values = self.values[_POINTS]
        return kind, (values[lo] if kind == "Point" else values[lo:hi])

    def lines(self, kind: str, i: int) -> tuple[str, list]:
        _, geometries = self.offsets[_LINES]
        first, last = geometries[i], geometries[i + 1]
        if kind == "LineString" and last - first == 1:
            return kind, self.parts[first]
        return "MultiLineString", self.parts[first:last]

    def polygons(self, kind: str, i: int) -> tuple[str, list]:
        _, _, geometries = self.offsets[_POLYGONS]
        first, last = geometries[i], geometries[i + 1]
        if kind == "Polygon" and last - first == 1:
            return kind, self.polygon_rings[first]
        return "MultiPolygon", self.polygon_rings[first:last]

    def replace(self, obj: dict, name: str, value: object, box: tuple | None) -> dict:
        """Return a copy of `obj` with member `name` set and its bbox recomputed."""
        out = dict(obj)  # members keep their order when set again
        out[name] = value
        if "bbox" in out:
            self.set_bbox(out, box)
        return out

    def set_bbox(self, out: dict, box: tuple | None) -> None:
        """Recompute the ``bbox`` member of `out` from `box`, or drop it if `box` is None."""
        if box is None:
            del out["bbox"]
        else:
            out["bbox"] = self.bbox(box, out["bbox"])

    def bbox(self, box: tuple, old: object) -> list:
        """Return ``[min..., max...]``, 3D only if the document and the old bbox are.

        And if some position it covers has Z (in a document that mixes dimensions).
        """
        dim = 3 if self.dim == 3 and isinstance(old, _ARRAY) and len(old) == 6 else 2
        if dim == 3 and self.missing_z and np.isnan(box[0][2]):
            dim = 2
        return box[0][:dim].tolist() + box[1][:dim].tolist()


_WRITE = (_Writer.points, _Writer.lines, _Writer.polygons)


def _split(items: Sequence, offsets: list) -> list:
    """Return ``[items[offsets[k]:offsets[k + 1]] for each k]``."""
    return [items[lo:hi] for lo, hi in zip(offsets[:-1], offsets[1:], strict=True)]


def _union(box, other, missing_z=False):
    """Return the bbox covering both (either may be None for nothing).

    With `missing_z`, a NaN (a Z range over no position) is ignored beside a number.
    """
    if box is None:
        return other
    if other is None:
        return box
    if missing_z:
        return np.fmin(box[0], other[0]), np.fmax(box[1], other[1])
    return np.minimum(box[0], other[0]), np.maximum(box[1], other[1])


def _positions(coords: np.ndarray, arrays: bool, missing_z: bool) -> np.ndarray | list:
    """Return `coords` as the writer indexes them: an array, or a list per position.

    With `missing_z`, an (n, 3) `coords` gives a list whose positions with a NaN Z have
    two numbers (`arrays`: an array of 3 or 2 numbers each).
    """
    if not (missing_z and coords.shape[1] == 3):
        return coords if arrays else coords.tolist()
    # Each position's list (or view) made once, in C, and placed through an object array:
    # a Python loop over the positions to shorten them cost as much as all the rest.
    missing = np.isnan(coords[:, 2])
    values = np.empty(coords.shape[0], dtype=object)
    for rows, width in ((~missing, 3), (missing, 2)):
        kept = coords[rows, :width]
        values[rows] = np.fromiter(kept if arrays else kept.tolist(), dtype=object,
                                   count=kept.shape[0])
    return values.tolist()
