"""Shapely geometries to and from a GeoJSON FeatureCollection whose ids are positions.

Feature ``i`` carries the geometry at position ``i`` (its ``id``) and no properties: the
server keeps ids, so the features of the answer say which positions they came from, and
the caller's other columns stay with the caller. GEOS writes and reads the geometries
(``shapely.to_geojson``, ``shapely.from_geojson``), in C.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import shapely

from rnsca_client.errors import InvalidInputError, ResponseFormatError

__all__ = ["feature_collection", "read_features"]

_EMPTY_TYPES = {0: "Point", 1: "LineString", 2: "LineString", 3: "Polygon", 4: "MultiPoint",
                5: "MultiLineString", 6: "MultiPolygon", 7: "GeometryCollection"}


def feature_collection(geometries: np.ndarray, ids: np.ndarray | int = 0) -> bytes:
    """Return the JSON bytes of a FeatureCollection of `geometries` with their `ids`.

    `ids` is one integer per geometry, or the first of consecutive ones. A missing
    geometry (None) is a feature whose geometry is null; an empty one has no
    coordinates.

    Raises
    ------
    InvalidInputError
        A coordinate is NaN or infinite (JSON cannot carry them).

    Examples
    --------
    >>> feature_collection(np.array([shapely.Point(1, 2), None], dtype=object), ids=5)
    b'{"type":"FeatureCollection","features":[{"type":"Feature","id":5,"properties":{},\
"geometry":{"type":"Point","coordinates":[1.0,2.0]}},{"type":"Feature","id":6,"properties":\
{},"geometry":null}]}'
    """
    if isinstance(ids, (int, np.integer)):
        ids = np.arange(ids, ids + len(geometries))
    coords = shapely.get_coordinates(geometries, include_z=True)
    if not np.isfinite(coords[:, :2]).all() or np.isinf(coords[:, 2]).any():
        row = _first_non_finite(geometries)
        raise InvalidInputError(
            f"geometry {ids[row]} has a NaN or infinite coordinate, which JSON cannot "
            "carry: every coordinate must be finite")
    texts = shapely.to_geojson(geometries)
    empty = shapely.is_empty(geometries)
    if empty.any():   # GEOS writes "[[]]" for an empty polygon; GeoJSON wants []
        types = shapely.get_type_id(geometries[empty])
        texts[empty] = [f'{{"type":"{_EMPTY_TYPES[int(t)]}","coordinates":[]}}'
                        if t != 7 else '{"type":"GeometryCollection","geometries":[]}'
                        for t in types]
    missing = shapely.is_missing(geometries)
    texts[missing] = "null"
    features = ",".join(
        f'{{"type":"Feature","id":{i},"properties":{{}},"geometry":{text}}}'
        for i, text in zip(ids.tolist(), texts.tolist(), strict=True))
    return f'{{"type":"FeatureCollection","features":[{features}]}}'.encode()


def _first_non_finite(geometries: np.ndarray) -> int:
    coords, index = shapely.get_coordinates(geometries, include_z=True, return_index=True)
    finite = np.isfinite(coords[:, :2]).all(axis=1) & ~np.isinf(coords[:, 2])
    return int(index[np.flatnonzero(~finite)[0]])


def read_features(document: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Return the ids (int64) and Shapely geometries of a FeatureCollection's features.

    Raises
    ------
    ResponseFormatError
        The document is not a FeatureCollection of features with integer ids.

    Examples
    --------
    >>> ids, geometries = read_features(json.loads(feature_collection(
    ...     np.array([shapely.Point(1, 2)]), ids=3)))
    >>> ids.tolist(), geometries.tolist()
    ([3], [<POINT (1 2)>])
    """
    try:
        features = document["features"]
        ids = np.array([f["id"] for f in features], dtype=np.int64)
        texts = [None if f["geometry"] is None else json.dumps(f["geometry"])
                 for f in features]
    except (KeyError, TypeError, ValueError) as exc:
        raise ResponseFormatError(
            f"the answer is not a FeatureCollection of features with ids ({exc})") from None
    geometries = np.empty(len(texts), dtype=object)
    geometries[:] = shapely.from_geojson(np.array(texts, dtype=object)) if texts else []
    return ids, geometries
