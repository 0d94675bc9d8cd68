"""Feature files for `rnsca tiles`: GeoJSON, GeoJSON text sequences, GeoParquet, FlatGeobuf.

`read_features` returns the geometries (a Shapely array), properties, ids and the
coordinate system of a file, chosen by its suffix:

- ``.geojson``, ``.json``: a FeatureCollection, Feature or Geometry (orjson).
- ``.geojsons``, ``.geojsonl``, ``.geojsonseq``, ``.ndjson``, ``.jsonl``: one Feature (or
  Geometry) per line, RS-prefixed (RFC 8142) or not.
- ``.parquet``, ``.geoparquet``: GeoParquet (pyarrow): the primary geometry column as
  WKB, the other columns as properties; EPSG:3857 if the column's CRS says so.
- ``.fgb``: FlatGeobuf (pyogrio, which reads it through GDAL).

GeoJSON and GeoJSON sequences are read by the compiled reader of
`rnsca.io.geojson_file` (no Python object per number); a document it does not take (a
GeometryCollection, an error) is parsed by orjson and read by
`rnsca.io.geojson.from_geojson`, which gives the same arrays and names any problem. Other
geometries are made by Shapely from the whole column at once (``from_geojson`` on the
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

from rnsca.arrays import Ragged
from rnsca.errors import InvalidGeometryError, ParseError, UnsupportedGeometryError
from rnsca.io.geojson import from_geojson, loads
from rnsca.io.geojson_file import (
    FileFeatures,
    padded_bytes,
    padded_text,
    read_file_features,
)
from rnsca.tiles.features import FeatureTable
from rnsca.tiles.mercator import Crs

__all__ = ["Features", "features_of_geojson", "features_of_geojson_text", "read_features",
           "SUFFIXES"]

_GEOJSON = (".geojson", ".json")
_SEQUENCE = (".geojsons", ".geojsonl", ".geojsonseq", ".ndjson", ".jsonl")
_PARQUET = (".parquet", ".geoparquet")
_FLATGEOBUF = (".fgb",)
#: The suffixes `read_features` reads.
SUFFIXES = _GEOJSON + _SEQUENCE + _PARQUET + _FLATGEOBUF


@dataclass(frozen=True, slots=True, eq=False)
class Features:
    """Features read: their geometry, properties (list of dict), ids (list) and CRS.

    The geometry is either `geometries` (a Shapely array, one per feature) or `ragged`
    (MULTIPOINT, MULTILINESTRING and MULTIPOLYGON ragged arrays) with `sources` (the
    feature of each of their geometries); `table` builds the `FeatureTable` of either.
    """

    geometries: np.ndarray | None
    properties: list
    ids: list
    crs: Crs
    ragged: tuple | None = None
    sources: tuple | None = None

    def table(self, crs: Crs | None = None) -> FeatureTable:
        """Return the features as a `FeatureTable` (in `crs`, default the file's)."""
        crs = crs or self.crs
        if self.ragged is not None and self.sources is not None:
            return FeatureTable.from_ragged(self.ragged, self.sources, len(self.properties),
                                            self.properties, self.ids, crs)
        return FeatureTable.of(self.geometries, self.properties, self.ids, crs=crs)


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
    if suffix in _GEOJSON + _SEQUENCE:
        read = read_file_features(*padded_bytes(path), sequence=suffix in _SEQUENCE)
        if read is not None:
            return _of_file_features(read)
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


def features_of_geojson_text(text: bytes | bytearray | memoryview) -> Features:
    """Return the features of GeoJSON text (a FeatureCollection, Feature or Geometry).

    As `read_features` reads a GeoJSON file: the compiled reader first, and a document
    it does not take parsed by orjson (`rnsca.io.geojson.loads`: a `ParseError` names
    the offset of text that is not JSON) and read by `features_of_geojson`.
    """
    read = read_file_features(*padded_text(text))
    if read is not None:
        return _of_file_features(read)
    return features_of_geojson(loads(text))


def features_of_geojson(document: Any) -> Features:
    """Return the features of a parsed GeoJSON object (FeatureCollection, Feature, Geometry)."""
    return _of_features(_features_of(document), Path("<geojson>"))


def _features_of(document: Any) -> list:
    if not isinstance(document, dict):
        raise ParseError("a GeoJSON object must be a JSON object")
    kind = document.get("type")
    if kind == "FeatureCollection":
        return list(document.get("features") or [])
    if kind == "Feature":
        return [document]
    return [{"type": "Feature", "geometry": document, "properties": None}]


#: Feature geometry types and the array of `rnsca.io.geojson.from_geojson` they go to.
_KIND = {"Point": 0, "MultiPoint": 0, "LineString": 1, "MultiLineString": 1, "Polygon": 2,
         "MultiPolygon": 2}


def _of_features(features: list, path: Path) -> Features:
    """Return features read by the library's GeoJSON reader (bulk, no object per geometry).

    Each feature's geometry is the next one of its kind in the reader's arrays; a
    GeometryCollection (several kinds, or none) goes through Shapely instead.
    """
    kinds = np.array([_KIND.get(str(f["geometry"].get("type")), -1)
                      if isinstance(f, dict) and isinstance(f.get("geometry"), dict) else -2
                      for f in features], dtype=np.int64)
    # Only GeometryCollections go to Shapely: any other type (unknown, or not a string)
    # is refused by `from_geojson`, which names where.
    collections = any(isinstance(f, dict) and isinstance(f.get("geometry"), dict)
                      and f["geometry"].get("type") == "GeometryCollection"
                      for f in features)
    if not collections:
        try:
            layout = from_geojson({"type": "FeatureCollection", "features": features})
        except InvalidGeometryError as exc:
            raise ParseError(f"{path}: {exc}") from None
        ragged = tuple(Ragged.of(*getattr(layout, kind), partial_z=layout.partial_z)
                       for kind in ("points", "lines", "polygons"))
        sources = tuple(np.flatnonzero(kinds == k) for k in range(3))
        properties = [f.get("properties") for f in features]
        ids = [f.get("id") for f in features]
        return Features(None, properties, ids, Crs.EPSG_4326, ragged, sources)
    return _of_shapely(features, path)


def _of_file_features(read: FileFeatures) -> Features:
    """Return the features the compiled GeoJSON reader read, as `_of_features` would."""
    ragged = tuple(Ragged.of(*arrays, partial_z=read.partial_z)
                   for arrays in (read.points, read.lines, read.polygons))
    sources = tuple(np.flatnonzero(read.kinds == k) for k in range(3))
    return Features(None, read.properties, read.ids, Crs.EPSG_4326, ragged, sources)


def _of_shapely(features: list, path: Path) -> Features:
    """Return features whose geometries Shapely reads (GeometryCollections among them)."""
    present = [i for i, f in enumerate(features)
               if isinstance(f, dict) and isinstance(f.get("geometry"), dict)]
    geometries = np.full(len(features), None, dtype=object)
    try:
        geometries[present] = shapely.from_geojson(
            np.array([orjson.dumps(features[i]["geometry"]) for i in present],
                     dtype=object), on_invalid="raise")
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
