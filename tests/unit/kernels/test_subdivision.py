"""RNSCA and midpoint subdivision: how N, max_depth, tolerance and mode shape the result.

One segment, ``(-5, 5) -> (15, 5)`` across the window ``[0, 10]^2``, worked by hand: its
split points are easy to place, so each test states the pieces, the parameter interval
and the counters literally.
"""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rnsca import clip_segments
from rnsca.constants import N_MAX, N_MIN
from rnsca.kernels.segments import auto_n

W10 = (0.0, 0.0, 10.0, 10.0)
ACROSS = [[-5.0, 5.0, 15.0, 5.0]]


def counters(stats):
    return (stats.fragments_evaluated, stats.accepted, stats.rejected, stats.subdivided,
            stats.clipped, stats.dropped, stats.intersections, stats.deepest_level)


def test_rnsca_exact_mode_clips_a_crossing_segment_at_level_0_by_default(backend):
    r = clip_segments(ACROSS, W10, backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_array_equal(r.t, [[0.25, 0.75]])
    # evaluated, accepted, rejected, subdivided, clipped, dropped, intersections, deepest
    assert counters(r.stats) == (1, 0, 0, 0, 1, 0, 2, 0)


def test_rnsca_exact_mode_with_a_tolerance_clips_only_the_leaves_at_the_edges(backend):
    # N = 3 splits at x = 1.67 and 8.33: the middle third is accepted whole, and the two
    # outer thirds (shorter than the tolerance) are leaves, each cut at one edge.
    r = clip_segments(ACROSS, W10, n=3, tolerance=10.0, backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_array_equal(r.t, [[0.25, 0.75]])
    assert counters(r.stats) == (4, 1, 0, 1, 2, 0, 2, 1)
    assert r.stats.decided_per_level[:3] == (0, 3, 0)


def test_rnsca_exact_mode_at_depth_0_clips_the_whole_segment(backend):
    r = clip_segments(ACROSS, W10, max_depth=0, tolerance=1.0, backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    assert counters(r.stats) == (1, 0, 0, 0, 1, 0, 2, 0)


def test_rnsca_approx_mode_at_depth_0_drops_every_crossing_segment(backend):
    r = clip_segments(ACROSS, W10, mode="approx", max_depth=0, backend=backend)
    assert len(r) == 0
    assert counters(r.stats) == (1, 0, 0, 0, 0, 1, 0, 0)


def test_rnsca_approx_mode_keeps_the_accepted_pieces_between_dropped_leaves(backend):
    # N = 4 splits exactly at the edges (x = 0 and 10): the two middle quarters are
    # accepted, the outer ones dropped, so nothing visible is lost.
    r = clip_segments(ACROSS, W10, mode="approx", n=4, max_depth=1, backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_array_equal(r.t, [[0.25, 0.75]])
    assert counters(r.stats) == (5, 2, 0, 1, 0, 2, 0, 1)


def test_rnsca_approx_mode_loses_less_than_one_leaf_at_each_crossing(backend):
    # N = 3, one level: the leaves [-5, 1.67] and [8.33, 15] are dropped, so each end
    # loses 1.67, less than the leaf length 20 / 3.
    r = clip_segments(ACROSS, W10, mode="approx", n=3, max_depth=1, backend=backend)
    np.testing.assert_allclose(r.segments, [[5 / 3, 5.0, 25 / 3, 5.0]], rtol=1e-15)
    np.testing.assert_allclose(r.t, [[1 / 3, 2 / 3]], rtol=1e-15)
    assert counters(r.stats) == (4, 1, 0, 1, 0, 2, 0, 1)


def test_rnsca_approx_mode_computes_no_intersection(backend):
    r = clip_segments(ACROSS, W10, mode="approx", backend=backend)
    assert r.stats.intersections == 0 and r.stats.clipped == 0
    # The default tolerance is 1e-9 of the window: the ends are that close to the edges.
    np.testing.assert_allclose(r.segments, [[0.0, 5.0, 10.0, 5.0]], atol=1e-8)
    assert r.segments[0, 0] >= 0.0 and r.segments[0, 2] <= 10.0


def test_midpoint_approx_mode_keeps_the_visible_end_of_each_final_bracket(backend):
    # Two halvings bracket the exit in [10, 15] and the entry in [-5, 0]; their visible
    # ends are exactly on the edges.
    r = clip_segments(ACROSS, W10, method="midpoint", mode="approx", max_depth=2,
                      backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_array_equal(r.t, [[0.25, 0.75]])
    assert counters(r.stats) == (7, 0, 0, 5, 0, 2, 0, 2)


def test_midpoint_approx_mode_drops_a_visible_part_shorter_than_two_brackets(backend):
    # One halving: both searches end with the midpoint (5, 5) as their visible end, so the
    # piece would be that single point.
    r = clip_segments(ACROSS, W10, method="midpoint", mode="approx", max_depth=1,
                      backend=backend)
    assert len(r) == 0
    assert counters(r.stats) == (5, 0, 0, 3, 0, 2, 0, 1)


def test_midpoint_exact_mode_clips_both_final_brackets(backend):
    r = clip_segments(ACROSS, W10, method="midpoint", max_depth=2, tolerance=1e-9,
                      backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    assert counters(r.stats) == (7, 0, 0, 5, 2, 0, 2, 2)


def test_midpoint_exact_mode_keeps_a_bracket_end_that_lies_on_a_corner(backend):
    # The segment passes (to rounding) through the corners (xmin, ymax) and (xmax, ymin)
    # of a thin window, at t = 1/4 and 3/4: a bracket end lands on the corner, and
    # Liang-Barsky finds the bracket's visible part empty by one ulp of t.
    window = (19.084346601493408, 57.13458171194935, 31.296672230626648, 57.135874301761795)
    segment = [[12.978183786926788, 57.136520596668014, 37.402835045193264, 57.13393541704313]]
    r = clip_segments(segment, window, method="midpoint", tolerance=1e-3, backend=backend)
    np.testing.assert_allclose(r.segments, [[19.084346601493408, 57.135874301761795,
                                             31.296672230626648, 57.13458171194935]],
                               rtol=0, atol=1e-9 * 12.3)


def test_cohen_sutherland_moves_each_outside_end_once_for_a_horizontal_crossing(backend):
    r = clip_segments(ACROSS, W10, method="cohen_sutherland", backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    assert counters(r.stats) == (3, 1, 0, 0, 2, 0, 2, 0)


def test_cohen_sutherland_settles_an_end_rounded_past_a_corner(backend):
    # The segment enters (to rounding) through the corner (xmax, ymin) of a thin window;
    # moved onto one edge there, the end tests a hair beyond the other. It must still be
    # clipped at both ends (it used to keep its far end unclipped, clamped to a corner).
    window = (10.691182117162697, 36.529571357767594, 62.91115945000756, 38.321575782492936)
    segment = [[214.10562316472118, -187.81836794336712, -111.14499066043233, 294.8005267920046]]
    r = clip_segments(segment, window, method="cohen_sutherland", backend=backend)
    np.testing.assert_allclose(r.segments, [[62.91115945000756, 36.529571357767594,
                                             61.703476647951305, 38.321575782492936]],
                               rtol=0, atol=1e-9 * 52.3)
    np.testing.assert_allclose(r.t, [[0.4648552755568109, 0.46856835940883856]], rtol=1e-12)


@pytest.mark.parametrize("method", ["liang_barsky", "nicholl_lee_nicholl"])
def test_one_pass_methods_evaluate_each_segment_once(method, backend):
    r = clip_segments(ACROSS, W10, method=method, backend=backend)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])
    assert counters(r.stats) == (1, 0, 0, 0, 1, 0, 2, 0)


def test_rnsca_decides_inside_and_outside_segments_at_level_0(backend):
    r = clip_segments([[2.0, 3.0, 7.0, 8.0], [20.0, 20.0, 30.0, 30.0]], W10, backend=backend)
    np.testing.assert_array_equal(r.segments, [[2.0, 3.0, 7.0, 8.0]])
    assert counters(r.stats) == (2, 1, 1, 0, 0, 0, 0, 0)
    assert r.stats.decided_per_level[0] == 2


def test_midpoint_bisects_whatever_n_is_asked(backend):
    r = clip_segments(ACROSS, W10, method="midpoint", n=5, backend=backend)
    assert r.options.n == 2


@given(st.floats(1e-300, 1e300), st.floats(1e-300, 1e300), st.integers(1, 33))
def test_auto_n_bisects_unless_the_levels_left_cannot_reach_the_tolerance(length, tol, levels):
    """``n="auto"``: 2, or the smallest N whose `levels` splits bring the piece to `tol`."""
    n = auto_n(length, tol, levels)
    assert N_MIN <= n <= N_MAX
    need = Fraction(length) / Fraction(tol)  # exact: the split factor the levels must give
    if need <= 2 ** levels:
        assert n == 2
    elif need <= N_MAX ** levels:
        assert n ** levels >= need * (1 - Fraction(1, 10**12))  # pow() may round by an ulp
        assert (n - 1) ** levels < need * (1 + Fraction(1, 10**12)) or n == 2
    else:
        assert n == N_MAX


def test_auto_n_in_approx_mode_bisects_down_to_the_resolution(backend):
    """The default resolution (a 4096th of the window) and ``n="auto"``: bisection, 13 levels."""
    r = clip_segments(ACROSS, W10, mode="approx", backend=backend)
    # 20 long, leaves of at most 10/4096: 20 / 2**13 = 0.0024 <= 0.00244
    assert r.stats.deepest_level == 13
    lost = 10.0 - (r.segments[0, 2] - r.segments[0, 0])
    assert 0.0 <= lost <= 2 * 10.0 / 4096
