"""Lines and polygons on OpenCL give what the Numba backend gives: the same chains and
rings, coordinates equal to 1e-12 in float64, the same sources, offsets and counters.

On OpenCL the run-level pruning of lines and rings (chunk boxes, RNSCA over runs of
chunks) and the clip of the undecided chunks' segments run on the device, and the chains
(and, for polygons, the walk along the window) are assembled on the host; on Numba all
of it runs in one kernel. Inputs: the adversarial strategies of the geometry tests
(vertices on edges and corners, an ulp either side, frames from 1e-300 to 1e300; stars
with holes, combs), every method, mode and boundary rule, with and without Z, and long
random walks whose runs are pruned several levels deep.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

import rnsca
from rnsca import Method, Mode
from rnsca.ragged import clip_ragged
from tests.property.geometry_strategies import cases

pytestmark = pytest.mark.opencl


def assert_geometry_agrees(triple, window, **options):
    """The ragged clip of `triple` is the same on Numba and OpenCL."""
    where = f"{options} window={window}"
    ref = clip_ragged(*triple, window, backend="numba", **options)
    got = clip_ragged(*triple, window, backend="opencl", **options)
    assert got.geometry_type == ref.geometry_type, where
    np.testing.assert_array_equal(got.source, ref.source, err_msg=where)
    assert len(got.offsets) == len(ref.offsets), where
    for a, b in zip(got.offsets, ref.offsets, strict=True):
        np.testing.assert_array_equal(a, b, err_msg=where)
    np.testing.assert_allclose(got.coords, ref.coords, rtol=1e-12, atol=0, err_msg=where)
    assert dataclasses.replace(got.stats, device=None) == ref.stats, where
    assert got.stats.device is not None


@settings(max_examples=40, deadline=None)
@given(data=st.data(), kind=st.sampled_from(["linestring", "multilinestring"]),
       method=st.sampled_from(list(Method)), mode=st.sampled_from(list(Mode)),
       boundary=st.sampled_from(["closed", "interior"]), z=st.booleans())
def test_drawn_lines_agree(opencl, data, kind, method, mode, boundary, z):
    geometries, window = data.draw(cases(kind, z=z))
    triple = shapely.to_ragged_array(np.array(geometries, dtype=object), include_z=z)
    assert_geometry_agrees(triple, window, method=method, mode=mode, boundary=boundary,
                       keep_empty=True)


def _walks(rng, count, vertices, scale=1.0):
    steps = rng.normal(size=(count * vertices, 2)) * scale
    coords = steps.cumsum(axis=0)
    return [shapely.LineString(coords[i * vertices:(i + 1) * vertices]) for i in range(count)]


@pytest.mark.parametrize("window", [(0.0, 0.0, 10.0, 10.0), (-30.0, -30.0, 30.0, 30.0),
                                    (-1e4, -1e4, 1e4, 1e4), (1e4, 1e4, 2e4, 2e4)])
@pytest.mark.parametrize("n", ["auto", 2, 5, 64])
def test_long_walks_pruned_deep_agree(opencl, rng, window, n):
    lines = _walks(rng, 6, 3000) + [shapely.LineString([(0, 0), (1, 1)]),
                                    shapely.LineString([(-5, 1), (5, 1), (5, 20), (8, 20)])]
    triple = shapely.to_ragged_array(np.array(lines, dtype=object))
    for boundary in ("closed", "interior"):
        assert_geometry_agrees(triple, window, n=n, boundary=boundary)
    r = clip_ragged(*triple, window, n=n, backend="opencl")
    assert r.stats.runs_subdivided > 0 or window[2] >= 1e4


def test_a_window_per_geometry_agrees(opencl, rng):
    lines = _walks(rng, 20, 200)
    triple = shapely.to_ragged_array(np.array(lines, dtype=object))
    windows = rng.uniform(-10.0, 0.0, size=(20, 2))
    windows = np.hstack([windows, windows + rng.uniform(1.0, 20.0, size=(20, 2))])
    assert_geometry_agrees(triple, windows)


def test_lines_through_rnsca_clip_on_opencl():
    line = shapely.LineString([(-5, 1), (5, 1), (5, 20), (8, 20), (8, 5), (15, 5)])
    assert rnsca.clip(line, (0, 0, 10, 10), backend="opencl").wkt == \
        "MULTILINESTRING ((0 1, 5 1, 5 10), (8 10, 8 5, 10 5))"


def test_empty_lines_agree(opencl):
    triple = shapely.to_ragged_array(np.array([shapely.LineString(), shapely.LineString(
        [(1, 1), (2, 2)]), shapely.LineString()], dtype=object))
    assert_geometry_agrees(triple, (0.0, 0.0, 10.0, 10.0), keep_empty=True)
    nothing = shapely.to_ragged_array(np.array([shapely.LineString()], dtype=object))
    assert_geometry_agrees(nothing, (0.0, 0.0, 10.0, 10.0), keep_empty=True)


@settings(max_examples=40, deadline=None)
@given(data=st.data(), kind=st.sampled_from(["polygon", "multipolygon"]),
       method=st.sampled_from(list(Method)), z=st.booleans())
def test_drawn_polygons_agree(opencl, data, kind, method, z):
    geometries, window = data.draw(cases(kind, z=z))
    triple = shapely.to_ragged_array(np.array(geometries, dtype=object), include_z=z)
    assert_geometry_agrees(triple, window, method=method, keep_empty=True)


def test_many_polygons_with_holes_agree(opencl, rng):
    polygons = []
    for _ in range(300):
        centre = rng.uniform(0.0, 100.0, 2)
        radius = rng.uniform(1.0, 30.0)
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, 80))
        r = radius * rng.uniform(0.5, 1.0, 80)
        shell = np.c_[centre[0] + r * np.cos(angles), centre[1] + r * np.sin(angles)]
        hole = np.c_[centre[0] + 0.2 * radius * np.cos(angles[::8]),
                     centre[1] + 0.2 * radius * np.sin(angles[::8])]
        polygons.append(shapely.Polygon(shell, [hole]))
    polygons.append(shapely.box(-10.0, -10.0, 200.0, 200.0))  # contains the window
    triple = shapely.to_ragged_array(np.array(polygons, dtype=object))
    for window in [(25.0, 25.0, 75.0, 75.0), (10.0, 30.0, 13.0, 90.0), (-1.0, -1.0, 101.0, 101.0)]:
        for n in ("auto", 3):
            assert_geometry_agrees(triple, window, n=n)


def test_polygons_through_rnsca_clip_on_opencl(opencl):
    square = shapely.Polygon([(-5, -5), (5, -5), (5, 5), (-5, 5)], [[(1, 1), (1, 2), (2, 2),
                                                                      (2, 1)]])
    assert rnsca.clip(square, (0, 0, 10, 10), backend="opencl").normalize().equals(
        rnsca.clip(square, (0, 0, 10, 10), backend="numba").normalize())
