"""GeoArrow tables for the tests, built and read without `rnsca.io.geoarrow`.

`encode` writes Shapely geometries as nested Python lists and lets ``pyarrow.array``
build the column from them (so the offsets and coordinate buffers are pyarrow's own, not
ours); `decode` reads a column back through ``to_pylist`` into Shapely geometries. The
two are the independent oracle of the reader and writer under test.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import shapely

ARROW_STREAM = "application/vnd.apache.arrow.stream"
#: Nesting of each kind: the child field name of each list level, outermost first.
LEVELS = {"point": (), "linestring": ("vertices",), "multipoint": ("points",),
          "polygon": ("rings", "vertices"), "multilinestring": ("linestrings", "vertices"),
          "multipolygon": ("polygons", "rings", "vertices")}
ENCODINGS = ("separated", "interleaved", "wkb")


def coord_type(layout: str, z: bool) -> pa.DataType:
    """Return the Arrow type of one vertex."""
    dims = "xyz" if z else "xy"
    if layout == "interleaved":
        return pa.list_(pa.field(dims, pa.float64(), nullable=False), len(dims))
    return pa.struct([pa.field(d, pa.float64(), nullable=False) for d in dims])


def storage_type(kind: str, layout: str, z: bool) -> pa.DataType:
    """Return the storage type of a native `kind` column."""
    value = coord_type(layout, z)
    for name in reversed(LEVELS[kind]):
        value = pa.list_(pa.field(name, value, nullable=False))
    return value


def _vertex(xyz, layout: str, z: bool):
    values = [float(v) for v in xyz[:3 if z else 2]]
    return values if layout == "interleaved" else dict(zip("xyz", values, strict=False))


def _nested(geometry, kind: str, layout: str, z: bool):
    def vertices(g):
        return [_vertex(c, layout, z) for c in shapely.get_coordinates(g, include_z=z)]

    def rings(polygon):
        if polygon.is_empty:
            return []
        return [vertices(polygon.exterior)] + [vertices(r) for r in polygon.interiors]

    if kind == "point":
        if geometry.is_empty:
            return _vertex([np.nan] * 3, layout, z)
        return vertices(geometry)[0]
    if kind in ("linestring", "multipoint"):
        return vertices(geometry)
    if kind == "polygon":
        return rings(geometry)
    parts = list(geometry.geoms)
    if kind == "multilinestring":
        return [vertices(p) for p in parts]
    return [rings(p) for p in parts]


def encode(geometries, kind: str, encoding: str, z: bool) -> tuple[pa.Array, pa.Field]:
    """Return a column of `geometries` (None: a null row) and its field."""
    if encoding == "wkb":
        values = [None if g is None else shapely.to_wkb(g, output_dimension=3 if z else 2)
                  for g in geometries]
        return pa.array(values, pa.binary()), pa.field(
            "geometry", pa.binary(), metadata={"ARROW:extension:name": "geoarrow.wkb"})
    storage = storage_type(kind, encoding, z)
    values = [None if g is None else _nested(g, kind, encoding, z) for g in geometries]
    field = pa.field("geometry", storage, metadata={
        "ARROW:extension:name": f"geoarrow.{kind}",
        "ARROW:extension:metadata": '{"crs": "OGC:CRS84"}'})
    return pa.array(values, storage), field


def table(geometries, kind: str, encoding: str, z: bool) -> pa.Table:
    """Return a table of an ``id`` column (the row number), a ``name`` and the geometry."""
    column, field = encode(geometries, kind, encoding, z)
    n = len(geometries)
    return pa.Table.from_arrays(
        [pa.array(range(n), pa.int64()), pa.array([f"row {i}" for i in range(n)]), column],
        schema=pa.schema([pa.field("id", pa.int64()), pa.field("name", pa.string()), field],
                         metadata={"source": "tests"}))


def to_stream(t: pa.Table) -> bytes:
    """Return `t` as an Arrow IPC stream."""
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, t.schema) as writer:
        writer.write_table(t)
    return sink.getvalue().to_pybytes()


def from_stream(body: bytes) -> pa.Table:
    """Return the table of an Arrow IPC stream."""
    return pa.ipc.open_stream(pa.py_buffer(body)).read_all()


def _xyz(vertex) -> tuple:
    return tuple(vertex) if isinstance(vertex, list) else tuple(vertex.values())


def decode(column: pa.Array | pa.ChunkedArray, field: pa.Field) -> list:
    """Return the geometries of a column (None for a null row)."""
    name = field.metadata[b"ARROW:extension:name"].decode()
    kind = name.split(".")[1]
    values = column.to_pylist()
    if kind == "wkb":
        return [None if v is None else shapely.from_wkb(v) for v in values]
    out = []
    for v in values:
        if v is None:
            out.append(None)
        elif kind == "point":
            xyz = _xyz(v)
            out.append(shapely.Point() if np.isnan(xyz[0]) else shapely.Point(xyz))
        elif kind == "linestring":
            out.append(shapely.LineString([_xyz(p) for p in v]))
        elif kind == "multipoint":
            out.append(shapely.MultiPoint([_xyz(p) for p in v]))
        elif kind == "polygon":
            out.append(_polygon(v))
        elif kind == "multilinestring":
            out.append(shapely.MultiLineString([[_xyz(p) for p in part] for part in v]))
        else:
            out.append(shapely.MultiPolygon([_polygon(p) for p in v]))
    return out


def _polygon(rings) -> shapely.Polygon:
    if not rings:
        return shapely.Polygon()
    shell, *holes = ([_xyz(p) for p in ring] for ring in rings)
    return shapely.Polygon(shell, holes)


def raw_native(kind: str, coords, *offsets) -> bytes:
    """Return a stream of an ``id`` column and an interleaved native column of `kind`.

    Built from raw offsets, outermost first, so that it may hold what Shapely cannot
    write (`encode` goes through Shapely): polygons of no rings, empty exteriors.
    """
    names = LEVELS[kind]
    xy = pa.list_(pa.field("xy", pa.float64(), nullable=False), 2)
    storage = pa.FixedSizeListArray.from_arrays(
        pa.array(np.asarray(coords, dtype=float).reshape(-1)), type=xy)
    for name, level in zip(reversed(names), reversed(offsets), strict=True):
        storage = pa.ListArray.from_arrays(
            pa.array(level, pa.int32()), storage,
            type=pa.list_(pa.field(name, storage.type, nullable=False)))
    field = pa.field("geometry", storage.type,
                     metadata={"ARROW:extension:name": f"geoarrow.{kind}"})
    rows = len(offsets[0]) - 1
    return to_stream(pa.Table.from_arrays([pa.array(range(rows)), storage], schema=pa.schema(
        [pa.field("id", pa.int64()), field])))
