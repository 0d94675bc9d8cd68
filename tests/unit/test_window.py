"""Window: a closed, finite rectangle with min < max, validated once."""

import math

import numpy as np
import pytest

from rnsca import InvalidWindowError, Window


def test_bounds_are_stored_as_floats():
    w = Window(0, 1, 10, 5)
    assert w.bounds == (0.0, 1.0, 10.0, 5.0)
    assert all(type(v) is float for v in w.bounds)


def test_array_scalars_are_accepted_as_bounds():
    w = Window(np.float32(0.5), np.int64(0), np.float64(2.0), np.int32(3))
    assert w.bounds == (0.5, 0.0, 2.0, 3.0)


def test_width_height_and_size_of_a_wide_window():
    w = Window(-2.0, 1.0, 8.0, 5.0)
    assert (w.width, w.height, w.size) == (10.0, 4.0, 10.0)


def test_size_is_the_longer_side_of_a_tall_window():
    assert Window(0.0, 0.0, 1.0, 3.0).size == 3.0


def test_window_is_immutable():
    w = Window(0, 0, 1, 1)
    with pytest.raises(AttributeError):
        w.xmin = 5.0


def test_windows_with_the_same_bounds_are_equal_and_hash_alike():
    assert Window(0, 0, 1, 1) == Window(0.0, 0.0, 1.0, 1.0)
    assert len({Window(0, 0, 1, 1), Window(0.0, 0.0, 1.0, 1.0)}) == 1


@pytest.mark.parametrize("bounds, message", [
    ((0, 0, 0, 5), "xmin < xmax"),
    ((1, 0, 0, 5), "xmin < xmax"),
    ((0, 5, 10, 5), "ymin < ymax"),
    ((0, 6, 10, 5), "ymin < ymax"),
])
def test_empty_or_inverted_window_is_refused(bounds, message):
    with pytest.raises(InvalidWindowError, match=message):
        Window(*bounds)


@pytest.mark.parametrize("name, index", [("xmin", 0), ("ymin", 1), ("xmax", 2), ("ymax", 3)])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_bound_is_refused_and_named(name, index, value):
    bounds = [0.0, 0.0, 1.0, 1.0]
    bounds[index] = value
    with pytest.raises(InvalidWindowError, match=f"{name} must be finite"):
        Window(*bounds)


@pytest.mark.parametrize("value", [None, "left", [1.0], object()])
def test_non_numeric_bound_is_refused(value):
    with pytest.raises(InvalidWindowError, match="xmin must be a number"):
        Window(value, 0, 1, 1)


def test_window_wider_than_float64_can_hold_is_refused():
    with pytest.raises(InvalidWindowError, match="finite in float64"):
        Window(-1e308, 0.0, 1e308, 1.0)


def test_invalid_window_error_is_a_value_error():
    with pytest.raises(ValueError):
        Window(0, 0, 0, 0)


def test_window_of_accepts_a_window_unchanged():
    w = Window(0, 0, 1, 1)
    assert Window.of(w) is w


@pytest.mark.parametrize("bounds", [(0, 0, 2, 1), [0, 0, 2, 1], np.array([0.0, 0.0, 2.0, 1.0])])
def test_window_of_accepts_four_bounds(bounds):
    assert Window.of(bounds) == Window(0.0, 0.0, 2.0, 1.0)


@pytest.mark.parametrize("bounds", [(0, 0, 1), (0, 0, 1, 1, 2), ()])
def test_window_of_refuses_a_wrong_number_of_bounds(bounds):
    with pytest.raises(InvalidWindowError, match="4 bounds"):
        Window.of(bounds)


def test_window_of_refuses_a_non_sequence():
    with pytest.raises(InvalidWindowError, match="must be a Window or"):
        Window.of(3.0)


def test_tiny_and_huge_windows_are_valid():
    assert Window(0.0, 0.0, 1e-310, 1e-310).size == 1e-310
    assert Window(-1e300, -1e300, 1e300, 1e300).size == 2e300
