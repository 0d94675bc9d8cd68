"""clip_geojson: GeoJSON documents clipped like shapely.intersection, document shape kept.

Shapely is the oracle. Geometries are compared by geometry, not by vertex list: the
discrete Hausdorff distance between ours and Shapely's result, and the length (lines) or
the area of the symmetric difference (polygons), within ``TOL`` times the window size.
Windows have non-round bounds, so no input vertex or edge lies on the window's edge and
Shapely's result has no lower-dimensional leftovers to discard (``same_dimension``
discards them anyway).
"""

import copy
import math

import numpy as np
import orjson
import pytest
import shapely
from shapely.geometry import mapping, shape

from rnsca import ClipStats, InvalidGeometryError, InvalidOptionError, InvalidWindowError
from rnsca.clip_geojson import clip_geojson, combine_stats
from rnsca.io.geojson import dumps, from_geojson
from rnsca.ragged import clip_ragged
from tests.cases import MIXED_DIMENSIONS, MIXED_DIMENSIONS_CLIPPED

TOL = 1e-9
WINDOW = (25.31, 30.17, 70.73, 80.91)
BOX = shapely.box(*WINDOW)
SIZE = max(WINDOW[2] - WINDOW[0], WINDOW[3] - WINDOW[1])


def feature(geometry, **members):
    return {"type": "Feature", "properties": members.pop("properties", {}),
            "geometry": geometry, **members}


def collection(*features, **members):
    return {"type": "FeatureCollection", "features": list(features), **members}


def same_dimension(geometry, dimension):
    """Return the parts of `geometry` (collections flattened) of the given dimension."""
    parts = []
    stack = [geometry]
    while stack:
        g = stack.pop()
        if g.is_empty:
            continue
        if shapely.get_type_id(g) in (4, 5, 6, 7):
            stack.extend(shapely.get_parts(g))
        elif shapely.get_dimensions(g) == dimension:
            parts.append(g)
    return shapely.union_all(parts) if dimension == 2 else shapely.GeometryCollection(parts)


def assert_matches_shapely(ours, original, window_box=BOX, size=SIZE):
    """Assert our GeoJSON geometry (or None) equals the clip Shapely computes."""
    source = shape(original)
    dimension = shapely.get_dimensions(source)
    expected = same_dimension(shapely.intersection(source, window_box), dimension)
    got = shape(ours) if ours is not None else shapely.GeometryCollection()
    if expected.is_empty:
        assert got.is_empty, got.wkt
        return
    assert not got.is_empty
    assert shapely.get_dimensions(got) == dimension
    assert shapely.hausdorff_distance(got, expected) <= TOL * size
    if dimension == 0:
        ours_points = sorted(map(tuple, shapely.get_coordinates(got).tolist()))
        assert ours_points == sorted(map(tuple, shapely.get_coordinates(expected).tolist()))
    elif dimension == 1:
        assert abs(got.length - expected.length) <= TOL * size
    else:
        assert shapely.is_valid(got), shapely.is_valid_reason(got)
        assert shapely.symmetric_difference(got, expected).area <= TOL * size * size
        assert abs(got.area - expected.area) <= TOL * size * size


def assert_rfc7946_orientation(geometry):
    """Shells counter-clockwise, holes clockwise, rings closed."""
    for polygon in shapely.get_parts(shape(geometry)):
        assert shapely.is_ccw(polygon.exterior)
        assert not any(shapely.is_ccw(ring) for ring in polygon.interiors)
    rings = (geometry["coordinates"] if geometry["type"] == "Polygon"
             else [r for p in geometry["coordinates"] for r in p])
    assert all(ring[0] == ring[-1] for ring in rings)


def random_walk(rng, n, start=None):
    start = rng.uniform(0, 100, 2) if start is None else start
    return np.cumsum(np.vstack([start, rng.normal(0, 4, (n - 1, 2))]), axis=0)


def star(rng, center, radius, n):
    angles = np.sort(rng.uniform(0, 2 * math.pi, n))
    radii = radius * rng.uniform(0.5, 1.0, n)
    ring = np.c_[center[0] + radii * np.cos(angles), center[1] + radii * np.sin(angles)]
    return np.vstack([ring, ring[:1]])


def star_with_hole(rng):
    center = rng.uniform(10, 90, 2)
    radius = rng.uniform(10, 40)
    hole = star(rng, center, radius * 0.3, 12)[::-1]
    return shapely.Polygon(star(rng, center, radius, 40), [hole])


# --------------------------------------------------------------------------- vs Shapely

def test_lines_match_shapely(rng):
    lines = [shapely.LineString(random_walk(rng, 200)) for _ in range(60)]
    lines += [shapely.MultiLineString([random_walk(rng, 30), random_walk(rng, 40)])
              for _ in range(20)]
    doc = collection(*(feature(mapping(g), id=i) for i, g in enumerate(lines)))
    out, stats = clip_geojson(doc, WINDOW, keep_empty=True)
    assert len(out["features"]) == len(lines)
    for original, clipped in zip(doc["features"], out["features"], strict=True):
        assert clipped["id"] == original["id"]
        geometry = clipped["geometry"]
        assert_matches_shapely(geometry if geometry["coordinates"] else None,
                               original["geometry"])
    assert stats.geometries_in == 80
    assert stats.vertices_in == 60 * 200 + 20 * 70


def test_polygons_with_holes_match_shapely(rng):
    polygons = [star_with_hole(rng) for _ in range(60)]
    polygons += [shapely.MultiPolygon([star_with_hole(rng)]) for _ in range(10)]
    assert shapely.is_valid(polygons).all()
    doc = collection(*(feature(mapping(g), id=i) for i, g in enumerate(polygons)))
    out, stats = clip_geojson(doc, WINDOW)
    kept = {f["id"]: f["geometry"] for f in out["features"]}
    assert 0 < len(kept) < len(polygons)
    for i, original in enumerate(doc["features"]):
        assert_matches_shapely(kept.get(i), original["geometry"])
        if i in kept:
            assert_rfc7946_orientation(kept[i])
    assert stats.geometries_in == 70 and stats.invalid_polygons == 0


def test_comb_polygon_splits_into_a_multipolygon_like_shapely():
    # Five teeth x in [10i, 10i + 5], y in [10, 100], on a base y in [0, 10].
    ring = [[0, 0], [45, 0], [45, 100], [40, 100], [40, 10], [35, 10], [35, 100], [30, 100],
            [30, 10], [25, 10], [25, 100], [20, 100], [20, 10], [15, 10], [15, 100],
            [10, 100], [10, 10], [5, 10], [5, 100], [0, 100], [0, 0]]
    comb = shapely.Polygon(ring)
    assert comb.is_valid and shapely.is_ccw(comb.exterior)
    geometry = mapping(comb)
    window = (-1.3, 50.7, 60.9, 90.1)
    out, _ = clip_geojson(feature(geometry), window)
    assert out["geometry"]["type"] == "MultiPolygon"
    assert len(out["geometry"]["coordinates"]) == 5
    assert_matches_shapely(out["geometry"], geometry, shapely.box(*window), 62.2)
    assert_rfc7946_orientation(out["geometry"])


def test_points_match_shapely(rng):
    coords = rng.uniform(0, 100, (40, 2))
    doc = collection(feature({"type": "MultiPoint", "coordinates": coords.tolist()}),
                     *(feature({"type": "Point", "coordinates": c}) for c in coords.tolist()))
    out, stats = clip_geojson(doc, WINDOW, keep_empty=True)
    for original, clipped in zip(doc["features"], out["features"], strict=True):
        geometry = clipped["geometry"]
        assert_matches_shapely(geometry if geometry["coordinates"] else None,
                               original["geometry"])
    inside = sum(BOX.contains(shapely.Point(c)) for c in coords)
    assert stats.geometries_in == 41 and stats.geometries_out == 1 + inside


def test_mixed_collection_matches_shapely_member_by_member(rng):
    members = [shapely.LineString(random_walk(rng, 50, start=np.array([48.0, 55.0]))),
               star_with_hole(rng), shapely.Point(50, 50), shapely.Point(0, 0),
               shapely.MultiPoint([(30, 40), (1, 1)])]
    doc = {"type": "GeometryCollection", "geometries": [mapping(g) for g in members]}
    out, _ = clip_geojson(doc, WINDOW, keep_empty=True)
    assert len(out["geometries"]) == len(members)
    for original, clipped in zip(doc["geometries"], out["geometries"], strict=True):
        assert_matches_shapely(clipped if clipped["coordinates"] else None, original)


@pytest.mark.parametrize("boundary, expected", [
    ("closed", [[0.0, 5.0], [5.0, 5.0]]),
    ("interior", [[5.0, 5.0]]),
])
def test_boundary_option_is_passed_to_the_clip(boundary, expected):
    doc = {"type": "MultiPoint", "coordinates": [[0, 5], [5, 5], [20, 5]]}
    out, _ = clip_geojson(doc, (0, 0, 10, 10), boundary=boundary)
    assert out == {"type": "MultiPoint", "coordinates": expected}


# --------------------------------------------------------------------------- document

def test_linestring_leaving_and_reentering_becomes_multilinestring():
    doc = feature({"type": "LineString",
                   "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5], [15, 5]]})
    out, _ = clip_geojson(doc, (0, 0, 10, 10))
    assert out["geometry"] == {"type": "MultiLineString", "coordinates": [
        [[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]}


def test_single_part_stays_single():
    line = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
    polygon = {"type": "Polygon", "coordinates": [[[-5, -5], [15, -5], [15, 5], [-5, 5],
                                                   [-5, -5]]]}
    out, _ = clip_geojson(collection(feature(line), feature(polygon)), (0, 0, 10, 10))
    assert out["features"][0]["geometry"] == {"type": "LineString",
                                              "coordinates": [[0.0, 5.0], [10.0, 5.0]]}
    geometry = out["features"][1]["geometry"]
    assert geometry["type"] == "Polygon"
    assert shape(geometry).normalize().equals_exact(
        shapely.box(0, 0, 10, 5).normalize(), 0)


def test_point_outside_is_dropped_and_kept_empty_on_request():
    doc = collection(feature({"type": "Point", "coordinates": [50, 50]}, id="out"),
                     feature({"type": "Point", "coordinates": [5, 5]}, id="in"))
    out, _ = clip_geojson(doc, (0, 0, 10, 10))
    assert out["features"] == [feature({"type": "Point", "coordinates": [5.0, 5.0]}, id="in")]
    out, _ = clip_geojson(doc, (0, 0, 10, 10), keep_empty=True)
    assert out["features"][0] == feature({"type": "Point", "coordinates": []}, id="out")


def test_multipoint_with_one_point_left_stays_multipoint():
    out, _ = clip_geojson({"type": "MultiPoint", "coordinates": [[1, 1], [50, 50]]},
                          (0, 0, 10, 10))
    assert out == {"type": "MultiPoint", "coordinates": [[1.0, 1.0]]}


def test_properties_id_and_foreign_members_are_kept_and_bbox_recomputed():
    doc = collection(
        {"type": "Feature", "id": 17, "properties": {"name": "road", "lanes": 2},
         "bbox": [-5, 5, 15, 5], "source": {"survey": 1999},
         "geometry": {"type": "LineString", "coordinates": [[-5, 5], [15, 5]],
                      "bbox": [-5, 5, 15, 5], "style": "dashed"}},
        feature({"type": "LineString", "coordinates": [[50, 50], [60, 60]]}, id=18),
        bbox=[-5, 5, 60, 60], crs_note="foreign")
    out, _ = clip_geojson(doc, (0, 0, 10, 10))
    assert out == {
        "type": "FeatureCollection", "bbox": [0.0, 5.0, 10.0, 5.0], "crs_note": "foreign",
        "features": [{
            "type": "Feature", "id": 17, "properties": {"name": "road", "lanes": 2},
            "bbox": [0.0, 5.0, 10.0, 5.0], "source": {"survey": 1999},
            "geometry": {"type": "LineString", "coordinates": [[0.0, 5.0], [10.0, 5.0]],
                         "bbox": [0.0, 5.0, 10.0, 5.0], "style": "dashed"}}]}


def test_null_geometry_features_follow_keep_empty():
    doc = collection(feature(None, id=1))
    assert clip_geojson(doc, (0, 0, 1, 1))[0]["features"] == []
    assert clip_geojson(doc, (0, 0, 1, 1), keep_empty=True)[0] == doc


def test_collection_members_left_empty_are_dropped():
    doc = feature({"type": "GeometryCollection", "geometries": [
        {"type": "Point", "coordinates": [50, 50]},
        {"type": "LineString", "coordinates": [[1, 1], [2, 2]]}]})
    out, _ = clip_geojson(collection(doc), (0, 0, 10, 10))
    assert out["features"][0]["geometry"] == {"type": "GeometryCollection", "geometries": [
        {"type": "LineString", "coordinates": [[1.0, 1.0], [2.0, 2.0]]}]}


def test_z_is_kept_on_vertices_and_interpolated_on_new_ones():
    doc = {"type": "LineString", "coordinates": [[-10, 1, 0], [0, 1, 7], [10, 1, 20]]}
    out, _ = clip_geojson(doc, (-5, 0, 5, 5))
    assert out == {"type": "LineString",
                   "coordinates": [[-5.0, 1.0, 3.5], [0.0, 1.0, 7.0], [5.0, 1.0, 13.5]]}


def test_json_text_in_gives_the_same_result():
    doc = collection(feature({"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}))
    assert clip_geojson(orjson.dumps(doc), (0, 0, 10, 10))[0] == \
        clip_geojson(doc, (0, 0, 10, 10))[0]


def test_arrays_output_serializes_like_list_output(rng):
    doc = collection(*(feature(mapping(star_with_hole(rng))) for _ in range(20)))
    listed, _ = clip_geojson(doc, WINDOW)
    fast, _ = clip_geojson(doc, WINDOW, arrays=True)
    assert dumps(fast) == orjson.dumps(listed)


@pytest.mark.parametrize("window", [WINDOW, (-1e3, -1e3, 1e3, 1e3), (40.1, 40.2, 60.3, 60.4)])
def test_list_output_of_a_parsed_document_serializes_like_array_output(rng, window):
    """Geometries the clip leaves unchanged keep the input's lists: the same output."""
    shapes = [star_with_hole(rng) for _ in range(30)]
    shapes += [shapely.LineString(random_walk(rng, 40)) for _ in range(30)]
    shapes += [shapely.MultiPoint(rng.uniform(0, 100, (5, 2))) for _ in range(10)]
    shapes += [shapely.Polygon(star(rng, rng.uniform(30, 60, 2), 5, 12)[::-1])]  # clockwise
    doc = orjson.loads(orjson.dumps(collection(*(feature(mapping(g)) for g in shapes))))
    listed, _ = clip_geojson(doc, window)
    fast, _ = clip_geojson(doc, window, arrays=True)
    assert dumps(fast) == orjson.dumps(listed)
    kept = {id(f["geometry"]["coordinates"]) for f in doc["features"]}
    shared = [id(f["geometry"]["coordinates"]) in kept for f in listed["features"]]
    inside = [shapely.contains_properly(shapely.box(*window), g) for g in shapes]
    # Only what lies inside can be unchanged; the clockwise star is turned around.
    assert sum(shared) <= sum(inside) - inside[-1]
    if window[0] < -100:
        assert sum(shared) == len(shapes) - 1
    for out in listed["features"]:
        if out["geometry"]["type"].endswith("Polygon"):
            assert_rfc7946_orientation(out["geometry"])


def test_an_unchanged_feature_keeps_the_input_coordinates():
    inside = {"type": "LineString", "coordinates": [[30.5, 40.5], [50.5, 60.5]]}
    cut = {"type": "LineString", "coordinates": [[0.5, 40.5], [50.5, 60.5]]}
    doc = collection(feature(inside), feature(cut))
    out, _ = clip_geojson(doc, WINDOW)
    first, second = (f["geometry"]["coordinates"] for f in out["features"])
    assert first is inside["coordinates"]
    assert second is not cut["coordinates"] and second[1] == [50.5, 60.5]


def test_empty_document_gives_zero_stats():
    out, stats = clip_geojson(collection(), (0, 0, 1, 1))
    assert out == collection()
    assert stats.geometries_in == 0 and stats.vertices_in == 0
    assert sum(stats.decided_per_level) == 0


def test_stats_are_the_sum_of_the_three_clips():
    doc = collection(
        feature({"type": "MultiPoint", "coordinates": [[1, 1], [20, 20]]}),
        feature({"type": "LineString", "coordinates": [[-5, 5], [15, 5], [15, 8], [5, 8]]}),
        feature({"type": "Polygon", "coordinates": [[[-5, -5], [5, -5], [5, 5], [-5, -5]]]}))
    _, stats = clip_geojson(doc, (0, 0, 10, 10))
    layout = from_geojson(doc)
    parts = [clip_ragged(*getattr(layout, kind), (0, 0, 10, 10), keep_empty=True).stats
             for kind in ("points", "lines", "polygons")]
    assert stats == combine_stats(parts)
    assert stats.geometries_in == 3 and stats.geometries_out == 3
    assert stats.vertices_in == 2 + 4 + 4
    assert stats.segments_in == parts[1].segments_in + parts[2].segments_in > 0


def test_combine_stats_adds_counters_and_takes_the_deepest_levels():
    a = ClipStats(3, 1, 4, 1, 1, 1, 1, 0, 2, 2, (1, 2, 0), geometries_in=2,
                  runs_deepest_level=1, runs_decided_per_level=(1, 0, 0))
    b = ClipStats(1, 1, 1, 1, 0, 0, 0, 0, 0, 0, (1, 0, 0), geometries_in=5,
                  runs_deepest_level=3, runs_decided_per_level=(2, 0, 1))
    c = combine_stats([a, b])
    assert (c.segments_in, c.pieces_out, c.fragments_evaluated, c.accepted) == (4, 2, 5, 2)
    assert c.decided_per_level == (2, 2, 0) and c.runs_decided_per_level == (3, 0, 1)
    assert (c.deepest_level, c.runs_deepest_level, c.geometries_in) == (2, 3, 7)
    assert combine_stats([a]) is a


# --------------------------------------------------------------------------- errors

def test_invalid_geojson_is_refused_before_clipping():
    doc = collection(feature({"type": "LineString", "coordinates": [[0, 0], [1, "x"]]}))
    with pytest.raises(InvalidGeometryError,
                       match=r"features\[0\]\.geometry\.coordinates\[1\]\[1\]"):
        clip_geojson(doc, (0, 0, 1, 1))


@pytest.mark.parametrize("window", [(0, 0, 0, 1), (0, 0, 1), [[0, 0, 1, 1]] * 4,
                                    (0, 0, math.inf, 1)])
def test_a_bad_window_is_refused(window):
    with pytest.raises(InvalidWindowError):
        clip_geojson({"type": "Point", "coordinates": [0, 0]}, window)


def test_bad_options_are_refused_even_for_an_empty_document():
    with pytest.raises(InvalidOptionError):
        clip_geojson(collection(), (0, 0, 1, 1), boundary="outside")
    with pytest.raises(InvalidOptionError):
        clip_geojson({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]},
                     (0, 0, 1, 1), mode="approx")


# --- where each output came from -------------------------------------------------------------

def test_result_unpacks_as_document_and_stats_and_names_each_features_source():
    far = {"type": "Point", "coordinates": [0.0, 0.0]}
    inside = {"type": "Point", "coordinates": [50.0, 50.0]}
    doc = collection(feature(far, id="a"), feature(None, id="b"), feature(inside, id="c"),
                     feature(far, id="d"), feature(inside, id="e"))
    result = clip_geojson(doc, WINDOW)
    out, stats = result
    assert out is result.document and stats is result.stats and result[0] is out
    assert [f["id"] for f in out["features"]] == ["c", "e"]
    assert result.feature_source.tolist() == [2, 4]
    kept = clip_geojson(doc, WINDOW, keep_empty=True)
    assert kept.feature_source.tolist() == [0, 1, 2, 3, 4]
    assert clip_geojson(feature(far), WINDOW).feature_source.tolist() == [0]


def test_result_holds_each_kinds_inputs_and_their_clips_one_for_one():
    doc = collection(feature({"type": "LineString", "coordinates": [[0, 50], [100, 50]]}),
                     feature({"type": "Point", "coordinates": [0.0, 0.0]}),
                     feature({"type": "LineString", "coordinates": [[0, 0], [1, 1]]}))
    result = clip_geojson(doc, WINDOW)
    assert set(result.inputs) == set(result.outputs) == {"points", "lines"}
    lines = result.outputs["lines"]
    assert lines.source.tolist() == [0, 1]  # one output per input, empty ones kept
    expected = shapely.intersection(shapely.from_ragged_array(*result.inputs["lines"]), BOX)
    got = lines.to_shapely()
    assert shapely.equals(got[0], expected[0]) and got[1].is_empty


def test_verify_reads_the_results_arrays_not_the_documents():
    import rnsca

    doc = collection(*(feature({"type": "LineString", "coordinates": [[0, y], [100, y]]})
                       for y in (0.0, 40.0, 50.0)))
    result = clip_geojson(doc, WINDOW)
    assert len(result.document["features"]) == 2  # the first is outside, dropped
    assert rnsca.verify(None, result, WINDOW).passed
    # A wrong document changes nothing: verification never reads it ...
    result.document["features"][0]["geometry"] = None
    assert rnsca.verify(doc, result, WINDOW).passed
    # ... and wrong arrays are caught, in the geometry they belong to.
    result.outputs["lines"].coords[0] = [0.0, 40.0]
    v = rnsca.verify(None, result, WINDOW)
    assert not v.passed and v.false_positives == 1


# --------------------------------------------------------------------------- 2D and 3D mixed
# RFC 7946 allows 2 or 3 numbers in any position. Each position comes out with the number
# it came in with; a new one (cut point, window corner) has Z only if every Z it is
# computed from is known.

MIXED_LINE = {"type": "LineString", "coordinates": [[-5, 5], [5, 5, 1], [15, 5, 3], [15, 8]]}
MIXED_RING = [[-5, -5, 1], [5, -5], [5, 5, 2], [-5, 5, 2], [-5, -5, 1]]


def xy_only(geometry):
    """Return a GeoJSON geometry with every position cut to x and y (for ``shape``)."""
    def cut(value):
        if value and not isinstance(value[0], (list, tuple)):
            return list(value[:2])
        return [cut(item) for item in value]
    if geometry["type"] == "GeometryCollection":
        return {**geometry, "geometries": [xy_only(g) for g in geometry["geometries"]]}
    return {**geometry, "coordinates": cut(geometry["coordinates"])}


def positions(coordinates):
    """Yield every position of a coordinates member."""
    if coordinates and isinstance(coordinates[0], (int, float)):
        yield coordinates
        return
    for item in coordinates:
        yield from positions(item)


def test_a_cut_point_has_z_only_between_two_3d_positions():
    out, _ = clip_geojson(collection(feature(MIXED_LINE)), (0, 0, 10, 10))
    assert out["features"][0]["geometry"] == {
        "type": "LineString", "coordinates": [[0.0, 5.0], [5.0, 5.0, 1.0], [10.0, 5.0, 2.0]]}


def test_a_polygon_corner_has_z_only_when_both_ends_it_is_interpolated_between_have():
    # (5, 0) cuts the edge from the 2D (5, -5); the corner (0, 0) lies between the
    # exit (0, 5, 2) and that entry, so it has no Z either.
    out, _ = clip_geojson(collection(feature({"type": "Polygon", "coordinates": [MIXED_RING]}),
                                     feature({"type": "Point", "coordinates": [1, 1]})),
                          (0, 0, 10, 10))
    assert out["features"][0]["geometry"] == {"type": "Polygon", "coordinates": [
        [[5.0, 0.0], [5.0, 5.0, 2.0], [0.0, 5.0, 2.0], [0.0, 0.0], [5.0, 0.0]]]}
    assert out["features"][1]["geometry"] == {"type": "Point", "coordinates": [1.0, 1.0]}


def test_a_window_inside_a_polygon_takes_z_only_from_a_3d_shell():
    ring_3d = [[-5, -5, 4], [15, -5, 4], [15, 15, 8], [-5, 15, 8], [-5, -5, 4]]
    ring_2d = [[-5, -5], [15, -5], [15, 15], [-5, 15], [-5, -5]]
    mixed = [[-5, -5, 4], [15, -5], [15, 15, 8], [-5, 15, 8], [-5, -5, 4]]
    doc = collection(*(feature({"type": "Polygon", "coordinates": [ring]})
                       for ring in (ring_3d, ring_2d, mixed)))
    out, _ = clip_geojson(doc, (0, 0, 10, 10))
    dims = [{len(p) for p in positions(f["geometry"]["coordinates"])}
            for f in out["features"]]
    assert dims == [{3}, {2}, {2}]  # the shell's mean Z: known only for the 3D one
    alone, _ = clip_geojson(feature({"type": "Polygon", "coordinates": [ring_3d]}),
                            (0, 0, 10, 10))
    assert out["features"][0]["geometry"] == alone["geometry"]


def test_every_backend_writes_the_mixed_case_alike(backend):
    out, _ = clip_geojson(MIXED_DIMENSIONS, (0, 0, 10, 10), backend=backend)
    assert [f["geometry"] for f in out["features"]] == MIXED_DIMENSIONS_CLIPPED


def test_points_keep_their_own_dimension():
    doc = collection(feature({"type": "MultiPoint", "coordinates": [[1, 1], [2, 2, 5],
                                                                   [20, 20, 1], [3, 3]]}))
    out, _ = clip_geojson(doc, (0, 0, 10, 10))
    assert out["features"][0]["geometry"]["coordinates"] == [[1.0, 1.0], [2.0, 2.0, 5.0],
                                                             [3.0, 3.0]]


def test_geometries_of_one_dimension_clip_as_in_a_document_of_their_own(rng):
    shapes = [star_with_hole(rng) for _ in range(5)]
    shapes += [shapely.LineString(random_walk(rng, 50)) for _ in range(5)]
    flat = [mapping(g) for g in shapes]
    raised = [mapping(shapely.force_3d(g, 7.5)) for g in shapes]
    mixed = collection(*(feature(g) for pair in zip(flat, raised, strict=True) for g in pair))
    out, _ = clip_geojson(mixed, WINDOW, keep_empty=True)
    flat_out, _ = clip_geojson(collection(*map(feature, flat)), WINDOW, keep_empty=True)
    raised_out, _ = clip_geojson(collection(*map(feature, raised)), WINDOW, keep_empty=True)
    assert out["features"][0::2] == flat_out["features"]
    assert out["features"][1::2] == raised_out["features"]


def test_a_mixed_document_matches_shapely_in_2d(rng):
    geometries = []
    for k in range(40):
        g = mapping(star_with_hole(rng) if k % 2 else shapely.LineString(random_walk(rng, 80)))
        coordinates = orjson.loads(orjson.dumps(g["coordinates"]))
        for position in positions(coordinates):
            if rng.random() < 0.5:
                position.append(float(rng.uniform(-10, 10)))
        if g["type"] == "Polygon":  # ring ends of one dimension, and equal
            for ring in coordinates:
                ring[-1] = list(ring[0])
        geometries.append({"type": g["type"], "coordinates": coordinates})
    doc = collection(*map(feature, geometries))
    assert from_geojson(doc).partial_z
    result = clip_geojson(doc, WINDOW, keep_empty=True)
    for original, out in zip(geometries, result.document["features"], strict=True):
        assert_matches_shapely(xy_only(out["geometry"]) if out["geometry"]["coordinates"]
                               else None, xy_only(original))
        for position in positions(out["geometry"]["coordinates"]):
            assert len(position) in (2, 3) and all(math.isfinite(v) for v in position)
    import rnsca

    assert rnsca.verify(None, result, WINDOW).passed
    assert rnsca.verify(doc, result.document, WINDOW).passed  # two documents, no arrays


def test_a_mixed_document_is_written_back_as_it_came():
    doc = copy.deepcopy(collection(
        feature(MIXED_LINE), feature({"type": "Polygon", "coordinates": [MIXED_RING]}),
        feature({"type": "MultiPoint", "coordinates": [[1, 2], [3, 4, 5]]})))
    for f in doc["features"]:  # floats, as they are written back
        for position in positions(f["geometry"]["coordinates"]):
            position[:] = map(float, position)
    everything = (-100, -100, 100, 100)
    out, _ = clip_geojson(doc, everything)
    assert out == doc
    fast, _ = clip_geojson(doc, everything, arrays=True)
    assert dumps(fast) == orjson.dumps(doc)


def test_list_and_array_output_of_a_mixed_document_serialize_alike():
    doc = collection(
        feature(MIXED_LINE), feature({"type": "Polygon", "coordinates": [MIXED_RING]}),
        feature({"type": "MultiPoint", "coordinates": [[1, 2], [3, 4, 5]]}),
        feature({"type": "LineString", "coordinates": [[1, 1, 1], [2, 2, 2]]}))
    listed, _ = clip_geojson(doc, (0, 0, 10, 10))
    fast, _ = clip_geojson(doc, (0, 0, 10, 10), arrays=True)
    text = dumps(fast)
    assert text == orjson.dumps(listed)
    assert b"null" not in text and b"NaN" not in text


def test_a_bbox_has_z_only_over_positions_that_have_it():
    doc = collection(
        feature({"type": "LineString", "coordinates": [[1, 1], [2, 2]]},
                bbox=[1, 1, 0, 2, 2, 0]),
        feature({"type": "LineString", "coordinates": [[3, 3, 7], [4, 4], [5, 5, 9]]},
                bbox=[3, 3, 7, 5, 5, 9]),
        bbox=[1, 1, 7, 5, 5, 9])
    out, _ = clip_geojson(doc, (0, 0, 10, 10))
    assert out["features"][0]["bbox"] == [1.0, 1.0, 2.0, 2.0]
    assert out["features"][1]["bbox"] == [3.0, 3.0, 7.0, 5.0, 5.0, 9.0]
    assert out["bbox"] == [1.0, 1.0, 7.0, 5.0, 5.0, 9.0]
