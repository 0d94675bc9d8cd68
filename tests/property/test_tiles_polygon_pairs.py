"""The cascade's polygon pairs (`rnsca.tiles.pyramid.clip_polygon_pairs`) against the general clip.

The pairs' fast path (`rnsca.kernels.tile_polygons`) must give what ``clip_ragged`` gives
for the same pairs, bit for bit: the same coordinates, offsets and sources. Inputs:
valid stars with holes, combs and multipolygons against windows placed against them
(`geometry_strategies`), rings enclosing the window and holes enclosing it, and random
lattice rings (self-intersecting, repeated and collinear positions, spikes, collapsed
rings) against windows on the lattice's lines or between them (so vertices lie exactly
on edges and corners, or never). On valid input the result is also valid and its area
is Shapely's (``clip_by_rect``).
"""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rnsca.arrays import GeometryKind, Ragged
from rnsca.kernels import tile_polygons as TP
from rnsca.ragged import clip_ragged
from rnsca.tiles.pyramid import clip_polygon_pairs
from tests.property.geometry_strategies import (
    frames,
    multipolygons,
    polygons,
    window_for,
)

_position = st.tuples(st.integers(0, 8), st.integers(0, 8))
_ring = st.lists(_position, min_size=3, max_size=10)


def _as_multipolygons(geometries) -> Ragged:
    multi = [g if g.geom_type == "MultiPolygon" else shapely.MultiPolygon([g])
             for g in geometries]
    return Ragged.from_shapely(np.array(multi, dtype=object))


def _check(ragged: Ragged, geometry: np.ndarray, windows: np.ndarray) -> None:
    """Assert the pairs' clip equals the general one bit for bit."""
    got, source = clip_polygon_pairs(ragged, geometry, windows)
    taken = ragged.take(geometry)
    want = clip_ragged(GeometryKind.MULTIPOLYGON, taken.coords, taken.offsets, windows,
                       mode="exact")
    assert np.array_equal(source, want.source)
    assert got.coords.tobytes() == want.coords.tobytes()
    assert len(got.offsets) == len(want.offsets)
    for mine, theirs in zip(got.offsets, want.offsets, strict=True):
        assert np.array_equal(mine, theirs)


def _fast_share(ragged: Ragged, geometry: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """Return the status (`TP.FAST`, `TP.FALLBACK`) the bounds pass gives each pair."""
    polygon_offsets, geometry_offsets = ragged.item_offsets()
    n = geometry.shape[0]
    status = np.empty(n, dtype=np.int8)
    bounds = [np.empty(n, dtype=np.int64) for _ in range(3)]
    TP.plan_pairs(ragged.coords, ragged.offsets[0], polygon_offsets, geometry_offsets,
                  geometry, windows, status, *bounds)
    return status


@st.composite
def _valid_pairs(draw):
    frame = draw(frames())
    relative = []
    suggested = None
    for _ in range(draw(st.integers(1, 3))):
        if draw(st.booleans()):
            shape, suggested = draw(polygons(frame))
        else:
            shape = draw(multipolygons(frame))
        relative.append(shape)
    geometries = [frame.geometry(g) for g in relative]
    n_pairs = draw(st.integers(1, 6))
    geometry = np.array([draw(st.integers(0, len(geometries) - 1)) for _ in range(n_pairs)])
    windows = []
    for g in geometry:
        w = draw(window_for(frame, [relative[g]], suggested))
        windows.append((w.xmin, w.ymin, w.xmax, w.ymax))
    windows = np.array(windows, dtype=np.float64)
    return geometries, geometry, windows


@settings(max_examples=300, deadline=None)
@given(_valid_pairs())
def test_valid_polygons_clip_as_the_general_clip_and_as_shapely(case):
    geometries, geometry, windows = case
    ragged = _as_multipolygons(geometries)
    _check(ragged, geometry, windows)
    got, source = clip_polygon_pairs(ragged, geometry, windows)
    clipped = got.to_shapely()
    # Valid in, valid out and Shapely's area (a frame's rounding can make two stars
    # touch or overlap: then only the equality with the general clip above holds).
    valid_in = shapely.is_valid(np.array(geometries, dtype=object))[geometry[source]]
    assert shapely.is_valid(clipped[valid_in]).all()
    area = np.zeros(geometry.shape[0])
    area[source] = shapely.area(clipped)
    for j, g in enumerate(geometry):
        if not shapely.is_valid(geometries[g]):
            continue  # Shapely's area of an invalid input is no oracle
        want = shapely.clip_by_rect(geometries[g], *windows[j]).area
        size = max(windows[j, 2] - windows[j, 0], windows[j, 3] - windows[j, 1])
        assert abs(area[j] - want) <= 1e-9 * size * size + 1e-9 * want


@st.composite
def _lattice_pairs(draw):
    """Random rings on a lattice (any shape, valid or not) and windows on or off its lines."""
    geometries = []
    for _ in range(draw(st.integers(1, 3))):
        parts = []
        for _ in range(draw(st.integers(1, 3))):
            rings = [draw(_ring) for _ in range(draw(st.integers(1, 3)))]
            parts.append([r + r[:1] for r in rings])
        geometries.append(shapely.MultiPolygon([(p[0], p[1:]) for p in parts]))
    n_pairs = draw(st.integers(1, 6))
    geometry = np.array([draw(st.integers(0, len(geometries) - 1)) for _ in range(n_pairs)])
    windows = []
    for _ in range(n_pairs):
        shift = draw(st.sampled_from([0.0, 0.5, 0.25]))
        x0, y0 = draw(st.integers(-1, 7)) + shift, draw(st.integers(-1, 7)) + shift
        windows.append((x0, y0, x0 + draw(st.integers(1, 9)), y0 + draw(st.integers(1, 9))))
    return geometries, geometry, np.array(windows, dtype=np.float64)


@settings(max_examples=400, deadline=None)
@given(_lattice_pairs())
def test_any_lattice_polygons_clip_as_the_general_clip(case):
    geometries, geometry, windows = case
    _check(_as_multipolygons(geometries), geometry, windows)


@st.composite
def _enclosing_pairs(draw):
    """Shells and holes that enclose the window, holes inside it, crossings of its edges."""
    frame = draw(frames())
    geometries, geometry, windows = [], [], []
    for _ in range(draw(st.integers(1, 4))):
        # A window in the middle of the frame; rings around it or inside it.
        window = np.array([0.4, 0.4, 0.6, 0.6])
        shell_r = draw(st.sampled_from([0.45, 0.3, 0.15, 0.12]))
        hole_r = draw(st.sampled_from([0.0, 0.2, 0.13, 0.05, 0.02]))
        n = draw(st.integers(3, 12))
        turn = draw(st.floats(0.0, 6.3))
        angles = turn + 2 * np.pi * np.arange(n) / n
        shell = np.column_stack([0.5 + shell_r * np.cos(angles), 0.5 + shell_r * np.sin(angles)])
        rings = [shell]
        if 0.0 < hole_r < shell_r * np.cos(np.pi / n):
            m = draw(st.integers(3, 8))
            hole = np.column_stack([0.5 + hole_r * np.cos(angles[0] + 2 * np.pi * np.arange(m)
                                                          / m),
                                    0.5 + hole_r * np.sin(angles[0] + 2 * np.pi
                                                          * np.arange(m) / m)])
            rings.append(hole[::-1] if draw(st.booleans()) else hole)
        if draw(st.booleans()):
            rings[0] = rings[0][::-1]
        closed = [frame.absolute(np.vstack([r, r[:1]])) for r in rings]
        geometries.append(shapely.MultiPolygon([(closed[0], closed[1:])]))
        geometry.append(len(geometries) - 1)
        windows.append(frame.absolute(window.reshape(2, 2)).ravel())
    return geometries, np.array(geometry), np.array(windows, dtype=np.float64)


@settings(max_examples=200, deadline=None)
@given(_enclosing_pairs())
def test_rings_around_and_inside_the_window_clip_as_the_general_clip(case):
    geometries, geometry, windows = case
    _check(_as_multipolygons(geometries), geometry, windows)


def test_simple_pairs_take_the_fast_path():
    # A shell crossing the window twice with a hole inside it; a polygon inside; one
    # outside; a shell enclosing the window with a hole inside the window.
    crossing = shapely.Polygon([(-1, 1), (3, 1), (3, 3), (-1, 3)], [[(1, 1.5), (2, 1.5),
                                                                     (2, 2.5), (1, 2.5)]])
    inside = shapely.Polygon([(1, 1), (2, 1), (2, 2), (1, 2)])
    outside = shapely.Polygon([(8, 8), (9, 8), (9, 9), (8, 9)])
    around = shapely.Polygon([(-5, -5), (9, -5), (9, 9), (-5, 9)],
                             [[(1, 1), (1, 2), (2, 2), (2, 1)]])
    ragged = _as_multipolygons([crossing, inside, outside, around])
    geometry = np.arange(4)
    windows = np.array([(0.5, 0.5, 4.5, 4.5)] * 4)
    assert (_fast_share(ragged, geometry, windows) == TP.FAST).all()
    _check(ragged, geometry, windows)
    got, source = clip_polygon_pairs(ragged, geometry, windows)
    assert source.tolist() == [0, 1, 3]
    shapes = got.to_shapely()
    assert shapes[0].equals(shapely.clip_by_rect(crossing, *windows[0]))
    assert shapes[2].equals(shapely.box(0.5, 0.5, 4.5, 4.5).difference(
        shapely.box(1, 1, 2, 2)))


def test_a_vertex_on_an_edge_line_falls_back():
    touching = shapely.Polygon([(0, 1), (5, 1), (5, 3), (0, 3)])  # x = 0 is the edge
    ragged = _as_multipolygons([touching])
    windows = np.array([(0.0, 0.5, 4.5, 4.5)])
    assert _fast_share(ragged, np.array([0]), windows)[0] == TP.FALLBACK
    _check(ragged, np.array([0]), windows)


@pytest.mark.opencl
def test_every_backend_clips_the_pairs_alike(opencl):
    """The pair operation is every backend's (`ClipBackend.clip_polygon_pairs`): OpenCL
    gathers the pairs and clips them whole, with the same output as Numba's fast path."""
    crossing = shapely.Polygon([(-1, 1), (3, 1), (3, 3), (-1, 3)], [[(1, 1.5), (2, 1.5),
                                                                     (2, 2.5), (1, 2.5)]])
    star = shapely.Polygon([(2 + (3 if k % 2 else 1) * np.cos(k * np.pi / 6),
                             2 + (3 if k % 2 else 1) * np.sin(k * np.pi / 6))
                            for k in range(12)])
    ragged = _as_multipolygons([crossing, star])
    geometry = np.array([0, 1, 1, 0])
    windows = np.array([(0.5, 0.5, 4.5, 4.5), (0.5, 0.5, 4.5, 4.5), (1.5, -1.0, 6.0, 2.5),
                        (-2.0, 2.0, 1.0, 5.0)])
    a, a_source = clip_polygon_pairs(ragged, geometry, windows, "numba")
    b, b_source = clip_polygon_pairs(ragged, geometry, windows, "opencl")
    assert np.array_equal(a_source, b_source)
    assert a.coords.tobytes() == b.coords.tobytes()
    for mine, theirs in zip(a.offsets, b.offsets, strict=True):
        assert np.array_equal(mine, theirs)
