"""Bézier clipping against independent oracles (issue 4).

Random and adversarial paths of lines, quadratics and cubics (loops, cusps, tangents to
an edge, collinear and coincident control points, control points far outside, curves
along an edge) are clipped to a window, at scales from 2**-40 to 2**40, and checked:

- preserve/exact: every output point lies on the input curve and in the window, both
  within 1e-9 of the window's size; the clipped length is that of the finely
  flattened input inside the box (chords clipped one by one: a stroke that doubles
  back counts twice, where a Shapely overlay would merge it); degrees are kept;
- approx: no point outside the window, every point on the input, no extra length;
- flatten: lines within the tolerance of the input, in the window;
- fill (nonzero, evenodd): the painted area equals Shapely's area of the painted region
  of the input inside the box.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, note
from hypothesis import strategies as st

from rnsca import Fill, clip_paths, parse_paths, verify
from rnsca.verify.paths import filled_region
from tests.curve_checks import (
    distance_to_paths,
    evaluate,
    inside_length,
    length,
    outside_by,
    sample,
)

BASE = (0.0, 0.0, 10.0, 10.0)

near = st.floats(-12.0, 22.0, allow_nan=False, allow_infinity=False)
on_lines = st.sampled_from([0.0, 10.0, 5.0, -3.0, 13.0])
far = st.floats(-500.0, 500.0, allow_nan=False, allow_infinity=False)
coordinate = st.one_of(near, near, on_lines, far)
point = st.tuples(coordinate, coordinate)


@st.composite
def random_segment(draw, start):
    degree = draw(st.integers(1, 3))
    return degree, [start] + [draw(point) for _ in range(degree)]


@st.composite
def tangent_quadratic(draw, start):
    """A quadratic whose extreme y (or x) touches an edge line exactly at t = 1/2."""
    edge = draw(st.sampled_from([0.0, 10.0]))
    h = start[1]
    x1, x2 = draw(near), draw(near)
    return 2, [start, (x1, 2.0 * edge - h), (x2, h)]


@st.composite
def shaped_cubic(draw, start):
    """A cusp, a loop, or collinear control points going back and forth."""
    kind = draw(st.sampled_from(["cusp", "loop", "collinear", "coincident"]))
    sx, sy = start
    a = draw(st.floats(1.0, 15.0))
    b = draw(st.floats(1.0, 15.0)) * draw(st.sampled_from([-1.0, 1.0]))
    if kind == "cusp":
        return 3, [start, (sx + a, sy + b), (sx, sy + b), (sx + a, sy)]
    if kind == "loop":
        return 3, [start, (sx + 2 * a, sy + b), (sx - a, sy + b), (sx + a, sy)]
    if kind == "collinear":
        k = [draw(st.floats(-2.0, 3.0)) for _ in range(3)]
        return 3, [start] + [(sx + ki * a, sy + ki * b) for ki in k]
    return 3, [start, start, (sx + a, sy + b), (sx + a, sy + b)]


@st.composite
def along_edge(draw, start):
    """A line or curve lying on an edge line (closed window: it is kept)."""
    edge = draw(st.sampled_from([0.0, 10.0]))
    degree = draw(st.integers(1, 3))
    xs = [draw(near) for _ in range(degree)]
    return degree, [(start[0], edge)] + [(x, edge) for x in xs]


@st.composite
def paths(draw, max_segments=5, closed=None):
    start = draw(point)
    segments = []
    here = start
    for _ in range(draw(st.integers(1, max_segments))):
        maker = draw(st.sampled_from([random_segment, random_segment, tangent_quadratic,
                                      shaped_cubic, along_edge]))
        degree, pts = draw(maker(here))
        if maker is along_edge and pts[0] != here:
            segments.append((1, [here, pts[0]]))
        segments.append((degree, pts))
        here = pts[-1]
    is_closed = draw(st.booleans()) if closed is None else closed
    return start, segments, is_closed


def to_d(start, segments, is_closed, scale=1.0) -> str:
    """Path data with every number exact (repr), coordinates scaled by `scale`."""
    def num(v):
        return repr(float(v) * scale)
    parts = [f"M{num(start[0])} {num(start[1])}"]
    letters = {1: "L", 2: "Q", 3: "C"}
    for degree, pts in segments:
        parts.append(letters[degree] + " ".join(f"{num(x)} {num(y)}" for x, y in pts[1:]))
    if is_closed:
        parts.append("Z")
    return " ".join(parts)


def _extent(paths, size: float) -> float:
    """Return the scale rounding is relative to: the window or the control points' spread.

    Pieces are blossoms of the input's control points, so their rounding grows with the
    control points' magnitude (a control point 50 windows away, say).
    """
    spread = float(np.abs(paths.controls).max(initial=0.0))
    return max(size, spread)


scales = st.sampled_from([2.0 ** -40, 1.0, 2.0 ** 20, 2.0 ** 40])


def _window(scale):
    return tuple(v * scale for v in BASE)


@pytest.mark.parametrize("n, max_depth", [("auto", None), (2, 0), (3, 5), (16, 1)])
@given(path=paths(), scale=scales)
def test_preserve_is_exact_on_the_curve_and_in_the_window(path, scale, n, max_depth):
    window = _window(scale)
    size = 10.0 * scale
    d = to_d(*path, scale)
    note(f"d={d!r}")
    source = parse_paths([d])
    result = clip_paths(source, window, n=n, max_depth=max_depth)
    out = result.paths
    points = sample(out, 9)
    if points.size:
        assert outside_by(points, window).max() <= 1e-9 * size
        assert distance_to_paths(points, source).max() <= 1e-9 * _extent(source, size)
    # Degrees are kept: every output curve has a degree the input has.
    assert set(out.degree.tolist()) <= set(source.degree.tolist()) | {1}
    expected = inside_length(source, window, close=bool(path[2]))
    got = length(out, close=False)
    # The oracle's chords are off by up to 1e-5 of the size where a curve crosses an
    # edge almost tangentially; a missing or extra piece is far larger.
    assert abs(got - expected) <= 1e-4 * max(expected, size)


@given(path=paths(), scale=scales)
def test_approx_never_leaves_the_window_nor_adds_length(path, scale):
    window = _window(scale)
    size = 10.0 * scale
    d = to_d(*path, scale)
    note(f"d={d!r}")
    source = parse_paths([d])
    out = clip_paths(source, window, mode="approx", max_depth=8).paths
    points = sample(out, 9)
    if points.size:
        assert outside_by(points, window).max() <= 1e-9 * size
        assert distance_to_paths(points, source).max() <= 1e-9 * _extent(source, size)
    expected = inside_length(source, window, close=bool(path[2]))
    assert length(out) <= expected + 1e-5 * max(expected, size)


@given(path=paths(), scale=scales)
def test_flatten_gives_lines_within_the_tolerance(path, scale):
    window = _window(scale)
    size = 10.0 * scale
    tolerance = 1e-3 * size
    d = to_d(*path, scale)
    note(f"d={d!r}")
    source = parse_paths([d])
    out = clip_paths(source, window, curves="flatten", tolerance=tolerance).paths
    assert set(out.degree.tolist()) <= {1}
    points = sample(out, 5)
    if points.size:
        assert outside_by(points, window).max() <= 1e-9 * size
        assert distance_to_paths(points, source).max() <= tolerance + 1e-9 * size
    expected = inside_length(source, window, close=bool(path[2]))
    # Chords are shorter than arcs; each crossing may move by the tolerance.
    assert abs(length(out) - expected) <= 0.01 * expected + 50 * tolerance


def _painted_area(p, rule: Fill, window=None) -> float:
    t = np.linspace(0.0, 1.0, 1001)
    rings = []
    for s in range(p.closed.shape[0]):
        a, b = p.subpath_offsets[s], p.subpath_offsets[s + 1]
        if b == a:
            continue
        pts = np.concatenate([evaluate(p.controls[i], int(p.degree[i]), t)
                              for i in range(a, b)] + [p.start[s][None]])
        rings.append(pts)
    region = filled_region(rings, rule)
    if window is not None:
        region = shapely.intersection(region, shapely.box(*window))
    return float(region.area)


# Fills are compared through GEOS overlays, which fail on coordinates within 1e-100 of 0
# (-5e-324: "TopologyException: Result area inconsistent"): those are taken as 0 here.
fill_near = near.map(lambda v: 0.0 if abs(v) < 1e-100 else v)
fill_coordinate = st.one_of(fill_near, fill_near, on_lines)
fill_point = st.tuples(fill_coordinate, fill_coordinate)


@st.composite
def fill_paths(draw):
    """Closed paths (1-2 subpaths) of 2-5 segments near the window."""
    subpaths = []
    for _ in range(draw(st.integers(1, 2))):
        start = draw(fill_point)
        here = start
        segments = []
        for _ in range(draw(st.integers(2, 5))):
            degree = draw(st.integers(1, 3))
            pts = [here] + [draw(fill_point) for _ in range(degree)]
            segments.append((degree, pts))
            here = pts[-1]
        subpaths.append(to_d(start, segments, True))
    return " ".join(subpaths)


@pytest.mark.parametrize("rule", list(Fill), ids=lambda r: r.value)
@given(d=fill_paths())
def test_fill_keeps_the_painted_area_inside_the_window(d, rule):
    note(f"d={d!r}")
    source = parse_paths([d])
    result = clip_paths(source, BASE, fill=rule)
    assert result.paths.closed.all()
    expected = _painted_area(source, rule, BASE)
    got = _painted_area(result.paths, rule)
    assert abs(got - expected) <= 1e-3 * max(expected, 1.0)
    points = sample(result.paths, 9)
    if points.size:
        assert outside_by(points, BASE).max() <= 1e-8


@pytest.mark.parametrize("rule", list(Fill), ids=lambda r: r.value)
@given(d=fill_paths())
def test_verify_passes_fills(d, rule):
    note(f"d={d!r}")
    result = clip_paths(parse_paths([d]), BASE, fill=rule)
    v = verify(d, result, BASE, tolerance=1e-4)
    assert v.false_positives == 0
    assert v.valid
