"""GeoArrow geometry columns to and from the ragged arrays `clip_ragged` takes.

A GeoArrow native column stores one coordinate array and one list offsets array per
level of nesting (https://geoarrow.org/format.html): the layout of `rnsca.Ragged`. The
coordinates are either *separated* (a struct of ``x``, ``y`` [, ``z``] double arrays) or
*interleaved* (a fixed-size list of 2 or 3 doubles per vertex). Reading takes the
buffers as they are where the layout allows it: interleaved coordinates are viewed, not
copied, where their Arrow buffer is mutable (arrays pyarrow built in this process), and
copied once where it is not (buffers read from an IPC stream or a file are read-only, and
the kernels take writeable arrays: see `_numbers`); separated ones are stacked into rows,
and int32 offsets widened to int64. Writing wraps the clipped arrays in Arrow arrays of
the input's encoding (``from_arrays`` over them, no copy of interleaved coordinates). WKB and WKT
columns go through Shapely. This module knows nothing of clipping.

The column's kind and encoding come from the field's Arrow extension metadata
(``ARROW:extension:name`` = ``geoarrow.point`` ... ``geoarrow.multipolygon``,
``geoarrow.wkb``, ``geoarrow.wkt``), or, for a plain binary column without it, from the
column's name `WKB_COLUMN_NAME` (a WKB column as GeoParquet and GDAL write it).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import Any

import numpy as np
import pyarrow as pa
import shapely

from rnsca.arrays import GeometryKind, to_shapely
from rnsca.errors import ParseError, UnsupportedGeometryError

__all__ = ["GeoArrowEncoding", "CoordLayout", "GeoArrowColumn", "WKB_COLUMN_NAME",
           "find_geometry_column", "read_geoarrow", "write_geoarrow"]

#: A binary column of this name without extension metadata is read as WKB.
WKB_COLUMN_NAME = "geometry"

_EXTENSION_NAME = b"ARROW:extension:name"
_EXTENSION_METADATA = b"ARROW:extension:metadata"

#: Native extension name: (kind, list levels above the coordinates).
_NATIVE = {"geoarrow.point": (GeometryKind.POINT, 0),
           "geoarrow.linestring": (GeometryKind.LINESTRING, 1),
           "geoarrow.multipoint": (GeometryKind.MULTIPOINT, 1),
           "geoarrow.polygon": (GeometryKind.POLYGON, 2),
           "geoarrow.multilinestring": (GeometryKind.MULTILINESTRING, 2),
           "geoarrow.multipolygon": (GeometryKind.MULTIPOLYGON, 3)}
#: Name of each level's child field, outermost first, as the GeoArrow spec names them.
_LEVEL_NAMES = {GeometryKind.LINESTRING: ("vertices",),
                GeometryKind.MULTIPOINT: ("points",),
                GeometryKind.POLYGON: ("rings", "vertices"),
                GeometryKind.MULTILINESTRING: ("linestrings", "vertices"),
                GeometryKind.MULTIPOLYGON: ("polygons", "rings", "vertices")}
#: What a clip of each kind is written as: a cut line or polygon may have several parts,
#: so the single kinds widen to multi whatever the data, and the schema of the answer
#: depends on the schema of the request only.
_CLIPPED_KIND = {GeometryKind.POINT: GeometryKind.POINT,
                 GeometryKind.MULTIPOINT: GeometryKind.MULTIPOINT,
                 GeometryKind.LINESTRING: GeometryKind.MULTILINESTRING,
                 GeometryKind.MULTILINESTRING: GeometryKind.MULTILINESTRING,
                 GeometryKind.POLYGON: GeometryKind.MULTIPOLYGON,
                 GeometryKind.MULTIPOLYGON: GeometryKind.MULTIPOLYGON}


class GeoArrowEncoding(str, Enum):
    """How a column stores its geometries."""

    NATIVE = "native"
    """Coordinates and offsets (``geoarrow.point`` ... ``geoarrow.multipolygon``)."""
    WKB = "wkb"
    """Well-known binary, one value per row (``geoarrow.wkb`` or a binary ``geometry``)."""
    WKT = "wkt"
    """Well-known text, one value per row (``geoarrow.wkt``)."""


class CoordLayout(str, Enum):
    """How a native column stores its coordinates."""

    SEPARATED = "separated"
    """A struct of one double array per dimension (``x``, ``y`` [, ``z``])."""
    INTERLEAVED = "interleaved"
    """A fixed-size list of the dimensions of each vertex (``xy`` or ``xyz``)."""


@dataclass(frozen=True)
class GeoArrowColumn:
    """A geometry column read into ragged arrays, with what it takes to write it back.

    Attributes
    ----------
    kind : GeometryKind
        The kind of `coords` and `offsets` (for WKB and WKT: what Shapely's
        ``to_ragged_array`` made of the values, a mix of single and multi as multi).
    coords : ndarray of float64, shape (n, 2) or (n, 3)
        The present geometries' vertices; a view of the Arrow buffer where it allows one.
    offsets : tuple of ndarray of int
        Innermost level first, one geometry per present row.
    rows : ndarray of int64
        The row of each geometry: rows that are null (or, for points, an empty point,
        all NaN; for WKB and WKT, an empty geometry) have none.
    row_count : int
        Rows in the column.
    null : ndarray of bool, shape (row_count,)
        Which rows are null.
    field : pyarrow.Field
        The column's field as read (extension metadata included).
    encoding : GeoArrowEncoding
    coord_layout : CoordLayout or None
        Native columns only.
    partial_z : bool
        WKB and WKT: some geometries are 3D and others not (the 2D ones have NaN Z).
    single : ndarray of bool or None
        WKB and WKT: whether each geometry was a single kind (POINT, LINESTRING,
        POLYGON), so that a clip left in one part is written as that kind again.
    with_z : ndarray of bool or None
        WKB and WKT: whether each geometry has Z. WKB and WKT carry the dimension of
        each value, so each is written back in its own (a 2D one beside 3D ones stays
        2D); a native column has one dimension for all its rows.
    large_offsets : bool
        Native: the lists are ``large_list`` (int64 offsets), and are written so again.
    """

    kind: GeometryKind
    coords: np.ndarray
    offsets: tuple
    rows: np.ndarray
    row_count: int
    null: np.ndarray
    field: pa.Field
    encoding: GeoArrowEncoding
    coord_layout: CoordLayout | None = None
    partial_z: bool = False
    single: np.ndarray | None = None
    with_z: np.ndarray | None = None
    large_offsets: bool = False

    @property
    def has_z(self) -> bool:
        """Whether the coordinates have a Z."""
        return self.coords.shape[1] == 3


def _extension_name(field: pa.Field) -> str | None:
    if isinstance(field.type, pa.ExtensionType):  # a registered geoarrow-pyarrow type
        return field.type.extension_name
    name = (field.metadata or {}).get(_EXTENSION_NAME)
    return None if name is None else name.decode("utf-8", "replace")


def find_geometry_column(schema: pa.Schema, name: str | None = None) -> int:
    """Return the index of the geometry column of `schema`.

    Parameters
    ----------
    schema : pyarrow.Schema
    name : str, optional
        The column to read. By default, the one field whose extension name starts with
        ``geoarrow.``, or else a binary field named `WKB_COLUMN_NAME`.

    Raises
    ------
    ParseError
        (ValueError) When `name` is not a column, no column is geometry, or several are
        and `name` does not choose.
    """
    if name is not None:
        index = schema.get_field_index(name)
        if index < 0:
            raise ParseError(f"no column named {name!r}; the columns are {schema.names}")
        return index
    tagged = [i for i, field in enumerate(schema)
              if (_extension_name(field) or "").startswith("geoarrow.")]
    if len(tagged) > 1:
        raise ParseError(f"several geometry columns ({[schema.names[i] for i in tagged]}): "
                         "name the one to clip")
    if tagged:
        return tagged[0]
    index = schema.get_field_index(WKB_COLUMN_NAME)
    if index >= 0 and (pa.types.is_binary(schema.field(index).type)
                       or pa.types.is_large_binary(schema.field(index).type)):
        return index
    raise ParseError("no geometry column: tag one with ARROW:extension:name "
                     "(geoarrow.point, geoarrow.linestring, geoarrow.polygon, their multi "
                     f"kinds, geoarrow.wkb or geoarrow.wkt), or name a binary WKB column "
                     f"{WKB_COLUMN_NAME!r}; the columns are {schema.names}")


def read_geoarrow(column: pa.Array | pa.ChunkedArray, field: pa.Field) -> GeoArrowColumn:
    """Return the geometries of a GeoArrow column as ragged arrays.

    Parameters
    ----------
    column : pyarrow.Array or ChunkedArray
        The column's values (chunks are combined, which copies them).
    field : pyarrow.Field
        Its field: the extension name says the encoding (see the module docstring).

    Returns
    -------
    GeoArrowColumn

    Raises
    ------
    UnsupportedGeometryError
        An extension this reader does not take (``geoarrow.geometry``, ``box``, M
        coordinates, spherical edges).
    ParseError
        (ValueError) The storage does not match the extension: wrong nesting, null
        coordinates or null inner lists, a value that is not WKB or WKT.

    Examples
    --------
    >>> import pyarrow as pa
    >>> vertices = pa.struct([("x", pa.float64()), ("y", pa.float64())])
    >>> field = pa.field("geom", pa.list_(pa.field("vertices", vertices)),
    ...                  metadata={"ARROW:extension:name": "geoarrow.linestring"})
    >>> column = pa.array([[{"x": 0.0, "y": 1.0}, {"x": 2.0, "y": 3.0}]], field.type)
    >>> read = read_geoarrow(column, field)
    >>> read.kind.name, read.coords.tolist(), [o.tolist() for o in read.offsets]
    ('LINESTRING', [[0.0, 1.0], [2.0, 3.0]], [[0, 2]])
    """
    if isinstance(column, pa.ChunkedArray):
        # One chunk (a stream of one batch) as it is: combining copies even one.
        column = column.chunk(0) if column.num_chunks == 1 else column.combine_chunks()
    if isinstance(column, pa.ExtensionArray):
        column = column.storage
    name = _extension_name(field)
    storage = column.type
    if name is None and field.name == WKB_COLUMN_NAME and (
            pa.types.is_binary(storage) or pa.types.is_large_binary(storage)):
        name = "geoarrow.wkb"
    _check_planar(field, name)
    if name in ("geoarrow.wkb", "geoarrow.wkt"):
        return _read_serialized(column, field, GeoArrowEncoding(name.split(".")[1]))
    if name not in _NATIVE:
        raise UnsupportedGeometryError(
            f"column {field.name!r}: extension {name!r} is not one this reader takes: "
            f"{', '.join([*_NATIVE, 'geoarrow.wkb', 'geoarrow.wkt'])}")
    kind, levels = _NATIVE[name]
    null = _null_mask(column)
    present = column if column.null_count == 0 else column.drop_null()  # compacts them
    offsets = []
    values = present
    large = pa.types.is_large_list(values.type)
    for level in range(levels):
        if not (pa.types.is_list(values.type) or pa.types.is_large_list(values.type)):
            raise ParseError(f"column {field.name!r}: {name} needs {levels} levels of lists "
                             f"above the coordinates, found {values.type} at level {level}")
        if level > 0 and values.null_count:
            raise ParseError(f"column {field.name!r}: null {_LEVEL_NAMES[kind][level - 1]} "
                             "(only a whole geometry may be null)")
        level_offsets = _numbers(values.offsets)
        child = values.values
        # A slice's offsets start past 0 and its child runs on: take the part it uses.
        if level_offsets.shape[0] and (level_offsets[0] != 0
                                       or level_offsets[-1] != len(child)):
            child = child.slice(level_offsets[0], level_offsets[-1] - level_offsets[0])
            level_offsets = level_offsets - level_offsets[0]
        offsets.append(level_offsets)
        values = child
    coords, layout = _read_coords(values, field, name)
    rows = np.flatnonzero(~null).astype(np.int64)
    if kind is GeometryKind.POINT:
        # An empty point is all NaN (the spec): like a null one, it has no geometry.
        empty = np.isnan(coords).all(axis=1)
        if empty.any():
            rows = rows[~empty]
            coords = np.ascontiguousarray(coords[~empty])
    return GeoArrowColumn(kind, coords, tuple(reversed(offsets)), rows, len(column), null,
                          field, GeoArrowEncoding.NATIVE, layout, large_offsets=large)


def _null_mask(column: pa.Array) -> np.ndarray:
    if column.null_count == 0:
        return np.zeros(len(column), dtype=bool)
    return column.is_null().to_numpy(zero_copy_only=False)


def _check_planar(field: pa.Field, name: str | None) -> None:
    raw = (field.metadata or {}).get(_EXTENSION_METADATA)
    if isinstance(field.type, pa.ExtensionType):
        raw = field.type.__arrow_ext_serialize__()
    if not raw:
        return
    try:
        metadata = json.loads(raw)
    except ValueError:
        raise ParseError(f"column {field.name!r}: ARROW:extension:metadata is not "
                         "JSON") from None
    edges = metadata.get("edges", "planar") if isinstance(metadata, dict) else "planar"
    if edges != "planar":
        # A straight window edge is not a geodesic: clipping such edges as straight lines
        # would be wrong, not approximate.
        raise UnsupportedGeometryError(
            f"column {field.name!r}: {name} with {edges!r} edges; only planar edges can "
            "be clipped to a rectangle")


def _read_coords(values: pa.Array, field: pa.Field,
                 name: str) -> tuple[np.ndarray, CoordLayout]:
    """Return the (n, 2) or (n, 3) coordinates: a view of interleaved ones."""
    if values.null_count:
        raise ParseError(f"column {field.name!r}: null coordinates")
    if pa.types.is_struct(values.type):
        dims = "".join(values.type.field(i).name for i in range(values.type.num_fields))
        _check_dims(dims, field, name)
        arrays = [values.field(i) for i in range(len(dims))]
        if any(a.null_count for a in arrays):
            raise ParseError(f"column {field.name!r}: null coordinates")
        # Stacking into rows copies: the read-only views will do.
        return (np.column_stack([_doubles(a, field, view=True) for a in arrays]),
                CoordLayout.SEPARATED)
    if pa.types.is_fixed_size_list(values.type):
        dims = values.type.value_field.name
        size = values.type.list_size
        if dims not in ("xy", "xyz", "xym", "xyzm"):
            dims = "xy" if size == 2 else "xyz" if size == 3 else f"{size} values"
        _check_dims(dims, field, name)
        if size != len(dims):
            raise ParseError(f"column {field.name!r}: {size} values per vertex named {dims!r}")
        flat = values.values
        if values.offset or len(flat) != size * len(values):
            flat = flat.slice(values.offset * size, size * len(values))
        if flat.null_count:
            raise ParseError(f"column {field.name!r}: null coordinates")
        return _doubles(flat, field).reshape(-1, size), CoordLayout.INTERLEAVED
    raise ParseError(f"column {field.name!r}: {name} coordinates must be a struct of x, y "
                     f"[, z] or a fixed-size list of xy or xyz doubles, not {values.type}")


def _check_dims(dims: str, field: pa.Field, name: str) -> None:
    if "m" in dims:
        raise UnsupportedGeometryError(f"column {field.name!r}: {name} with M values "
                                       f"({dims}); send xy or xyz coordinates")
    if dims not in ("xy", "xyz"):
        raise ParseError(f"column {field.name!r}: coordinates named {dims!r}; GeoArrow "
                         "names them x, y [, z] (separated) or xy, xyz (interleaved)")


def _doubles(array: pa.Array, field: pa.Field, view: bool = False) -> np.ndarray:
    if not pa.types.is_float64(array.type):
        raise ParseError(f"column {field.name!r}: coordinates must be double, "
                         f"not {array.type}")
    return array.to_numpy(zero_copy_only=True) if view else _numbers(array)


def _numbers(array: pa.Array) -> np.ndarray:
    """Return a primitive array without nulls as a writeable NumPy array.

    A view of the Arrow buffer where that buffer is mutable (Arrow's own allocations),
    else a copy (a memcpy): ``to_numpy`` views are read-only, and the kernels are compiled
    and warmed up for writeable arrays; a read-only one would make each kernel compile a
    second specialisation on its first call (seconds, on a cold cache).
    """
    dtype = np.dtype(array.type.to_pandas_dtype())
    buffer = array.buffers()[1]
    if buffer is not None and buffer.is_mutable:
        return np.frombuffer(buffer, dtype=dtype, count=len(array),
                             offset=array.offset * dtype.itemsize)
    return array.to_numpy(zero_copy_only=False).copy()


def _read_serialized(column: pa.Array, field: pa.Field,
                     encoding: GeoArrowEncoding) -> GeoArrowColumn:
    binary = encoding is GeoArrowEncoding.WKB
    allowed = ((pa.types.is_binary, pa.types.is_large_binary) if binary
               else (pa.types.is_string, pa.types.is_large_string))
    if not any(test(column.type) for test in allowed):
        raise ParseError(f"column {field.name!r}: {encoding.value.upper()} must be stored "
                         f"as {'binary' if binary else 'string'}, not {column.type}")
    null = _null_mask(column)
    values = column.to_numpy(zero_copy_only=False)
    parse = shapely.from_wkb if binary else shapely.from_wkt
    try:
        geometries = parse(values)  # None stays None
    except shapely.errors.ShapelyError:
        row = next(i for i, v in enumerate(values) if not _parses(parse, v))
        raise ParseError(f"column {field.name!r}, row {row}: not valid "
                         f"{encoding.value.upper()}") from None
    geometries = _without_empty_points(geometries)
    empty = shapely.is_empty(geometries)
    rows = np.flatnonzero(~null & ~empty).astype(np.int64)
    if rows.shape[0] == 0:
        # Every row null or empty (or no rows): nothing to clip, whatever the kind.
        kind = _kind_of_empties(geometries[~null])
        nothing = tuple(np.zeros(1, dtype=np.int64) for _ in range(kind.depth))
        return GeoArrowColumn(kind, np.empty((0, 2)), nothing, rows, len(column), null,
                              field, encoding, single=np.empty(0, dtype=bool))
    geometries = geometries[rows]
    has_z = shapely.has_z(geometries)
    try:
        kind_id, coords, offsets = shapely.to_ragged_array(geometries,
                                                           include_z=bool(has_z.any()))
    except ValueError as exc:  # Shapely: mixed kinds, or a collection
        types = sorted({shapely.GeometryType(t).name
                        for t in np.unique(shapely.get_type_id(geometries))})
        raise UnsupportedGeometryError(
            f"column {field.name!r}: the geometries must be of one kind (points, lines or "
            f"polygons, single or multi), found {', '.join(types)} ({exc})") from None
    single = np.isin(shapely.get_type_id(geometries), [0, 1, 3])
    # Shapely widens a mix of single and multi kinds to multi.
    kind = GeometryKind.of(shapely.GeometryType(kind_id))
    partial_z = bool(has_z.any() and not has_z.all())
    return GeoArrowColumn(kind, coords, tuple(offsets), rows, len(column), null, field,
                          encoding, partial_z=partial_z, single=single,
                          with_z=has_z if partial_z else None)


#: The kinds of each family, single first, by Shapely type id.
_FAMILIES = ({0, 4}, {1, 5}, {3, 6})


def _kind_of_empties(geometries: np.ndarray) -> GeometryKind:
    """Return the kind of a column whose values are all empty: points if they are none.

    Empty values of one family are that family's kind (its multi kind beside a multi
    one, as Shapely widens them); of several families or collections, points: no
    kind fits them all, and no value has a coordinate to clip.
    """
    types = {int(t) for t in np.unique(shapely.get_type_id(geometries))}
    for family in _FAMILIES:
        if types and types <= family:
            return GeometryKind.of(shapely.GeometryType(max(types)))
    return GeometryKind.POINT


def _without_empty_points(geometries: np.ndarray) -> np.ndarray:
    """Return `geometries` with the empty points of multipoints dropped.

    WKB and WKT allow ``MULTIPOINT (EMPTY, (1 2))``. ``shapely.to_ragged_array`` counts
    such a point in the offsets but writes no coordinates for it, so the arrays would not
    agree; an empty point adds nothing to a multipoint, so it goes. (A multipoint's
    points each have one coordinate unless empty: the counts find them.)
    """
    multi = shapely.get_type_id(geometries) == shapely.GeometryType.MULTIPOINT
    if not multi.any():
        return geometries
    holed = multi & (shapely.get_num_coordinates(geometries)
                     != shapely.get_num_geometries(geometries))
    if not holed.any():
        return geometries
    rows = np.flatnonzero(holed)
    points, index = shapely.get_parts(geometries[rows], return_index=True)
    kept = ~shapely.is_empty(points)
    rebuilt = np.full(rows.shape[0], shapely.from_wkt("MULTIPOINT EMPTY"), dtype=object)
    shapely.multipoints(points[kept], indices=index[kept], out=rebuilt)
    geometries = geometries.copy()
    geometries[rows] = rebuilt
    return geometries


def _parses(parse: Callable[[Any], Any], value: Any) -> bool:
    try:
        parse(value)
    except shapely.errors.ShapelyError:
        return False
    return True


def write_geoarrow(read: GeoArrowColumn, geometry_type: shapely.GeometryType | GeometryKind,
                   coords: np.ndarray, offsets: tuple,
                   source: np.ndarray) -> tuple[pa.Array, pa.Field]:
    """Return a column of ``read.row_count`` rows in the encoding `read` was read from.

    Parameters
    ----------
    read : GeoArrowColumn
        What `read_geoarrow` returned for the input column.
    geometry_type, coords, offsets
        The output geometries (a ``RaggedClipResult``'s), innermost offsets first.
    source : ndarray of int64
        Index of each output geometry among ``read``'s geometries (increasing).

    Returns
    -------
    pyarrow.Array, pyarrow.Field
        Row ``read.rows[source[i]]`` holds output geometry i; a row that was null stays
        null; every other row holds an empty geometry (an all-NaN point). Native columns
        keep their coordinate layout and dimension and become multi kinds where the
        input was a line or polygon (`_CLIPPED_KIND`); the field keeps its name,
        nullability and metadata, its extension name changed to match.
    """
    kind = GeometryKind.of(geometry_type)
    rows = read.rows[np.asarray(source, dtype=np.int64)]
    if read.encoding is not GeoArrowEncoding.NATIVE:
        return _write_serialized(read, kind, coords, offsets, source, rows)
    out_kind = _CLIPPED_KIND[read.kind]
    offsets = tuple(np.asarray(o, dtype=np.int64) for o in offsets)
    if kind is not out_kind:
        # At most one part each: an empty single geometry becomes a multi of no parts
        # (not one empty part), so its repeated part offset goes.
        parts = offsets[-1]
        nonempty = parts[1:] > parts[:-1]
        geometry_offsets = np.zeros(len(rows) + 1, dtype=np.int64)
        np.cumsum(nonempty, out=geometry_offsets[1:])
        offsets = (*offsets[:-1], np.concatenate([parts[:1], parts[1:][nonempty]]),
                   geometry_offsets)
    mask = pa.array(read.null) if read.null.any() else None
    if out_kind is GeometryKind.POINT:
        full = np.full((read.row_count, coords.shape[1]), np.nan)
        full[rows] = coords
        storage = _coords_array(full, read, mask)
    else:
        # Rows without an output geometry get none: their outer offsets repeat.
        counts = np.zeros(read.row_count, dtype=np.int64)
        counts[rows] = np.diff(offsets[-1])
        outer = np.zeros(read.row_count + 1, dtype=np.int64)
        np.cumsum(counts, out=outer[1:])
        storage = _coords_array(coords, read, None)
        names = _LEVEL_NAMES[out_kind]
        levels = [*offsets[:-1], outer]
        for depth, level_offsets in enumerate(levels):
            outermost = depth == len(levels) - 1
            storage = _list_array(level_offsets, storage, names[len(names) - 1 - depth],
                                  mask if outermost else None, read.large_offsets)
    metadata = dict(read.field.metadata or {})
    metadata[_EXTENSION_NAME] = b"geoarrow." + out_kind.name.lower().encode()
    field = pa.field(read.field.name, storage.type, read.field.nullable, metadata)
    return storage, field


def _coords_array(coords: np.ndarray, read: GeoArrowColumn,
                  mask: pa.Array | None) -> pa.Array:
    dims = "xyz"[:coords.shape[1]]
    if read.coord_layout is CoordLayout.INTERLEAVED:
        # The flat C-contiguous rows are the child buffer as they are.
        flat = pa.array(np.ascontiguousarray(coords, dtype=np.float64).reshape(-1))
        value_type = pa.list_(pa.field(dims, pa.float64(), nullable=False), len(dims))
        return pa.FixedSizeListArray.from_arrays(flat, type=value_type, mask=mask)
    return pa.StructArray.from_arrays(
        [pa.array(coords[:, i]) for i in range(len(dims))],
        fields=[pa.field(d, pa.float64(), nullable=False) for d in dims], mask=mask)


def _list_array(offsets: np.ndarray, values: pa.Array, child: str, mask: pa.Array | None,
                large: bool) -> pa.Array:
    # int32 offsets as the input had them, unless the clip's output outgrows them.
    large = large or offsets[-1] > np.iinfo(np.int32).max
    offset_type = np.int64 if large else np.int32
    list_type = (pa.large_list if large else pa.list_)(pa.field(child, values.type,
                                                                nullable=False))
    cls = pa.LargeListArray if large else pa.ListArray
    return cls.from_arrays(pa.array(offsets.astype(offset_type, copy=False)), values,
                           type=list_type, mask=mask)


def _write_serialized(read: GeoArrowColumn, kind: GeometryKind, coords: np.ndarray,
                      offsets: tuple, source: np.ndarray,
                      rows: np.ndarray) -> tuple[pa.Array, pa.Field]:
    geometries = to_shapely(kind, coords, offsets)
    if kind is GeometryKind.POINT:
        geometries[np.isnan(coords[:, :2]).any(axis=1)] = shapely.from_wkt("POINT EMPTY")
    # A single geometry left in one part is written as its own kind again.
    assert read.single is not None  # read from WKB or WKT
    single = read.single[source] & (shapely.get_num_geometries(geometries) == 1)
    geometries[single] = shapely.get_geometry(geometries[single], 0)
    if read.with_z is not None:
        # 2D values beside 3D ones: their NaN Z goes (`to_wkb` and `to_wkt` then write
        # each value in its own dimension, at most `dimension`).
        flat = ~read.with_z[source]
        geometries[flat] = shapely.force_2d(geometries[flat])
    values = np.full(read.row_count, None, dtype=object)
    values[~read.null] = shapely.from_wkt(f"{kind.name} EMPTY")  # rows left without one
    values[rows] = geometries
    dimension = 3 if read.has_z else 2
    if read.encoding is GeoArrowEncoding.WKB:
        data = shapely.to_wkb(values, output_dimension=dimension)
        array = pa.array(data, type=read.field.type if not isinstance(
            read.field.type, pa.ExtensionType) else pa.binary())
    else:
        data = shapely.to_wkt(values, rounding_precision=-1, output_dimension=dimension)
        array = pa.array(data, type=read.field.type if not isinstance(
            read.field.type, pa.ExtensionType) else pa.string())
    return array, read.field
