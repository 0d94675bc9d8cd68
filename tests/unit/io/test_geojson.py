"""GeoJSON to ragged arrays and back: layout, strict validation with JSON paths, writing."""

import copy
import enum
import gc
import math
import struct

import numpy as np
import orjson
import pytest
import shapely
from shapely.geometry import mapping

from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    LimitExceededError,
    ParseError,
)
from rnsca.io import geojson as geojson_module
from rnsca.io.geojson import (
    MAX_COLLECTION_DEPTH,
    dumps,
    from_geojson,
    loads,
    to_geojson,
)
from rnsca.io.msgpack_decode import same_geometries
from rnsca.runtime import collector_paused

SQUARE = [[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]
HOLE = [[2, 2], [2, 4], [4, 4], [4, 2], [2, 2]]
TRIANGLE = [[20, 20], [30, 20], [25, 30], [20, 20]]


def feature(geometry, **members):
    return {"type": "Feature", "properties": members.pop("properties", None),
            "geometry": geometry, **members}


def collection(*features, **members):
    return {"type": "FeatureCollection", "features": list(features), **members}


def levels(ragged):
    geometry_type, coords, offsets = ragged
    return geometry_type.name, coords.tolist(), [level.tolist() for level in offsets]


# --------------------------------------------------------------------------- layout

def test_point_is_one_multipoint_geometry_of_one_position():
    layout = from_geojson({"type": "Point", "coordinates": [1, 2]})
    assert levels(layout.points) == ("MULTIPOINT", [[1.0, 2.0]], [[0, 1]])
    assert levels(layout.lines) == ("MULTILINESTRING", [], [[0], [0]])
    assert levels(layout.polygons) == ("MULTIPOLYGON", [], [[0], [0], [0]])
    assert not layout.has_z and layout.vertex_count == 1


def test_multipoint_is_one_multipoint_geometry():
    layout = from_geojson({"type": "MultiPoint", "coordinates": [[1, 2], [3, 4], [5, 6]]})
    assert levels(layout.points) == ("MULTIPOINT", [[1, 2], [3, 4], [5, 6]], [[0, 3]])


def test_linestring_is_one_part():
    layout = from_geojson({"type": "LineString", "coordinates": [[0, 0], [1, 1], [2, 0]]})
    assert levels(layout.lines) == ("MULTILINESTRING", [[0, 0], [1, 1], [2, 0]],
                                    [[0, 3], [0, 1]])


def test_multilinestring_parts_share_one_geometry():
    layout = from_geojson({"type": "MultiLineString",
                           "coordinates": [[[0, 0], [1, 1]], [[5, 5], [6, 6], [7, 5]]]})
    assert levels(layout.lines) == ("MULTILINESTRING",
                                    [[0, 0], [1, 1], [5, 5], [6, 6], [7, 5]],
                                    [[0, 2, 5], [0, 2]])


def test_polygon_with_a_hole_is_two_rings_of_one_polygon():
    layout = from_geojson({"type": "Polygon", "coordinates": [SQUARE, HOLE]})
    name, coords, offsets = levels(layout.polygons)
    assert name == "MULTIPOLYGON"
    assert coords == SQUARE + HOLE
    assert offsets == [[0, 5, 10], [0, 2], [0, 1]]


def test_multipolygon_polygons_share_one_geometry():
    layout = from_geojson({"type": "MultiPolygon",
                           "coordinates": [[SQUARE, HOLE], [TRIANGLE]]})
    assert levels(layout.polygons)[2] == [[0, 5, 10, 14], [0, 2, 3], [0, 2]]


def test_layout_matches_shapely_ragged_arrays():
    geoms = [shapely.MultiPolygon([shapely.Polygon(SQUARE, [HOLE]), shapely.Polygon(TRIANGLE)]),
             shapely.MultiPolygon([shapely.Polygon(TRIANGLE)])]
    doc = collection(*(feature(mapping(g)) for g in geoms))
    kind, coords, offsets = shapely.to_ragged_array(geoms)
    ours = from_geojson(doc).polygons
    assert ours[0] == kind
    np.testing.assert_array_equal(ours[1], coords)
    for a, b in zip(ours[2], offsets, strict=True):
        np.testing.assert_array_equal(a, b)


def test_geometries_are_numbered_in_document_order_per_kind():
    doc = collection(
        feature({"type": "LineString", "coordinates": [[0, 0], [1, 0]]}),
        feature({"type": "GeometryCollection", "geometries": [
            {"type": "Point", "coordinates": [7, 7]},
            {"type": "GeometryCollection", "geometries": [
                {"type": "LineString", "coordinates": [[2, 0], [3, 0]]}]},
            {"type": "Polygon", "coordinates": [TRIANGLE]},
        ]}),
        feature(None),
        feature({"type": "MultiPoint", "coordinates": [[8, 8], [9, 9]]}),
    )
    layout = from_geojson(doc)
    assert levels(layout.points) == ("MULTIPOINT", [[7, 7], [8, 8], [9, 9]], [[0, 1, 3]])
    assert levels(layout.lines) == ("MULTILINESTRING", [[0, 0], [1, 0], [2, 0], [3, 0]],
                                    [[0, 2, 4], [0, 1, 2]])
    assert layout.geometry_count("polygons") == 1


def test_coordinates_are_contiguous_float64_and_offsets_int64():
    layout = from_geojson({"type": "Polygon", "coordinates": [SQUARE]})
    _, coords, offsets = layout.polygons
    assert coords.dtype == np.float64 and coords.flags.c_contiguous
    assert all(level.dtype == np.int64 for level in offsets)


def test_empty_coordinates_are_empty_geometries():
    doc = collection(*(feature({"type": t, "coordinates": []}) for t in (
        "Point", "MultiPoint", "LineString", "MultiLineString", "Polygon", "MultiPolygon")))
    layout = from_geojson(doc)
    assert levels(layout.points) == ("MULTIPOINT", [], [[0, 0, 0]])
    assert levels(layout.lines) == ("MULTILINESTRING", [], [[0], [0, 0, 0]])
    assert levels(layout.polygons) == ("MULTIPOLYGON", [], [[0], [0], [0, 0, 0]])


def test_empty_members_of_multi_geometries_are_read_as_nothing():
    layout = from_geojson(collection(
        feature({"type": "MultiLineString", "coordinates": [[], [[0, 0], [1, 1]], []]}),
        feature({"type": "MultiPolygon", "coordinates": [[], [TRIANGLE]]})))
    assert levels(layout.lines)[2] == [[0, 2], [0, 1]]
    assert levels(layout.polygons)[2] == [[0, 4], [0, 1], [0, 1]]


def test_text_and_dict_give_the_same_layout():
    doc = collection(feature({"type": "Polygon", "coordinates": [SQUARE, HOLE]}))
    for text in (orjson.dumps(doc), orjson.dumps(doc).decode(), bytearray(orjson.dumps(doc))):
        layout = from_geojson(text)
        assert levels(layout.polygons) == levels(from_geojson(doc).polygons)
        assert layout.document == doc


def test_shapely_mapping_with_tuples_is_read():
    polygon = shapely.Polygon(SQUARE, [HOLE])
    layout = from_geojson(mapping(polygon))
    assert levels(layout.polygons)[1] == SQUARE + HOLE


def test_numpy_scalars_in_a_dict_are_numbers():
    doc = {"type": "LineString",
           "coordinates": [[np.float64(0.5), np.int32(1)], [np.float32(2.0), 3]]}
    assert levels(from_geojson(doc).lines)[1] == [[0.5, 1.0], [2.0, 3.0]]


def test_large_ints_are_read_as_floats():
    layout = from_geojson({"type": "Point", "coordinates": [2 ** 70, -(10 ** 300)]})
    assert layout.points[1].tolist() == [[float(2 ** 70), -1e300]]


def test_z_is_kept():
    layout = from_geojson(collection(
        feature({"type": "LineString", "coordinates": [[0, 0, 1], [1, 1, 2]]}),
        feature({"type": "Point", "coordinates": [5, 5, 9]})))
    assert layout.has_z
    assert layout.lines[1].tolist() == [[0, 0, 1], [1, 1, 2]]
    assert layout.points[1].tolist() == [[5, 5, 9]]
    assert layout.polygons[1].shape == (0, 3)


def test_numbers_after_z_are_dropped():
    layout = from_geojson({"type": "LineString",
                           "coordinates": [[0, 0, 1, 7], [1, 1, 2], [2, 2, 3, 8, 9]]})
    assert layout.lines[1].tolist() == [[0, 0, 1], [1, 1, 2], [2, 2, 3]]


def test_null_geometry_is_in_no_array():
    layout = from_geojson(collection(feature(None), feature(None)))
    assert layout.vertex_count == 0
    assert all(layout.geometry_count(k) == 0 for k in ("points", "lines", "polygons"))


# --------------------------------------------------------------------------- errors

def error_path(doc, error=InvalidGeometryError, **kwargs):
    with pytest.raises(error) as info:
        from_geojson(doc, **kwargs)
    message = str(info.value)
    assert f"invalid GeoJSON at {info.value.path or '<top level>'}: " in message
    return info.value.path, message


def line(*positions):
    return {"type": "LineString", "coordinates": list(positions)}


@pytest.mark.parametrize("doc, path, reason", [
    ([1, 2], "", "expected a GeoJSON object, got an array of 2"),
    ({"coordinates": [1, 2]}, "", 'missing member "type"'),
    ({"type": "Pointt", "coordinates": [1, 2]}, "type", "unknown GeoJSON type 'Pointt'"),
    ({"type": "point", "coordinates": [1, 2]}, "type", "unknown GeoJSON type 'point'"),
    ({"type": 5, "coordinates": [1, 2]}, "type", "expected a string, got number 5"),
    ({"type": "FeatureCollection"}, "", 'FeatureCollection has no "features" member'),
    ({"type": "FeatureCollection", "features": {}}, "features", "expected an array"),
    (collection(feature(None), 5), "features[1]", "expected a Feature object, got number 5"),
    (collection({"type": "feature", "geometry": None}), "features[0].type",
     "expected \"Feature\", got 'feature'"),
    (collection({"type": "Feature", "properties": {}}), "features[0]",
     'Feature has no "geometry" member (use null for a feature without geometry)'),
    (collection(feature(feature(None))), "features[0].geometry.type",
     "expected a geometry type"),
    (collection(feature({"type": "Point"})), "features[0].geometry",
     'Point has no "coordinates" member'),
    (collection(feature({"type": "Point", "coordinates": None})),
     "features[0].geometry.coordinates", "expected an array, got null"),
    (collection(feature({"type": "Polygon", "coordinates": "0 0"})),
     "features[0].geometry.coordinates", "expected an array, got string '0 0'"),
    ({"type": "Point", "coordinates": [1]}, "coordinates",
     "a position needs at least 2 numbers, got 1"),
    ({"type": "MultiPoint", "coordinates": [[1, 2], []]}, "coordinates[1]",
     "a position needs at least 2 numbers, got 0"),
    (line(1, 2), "coordinates[0]", "expected a position (an array of 2 or 3 numbers), "
     "got number 1"),
    (line([0, 0], [1, "2"]), "coordinates[1][1]", "expected a number, got string '2'"),
    (line([0, 0], [True, 2]), "coordinates[1][0]", "expected a number, got boolean True"),
    (line([0, 0], [1, None]), "coordinates[1][1]", "expected a number, got null"),
    (line([0, 0], [1, [2]]), "coordinates[1][1]", "expected a number, got an array of 1"),
    (line([0, 0], [1, float("nan")]), "coordinates[1][1]", "expected a finite number, got nan"),
    (line([0, 0], [float("-inf"), 1]), "coordinates[1][0]",
     "expected a finite number, got -inf"),
    (line([0, 0], [10 ** 400, 1]), "coordinates[1][0]", "expected a finite number"),
    (line([0, 0, 0], [1, 1, float("nan")]), "coordinates[1][2]", "expected a finite number"),
    (line([0, 0, 0], [1, 1, 1, "m"]), "coordinates[1][3]", "expected a number"),
    (line([0, 0]), "coordinates", "a LineString needs at least 2 positions, got 1"),
    ({"type": "MultiLineString", "coordinates": [[[0, 0], [1, 1]], [[2, 2]]]},
     "coordinates[1]", "a LineString needs at least 2 positions, got 1"),
    ({"type": "MultiLineString", "coordinates": [[[0, 0], [1, 1]], 3]}, "coordinates[1]",
     "expected an array, got number 3"),
    ({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [0, 0]]]}, "coordinates[0]",
     "a polygon ring needs at least 4 positions, got 3"),
    ({"type": "Polygon", "coordinates": [[]]}, "coordinates[0]",
     "a polygon ring needs at least 4 positions, got 0"),
    ({"type": "Polygon", "coordinates": [SQUARE, HOLE[:-1] + [[2, 3]]]}, "coordinates[1]",
     "polygon ring is not closed: its first position [2.0, 2.0] differs from its last "
     "[2.0, 3.0]"),
    ({"type": "Polygon", "coordinates": [SQUARE[:-1]]}, "coordinates[0]",
     "polygon ring is not closed"),
    ({"type": "Polygon", "coordinates": [[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 1]]]},
     "coordinates[0]", "polygon ring is not closed: its first position [0.0, 0.0, 0.0] "
     "differs from its last [0.0, 0.0, 1.0]"),
    ({"type": "Polygon", "coordinates": [SQUARE, 7]}, "coordinates[1]", "expected an array"),
    ({"type": "MultiPolygon", "coordinates": [[SQUARE], [TRIANGLE[:-1]]]},
     "coordinates[1][0]", "a polygon ring needs at least 4 positions, got 3"),
    ({"type": "MultiPolygon", "coordinates": [[SQUARE], [SQUARE[1:]]]},
     "coordinates[1][0]", "polygon ring is not closed"),
    ({"type": "MultiPolygon", "coordinates": [SQUARE]}, "coordinates[0][0]",
     "a polygon ring needs at least 4 positions, got 2"),
    ({"type": "MultiPolygon", "coordinates": [[SQUARE, [1, 2]]]}, "coordinates[0][1]",
     "a polygon ring needs at least 4 positions, got 2"),
    ({"type": "MultiPolygon", "coordinates": [[SQUARE], 5]}, "coordinates[1]",
     "expected an array, got number 5"),
    ({"type": "GeometryCollection"}, "", 'GeometryCollection has no "geometries" member'),
    ({"type": "GeometryCollection", "geometries": None}, "geometries",
     "expected an array, got null"),
    ({"type": "GeometryCollection", "geometries": [line([0, 0], [1, 1]), "x"]},
     "geometries[1]", "expected a geometry object, got string 'x'"),
    ({"type": "GeometryCollection", "geometries": [
        {"type": "GeometryCollection", "geometries": [line([0, 0], [1, 1]),
                                                      line([0, 0], [1, False])]}]},
     "geometries[0].geometries[1].coordinates[1][1]", "expected a number, got boolean False"),
])
def test_invalid_geojson_names_the_path_of_the_problem(doc, path, reason):
    found, message = error_path(doc)
    assert found == path
    assert reason in message


def test_the_issue_example_path():
    polygons = [feature({"type": "Polygon", "coordinates": [copy.deepcopy(SQUARE)]})
                for _ in range(13)]
    polygons[12]["geometry"]["coordinates"][0][3][0] = float("nan")
    path, message = error_path(collection(*polygons))
    assert path == "features[12].geometry.coordinates[0][3][0]"
    assert "features[12].geometry.coordinates[0][3]" in message


def test_a_document_mixing_2d_and_3d_is_read_in_3d_with_nan_z_where_missing():
    doc = collection(feature(line([0, 0, 1], [1, 1, 1])),
                     feature({"type": "Point", "coordinates": [5, 5]}),
                     feature(line([0, 0, 2], [1, 1])))
    layout = from_geojson(doc)
    assert layout.has_z and layout.partial_z
    np.testing.assert_array_equal(layout.points[1], [[5, 5, np.nan]])
    np.testing.assert_array_equal(layout.lines[1],
                                  [[0, 0, 1], [1, 1, 1], [0, 0, 2], [1, 1, np.nan]])


@pytest.mark.parametrize("dim", [2, 3])
def test_a_document_of_one_dimension_is_not_partial(dim):
    position = [1.5, 2.5, 3.5][:dim]
    layout = from_geojson(feature({"type": "MultiPoint", "coordinates": [position] * 3}))
    assert layout.has_z == (dim == 3) and not layout.partial_z
    assert layout.points[1].shape == (3, dim)


@pytest.mark.parametrize("ends, closed", [
    (([0, 0, 1], [0, 0, 1]), True),
    (([0, 0], [0, 0]), True),
    (([0, 0, 1], [0, 0]), False),
    (([0, 0], [0, 0, 1]), False),
    (([0, 0, 1], [0, 0, 2]), False),
])
def test_a_ring_of_a_mixed_document_is_closed_only_by_ends_of_one_dimension(ends, closed):
    first, last = ends
    ring = [first, [4, 0, 5], [4, 4], last]
    doc = collection(feature({"type": "Polygon", "coordinates": [ring]}),
                     feature({"type": "Point", "coordinates": [1, 1, 1]}))
    if closed:
        rings = from_geojson(doc).polygons[1]
        np.testing.assert_array_equal(rings[0], rings[3])  # NaN equal to NaN here
        return
    path, message = error_path(doc)
    assert path == "features[0].geometry.coordinates[0]"
    assert "polygon ring is not closed" in message


def test_the_first_problem_in_document_order_is_reported():
    doc = collection(feature(line([0, 0], [1, 1])),
                     feature(line([0, 0], [1, float("nan")])),
                     {"type": "Feature"})
    assert error_path(doc)[0] == "features[1].geometry.coordinates[1][1]"
    doc = collection(feature(line([0, 0], [1, 1])), {"type": "Feature"},
                     feature(line([0, 0], [1, float("nan")])))
    assert error_path(doc)[0] == "features[1]"
    doc = collection(feature({"type": "Polygon", "coordinates": [SQUARE[:-1]]}),
                     feature(line([0, 0], [1, "1"])))
    assert error_path(doc)[0] == "features[0].geometry.coordinates[0]"


def nested_collections(levels, leaf):
    geometry = leaf
    for _ in range(levels):
        geometry = {"type": "GeometryCollection", "geometries": [geometry]}
    return geometry


def test_collections_nested_to_the_limit_are_read():
    doc = nested_collections(MAX_COLLECTION_DEPTH, line([0, 0], [1, 1]))
    assert from_geojson(doc).geometry_count("lines") == 1
    assert from_geojson(orjson.dumps(doc)).geometry_count("lines") == 1


def test_collections_nested_deeper_than_the_limit_are_refused():
    assert MAX_COLLECTION_DEPTH == 32
    doc = nested_collections(MAX_COLLECTION_DEPTH + 1, line([0, 0], [1, 1]))
    path, message = error_path(doc)
    assert path == ".".join(["geometries[0]"] * MAX_COLLECTION_DEPTH)
    assert "GeometryCollections nested more than 32 levels deep" in message


def test_very_deep_nesting_is_a_clear_error_not_a_recursion_error():
    doc = nested_collections(5000, line([0, 0], [1, 1]))
    with pytest.raises(InvalidGeometryError, match="nested more than 32 levels"):
        from_geojson(doc)
    text = b'{"type":"GeometryCollection","geometries":[' * 600 + b"]}" * 600
    with pytest.raises((InvalidGeometryError, ParseError)):
        from_geojson(text)


def test_self_containing_collection_is_refused():
    doc = {"type": "GeometryCollection", "geometries": []}
    doc["geometries"].append(doc)
    with pytest.raises(InvalidGeometryError, match="nested more than 32 levels"):
        from_geojson(doc)


def test_text_that_is_not_json_is_a_parse_error():
    with pytest.raises(ParseError, match="GeoJSON text is not valid JSON") as info:
        from_geojson(b'{"type": "Point", "coordinates": [1, 2]')
    assert info.value.position == 39
    assert isinstance(info.value, ValueError)


def test_nan_literal_in_text_is_a_parse_error():
    with pytest.raises(ParseError) as info:
        from_geojson('{"type": "Point", "coordinates": [NaN, 2]}')
    assert info.value.position == 34


def test_input_that_is_neither_dict_nor_text_is_refused():
    path, message = error_path(42)
    assert path == "" and "expected a GeoJSON object, got number 42" in message


def test_errors_are_value_errors():
    assert issubclass(InvalidGeometryError, ValueError)
    assert issubclass(ParseError, ValueError)


def test_max_vertices_refuses_a_huge_coordinate_array():
    n = 2_000_000
    huge = {"type": "LineString", "coordinates": [[float(i), 0.0] for i in range(n)]}
    with pytest.raises(LimitExceededError, match="2000000 positions, more than "
                                                 "max_vertices=1000000"):
        from_geojson(huge, max_vertices=1_000_000)


def test_max_vertices_counts_every_kind():
    doc = collection(feature(line([0, 0], [1, 1])), feature({"type": "Point",
                                                             "coordinates": [1, 1]}),
                     feature({"type": "Polygon", "coordinates": [TRIANGLE]}))
    assert from_geojson(doc, max_vertices=7).vertex_count == 7
    with pytest.raises(LimitExceededError):
        from_geojson(doc, max_vertices=6)


def test_max_vertices_is_checked_while_validating_a_slow_document():
    doc = {"type": "LineString", "coordinates": [[np.float64(i), 0] for i in range(10)]}
    with pytest.raises(LimitExceededError):
        from_geojson(doc, max_vertices=5)


@pytest.mark.parametrize("value", [-1, 1.5, True, "10"])
def test_max_vertices_must_be_a_non_negative_int(value):
    with pytest.raises(InvalidOptionError, match="max_vertices"):
        from_geojson({"type": "Point", "coordinates": [1, 2]}, max_vertices=value)


# --------------------------------------------------------------------------- large documents
# Large documents are read in bulk, a chunk of whole coordinate arrays at a time (see
# `_coordinates`, `read_positions`). The `small_chunks` fixture makes chunks end after the
# array holding position 4096, 8192, ..., so that the 100 lines of 100 positions of
# `make_lines` make three chunks (positions 0-4099, 4100-8199, 8200-9999), and these tests
# put every kind of value at places the bulk reader treats differently: first and last
# positions of chunks, of batches of 1000 and of the document.

LINES, LINE_LENGTH = 100, 100
PLACES = [0, 1, 999, 1000, 4099, 4100, 6543, 8200, LINES * LINE_LENGTH - 1]


@pytest.fixture
def small_chunks(monkeypatch):
    monkeypatch.setattr(geojson_module, "_CHUNK", 4096)


@pytest.fixture
def make_lines(small_chunks, rng):
    """Return a function of dim giving (document, coords): lines of random floats."""

    def make(dim=2):
        coords = rng.uniform(-1000, 1000, (LINES * LINE_LENGTH, dim))
        features = [feature(line(*coords[k * LINE_LENGTH:(k + 1) * LINE_LENGTH].tolist()))
                    for k in range(LINES)]
        return collection(*features), coords

    return make


def position_at(doc, index):
    """Return (the position list, the JSON path of position `index` of `make_lines`)."""
    k, i = divmod(index, LINE_LENGTH)
    path = f"features[{k}].geometry.coordinates[{i}]"
    return doc["features"][k]["geometry"]["coordinates"][i], path


def test_a_large_document_of_floats_is_read_exactly(make_lines):
    doc, coords = make_lines()
    layout = from_geojson(doc)
    np.testing.assert_array_equal(layout.lines[1], coords)
    assert layout.lines[2][0].tolist() == list(range(0, LINES * LINE_LENGTH + 1, LINE_LENGTH))
    np.testing.assert_array_equal(from_geojson(orjson.dumps(doc)).lines[1], coords)


def test_a_large_3d_document_is_read_exactly(make_lines):
    doc, coords = make_lines(3)
    layout = from_geojson(doc)
    assert layout.has_z
    np.testing.assert_array_equal(layout.lines[1], coords)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_large_document_of_every_kind_matches_shapely(small_chunks, rng, dim):
    polygons = [shapely.Polygon(rng.uniform(0, 1, (40, dim)) + k) for k in range(200)]
    points = shapely.points(rng.uniform(0, 100, (2000, dim)))
    lines = [shapely.LineString(rng.uniform(0, 100, (5000, dim)))]  # more than a chunk
    empty = [shapely.MultiPoint(), shapely.Polygon()]
    doc = collection(*(feature(mapping(g)) for g in [*polygons, *lines, *points, *empty]))
    doc = orjson.loads(orjson.dumps(doc))  # lists, as a parsed document has
    layout = from_geojson(doc)
    np.testing.assert_array_equal(layout.polygons[1],
                                  shapely.to_ragged_array(polygons, include_z=dim == 3)[1])
    z = dim == 3
    np.testing.assert_array_equal(layout.lines[1], shapely.get_coordinates(lines, include_z=z))
    np.testing.assert_array_equal(layout.points[1], shapely.get_coordinates(points, include_z=z))
    assert layout.geometry_count("points") == 2001 and layout.geometry_count("polygons") == 201


#: Ints of every size MessagePack writes differently: fixints, then 1, 2, 4 and 8 bytes,
#: signed and unsigned.
INTS = [0, 7, 127, 128, 255, 256, 65_535, 65_536, -1, -32, -33, -128, -129, -300, -32_769,
        2 ** 31 - 1, -(2 ** 31)]
BIG_INTS = [2 ** 31, 2 ** 32, -(2 ** 31) - 1, -(2 ** 40), 2 ** 47, 2 ** 53, 2 ** 63 - 1, 2 ** 63,
            2 ** 64 - 1, -(2 ** 63)]


@pytest.mark.parametrize("count", [1, 40, 2000])
@pytest.mark.parametrize("ints", [INTS, INTS + BIG_INTS])
def test_ints_among_floats_are_read_as_floats(make_lines, rng, count, ints):
    doc, coords = make_lines()
    for index in rng.choice(coords.shape[0], count, replace=False):
        position, _ = position_at(doc, index)
        axis = rng.integers(2)
        value = ints[rng.integers(len(ints))]
        position[axis] = value
        coords[index, axis] = value
    np.testing.assert_array_equal(from_geojson(doc).lines[1], coords)


def test_a_document_of_ints_only_is_read(small_chunks, rng):
    coords = rng.integers(-100_000, 100_000, (10_000, 3))
    layout = from_geojson(line(*coords.tolist()))
    np.testing.assert_array_equal(layout.lines[1], coords.astype(np.float64))


def test_floats_whose_bytes_look_like_type_tags_are_read(make_lines, rng):
    """Floats whose bytes read as array headers or numbers in MessagePack (or pickle)."""
    tricky = [struct.unpack(">d", bytes(b))[0] for b in (
        b"@](K\x01e](", b"@](G@](e", b"@](J\x00\x00\x00\x00", b"@e](M\x01\x02e",
        b"\x92\x01\x02\x92\x01\x02\x91\x01", b"\x91\xcb\x40\x00\x00\x00\x00\x00",
        b"\xdc\x00\x02\x92\xcb\xdd\x00\x00")]
    assert all(np.isfinite(tricky))
    doc, coords = make_lines()
    for n, index in enumerate(rng.choice(coords.shape[0], 1500, replace=False)):
        position, _ = position_at(doc, index)
        value = tricky[n % len(tricky)] if n % 3 else INTS[n % len(INTS)]
        position[n % 2] = value
        coords[index, n % 2] = value
    np.testing.assert_array_equal(from_geojson(doc).lines[1], coords)


@pytest.mark.parametrize("place", PLACES)
def test_a_string_whose_bytes_end_like_a_position_is_refused(make_lines, place):
    """A string may hold the bytes of a position, ending where its own record does.

    ``"](K\\x01K\\x02"`` holds the pickled bytes of the position [1, 2]; ``"\\x92\\x01\\x02"``
    (below) its MessagePack bytes: only reading the objects in sequence tells them apart.
    """
    for text in ("](K\x01K\x02", "\x92\x01\x02"):
        doc, _ = make_lines()
        position, path = position_at(doc, place)
        position[1] = text
        found, message = error_path(doc)
        assert found == f"{path}[1]"
        assert "expected a number, got string" in message


class Number:
    """Not a number type of ours; pickling it would run `__reduce_ex__`."""

    reduced = 0

    def __float__(self):
        return 1.5

    def __reduce_ex__(self, protocol):
        Number.reduced += 1
        return (float, (1.5,))


@pytest.mark.parametrize("value, reason", [
    (True, "expected a number, got boolean True"),
    (False, "expected a number, got boolean False"),
    (np.bool_(True), "expected a number, got boolean True"),
    (None, "expected a number, got null"),
    ("1.5", "expected a number, got string '1.5'"),
    ("1.25", "expected a number, got string '1.25'"),
    ("\x92\x01\x02", "expected a number, got string"),  # the MessagePack bytes of [1, 2]
    ([1.5], "expected a number, got an array of 1"),
    ({}, "expected a number, got an object"),
    (float("nan"), "expected a finite number, got nan"),
    (float("-inf"), "expected a finite number, got -inf"),
    (10 ** 400, "expected a finite number"),
    (Number(), "expected a number, got Number"),
])
@pytest.mark.parametrize("place", PLACES)
def test_a_bad_number_in_a_large_document_is_named(make_lines, value, reason, place):
    doc, _ = make_lines()
    position, path = position_at(doc, place)
    position[1] = value
    found, message = error_path(doc)
    assert found == f"{path}[1]"
    assert reason in message
    assert Number.reduced == 0


@pytest.mark.parametrize("value, path_end, reason", [
    ([1.5], "", "a position needs at least 2 numbers, got 1"),
    ("xy", "", "expected a position (an array of 2 or 3 numbers), got string 'xy'"),
    (5.0, "", "expected a position"),
])
@pytest.mark.parametrize("place", [PLACES[1], PLACES[4], PLACES[-1]])
def test_a_bad_position_in_a_large_document_is_named(make_lines, value, path_end, reason, place):
    doc, _ = make_lines()
    k, i = divmod(place, LINE_LENGTH)
    doc["features"][k]["geometry"]["coordinates"][i] = value
    found, message = error_path(doc)
    assert found == f"features[{k}].geometry.coordinates[{i}]{path_end}"
    assert reason in message


def test_a_position_holding_itself_is_refused(make_lines):
    doc, _ = make_lines()
    position, path = position_at(doc, PLACES[5])
    position[1] = position
    found, message = error_path(doc)
    assert found == f"{path}[1]"
    assert "expected a number, got an array of 2" in message


@pytest.mark.parametrize("value", [np.float64(2.5), np.float32(2.5), np.int64(-3),
                                   np.uint8(200)])
def test_numpy_scalars_in_a_large_document_are_numbers(make_lines, value):
    doc, coords = make_lines()
    for place in PLACES:
        position, _ = position_at(doc, place)
        position[0] = value
        coords[place, 0] = float(value)
    np.testing.assert_array_equal(from_geojson(doc).lines[1], coords)


class Position(list):
    """A list subclass: read like a list, but only by the slow validator."""


@pytest.mark.parametrize("dim", [2, 3])
def test_tuples_list_subclasses_and_long_positions_in_a_large_document(make_lines, dim):
    doc, coords = make_lines(dim)
    for n, place in enumerate(PLACES):
        position, _ = position_at(doc, place)
        k, i = divmod(place, LINE_LENGTH)
        kinds = (tuple(position), Position(position), [*position, 9.5, 8.5])
        doc["features"][k]["geometry"]["coordinates"][i] = kinds[n % (3 if dim == 3 else 2)]
    np.testing.assert_array_equal(from_geojson(doc).lines[1], coords)


class Tag(enum.Enum):
    """An enum member is not a number, whatever its value (ormsgpack would pack the value)."""

    HALF = 1.5


def test_bulk_reading_takes_lists_of_ints_and_floats_and_nothing_else():
    """What `_coordinates` takes, so that documents of such numbers stay fast, and which of
    its arrays it finds plain (lists of floats of the document's dimension)."""
    def read(*arrays):
        sizes = np.array([len(array) for array in arrays], dtype=np.int64)
        result = geojson_module._coordinates(list(arrays), sizes)
        if result is None:
            return None
        coords, plain, partial_z = result
        dim = coords.shape[1]
        expected = [[float(v) for v in p[:dim]] + [math.nan] * (dim - len(p))
                    for a in arrays for p in a]
        np.testing.assert_array_equal(coords, np.array(expected).reshape(-1, dim))
        assert partial_z == any(len(p) < dim for a in arrays for p in a)
        return plain.tolist()

    floats = [[0.5 + k, -1.5 * k] for k in range(2500)]
    assert read(floats) == [True] and read(floats[:1]) == [True]
    assert read([[*p, 3.25] for p in floats]) == [True]
    assert read([[*p, 3.25, 4.5] for p in floats]) == [False]  # numbers after z dropped
    assert read(floats, [[k, 1.5] for k in range(-70_000, 70_000, 7)]) == [True, False]
    assert read(floats, [[k, 0.5] for k in INTS + BIG_INTS], floats) == [True, False, True]
    assert read([[1.5, 2.5]], [(1.5, 2.5)]) == [False, False]  # tuples: the chunk is not plain
    assert read(floats, [[1.5, 2.5, 3.5]]) == [False, True]  # 2D then 3D: read again in 3D
    assert read([[1.5, 2.5, 3.5]], floats) == [True, False]  # 3D then 2D
    for value in (True, None, "1", np.float64(1.5), np.int64(1), 2 ** 64, -(2 ** 63) - 1,
                  float("nan"), float("inf"), [1], {}, Tag.HALF, b"12345678"):
        assert read([*floats[:1500], [1.5, value], *floats[1500:]]) is None, value
    assert read(floats[:10], [Position([1.5, 2.5])]) is None
    assert read(floats[:10], [[1.5]]) is None and read(floats[:10], [[]]) is None


NUMBER_REPLACEMENTS = [0, 255, 65_536, -7, 2 ** 40, 1.5, "1.25", None, True, np.float64(2.5),
                       np.int32(3), float("inf"), [], [1.5], Position([1.5])]
POSITION_REPLACEMENTS = [[1.5], [1.5, 2.5, 3.5], (1.5, 2.5), Position([1.5, 2.5]), "ab", None,
                         [0, 1], [True, 1.5]]


@pytest.mark.parametrize("dim", [2, 3])
def test_random_corruptions_of_a_large_document_are_judged_like_the_validator(
        make_lines, rng, dim):
    """The bulk reader accepts what the slow validator accepts, with the same numbers."""
    refused = 0
    for _ in range(25):
        doc, _ = make_lines(dim)
        for index in rng.choice(LINES * LINE_LENGTH, rng.integers(1, 4), replace=False):
            position, _ = position_at(doc, index)
            k, i = divmod(index, LINE_LENGTH)
            if rng.random() < 0.3:
                replacement = POSITION_REPLACEMENTS[rng.integers(len(POSITION_REPLACEMENTS))]
                doc["features"][k]["geometry"]["coordinates"][i] = copy.copy(replacement)
            else:
                replacement = NUMBER_REPLACEMENTS[rng.integers(len(NUMBER_REPLACEMENTS))]
                position[rng.integers(dim)] = copy.copy(replacement)
        validator = geojson_module._Validator(None)
        try:
            validator.document(doc)
        except InvalidGeometryError as expected:
            refused += 1
            assert error_path(doc)[0] == expected.path
            continue
        positions = [p for f in doc["features"] for p in f["geometry"]["coordinates"]]
        np.testing.assert_array_equal(
            from_geojson(doc).lines[1],
            geojson_module._checked_coordinates(positions, validator.dim))
    assert 0 < refused < 25


@pytest.mark.parametrize("first, rest", [(3, 2), (2, 3)])
def test_a_whole_chunk_of_another_dimension_is_read_with_nan_z_for_the_2d_positions(
        make_lines, first, rest):
    doc, coords = make_lines(first)
    _, others = make_lines(rest)
    for k in range(41, LINES):  # the second and third chunks
        doc["features"][k] = feature(line(*others[k * LINE_LENGTH:(k + 1) * LINE_LENGTH]
                                          .tolist()))
    expected = np.full((LINES * LINE_LENGTH, 3), np.nan)
    expected[:41 * LINE_LENGTH, :first] = coords[:41 * LINE_LENGTH]
    expected[41 * LINE_LENGTH:, :rest] = others[41 * LINE_LENGTH:]
    layout = from_geojson(doc)
    assert layout.partial_z
    np.testing.assert_array_equal(layout.lines[1], expected)


@pytest.mark.parametrize("place", PLACES)
@pytest.mark.parametrize("dim", [2, 3])
def test_one_position_of_the_other_dimension_anywhere_in_a_large_document_is_read(
        make_lines, place, dim):
    """A 3D position late in a 2D document makes the reader read again in 3D; a 2D one in
    a 3D document gets Z NaN in one pass. The slow validator reads the same."""
    doc, coords = make_lines(dim)
    position, _ = position_at(doc, place)
    expected = np.full((coords.shape[0], 3), np.nan)
    expected[:, :dim] = coords
    if dim == 2:
        position.append(7.25)
        expected[place, 2] = 7.25
    else:
        del position[2]
        expected[place, 2] = np.nan
    layout = from_geojson(doc)
    assert layout.has_z and layout.partial_z
    np.testing.assert_array_equal(layout.lines[1], expected)
    validator = geojson_module._Validator(None)
    validator.document(doc)
    assert validator.dim == 3 and validator.partial_z
    positions = [p for f in doc["features"] for p in f["geometry"]["coordinates"]]
    np.testing.assert_array_equal(geojson_module._checked_coordinates(positions, 3), expected)


# --------------------------------------------------------------------------- writing

RICH = collection(
    {"type": "Feature", "id": 1, "properties": {"name": "square", "tags": [1, 2]},
     "bbox": [0.0, 0.0, 10.0, 10.0], "title": "foreign member",
     "geometry": {"type": "Polygon", "coordinates": [SQUARE, HOLE]}},
    {"type": "Feature", "id": "b", "properties": {},
     "geometry": {"type": "MultiPolygon", "coordinates": [[SQUARE], [TRIANGLE]],
                  "bbox": [0.0, 0.0, 30.0, 30.0]}},
    feature({"type": "Point", "coordinates": [1.5, 2.5]}),
    feature({"type": "MultiPoint", "coordinates": [[1, 2], [3, 4]]}),
    feature({"type": "LineString", "coordinates": [[0, 0], [5, 5], [10, 0]]}),
    feature({"type": "MultiLineString", "coordinates": [[[0, 0], [1, 1]], [[2, 2], [3, 3]]]}),
    feature({"type": "GeometryCollection", "geometries": [
        {"type": "Point", "coordinates": [0, 0]},
        {"type": "GeometryCollection", "geometries": [
            {"type": "LineString", "coordinates": [[0, 0], [1, 0]]}]}]}),
    bbox=[0.0, 0.0, 30.0, 30.0], name="layer",
)


def test_round_trip_gives_an_equal_document():
    assert to_geojson(from_geojson(RICH)) == RICH
    assert to_geojson(from_geojson(orjson.dumps(RICH))) == RICH


def test_round_trip_of_every_root_kind():
    for root in (RICH["features"][0], RICH["features"][0]["geometry"],
                 RICH["features"][6]["geometry"], {"type": "Point", "coordinates": []}):
        assert to_geojson(from_geojson(root)) == root


def test_round_trip_keeps_z():
    doc = feature({"type": "Polygon", "coordinates": [[[0, 0, 1], [1, 0, 2], [1, 1, 3],
                                                       [0, 0, 1]]]}, bbox=[0, 0, 1, 1, 1, 3])
    assert to_geojson(from_geojson(doc)) == doc


def test_round_trip_keeps_null_and_empty_geometries_with_keep_empty():
    doc = collection(feature(None, id=1), feature({"type": "LineString", "coordinates": []}),
                     feature({"type": "GeometryCollection", "geometries": []}))
    assert to_geojson(from_geojson(doc), keep_empty=True) == doc
    assert to_geojson(from_geojson(doc)) == collection()


def test_output_shares_members_but_not_the_containers_it_rewrote():
    out = to_geojson(from_geojson(RICH))
    assert out["features"][0]["properties"] is RICH["features"][0]["properties"]
    assert out["features"] is not RICH["features"]
    assert out["features"][0]["geometry"] is not RICH["features"][0]["geometry"]


def test_numbers_are_written_as_floats_and_member_order_is_kept():
    doc = {"coordinates": [1, 2], "type": "Point", "extra": True}
    out = to_geojson(from_geojson(doc))
    assert list(out) == ["coordinates", "type", "extra"]
    assert [type(v) for v in out["coordinates"]] == [float, float]


def multi(kind, coords, *offsets, dim=2):
    return (kind, np.asarray(coords, dtype=np.float64).reshape(-1, dim),
            tuple(np.asarray(o, dtype=np.int64) for o in offsets))


def test_linestring_holding_two_parts_becomes_multilinestring():
    layout = from_geojson(feature(line([0, 0], [10, 0], [10, 10], [0, 10])))
    lines = multi("MultiLineString", [[0, 0], [5, 0], [5, 10], [0, 10]], [0, 2, 4], [0, 2])
    out = to_geojson(layout, lines=lines)
    assert out["geometry"] == {"type": "MultiLineString",
                               "coordinates": [[[0, 0], [5, 0]], [[5, 10], [0, 10]]]}


def test_polygon_holding_two_polygons_becomes_multipolygon_and_one_stays_polygon():
    layout = from_geojson(collection(feature({"type": "Polygon", "coordinates": [SQUARE]}),
                                     feature({"type": "Polygon", "coordinates": [SQUARE]})))
    a = [[0, 0], [1, 0], [1, 1], [0, 0]]
    b = [[5, 5], [6, 5], [6, 6], [5, 5]]
    polygons = multi("MULTIPOLYGON", a + b + a, [0, 4, 8, 12], [0, 1, 2, 3], [0, 2, 3])
    out = to_geojson(layout, polygons=polygons)
    assert [f["geometry"] for f in out["features"]] == [
        {"type": "MultiPolygon", "coordinates": [[a], [b]]},
        {"type": "Polygon", "coordinates": [a]},
    ]


def test_multi_types_stay_multi_with_one_part():
    layout = from_geojson(collection(
        feature({"type": "MultiPoint", "coordinates": [[0, 0], [1, 1]]}),
        feature({"type": "MultiLineString", "coordinates": [[[0, 0], [1, 1]],
                                                            [[2, 2], [3, 3]]]})))
    out = to_geojson(layout, points=multi("MultiPoint", [[1, 1]], [0, 1]),
                     lines=multi("MultiLineString", [[2, 2], [3, 3]], [0, 2], [0, 1]))
    assert [f["geometry"] for f in out["features"]] == [
        {"type": "MultiPoint", "coordinates": [[1, 1]]},
        {"type": "MultiLineString", "coordinates": [[[2, 2], [3, 3]]]},
    ]


def emptied(layout):
    """Every geometry of the layout, empty."""
    out = {}
    for kind in ("points", "lines", "polygons"):
        geometry_type, coords, offsets = getattr(layout, kind)
        count = layout.geometry_count(kind)
        out[kind] = (geometry_type, coords[:0],
                     tuple(np.zeros(1 if i < len(offsets) - 1 else count + 1, np.int64)
                           for i in range(len(offsets))))
    return out


def test_empty_features_are_dropped_and_their_bbox_too():
    layout = from_geojson(RICH)
    out = to_geojson(layout, **emptied(layout))
    assert out == {"type": "FeatureCollection", "features": [], "name": "layer"}


def test_keep_empty_writes_empty_coordinates_of_the_input_type():
    layout = from_geojson(RICH)
    out = to_geojson(layout, **emptied(layout), keep_empty=True)
    assert "bbox" not in out and len(out["features"]) == 7
    first = out["features"][0]
    assert first == {"type": "Feature", "id": 1, "properties": RICH["features"][0]["properties"],
                     "title": "foreign member",
                     "geometry": {"type": "Polygon", "coordinates": []}}
    assert out["features"][1]["geometry"] == {"type": "MultiPolygon", "coordinates": []}
    assert out["features"][6]["geometry"] == {"type": "GeometryCollection", "geometries": [
        {"type": "Point", "coordinates": []},
        {"type": "GeometryCollection", "geometries": [
            {"type": "LineString", "coordinates": []}]}]}


def test_empty_collection_members_are_dropped_and_an_empty_collection_too():
    doc = collection(
        feature({"type": "GeometryCollection", "geometries": [
            {"type": "Point", "coordinates": [0, 0]}, line([0, 0], [1, 1])]}),
        feature({"type": "GeometryCollection", "geometries": [
            {"type": "Point", "coordinates": [5, 5]}]}))
    layout = from_geojson(doc)
    points = multi("MultiPoint", [[0, 0]], [0, 1, 1])
    lines = multi("MultiLineString", [], [0], [0, 0])
    out = to_geojson(layout, points=points, lines=lines)
    assert out["features"] == [feature({"type": "GeometryCollection", "geometries": [
        {"type": "Point", "coordinates": [0, 0]}]})]


def test_the_top_level_object_is_never_dropped():
    for root in ({"type": "LineString", "coordinates": [[0, 0], [1, 1]]},
                 feature({"type": "LineString", "coordinates": [[0, 0], [1, 1]]}, id=3)):
        layout = from_geojson(root)
        out = to_geojson(layout, **emptied(layout))
        empty_line = {"type": "LineString", "coordinates": []}
        assert out == (empty_line if root["type"] != "Feature" else
                       feature(empty_line, id=3))
    doc = {"type": "GeometryCollection", "geometries": [{"type": "Point", "coordinates": [0, 0]}]}
    layout = from_geojson(doc)
    assert to_geojson(layout, **emptied(layout)) == {"type": "GeometryCollection",
                                                     "geometries": []}


def test_bbox_is_recomputed_where_the_input_had_one():
    doc = collection(
        feature(line([0, 0], [4, 2]), bbox=[9, 9, 9, 9]),
        feature({"type": "GeometryCollection", "bbox": [0, 0, 0, 0], "geometries": [
            {"type": "Point", "coordinates": [-1, 7], "bbox": [1, 1, 1, 1]},
            line([3, 3], [5, -2])]}),
        feature(line([100, 100], [200, 200])),
        bbox=[1, 2, 3, 4])
    out = to_geojson(from_geojson(doc))
    assert out["features"][0]["bbox"] == [0.0, 0.0, 4.0, 2.0]
    collection_geometry = out["features"][1]["geometry"]
    assert collection_geometry["bbox"] == [-1.0, -2.0, 5.0, 7.0]
    assert collection_geometry["geometries"][0]["bbox"] == [-1.0, 7.0, -1.0, 7.0]
    assert "bbox" not in out["features"][2]
    assert out["bbox"] == [-1.0, -2.0, 200.0, 200.0]


def test_bbox_of_kept_features_only():
    doc = collection(feature(line([0, 0], [4, 2])), feature(line([10, 10], [20, 20])),
                     bbox=[0, 0, 20, 20])
    layout = from_geojson(doc)
    lines = multi("MultiLineString", [[1, 1], [2, 2]], [0, 2], [0, 1, 1])
    out = to_geojson(layout, lines=lines)
    assert out["bbox"] == [1.0, 1.0, 2.0, 2.0] and len(out["features"]) == 1


def test_bbox_has_six_numbers_only_if_the_input_bbox_had_six_and_the_data_is_3d():
    six = feature(line([0, 0, 5], [1, 2, 3]), bbox=[0, 0, 0, 0, 0, 0])
    four = feature(line([0, 0, 5], [1, 2, 3]), bbox=[0, 0, 0, 0])
    assert to_geojson(from_geojson(six))["bbox"] == [0.0, 0.0, 3.0, 1.0, 2.0, 5.0]
    assert to_geojson(from_geojson(four))["bbox"] == [0.0, 0.0, 1.0, 2.0]
    flat = feature(line([0, 0], [1, 2]), bbox=[0, 0, 0, 0, 0, 0])
    assert to_geojson(from_geojson(flat))["bbox"] == [0.0, 0.0, 1.0, 2.0]


def test_arrays_output_holds_views_and_serializes_like_lists():
    layout = from_geojson(RICH)
    fast = to_geojson(layout, arrays=True)
    polygon = fast["features"][0]["geometry"]["coordinates"]
    assert isinstance(polygon[0], np.ndarray) and polygon[0].shape == (5, 2)
    assert isinstance(fast["features"][2]["geometry"]["coordinates"], np.ndarray)
    assert dumps(fast) == orjson.dumps(to_geojson(layout))
    assert loads(dumps(fast)) == RICH


def test_arrays_output_of_a_large_document_equals_list_output():
    rng = np.random.default_rng(7)
    features = [feature(line(*rng.uniform(0, 100, (50, 2)).tolist())) for _ in range(3000)]
    layout = from_geojson(collection(*features))
    assert loads(dumps(to_geojson(layout, arrays=True))) == to_geojson(layout)


@pytest.mark.parametrize("enabled", [True, False])
def test_writing_leaves_the_garbage_collector_as_it_was(enabled):
    layout = from_geojson(line(*[[float(i), 0.0] for i in range(1000)]))
    was = gc.isenabled()
    try:
        (gc.enable if enabled else gc.disable)()
        out = to_geojson(layout)
        assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()
    assert len(out["coordinates"]) == 1000


def _collections_while(call):
    """Return how many garbage collections start during `call()` (threshold 1)."""
    collections = []

    def record(phase, info):
        if phase == "start":
            collections.append(info["generation"])

    threshold, was = gc.get_threshold(), gc.isenabled()
    gc.enable()
    gc.set_threshold(1)  # each container allocated starts a collection
    gc.callbacks.append(record)
    try:
        call()
    finally:
        gc.callbacks.remove(record)
        gc.set_threshold(*threshold)
        (gc.enable if was else gc.disable)()
    return len(collections)


def test_writing_leaves_the_collector_to_the_application():
    # The collector is process-wide: the library neither pauses nor resumes it. An
    # application that owns its process pauses it around a large write (rnsca.runtime).
    layout = from_geojson(line(*[[float(i), 0.0] for i in range(1000)]))
    assert _collections_while(lambda: to_geojson(layout)) > 30  # 1000 position lists
    gc.disable()
    try:
        to_geojson(layout)
        assert not gc.isenabled()
    finally:
        gc.enable()

    def paused():
        with collector_paused():
            to_geojson(layout)

    # A few from the setup before the pause, none per position written.
    assert _collections_while(paused) < 10


def test_arrays_of_the_wrong_type_or_count_are_refused():
    layout = from_geojson(collection(feature(line([0, 0], [1, 1]))))
    with pytest.raises(InvalidGeometryError, match="lines must be MULTILINESTRING"):
        to_geojson(layout, lines=multi("MultiPoint", [[0, 0]], [0, 1]))
    with pytest.raises(InvalidGeometryError, match="lines holds 2 geometries, the layout 1"):
        to_geojson(layout, lines=multi("MultiLineString", [[0, 0], [1, 1]], [0, 2], [0, 1, 1]))
    with pytest.raises(InvalidGeometryError, match="triple"):
        to_geojson(layout, lines=(1, 2))


def test_offsets_that_do_not_fit_their_arrays_are_refused():
    layout = from_geojson(collection(feature(line([0, 0], [1, 1]))))
    for parts, geometries in (([0, 3], [0, 1]), ([1, 2], [0, 1]), ([0, 2], [0, 2]),
                              ([0, 2, 1, 2], [0, 3])):
        with pytest.raises(InvalidGeometryError, match=r"offsets\[\d\] must rise from 0"):
            to_geojson(layout, lines=multi("MultiLineString", [[0, 0], [1, 1]], parts,
                                           geometries))


# --------------------------------------------------------------------------- written back
# A geometry that the arrays given to `to_geojson` hold exactly as the layout does is
# written with the input's own coordinates member, if that member holds exactly what
# the writer would write: lists of floats of the document's dimension, no empty member.

FLOATS = collection(
    feature(line([0.5, 0.5], [1.5, 2.5])),
    feature({"type": "Polygon", "coordinates": [[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 0.0]]]}),
    feature({"type": "MultiPoint", "coordinates": [[1.5, 2.5], [3.5, 4.5]]}),
    feature({"type": "Point", "coordinates": [7.5, 8.5]}),
    feature({"type": "MultiLineString", "coordinates": [[[0.5, 0.5], [1.5, 2.5]],
                                                        [[5.5, 5.5], [6.5, 7.5]]]}),
)


def coordinates_of(doc):
    return [f["geometry"]["coordinates"] for f in doc["features"]]


def test_an_unchanged_document_is_written_with_its_own_coordinates():
    out = to_geojson(from_geojson(FLOATS))
    assert out == FLOATS
    assert all(a is b for a, b in zip(coordinates_of(out), coordinates_of(FLOATS), strict=True))
    arrays = to_geojson(from_geojson(FLOATS), arrays=True)
    assert not any(a is b for a, b in zip(coordinates_of(arrays), coordinates_of(FLOATS),
                                          strict=True))


def test_only_the_geometries_the_arrays_change_are_rewritten():
    layout = from_geojson(FLOATS)
    _, coords, (parts, geometries) = layout.lines
    moved = coords.copy()
    moved[1] = [1.5, 3.0]  # the second position of the first line
    out = to_geojson(layout, lines=multi("MultiLineString", moved, parts, geometries))
    first, *rest = coordinates_of(out)
    assert first == [[0.5, 0.5], [1.5, 3.0]] and first is not coordinates_of(FLOATS)[0]
    assert all(a is b for a, b in zip(rest, coordinates_of(FLOATS)[1:], strict=True))
    assert dumps(out) == dumps(to_geojson(layout, lines=multi(
        "MultiLineString", moved, parts, geometries), arrays=True))


def test_the_same_positions_in_other_parts_are_a_change():
    layout = from_geojson(FLOATS)
    _, coords, _ = layout.lines
    regrouped = multi("MultiLineString", coords, [0, 2, 3, 6], [0, 1, 3])  # parts 2, 1, 3
    out = to_geojson(layout, lines=regrouped)
    assert coordinates_of(out)[0] is coordinates_of(FLOATS)[0]
    assert coordinates_of(out)[4] == [[[0.5, 0.5]], [[1.5, 2.5], [5.5, 5.5], [6.5, 7.5]]]
    assert dumps(out) == dumps(to_geojson(layout, lines=regrouped, arrays=True))


@pytest.mark.parametrize("geometry, written, others_kept", [
    (line([0, 0], [1.5, 2.5]), [[0.0, 0.0], [1.5, 2.5]], True),  # ints become floats
    # Tuples become lists; MessagePack cannot tell them from lists, so the whole chunk
    # of arrays read with them is rewritten.
    (line((0.5, 0.5), (1.5, 2.5)), [[0.5, 0.5], [1.5, 2.5]], False),
    ({"type": "MultiLineString", "coordinates": [[], [[0.5, 0.5], [1.5, 2.5]]]},
     [[[0.5, 0.5], [1.5, 2.5]]], True),  # an empty member is left out
    ({"type": "MultiPolygon", "coordinates": [[[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0],
                                                [0.0, 0.0]]], []]},
     [[[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 0.0]]]], True),
])
def test_a_member_unlike_its_written_form_is_rewritten(geometry, written, others_kept):
    doc = collection(feature(geometry), *FLOATS["features"])
    out = to_geojson(from_geojson(doc))
    assert coordinates_of(out)[0] == written and coordinates_of(out)[0] is not \
        geometry["coordinates"]
    assert orjson.dumps(coordinates_of(out)[0]) == orjson.dumps(written)
    assert out["features"][1:] == FLOATS["features"]
    kept = [a is b for a, b in zip(coordinates_of(out)[1:], coordinates_of(FLOATS), strict=True)]
    assert kept == [others_kept] * len(kept)


def test_numbers_after_z_are_not_written_back():
    doc = collection(feature(line([0.5, 0.5, 1.5, 9.5], [1.5, 2.5, 3.5, 9.5])),
                     feature(line([0.5, 0.5, 1.5], [1.5, 2.5, 3.5])))
    out = to_geojson(from_geojson(doc))
    assert coordinates_of(out)[0] == [[0.5, 0.5, 1.5], [1.5, 2.5, 3.5]]
    assert coordinates_of(out)[1] is coordinates_of(doc)[1]


def test_a_document_read_by_the_validator_is_rewritten_whole():
    doc = collection(feature(line([np.float64(0.5), 0.5], [1.5, 2.5])), *FLOATS["features"])
    out = to_geojson(from_geojson(doc))
    assert from_geojson(doc).sources is None
    assert not any(a is b for a, b in zip(coordinates_of(out)[1:], coordinates_of(FLOATS),
                                          strict=True))
    assert out["features"][1:] == FLOATS["features"]


def test_same_geometries_compares_parts_and_coordinates():
    coords = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]])
    offsets = (np.array([0, 2, 4]), np.array([0, 1, 2]))
    regrouped = (np.array([0, 1, 4]), np.array([0, 1, 2]))
    assert same_geometries(coords, offsets, coords, offsets).tolist() == [True, True]
    assert same_geometries(coords, offsets, coords, regrouped).tolist() == [False, False]
    signed = coords.copy()
    signed[0] = -0.0
    moved = coords.copy()
    moved[3, 1] = 3.5
    assert same_geometries(coords, offsets, signed, offsets).tolist() == [True, True]
    assert same_geometries(coords, offsets, moved, offsets).tolist() == [True, False]
    # The second geometry is empty in the other arrays; the first keeps its part.
    emptied = (np.array([0, 2]), np.array([0, 1, 1]))
    assert same_geometries(coords, offsets, coords[:2], emptied).tolist() == [True, False]


def test_loads_and_dumps():
    assert loads(b'{"a": [1, 2.5]}') == {"a": [1, 2.5]}
    assert dumps({"a": np.array([[1.0, 2.0]])}) == b'{"a":[[1.0,2.0]]}'
    assert dumps({"a": 1}, indent=True) == b'{\n  "a": 1\n}'
    with pytest.raises(ParseError):
        loads("{")


def all_paths(value, path=()):
    """Yield the path of every value inside `value` (dict keys and list indices)."""
    yield path
    if isinstance(value, dict):
        for key, item in value.items():
            yield from all_paths(item, (*path, key))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from all_paths(item, (*path, i))


REPLACEMENTS = [None, True, 0, 1.5, float("nan"), "x", "Point", [], [1], [1, 2], [1, 2, 3],
                [[1, 2]], [[1, 2], [1, 2]], [[0, 0], [1, 0], [1, 1], [0, 0]], {},
                {"type": "Point"}, {"type": "Point", "coordinates": [1, 2]}, np.float64(3)]


def test_any_single_corruption_is_read_or_refused_with_our_error(rng):
    """The fast reader and the validator agree: no other exception, whatever breaks."""
    paths = list(all_paths(RICH))[1:]
    refused = 0
    for _ in range(600):
        doc = copy.deepcopy(RICH)
        path = paths[rng.integers(len(paths))]
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        parent[path[-1]] = copy.deepcopy(REPLACEMENTS[rng.integers(len(REPLACEMENTS))])
        try:
            layout = from_geojson(doc)
        except InvalidGeometryError as error:
            refused += 1
            assert isinstance(error.path, str)
            continue
        out = to_geojson(layout, keep_empty=True)
        assert out["type"] == "FeatureCollection"
    assert 0 < refused < 600
