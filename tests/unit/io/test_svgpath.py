"""SVG path data: the grammar's corner cases, SVG semantics, arcs, errors, the writer."""

import math

import numpy as np
import pytest

from rnsca.errors import InvalidGeometryError, InvalidOptionError, ParseError
from rnsca.io.svgparse import arc_error
from rnsca.io.svgpath import (
    PathArrays,
    parse_path,
    parse_paths,
    write_path,
    write_paths,
)


def segments(d, **kwargs):
    """Return the segments of `d` as (degree, [control points used]) pairs."""
    p = parse_path(d, **kwargs)
    return [(int(g), c[:g + 1].tolist()) for g, c in zip(p.degree, p.controls, strict=True)]


def subpaths(d):
    """Return (start, closed, segment count) per subpath of `d`."""
    p = parse_path(d)
    counts = np.diff(p.subpath_offsets).tolist()
    return list(zip(p.start.tolist(), p.closed.tolist(), counts, strict=True))


def error_of(d):
    with pytest.raises(ParseError) as info:
        parse_path(d)
    return str(info.value)


# --------------------------------------------------------------------------- grammar

def test_absolute_lineto_with_commas():
    assert segments("M0,0L10,10") == [(1, [[0, 0], [10, 10]])]


def test_pairs_after_relative_moveto_are_relative_linetos():
    assert segments("m1 2 3 4") == [(1, [[1, 2], [4, 6]])]
    assert subpaths("m1 2 3 4") == [([1, 2], False, 1)]


def test_pairs_after_absolute_moveto_are_absolute_linetos():
    assert segments("M1 2 3 4 5 6") == [(1, [[1, 2], [3, 4]]), (1, [[3, 4], [5, 6]])]


def test_signs_and_second_decimal_points_separate_numbers():
    assert subpaths("M-.5.5e-3") == [([-0.5, 0.0005], False, 0)]
    assert segments("M1-2L3.5.5") == [(1, [[1, -2], [3.5, 0.5]])]
    assert segments("M0 0L-1-2-3-4") == [(1, [[0, 0], [-1, -2]]), (1, [[-1, -2], [-3, -4]])]


def test_exponents_in_every_spelling():
    assert segments("M1e2 1E+2L.5e-1 5E-1") == [(1, [[100, 100], [0.05, 0.5]])]
    assert segments("M0 0L+1.e1 1e+0") == [(1, [[0, 0], [10, 1]])]


def test_a_trailing_decimal_point_ends_a_number():
    assert subpaths("M1. 2.") == [([1, 2], False, 0)]
    assert subpaths("M1..5") == [([1, 0.5], False, 0)]


def test_arc_flags_need_no_separators():
    spaced = parse_path("M0 0a1 1 0 0 0 1 1")
    assert parse_path("M0 0a1 1 0 00 1 1") == spaced
    assert parse_path("M0 0a1,1,0,0,0,1,1") == spaced
    # "0011" is two flags and the number 11.
    p = parse_path("M0 0a1 1 0 0011 1")
    assert p.controls[-1, 3].tolist() == [11.0, 1.0]


def test_a_comma_may_separate_numbers_once_with_whitespace_around():
    expected = [(1, [[1, 2], [3, 4]])]
    for d in ("M1,2,3,4", "M1 , 2 ,3, 4", "M1\t,\n2\r,\x0c3 4"):
        assert segments(d) == expected


def test_doubled_comma_is_an_error():
    assert error_of("M1,,2") == "position 3: expected a number, found ','"


def test_comma_after_a_command_letter_is_an_error():
    assert error_of("M,1 2") == "position 1: expected a number, found ','"
    assert error_of("M1 2L,3 4") == "position 5: expected a number, found ','"


def test_comma_before_a_command_letter_or_the_end_is_an_error():
    assert error_of("M1 2,L3 4") == "position 5: expected a number, found 'L'"
    assert error_of("M1 2,") == "position 5: expected a number, found the end of the path"


def test_every_command_repeats_implicitly():
    assert len(segments("M0 0L1 1 2 2")) == 2
    assert segments("M0 0H1 2V3 4") == [(1, [[0, 0], [1, 0]]), (1, [[1, 0], [2, 0]]),
                                        (1, [[2, 0], [2, 3]]), (1, [[2, 3], [2, 4]])]
    assert [g for g, _ in segments("M0 0C1 1 2 2 3 3 4 4 5 5 6 6")] == [3, 3]
    assert [g for g, _ in segments("M0 0Q1 1 2 2 3 3 4 4T5 5 6 6")] == [2, 2, 2, 2]
    assert [g for g, _ in segments("M0 0S1 1 2 2 3 3 4 4", )] == [3, 3]
    assert len(parse_path("M0 0A1 1 0 0 1 0 2 1 1 0 0 1 0 0").subpath_offsets) == 2


def test_command_letters_need_no_whitespace():
    assert segments("M0 0L1 1Z") == segments("M 0 0 L 1 1 Z")


def test_empty_or_whitespace_only_data_is_a_path_with_no_subpaths():
    for d in ("", " ", " \t\n\r\x0c "):
        p = parse_path(d)
        assert len(p) == 1
        assert p.path_offsets.tolist() == [0, 0]
        assert p.subpath_offsets.tolist() == [0]


def test_leading_and_trailing_whitespace_is_allowed():
    assert segments("  M0 0 L1 1  \n") == [(1, [[0, 0], [1, 1]])]


# --------------------------------------------------------------------------- semantics

def test_moveto_alone_is_a_subpath_without_segments():
    assert subpaths("M1 2") == [([1, 2], False, 0)]
    assert subpaths("M1 2Z") == [([1, 2], True, 0)]
    assert subpaths("M1 2 M3 4") == [([1, 2], False, 0), ([3, 4], False, 0)]


def test_z_closes_without_adding_a_segment():
    assert subpaths("M0 0 L1 0 L1 1 Z") == [([0, 0], True, 2)]


def test_relative_moveto_after_z_is_relative_to_the_subpath_start():
    assert subpaths("M10 10 l5 0 z m1 1 l1 0") == [([10, 10], True, 1), ([11, 11], False, 1)]


def test_first_relative_moveto_is_relative_to_the_origin():
    assert subpaths("m3 4") == [([3, 4], False, 0)]


def test_drawing_after_z_starts_a_new_subpath_at_the_same_start():
    assert subpaths("M10 10 l5 0 z l0 5") == [([10, 10], True, 1), ([10, 10], False, 1)]
    assert segments("M10 10 l5 0 z l0 5")[1] == (1, [[10, 10], [10, 15]])


def test_z_after_z_is_an_empty_closed_subpath():
    assert subpaths("M1 2ZZ") == [([1, 2], True, 0), ([1, 2], True, 0)]


def test_horizontal_and_vertical_lines_absolute_and_relative():
    assert segments("M1 2h3v4H0V0") == [(1, [[1, 2], [4, 2]]), (1, [[4, 2], [4, 6]]),
                                        (1, [[4, 6], [0, 6]]), (1, [[0, 6], [0, 0]])]


def test_relative_cubic_control_points_are_relative_to_the_segment_start():
    assert segments("M1 1c1 0 2 1 3 3") == [(3, [[1, 1], [2, 1], [3, 2], [4, 4]])]


def test_smooth_cubic_reflects_the_previous_cubic_control_point():
    assert segments("M0 0C1 1 2 2 3 3S5 4 6 6")[1] == (3, [[3, 3], [4, 4], [5, 4], [6, 6]])
    assert segments("M0 0c1 1 2 2 3 3s2 1 3 3")[1] == (3, [[3, 3], [4, 4], [5, 4], [6, 6]])
    assert segments("M0 0S1 1 2 2S3 1 4 0")[1] == (3, [[2, 2], [3, 3], [3, 1], [4, 0]])


def test_smooth_cubic_after_a_non_cubic_starts_at_the_current_point():
    for d in ("M0 0L1 2S3 4 5 6", "M0 0Q9 9 1 2S3 4 5 6", "M0 0L1 2ZM1 2S3 4 5 6",
              "M1 2S3 4 5 6"):
        assert segments(d)[-1] == (3, [[1, 2], [1, 2], [3, 4], [5, 6]]), d


def test_smooth_cubic_after_an_arc_starts_at_the_current_point():
    last = segments("M0 0A1 1 0 0 1 1 1S3 4 5 6")[-1]
    assert last == (3, [[1, 1], [1, 1], [3, 4], [5, 6]])


def test_smooth_quadratic_reflects_the_previous_quadratic_control_point():
    assert segments("M0 0Q1 1 2 0T4 0")[1] == (2, [[2, 0], [3, -1], [4, 0]])
    assert segments("M0 0Q1 1 2 0T4 0T6 0")[2] == (2, [[4, 0], [5, 1], [6, 0]])
    assert segments("M0 0q1 1 2 0t2 0")[1] == (2, [[2, 0], [3, -1], [4, 0]])


def test_smooth_quadratic_after_a_non_quadratic_starts_at_the_current_point():
    assert segments("M0 0T1 1 2 0") == [(2, [[0, 0], [0, 0], [1, 1]]),
                                         (2, [[1, 1], [2, 2], [2, 0]])]
    assert segments("M0 0C1 1 2 2 3 3T4 0")[1] == (2, [[3, 3], [3, 3], [4, 0]])


def test_unused_control_rows_repeat_the_end_point():
    p = parse_path("M0 0L1 2Q3 4 5 6")
    assert p.controls.tolist() == [[[0, 0], [1, 2], [1, 2], [1, 2]],
                                   [[1, 2], [3, 4], [5, 6], [5, 6]]]


def test_many_paths_are_laid_out_by_offsets():
    p = parse_paths(["M0 0L1 1", "", "M0 0ZM1 1L2 2L3 3"])
    assert len(p) == 3
    assert p.path_offsets.tolist() == [0, 1, 1, 3]
    assert p.subpath_offsets.tolist() == [0, 1, 1, 3]
    assert p.closed.tolist() == [False, True, False]


# --------------------------------------------------------------------------- errors

@pytest.mark.parametrize(("d", "message"), [
    ("L1 2", "position 0: expected a moveto command ('M' or 'm'), found 'L'"),
    ("  Z", "position 2: expected a moveto command ('M' or 'm'), found 'Z'"),
    ("M1 x", "position 3: expected a number, found 'x'"),
    ("M1 2 3", "position 6: expected a number, found the end of the path"),
    ("M1 2x", "position 4: expected a number, a command letter or the end of the path, "
              "found 'x'"),
    ("M1 2 Z 3 4", "position 7: expected a command letter or the end of the path, found '3'"),
    ("M1 2Z,", "position 5: expected a command letter or the end of the path, found ','"),
    ("M1e", "position 3: expected a digit in the exponent, found the end of the path"),
    ("M1e+x", "position 4: expected a digit in the exponent, found 'x'"),
    ("M-x", "position 2: expected a digit, found 'x'"),
    ("M.e1", "position 2: expected a digit, found 'e'"),
    ("M0 0A1 1 0 2 0 3 4", "position 11: expected an arc flag ('0' or '1'), found '2'"),
    ("M0 0A1 1 0 0 -1 3 4", "position 13: expected an arc flag ('0' or '1'), found '-'"),
    ("M0 0 K1 1", "position 5: expected a number, a command letter or the end of the path, "
                  "found 'K'"),
    ("M0 0\x00", "position 4: expected a number, a command letter or the end of the path, "
                 "found '\\x00'"),
    ("M0 0é1", "position 4: expected a number, a command letter or the end of the path, "
               "found 'é'"),
    ("M1e999 0", "position 1: number out of range, found '1e999'"),
    ("M0 -1.8e308", "position 3: number out of range, found '-1.8e308'"),
])
def test_syntax_errors_give_position_found_and_expected(d, message):
    assert error_of(d) == message


def test_error_position_counts_characters_before_non_ascii_text():
    with pytest.raises(ParseError) as info:
        parse_paths(["M0 0", "M0 0 L1 2 Ω"])
    assert str(info.value) == ("path 1, position 10: expected a number, a command letter "
                               "or the end of the path, found 'Ω'")


def test_bulk_error_names_the_first_bad_path_and_has_attributes():
    with pytest.raises(ParseError) as info:
        parse_paths(["M0 0", "M0 0", "M1", "M0 0 L1 2 x", "L"])
    assert str(info.value) == "path 2, position 2: expected a number, found the end of the path"
    assert (info.value.path_index, info.value.position) == (2, 2)
    assert isinstance(info.value, ValueError)


def test_numbers_of_huge_magnitude_are_out_of_range_and_tiny_ones_are_zero():
    assert error_of("M0 0L1 2e99999999999999999999") == (
        "position 7: number out of range, found '2e99999999999999999999'")
    assert subpaths("M1e-99999999999 0e999") == [([0.0, 0.0], False, 0)]
    long_number = "9" * 400
    assert error_of(f"M{long_number} 0").startswith(
        "position 1: number out of range, found '9999999999")
    assert subpaths(f"M.{long_number} 0") == [([1.0, 0.0], False, 0)]


def test_coordinates_overflowing_as_they_add_up_are_invalid_geometry():
    with pytest.raises(InvalidGeometryError) as info:
        parse_paths(["M0 0", "M1e308 0 l1e308 0"])
    assert str(info.value) == "path 1: coordinates must be finite (segment 0)"
    assert info.value.path_index == 1


def test_arguments_that_are_not_strings_are_type_errors():
    with pytest.raises(TypeError):
        parse_path(b"M0 0")
    with pytest.raises(TypeError):
        parse_paths("M0 0")
    with pytest.raises(TypeError):
        parse_paths(["M0 0", 3])


@pytest.mark.parametrize("tolerance", [0, -1.0, math.inf, math.nan, "1", True])
def test_tolerance_must_be_positive_and_finite(tolerance):
    with pytest.raises(InvalidOptionError, match="tolerance"):
        parse_path("M0 0", tolerance=tolerance)


# --------------------------------------------------------------------------- arcs

def on_ellipse(p, cx, cy, rx, ry, phi_degrees=0.0):
    """Return |normalised radius - 1| of every end and control-free junction point."""
    phi = math.radians(phi_degrees)
    x = p.controls[:, 3, 0] - cx
    y = p.controls[:, 3, 1] - cy
    u = (math.cos(phi) * x + math.sin(phi) * y) / rx
    v = (-math.sin(phi) * x + math.cos(phi) * y) / ry
    return np.abs(np.hypot(u, v) - 1.0)


def test_arc_with_coincident_ends_is_omitted():
    assert subpaths("M5 5 A3 3 0 1 1 5 5") == [([5, 5], False, 0)]
    assert subpaths("M5 5 a3 3 0 1 1 0 0 L6 6") == [([5, 5], False, 1)]


def test_arc_with_a_zero_radius_is_a_straight_line():
    assert segments("M0 0A0 5 0 0 1 3 4") == [(1, [[0, 0], [3, 4]])]
    assert segments("M0 0a5 0 0 0 1 3 4") == [(1, [[0, 0], [3, 4]])]


def test_arc_flags_choose_among_the_four_arcs():
    # Chord (0,0)-(1,1), radius 1: centres (1,0) and (0,1); small arcs are 90 degrees,
    # large ones 270 (three quarter pieces at a loose tolerance).
    cases = {"0 0": ((1, 0), 1), "0 1": ((0, 1), 1), "1 0": ((0, 1), 3), "1 1": ((1, 0), 3)}
    for flags, ((cx, cy), pieces) in cases.items():
        p = parse_path(f"M0 0A1 1 0 {flags} 1 1", tolerance=1.0)
        assert p.degree.tolist() == [3] * pieces, flags
        assert on_ellipse(p, cx, cy, 1, 1).max() < 1e-15, flags
        assert p.controls[-1, 3].tolist() == [1.0, 1.0]


def test_arc_sweep_flag_one_turns_towards_positive_angles():
    # From (0,0) to (4,0) around (2,0): positive angles (y down: clockwise) pass y = -2.
    p = parse_path("M0 0A2 2 0 0 1 4 0", tolerance=1.0)
    assert np.round(p.controls[:, 3], 12).tolist() == [[2, -2], [4, 0]]
    p = parse_path("M0 0A2 2 0 0 0 4 0", tolerance=1.0)
    assert np.round(p.controls[:, 3], 12).tolist() == [[2, 2], [4, 0]]


def test_arc_radii_too_small_are_scaled_up_to_reach_the_end():
    p = parse_path("M0 0A1 1 0 0 1 4 0", tolerance=1.0)
    assert np.round(p.controls[:, 3], 12).tolist() == [[2, -2], [4, 0]]
    p = parse_path("M0 0A1 .5 0 0 1 4 0", tolerance=1.0)   # keeps the ratio rx:ry = 2:1
    assert np.round(p.controls[:, 3], 12).tolist() == [[2, -1], [4, 0]]


def test_arc_of_subnormal_radii_is_a_few_cubics_on_its_circle():
    # Found by fuzzing: the absolute tolerance (4 ulps of the radius) underflowed to 0,
    # so the piece count had no end (a count beyond any array).
    p = parse_path("M0 0 A1e-320 1e-320 0 0 1 1e-320 0")
    assert 1 <= len(p.degree) <= 8 and (p.degree == 3).all()
    assert p.controls[-1, 3].tolist() == [1e-320, 0.0]


def test_arc_whose_scaled_radius_overflows_is_an_invalid_geometry():
    # Found by fuzzing: ry = 1e-100 must grow by 4e100 to reach the end, and rx = 1e300
    # with it: the half ellipse reaches x = 4e400. Was a piece count beyond any array.
    with pytest.raises(InvalidGeometryError, match="finite"):
        parse_path("M0 0 A1e300 1e-100 0 0 1 6 6")


def test_arc_negative_radii_count_as_positive():
    assert parse_path("M0 0A-3 -2 0 0 1 4 1") == parse_path("M0 0A3 2 0 0 1 4 1")


def spec_centre(x1, y1, rx, ry, phi_degrees, fa, fs, x2, y2):
    """Return (cx, cy, rx, ry): SVG 2 notes F.6.5 and F.6.6, written out literally."""
    phi = math.radians(phi_degrees % 360)
    c, s = math.cos(phi), math.sin(phi)
    x1p = c * (x1 - x2) / 2 + s * (y1 - y2) / 2
    y1p = -s * (x1 - x2) / 2 + c * (y1 - y2) / 2
    rx, ry = abs(rx), abs(ry)
    lam = x1p**2 / rx**2 + y1p**2 / ry**2
    if lam > 1:
        rx, ry = math.sqrt(lam) * rx, math.sqrt(lam) * ry
    num = rx**2 * ry**2 - rx**2 * y1p**2 - ry**2 * x1p**2
    coef = math.sqrt(max(num, 0) / (rx**2 * y1p**2 + ry**2 * x1p**2))
    coef = -coef if fa == fs else coef
    cxp, cyp = coef * rx * y1p / ry, -coef * ry * x1p / rx
    return c * cxp - s * cyp + (x1 + x2) / 2, s * cxp + c * cyp + (y1 + y2) / 2, rx, ry


def test_arc_rotation_is_taken_modulo_360_degrees():
    assert parse_path("M0 0A3 2 390 0 1 4 1") == parse_path("M0 0A3 2 30 0 1 4 1")
    assert parse_path("M0 0A3 2 -330 0 1 4 1") == parse_path("M0 0A3 2 30 0 1 4 1")


@pytest.mark.parametrize("arc", ["3 2 30 1 1 4 1", "3 2 30 0 0 4 1", "1 5 -70 1 0 -2 3",
                                 "0.5 0.25 45 0 1 9 -4"])
def test_arc_ends_and_junctions_lie_on_the_ellipse_of_the_spec(arc):
    rx, ry, phi, fa, fs, x, y = map(float, arc.split())
    cx, cy, rx, ry = spec_centre(0.0, 0.0, rx, ry, phi, fa, fs, x, y)
    p = parse_path(f"M0 0A{arc}", tolerance=1e-3)
    assert on_ellipse(p, cx, cy, rx, ry, phi).max() < 1e-12


def test_arc_pieces_are_at_most_a_quarter_turn():
    p = parse_path("M0 0A10 10 0 1 1 0 .001", tolerance=1e3)
    assert p.degree.tolist() == [3, 3, 3, 3]


def test_arc_tolerance_sets_the_number_of_pieces():
    # A quarter circle of radius 100: one piece deviates by 0.0273 (arc_error).
    d = "M100 0A100 100 0 0 1 0 100"
    assert 100 * arc_error(math.pi / 2) == pytest.approx(0.0272567, rel=1e-5)
    assert len(parse_path(d, tolerance=0.03).degree) == 1
    assert len(parse_path(d, tolerance=0.02).degree) == 2
    # The default: 1e-9 of the radius, 9 pieces for a quarter.
    assert len(parse_path(d).degree) == 9


@pytest.mark.parametrize("tolerance", [1e-2, 1e-5, None])
def test_arc_cubics_stay_within_tolerance_of_the_ellipse(tolerance):
    p = parse_path("M10 20a30 12 25 1 0 40 5", tolerance=tolerance)
    limit = 30 * 1e-9 if tolerance is None else tolerance
    cx, cy, rx, ry = spec_centre(10, 20, 30, 12, 25, 1, 0, 50, 25)
    t = np.linspace(0, 1, 101)[:, None, None]
    c = p.controls[None]
    points = ((1 - t) ** 3 * c[:, :, 0] + 3 * (1 - t) ** 2 * t * c[:, :, 1]
              + 3 * (1 - t) * t ** 2 * c[:, :, 2] + t ** 3 * c[:, :, 3]).reshape(-1, 2)
    phi = math.radians(25)
    x, y = points[:, 0] - cx, points[:, 1] - cy
    u = (math.cos(phi) * x + math.sin(phi) * y) / rx
    v = (-math.sin(phi) * x + math.cos(phi) * y) / ry
    # The radial error in the frame where the ellipse is the unit circle, mapped back,
    # bounds the distance to the ellipse: at most max(rx, ry) times it.
    assert (max(rx, ry) * np.abs(np.hypot(u, v) - 1)).max() <= limit * (1 + 1e-6) + 1e-12


def test_arc_ends_exactly_at_its_end_point_and_starts_at_the_current_point():
    p = parse_path("M.1 .2A3 2 17 1 0 4.3 1.7")
    assert p.controls[0, 0].tolist() == [0.1, 0.2]
    assert p.controls[-1, 3].tolist() == [4.3, 1.7]
    assert (p.controls[1:, 0] == p.controls[:-1, 3]).all()


def test_relative_arc_end_is_relative_to_the_current_point():
    p = parse_path("M1 1a1 1 0 0 1 2 0", tolerance=1.0)
    assert p.controls[-1, 3].tolist() == [3.0, 1.0]


# --------------------------------------------------------------------------- writer

@pytest.mark.parametrize(("d", "written"), [
    ("", ""),
    ("M1 2", "M1 2"),
    ("M1 2Z", "M1 2Z"),
    ("M 0 0 L 10 0 L 10 -10.5 C 0.5 0, 1 1, 2 2 Z", "M0 0H10V-10.5C.5 0 1 1 2 2Z"),
    ("M0 0 l 1 -2 l -0.5 -0.5", "M0 0 1-2 .5-2.5"),
    ("M0 0 L .1 .2 L 1.5 .5", "M0 0 .1.2 1.5.5"),
    ("M0 0 L 1000000 0.0001", "M0 0 1e6 1e-4"),
    ("M0 0 L 1e-30 12e40", "M0 0 1e-30 12e40"),
    ("M-0 -0 L -0.5 -0", "M0 0H-.5"),
    ("M0 0C1 1 2 2 3 3S5 4 6 6", "M0 0C1 1 2 2 3 3S5 4 6 6"),
    ("M0 0L1 1T2 0", "M0 0 1 1T2 0"),
    ("M0 0L1 1S2 0 3 3", "M0 0 1 1S2 0 3 3"),
    ("M1 1 Z L 2 2", "M1 1ZL2 2"),
    ("M1 1 L 2 2 Z M 1 1 L 3 3", "M1 1 2 2ZL3 3"),
    ("M1 1 L 2 2 Z M 1 1", "M1 1 2 2ZM1 1"),
    ("M1 1ZZ", "M1 1ZZ"),
    ("M0 0ZM5 5 6 6", "M0 0ZM5 5 6 6"),
    ("M0 0H5 6 7V1 2", "M0 0H5 6 7V1 2"),
    ("M1 1L1 1", "M1 1H1"),
])
def test_writer_is_compact(d, written):
    assert write_path(parse_path(d)) == written
    assert parse_path(written) == parse_path(d)


def test_writer_rounds_to_significant_digits():
    p = parse_path("M0 0L1.23456789 -98765.4321")
    assert write_path(p, precision=3) == "M0 0 1.23-98800"
    assert write_path(p) == "M0 0 1.23457-98765.4"
    assert write_path(p, precision=None) == "M0 0 1.23456789-98765.4321"
    assert write_path(parse_path("M0 0L123456789 1"), precision=2) == "M0 0 12e7 1"


def test_writer_shortest_round_trip_digits_with_precision_none():
    p = parse_path("M0.1 0.2L0.30000000000000004 1e-300")
    assert write_path(p, precision=None) == "M.1.2.30000000000000004 1e-300"


def test_writer_breaks_chains_of_t_at_finite_precision():
    p = parse_path("M0 0Q1 1 2 0T4 0T6 0T8 0")
    assert write_path(p, precision=None) == "M0 0Q1 1 2 0T4 0 6 0 8 0"
    assert write_path(p) == "M0 0Q1 1 2 0T4 0Q5 1 6 0T8 0"


def test_writer_writes_every_path_and_indexes_from_the_end():
    p = parse_paths(["M0 0L1 1", "", "M2 2Z"])
    assert write_paths(p) == ["M0 0 1 1", "", "M2 2Z"]
    assert write_path(p, -1) == "M2 2Z"
    assert write_path(p, 1) == ""
    with pytest.raises(IndexError):
        write_path(p, 3)


@pytest.mark.parametrize("precision", [0, 18, 1.5, True, "6"])
def test_writer_precision_must_be_none_or_1_to_17(precision):
    with pytest.raises(InvalidOptionError, match="precision"):
        write_paths(parse_path("M0 0"), precision=precision)


def test_writer_output_of_arcs_reads_back_exactly():
    p = parse_path("M0 0A3 2 30 1 1 4 1a5 5 0 0 0 -3 -3")
    assert parse_path(write_path(p, precision=None)) == p


# --------------------------------------------------------------------------- PathArrays

def line_arrays(**changes):
    fields = dict(controls=[[[0, 0], [1, 1], [1, 1], [1, 1]]], degree=[1],
                  subpath_offsets=[0, 1], closed=[False], start=[[0, 0]], path_offsets=[0, 1])
    fields.update(changes)
    return fields


def test_path_arrays_normalise_dtypes():
    p = PathArrays(**line_arrays())
    assert (p.controls.dtype, p.degree.dtype, p.closed.dtype, p.start.dtype) == (
        np.float64, np.int8, np.bool_, np.float64)
    assert p.subpath_offsets.dtype == p.path_offsets.dtype == np.int64
    assert p.controls.flags.c_contiguous
    assert p == parse_path("M0 0L1 1")


def test_path_arrays_empty_has_no_paths():
    p = PathArrays.empty()
    assert len(p) == 0
    assert write_paths(p) == []
    assert parse_paths([]) == p


@pytest.mark.parametrize(("changes", "message"), [
    (dict(controls=[[0, 0, 1, 1]]), "controls must have shape"),
    (dict(degree=[4]), "degree values must be in"),
    (dict(degree=[257]), "degree values must be in"),
    (dict(degree=[1, 1]), "degree must have shape"),
    (dict(subpath_offsets=[0, 2]), "subpath_offsets must start at 0"),
    (dict(subpath_offsets=[1, 1]), "subpath_offsets must start at 0"),
    (dict(closed=[2]), "closed values must be in"),
    (dict(start=[[0, 0], [1, 1]]), "start must have shape"),
    (dict(path_offsets=[0, 1, 0, 1]), "path_offsets must start at 0, never decrease"),
    (dict(path_offsets=[0.0, 1.0]), "path_offsets must be a 1-d integer array"),
])
def test_path_arrays_reject_bad_layout(changes, message):
    with pytest.raises(InvalidGeometryError, match=message):
        PathArrays(**line_arrays(**changes))


@pytest.mark.parametrize(("controls", "start", "message"), [
    ([[[0, 0], [1, np.nan], [1, 1], [1, 1]]], [[0, 0]],
     "path 1: coordinates must be finite (segment 1)"),
    ([[[0, 0], [1, 1], [1, 1], [1, 1]]], [[0, np.inf]],
     "path 1: coordinates must be finite (subpath start)"),
    ([[[0, 0], [1, 1], [2, 2], [1, 1]]], [[0, 0]],
     "path 1: unused control points must repeat the end point (segment 1)"),
    ([[[0, 1], [1, 1], [1, 1], [1, 1]]], [[0, 0]],
     "path 1: segments must start where the previous one ends (the first at the "
     "subpath's start) (segment 1)"),
])
def test_path_arrays_name_the_path_with_bad_geometry(controls, start, message):
    good = [[[5, 5], [6, 6], [6, 6], [6, 6]]]
    with pytest.raises(InvalidGeometryError) as info:
        PathArrays(controls=good + controls, degree=[1, 1], subpath_offsets=[0, 1, 2],
                   closed=[False, False], start=[[5, 5]] + start, path_offsets=[0, 1, 2])
    assert str(info.value) == message
    assert info.value.path_index == 1


def test_path_selects_one_path():
    p = parse_paths(["M0 0L1 1", "M2 2L3 3ZL4 4"])
    assert p.path(1) == parse_path("M2 2L3 3ZL4 4")
    assert p.path(-2) == parse_path("M0 0L1 1")
