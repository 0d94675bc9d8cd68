"""Many windows for points, lines and polygons (`rnsca.clip_ragged(..., windows=)` and
`rnsca.clip(obj, windows=)`): every geometry against every window its box touches, in
one call, checked window by window against one call per window and against Shapely."""

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rnsca
from rnsca import clip_ragged
from rnsca.arrays import Ragged
from rnsca.errors import InvalidWindowError
from rnsca.many_windows import assign_boxes, vertex_boxes
from tests.geometry_checks import assert_matches_shapely


def _grid(side, extent=100.0):
    xs = np.linspace(0.0, extent, side + 1)
    return np.array([(xs[i], xs[j], xs[i + 1], xs[j + 1]) for j in range(side)
                     for i in range(side)])


def _walks(rng, count, steps=30):
    start = rng.uniform(-10, 110, size=(count, 1, 2))
    return [shapely.LineString(w) for w in start + rng.normal(0, 6, (count, steps, 2)).cumsum(1)]


def _stars(rng, count):
    out = []
    for _ in range(count):
        cx, cy = rng.uniform(-10, 110, 2)
        r = rng.uniform(3, 30)
        angles = np.linspace(0, 2 * np.pi, 17)[:-1]
        radii = np.where(np.arange(16) % 2, r, r / 2.5)
        shell = np.c_[cx + radii * np.cos(angles), cy + radii * np.sin(angles)]
        hole = np.c_[cx + r / 5 * np.cos(-angles), cy + r / 5 * np.sin(-angles)]
        out.append(shapely.Polygon(shell, [hole]))
    return out


def _inputs(rng):
    walks, stars = _walks(rng, 40), _stars(rng, 40)
    return {
        "lines": walks,
        "multilines": [shapely.MultiLineString([a, b])
                       for a, b in zip(walks[::2], walks[1::2], strict=True)],
        "polygons": stars,
        "multipolygons": [shapely.MultiPolygon([a, b])
                          for a, b in zip(stars[::2], stars[1::2], strict=True)
                          if not a.intersects(b)],
        "points": [shapely.Point(p) for p in rng.uniform(-10, 110, (60, 2))],
        "multipoints": [shapely.MultiPoint(p) for p in rng.uniform(-10, 110, (20, 3, 2))],
    }


WINDOW_SETS = {
    "grid": _grid(4),
    "shuffled grid": np.random.default_rng(5).permutation(_grid(3)),
    "overlapping": np.array([[0, 0, 60, 60], [40, 40, 100, 100], [20, 10, 30, 90],
                             [20, 10, 30, 90], [-50, -50, -40, -40]], dtype=float),
}


def _multi(geometry):
    parts = shapely.get_parts(geometry)
    return {"Point": shapely.MultiPoint, "LineString": shapely.MultiLineString,
            "Polygon": shapely.MultiPolygon}[parts[0].geom_type](list(parts))


def _check_against_single_calls(result, triple, windows, **options):
    assert result.window_offsets.shape == (len(windows) + 1,)
    got = result.to_shapely()
    for w, window in enumerate(windows):
        a, b = result.window_offsets[w], result.window_offsets[w + 1]
        one = clip_ragged(*triple, window, **options)
        assert (result.window[a:b] == w).all()
        np.testing.assert_array_equal(result.source[a:b], one.source, err_msg=f"window {w}")
        expected = one.to_shapely()
        assert len(expected) == b - a
        for x, y in zip(got[a:b], expected, strict=True):
            # The kinds may differ (LINESTRING here, MULTILINESTRING there): the parts not.
            assert shapely.equals_exact(_multi(x), _multi(y), 0.0), (w, x.wkt, y.wkt)
    assert len(result) == result.window_offsets[-1]


@pytest.mark.parametrize("windows", WINDOW_SETS.values(), ids=WINDOW_SETS.keys())
@pytest.mark.parametrize("kind", ["lines", "multilines", "polygons", "multipolygons",
                                  "points", "multipoints"])
def test_windows_equal_one_call_per_window(backend, rng, kind, windows):
    triple = shapely.to_ragged_array(_inputs(rng)[kind])
    result = clip_ragged(*triple, windows=windows, backend=backend)
    _check_against_single_calls(result, triple, windows, backend=backend)


@pytest.mark.parametrize("kind", ["lines", "polygons", "multipolygons"])
def test_windows_match_shapely(rng, kind):
    geometries = _inputs(rng)[kind]
    windows = WINDOW_SETS["overlapping"]
    result = clip_ragged(*shapely.to_ragged_array(geometries), windows=windows)
    got = result.to_shapely()
    for g, w, source in zip(got, result.window, result.source, strict=True):
        assert_matches_shapely(g, geometries[source], windows[w], "closed", f"window {w}")
    # Every (geometry, window) pair Shapely finds something in is there.
    for w, window in enumerate(windows):
        expected = {i for i, g in enumerate(geometries)
                    if shapely.area(shapely.intersection(g, shapely.box(*window))) > 1e-9
                    or shapely.length(shapely.intersection(g, shapely.box(*window))) > 1e-9}
        assert set(result.source[result.window == w].tolist()) >= expected


def test_approx_lines_and_interior_boundary(rng):
    triple = shapely.to_ragged_array(_walks(rng, 30))
    windows = _grid(3)
    for options in ({"mode": "approx", "resolution": 0.01}, {"boundary": "interior"}):
        result = clip_ragged(*triple, windows=windows, **options)
        _check_against_single_calls(result, triple, windows, **options)


def test_keep_empty_gives_one_output_per_pair_of_touching_boxes():
    lines = [shapely.LineString([(1, 1), (9, 9)]), shapely.LineString([(1, 4), (4, 1)])]
    windows = [[0, 0, 5, 5], [5, 5, 10, 10], [6, 0, 10, 4]]
    result = clip_ragged(*shapely.to_ragged_array(lines), windows=windows, keep_empty=True)
    # Line 1's box touches window 0 only; line 0's touches windows 0, 1 and 2 (its box
    # covers window 2, the line misses it).
    assert result.window.tolist() == [0, 0, 1, 2]
    assert result.source.tolist() == [0, 1, 0, 0]
    assert shapely.is_empty(result.to_shapely()).tolist() == [False, False, False, True]


def test_geometry_touching_no_window_and_empty_input():
    far = shapely.to_ragged_array([shapely.LineString([(500, 500), (600, 600)])])
    result = clip_ragged(*far, windows=_grid(2))
    assert len(result) == 0 and result.window_offsets.tolist() == [0, 0, 0, 0, 0]
    empty = clip_ragged("LineString", np.empty((0, 2)), (np.zeros(1, dtype=np.int64),),
                        windows=_grid(2))
    assert len(empty) == 0 and empty.window.shape == (0,)


def test_empty_geometries_touch_no_window():
    geometries = [shapely.Polygon(), shapely.box(1, 1, 2, 2)]
    result = clip_ragged(*shapely.to_ragged_array(geometries), windows=_grid(2))
    assert result.source.tolist() == [1]


def test_window_and_windows_are_exclusive():
    triple = shapely.to_ragged_array([shapely.LineString([(0, 0), (1, 1)])])
    with pytest.raises(InvalidWindowError, match="one of window= and windows="):
        clip_ragged(*triple, (0, 0, 1, 1), windows=_grid(2))
    with pytest.raises(InvalidWindowError, match="one of window= and windows="):
        clip_ragged(*triple)
    with pytest.raises(InvalidWindowError, match="window 1"):
        clip_ragged(*triple, windows=[[0, 0, 1, 1], [2, 2, 1, 3]])


def test_take_gathers_geometries_in_any_order_with_repeats(rng):
    geometries = _inputs(rng)["multipolygons"]
    ragged = Ragged.from_shapely(geometries)
    index = np.array([3, 0, 3, 1])
    taken = ragged.take(index).to_shapely()
    assert all(shapely.equals_exact(a, geometries[i], 0)
               for a, i in zip(taken, index, strict=True))
    assert ragged.take([]).count == 0


def test_vertex_boxes_and_assign_boxes(rng):
    ragged = Ragged.from_shapely(_walks(rng, 50))
    boxes = vertex_boxes(ragged.coords, ragged.vertex_offsets())
    np.testing.assert_array_equal(boxes, shapely.bounds(ragged.to_shapely()))
    windows = WINDOW_SETS["overlapping"]
    pairs = assign_boxes(boxes, windows)
    for w, window in enumerate(windows):
        touching = np.flatnonzero(shapely.intersects(shapely.box(*boxes.T),
                                                     shapely.box(*window)))
        got = pairs.segment[pairs.window_offsets[w]:pairs.window_offsets[w + 1]]
        np.testing.assert_array_equal(got, touching)


def test_clip_shapely_geometries_to_many_windows():
    geometries = [shapely.LineString([(-5, 1), (15, 1)]), shapely.box(2, 2, 8, 8), None,
                  shapely.GeometryCollection([shapely.Point(6, 6),
                                              shapely.LineString([(0, 6), (10, 6)])])]
    windows = [[0, 0, 5, 5], [5, 0, 10, 5], [0, 5, 5, 10], [5, 5, 10, 10]]
    result = rnsca.clip(geometries, windows=windows)
    assert [g.wkt for g in result.of_window(1)] == [
        "LINESTRING (5 1, 10 1)", "POLYGON ((5 2, 8 2, 8 5, 5 5, 5 2))"]
    assert result.source[result.window == 3].tolist() == [1, 3, 3]
    assert result.window_offsets.tolist() == [0, 2, 4, 6, 9]
    single = rnsca.clip(shapely.box(2, 2, 8, 8), windows=windows)
    assert single.source.tolist() == [0, 0, 0, 0]


def test_clip_geojson_to_many_windows_gives_a_document_per_window():
    doc = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "id": 7, "properties": {"name": "road"},
         "geometry": {"type": "LineString", "coordinates": [[-5, 1], [15, 1]]}},
        {"type": "Feature", "properties": {"name": "park"},
         "geometry": {"type": "Polygon", "coordinates": [[[6, 6], [9, 6], [9, 9], [6, 6]]]}}]}
    documents = rnsca.clip(doc, windows=[[0, 0, 5, 5], [5, 0, 10, 10], [20, 20, 30, 30]])
    assert [len(d["features"]) for d in documents] == [1, 2, 0]
    assert documents[0]["features"][0]["id"] == 7
    assert documents[0]["features"][0]["geometry"]["coordinates"] == [[0.0, 1.0], [5.0, 1.0]]
    assert documents[1]["features"][1]["properties"] == {"name": "park"}
    result = rnsca.clip_geojson_windows(doc, [[0, 0, 5, 5]], keep_empty=True)
    assert len(result.documents[0]["features"]) == 2
    assert result.feature_source[0].tolist() == [0, 1]


@given(st.lists(st.lists(st.tuples(st.floats(-20, 120), st.floats(-20, 120)), min_size=2,
                         max_size=8), min_size=0, max_size=20),
       st.lists(st.tuples(st.floats(-20, 100), st.floats(-20, 100), st.floats(0.5, 60),
                          st.floats(0.5, 60)), min_size=1, max_size=8),
       st.booleans())
@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_random_lines_and_polygons_equal_a_loop_of_single_calls(paths, boxes, polygons):
    windows = np.array([(x, y, x + w, y + h) for x, y, w, h in boxes])
    if polygons:
        geometries = [shapely.LineString(p).buffer(3.0, quad_segs=2) for p in paths]
        geometries = [g for g in geometries if g.geom_type == "Polygon" and not g.is_empty]
    else:
        geometries = [shapely.LineString(p) for p in paths]
    triple = shapely.to_ragged_array(geometries) if geometries else (
        "LineString", np.empty((0, 2)), (np.zeros(1, dtype=np.int64),))
    result = clip_ragged(*triple, windows=windows)
    _check_against_single_calls(result, triple, windows)
