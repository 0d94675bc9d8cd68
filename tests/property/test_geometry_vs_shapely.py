"""Whole geometries against Shapely, the spec: ``shapely.intersection`` for
``boundary="closed"`` and ``shapely.clip_by_rect`` for ``boundary="interior"``; lines also
against exact rational arithmetic.

Each example is 1 to 3 geometries of one kind (points, multipoints, lines, multilines,
star polygons with holes, combs, multipolygons of disjoint stars; 2D or with Z) and one
window placed against them (`tests.property.geometry_strategies`). They are clipped as an
array of Shapely geometries (`rnsca.clip`), and each output geometry is checked with
`tests.geometry_checks.assert_matches_shapely`: every vertex in the closed window, only
parts of the input's dimension, polygons valid, and equal to the parts of Shapely's
result with the input's dimension (normalized; Hausdorff distance within 1e-9 of the
window's size; line lengths, polygon symmetric-difference areas, point sets as there).
Inputs where GEOS's own answer is not accurate to 1e-9 of the window (a segment nearly
parallel to an edge; for lines, any answer that differs from exact arithmetic, as where
a line runs back over itself a sub-ulp distance away: see
`tests.geometry_checks.shapely_can_judge`) are left out of the Shapely comparisons;
`test_lines_equal_exact_arithmetic` takes every input and compares lines with their clip
in exact rational arithmetic, segment by segment. The same inputs clipped through
`rnsca.clip_ragged` are compared with these in `test_geometry_invariants.py`.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import rnsca
from tests.geometry_checks import (
    TOLERANCE,
    assert_equal_geometry,
    assert_inside_window,
    assert_matches_shapely,
    exact_line_clip,
    parts_of_dimension,
    shapely_can_judge,
)
from tests.property.geometry_strategies import cases

BOUNDARIES = ["closed", "interior"]


def _check(geometries, window, boundary):
    assume(shapely_can_judge(geometries, window, boundary))
    ours = rnsca.clip(np.array(geometries, dtype=object), window, boundary=boundary)
    assert isinstance(ours, np.ndarray) and ours.shape == (len(geometries),), ours
    for i, (got, geometry) in enumerate(zip(ours, geometries, strict=True)):
        assert isinstance(got, shapely.Geometry), got
        assert_matches_shapely(got, geometry, window, boundary, where=f"geometry {i}")


@pytest.mark.parametrize("boundary", BOUNDARIES)
@given(case=cases("point", z=None))
def test_points_equal_shapely(case, boundary):
    _check(*case, boundary)


@pytest.mark.parametrize("boundary", BOUNDARIES)
@given(case=cases("multipoint", z=None))
def test_multipoints_equal_shapely(case, boundary):
    _check(*case, boundary)


@pytest.mark.parametrize("boundary", BOUNDARIES)
@given(case=cases("linestring", z=None))
def test_lines_equal_shapely(case, boundary):
    _check(*case, boundary)


@pytest.mark.parametrize("boundary", BOUNDARIES)
@given(case=cases("multilinestring", z=None))
def test_multilines_equal_shapely(case, boundary):
    _check(*case, boundary)


# Polygons carry the most machinery (ring walk, holes, combs): twice the profile's examples.
@pytest.mark.parametrize("boundary", BOUNDARIES)
@settings(max_examples=2 * settings.default.max_examples)
@given(case=cases("polygon", z=None))
def test_polygons_with_holes_and_combs_equal_shapely(case, boundary):
    _check(*case, boundary)


@pytest.mark.parametrize("boundary", BOUNDARIES)
@given(case=cases("multipolygon", z=None))
def test_multipolygons_equal_shapely(case, boundary):
    _check(*case, boundary)


# Lines against exact rational arithmetic, including the inputs GEOS cannot judge.
@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ["linestring", "multilinestring"])
@given(data=st.data())
def test_lines_equal_exact_arithmetic(kind, boundary, data):
    geometries, window = data.draw(cases(kind))
    ours = rnsca.clip(np.array(geometries, dtype=object), window, boundary=boundary)
    for i, (got, geometry) in enumerate(zip(ours, geometries, strict=True)):
        where = f"geometry {i} {boundary} clip of {geometry.wkt} to {window.bounds}"
        assert_inside_window(got, window, where)
        assert_equal_geometry(parts_of_dimension(got, 1),
                              exact_line_clip(geometry, window, boundary),
                              TOLERANCE * window.size, where)
