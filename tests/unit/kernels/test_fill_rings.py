"""Clean fills (`rnsca.kernels.fill_rings`, ``fill_output="clean"``): literal cases.

Each case is clipped to the window (0, 0, 10, 10) under both rules: the clean output is
written out in full, every subpath is a simple ring (`tests.ring_checks`), and the
region its rings paint is the one the raw fill paints (both flattened alike; curves
split where they touch an edge are compared by their exact area).
"""

import numpy as np
import pytest

from rnsca import clip_paths, clip_svg, parse_paths
from rnsca.backends.numba_cpu import clean_fills
from rnsca.window import Window
from tests.curve_checks import signed_area
from tests.ring_checks import (
    relative_difference,
    simple_ring_problems,
    winding_painted,
    window_edge_runs,
)

W = (0, 0, 10, 10)
RULES = ["nonzero", "evenodd"]


def clean(d, rule, **options):
    return clip_svg(d, W, fill=rule, precision=6, **options)[0]


def assert_clean_and_same_region(d, rule, exact=True, **options):
    source = parse_paths([d])
    out = clip_paths(source, W, fill=rule, **options).paths
    raw = clip_paths(source, W, fill=rule, fill_output="raw", **options).paths
    assert simple_ring_problems(out) == []
    assert window_edge_runs(out, W) == 0
    if exact:  # the same pieces: the same points
        assert relative_difference(winding_painted(out, rule),
                                   winding_painted(raw, rule)) <= 1e-12
    return out, raw


# --- one ring per painted piece ---------------------------------------------------------------

@pytest.mark.parametrize("rule", RULES)
def test_a_run_back_and_forth_along_an_edge_becomes_one_line(rule):
    # Raw: "M2 0H1.5L1 1 2 0Z", along the bottom edge to 1.5 and back over it.
    expected = {"nonzero": "M1.5 0 1 1 2 0Z", "evenodd": "M2 0 1 1 1.5 0Z"}[rule]
    assert clean("M2 -1L1 1L3 -1L1 -1Z", rule) == expected
    assert_clean_and_same_region("M2 -1L1 1L3 -1L1 -1Z", rule)


@pytest.mark.parametrize("rule", RULES)
def test_a_shape_leaving_twice_through_one_edge_gives_two_rings(rule):
    d = "M2 -5 L2 5 L4 5 L4 -2 L6 -2 L6 5 L8 5 L8 -5 Z"
    # Raw: one subpath running the bottom edge from 4 to 6 and back from 8 to 2.
    assert clip_svg(d, W, fill=rule, fill_output="raw")[0] == "M2 0V5H4V0H6V5H8V0H2Z"
    expected = {"nonzero": "M2 0V5H4V0ZM6 0V5H8V0Z", "evenodd": "M4 0V5H2V0ZM8 0V5H6V0Z"}
    assert clean(d, rule) == expected[rule]
    assert_clean_and_same_region(d, rule)


@pytest.mark.parametrize("rule", RULES)
def test_a_notch_touching_an_edge_at_a_vertex_splits_the_region_there(rule):
    # The painted region is two triangles meeting at (5, 0): two rings meeting there.
    assert clean("M1 -2 L9 -2 L9 5 L5 0 L1 5 Z", rule) == "M9 0V5L5 0ZM5 0 1 5V0Z"
    assert_clean_and_same_region("M1 -2 L9 -2 L9 5 L5 0 L1 5 Z", rule)


@pytest.mark.parametrize("rule", RULES)
def test_a_curve_touching_an_edge_from_inside_is_cut_where_it_touches(rule):
    # y(t) of the quadratic has its minimum 0 at t = 1/2: it touches the bottom edge at
    # (5, 0). Below it, the region is two lobes meeting there: two rings, each with one
    # half of the curve (the raw fill's single subpath runs through (5, 0) twice).
    d = "M-2 5 Q5 -5 12 5 L12 -5 L-2 -5 Z"
    expected = {"nonzero": "M0 2.55102Q2.5 0 5 0H0ZM5 0Q7.5 0 10 2.55102V0Z",
                "evenodd": "M5 0Q2.5 0 0 2.55102V0ZM10 2.55102Q7.5 0 5 0H10Z"}
    assert clean(d, rule) == expected[rule]
    out, raw = assert_clean_and_same_region(d, rule, exact=False)
    assert simple_ring_problems(raw)
    fine = 100_001  # chords within 1e-10 of the area
    assert abs(signed_area(out, fine)) == pytest.approx(abs(signed_area(raw, fine)), rel=1e-9)
    # Above the curve nothing touches the region's boundary: one ring, through (5, 0).
    assert clean("M-2 5 Q5 -5 12 5 Z", "nonzero") == "M0 2.55102Q2.5 0 5 0T10 2.55102V5H0Z"


@pytest.mark.parametrize("rule", RULES)
def test_a_shape_around_the_window_or_through_its_corners(rule):
    assert clean("M-5 5 L5 -5 L15 5 L5 15 Z", rule) == "M0 0H10V10H0Z"
    assert clean("M-2 -2 L5 5 L-2 12 Z", rule) == "M0 0 5 5 0 10Z"
    assert_clean_and_same_region("M-2 -2 L5 5 L-2 12 Z", rule)


@pytest.mark.parametrize("rule", RULES)
def test_outline_lying_on_an_edge_joins_the_edge_run(rule):
    assert clean("M2 0 H8 V5 H2 Z", "nonzero") == "M8 0V5H2V0Z"
    assert clean("M2 0 H12 V5 H2 Z", "nonzero") == "M10 5H2V0H10Z"
    assert_clean_and_same_region("M2 0 H12 V5 H2 Z", rule)


@pytest.mark.parametrize("rule", RULES)
def test_a_spike_along_an_edge_is_gone(rule):
    # Raw: "M5 0V5H6V0H5.5 5.2 5Z" (a spike back along the bottom edge from 6 to 5.2).
    d = "M5 -5 L5 5 L6 5 L6 -5 L5.5 -5 L5.5 0 L5.2 0 Z"
    assert clean(d, rule) == {"nonzero": "M5 0V5H6V0Z", "evenodd": "M6 0V5H5V0Z"}[rule]
    assert_clean_and_same_region(d, rule)


# --- winding numbers -------------------------------------------------------------------------

def test_nonzero_keeps_winding_two_as_two_rings_evenodd_keeps_its_parity():
    # The outline winds twice round [0, 4] x [2, 8] (it crosses the left edge 4 times).
    d = "M-5 1 H5 V9 H-5 V2 H4 V8 H-5 Z"
    assert clip_svg(d, W, fill="nonzero", fill_output="raw")[0] == "M0 1H5V9H0V2H4V8H0V1Z"
    assert clean(d, "nonzero") == "M0 1H5V9H0ZM0 2H4V8H0Z"
    assert clean(d, "evenodd") == "M0 1H5V9H0V8H4V2H0Z"  # the C between the two
    for rule in RULES:
        assert_clean_and_same_region(d, rule)


def test_evenodd_hole_of_the_same_turning_leaves_two_strips():
    d = "M-5 -5 H15 V15 H-5 Z M2 -2 H8 V12 H2 Z"
    assert clean(d, "evenodd") == "M8 10V0H10V10ZM2 0V10H0V0Z"
    # Nonzero paints both: the window, and the strip (winding 2) over it.
    assert clean(d, "nonzero") == "M0 0H10V10ZM8 0V10H2V0Z".replace("V10Z", "V10H0Z")
    for rule in RULES:
        assert_clean_and_same_region(d, rule)


def circle(r, cy=5.0, cx=0.0):
    """Return a counter-clockwise circle of radius r about (cx, cy), in four cubics."""
    k = 0.5522847498 * r
    x0, x1, xm, xk, xl = cx + r, cx - r, cx, cx + k, cx - k
    return (f"M{x0} {cy}C{x0} {cy + k} {xk} {cy + r} {xm} {cy + r}"
            f"C{xl} {cy + r} {x1} {cy + k} {x1} {cy}C{x1} {cy - k} {xl} {cy - r} {xm} {cy - r}"
            f"C{xk} {cy - r} {x0} {cy - k} {x0} {cy}Z")


def test_evenodd_donut_cut_through_its_hole_is_one_ring():
    d = circle(4) + circle(2)  # turning alike: the hole is a hole by parity only
    out, _ = assert_clean_and_same_region(d, "evenodd")
    assert out.closed.shape[0] == 1  # the right half of the annulus, a C
    out, _ = assert_clean_and_same_region(d, "nonzero")
    assert out.closed.shape[0] == 2  # winding 1 and 2: the two half discs


def test_a_counter_touching_an_edge_at_one_point_inside_a_shape_around_the_window():
    # Every chain end is at one point, (10, 5): the lane of the outer shape runs all the
    # way round from it back to it (the walk is cut there into the window and the
    # circle). The circle leaves straight up the edge and comes back straight down it.
    d = "M-5 -5 H15 V15 H-5 Z " + circle(1.0, 5.0, 9.0)
    ring = "M10 5C10 5.55228 9.55228 6 9 6S8 5.55228 8 5 8.44772 4 9 4 10 4.44772 10 5Z"
    assert clean(d, "nonzero") == "M0 0H10V10H0Z" + ring
    # Evenodd: the circle is a hole, turned with the painted side on its left.
    out, _ = assert_clean_and_same_region(d, "evenodd")
    assert out.closed.shape[0] == 2
    assert signed_area(out) == pytest.approx(100.0 - np.pi, rel=1e-3)
    assert_clean_and_same_region(d, "nonzero")


def test_a_sliver_an_ulp_below_an_edge_paints_nothing():
    # The line from (0, -5e-324) up to (1, 2) crosses y = 0 at t ~ 2.5e-324 (0 in
    # floats). The root finder once lost the sign of its bracket there (the Illinois
    # halving of g(0) = -5e-324 underflows to -0.0) and cut the line at t = 0.25, a
    # point (0.25, 0.5) moved onto the edge: a triangle of area 0.25 out of nothing.
    assert clean("M0 0 L0 -5e-324 L1 2 Z", "nonzero") == ""
    assert clean("M0 0 L0 -5e-324 L1 2 Z", "evenodd") == ""


@pytest.mark.parametrize("rule", RULES)
def test_outlines_crossing_inside_the_window_stay_separate_rings(rule):
    # The second square turns the other way and sticks out of the first at x = 5..6:
    # joined along the left edge, the two would make a ring crossing itself.
    d = "M-5 2H5V8H-5Z M-5 3V7H6V3Z"
    expected = {"nonzero": "M0 2H5V8H0ZM0 7H6V3H0Z", "evenodd": "M0 2H5V8H0ZM0 3H6V7H0Z"}
    assert clean(d, rule) == expected[rule]
    source = parse_paths([d])
    out = clip_paths(source, W, fill=rule).paths
    assert simple_ring_problems(out) == []


def test_a_counter_open_to_the_edge_joins_its_shell_in_one_ring():
    # A square with a square hole reaching the left edge: one C-shaped ring.
    d = "M-5 2H5V8H-5Z M-5 3V7H4V3Z"
    for rule in RULES:
        out, _ = assert_clean_and_same_region(d, rule)
        assert out.closed.shape[0] == 1


# --- the kernel on its own -------------------------------------------------------------------

def test_rings_are_written_where_the_count_pass_says_for_many_paths():
    # Many paths of different sizes in one call (blocks in parallel): every path's rings
    # are those it gives alone.
    rng = np.random.default_rng(3)
    texts = []
    for _ in range(300):
        x, y = rng.uniform(-6, 12, 2)
        w, h = rng.uniform(1, 9, 2)
        texts.append(f"M{x:.2f} {y:.2f}h{w:.2f}v{h:.2f}h{-w:.2f}z"
                     f"M{x + w / 4:.2f} {y + h / 4:.2f}v{h / 2:.2f}h{w / 2:.2f}v{-h / 2:.2f}z")
    together = clip_svg(texts, W, fill="nonzero")[0]
    assert together == [clip_svg(t, W, fill="nonzero")[0] for t in texts]


def test_the_kernel_returns_a_path_unchanged_when_nothing_touches_the_boundary():
    raw = clip_paths(parse_paths(["M2 2H8V7H2Z M3 3V6H7V3Z"]), W, fill="nonzero",
                     fill_output="raw").paths
    out = clean_fills(raw, Window(*W), False)
    assert out.degree.shape[0] == raw.degree.shape[0] - 2  # the drawn closing lines
    assert np.array_equal(out.start, raw.start)
