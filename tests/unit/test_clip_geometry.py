"""Clipping whole geometries: literal cases, each named after the behaviour it pins down.

Most cases go through `rnsca.clip_ragged` (the columnar core) and check the output
arrays literally; polygon cases compare normalized rings exactly (ring start is the
implementation's choice, orientation is checked on its own). The last section checks the
forms `rnsca.clip` accepts. The window is ``W = (0, 0, 10, 10)`` unless a case says
otherwise.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import shapely
from shapely import GeometryType

import rnsca
from rnsca import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    UnsupportedGeometryError,
    Window,
    clip_ragged,
)
from tests.geometry_checks import geometries_of

W = (0.0, 0.0, 10.0, 10.0)


def clip_wkt(wkt: str, window=W, **options):
    """Return the one geometry clipping `wkt` gives (an empty one if nothing is left)."""
    result = clip_ragged(*shapely.to_ragged_array([shapely.from_wkt(wkt)]), window,
                         keep_empty=True, **options)
    assert result.source.tolist() == [0]
    return geometries_of(result)[0]


def ragged(wkt: str, window=W, **options):
    """Return the RaggedClipResult of clipping the geometries in `wkt` (';'-separated)."""
    geometries = [shapely.from_wkt(w) for w in wkt.split(";")]
    return clip_ragged(*shapely.to_ragged_array(geometries), window, **options)


def assert_same_polygons(got, expected_wkt: str) -> None:
    """Check that `got` has exactly the rings of `expected_wkt` (any start or orientation)."""
    expected = shapely.from_wkt(expected_wkt)
    assert shapely.equals_exact(shapely.normalize(got), shapely.normalize(expected), 0.0), (
        f"got {got.wkt}, expected {expected.wkt}")
    assert shapely.is_valid(got), shapely.is_valid_reason(got)


def assert_oriented(polygonal) -> None:
    """Check RFC 7946 orientation: shells counter-clockwise, holes clockwise."""
    for polygon in shapely.get_parts(polygonal):
        assert shapely.is_ccw(polygon.exterior), polygon.wkt
        assert not any(shapely.is_ccw(h) for h in polygon.interiors), polygon.wkt


# --- lines ---------------------------------------------------------------------------------

def test_line_inside_is_returned_unchanged():
    r = ragged("LINESTRING (1 1, 2 2, 3 3)")
    assert r.geometry_type == GeometryType.LINESTRING
    np.testing.assert_array_equal(r.coords, [[1, 1], [2, 2], [3, 3]])
    np.testing.assert_array_equal(r.offsets[0], [0, 3])
    np.testing.assert_array_equal(r.source, [0])


def test_line_leaving_and_reentering_splits_into_parts_in_input_order_and_direction():
    r = ragged("LINESTRING (2 2, 12 2, 12 8, 2 8)")
    assert r.geometry_type == GeometryType.MULTILINESTRING
    np.testing.assert_array_equal(r.coords, [[2, 2], [10, 2], [10, 8], [2, 8]])
    np.testing.assert_array_equal(r.offsets[0], [0, 2, 4])
    np.testing.assert_array_equal(r.offsets[1], [0, 2])


def test_reversed_line_gives_the_parts_reversed():
    r = ragged("LINESTRING (2 8, 12 8, 12 2, 2 2)")
    np.testing.assert_array_equal(r.coords, [[2, 8], [10, 8], [10, 2], [2, 2]])
    np.testing.assert_array_equal(r.offsets[0], [0, 2, 4])


def test_line_crossing_many_times_clips_without_leaving_empty_parts():
    # lineclip's "clips line" case.
    got = clip_wkt("LINESTRING (-10 10, 10 10, 10 -10, 20 -10, 20 10, 40 10, 40 20, 20 20, "
                   "20 40, 10 40, 10 20, 5 20, -10 20)", (0, 0, 30, 30))
    assert got.wkt == ("MULTILINESTRING ((0 10, 10 10, 10 0), (20 0, 20 10, 30 10), "
                       "(30 20, 20 20, 20 30), (10 30, 10 20, 5 20, 0 20))")


def test_line_through_a_corner_is_cut_at_both_corners():
    assert clip_wkt("LINESTRING (-1 -1, 11 11)").wkt == "LINESTRING (0 0, 10 10)"


def test_line_along_an_edge_is_kept_with_the_closed_boundary():
    assert clip_wkt("LINESTRING (0 2, 0 8)", boundary="closed").wkt == "LINESTRING (0 2, 0 8)"


def test_line_along_an_edge_is_dropped_with_the_interior_boundary():
    assert clip_wkt("LINESTRING (0 2, 0 8)", boundary="interior").is_empty


def test_line_along_an_edge_beyond_the_corner_keeps_only_the_edge_part_closed():
    assert clip_wkt("LINESTRING (0 -5, 0 5)", boundary="closed").wkt == "LINESTRING (0 0, 0 5)"
    assert clip_wkt("LINESTRING (0 -5, 0 5)", boundary="interior").is_empty


def test_run_along_an_edge_between_inside_runs_joins_closed_and_splits_interior():
    line = "LINESTRING (5 5, 0 5, 0 8, 5 8)"
    assert clip_wkt(line, boundary="closed").wkt == "LINESTRING (5 5, 0 5, 0 8, 5 8)"
    assert clip_wkt(line, boundary="interior").wkt == "MULTILINESTRING ((5 5, 0 5), (0 8, 5 8))"


@pytest.mark.parametrize("boundary", ["closed", "interior"])
@pytest.mark.parametrize("line", ["LINESTRING (-5 5, 0 5, -5 8)",    # touches an edge
                                  "LINESTRING (-1 11, 0 10, 1 11)",  # touches a corner
                                  "LINESTRING (-5 5, 5 15)"])        # grazes a corner
def test_line_touching_the_window_at_a_point_gives_nothing(line, boundary):
    assert clip_wkt(line, boundary=boundary).is_empty


def test_line_outside_gives_nothing_and_is_dropped_unless_keep_empty():
    line = "LINESTRING (20 20, 30 30)"
    dropped = ragged(line)
    assert dropped.source.size == 0 and dropped.coords.shape == (0, 2)
    kept = ragged(line, keep_empty=True)
    np.testing.assert_array_equal(kept.source, [0])
    assert geometries_of(kept)[0].is_empty


def test_cut_point_of_a_steep_line_is_exact_where_geos_is_off():
    # x runs from 2 + 2**-24 to 2 - 2**-24 while y climbs 1.375: the line crosses x = 2
    # at exactly (2, 1). shapely.clip_by_rect gives (2, 1.0000000017074246).
    got = clip_wkt("LINESTRING (2.0000000596046448 0.3125, 1.9999999403953552 1.6875)",
                   (2, 0.75, 2.25, 1.6875))
    np.testing.assert_array_equal(shapely.get_coordinates(got),
                                  [[2.0000000216744165, 0.75], [2.0, 1.0]])


def test_z_is_kept_on_vertices_and_interpolated_on_cut_points():
    # GEOS's GEOSClipByRectTest 20, plus a kept vertex.
    got = clip_wkt("LINESTRING Z (0 15 0, 15 15 50, 100 15 100)", (10, 10, 20, 20))
    np.testing.assert_allclose(shapely.get_coordinates(got, include_z=True),
                               [[10, 15, 100 / 3], [15, 15, 50], [20, 15, 50 + 50 * 5 / 85]],
                               rtol=1e-15)


# --- points --------------------------------------------------------------------------------

def test_points_on_the_edge_are_kept_closed_and_dropped_interior():
    points = "MULTIPOINT ((1 1), (6 4), (5 4))"
    assert clip_wkt(points, (0, 0, 5, 5), boundary="closed").wkt == "MULTIPOINT ((1 1), (5 4))"
    assert clip_wkt(points, (0, 0, 5, 5), boundary="interior").wkt == "MULTIPOINT ((1 1))"


def test_points_stay_points_and_keep_their_order():
    r = ragged("POINT (15 15);POINT (3 4);POINT (10 0);POINT (-1 2)")
    assert r.geometry_type == GeometryType.POINT
    np.testing.assert_array_equal(r.coords, [[3, 4], [10, 0]])
    np.testing.assert_array_equal(r.source, [1, 2])


# --- polygons ------------------------------------------------------------------------------

def test_polygon_inside_is_returned_unchanged():
    got = clip_wkt("POLYGON ((1 1, 4 1, 4 4, 1 4, 1 1), (2 2, 2 3, 3 3, 3 2, 2 2))")
    assert_same_polygons(got, "POLYGON ((1 1, 4 1, 4 4, 1 4, 1 1), (2 2, 2 3, 3 3, 3 2, 2 2))")
    assert got.geom_type == "Polygon"


def test_polygon_containing_the_window_gives_the_window():
    got = clip_wkt("POLYGON ((-5 -5, 15 -5, 15 15, -5 15, -5 -5))")
    assert_same_polygons(got, "POLYGON ((0 0, 10 0, 10 10, 0 10, 0 0))")
    assert_oriented(got)


@pytest.mark.parametrize("boundary", ["closed", "interior"])
@pytest.mark.parametrize("polygon", ["POLYGON ((-5 0, 0 0, 0 10, -5 10, -5 0))",  # an edge
                                     "POLYGON ((-5 2, 0 2, 0 8, -5 8, -5 2))",    # part of one
                                     "POLYGON ((-5 -5, 0 -5, 0 0, -5 0, -5 -5))",  # a corner
                                     "POLYGON ((-5 5, 0 5, -5 6, -5 5))"])         # a point
def test_polygon_touching_only_the_boundary_gives_nothing(polygon, boundary):
    assert clip_wkt(polygon, boundary=boundary).is_empty


def test_hole_cut_by_the_window_is_merged_into_the_outer_ring():
    # GEOS's RectangleIntersectionTest 137.
    got = clip_wkt("POLYGON ((5 5, 15 5, 15 -5, 5 -5, 5 5), (8 1, 8 -1, 9 -1, 9 1, 8 1))")
    assert_same_polygons(got, "POLYGON ((5 0, 5 5, 10 5, 10 0, 9 0, 9 1, 8 1, 8 0, 5 0))")
    assert len(got.interiors) == 0


def test_hole_inside_the_window_is_kept_clockwise():
    got = clip_wkt("POLYGON ((-5 -5, 15 -5, 15 15, -5 15, -5 -5), (4 4, 6 4, 6 6, 4 6, 4 4))")
    assert_same_polygons(got, "POLYGON ((0 0, 10 0, 10 10, 0 10, 0 0), "
                              "(4 4, 6 4, 6 6, 4 6, 4 4))")
    assert_oriented(got)


def test_every_hole_inside_the_window_is_kept():
    # Two holes wound like the shell (valid: orientation does not matter to OGC).
    polygon = "POLYGON ((1 1, 9 1, 9 9, 1 9, 1 1), (6 5, 5 6, 5 5, 6 5), (4 4, 3 4, 3 3, 4 4))"
    r = ragged(polygon, (-1, -1, 11, 11))
    assert_same_polygons(geometries_of(r)[0], polygon)
    assert r.stats.invalid_polygons == 0


def test_every_hole_inside_a_cut_polygon_is_kept():
    r = ragged("POLYGON ((0 0, 10 0, 10 10, 0 10, 0 0), (2 2, 3 2, 3 3, 2 2), "
               "(3 6, 4 6, 4 7, 3 6))", (-1, -1, 5, 11))
    assert_same_polygons(geometries_of(r)[0], "POLYGON ((0 0, 5 0, 5 10, 0 10, 0 0), "
                                              "(2 2, 3 2, 3 3, 2 2), (3 6, 4 6, 4 7, 3 6))")
    assert r.stats.invalid_polygons == 0


def test_every_hole_of_a_polygon_touching_the_window_edges_is_kept():
    # The diamond's corners touch the window's edges: the rings go through the walk.
    r = ragged("POLYGON ((4 0, 0 4, -4 0, 0 -4, 4 0), (2 1, 1 0, 2 -1, 2 1), "
               "(0 0, -2 1, -2 -1, 0 0))", (-4, -4, 4, 4))
    assert_same_polygons(geometries_of(r)[0], "POLYGON ((4 0, 0 4, -4 0, 0 -4, 4 0), "
                                              "(2 1, 1 0, 2 -1, 2 1), (0 0, -2 1, -2 -1, 0 0))")
    assert r.stats.invalid_polygons == 0


def test_hole_touching_the_shell_on_the_window_edge_keeps_the_other_holes():
    # The first hole touches the shell at (2 0), on the window's right edge.
    polygon = ("POLYGON ((2 0, 2 3, -4 3, -4 -3, 2 -3, 2 0), (2 0, 1 1, 1 -1, 2 0), "
               "(0 0, -1 1, -1 -1, 0 0))")
    r = ragged(polygon, (-5, -4, 2, 4))
    assert_same_polygons(geometries_of(r)[0], polygon)
    assert r.stats.invalid_polygons == 0


def test_hole_pinched_between_shell_and_window_edge_splits_the_polygon():
    # The hole touches the shell at (1 6) (valid); the window's top edge y = 8 touches
    # the hole at (2 8): what is left falls apart into two polygons.
    got = clip_wkt("POLYGON ((4 7, 2 9, 0 7, 2 5, 4 7), (3 7, 2 8, 1 7, 1 6, 2 6, 3 7))",
                   (0, 0, 8, 8))
    assert shapely.is_valid(got), shapely.is_valid_reason(got)
    expected = shapely.from_wkt("MULTIPOLYGON (((4 7, 2 5, 1 6, 2 6, 3 7, 2 8, 3 8, 4 7)), "
                                "((1 8, 2 8, 1 7, 1 6, 0 7, 1 8)))")
    assert got.geom_type == "MultiPolygon" and len(got.geoms) == 2, got.wkt
    assert shapely.symmetric_difference(got, expected).area == 0.0, got.wkt


@pytest.mark.parametrize("window", [(-1, -1, 6, 5), (4, -1, 11, 2), (4.5, -1, 5.5, 4)])
def test_cut_hole_touching_its_shell_mid_edge_gives_a_valid_polygon(window):
    # The hole's vertex (5 0) lies inside the shell's bottom edge; the window cuts the
    # hole, so the walk joins shell and hole chains and must become a vertex there too.
    polygon = "POLYGON ((0 0, 10 0, 10 10, 0 10, 0 0), (5 0, 7 3, 3 3, 5 0))"
    got = clip_wkt(polygon, window)
    assert shapely.is_valid(got), shapely.is_valid_reason(got)
    expected = shapely.intersection(shapely.from_wkt(polygon), shapely.box(*window))
    assert shapely.symmetric_difference(got, expected).area < 1e-12, got.wkt
    assert got.area == pytest.approx(expected.area, abs=1e-12)


def test_hole_containing_the_window_gives_nothing():
    # GEOS's RectangleIntersectionTest 135.
    assert clip_wkt("POLYGON ((-2 -2, -2 12, 12 12, 12 -2, -2 -2), "
                    "(-1 -1, 11 -1, 11 11, -1 11, -1 -1))").is_empty


def test_hole_that_is_the_window_gives_nothing():
    # GEOS's GEOSClipByRectTest 10 (shapely.intersection gives the window's outline).
    assert clip_wkt("POLYGON ((-5 -5, 15 -5, 15 15, -5 15, -5 -5), "
                    "(0 0, 10 0, 10 10, 0 10, 0 0))").is_empty


def test_concave_u_shape_splits_into_two_polygons_without_a_bridge():
    u_shape = "POLYGON ((0 0, 10 0, 10 10, 7 10, 7 3, 3 3, 3 10, 0 10, 0 0))"
    got = clip_wkt(u_shape, (-1, 5, 11, 12))
    assert got.geom_type == "MultiPolygon"
    assert_same_polygons(got, "MULTIPOLYGON (((0 5, 3 5, 3 10, 0 10, 0 5)), "
                              "((7 5, 10 5, 10 10, 7 10, 7 5)))")
    assert_oriented(got)


def test_concave_u_shape_cut_inside_its_arms_gives_two_pieces_not_a_bridge():
    # Sutherland-Hodgman would join the arms along y = 5 with a zero-width bridge.
    got = clip_wkt("POLYGON ((0 0, 10 0, 10 10, 7 10, 7 3, 3 3, 3 10, 0 10, 0 0))",
                   (1, 5, 9, 12))
    assert_same_polygons(got, "MULTIPOLYGON (((1 5, 3 5, 3 10, 1 10, 1 5)), "
                              "((7 5, 9 5, 9 10, 7 10, 7 5)))")


def test_polygon_split_in_one_row_makes_every_row_multi():
    r = ragged("POLYGON ((1 1, 2 1, 2 2, 1 2, 1 1));"
               "POLYGON ((0 0, 10 0, 10 10, 7 10, 7 3, 3 3, 3 10, 0 10, 0 0))", (-1, 5, 11, 12),
               keep_empty=True)
    assert r.geometry_type == GeometryType.MULTIPOLYGON
    got = geometries_of(r)
    assert got[0].is_empty and len(shapely.get_parts(got[1])) == 2


def test_clockwise_shell_comes_back_counter_clockwise():
    got = clip_wkt("POLYGON ((-1 -1, -1 5, 5 5, 5 -1, -1 -1))")
    assert_same_polygons(got, "POLYGON ((0 0, 5 0, 5 5, 0 5, 0 0))")
    assert_oriented(got)


def test_polygon_with_z_gets_z_on_the_window_corners_it_gains():
    # GEOS's GEOSClipByRectTest 22: a constant Z stays constant, corners included.
    got = clip_wkt("POLYGON Z ((0 0 100, 0 30 100, 30 30 100, 30 0 100, 0 0 100))",
                   (5, 5, 15, 15))
    xyz = shapely.get_coordinates(got, include_z=True)
    assert len(xyz) == 5
    np.testing.assert_array_equal(xyz[:, 2], 100.0)


def test_polygon_edges_on_the_window_boundary_keep_the_z_of_the_input():
    # The shell's corner (0 0) is a window corner and its edges x = 0, y = 0 run along
    # window edges: (0 0) keeps its Z, (0 2) is interpolated along the edge x = 0.
    got = clip_wkt("POLYGON Z ((0 0 10, 3 0 20, 3 3 30, 0 3 40, 0 0 10))", (0, 0, 4, 2))
    z_at = {(x, y): z for x, y, z in shapely.get_coordinates(got, include_z=True)}
    assert set(z_at) == {(0, 0), (3, 0), (3, 2), (0, 2)}
    assert z_at[0, 0] == 10 and z_at[3, 0] == 20
    assert z_at[3, 2] == pytest.approx(20 + 10 * 2 / 3, rel=1e-15)
    assert z_at[0, 2] == pytest.approx(30, rel=1e-15)


def test_self_intersecting_polygon_is_clipped_ring_by_ring_and_counted():
    bowtie = "POLYGON ((0 0, 10 10, 10 0, 0 10, 0 0))"
    r = ragged(bowtie, (-1, -1, 5, 11))
    assert r.stats.invalid_polygons == 1
    # The cut end and the next start meet at the crossing (5 5): a repeated vertex there
    # is allowed (ring-by-ring clipping does not tidy invalid input).
    got = shapely.remove_repeated_points(geometries_of(r)[0])
    assert_same_polygons(got, "POLYGON ((0 0, 5 5, 0 10, 0 0))")


def test_self_intersecting_polygon_inside_is_not_repaired_and_is_counted():
    bowtie = "POLYGON ((0 0, 10 10, 10 0, 0 10, 0 0))"
    r = ragged(bowtie, (-1, -1, 11, 11))
    assert r.stats.invalid_polygons == 1
    got = geometries_of(r)[0]
    assert shapely.equals_exact(shapely.normalize(got), shapely.normalize(
        shapely.from_wkt(bowtie)), 0.0), got.wkt


def test_valid_polygons_are_not_counted_as_invalid():
    r = ragged("POLYGON ((-5 -5, 15 -5, 15 15, -5 15, -5 -5), (4 4, 6 4, 6 6, 4 6, 4 4))")
    assert r.stats.invalid_polygons == 0


def test_approx_mode_is_refused_for_polygons():
    with pytest.raises(InvalidOptionError, match="approx"):
        ragged("POLYGON ((1 1, 4 1, 4 4, 1 4, 1 1))", mode="approx")


# --- empties -------------------------------------------------------------------------------

EMPTIES = ["POINT EMPTY", "LINESTRING EMPTY", "POLYGON EMPTY", "MULTIPOINT EMPTY",
           "MULTILINESTRING EMPTY", "MULTIPOLYGON EMPTY"]


@pytest.mark.parametrize("boundary", ["closed", "interior"])
@pytest.mark.parametrize("wkt", EMPTIES)
def test_empty_geometry_gives_an_empty_result(wkt, boundary):
    dropped = ragged(wkt, boundary=boundary)
    assert dropped.source.size == 0
    kept = ragged(wkt, boundary=boundary, keep_empty=True)
    np.testing.assert_array_equal(kept.source, [0])
    assert geometries_of(kept)[0].is_empty


@pytest.mark.parametrize("wkt", EMPTIES + ["GEOMETRYCOLLECTION EMPTY"])
def test_empty_shapely_geometry_clips_to_an_empty_geometry(wkt):
    got = rnsca.clip(shapely.from_wkt(wkt), W)
    assert isinstance(got, shapely.Geometry) and got.is_empty


# --- errors --------------------------------------------------------------------------------

BAD_VALUES = [math.nan, math.inf, -math.inf]


@pytest.mark.parametrize("bad", BAD_VALUES, ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("wkt", ["LINESTRING (1 1, 2 2)", "POLYGON ((1 1, 4 1, 4 4, 1 1))",
                                 "MULTIPOINT ((1 1), (2 2))", "POINT (1 1)"])
def test_non_finite_coordinate_raises_naming_the_geometry(wkt, bad):
    geometries = [shapely.from_wkt(wkt)] * 4
    kind, coords, offsets = shapely.to_ragged_array(geometries)
    coords = coords.copy()
    per = coords.shape[0] // 4
    coords[2 * per + 1 if per > 1 else 2, 0] = bad
    with pytest.raises(InvalidGeometryError, match=r"geometry 2\b") as info:
        clip_ragged(kind, coords, offsets, W)
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("wkt", ["LINESTRING Z (1 1 1, 2 2 2)",
                                 "POLYGON Z ((1 1 1, 4 1 1, 4 4 1, 1 1 1))",
                                 "MULTIPOINT Z ((1 1 1), (2 2 2))"])
def test_nan_z_is_taken_only_with_partial_z_and_infinite_z_never(wkt):
    geometries = [shapely.from_wkt(wkt)] * 3
    kind, coords, offsets = shapely.to_ragged_array(geometries)
    per = coords.shape[0] // 3
    coords = coords.copy()
    coords[per + 1, 2] = math.nan
    with pytest.raises(InvalidGeometryError, match=r"geometry 1\b"):
        clip_ragged(kind, coords, offsets, W)
    result = clip_ragged(kind, coords, offsets, W, partial_z=True)
    np.testing.assert_array_equal(result.coords, coords)  # all inside: as they came
    for bad in (math.inf, -math.inf):
        coords[per + 1, 2] = bad
        with pytest.raises(InvalidGeometryError, match=r"geometry 1\b"):
            clip_ragged(kind, coords, offsets, W, partial_z=True)
    coords[per + 1, 2] = 0.0
    coords[per + 1, 0] = math.nan
    with pytest.raises(InvalidGeometryError, match=r"geometry 1\b"):
        clip_ragged(kind, coords, offsets, W, partial_z=True)


def test_a_nan_z_spreads_to_the_vertices_computed_from_it():
    coords = np.array([[-5.0, 5.0, math.nan], [5.0, 5.0, 1.0], [15.0, 5.0, 3.0],
                       [15.0, 8.0, math.nan]])
    line = clip_ragged("LINESTRING", coords, (np.array([0, 4]),), W, partial_z=True)
    np.testing.assert_array_equal(line.coords, [[0, 5, math.nan], [5, 5, 1], [10, 5, 2]])
    ring = np.array([[-5.0, -5.0, 1.0], [5.0, -5.0, math.nan], [5.0, 5.0, 2.0],
                     [-5.0, 5.0, 2.0], [-5.0, -5.0, 1.0]])
    polygon = clip_ragged("POLYGON", ring, (np.array([0, 5]), np.array([0, 1])), W,
                          partial_z=True)
    np.testing.assert_array_equal(polygon.coords, [[5, 0, math.nan], [5, 5, 2], [0, 5, 2],
                                                   [0, 0, math.nan], [5, 0, math.nan]])
    assert rnsca.verify((GeometryType.POLYGON, ring, (np.array([0, 5]), np.array([0, 1]))),
                        polygon, W).passed


def test_non_finite_coordinate_in_a_shapely_array_raises_naming_the_geometry():
    geometries = np.array([shapely.from_wkt("LINESTRING (1 1, 2 2)"),
                           shapely.from_wkt(f"LINESTRING (1 1, {math.inf} 2)")])
    with pytest.raises(ValueError, match=r"geometry 1\b"):
        rnsca.clip(geometries, W)


def test_unknown_geometry_type_raises_unsupported():
    with pytest.raises(UnsupportedGeometryError, match="CircularString"):
        clip_ragged("CircularString", np.zeros((2, 2)), (np.array([0, 2]),), W)
    assert issubclass(UnsupportedGeometryError, TypeError)
    assert issubclass(UnsupportedGeometryError, ValueError)


@pytest.mark.parametrize("name", ["linestring", "LINESTRING", "LineString",
                                  GeometryType.LINESTRING])
def test_geometry_type_is_taken_by_name_case_insensitively(name):
    r = clip_ragged(name, np.array([[-5.0, 5.0], [15.0, 5.0]]), (np.array([0, 2]),), W)
    np.testing.assert_array_equal(r.coords, [[0, 5], [10, 5]])


def test_window_array_of_the_wrong_length_raises():
    with pytest.raises(InvalidWindowError, match=r"\(2, 4\)"):
        ragged("LINESTRING (1 1, 2 2);LINESTRING (3 3, 4 4)", np.array([W, W, W]))


def test_invalid_row_of_a_window_array_raises_naming_it():
    with pytest.raises(InvalidWindowError, match="window 1"):
        ragged("LINESTRING (1 1, 2 2);LINESTRING (3 3, 4 4)", np.array([W, (5, 0, 5, 1)]))


# --- batches -------------------------------------------------------------------------------

def test_each_geometry_is_clipped_by_its_own_window():
    r = ragged("LINESTRING (-5 5, 15 5);LINESTRING (-5 5, 15 5);LINESTRING (-5 5, 15 5)",
               np.array([[0, 0, 10, 10], [2, 0, 3, 10], [20, 0, 30, 10]], dtype=float))
    np.testing.assert_array_equal(r.coords, [[0, 5], [10, 5], [2, 5], [3, 5]])
    np.testing.assert_array_equal(r.source, [0, 1])


def test_keep_empty_keeps_one_output_per_input_in_order():
    r = ragged("LINESTRING (20 20, 30 30);LINESTRING (-5 5, 15 5);"
               "LINESTRING (2 2, 12 2, 12 8, 2 8)", keep_empty=True)
    np.testing.assert_array_equal(r.source, [0, 1, 2])
    got = geometries_of(r)
    assert got[0].is_empty
    assert got[1].wkt == "MULTILINESTRING ((0 5, 10 5))"
    assert got[2].wkt == "MULTILINESTRING ((2 2, 10 2), (10 8, 2 8))"


def test_stats_count_geometries_vertices_and_runs():
    r = ragged("LINESTRING (2 2, 12 2, 12 8, 2 8);LINESTRING (20 20, 30 30)")
    s = r.stats
    assert (s.geometries_in, s.geometries_out, s.vertices_in, s.vertices_out) == (2, 1, 6, 4)
    # Each run evaluated is copied whole, skipped whole, split, or clipped segment by segment.
    assert s.runs_evaluated == (s.runs_accepted + s.runs_rejected + s.runs_subdivided
                                + s.runs_segmented) > 0
    assert sum(s.runs_decided_per_level) == s.runs_accepted + s.runs_rejected + s.runs_segmented
    assert s.to_dict()["invalid_polygons"] == 0


# --- rnsca.clip: the forms it takes --------------------------------------------------------

def test_clip_takes_a_shapely_geometry_and_returns_one():
    got = rnsca.clip(shapely.from_wkt("LINESTRING (-5 5, 15 5)"), W)
    assert isinstance(got, shapely.Geometry)
    assert got.wkt == "LINESTRING (0 5, 10 5)"


def test_clip_takes_an_array_and_returns_an_aligned_array():
    geometries = np.array([shapely.from_wkt("LINESTRING (20 20, 30 30)"),
                           shapely.from_wkt("LINESTRING (-5 5, 15 5)")])
    got = rnsca.clip(geometries, W)
    assert isinstance(got, np.ndarray) and got.shape == (2,)
    assert got[0].is_empty
    assert shapely.equals(got[1], shapely.from_wkt("LINESTRING (0 5, 10 5)"))


def test_clip_takes_empty_points_in_an_array():
    # shapely.to_ragged_array writes an empty point as a NaN row.
    got = rnsca.clip(np.array([shapely.Point(), shapely.Point(1, 2), shapely.Point(20, 2)]), W)
    assert got[0].is_empty and got[1].wkt == "POINT (1 2)" and got[2].is_empty


def test_clip_takes_a_ragged_triple_and_returns_a_ragged_result():
    triple = shapely.to_ragged_array([shapely.from_wkt("LINESTRING (-5 5, 15 5)")])
    got = rnsca.clip(triple, W)
    assert isinstance(got, rnsca.RaggedClipResult)
    np.testing.assert_array_equal(got.coords, [[0, 5], [10, 5]])


def test_clip_takes_a_window_object_and_an_array_of_windows():
    line = shapely.from_wkt("LINESTRING (-5 5, 15 5)")
    assert rnsca.clip(line, Window(2, 0, 3, 10)).wkt == "LINESTRING (2 5, 3 5)"
    got = rnsca.clip(np.array([line, line]), np.array([[0, 0, 1, 10], [4, 0, 5, 10]], float))
    assert [g.wkt for g in got] == ["LINESTRING (0 5, 1 5)", "LINESTRING (4 5, 5 5)"]


def test_clip_error_message_names_what_is_wrong():
    with pytest.raises(InvalidWindowError, match=re.escape("xmin < xmax")):
        rnsca.clip(shapely.from_wkt("LINESTRING (1 1, 2 2)"), (5, 0, 5, 1))


@pytest.mark.parametrize("where", ["inside", "outside"])
def test_a_nan_vertex_is_an_error_even_where_the_box_decides(where):
    """GEOS leaves NaN out of bounds: a box inside (or beyond) the window is no excuse."""
    import shapely

    offset = 0.0 if where == "inside" else 100.0
    bad = shapely.LineString([(1 + offset, 1), (np.nan, 2), (3 + offset, 3)])
    good = shapely.LineString([(1, 1), (2, 2)])
    with pytest.raises(InvalidGeometryError, match=r"geometry 1 has a non-finite coordinate"):
        rnsca.clip(np.array([good, bad]), (0, 0, 10, 10))
