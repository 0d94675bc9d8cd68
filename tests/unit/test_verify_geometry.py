"""verify on geometries: Shapely objects, ragged results and GeoJSON, against literal cases.

Each "ours" below is written by hand (right or deliberately wrong), so these tests need no
clipping code except where a ragged result is the subject.
"""

import json
import math

import numpy as np
import pytest
import shapely
from shapely import from_wkt as wkt

from rnsca import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    ParseError,
    UnsupportedGeometryError,
    clip,
    clip_ragged,
    verify,
)

W10 = (0.0, 0.0, 10.0, 10.0)
CROSSING = wkt("LINESTRING (-5 5, 15 5)")
REENTERING = wkt("LINESTRING (-5 2, 5 2, 5 15, 8 15, 8 2, 15 2)")
HOLED = wkt("POLYGON ((-5 -5, 15 -5, 15 5, -5 5, -5 -5), (2 1, 4 1, 4 3, 2 3, 2 1))")


# --- right outputs pass ------------------------------------------------------------------

def test_line_crossing_the_window_passes_with_no_deviation():
    v = verify(CROSSING, wkt("LINESTRING (0 5, 10 5)"), W10)
    assert (v.passed, v.max_deviation, v.false_positives, v.ratio, v.valid) == (
        True, 0.0, 0, 1.0, True)
    assert v.mode == "exact" and v.allowed_deviation == 1e-8


def test_line_running_backwards_is_the_same_set():
    assert verify(CROSSING, wkt("LINESTRING (10 5, 0 5)"), W10).max_deviation == 0.0


def test_line_leaving_and_reentering_compares_with_both_parts():
    ours = wkt("MULTILINESTRING ((0 2, 5 2, 5 10), (8 10, 8 2, 10 2))")
    v = verify(REENTERING, ours, W10)
    assert v.passed and v.max_deviation == 0.0 and v.ratio == 1.0


def test_line_crossing_itself_is_compared_segment_by_segment(monkeypatch):
    # 300 random vertices across the window: the line crosses itself ~10,000 times, and
    # GEOS's overlay of the whole line with the box would node it at every crossing.
    line = shapely.LineString(np.random.default_rng(3).uniform(-2, 12, (300, 2)))
    ours = clip(line, W10)
    asked, intersection = [], shapely.intersection

    def recording(a, b, **kwargs):
        asked.append(shapely.get_num_coordinates(a))
        return intersection(a, b, **kwargs)

    monkeypatch.setattr(shapely, "intersection", recording)
    v = verify(line, ours, W10)
    assert v.passed and math.isclose(v.ratio, 1.0, rel_tol=1e-12)
    assert asked and max(np.max(n) for n in asked) == 2  # only segments went to GEOS


def test_simple_lines_go_to_geos_whole_and_crossing_ones_by_segment(monkeypatch):
    # A simple line has nothing for the overlay to node: one intersection, cheaper than its
    # segments; in a mix, each input is still compared with its own expected pieces.
    wiggle = shapely.LineString([(-5, 5), (3, 6), (6, 4), (15, 5)])  # simple, 4 vertices
    knot = shapely.LineString(np.random.default_rng(4).uniform(-2, 12, (40, 2)))
    assert wiggle.is_simple and not knot.is_simple
    lines = np.array([knot, wiggle, knot, wiggle], dtype=object)
    ours = np.array([clip(line, W10) for line in lines], dtype=object)
    asked, intersection = [], shapely.intersection

    def recording(a, b, **kwargs):
        asked.extend(np.atleast_1d(shapely.get_num_coordinates(a)).tolist())
        return intersection(a, b, **kwargs)

    monkeypatch.setattr(shapely, "intersection", recording)
    v = verify(lines, ours, W10)
    assert v.passed and v.checked == 4 and math.isclose(v.ratio, 1.0, rel_tol=1e-12)
    assert asked.count(4) == 2 and set(asked) == {2, 4}
    # A wrong answer for one simple line is still caught, and only it.
    wrong = ours.copy()
    wrong[1] = shapely.LineString([(0, 5), (3, 6), (6, 4), (10, 6)])
    assert not verify(lines, wrong, W10).passed


def test_line_run_back_over_itself_counts_both_ways():
    # The whole line's overlay would count the overlap once (ratio 2).
    v = verify(wkt("LINESTRING (-5 5, 5 5, 2 5)"), wkt("LINESTRING (0 5, 5 5, 2 5)"), W10)
    assert v.passed and v.ratio == 1.0


def test_polygon_with_a_hole_passes_whatever_its_ring_order_and_start():
    # Shapely's answer runs clockwise from (10, 5); ours counter-clockwise from (0, 0).
    ours = wkt("POLYGON ((0 0, 10 0, 10 5, 0 5, 0 0), (2 1, 2 3, 4 3, 4 1, 2 1))")
    v = verify(HOLED, ours, W10)
    assert v.passed and v.max_deviation == 0.0 and v.ratio == 1.0 and v.valid


def test_points_on_the_edge_count_under_the_closed_boundary_only():
    points = wkt("MULTIPOINT (0 5, 5 5, 11 5)")
    assert verify(points, wkt("MULTIPOINT (0 5, 5 5)"), W10).passed
    interior = verify(points, wkt("POINT (5 5)"), W10, boundary="interior")
    assert interior.passed and interior.ratio == 1.0
    closed = verify(points, wkt("POINT (5 5)"), W10)
    assert not closed.passed and closed.ratio == 0.5 and closed.max_deviation == 5.0


def test_line_along_the_edge_is_expected_under_closed_and_not_under_interior():
    edge = wkt("LINESTRING (-1 0, 11 0)")
    assert verify(edge, wkt("LINESTRING (0 0, 10 0)"), W10).passed
    assert verify(edge, None, W10, boundary="interior").passed
    missing = verify(edge, None, W10)
    assert not missing.passed and missing.max_deviation == 10.0 and missing.ratio == 0.0


def test_geometry_wholly_outside_with_nothing_out_passes_with_ratio_one():
    v = verify(wkt("POLYGON ((20 20, 30 20, 30 30, 20 20))"), wkt("POLYGON EMPTY"), W10)
    assert v.passed and v.ratio == 1.0 and v.max_deviation == 0.0


def test_z_values_are_ignored():
    ours = wkt("LINESTRING Z (0 5 99, 10 5 -99)")
    assert verify(wkt("LINESTRING Z (-5 5 1, 15 5 3)"), ours, W10).passed


def test_collection_members_are_compared_dimension_by_dimension():
    original = wkt("GEOMETRYCOLLECTION (POLYGON ((-1 -1, 5 -1, 5 5, -1 5, -1 -1)), "
                   "LINESTRING (-5 8, 15 8), POINT (3 3), POINT (30 3))")
    ours = wkt("GEOMETRYCOLLECTION (POLYGON ((0 0, 5 0, 5 5, 0 5, 0 0)), "
               "LINESTRING (0 8, 10 8), POINT (3 3))")
    v = verify(original, ours, W10)
    assert v.passed and v.max_deviation == 0.0
    assert v.ratio == 1.0  # area: the highest dimension of the input


def test_arrays_are_compared_element_by_element():
    originals = np.array([CROSSING, wkt("POINT (1 1)"), wkt("POINT (20 1)")])
    ours = [wkt("LINESTRING (0 5, 10 5)"), wkt("POINT (1 1)"), None]
    assert verify(originals, ours, W10).passed
    # The same parts under the wrong inputs deviate.
    assert not verify(originals, ours[::-1], W10).passed


def test_one_window_per_geometry():
    originals = [CROSSING, CROSSING]
    ours = [wkt("LINESTRING (0 5, 10 5)"), wkt("LINESTRING (0 5, 5 5)")]
    windows = [[0, 0, 10, 10], [0, 0, 5, 10]]
    assert verify(originals, ours, windows).passed
    assert not verify(originals, ours[::-1], windows).passed


@pytest.mark.parametrize("window, ours", [
    ((0.0, 0.0, 1e-300, 1e-300), "LINESTRING (0 5e-301, 1e-300 5e-301)"),
    ((-1e300, -1e300, 1e300, 1e300), "LINESTRING (-1e300 0, 1e300 0)"),
])
def test_tiny_and_huge_windows_are_compared_after_exact_rescaling(window, ours):
    xmin, _, xmax, _ = window
    y = 5e-301 if xmax < 1 else 0.0
    original = shapely.LineString([(xmin - (xmax - xmin), y), (xmax + (xmax - xmin), y)])
    v = verify(original, wkt(ours), window)
    assert v.passed and v.max_deviation == 0.0 and v.ratio == 1.0


def test_polygon_area_ratio_does_not_overflow_at_1e300():
    window = (-1e300, -1e300, 1e300, 1e300)
    original = shapely.box(-2e300, -2e300, 2e300, 0.0)
    v = verify(original, shapely.box(-1e300, -1e300, 1e300, 0.0), window)
    assert v.passed and v.ratio == 1.0
    half = verify(original, shapely.box(-1e300, -1e300, 0.0, 0.0), window)
    assert not half.passed and half.ratio == 0.5 and half.max_deviation == 1e300


# --- wrong outputs fail, with the right numbers -------------------------------------------

def test_piece_overshooting_the_window_has_two_false_positives():
    v = verify(CROSSING, wkt("LINESTRING (-1 5, 11 5)"), W10)
    assert not v.passed
    assert (v.false_positives, v.max_deviation, v.ratio) == (2, 1.0, 1.2)


def test_vertex_outside_by_less_than_1e_9_of_the_window_is_no_false_positive():
    v = verify(CROSSING, wkt("LINESTRING (-5e-9 5, 10 5)"), W10)
    assert v.false_positives == 0 and v.passed


def test_ring_closing_vertex_outside_counts_once():
    v = verify(shapely.box(-5, -5, 5, 5), shapely.box(-1, 0, 5, 5), W10)
    assert v.false_positives == 2 and not v.passed


def test_gap_inside_a_straight_stretch_is_seen():
    ours = wkt("MULTILINESTRING ((0 5, 4 5), (6 5, 10 5))")
    # GEOS's discrete Hausdorff distance sees no difference: every vertex is on the other.
    assert shapely.hausdorff_distance(ours, wkt("LINESTRING (0 5, 10 5)")) == 0.0
    v = verify(CROSSING, ours, W10)
    assert not v.passed and v.max_deviation == 1.0 and v.ratio == 0.8


def test_polygon_cut_in_two_along_a_straight_edge_is_seen():
    ours = wkt("MULTIPOLYGON (((0 0, 4 0, 4 1, 0 1, 0 0)), ((6 0, 10 0, 10 1, 6 1, 6 0)))")
    v = verify(wkt("POLYGON ((-1 0, 11 0, 11 1, -1 1, -1 0))"), ours, W10)
    assert not v.passed and v.max_deviation == 1.0 and v.ratio == 0.8 and v.valid


def test_polygon_missing_its_hole_deviates_by_the_holes_depth():
    v = verify(HOLED, wkt("POLYGON ((0 0, 10 0, 10 5, 0 5, 0 0))"), W10)
    assert not v.passed and v.valid
    assert v.max_deviation == 2.0  # the middle of the hole's top edge, (3, 3), to y = 5
    assert v.ratio == pytest.approx(50 / 46)


def test_shifted_vertex_fails_with_its_distance():
    v = verify(CROSSING, wkt("LINESTRING (0 5, 5 5.000001, 10 5)"), W10)
    assert not v.passed and v.max_deviation == pytest.approx(1e-6)


def test_piece_where_nothing_is_expected_counts_its_extent():
    # The line touches the window at a corner only: Shapely's point is no line.
    v = verify(wkt("LINESTRING (-1 -1, 0 0, -1 1)"), wkt("LINESTRING (0 0, 3 4)"), W10)
    assert not v.passed and v.max_deviation == 5.0 and v.ratio == math.inf


def test_missing_point_counts_the_window_size():
    v = verify(wkt("POINT (5 5)"), None, W10)
    assert not v.passed and v.max_deviation == 10.0 and v.ratio == 0.0


def test_lower_dimensional_leftover_fails():
    # A polygon sharing only an edge with the window gives nothing, not the edge.
    original = wkt("POLYGON ((10 0, 20 0, 20 10, 10 10, 10 0))")
    assert verify(original, None, W10).passed
    v = verify(original, wkt("LINESTRING (10 0, 10 10)"), W10)
    assert not v.passed and v.max_deviation == 10.0


def test_invalid_polygon_output_is_flagged_and_fails():
    bowtie = wkt("POLYGON ((0 0, 5 5, 5 0, 0 5, 0 0))")
    v = verify(shapely.box(0, 0, 5, 5), bowtie, W10)
    assert v.valid is False and not v.passed and v.invalid_inputs == 0
    assert v.max_deviation == 2.5


def test_overlapping_output_polygons_are_invalid_together():
    ours = shapely.MultiPolygon([shapely.box(0, 0, 6, 5), shapely.box(4, 0, 10, 5)])
    v = verify(shapely.box(-1, 0, 11, 5), ours, W10)
    assert v.valid is False and not v.passed


def test_invalid_input_polygon_excuses_its_invalid_output():
    # Clipped ring by ring, a self-intersecting polygon stays self-intersecting.
    bowtie = wkt("POLYGON ((0 0, 10 10, 10 0, 0 10, 0 0))")
    ours = wkt("POLYGON ((1 1, 9 9, 9 1, 1 9, 1 1))")
    v = verify(bowtie, ours, (1, 1, 9, 9))
    assert v.valid is False and v.invalid_inputs == 1
    assert v.passed and v.max_deviation < 1e-12


def test_invalid_input_polygon_does_not_decide_the_verdict_by_its_deviation():
    bowtie = wkt("POLYGON ((0 0, 10 10, 10 0, 0 10, 0 0))")
    # Two overlapping triangles, against make_valid's left and right ones.
    ours = wkt("MULTIPOLYGON (((1 1, 9 9, 1 9, 1 1)), ((9 1, 1 9, 1 1, 9 1)))")
    v = verify([bowtie, CROSSING], [ours, wkt("LINESTRING (1 5, 9 5)")], (1, 1, 9, 9))
    assert v.invalid_inputs == 1 and v.valid is False
    assert v.max_deviation == pytest.approx(2 * math.sqrt(2))
    assert v.passed
    # The valid inputs still decide it.
    wrong = verify([bowtie, CROSSING], [ours, wkt("LINESTRING (1 5, 8 5)")], (1, 1, 9, 9))
    assert not wrong.passed


def test_nan_output_vertex_is_a_false_positive_and_fails():
    with np.errstate(invalid="ignore"):
        broken = shapely.LineString([(0, 5), (math.nan, 5)])
    v = verify(CROSSING, broken, W10)
    assert v.false_positives == 1 and not v.passed


# --- approx mode ---------------------------------------------------------------------------

def test_approx_passes_within_the_bound_and_fails_beyond_it():
    ours = wkt("LINESTRING (0.01 5, 9.99 5)")
    v = verify(CROSSING, ours, W10, mode="approx", approx_bound=0.02)
    assert v.passed and v.mode == "approx" and v.allowed_deviation == 0.02
    assert v.max_deviation == pytest.approx(0.01) and v.ratio == pytest.approx(0.998)
    assert not verify(CROSSING, ours, W10, mode="approx", approx_bound=0.005).passed


def test_approx_still_fails_on_a_false_positive():
    v = verify(CROSSING, wkt("LINESTRING (-0.01 5, 9.99 5)"), W10, mode="approx",
               approx_bound=1.0)
    assert v.false_positives == 1 and not v.passed


def test_approx_geometries_need_a_bound():
    with pytest.raises(InvalidOptionError, match="approx_bound"):
        verify(CROSSING, CROSSING, W10, mode="approx")


@pytest.mark.parametrize("bound", [-1.0, "wide", math.nan])
def test_approx_bound_must_be_a_non_negative_number(bound):
    with pytest.raises(InvalidOptionError, match="approx_bound"):
        verify(CROSSING, CROSSING, W10, mode="approx", approx_bound=bound)


# --- ragged results --------------------------------------------------------------------------

def ragged_lines():
    lines = [CROSSING, REENTERING, wkt("LINESTRING (20 20, 30 30)"),
             wkt("LINESTRING (1 1, 2 2, 3 1)")]
    return lines, shapely.to_ragged_array(lines)


@pytest.mark.parametrize("keep_empty", [False, True])
def test_ragged_result_is_aligned_by_source(keep_empty):
    lines, triple = ragged_lines()
    r = clip_ragged(*triple, W10, keep_empty=keep_empty)
    assert len(r) == (4 if keep_empty else 3)
    for original in (triple, lines, np.array(lines)):
        v = verify(original, r, W10)
        assert v.passed and v.max_deviation == 0.0 and v.ratio == 1.0


def test_ragged_result_with_a_moved_vertex_fails():
    _, triple = ragged_lines()
    r = clip_ragged(*triple, W10)
    coords = r.coords.copy()
    coords[0] = [-1.0, 5.0]
    v = verify(triple, type(r)(r.geometry_type, coords, r.offsets, r.source, r.stats), W10)
    assert not v.passed and v.false_positives == 1 and v.max_deviation == 1.0


def test_ragged_result_with_a_wrong_source_fails():
    _, triple = ragged_lines()
    r = clip_ragged(*triple, W10)
    swapped = type(r)(r.geometry_type, r.coords, r.offsets, r.source[::-1].copy(), r.stats)
    assert not verify(triple, swapped, W10).passed


def test_ragged_polygons_with_holes_pass():
    polygons = [HOLED, shapely.box(2, 2, 4, 4), shapely.box(20, 20, 30, 30)]
    triple = shapely.to_ragged_array(polygons)
    v = verify(triple, clip_ragged(*triple, W10), W10)
    assert v.passed and v.valid and v.ratio == 1.0


def test_ragged_result_needs_the_geometries_that_were_clipped():
    _, triple = ragged_lines()
    r = clip_ragged(*triple, W10)
    with pytest.raises(InvalidGeometryError, match="4 geometries that were clipped"):
        verify([CROSSING], r, W10)


# --- GeoJSON ---------------------------------------------------------------------------------

def feature(geometry, **properties):
    return {"type": "Feature", "properties": properties, "geometry": geometry}


def collection(*features):
    return {"type": "FeatureCollection", "features": list(features)}


LINE = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
FAR = {"type": "Point", "coordinates": [50, 50]}
CLIPPED_LINE = {"type": "LineString", "coordinates": [[0, 5], [10, 5]]}


def test_geojson_geometry_pair():
    assert verify(LINE, CLIPPED_LINE, W10).passed
    assert verify(feature(LINE), feature(CLIPPED_LINE), W10).passed


def test_geojson_collection_with_empty_features_dropped_is_aligned():
    original = collection(feature(FAR), feature(LINE), feature(None))
    assert verify(original, collection(feature(CLIPPED_LINE)), W10).passed


def test_geojson_collection_with_empty_features_kept_is_aligned():
    original = collection(feature(FAR), feature(LINE))
    empty = {"type": "Point", "coordinates": []}
    assert verify(original, collection(feature(empty), feature(CLIPPED_LINE)), W10).passed
    # Swapped, each feature deviates.
    assert not verify(original, collection(feature(CLIPPED_LINE), feature(empty)), W10).passed


def test_geojson_collections_that_cannot_be_matched_are_compared_whole():
    original = collection(feature(FAR), feature(LINE))
    halves = collection(feature({"type": "LineString", "coordinates": [[0, 5], [5, 5]]}),
                        feature({"type": "LineString", "coordinates": [[5, 5], [10, 5]]}),
                        feature({"type": "Point", "coordinates": [5, 5]}))
    v = verify(original, halves, W10)
    assert not v.passed and v.max_deviation == 10.0  # the extra point
    assert v.ratio == 1.0  # the lines, as a whole, are right


def test_geojson_must_be_paired_with_geojson():
    with pytest.raises(UnsupportedGeometryError, match="GeoJSON"):
        verify(CROSSING, CLIPPED_LINE, W10)


def test_geojson_that_is_not_a_geometry_names_its_path():
    bad = collection(feature(LINE), feature({"type": "LineString", "coordinates": 5}))
    with pytest.raises(ParseError, match=r"original\.features\[1\]\.geometry"):
        verify(bad, collection(feature(CLIPPED_LINE)), W10)


# --- refused inputs --------------------------------------------------------------------------

def test_non_finite_original_coordinate_names_the_geometry():
    bad = [CROSSING, shapely.LineString([(0, 0), (math.inf, 1)])]
    with pytest.raises(InvalidGeometryError, match="original geometry 1"):
        verify(bad, [CROSSING, None], W10)


def test_clipped_of_an_unknown_kind_is_refused():
    with pytest.raises(UnsupportedGeometryError, match="RaggedClipResult"):
        verify(CROSSING, "LINESTRING (0 5, 10 5)", W10)


def test_outputs_must_be_one_per_original():
    with pytest.raises(InvalidGeometryError, match="2 originals and 1 outputs"):
        verify([CROSSING, CROSSING], [CROSSING], W10)


def test_window_array_must_have_a_row_per_geometry():
    with pytest.raises(InvalidWindowError, match="one row"):
        verify([CROSSING, CROSSING], [None, None], [[0, 0, 1, 1]])
    with pytest.raises(InvalidWindowError, match="window 1"):
        verify([CROSSING, CROSSING], [None, None], [[0, 0, 1, 1], [0, 0, 0, 1]])


def test_to_dict_is_json_ready_with_the_geometry_fields():
    v = verify(HOLED, wkt("POLYGON ((0 0, 10 0, 10 5, 0 5, 0 0))"), W10)
    d = json.loads(json.dumps(v.to_dict()))
    assert d["valid"] is True and d["invalid_inputs"] == 0 and d["passed"] is False
    assert d["max_deviation"] == 2.0


def test_verify_works_for_a_window_of_subnormal_size():
    # Found by fuzzing: the power of two that would bring such a window to size 1 is
    # beyond float64 (infinite coordinates for Shapely).
    window = (0.0, 0.0, 5e-324, 5e-324)
    line = shapely.LineString([(-1e-323, 0.0), (1e-323, 5e-324)])
    v = verify(line, shapely.LineString([(0.0, 0.0), (5e-324, 5e-324)]), window)
    assert v.passed and v.max_deviation == 0.0


@pytest.mark.parametrize(("kind", "offsets"), [("multipoint", ([0, 1],)),
                                                ("linestring", ([0, 2],))])
def test_a_ragged_result_left_with_no_coordinates_is_compared(kind, offsets):
    """Every output empty (kept with keep_empty): Shapely's from_ragged_array fails there."""
    coords = [[20.0, 1.0]] if kind == "multipoint" else [[20.0, 1.0], [30.0, 1.0]]
    result = clip_ragged(kind, coords, offsets, (0, 0, 10, 10), keep_empty=True)
    assert result.coords.shape[0] == 0
    assert verify((kind, np.array(coords), offsets), result, (0, 0, 10, 10)).passed
