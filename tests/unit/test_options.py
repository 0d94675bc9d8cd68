"""Options: strings at the edge, enums and checked numbers inside."""

import math

import numpy as np
import pytest

from rnsca import Backend, InvalidOptionError, Method, Mode, Window
from rnsca.options import MAX_DEPTH_LIMIT, N_MAX, N_MIN, PathOptions, SegmentOptions

W = Window(0.0, 0.0, 10.0, 4.0)


@pytest.mark.parametrize("enum, text, member", [
    (Method, "rnsca", Method.RNSCA),
    (Method, "Liang_Barsky", Method.LIANG_BARSKY),
    (Method, "MIDPOINT", Method.MIDPOINT),
    (Mode, "Approx", Mode.APPROX),
    (Backend, "NUMBA", Backend.NUMBA),
    (Backend, "OpenCL", Backend.OPENCL),
])
def test_choices_are_looked_up_case_insensitively(enum, text, member):
    assert enum(text) is member


@pytest.mark.parametrize("enum, bad, listed", [
    (Method, "bresenham", "'rnsca', 'cohen_sutherland', 'liang_barsky', "
                          "'nicholl_lee_nicholl', 'midpoint'"),
    (Mode, "fast", "'exact', 'approx'"),
    (Backend, "numpy", "'numba', 'opencl'"),
])
def test_unknown_choice_error_lists_the_valid_ones(enum, bad, listed):
    with pytest.raises(InvalidOptionError) as info:
        enum(bad)
    assert listed in str(info.value) and repr(bad) in str(info.value)


@pytest.mark.parametrize("bad", [None, 1, " rnsca", ""])
def test_choice_of_wrong_type_or_spelling_is_refused(bad):
    with pytest.raises(InvalidOptionError, match="method must be one of"):
        Method(bad)


def test_invalid_option_error_is_a_value_error():
    with pytest.raises(ValueError):
        Mode("nope")


def test_choices_print_as_their_values():
    assert str(Method.NICHOLL_LEE_NICHOLL) == "nicholl_lee_nicholl"
    assert f"{Mode.EXACT}" == "exact"


def test_defaults_for_exact_mode():
    opts = SegmentOptions.resolve(W)
    assert (opts.method, opts.mode, opts.n, opts.max_depth) == (Method.RNSCA, Mode.EXACT, 0, 32)
    assert opts.tolerance == math.inf


def test_default_tolerance_in_approx_mode_is_a_4096th_of_the_window():
    assert SegmentOptions.resolve(W, mode="approx").tolerance == 10.0 / 4096


@pytest.mark.parametrize(("resolution", "tolerance"), [
    ("4096px", 10.0 / 4096), ("256PX", 10.0 / 256), (" 1px ", 10.0), (0.25, 0.25),
    (np.float32(0.5), 0.5), (3, 3.0)])
def test_resolution_sets_the_approx_tolerance(resolution, tolerance):
    assert SegmentOptions.resolve(W, mode="approx", resolution=resolution).tolerance == tolerance
    assert PathOptions.resolve(W, mode="approx", resolution=resolution).tolerance == tolerance


@pytest.mark.parametrize("resolution", ["0px", "px", "-3px", "4096", "1.5px", "abc", 0.0, -1.0,
                                        math.inf, math.nan, "1e3px"])
def test_a_bad_resolution_is_refused_naming_it(resolution):
    with pytest.raises(InvalidOptionError, match="resolution must be"):
        SegmentOptions.resolve(W, mode="approx", resolution=resolution)


def test_resolution_is_for_approx_mode_and_not_with_a_tolerance():
    with pytest.raises(InvalidOptionError, match="applies to mode='approx'"):
        SegmentOptions.resolve(W, resolution="4096px")
    with pytest.raises(InvalidOptionError, match="not both"):
        SegmentOptions.resolve(W, mode="approx", resolution=0.5, tolerance=0.5)
    with pytest.raises(InvalidOptionError, match="applies to mode='approx'"):
        PathOptions.resolve(W, resolution="4096px")


@pytest.mark.parametrize("n", ["auto", "AUTO", "Auto"])
def test_auto_n_is_stored_as_zero(n):
    assert SegmentOptions.resolve(W, n=n).n == 0


@pytest.mark.parametrize("n", [N_MIN, 7, N_MAX, np.int64(5), np.uint8(3)])
def test_integer_n_in_range_is_kept(n):
    assert SegmentOptions.resolve(W, n=n).n == int(n)


@pytest.mark.parametrize("n", [1, 0, -3, N_MAX + 1])
def test_n_out_of_range_is_refused(n):
    with pytest.raises(InvalidOptionError, match=f"n must be in {N_MIN}..{N_MAX}"):
        SegmentOptions.resolve(W, n=n)


@pytest.mark.parametrize("n", [True, 2.0, 2.5, "3", "many", None])
def test_n_of_another_type_is_refused(n):
    with pytest.raises(InvalidOptionError, match="n must be an integer"):
        SegmentOptions.resolve(W, n=n)


def test_midpoint_always_bisects():
    assert SegmentOptions.resolve(W, method="midpoint", n=17).n == 2
    assert SegmentOptions.resolve(W, method="midpoint").n == 2


@pytest.mark.parametrize("depth", [0, 1, MAX_DEPTH_LIMIT, np.int32(12)])
def test_max_depth_in_range_is_kept(depth):
    assert SegmentOptions.resolve(W, max_depth=depth).max_depth == int(depth)


@pytest.mark.parametrize("depth, message", [
    (-1, "in 0..32"), (MAX_DEPTH_LIMIT + 1, "in 0..32"), (3.0, "integer"), (False, "integer"),
    ("4", "integer"),
])
def test_bad_max_depth_is_refused(depth, message):
    with pytest.raises(InvalidOptionError, match=message):
        SegmentOptions.resolve(W, max_depth=depth)


@pytest.mark.parametrize("tolerance", [1e-300, 0.5, 7, np.float32(0.25), math.inf])
def test_positive_tolerance_is_kept(tolerance):
    assert SegmentOptions.resolve(W, tolerance=tolerance).tolerance == float(tolerance)


@pytest.mark.parametrize("tolerance", [0.0, -1.0, -math.inf, math.nan])
def test_non_positive_or_nan_tolerance_is_refused(tolerance):
    with pytest.raises(InvalidOptionError, match="tolerance must be > 0"):
        SegmentOptions.resolve(W, tolerance=tolerance)


@pytest.mark.parametrize("tolerance", [True, "small", [1.0], object()])
def test_tolerance_of_another_type_is_refused(tolerance):
    with pytest.raises(InvalidOptionError, match="tolerance must be a positive number"):
        SegmentOptions.resolve(W, tolerance=tolerance)


def test_resolved_options_are_immutable():
    opts = SegmentOptions.resolve(W)
    with pytest.raises(AttributeError):
        opts.n = 4
