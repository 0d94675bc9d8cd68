"""Feature files for `rnsca tiles`: GeoJSON, GeoJSON text sequences, GeoParquet, FlatGeobuf.

`read_features` returns the geometries (a Shapely array), properties, ids and the
coordinate system of a file, chosen by its suffix:

- ``.geojson``, ``.json``: a FeatureCollection, Feature or Geometry (orjson).
- ``.geojsons``, ``.geojsonl``, ``.geojsonseq``, ``.ndjson``, ``.jsonl``: one Feature (or
  Geometry) per line, RS-prefixed (RFC 8142) or not.
- ``.parquet``, ``.geoparquet``: GeoParquet (pyarrow): the primary geometry column as
  WKB, the other columns as properties; EPSG:3857 if the column's CRS says so.
- ``.fgb``: FlatGeobuf (pyogrio, which reads it through GDAL).

Geometries are made by Shapely from the whole column at once (``from_geojson`` on the
features' geometry texts, ``from_wkb`` on WKB).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import orjson
import shapely

from rnsca.errors import ParseError, UnsupportedGeometryError
from rnsca.tiles.mercator import Crs

__all__ = ["Features", "read_features", "SUFFIXES"]

_GEOJSON = (".geojson", ".json")
_SEQUENCE = (".geojsons", ".geojsonl", ".geojsonseq", ".ndjson", ".jsonl")
_PARQUET = (".parquet", ".geoparquet")
_FLATGEOBUF = (".fgb",)
#: The suffixes `read_features` reads.
SUFFIXES = _GEOJSON + _SEQUENCE + _PARQUET + _FLATGEOBUF


@dataclass(frozen=True, slots=True, eq=False)
class Features:
    """Geometries (Shapely array), properties (list of dict), ids (list) and their CRS."""

    geometries: np.ndarray
    properties: list
    ids: list
    crs: Crs


def read_features(path: str | Path) -> Features:
    """Return the features of a GeoJSON, GeoJSON sequence, GeoParquet or FlatGeobuf file.

    Raises
    ------
    ParseError
        For a file that is not what its suffix says.
    UnsupportedGeometryError
        For a suffix not in `SUFFIXES`.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in _GEOJSON:
        try:
            document = orjson.loads(path.read_bytes())
        except orjson.JSONDecodeError as exc:
            raise ParseError(f"{path}: not JSON: {exc}") from None
        return _of_features(_features_of(document), path)
    if suffix in _SEQUENCE:
        features = []
        with open(path, "rb") as f:
            for number, line in enumerate(f, 1):
                line = line.strip(b"\x1e \t\r\n")
                if not line:
                    continue
                try:
                    features += _features_of(orjson.loads(line))
                except orjson.JSONDecodeError as exc:
                    raise ParseError(f"{path}, line {number}: not JSON: {exc}") from None
        return _of_features(features, path)
    if suffix in _PARQUET:
        return _read_geoparquet(path)
    if suffix in _FLATGEOBUF:
        return _read_ogr(path)
    raise UnsupportedGeometryError(
        f"{path}: unknown suffix {suffix!r}; rnsca tiles reads {', '.join(SUFFIXES)}")


def _features_of(document: Any) -> list:
    if not isinstance(document, dict):
        raise ParseError("a GeoJSON object must be a JSON object")
    kind = document.get("type")
    if kind == "FeatureCollection":
        return list(document.get("features") or [])
    if kind == "Feature":
        return [document]
    return [{"type": "Feature", "geometry": document, "properties": None}]


def _of_features(features: list, path: Path) -> Features:
    texts = [orjson.dumps(f.get("geometry")) if isinstance(f, dict) else b"null"
             for f in features]
    try:
        geometries = shapely.from_geojson(np.array(texts, dtype=object), on_invalid="raise")
    except shapely.errors.GEOSException as exc:
        raise ParseError(f"{path}: invalid GeoJSON geometry: {exc}") from None
    properties = [f.get("properties") if isinstance(f, dict) else None for f in features]
    ids = [f.get("id") if isinstance(f, dict) else None for f in features]
    return Features(np.asarray(geometries, dtype=object), properties, ids, Crs.EPSG_4326)


def _crs_of(projjson: Any) -> Crs:
    """Return EPSG:3857 for a GeoParquet column CRS naming it, else EPSG:4326."""
    if isinstance(projjson, dict):
        code = (projjson.get("id") or {}).get("code")
        if code == 3857:
            return Crs.EPSG_3857
    if isinstance(projjson, str) and "3857" in projjson:
        return Crs.EPSG_3857
    return Crs.EPSG_4326


def _read_geoparquet(path: Path) -> Features:
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    metadata = json.loads((table.schema.metadata or {}).get(b"geo", b"{}"))
    column = metadata.get("primary_column", "geometry")
    if column not in table.column_names:
        raise ParseError(f"{path}: no geometry column {column!r}")
    encoding = metadata.get("columns", {}).get(column, {}).get("encoding", "WKB")
    if str(encoding).upper() != "WKB":
        raise UnsupportedGeometryError(
            f"{path}: geometry encoding {encoding!r}; rnsca tiles reads WKB GeoParquet")
    geometries = shapely.from_wkb(table.column(column).to_numpy(zero_copy_only=False))
    crs = _crs_of(metadata.get("columns", {}).get(column, {}).get("crs"))
    rest = table.drop_columns([column])
    properties = rest.to_pylist()
    ids = [None] * len(properties)
    return Features(np.asarray(geometries, dtype=object), properties, ids, crs)


def _read_ogr(path: Path) -> Features:
    try:
        import pyogrio.raw
    except ImportError:
        raise UnsupportedGeometryError(
            f"{path}: FlatGeobuf needs pyogrio (the tiles extra)") from None
    meta, _, wkb, fields = pyogrio.raw.read(path)
    geometries = shapely.from_wkb(wkb)
    names = list(meta["fields"])
    columns = [np.asarray(c).tolist() for c in fields]
    properties = [dict(zip(names, row, strict=True)) for row in zip(*columns, strict=True)] \
        if columns else [{} for _ in range(len(geometries))]
    crs = Crs.EPSG_3857 if "3857" in str(meta.get("crs") or "") else Crs.EPSG_4326
    return Features(np.asarray(geometries, dtype=object), properties,
                    [None] * len(properties), crs)
