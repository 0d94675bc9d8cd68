"""Every segment method on the named cases of `tests.cases`, in every mode and backend.

Each test is one behaviour with a literal expected piece (see `tests/cases.py`): exact
mode, and the analytic methods in any mode, must return it within 1e-9 of the window's
size; RNSCA and midpoint in approx mode must return it or a shorter piece on it, at most
one leaf shorter at each cut end (`tests.checks.assert_case`). Every result is also
checked for shapes, source order, t range and coordinates inside the window.

The subdivision methods run with their defaults and with options that make them split:
exact mode decides at level 0 by default (its tolerance is infinite), so a finite
tolerance is what exercises RNSCA's and midpoint's exact leaves.
"""

import pytest

from rnsca import Method, Mode
from tests import cases
from tests.checks import assert_case

# Tolerances are fractions of each case's window size.
_SPLIT_EXACT = {"n": 3, "tolerance": 1e-3}
_DEEP_EXACT = {"n": "auto", "tolerance": 1e-12}
_SHALLOW_APPROX = {"n": 3, "max_depth": 6}
_BISECTING_APPROX = {"n": 2}
SETTINGS = (
    [(m, mode, {}) for m in (Method.COHEN_SUTHERLAND, Method.LIANG_BARSKY,
                             Method.NICHOLL_LEE_NICHOLL) for mode in Mode]
    + [(m, Mode.EXACT, opts) for m in (Method.RNSCA, Method.MIDPOINT)
       for opts in ({}, _SPLIT_EXACT, _DEEP_EXACT)]
    + [(m, Mode.APPROX, opts) for m in (Method.RNSCA, Method.MIDPOINT)
       for opts in ({}, _SHALLOW_APPROX, _BISECTING_APPROX)]
)


def _id(value):
    if isinstance(value, dict):
        return "-".join(f"{k}={v}" for k, v in value.items()) or "defaults"
    return value.value


pytestmark = pytest.mark.parametrize("method, mode, options", SETTINGS, ids=_id)


def check(case, method, mode, backend, options):
    options = dict(options)
    if "tolerance" in options:
        options["tolerance"] *= case.size
    assert_case(case, method, mode, backend, **options)


# --- inside, outside, crossing --------------------------------------------------------

def test_segment_inside_is_kept_whole(method, mode, backend, options):
    check(cases.INSIDE, method, mode, backend, options)


def test_segment_crossing_left_to_right_is_cut_at_both_edges(method, mode, backend, options):
    check(cases.CROSSING_LEFT_TO_RIGHT, method, mode, backend, options)


def test_segment_crossing_right_to_left_keeps_its_direction(method, mode, backend, options):
    check(cases.CROSSING_RIGHT_TO_LEFT, method, mode, backend, options)


def test_vertical_segment_crossing_upward_is_cut_at_bottom_and_top(method, mode, backend, options):
    check(cases.VERTICAL_CROSSING_UPWARD, method, mode, backend, options)


def test_vertical_segment_crossing_downward_keeps_its_direction(method, mode, backend, options):
    check(cases.VERTICAL_CROSSING_DOWNWARD, method, mode, backend, options)


def test_horizontal_segment_leaving_right_is_cut_at_the_right_edge(method, mode, backend, options):
    check(cases.HORIZONTAL_LEAVING_RIGHT, method, mode, backend, options)


def test_sloped_segment_leaving_right_is_cut_where_it_crosses(method, mode, backend, options):
    check(cases.SLOPED_LEAVING_RIGHT, method, mode, backend, options)


def test_segment_entering_left_and_leaving_top_is_cut_twice(method, mode, backend, options):
    check(cases.ENTERING_LEFT_LEAVING_TOP, method, mode, backend, options)


def test_segment_cutting_top_right_corner_keeps_the_corner_part(method, mode, backend, options):
    check(cases.CUTTING_TOP_RIGHT_CORNER, method, mode, backend, options)


def test_segment_left_of_the_window_gives_no_piece(method, mode, backend, options):
    check(cases.OUTSIDE_LEFT, method, mode, backend, options)


def test_segment_passing_outside_a_corner_gives_no_piece(method, mode, backend, options):
    check(cases.MISSING_TOP_LEFT_CORNER, method, mode, backend, options)


# --- on the boundary ------------------------------------------------------------------

def test_segment_along_top_edge_is_kept_whole(method, mode, backend, options):
    check(cases.ALONG_TOP_EDGE, method, mode, backend, options)


def test_segment_along_bottom_edge_is_cut_at_the_corners(method, mode, backend, options):
    check(cases.ALONG_BOTTOM_EDGE_BEYOND_BOTH_ENDS, method, mode, backend, options)


def test_segment_partly_along_left_edge_keeps_the_part_on_the_edge(method, mode, backend, options):
    check(cases.ALONG_LEFT_EDGE_PARTLY, method, mode, backend, options)


def test_segment_along_right_edge_downward_keeps_its_direction(method, mode, backend, options):
    check(cases.ALONG_RIGHT_EDGE_DOWNWARD, method, mode, backend, options)


def test_segment_on_an_edge_line_beyond_the_corner_gives_no_piece(method, mode, backend, options):
    check(cases.ON_EDGE_LINE_BEYOND_CORNER, method, mode, backend, options)


def test_segment_on_an_edge_line_touching_the_corner_gives_no_piece(method, mode, backend, options):
    check(cases.ON_EDGE_LINE_TOUCHING_CORNER, method, mode, backend, options)


def test_diagonal_through_two_corners_is_cut_at_the_corners(method, mode, backend, options):
    check(cases.THROUGH_TWO_CORNERS, method, mode, backend, options)


def test_antidiagonal_through_two_corners_is_cut_at_the_corners(method, mode, backend, options):
    check(cases.THROUGH_THE_OTHER_TWO_CORNERS, method, mode, backend, options)


def test_segment_touching_corner_gives_no_piece(method, mode, backend, options):
    check(cases.TOUCHING_BOTTOM_LEFT_CORNER, method, mode, backend, options)


def test_segment_touching_top_right_corner_gives_no_piece(method, mode, backend, options):
    check(cases.TOUCHING_TOP_RIGHT_CORNER, method, mode, backend, options)


def test_segment_ending_at_a_corner_from_outside_gives_no_piece(method, mode, backend, options):
    check(cases.ENDING_AT_CORNER_FROM_OUTSIDE, method, mode, backend, options)


def test_segment_ending_on_an_edge_from_outside_gives_no_piece(method, mode, backend, options):
    check(cases.ENDING_ON_EDGE_FROM_OUTSIDE, method, mode, backend, options)


def test_segment_starting_on_an_edge_going_out_gives_no_piece(method, mode, backend, options):
    check(cases.STARTING_ON_EDGE_GOING_OUT, method, mode, backend, options)


def test_segment_starting_on_an_edge_going_in_is_kept_whole(method, mode, backend, options):
    check(cases.STARTING_ON_EDGE_GOING_IN, method, mode, backend, options)


def test_segment_ending_on_top_edge_at_an_inexact_x_gives_no_piece(method, mode, backend, options):
    check(cases.ENDING_ON_TOP_EDGE_FROM_ABOVE, method, mode, backend, options)


def test_segment_descending_onto_top_edge_from_one_ulp_above_gives_no_piece(method, mode, backend,
                                                                            options):
    check(cases.DESCENDING_ONTO_TOP_EDGE_FROM_ONE_ULP_ABOVE, method, mode, backend, options)


def test_segment_leaving_a_corner_a_subnormal_below_the_edge_gives_no_piece(method, mode, backend,
                                                                           options):
    check(cases.LEAVING_A_CORNER_BELOW_THE_EDGE_BY_A_SUBNORMAL, method, mode, backend, options)


def test_segment_through_a_corner_with_a_slope_of_1e_minus_153_gives_no_piece(method, mode,
                                                                             backend, options):
    check(cases.THROUGH_A_CORNER_WITH_A_SLOPE_OF_1E_MINUS_153, method, mode, backend, options)


def test_segment_along_an_edge_one_ulp_outside_gives_no_piece(method, mode, backend, options):
    check(cases.ALONG_EDGE_ONE_ULP_OUTSIDE, method, mode, backend, options)


def test_segment_along_an_edge_one_ulp_inside_is_kept_whole(method, mode, backend, options):
    check(cases.ALONG_EDGE_ONE_ULP_INSIDE, method, mode, backend, options)


def test_segment_starting_one_ulp_outside_is_cut_onto_the_edge(method, mode, backend, options):
    check(cases.STARTING_ONE_ULP_OUTSIDE, method, mode, backend, options)


# --- zero length ----------------------------------------------------------------------

def test_zero_length_segment_inside_is_kept(method, mode, backend, options):
    check(cases.ZERO_LENGTH_INSIDE, method, mode, backend, options)


def test_zero_length_segment_outside_gives_no_piece(method, mode, backend, options):
    check(cases.ZERO_LENGTH_OUTSIDE, method, mode, backend, options)


def test_zero_length_segment_on_an_edge_is_kept(method, mode, backend, options):
    check(cases.ZERO_LENGTH_ON_EDGE, method, mode, backend, options)


def test_zero_length_segment_on_a_corner_is_kept(method, mode, backend, options):
    check(cases.ZERO_LENGTH_ON_CORNER, method, mode, backend, options)


def test_zero_length_segment_one_ulp_outside_gives_no_piece(method, mode, backend, options):
    check(cases.ZERO_LENGTH_ONE_ULP_OUTSIDE, method, mode, backend, options)


# --- magnitudes -----------------------------------------------------------------------

def test_horizontal_segment_at_1e300_is_cut_at_both_edges(method, mode, backend, options):
    check(cases.HUGE_HORIZONTAL, method, mode, backend, options)


def test_diagonal_at_1e300_is_cut_at_the_corners(method, mode, backend, options):
    check(cases.HUGE_DIAGONAL, method, mode, backend, options)


def test_sloped_segment_at_1e300_is_cut_where_it_crosses(method, mode, backend, options):
    check(cases.HUGE_SLOPED, method, mode, backend, options)


def test_segment_spanning_1_6e308_is_cut_at_both_edges(method, mode, backend, options):
    check(cases.HUGE_SPAN_NEAR_OVERFLOW, method, mode, backend, options)


def test_horizontal_segment_at_1e_minus_300_is_cut_at_both_edges(method, mode, backend, options):
    check(cases.TINY_HORIZONTAL, method, mode, backend, options)


def test_diagonal_at_1e_minus_300_is_cut_at_the_corners(method, mode, backend, options):
    check(cases.TINY_DIAGONAL, method, mode, backend, options)


def test_antidiagonal_at_1e_minus_300_is_cut_at_the_corners(method, mode, backend, options):
    check(cases.TINY_ANTIDIAGONAL, method, mode, backend, options)


def test_segment_through_a_subnormal_window_is_cut_at_both_edges(method, mode, backend, options):
    check(cases.SUBNORMAL_HORIZONTAL, method, mode, backend, options)


def test_segment_from_1e200_away_is_cut_at_the_corner(method, mode, backend, options):
    check(cases.FROM_FAR_AWAY_INTO_UNIT, method, mode, backend, options)


def test_segment_1e200_long_through_unit_window_is_cut_at_edges(method, mode, backend, options):
    check(cases.FAR_HORIZONTAL_THROUGH_UNIT, method, mode, backend, options)


def test_vertical_segment_from_1e_minus_200_to_1e200_is_cut(method, mode, backend, options):
    check(cases.VERTICAL_FROM_TINY_TO_HUGE, method, mode, backend, options)


def test_segment_from_1e_minus_300_to_1e300_is_cut_at_the_corner(method, mode, backend, options):
    check(cases.FROM_1E_MINUS_300_TO_1E300, method, mode, backend, options)


def test_horizontal_segment_at_1e6_is_cut_at_both_edges(method, mode, backend, options):
    check(cases.FAR_WINDOW_HORIZONTAL, method, mode, backend, options)


def test_sloped_segment_at_1e6_is_cut_where_it_crosses(method, mode, backend, options):
    check(cases.FAR_WINDOW_SLOPED, method, mode, backend, options)


def test_segment_1e4_windows_long_is_cut_within_1e_9_of_the_window(method, mode, backend, options):
    check(cases.LONG_SEGMENT_THROUGH_WINDOW, method, mode, backend, options)


def test_segment_2e8_windows_long_is_cut_within_1e_9_of_the_window(method, mode, backend, options):
    check(cases.VERY_LONG_SEGMENT_THROUGH_TINY_WINDOW, method, mode, backend, options)


def test_segment_2e15_windows_long_is_cut_within_1e_9_of_the_window(method, mode, backend, options):
    check(cases.EXTREMELY_LONG_SEGMENT_THROUGH_TINY_WINDOW, method, mode, backend, options)
