"""GeoJSON files read without a Python object per number.

`read_file_features` reads the bytes of a GeoJSON file (a FeatureCollection, Feature or
Geometry; or, for a text sequence, one per line) into what `rnsca.io.geojson.from_geojson`
would give for its features: the three ragged arrays, with each feature's properties,
id and array. A compiled scan (`rnsca.kernels.geojson_scan`) reads every number of every
geometry's ``coordinates`` in one pass over the bytes, correctly rounded, and hands
orjson a *skeleton* of the document where each coordinates value is the geometry's
index; orjson then makes the objects of the rest (types, ids, properties), and a second
compiled pass (`rnsca.kernels.geojson_build`) checks the geometries and writes the arrays.

The result is the same, bit for bit, as parsing the whole file with orjson and reading it
with ``from_geojson``; in particular ``-0`` (an integer to JSON parsers) is +0.0 and
``-0.0`` is -0.0. The reader takes only documents it reads exactly so: for anything else
(invalid JSON or GeoJSON, GeometryCollections, geometry types it does not know,
duplicated keys the structure depends on, ...) it returns None, and the caller reads the
file the exact way, which names the problem as before.

Measured (CPU s, one process, alternated): 213 MB, 100,000 polygons, 10.4M numbers: 7.1 -> 1.1 s.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import orjson
import shapely

from rnsca.kernels.geojson_build import (
    BUILT,
    CURSOR_SLOTS,
    ROW_SLOTS,
    TYPE_CODES,
    Layout,
    build,
)
from rnsca.kernels.geojson_scan import PADDING, SCANNED, scan

__all__ = ["FileFeatures", "padded_bytes", "read_file_features"]

# The pattern `scan` records for a geometry found where each top-level type has one.
_TOP_GEOMETRY, _FEATURE_GEOMETRY, _COLLECTION_GEOMETRY = 0, 1, 2


@dataclass(frozen=True, slots=True)
class FileFeatures:
    """The features of a GeoJSON file, as ``from_geojson`` reads them.

    Attributes
    ----------
    properties, ids : list
        Each feature's ``properties`` and ``id`` member (None where absent; None for
        both where the document is a bare Geometry).
    kinds : ndarray of int64
        Each feature's array: 0 points, 1 lines, 2 polygons; -2 for a null geometry.
    points, lines, polygons : tuple
        ``(geometry_type, coords, offsets)`` as in `rnsca.io.geojson.GeoJSONLayout`.
    partial_z : bool
        Whether the document mixes 2D and 3D positions (Z NaN for the 2D ones).
    """

    properties: list
    ids: list
    kinds: np.ndarray
    points: tuple
    lines: tuple
    polygons: tuple
    partial_z: bool


def padded_bytes(path: str | Path) -> tuple[np.ndarray, int]:
    """Return the bytes of the file at `path` followed by zeros, as `read_file_features` takes them.

    Returns
    -------
    data : ndarray of uint8
        The file's bytes, then `rnsca.kernels.geojson_scan.PADDING` zero bytes.
    size : int
        The file's size.
    """
    with open(path, "rb") as f:
        size = f.seek(0, 2)
        f.seek(0)
        data = np.empty(size + PADDING, dtype=np.uint8)  # np.zeros would touch every page
        data[size:] = 0
        if f.readinto(data[:size].data) != size:
            raise OSError(f"{path}: changed size while being read")
    return data, size


def padded_text(text: bytes | bytearray | memoryview) -> tuple[np.ndarray, int]:
    """Return GeoJSON text held in memory as `padded_bytes` returns a file's (a copy)."""
    view = memoryview(text).cast("B")
    size = view.nbytes
    data = np.empty(size + PADDING, dtype=np.uint8)
    data[:size] = np.frombuffer(view, dtype=np.uint8)
    data[size:] = 0
    return data, size


def read_file_features(data: np.ndarray, size: int, *,
                       sequence: bool = False) -> FileFeatures | None:
    """Return the features of GeoJSON bytes, or None for a document to read the exact way.

    Parameters
    ----------
    data : ndarray of uint8
        The bytes (`padded_bytes`): ``data[:size]``, then at least ``PADDING`` zeros.
    size : int
    sequence : bool
        One document per line (GeoJSON text sequences, newline-delimited GeoJSON,
        RS-prefixed or not), as `rnsca.tiles.sources.read_features` reads them.

    Returns
    -------
    FileFeatures or None
        None for anything this reader does not take (see the module docstring).
    """
    if data.dtype != np.uint8 or data.ndim != 1 or data.shape[0] < size + PADDING \
            or data[size:size + PADDING].any():
        # The scan reads past the document until a zero byte, with no bounds check.
        raise ValueError(f"data must be uint8 bytes followed by {PADDING} zero bytes")
    scanned = scan(data, size, bool(sequence))
    if scanned.status != SCANNED:
        return None
    try:
        skeleton = orjson.loads(memoryview(scanned.skeleton))
    except orjson.JSONDecodeError:
        return None
    documents = skeleton if sequence else [skeleton]
    walked = _walk(documents, scanned.geometries)
    if walked is None:
        return None
    properties, ids, kinds, types = walked
    values = scanned.values
    for index, first, end in scanned.slow.tolist():  # numbers of > 19 digits near a tie
        values[index] = float(data[first:end].tobytes())
    dim = 3 if scanned.max_numbers >= 3 else 2
    cursor = np.zeros(CURSOR_SLOTS, dtype=np.int64)
    empty_coords, empty = np.empty((0, dim)), np.empty(0, dtype=np.int64)
    if build(scanned.events, values, types,
             Layout(*([empty_coords, empty, empty_coords] + [empty] * 2 + [empty_coords]
                      + [empty] * 3)), cursor, False) != BUILT:
        return None
    sizes = cursor.tolist()
    # Where every number is a coordinate of the one array that has positions, the values
    # viewed as (n, dim) are its coords: not copied (the polygons file: 83 MB less).
    shared = scanned.min_numbers == scanned.max_numbers == dim \
        and sum(sizes[slot] > 0 for slot in ROW_SLOTS) == 1
    arrays = [np.empty((0 if shared else sizes[slot], dim)) if slot in ROW_SLOTS
              else np.zeros(sizes[slot] + 1, dtype=np.int64) for slot in range(CURSOR_SLOTS)]
    build(scanned.events, values, types, Layout(*arrays),
          np.zeros(CURSOR_SLOTS, dtype=np.int64), True)
    if shared:
        arrays[next(slot for slot in ROW_SLOTS if sizes[slot] > 0)] = values.reshape(-1, dim)
    out = Layout(*arrays)
    partial_z = dim == 3 and scanned.min_numbers == 2
    return FileFeatures(
        properties, ids, kinds,
        (shapely.GeometryType.MULTIPOINT, out.point_coords, (out.point_offsets,)),
        (shapely.GeometryType.MULTILINESTRING, out.line_coords,
         (out.part_offsets, out.line_offsets)),
        (shapely.GeometryType.MULTIPOLYGON, out.polygon_coords,
         (out.ring_offsets, out.polygon_offsets, out.shape_offsets)),
        partial_z)


def _walk(documents: list, geometries: np.ndarray) -> tuple | None:
    """Return (properties, ids, kinds, geometry types) of the documents' features, or None.

    Each feature's geometry must be null or an object of a `TYPE_CODES` type whose
    ``coordinates`` is the next placeholder the scan wrote, found where this document's
    top-level type has its geometries. Every placeholder sits in such a place, at most
    one per object, so the indices read being exactly 0, 1, ..., n - 1 proves each was
    read where it was written (a genuine integer in a geometry's place would repeat one).
    """
    patterns = geometries[:, 1].tolist()
    owners = geometries[:, 2].tolist()
    count = len(patterns)
    properties: list = []
    ids: list = []
    kinds: list[int] = []
    types: list[int] = []
    for number, document in enumerate(documents):
        if type(document) is not dict:
            return None
        kind = document.get("type")
        if kind == "FeatureCollection":
            features = document.get("features")
            pattern = _COLLECTION_GEOMETRY
            if type(features) is not list:
                return None
        elif kind == "Feature":
            features, pattern = [document], _FEATURE_GEOMETRY
        else:
            features = [{"type": "Feature", "geometry": document, "properties": None}]
            pattern = _TOP_GEOMETRY
        for feature in features:
            if type(feature) is not dict or feature.get("type") != "Feature" \
                    or "geometry" not in feature:
                return None
            geometry = feature["geometry"]
            if geometry is None:
                kinds.append(-2)
            else:
                if type(geometry) is not dict:
                    return None
                name = geometry.get("type")
                code = TYPE_CODES.get(name) if type(name) is str else None
                index = geometry.get("coordinates")
                if code is None or type(index) is not int or index != len(types) \
                        or index >= count or patterns[index] != pattern \
                        or owners[index] != number:
                    return None
                types.append(code)
                kinds.append(code >> 1)
            properties.append(feature.get("properties"))
            ids.append(feature.get("id"))
    if len(types) != count:
        return None
    return (properties, ids, np.array(kinds, dtype=np.int64),
            np.array(types, dtype=np.int8))
