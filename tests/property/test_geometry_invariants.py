"""Invariants of geometry clipping that need no oracle beyond the input itself.

- Z is kept on the input's vertices and linearly interpolated on new ones;
- an (G, 4) window array clips each geometry with its own window, as if alone;
- ``keep_empty=True`` gives one output per input, in order, empty where nothing is
  left; ``keep_empty=False`` drops those, and its ``source`` says which survived;
- clipping the output again changes nothing (geometrically);
- `rnsca.clip_ragged` on ``shapely.to_ragged_array`` arrays gives the very coordinates
  `rnsca.clip` gives on the Shapely objects;
- a geometry inside the window comes back unchanged (lines and points vertex for
  vertex, polygons as the same area: see `test_geometry_inside_the_window_is_unchanged`);
  one beyond a side gives nothing;
- line parts come in the input's order and direction;
- polygon shells are counter-clockwise and holes clockwise (RFC 7946);
- the output kind follows the input kind (POINT stays POINT, MULTI* stays MULTI*,
  LINESTRING and POLYGON become MULTI* only when some output has several parts);
- the stats count geometries and vertices in and out, and no invalid polygon among
  valid inputs.

Inputs come from `tests.property.geometry_strategies`; comparisons from
`tests.geometry_checks`.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st
from shapely import GeometryType

import rnsca
from rnsca import Window
from tests.geometry_checks import (
    TOLERANCE,
    assert_equal_geometry,
    assert_inside_window,
    assert_z_on_input,
    dimension_of_type,
    flat_parts,
    geometries_of,
    parts_of_dimension,
)
from tests.property.geometry_strategies import (
    cases,
    frames,
    monotone_lines,
    stars,
    window_for,
)

BOUNDARIES = ["closed", "interior"]
ALL_KINDS = ["point", "multipoint", "linestring", "multilinestring", "polygon", "multipolygon"]
SHAPED_KINDS = ["linestring", "multilinestring", "polygon", "multipolygon"]


def _array(geometries) -> np.ndarray:
    return np.array(geometries, dtype=object)


def _same_geometry(ours, expected, window, where=""):
    if ours.is_empty and expected.is_empty:
        return
    dimension = max(dimension_of_type(ours), dimension_of_type(expected))
    assert_equal_geometry(parts_of_dimension(ours, dimension),
                          parts_of_dimension(expected, dimension),
                          TOLERANCE * Window.of(window).size, where)


def _identical_parts(a, b, where=""):
    """Check that two geometries have the same parts with bitwise equal coordinates."""
    pa, pb = flat_parts(a), flat_parts(b)
    assert len(pa) == len(pb), f"{where}: {len(pa)} parts vs {len(pb)}: {a.wkt} / {b.wkt}"
    for x, y in zip(pa, pb, strict=True):
        assert x.geom_type == y.geom_type, f"{where}: {x.wkt} / {y.wkt}"
        np.testing.assert_array_equal(shapely.get_coordinates(x, include_z=True),
                                      shapely.get_coordinates(y, include_z=True),
                                      err_msg=where)


# --- Z -------------------------------------------------------------------------------------

@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_z_is_kept_on_vertices_and_interpolated_on_new_ones(kind, boundary, data):
    geometries, window = data.draw(cases(kind, z=True))
    ours = rnsca.clip(_array(geometries), window, boundary=boundary)
    for i, (got, geometry) in enumerate(zip(ours, geometries, strict=True)):
        if not got.is_empty:
            assert shapely.has_z(got), f"geometry {i} lost its Z: {got.wkt}"
        assert_z_on_input(got, geometry, window, where=f"geometry {i}")


# --- batch windows, keep_empty, idempotence, the two paths ---------------------------------

@st.composite
def batches_with_windows(draw, kind):
    """Return geometries of one kind, each from its own frame, and one window each."""
    drawn = draw(st.lists(cases(kind, max_geometries=1, z=False), min_size=1, max_size=4))
    geometries = [g for gs, _ in drawn for g in gs]
    windows = np.array([w.bounds for _, w in drawn], dtype=np.float64)
    return geometries, windows


@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_window_per_geometry_equals_clipping_each_alone(kind, data):
    geometries, windows = data.draw(batches_with_windows(kind))
    batch = rnsca.clip(_array(geometries), windows)
    ragged = rnsca.clip_ragged(*shapely.to_ragged_array(_array(geometries)), windows,
                               keep_empty=True)
    rebuilt = geometries_of(ragged)
    for i, geometry in enumerate(geometries):
        alone = rnsca.clip(geometry, Window(*windows[i]))
        where = f"geometry {i} with window {windows[i].tolist()}"
        _same_geometry(batch[i], alone, windows[i], where)
        _same_geometry(rebuilt[i], alone, windows[i], where + " (ragged)")


@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_keep_empty_gives_one_output_per_input_in_order(kind, boundary, data):
    geometries, window = data.draw(cases(kind, max_geometries=5))
    arrays = shapely.to_ragged_array(_array(geometries))
    kept = rnsca.clip_ragged(*arrays, window, boundary=boundary, keep_empty=True)
    dropped = rnsca.clip_ragged(*arrays, window, boundary=boundary, keep_empty=False)
    every, survivors = geometries_of(kept), geometries_of(dropped)
    n = len(geometries)
    np.testing.assert_array_equal(kept.source, np.arange(n))
    assert len(every) == n
    empty = shapely.is_empty(every)
    np.testing.assert_array_equal(dropped.source, np.flatnonzero(~empty))
    assert not shapely.is_empty(survivors).any()
    for j, i in enumerate(dropped.source):
        _identical_parts(survivors[j], every[i], where=f"geometry {i}")


@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_clipping_twice_equals_clipping_once(kind, boundary, data):
    geometries, window = data.draw(cases(kind, z=None))
    once = rnsca.clip(_array(geometries), window, boundary=boundary)
    twice = rnsca.clip(once, window, boundary=boundary)
    for i, (a, b) in enumerate(zip(once, twice, strict=True)):
        _same_geometry(b, a, window, where=f"geometry {i}: {geometries[i].wkt}")


@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_ragged_path_equals_shapely_object_path(kind, boundary, data):
    geometries, window = data.draw(cases(kind, z=None))
    objects = rnsca.clip(_array(geometries), window, boundary=boundary)
    result = rnsca.clip_ragged(*shapely.to_ragged_array(_array(geometries)), window,
                               boundary=boundary, keep_empty=True)
    rebuilt = geometries_of(result)
    assert len(rebuilt) == len(objects) == len(geometries)
    for i, (a, b) in enumerate(zip(rebuilt, objects, strict=True)):
        _identical_parts(a, b, where=f"geometry {i}: {geometries[i].wkt}")


# --- inside, outside -----------------------------------------------------------------------

def _bounds(geometries):
    return shapely.total_bounds(_array(geometries))


@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_geometry_inside_the_window_is_unchanged(kind, boundary, data):
    geometries, _ = data.draw(cases(kind, z=None))
    xmin, ymin, xmax, ymax = _bounds(geometries)
    size = max(xmax - xmin, ymax - ymin, 1e-3 * max(1.0, abs(xmin), abs(ymin)))
    # closed: the window may touch the geometry's bounding box; interior: it may not
    # (parts along the edge would be dropped).
    low = 0.0 if boundary == "closed" else 1e-3
    margins = [data.draw(st.sampled_from([low, 0.01, 0.5])) * size for _ in range(4)]
    # A point, or a line along an axis, has a flat bounding box: open it up.
    if xmax == xmin:
        margins[0] = margins[2] = max(margins[0], 0.01 * size)
    if ymax == ymin:
        margins[1] = margins[3] = max(margins[1], 0.01 * size)
    window = Window(xmin - margins[0], ymin - margins[1], xmax + margins[2], ymax + margins[3])
    ours = rnsca.clip(_array(geometries), window, boundary=boundary)
    for i, (got, geometry) in enumerate(zip(ours, geometries, strict=True)):
        where = f"geometry {i} in {window.bounds}"
        if dimension_of_type(geometry) == 2:
            # The same area; ring start and orientation may change (shells CCW, holes CW),
            # and so may vertices that add nothing to it: a repeated vertex, a vertex in the
            # middle of an edge along the window's boundary, a hole's vertex where it
            # touches the shell.
            assert shapely.is_valid(got), shapely.is_valid_reason(got)
            _same_geometry(got, geometry, window, where)
        else:
            _identical_parts(got, geometry, where)


@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_geometry_beyond_one_side_gives_nothing(kind, boundary, data):
    geometries, _ = data.draw(cases(kind, z=None))
    xmin, ymin, xmax, ymax = _bounds(geometries)
    size = max(xmax - xmin, ymax - ymin, 1.0)
    # closed: strictly beyond; interior: touching the bounding box counts as beyond.
    gap = data.draw(st.sampled_from([0.01, 1.0])) * size
    if boundary == "interior":
        gap = data.draw(st.sampled_from([0.0, gap]))
    side = data.draw(st.sampled_from(["left", "right", "below", "above"]))
    window = {"left": Window(xmin - gap - size, ymin, xmin - gap, ymax + size),
              "right": Window(xmax + gap, ymin - size, xmax + gap + size, ymax),
              "below": Window(xmin - size, ymin - gap - size, xmax, ymin - gap),
              "above": Window(xmin, ymax + gap, xmax + size, ymax + gap + size)}[side]
    result = rnsca.clip_ragged(*shapely.to_ragged_array(_array(geometries)), window,
                               boundary=boundary)
    assert result.source.size == 0, geometries_of(result)
    assert result.coords.shape[0] == 0


# --- order, orientation, kinds -------------------------------------------------------------

@pytest.mark.parametrize("boundary", BOUNDARIES)
@given(data=st.data())
def test_line_parts_keep_the_input_order_and_direction(boundary, data):
    frame = data.draw(frames())
    relative = data.draw(monotone_lines(frame))
    line = frame.geometry(relative)
    window = data.draw(window_for(frame, [relative]))
    ours = rnsca.clip(line, window, boundary=boundary)
    # x strictly increases along the input, so the output's x must not decrease, within
    # the window's rounding, across all parts taken in order.
    xs = np.concatenate([shapely.get_coordinates(p)[:, 0] for p in flat_parts(ours)]
                        or [np.empty(0)])
    slack = TOLERANCE * Window.of(window).size
    assert np.all(np.diff(xs) >= -slack), f"{line.wkt} in {window.bounds}: {ours.wkt}"


@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("kind", ["polygon", "multipolygon"])
@given(data=st.data())
def test_polygon_shells_are_ccw_and_holes_cw(kind, boundary, data):
    geometries, window = data.draw(cases(kind))
    ours = rnsca.clip(_array(geometries), window, boundary=boundary)
    for got in ours:
        for polygon in flat_parts(got):
            assert shapely.is_ccw(polygon.exterior), f"shell not CCW: {polygon.wkt}"
            for hole in polygon.interiors:
                assert not shapely.is_ccw(hole), f"hole not CW: {polygon.wkt}"


_MULTI = {GeometryType.LINESTRING: GeometryType.MULTILINESTRING,
          GeometryType.POLYGON: GeometryType.MULTIPOLYGON}


@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_output_kind_follows_the_input_kind(kind, data):
    geometries, window = data.draw(cases(kind))
    in_type, coords, offsets = shapely.to_ragged_array(_array(geometries))
    result = rnsca.clip_ragged(in_type, coords, offsets, window, keep_empty=True)
    out = geometries_of(result)
    several = any(len(flat_parts(g)) > 1 for g in out)
    if in_type in _MULTI and several:
        assert result.geometry_type == _MULTI[in_type]
    else:
        assert result.geometry_type == in_type, (in_type, result.geometry_type,
                                                 [g.wkt for g in out])


@pytest.mark.parametrize("kind", ALL_KINDS)
@given(data=st.data())
def test_stats_count_geometries_and_vertices(kind, data):
    geometries, window = data.draw(cases(kind, max_geometries=4))
    in_type, coords, offsets = shapely.to_ragged_array(_array(geometries))
    result = rnsca.clip_ragged(in_type, coords, offsets, window)
    stats = result.stats
    assert stats.geometries_in == len(geometries)
    assert stats.geometries_out == result.source.size
    assert stats.vertices_in == coords.shape[0]
    assert stats.vertices_out == result.coords.shape[0]
    assert stats.invalid_polygons == 0
    assert_inside_window(shapely.multipoints(result.coords[:, :2]), window, "ragged coords")


@given(data=st.data())
def test_star_with_holes_clipped_to_its_own_bounding_box_is_itself(data):
    frame = data.draw(frames())
    star = frame.geometry(data.draw(stars(frame)))
    window = Window(*shapely.bounds(star))
    ours = rnsca.clip(star, window)
    assert shapely.is_valid(ours), shapely.is_valid_reason(ours)
    _same_geometry(ours, star, window, f"{star.wkt} in {window.bounds}")
