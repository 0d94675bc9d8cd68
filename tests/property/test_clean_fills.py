"""Clean fills against independent oracles: random outlines, random windows (issue 17).

Outlines are drawn so that each is simple (its rings can then be simple), in shapes that
a window cuts through many times, with windows whose edges pass exactly through their
vertices or touch their curves:

- star-shaped polygons of up to 40 vertices (teeth that cross a window edge again and
  again), with a hole (the polygon shrunk about its centre, turning either way), under
  both rules, compared with Shapely's exact intersection: the rings' polygonisation
  paints the same region within 1e-9 of its area;
- scalloped bands: a closed outline whose top and bottom are quadratics touching a
  level exactly at their apex (``y1 = 2e - y0``), cut by windows with an edge at that
  level (the curves touch the edge and turn back: the clip cuts them there) or through
  the scallops (two crossings per scallop);
- convex blobs (TrueType-style quadratic splines and cubic circles), several per path,
  overlapping or nested, turning either way;
- any closed path of random segments (crossing itself): no ring can be simple then, but
  the clean output must still paint what the raw fill paints.

Curved outputs are compared with the raw fill's, both flattened alike at 2048 steps per
segment (a curve cut where it touches an edge is flattened in two pieces: within 1e-6 of
the area), and, for nonzero, by their signed area (the winding numbers are kept).
"""

from __future__ import annotations

import math
from functools import reduce

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, note
from hypothesis import strategies as st

from rnsca import Fill, clip_paths, parse_paths
from rnsca.verify.paths import filled_region
from tests.curve_checks import signed_area
from tests.property.test_curves_vs_shapely import fill_paths
from tests.ring_checks import (
    flat_subpaths,
    polygonised,
    relative_difference,
    simple_ring_problems,
    winding_painted,
    window_edge_runs,
)

RULES = [Fill.NONZERO, Fill.EVENODD]
#: Exact pieces (lines): the regions agree to rounding.
EXACT = 1e-9
#: Rings are checked with curves flattened at `STEPS` per segment; regions compared at
#: `FINE_STEPS`, where a curve cut in two where it touches an edge (each half flattened
#: by itself) moves the area by under `FLATTENED` of it.
STEPS = 512
FINE_STEPS = 2048
FLATTENED = 1e-6


def floats(low: float, high: float, **kwargs):
    # Coordinates within 1e-100 of 0 (2.2e-308, say) are no test of the rings: GEOS's
    # own intersection with such a box paints beyond the polygon. They are taken as 0.
    return st.floats(low, high, allow_subnormal=False, **kwargs).map(
        lambda v: 0.0 if abs(v) < 1e-100 else v)


def num(v: float) -> str:
    return repr(float(v))


def polygon_d(points, reverse=False) -> str:
    pts = points[::-1] if reverse else points
    return "M" + " L".join(f"{num(x)} {num(y)}" for x, y in pts) + " Z"


@st.composite
def star_polygon(draw):
    """A star-shaped polygon about a centre near the window (0..10)², simple by angle."""
    cx = draw(floats(-2.0, 12.0))
    cy = draw(floats(-2.0, 12.0))
    k = draw(st.integers(3, 40))
    # One vertex per sector of the circle, on rays apart from each other: simple.
    jitter = draw(st.lists(floats(0.05, 0.95), min_size=k, max_size=k))
    angles = [2 * math.pi * (i + u) / k for i, u in enumerate(jitter)]
    radii = draw(st.lists(floats(0.5, 12.0), min_size=k, max_size=k))
    return (cx, cy), [(cx + r * math.cos(a), cy + r * math.sin(a))
                      for a, r in zip(angles, radii, strict=True)]


@st.composite
def window_for(draw, points):
    """A window (xmin, ymin, xmax, ymax): random, or with edges on vertex coordinates."""
    xs = sorted({x for x, _ in points})
    ys = sorted({y for _, y in points})
    coordinate = floats(-5.0, 15.0)

    def bound(values):
        return st.one_of(coordinate, st.sampled_from(values)) if values else coordinate

    x0, x1 = draw(bound(xs)), draw(bound(xs))
    y0, y1 = draw(bound(ys)), draw(bound(ys))
    # Windows far thinner than the shapes are the fill clip's own concern (a window
    # 1e-20 tall at unit coordinates: the raw fill drops the piece), not the rings'.
    assume(abs(x0 - x1) > 1e-6 and abs(y0 - y1) > 1e-6)
    return (min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))


@st.composite
def polygon_fill(draw):
    """Path data of a star polygon, maybe with a hole; its rings; a window."""
    (cx, cy), outer = draw(star_polygon())
    rings = [outer]
    d = polygon_d(outer, reverse=draw(st.booleans()))
    if draw(st.booleans()):
        s = draw(floats(0.2, 0.8))
        hole = [(cx + s * (x - cx), cy + s * (y - cy)) for x, y in outer]
        rings.append(hole)
        d += " " + polygon_d(hole, reverse=draw(st.booleans()))
    window = draw(window_for([p for r in rings for p in r]))
    return d, window


def exact_region(d: str, rule: Fill):
    """Shapely's region of line-only path data under `rule` (every subpath closed)."""
    paths = parse_paths([d])
    rings = flat_subpaths(paths, 1)  # lines only: the vertices, exactly
    if rule is Fill.EVENODD:
        return reduce(shapely.symmetric_difference, [shapely.Polygon(r) for r in rings])
    return filled_region(rings, rule)


def check_rings(d: str, window, rule: Fill):
    """Clip `d` clean and raw; the clean rings are simple; return both outputs."""
    source = parse_paths([d])
    clean = clip_paths(source, window, fill=rule).paths
    raw = clip_paths(source, window, fill=rule, fill_output="raw").paths
    problems = simple_ring_problems(clean, STEPS)
    assert not problems, problems
    assert window_edge_runs(clean, window) == 0
    return clean, raw


@pytest.mark.parametrize("rule", RULES, ids=lambda r: r.value)
@given(case=polygon_fill())
def test_polygon_fills_are_simple_rings_painting_shapelys_intersection(case, rule):
    d, window = case
    note(f"d={d!r} window={window!r}")
    clean, _ = check_rings(d, window, rule)
    expected = shapely.intersection(exact_region(d, rule), shapely.box(*window))
    got = polygonised(flat_subpaths(clean, 1), rule)
    assert relative_difference(got, expected) <= EXACT


@st.composite
def scalloped_band(draw):
    """A band whose top and bottom are quadratics touching two levels at their apexes."""
    n = draw(st.integers(1, 8))
    x0 = draw(floats(-6.0, 2.0))
    width = draw(floats(1.0, 4.0))
    top_base, top_apex = draw(floats(5.0, 9.0)), draw(st.sampled_from([10.0, 12.0, 9.5]))
    bottom_base, bottom_apex = draw(floats(1.0, 4.0)), draw(st.sampled_from([0.0, -2.0]))
    xs = [x0 + i * width for i in range(n + 1)]
    # Apex of a quadratic (y0, y1, y0) is (y0 + y1) / 2: y1 = 2 apex - y0 touches apex.
    d = f"M{num(xs[0])} {num(top_base)}"
    for a, b in zip(xs, xs[1:], strict=False):
        d += f" Q{num((a + b) / 2)} {num(2 * top_apex - top_base)} {num(b)} {num(top_base)}"
    d += f" L{num(xs[-1])} {num(bottom_base)}"
    for a, b in zip(xs[::-1], xs[::-1][1:], strict=False):
        d += (f" Q{num((a + b) / 2)} {num(2 * bottom_apex - bottom_base)} {num(b)} "
              f"{num(bottom_base)}")
    d += " Z"
    ymin = draw(st.sampled_from([bottom_apex, 0.0, 2.0, bottom_base]))
    ymax = draw(st.sampled_from([top_apex, 10.0, 8.0, top_base]))
    xmin = draw(floats(-4.0, 4.0))
    xmax = xmin + draw(floats(1.0, 20.0))
    assume(ymin < ymax)
    return d, (xmin, ymin, xmax, ymax)


def apart_from_edges(d: str, window) -> bool:
    """Return whether every control coordinate is on a window line or 1e-9 from it.

    A curve within an ulp of an edge line over a stretch makes a ring an ulp wide:
    simple, but its flattened points round onto the edge line, where the oracle would
    see the ring touch itself. Exact touches (a coordinate on the line) stay in.
    """
    controls = parse_paths([d]).controls
    xs, ys = controls[..., 0], controls[..., 1]
    return all(((v == bound) | (np.abs(v - bound) > 1e-9)).all()
               for v, bounds in ((xs, window[0::2]), (ys, window[1::2])) for bound in bounds)


def check_curves(d: str, window, rule: Fill):
    assume(apart_from_edges(d, window))
    clean, raw = check_rings(d, window, rule)
    got = winding_painted(clean, rule, FINE_STEPS)
    expected = winding_painted(raw, rule, FINE_STEPS)
    # Relative to the window at least: outlines that cancel (a circle and the same one
    # turning the other way) leave two slivers of flattening noise.
    area = (window[2] - window[0]) * (window[3] - window[1])
    assert float(shapely.area(shapely.symmetric_difference(got, expected))) <= \
        FLATTENED * max(float(shapely.area(expected)), area)
    if rule is Fill.NONZERO:
        fine = 20_001
        area = (window[2] - window[0]) * (window[3] - window[1])
        scale = max(abs(signed_area(raw, fine)), 1e-6 * area)  # rounding of a zero area
        assert abs(signed_area(clean, fine) - signed_area(raw, fine)) <= 1e-7 * scale
    return clean, raw


@pytest.mark.parametrize("rule", RULES, ids=lambda r: r.value)
@given(case=scalloped_band())
def test_curves_touching_and_crossing_an_edge_give_simple_rings(case, rule):
    d, window = case
    note(f"d={d!r} window={window!r}")
    check_curves(d, window, rule)


@st.composite
def convex_blob(draw):
    """A convex outline: a quadratic spline on a convex polygon's edges, or a circle."""
    cx, cy = draw(floats(-3.0, 13.0)), draw(floats(-3.0, 13.0))
    r = draw(floats(0.5, 9.0))
    if draw(st.booleans()):
        k = 0.5522847498 * r
        d = (f"M{num(cx + r)} {num(cy)}C{num(cx + r)} {num(cy + k)} {num(cx + k)} "
             f"{num(cy + r)} {num(cx)} {num(cy + r)}C{num(cx - k)} {num(cy + r)} "
             f"{num(cx - r)} {num(cy + k)} {num(cx - r)} {num(cy)}C{num(cx - r)} "
             f"{num(cy - k)} {num(cx - k)} {num(cy - r)} {num(cx)} {num(cy - r)}"
             f"C{num(cx + k)} {num(cy - r)} {num(cx + r)} {num(cy - k)} {num(cx + r)} "
             f"{num(cy)}Z")
        return d, (cx, cy, r)
    n = draw(st.integers(3, 9))
    # One vertex per sector of the circle, rays apart: a convex polygon, a simple spline.
    jitter = draw(st.lists(floats(0.05, 0.95), min_size=n, max_size=n))
    angles = [2 * math.pi * (i + u) / n for i, u in enumerate(jitter)]
    off = [(cx + r * math.cos(a), cy + r * math.sin(a)) for a in angles]  # on a circle
    mid = [((ax + bx) / 2, (ay + by) / 2) for (ax, ay), (bx, by)
           in zip(off, off[1:] + off[:1], strict=True)]
    d = f"M{num(mid[-1][0])} {num(mid[-1][1])}"
    for (px, py), (qx, qy) in zip(off, mid, strict=True):
        d += f" Q{num(px)} {num(py)} {num(qx)} {num(qy)}"
    return d + " Z", (cx, cy, r)


def reverse_d(d: str) -> str:
    """Return the path data of one subpath run backwards."""
    paths = parse_paths([d])
    out = f"M{num(paths.controls[-1, 3, 0])} {num(paths.controls[-1, 3, 1])}"
    for c, g in zip(paths.controls[::-1], paths.degree[::-1], strict=True):
        pts = c[: g + 1][::-1]
        out += {1: " L", 2: " Q", 3: " C"}[int(g)] + " ".join(
            f"{num(x)} {num(y)}" for x, y in pts[1:])
    return out + " Z"


@st.composite
def blob_fill(draw):
    parts = []
    extremes = []
    special_x, special_y = [], []
    for _ in range(draw(st.integers(1, 3))):
        d, (cx, cy, r) = draw(convex_blob())
        parts.append(reverse_d(d) if draw(st.booleans()) else d)
        extremes += [cx - r, cx + r, cy - r, cy + r]
        special_x += [cx - r, cx, cx + r]
        special_y += [cy - r, cy, cy + r]
    coordinate = st.one_of(floats(-5.0, 15.0), st.sampled_from(extremes))
    x0, x1, y0, y1 = (draw(coordinate) for _ in range(4))
    # A window line exactly at a circle's extreme (a tangent touch) or 1e-3 from every
    # one: a line just off a touch cuts a piece that hugs the edge within an ulp.
    assume(all(v == c or abs(v - c) > 1e-3 for v in (x0, x1) for c in special_x))
    assume(all(v == c or abs(v - c) > 1e-3 for v in (y0, y1) for c in special_y))
    # Near a tangent touch a curve stays within an ulp of the edge line over about
    # sqrt(ulp * radius) of its length: in a window thinner than 1e-3, all of a piece's
    # flattened points may round onto the edge line, where the oracle sees the ring
    # touch itself along its own edge line.
    assume(abs(x0 - x1) > 1e-3 and abs(y0 - y1) > 1e-3)
    return " ".join(parts), (min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))


@pytest.mark.parametrize("rule", RULES, ids=lambda r: r.value)
@given(case=blob_fill())
def test_convex_blobs_overlapping_or_nested_give_simple_rings(case, rule):
    d, window = case
    note(f"d={d!r} window={window!r}")
    check_curves(d, window, rule)


def without_tiny_numbers(d: str) -> bool:
    """Return whether no coordinate of `d` is within 1e-100 of 0 but for 0 itself.

    GEOS nodes the raw fill's self-crossing outline wrongly with coordinates such as
    1e-271, so its region (the oracle here) is not to be trusted there.
    """
    c = np.abs(parse_paths([d]).controls)
    return bool(((c == 0.0) | (c > 1e-100)).all())


@pytest.mark.parametrize("rule", RULES, ids=lambda r: r.value)
@given(d=fill_paths())
def test_any_closed_path_paints_what_the_raw_fill_paints(d, rule):
    # Random segments cross themselves: rings cannot all be simple, but the region is
    # the raw fill's and the kernel's counts add up (it raises if they do not).
    note(f"d={d!r}")
    assume(without_tiny_numbers(d))
    window = (0.0, 0.0, 10.0, 10.0)
    source = parse_paths([d])
    clean = clip_paths(source, window, fill=rule).paths
    raw = clip_paths(source, window, fill=rule, fill_output="raw").paths
    assert clean.closed.all()
    got = winding_painted(clean, rule, STEPS)
    expected = winding_painted(raw, rule, STEPS)
    # Flattened alike but for curves cut where they touch an edge: within 1e-6 of the
    # window's area (shapes here are a few units across).
    assert float(shapely.area(shapely.symmetric_difference(got, expected))) <= 1e-4
    assert np.isfinite(clean.controls).all()
