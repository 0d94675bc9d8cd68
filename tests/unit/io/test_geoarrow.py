"""rnsca.io.geoarrow: GeoArrow columns to ragged arrays and back, with literal arrays."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest
import shapely

from rnsca.arrays import GeometryKind
from rnsca.errors import ParseError, UnsupportedGeometryError
from rnsca.io.geoarrow import (
    CoordLayout,
    GeoArrowEncoding,
    find_geometry_column,
    read_geoarrow,
    write_geoarrow,
)
from rnsca.ragged import clip_ragged
from tests.geoarrow_tables import decode, encode, storage_type

SQUARE = shapely.from_wkt("POLYGON ((-5 -5, 5 -5, 5 5, -5 5, -5 -5))")
ZIGZAG = shapely.from_wkt("LINESTRING (-5 1, 5 1, 5 20, 8 20, 8 5, 15 5)")


def _field(name: str, storage: pa.DataType, extension: str | None, **metadata) -> pa.Field:
    meta = {} if extension is None else {"ARROW:extension:name": extension}
    return pa.field(name, storage, metadata={**meta, **metadata} or None)


def test_interleaved_coordinates_are_read_without_a_copy():
    column, field = encode([ZIGZAG], "linestring", "interleaved", z=False)
    read = read_geoarrow(column, field)
    assert read.coord_layout is CoordLayout.INTERLEAVED
    buffer = column.values.values.buffers()[1]
    assert read.coords.ctypes.data == buffer.address
    assert read.coords.tolist() == shapely.get_coordinates(ZIGZAG).tolist()
    assert [o.tolist() for o in read.offsets] == [[0, 6]]


def test_coordinates_and_offsets_are_writeable_copies_of_immutable_buffers():
    """A stream's buffers are read-only: the kernels get writeable copies."""
    column, field = encode([ZIGZAG], "linestring", "interleaved", z=False)
    sink = pa.BufferOutputStream()
    t = pa.Table.from_arrays([column], schema=pa.schema([field]))
    with pa.ipc.new_stream(sink, t.schema) as writer:
        writer.write_table(t)
    read_back = pa.ipc.open_stream(sink.getvalue()).read_all()
    read = read_geoarrow(read_back.column(0), read_back.schema.field(0))
    assert read.coords.flags.writeable and read.offsets[0].flags.writeable
    assert read.coords.tolist() == shapely.get_coordinates(ZIGZAG).tolist()
    assert [o.tolist() for o in read.offsets] == [[0, 6]]


def test_separated_coordinates_are_stacked_into_rows():
    column, field = encode([ZIGZAG], "linestring", "separated", z=False)
    read = read_geoarrow(column, field)
    assert read.coord_layout is CoordLayout.SEPARATED and read.coords.shape == (6, 2)
    assert read.coords.flags.c_contiguous


def test_polygon_offsets_run_innermost_first_as_shapely_gives_them():
    column, field = encode([SQUARE, SQUARE], "polygon", "separated", z=False)
    read = read_geoarrow(column, field)
    _, _, offsets = shapely.to_ragged_array([SQUARE, SQUARE])
    assert [o.tolist() for o in read.offsets] == [o.tolist() for o in offsets]


def test_a_sliced_column_reads_only_its_rows():
    column, field = encode([SQUARE, ZIGZAG.buffer(1), SQUARE], "polygon", "interleaved",
                           z=False)
    read = read_geoarrow(column.slice(1, 1), field)
    expected = shapely.get_coordinates(ZIGZAG.buffer(1))
    assert read.coords.tolist() == expected.tolist()
    assert read.offsets[0][0] == 0 and read.offsets[-1].tolist() == [0, 1]


def test_null_rows_and_empty_points_have_no_geometry():
    column, field = encode([shapely.Point(1, 2), None, shapely.Point(), shapely.Point(3, 4)],
                           "point", "separated", z=False)
    read = read_geoarrow(column, field)
    assert read.rows.tolist() == [0, 3] and read.coords.tolist() == [[1, 2], [3, 4]]
    assert read.null.tolist() == [False, True, False, False]


def test_a_null_row_whose_span_is_not_empty_is_skipped():
    values = pa.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0], [7.0, 8.0]],
                      pa.list_(pa.field("xy", pa.float64()), 2))
    column = pa.ListArray.from_arrays(pa.array([0, 2, 4], pa.int32()), values,
                                      mask=pa.array([True, False]))
    read = read_geoarrow(column, _field("g", column.type, "geoarrow.linestring"))
    assert read.rows.tolist() == [1] and read.coords.tolist() == [[5, 6], [7, 8]]


def test_clipped_lines_are_written_as_multilinestrings_in_the_same_layout():
    for layout in ("separated", "interleaved"):
        column, field = encode([ZIGZAG, None, shapely.LineString([(20, 20), (30, 30)])],
                               "linestring", layout, z=False)
        read = read_geoarrow(column, field)
        result = clip_ragged(read.kind, read.coords, read.offsets, (0, 0, 10, 10),
                             keep_empty=True)
        array, out = write_geoarrow(read, result.geometry_type, result.coords,
                                    result.offsets, result.source)
        assert out.metadata[b"ARROW:extension:name"] == b"geoarrow.multilinestring"
        assert array.type == storage_type("multilinestring", layout, z=False)
        got = decode(array, out)
        assert got[0].equals(shapely.from_wkt(
            "MULTILINESTRING ((0 1, 5 1, 5 10), (8 10, 8 5, 10 5))"))
        assert got[1] is None and got[2].is_empty


def test_3d_coordinates_keep_their_z():
    line = shapely.from_wkt("LINESTRING Z (-10 5 0, 10 5 20)")
    column, field = encode([line], "linestring", "interleaved", z=True)
    read = read_geoarrow(column, field)
    result = clip_ragged(read.kind, read.coords, read.offsets, (0, 0, 10, 10))
    array, out = write_geoarrow(read, result.geometry_type, result.coords, result.offsets,
                                result.source)
    assert array.type.value_type.value_type.list_size == 3
    assert decode(array, out)[0].equals(shapely.from_wkt("MULTILINESTRING Z ((0 5 10, 10 5 20))"))


def test_wkb_keeps_a_single_kind_left_in_one_part():
    column, field = encode([ZIGZAG, SQUARE.boundary], "linestring", "wkb", z=False)
    read = read_geoarrow(column, field)
    assert read.encoding is GeoArrowEncoding.WKB
    result = clip_ragged(read.kind, read.coords, read.offsets, (0, 0, 10, 10))
    array, _ = write_geoarrow(read, result.geometry_type, result.coords, result.offsets,
                              result.source)
    types = [g.geom_type for g in shapely.from_wkb(array.to_numpy(zero_copy_only=False))]
    assert types == ["MultiLineString", "LineString"]


def test_a_binary_column_named_geometry_is_read_as_wkb():
    schema = pa.schema([("id", pa.int64()), ("geometry", pa.binary())])
    assert find_geometry_column(schema) == 1
    read = read_geoarrow(pa.array([shapely.to_wkb(SQUARE)], pa.binary()), schema.field(1))
    assert read.kind is GeometryKind.POLYGON and read.single.tolist() == [True]


def test_no_geometry_column_names_the_columns():
    with pytest.raises(ParseError, match=r"no geometry column.*\['id', 'geom'\]"):
        find_geometry_column(pa.schema([("id", pa.int64()), ("geom", pa.string())]))


def test_two_geometry_columns_need_a_name():
    tagged = _field("a", pa.binary(), "geoarrow.wkb")
    schema = pa.schema([tagged, tagged.with_name("b")])
    with pytest.raises(ParseError, match="several geometry columns"):
        find_geometry_column(schema)
    assert find_geometry_column(schema, "b") == 1


@pytest.mark.parametrize(("extension", "storage", "error", "match"), [
    ("geoarrow.geometry", pa.binary(), UnsupportedGeometryError, "not one this reader"),
    ("geoarrow.polygon", storage_type("linestring", "separated", False), ParseError,
     "levels of lists"),
    ("geoarrow.point", pa.list_(pa.field("xym", pa.float64()), 3),
     UnsupportedGeometryError, "M values"),
    ("geoarrow.point", pa.struct([("x", pa.float32()), ("y", pa.float32())]), ParseError,
     "must be double"),
    ("geoarrow.wkb", pa.string(), ParseError, "stored as binary"),
])
def test_a_column_that_is_not_its_extension_is_refused(extension, storage, error, match):
    with pytest.raises(error, match=match):
        read_geoarrow(pa.array([], storage), _field("g", storage, extension))


def test_spherical_edges_are_refused():
    storage = storage_type("linestring", "separated", False)
    field = _field("g", storage, "geoarrow.linestring",
                   **{"ARROW:extension:metadata": '{"edges": "spherical"}'})
    with pytest.raises(UnsupportedGeometryError, match="planar"):
        read_geoarrow(pa.array([], storage), field)


def test_null_coordinates_are_refused():
    storage = pa.list_(pa.field("vertices", pa.struct([("x", pa.float64()),
                                                        ("y", pa.float64())])))
    column = pa.array([[{"x": 1.0, "y": None}, {"x": 2.0, "y": 2.0}]], storage)
    with pytest.raises(ParseError, match="null coordinates"):
        read_geoarrow(column, _field("g", storage, "geoarrow.linestring"))


def test_bad_wkb_names_its_row():
    column = pa.array([shapely.to_wkb(SQUARE), b"\x01\x02"], pa.binary())
    with pytest.raises(ParseError, match="row 1: not valid WKB"):
        read_geoarrow(column, _field("g", pa.binary(), "geoarrow.wkb"))


def test_mixed_kinds_in_wkb_are_refused():
    column = pa.array(list(shapely.to_wkb([SQUARE, ZIGZAG])), pa.binary())
    with pytest.raises(UnsupportedGeometryError, match="one kind.*LINESTRING, POLYGON"):
        read_geoarrow(column, _field("g", pa.binary(), "geoarrow.wkb"))


def test_empty_column_reads_as_empty_arrays():
    column, field = encode([], "polygon", "interleaved", z=False)
    read = read_geoarrow(column, field)
    assert read.coords.shape == (0, 2) and read.rows.shape == (0,)
    assert np.array_equal(read.offsets[-1], [0])


def test_large_lists_are_read_and_written_as_large_lists():
    vertex = pa.struct([pa.field("x", pa.float64()), pa.field("y", pa.float64())])
    storage = pa.large_list(pa.field("vertices", vertex))
    column = pa.array([[{"x": -5.0, "y": 1.0}, {"x": 15.0, "y": 1.0}]], storage)
    read = read_geoarrow(column, _field("g", storage, "geoarrow.linestring"))
    assert read.large_offsets
    result = clip_ragged(read.kind, read.coords, read.offsets, (0, 0, 10, 10))
    array, _ = write_geoarrow(read, result.geometry_type, result.coords, result.offsets,
                              result.source)
    assert pa.types.is_large_list(array.type) and pa.types.is_large_list(array.type.value_type)
    assert array.to_pylist() == [[[{"x": 0.0, "y": 1.0}, {"x": 10.0, "y": 1.0}]]]


def test_interleaved_values_must_match_their_dimension_names():
    storage = pa.list_(pa.field("xy", pa.float64()), 3)
    with pytest.raises(ParseError, match="3 values per vertex named 'xy'"):
        read_geoarrow(pa.array([[1.0, 2.0, 3.0]], storage),
                      _field("g", storage, "geoarrow.point"))


def _serialized(values, encoding: str) -> tuple[pa.Array, pa.Field]:
    """Return a WKB or WKT column of these WKT texts (None: a null row)."""
    geometries = [None if v is None else shapely.from_wkt(v) for v in values]
    if encoding == "wkb":
        data = [None if g is None else shapely.to_wkb(g, output_dimension=3)
                for g in geometries]
        return pa.array(data, pa.binary()), _field("g", pa.binary(), "geoarrow.wkb")
    return pa.array(values, pa.string()), _field("g", pa.string(), "geoarrow.wkt")


def _clip_and_write(read, keep_empty: bool = True) -> list:
    result = clip_ragged(read.kind, read.coords, read.offsets, (0, 0, 10, 10),
                         keep_empty=keep_empty, partial_z=read.partial_z)
    array, _ = write_geoarrow(read, result.geometry_type, result.coords, result.offsets,
                              result.source)
    parse = shapely.from_wkb if pa.types.is_binary(array.type) else shapely.from_wkt
    return list(parse(array.to_numpy(zero_copy_only=False)))


@pytest.mark.parametrize("encoding", ["wkb", "wkt"])
@pytest.mark.parametrize("values", [[None, None], [], ["POLYGON EMPTY", None],
                                    ["POINT EMPTY", "LINESTRING EMPTY"]],
                         ids=["all null", "no rows", "null and empty", "empties of two kinds"])
def test_a_column_without_a_present_geometry_reads_as_no_geometries(encoding, values):
    read = read_geoarrow(*_serialized(values, encoding))
    assert read.coords.shape == (0, 2) and read.rows.shape == (0,)
    assert all(level.tolist() == [0] for level in read.offsets)
    got = _clip_and_write(read)
    assert [g is None for g in got] == [v is None for v in values]
    assert all(g is None or g.is_empty for g in got)


def test_empty_values_of_one_family_give_the_column_its_kind():
    read = read_geoarrow(*_serialized(["POLYGON EMPTY", "MULTIPOLYGON EMPTY", None], "wkb"))
    assert read.kind is GeometryKind.MULTIPOLYGON
    read = read_geoarrow(*_serialized(["LINESTRING EMPTY"], "wkt"))
    assert read.kind is GeometryKind.LINESTRING


@pytest.mark.parametrize("encoding", ["wkb", "wkt"])
def test_2d_and_3d_values_are_written_back_each_in_its_own_dimension(encoding):
    read = read_geoarrow(*_serialized(
        ["LINESTRING (-5 1, 15 1)", "LINESTRING Z (-5 2 7, 15 2 9)", None,
         "LINESTRING (-5 3, 5 3, 5 20, 8 20, 8 5, 15 5)"], encoding))
    assert read.partial_z and read.with_z.tolist() == [False, True, False]
    got = _clip_and_write(read)
    assert [None if g is None else shapely.to_wkt(g) for g in got] == [
        "LINESTRING (0 1, 10 1)", "LINESTRING Z (0 2 7.5, 10 2 8.5)", None,
        "MULTILINESTRING ((0 3, 5 3, 5 10), (8 10, 8 5, 10 5))"]


def test_a_column_of_one_dimension_has_no_per_value_dimensions():
    read = read_geoarrow(*_serialized(["LINESTRING Z (-5 2 7, 15 2 9)"], "wkb"))
    assert not read.partial_z and read.with_z is None
    assert shapely.has_z(_clip_and_write(read)[0])


def test_empty_points_of_a_multipoint_are_dropped():
    read = read_geoarrow(*_serialized(["MULTIPOINT (EMPTY, (1 1), EMPTY, (2 2))",
                                       "MULTIPOINT (EMPTY)", "MULTIPOINT ((3 3))"], "wkb"))
    assert read.rows.tolist() == [0, 2]
    assert read.coords.tolist() == [[1, 1], [2, 2], [3, 3]]
    assert read.offsets[0].tolist() == [0, 2, 3]
