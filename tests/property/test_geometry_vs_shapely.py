"""Whole geometries against Shapely, the spec: ``shapely.intersection`` for
``boundary="closed"`` and ``shapely.clip_by_rect`` for ``boundary="interior"``.

Each example is 1 to 3 geometries of one kind (points, multipoints, lines, multilines,
star polygons with holes, combs, multipolygons of disjoint stars; 2D or with Z) and one
window placed against them (`tests.property.geometry_strategies`). They are clipped as an
array of Shapely geometries (`rnsca.clip`), and each output geometry is checked with
`tests.geometry_checks.assert_matches_shapely`: every vertex in the closed window, only
parts of the input's dimension, polygons valid, and equal to the parts of Shapely's
result with the input's dimension (normalized; Hausdorff distance within 1e-9 of the
window's size; line lengths, polygon symmetric-difference areas, point sets as there).
The same inputs clipped through `rnsca.clip_ragged` are compared with these in
`test_geometry_invariants.py`.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings

import rnsca
from tests.geometry_checks import assert_matches_shapely
from tests.property.geometry_strategies import cases

BOUNDARIES = ["closed", "interior"]


def _check(geometries, window, boundary):
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
