"""Shapely geometries to and from the GeoArrow columns ``POST /v1/clip/geoarrow`` speaks.

`geometry_table` writes an array of Shapely geometries as one GeoArrow column: the
native encoding (interleaved coordinates and list offsets, from
``shapely.to_ragged_array``) when the geometries are of one family (points, lines or
polygons, single and multi mixed) and all 2D or all 3D, else WKB (which the server reads
whatever the mix, and answers in kind). `read_geometries` reads a column back into
Shapely geometries, whichever of the encodings the server answered in (native
separated or interleaved coordinates, WKB or WKT). `find_geometry_column` picks a
table's geometry column as the server does.

pyarrow and Shapely are imported here only; the module is loaded for the calls that need
them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyarrow as pa
import shapely

from rnsca_client.errors import InvalidInputError, ResponseFormatError

__all__ = ["ROW_COLUMN", "GEOMETRY_COLUMN", "geometry_table", "read_geometries",
           "find_geometry_column", "write_stream", "read_stream", "single_again", "is_single",
           "extension_name"]

#: The column of each row's position in the caller's input, sent beside the geometry and
#: passed through by the server: the answer's rows say which inputs they came from.
ROW_COLUMN = "rnsca_row"
#: The name of the geometry column the SDK sends (the server's errors name its rows).
GEOMETRY_COLUMN = "geometry"

_EXTENSION_NAME = b"ARROW:extension:name"
#: GeoArrow's name of each list level, outermost first (https://geoarrow.org/format.html).
_LEVELS = {shapely.GeometryType.POINT: (),
           shapely.GeometryType.LINESTRING: ("vertices",),
           shapely.GeometryType.MULTIPOINT: ("points",),
           shapely.GeometryType.POLYGON: ("rings", "vertices"),
           shapely.GeometryType.MULTILINESTRING: ("linestrings", "vertices"),
           shapely.GeometryType.MULTIPOLYGON: ("polygons", "rings", "vertices")}
_KIND_OF_EXTENSION = {f"geoarrow.{kind.name.lower()}": kind for kind in _LEVELS}
#: Shapely's type id of each kind the native encoding takes: its family.
_FAMILY = {0: "points", 4: "points", 1: "lines", 5: "lines", 3: "polygons", 6: "polygons"}
_SINGLE_OF_MULTI = {shapely.GeometryType.MULTIPOINT: shapely.GeometryType.POINT,
                    shapely.GeometryType.MULTILINESTRING: shapely.GeometryType.LINESTRING,
                    shapely.GeometryType.MULTIPOLYGON: shapely.GeometryType.POLYGON}
#: Shapely's type ids of the single kinds, and the empty geometry of each family.
_SINGLE = (0, 1, 3)
_EMPTY = {shapely.GeometryType.POINT: "POINT EMPTY",
          shapely.GeometryType.MULTIPOINT: "MULTIPOINT EMPTY",
          shapely.GeometryType.LINESTRING: "LINESTRING EMPTY",
          shapely.GeometryType.MULTILINESTRING: "MULTILINESTRING EMPTY",
          shapely.GeometryType.POLYGON: "POLYGON EMPTY",
          shapely.GeometryType.MULTIPOLYGON: "MULTIPOLYGON EMPTY"}


def geometry_table(geometries: np.ndarray, rows: np.ndarray) -> pa.Table:
    """Return a table of two columns: `geometries` as GeoArrow and their `rows`.

    Parameters
    ----------
    geometries : ndarray of object
        Shapely geometries; None (missing) is written as an empty geometry, which the
        server drops unless asked to keep empty rows.
    rows : ndarray of int64
        The position of each geometry in the caller's input (`ROW_COLUMN`).

    Returns
    -------
    pyarrow.Table
        `GEOMETRY_COLUMN` in the native encoding (interleaved ``xy`` or ``xyz``) where
        the geometries allow it, else ``geoarrow.wkb``.

    Examples
    --------
    >>> table = geometry_table(np.array([shapely.box(0, 0, 1, 1), None]), np.arange(2))
    >>> table.schema.field("geometry").metadata[b"ARROW:extension:name"]
    b'geoarrow.polygon'
    >>> geometry_table(np.array([shapely.Point(0, 0), shapely.box(0, 0, 1, 1)]),
    ...                np.arange(2)).schema.field("geometry").metadata
    {b'ARROW:extension:name': b'geoarrow.wkb'}
    """
    column, field = _native_column(geometries)
    if column is None:
        column, field = _wkb_column(geometries)
    return pa.Table.from_arrays([column, pa.array(rows, pa.int64())],
                                schema=pa.schema([field, pa.field(ROW_COLUMN, pa.int64(),
                                                                  nullable=False)]))


def _native_column(geometries: np.ndarray) -> tuple[pa.Array | None, pa.Field | None]:
    """Return the native column of `geometries`, or None where they need WKB."""
    present = ~shapely.is_missing(geometries)
    types = np.unique(shapely.get_type_id(geometries[present]))
    families = {_FAMILY.get(int(t)) for t in types}
    if len(families) != 1 or None in families:
        return None, None                # a mix of families, collections, or nothing at all
    has_z = shapely.has_z(geometries[present])
    if has_z.any() and not has_z.all():
        return None, None                # 2D beside 3D: WKB keeps each as it is
    # Shapely widens a single kind to its multi beside one; an empty single would then be
    # one part with no coordinates (a polygon of no rings, which from_ragged_array reads
    # into a crash in Shapely 2.2), so empties and missing geometries become the empty of
    # the kind written: a geometry of no parts.
    kind_written = shapely.GeometryType(int(types.max()))
    empty = ~present | (shapely.is_empty(geometries) & ~np.isin(shapely.get_type_id(
        geometries), [int(kind_written)]))
    if empty.any():
        geometries = geometries.copy()
        geometries[empty] = shapely.from_wkt(_EMPTY[kind_written])
    kind, coords, offsets = shapely.to_ragged_array(geometries, include_z=bool(has_z.any()))
    dims = "xyz"[:coords.shape[1]]
    storage: pa.Array = pa.FixedSizeListArray.from_arrays(
        pa.array(np.ascontiguousarray(coords).reshape(-1)),
        type=pa.list_(pa.field(dims, pa.float64(), nullable=False), len(dims)))
    names = _LEVELS[kind]
    for depth, level in enumerate(offsets):
        large = level.dtype == np.int64
        child = pa.field(names[len(names) - 1 - depth], storage.type, nullable=False)
        cls = pa.LargeListArray if large else pa.ListArray
        storage = cls.from_arrays(pa.array(level),
                                  storage, type=(pa.large_list if large else pa.list_)(child))
    field = pa.field(GEOMETRY_COLUMN, storage.type, metadata={
        _EXTENSION_NAME: f"geoarrow.{kind.name.lower()}".encode()})
    return storage, field


def _wkb_column(geometries: np.ndarray) -> tuple[pa.Array, pa.Field]:
    has_z = shapely.has_z(geometries[~shapely.is_missing(geometries)])
    values = shapely.to_wkb(geometries, output_dimension=3 if has_z.any() else 2)
    return pa.array(values, pa.binary()), pa.field(
        GEOMETRY_COLUMN, pa.binary(), metadata={_EXTENSION_NAME: b"geoarrow.wkb"})


def read_geometries(column: pa.Array | pa.ChunkedArray, field: pa.Field) -> np.ndarray:
    """Return a GeoArrow column as an array of Shapely geometries (null rows: None).

    Native columns (separated or interleaved coordinates, list or large list offsets),
    ``geoarrow.wkb`` and ``geoarrow.wkt`` are read; an all-NaN point is an empty point.

    Raises
    ------
    ResponseFormatError
        The column is none of those.

    Examples
    --------
    >>> table = geometry_table(np.array([shapely.box(0, 0, 1, 1)]), np.arange(1))
    >>> read_geometries(table.column("geometry"), table.schema.field("geometry"))
    array([<POLYGON ((1 0, 1 1, 0 1, 0 0, 1 0))>], dtype=object)
    """
    if isinstance(column, pa.ChunkedArray):
        column = (column.chunk(0) if column.num_chunks == 1
                  else pa.concat_arrays(column.chunks) if column.num_chunks
                  else pa.array([], column.type))
    if isinstance(column, pa.ExtensionArray):
        column = column.storage
    name = extension_name(field)
    null = column.is_null().to_numpy(zero_copy_only=False) if column.null_count else None
    if name in ("geoarrow.wkb", "geoarrow.wkt") or (
            name is None and pa.types.is_binary(column.type)):
        values = column.to_numpy(zero_copy_only=False)
        return (shapely.from_wkt if name == "geoarrow.wkt" else shapely.from_wkb)(values)
    kind = _KIND_OF_EXTENSION.get(name or "")
    if kind is None:
        raise ResponseFormatError(f"column {field.name!r} is not GeoArrow ({name!r})")
    offsets = []
    values = column
    for _ in _LEVELS[kind]:
        # A slice's offsets start past 0 and its child runs on: take the part it uses.
        level = values.offsets.to_numpy()
        if len(level) == 0:               # an empty array may have no offsets buffer
            level = np.zeros(1, np.int64)
        values = values.values.slice(level[0], level[-1] - level[0])
        offsets.append(level - level[0])
    coords = _coordinates(values)
    if kind is shapely.GeometryType.MULTIPOLYGON:
        offsets = _without_ringless_polygons(offsets)
    if coords.shape[0] == 0 and offsets:
        # Nothing left in any row (Shapely's from_ragged_array cannot read no coordinates).
        geometries = np.full(len(column), shapely.from_wkt(_EMPTY[kind]), dtype=object)
    else:
        geometries = shapely.from_ragged_array(kind, coords,
                                               tuple(reversed(offsets)) or None)
    if kind is shapely.GeometryType.POINT:
        empty = np.isnan(coords).all(axis=1)
        geometries[empty] = shapely.from_wkt("POINT EMPTY")
    if null is not None:
        geometries[null] = None
    return geometries


def _without_ringless_polygons(offsets: list[np.ndarray]) -> list[np.ndarray]:
    """Return multipolygon offsets (outermost first) without the polygons of no rings.

    GeoArrow allows such a polygon (an empty part); Shapely 2.2's ``from_ragged_array``
    crashes the process on one, and the part adds nothing.

    Examples
    --------
    >>> [o.tolist() for o in _without_ringless_polygons(
    ...     [np.array([0, 2, 3]), np.array([0, 1, 1, 2]), np.array([0, 5, 10])])]
    [[0, 1, 2], [0, 1, 2], [0, 5, 10]]
    """
    geometry_offsets, polygon_offsets = offsets[0], offsets[1]
    ringless = polygon_offsets[1:] == polygon_offsets[:-1]
    if not ringless.any():
        return offsets
    kept = np.concatenate([[0], np.cumsum(~ringless)])
    return [kept[geometry_offsets], np.concatenate([polygon_offsets[:1],
                                                    polygon_offsets[1:][~ringless]]),
            *offsets[2:]]


def _coordinates(values: pa.Array) -> np.ndarray:
    """Return the (n, 2) or (n, 3) coordinates of a separated or interleaved array."""
    if pa.types.is_struct(values.type):
        return np.column_stack([values.field(i).to_numpy(zero_copy_only=False)
                                for i in range(values.type.num_fields)])
    size = values.type.list_size
    return values.flatten().to_numpy(zero_copy_only=False).reshape(-1, size)


def single_again(geometries: np.ndarray, single: np.ndarray) -> np.ndarray:
    """Return `geometries` where each that was `single` is its own kind again.

    The server answers native lines and polygons as multi kinds (a cut may leave several
    parts); a single-kind input left in one part, or in none, is a single kind again, as
    ``shapely.intersection`` gives it.

    Examples
    --------
    >>> out = single_again(np.array([shapely.MultiPolygon([shapely.box(0, 0, 1, 1)]),
    ...                              shapely.from_wkt("MULTIPOLYGON EMPTY")]),
    ...                    np.array([True, True]))
    >>> [g.wkt for g in out]
    ['POLYGON ((1 0, 1 1, 0 1, 0 0, 1 0))', 'POLYGON EMPTY']
    """
    type_id = shapely.get_type_id(geometries)
    multi = single & (type_id >= 4) & (type_id <= 6)
    if not multi.any():
        return geometries
    geometries = geometries.copy()
    parts = shapely.get_num_geometries(geometries)
    one = multi & (parts == 1)
    geometries[one] = shapely.get_geometry(geometries[one], 0)
    for multi_kind, single_kind in _SINGLE_OF_MULTI.items():
        none = multi & (parts == 0) & (type_id == int(multi_kind))
        if none.any():
            geometries[none] = shapely.from_wkt(_EMPTY[single_kind])
    return geometries


def is_single(geometries: np.ndarray) -> np.ndarray:
    """Return whether each geometry is a single kind (point, line string, polygon)."""
    return np.isin(shapely.get_type_id(geometries), _SINGLE)


def extension_name(field: pa.Field) -> str | None:
    """Return the GeoArrow extension name of `field` (registered type or metadata)."""
    if isinstance(field.type, pa.ExtensionType):
        return field.type.extension_name
    name = (field.metadata or {}).get(_EXTENSION_NAME)
    return None if name is None else name.decode("utf-8", "replace")


def find_geometry_column(schema: pa.Schema, name: str | None = None) -> int:
    """Return the index of the geometry column of `schema`, as the server finds it.

    `name`, else the one field tagged ``geoarrow.*``, else a binary field named
    ``geometry`` (WKB).

    Raises
    ------
    InvalidInputError
        No such column, none is geometry, or several are and `name` does not choose.
    """
    if name is not None:
        index = schema.get_field_index(name)
        if index < 0:
            raise InvalidInputError(f"no column named {name!r}; the columns are "
                                    f"{schema.names}")
        return index
    tagged = [i for i, field in enumerate(schema)
              if (extension_name(field) or "").startswith("geoarrow.")]
    if len(tagged) > 1:
        raise InvalidInputError(f"several geometry columns "
                                f"({[schema.names[i] for i in tagged]}): name one (column=)")
    if tagged:
        return tagged[0]
    index = schema.get_field_index(GEOMETRY_COLUMN)
    if index >= 0 and pa.types.is_binary(schema.field(index).type):
        return index
    raise InvalidInputError(
        "the table has no geometry column: tag one with ARROW:extension:name "
        f"(geoarrow.polygon, geoarrow.wkb, ...) or name a binary WKB column 'geometry'; "
        f"the columns are {schema.names}")


def write_stream(table: Any) -> bytes:
    """Return `table` (a pyarrow Table or RecordBatch) as an Arrow IPC stream."""
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as writer:
        writer.write(table)
    return sink.getvalue().to_pybytes()


def read_stream(stream: bytes) -> pa.Table:
    """Return the table of an Arrow IPC stream.

    Raises
    ------
    ResponseFormatError
        `stream` is not one.
    """
    try:
        return pa.ipc.open_stream(pa.py_buffer(stream)).read_all()
    except pa.ArrowInvalid as exc:
        raise ResponseFormatError(f"the answer is not an Arrow IPC stream: {exc}") from None

