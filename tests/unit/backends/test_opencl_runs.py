"""Lines and rings on OpenCL in ranges: the device prunes one range while the host assembles
the one before (`rnsca.backends.opencl.runs`).

A call cut into many ranges gives the Numba backend's output bit for bit, as one range
does (tests/property/test_geometry_backends_agree.py checks the one-range calls on the
adversarial strategies, and here the same with ranges of a few vertices). The cut itself
(`ranges_by_vertices`) covers every item once, in order, in balanced non-empty ranges.
"""

from __future__ import annotations

import dataclasses
from contextlib import contextmanager
from unittest.mock import patch

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rnsca.ragged import clip_ragged
from tests.property.geometry_strategies import cases

pytestmark = pytest.mark.opencl


@pytest.fixture(scope="module")
def runs(opencl):
    from rnsca.backends.opencl import runs as module

    return module


@contextmanager
def ranges_of(runs, vertices: int):
    """Cut OpenCL line and ring calls into ranges of about `vertices`; count the ranges."""
    finished = []
    original = runs.RunCall.finish

    def finish(call, r):
        finished.append(r.part_offsets.shape[0] - 1)
        return original(call, r)

    with patch.object(runs, "PIPELINE_VERTICES", vertices), \
            patch.object(runs.RunCall, "finish", finish):
        yield finished


def assert_same(triple, window, **options):
    ref = clip_ragged(*triple, window, backend="numba", **options)
    got = clip_ragged(*triple, window, backend="opencl", **options)
    np.testing.assert_array_equal(got.coords, ref.coords)
    np.testing.assert_array_equal(got.source, ref.source)
    assert len(got.offsets) == len(ref.offsets)
    for a, b in zip(got.offsets, ref.offsets, strict=True):
        np.testing.assert_array_equal(a, b)
    assert dataclasses.replace(got.stats, device=None) == ref.stats


# --- the cut --------------------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(sizes=st.lists(st.integers(0, 50), max_size=80), target=st.integers(1, 200))
def test_ranges_cover_every_item_once_in_order(runs, sizes, target):
    ends = np.cumsum(np.array(sizes, dtype=np.int64))
    ranges = runs.ranges_by_vertices(ends, target)
    if not sizes:
        assert ranges == []
        return
    assert ranges[0][0] == 0 and ranges[-1][1] == len(sizes)
    assert all(a < b for a, b in ranges)  # none empty
    assert all(ranges[i][1] == ranges[i + 1][0] for i in range(len(ranges) - 1))
    assert len(ranges) <= runs.MAX_RANGES
    if int(ends[-1]) <= target:
        assert len(ranges) == 1


def test_ranges_share_the_vertices_evenly(runs):
    ends = np.cumsum(np.full(1000, 7, dtype=np.int64))
    ranges = runs.ranges_by_vertices(ends, 700)
    assert len(ranges) == 10
    assert {b - a for a, b in ranges} == {100}
    # Never more than MAX_RANGES, however small the target.
    assert len(runs.ranges_by_vertices(ends, 1)) == runs.MAX_RANGES


# --- lines and polygons in ranges, against Numba -------------------------------------

def _walks(rng, count, vertices):
    coords = rng.normal(size=(count * vertices, 2)).cumsum(axis=0)
    return [shapely.LineString(coords[i * vertices:(i + 1) * vertices]) for i in range(count)]


def _stars(rng, count):
    polygons = []
    for _ in range(count):
        centre = rng.uniform(0.0, 100.0, 2)
        radius = rng.uniform(1.0, 30.0)
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, 40))
        r = radius * rng.uniform(0.5, 1.0, 40)
        shell = np.c_[centre[0] + r * np.cos(angles), centre[1] + r * np.sin(angles)]
        hole = np.c_[centre[0] + 0.2 * radius * np.cos(angles[::8]),
                     centre[1] + 0.2 * radius * np.sin(angles[::8])]
        polygons.append(shapely.Polygon(shell, [hole]))
    return polygons


@pytest.mark.parametrize("vertices", [1, 50, 400, 10**9])
def test_lines_in_ranges_are_the_numba_lines(runs, rng, vertices):
    lines = _walks(rng, 40, 300) + [shapely.LineString(), shapely.LineString([(0, 0), (1, 1)])]
    triple = shapely.to_ragged_array(np.array(lines, dtype=object))
    with ranges_of(runs, vertices) as finished:
        for window in [(0.0, 0.0, 10.0, 10.0), (-30.0, -30.0, 30.0, 30.0)]:
            assert_same(triple, window, keep_empty=True)
            assert_same(triple, window, n=3, boundary="interior", keep_empty=True)
    expected = 1 if vertices == 10**9 else min(runs.MAX_RANGES, -(-len(triple[1]) // vertices))
    assert len(finished) == 4 * expected


@pytest.mark.parametrize("vertices", [1, 300, 10**9])
def test_polygons_in_ranges_are_the_numba_polygons(runs, rng, vertices):
    polygons = _stars(rng, 200) + [shapely.box(-10.0, -10.0, 200.0, 200.0), shapely.Polygon()]
    triple = shapely.to_ragged_array(np.array(polygons, dtype=object))
    with ranges_of(runs, vertices) as finished:
        for window in [(25.0, 25.0, 75.0, 75.0), (10.0, 30.0, 13.0, 90.0)]:
            assert_same(triple, window, keep_empty=True)
    assert (len(finished) > 2) == (vertices < 10**9)


def test_a_window_per_geometry_in_ranges(runs, rng):
    lines = _walks(rng, 30, 100)
    triple = shapely.to_ragged_array(np.array(lines, dtype=object))
    low = rng.uniform(-10.0, 0.0, size=(30, 2))
    windows = np.hstack([low, low + rng.uniform(1.0, 20.0, size=(30, 2))])
    with ranges_of(runs, 200) as finished:
        assert_same(triple, windows)
    assert len(finished) > 1


@settings(max_examples=40, deadline=None)
@given(data=st.data(), kind=st.sampled_from(["linestring", "multilinestring", "polygon",
                                             "multipolygon"]),
       vertices=st.integers(1, 40), z=st.booleans())
def test_drawn_geometries_in_ranges_agree(runs, data, kind, vertices, z):
    geometries, window = data.draw(cases(kind, z=z))
    triple = shapely.to_ragged_array(np.array(geometries, dtype=object), include_z=z)
    with ranges_of(runs, vertices):
        assert_same(triple, window, keep_empty=True)


# --- the pipeline's order: the device is given work before the host waits ---------------

class _Recorder:
    """A stand-in for `RunCall` that records the order of the pipeline's steps."""

    def __init__(self):
        self.steps = []

    def start(self, item):
        self.steps.append(("start", item))
        return item

    def clip(self, item):
        self.steps.append(("clip", item))

    def finish(self, item):
        self.steps.append(("finish", item))
        return f"tables {item}"


@pytest.mark.parametrize("n", [0, 1, 2, 3, 6])
def test_the_device_is_two_ranges_ahead_of_the_host(runs, n):
    call = _Recorder()
    yielded = []
    for item, tables in runs.pipelined(call, range(n), call.start):
        assert tables == f"tables {item}"
        # While the host works on `item`, the next range is clipped and the one after
        # started (where there are such ranges).
        done = {step for step in call.steps}
        if item + 1 < n:
            assert ("clip", item + 1) in done
        if item + 2 < n:
            assert ("start", item + 2) in done
        assert ("finish", item + 1) not in done
        yielded.append(item)
    assert yielded == list(range(n))
    # Each range is started, clipped and finished once, in that order.
    for item in range(n):
        order = [s for s in call.steps if s[1] == item]
        assert order == [("start", item), ("clip", item), ("finish", item)]
