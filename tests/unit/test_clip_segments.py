"""clip_segments: input validation, the result's fields, and its contract.

Validation is the same whatever the method, mode or backend, and happens before any
kernel runs; the contract (source order, t consistent with the pieces, pieces inside)
is checked here on seeded random inputs for every method, mode and backend.
"""

import math
import re

import numpy as np
import pytest

from rnsca import (
    BackendUnavailableError,
    ClipStats,
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    Method,
    Mode,
    SegmentClipResult,
    Window,
    clip_segments,
)
from rnsca.options import SegmentOptions
from tests.checks import assert_inside_window, assert_t_matches_pieces, assert_well_formed

W10 = (0.0, 0.0, 10.0, 10.0)
ACROSS = [[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0], [1.0, 1.0, 2.0, 3.0]]
ACROSS_PIECES = [[0.0, 5.0, 10.0, 5.0], [1.0, 1.0, 2.0, 3.0]]


# --- accepted input forms --------------------------------------------------------------------

def test_rows_of_four_are_clipped():
    r = clip_segments(np.array(ACROSS), W10)
    np.testing.assert_array_equal(r.segments, ACROSS_PIECES)
    np.testing.assert_array_equal(r.source, [0, 2])


def test_pairs_of_points_are_clipped_like_rows_of_four():
    r = clip_segments(np.array(ACROSS).reshape(-1, 2, 2), W10)
    np.testing.assert_array_equal(r.segments, ACROSS_PIECES)
    np.testing.assert_array_equal(r.source, [0, 2])


def test_nested_lists_are_clipped():
    r = clip_segments([[[-5, 5], [15, 5]]], W10)
    np.testing.assert_array_equal(r.segments, [[0.0, 5.0, 10.0, 5.0]])


@pytest.mark.parametrize("dtype", [np.int8, np.int32, np.int64, np.uint16, np.float16,
                                   np.float32])
def test_other_real_dtypes_are_converted_to_float64(dtype):
    r = clip_segments(np.array([[1, 2, 3, 4], [20, 20, 30, 30]], dtype=dtype), W10)
    assert r.segments.dtype == np.float64
    np.testing.assert_array_equal(r.segments, [[1.0, 2.0, 3.0, 4.0]])


def test_non_contiguous_input_is_clipped():
    wide = np.zeros((3, 8))
    wide[:, ::2] = ACROSS
    r = clip_segments(wide[:, ::2], W10)
    np.testing.assert_array_equal(r.segments, ACROSS_PIECES)


def test_input_array_is_not_modified():
    segs = np.array(ACROSS)
    before = segs.copy()
    clip_segments(segs, W10)
    np.testing.assert_array_equal(segs, before)


@pytest.mark.parametrize("window", [W10, list(W10), Window(*W10), np.array(W10)])
def test_window_may_be_a_window_or_four_bounds(window):
    np.testing.assert_array_equal(clip_segments(ACROSS, window).segments, ACROSS_PIECES)


# --- empty input -------------------------------------------------------------------------------

@pytest.mark.parametrize("empty", [[], np.empty((0, 4)), np.empty((0, 2, 2)),
                                   np.empty((0, 4), dtype=np.int32)])
def test_empty_input_gives_an_empty_result(empty, method, mode, backend):
    r = clip_segments(empty, W10, method=method, mode=mode, backend=backend)
    assert r.segments.shape == (0, 4) and r.segments.dtype == np.float64
    assert r.source.shape == (0,) and r.source.dtype == np.int64
    assert r.t.shape == (0, 2) and r.t.dtype == np.float64
    assert len(r) == 0
    assert r.stats.segments_in == 0 and r.stats.pieces_out == 0
    assert r.stats.fragments_evaluated == 0 and sum(r.stats.decided_per_level) == 0


# --- refused input -----------------------------------------------------------------------------

@pytest.mark.parametrize("shape", [(4,), (3, 3), (3, 5), (2, 4, 1), (3, 2, 3), (3, 3, 2),
                                   (1, 2, 2, 1), (0, 3)])
def test_wrong_shape_is_refused_with_the_shape(shape):
    with pytest.raises(InvalidGeometryError, match=re.escape(str(shape))):
        clip_segments(np.zeros(shape), W10)


def test_scalar_is_refused():
    with pytest.raises(InvalidGeometryError, match="shape"):
        clip_segments(3.0, W10)


@pytest.mark.parametrize("array", [
    np.zeros((2, 4), dtype=bool),
    np.zeros((2, 4), dtype=np.complex128),
    np.array([["a", "b", "c", "d"]]),
    np.array([[1.0, 2.0, None, 4.0]], dtype=object),
    np.zeros((2, 4), dtype="datetime64[s]"),
])
def test_non_real_dtype_is_refused_with_the_dtype(array):
    with pytest.raises(InvalidGeometryError, match=f"got {re.escape(str(array.dtype))}"):
        clip_segments(array, W10)


def test_ragged_rows_are_refused():
    with pytest.raises(InvalidGeometryError, match="numeric array"):
        clip_segments([[0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 1.0]], W10)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("column", [0, 1, 2, 3])
def test_non_finite_coordinate_is_refused_naming_the_first_bad_row(bad, column):
    segs = np.array([[0.0, 0.0, 1.0, 1.0]] * 5)
    segs[2, column] = bad
    segs[4, 0] = bad
    with pytest.raises(InvalidGeometryError, match="segment 2 has a non-finite coordinate"):
        clip_segments(segs, W10)


def test_non_finite_coordinate_in_pairs_of_points_names_its_segment():
    segs = np.zeros((3, 2, 2))
    segs[1, 1, 0] = math.nan
    with pytest.raises(InvalidGeometryError, match="segment 1 "):
        clip_segments(segs, W10)


@pytest.mark.parametrize("row", [[-1e308, 0.0, 1e308, 0.0], [0.0, 1.7e308, 0.0, -1.7e308]])
def test_segment_whose_span_overflows_is_refused_naming_it(row):
    segs = np.array([[0.0, 0.0, 1.0, 1.0], row])
    with pytest.raises(InvalidGeometryError, match="segment 1 spans more than float64"):
        clip_segments(segs, W10)


def test_geometry_errors_are_value_errors():
    with pytest.raises(ValueError):
        clip_segments([[math.nan, 0.0, 1.0, 1.0]], W10)


def test_invalid_window_is_refused():
    with pytest.raises(InvalidWindowError):
        clip_segments(ACROSS, (0.0, 0.0, -1.0, 1.0))


@pytest.mark.parametrize("option", [{"method": "fast"}, {"mode": "sloppy"}, {"n": 1},
                                    {"max_depth": 40}, {"tolerance": -1.0},
                                    {"backend": "abacus"}])
def test_invalid_option_is_refused(option):
    with pytest.raises(InvalidOptionError):
        clip_segments(ACROSS, W10, **option)


def test_backend_unavailable_error_is_a_runtime_error():
    assert issubclass(BackendUnavailableError, RuntimeError)


# --- the result --------------------------------------------------------------------------------

def test_result_reports_what_ran_with_the_resolved_options(backend):
    r = clip_segments(ACROSS, W10, method="liang_barsky", mode="approx", backend=backend)
    assert isinstance(r, SegmentClipResult)
    assert (r.method, r.mode, r.backend) == (Method.LIANG_BARSKY, Mode.APPROX, backend)
    assert r.options == SegmentOptions.resolve(Window(*W10), method="liang_barsky",
                                               mode="approx")
    assert isinstance(r.stats, ClipStats)
    assert len(r) == 2


def test_result_fields_have_literal_values(backend):
    r = clip_segments(ACROSS, W10, backend=backend)
    np.testing.assert_array_equal(r.segments, ACROSS_PIECES)
    np.testing.assert_array_equal(r.source, [0, 2])
    np.testing.assert_array_equal(r.t, [[0.25, 0.75], [0.0, 1.0]])
    assert (r.stats.segments_in, r.stats.pieces_out) == (3, 2)


def test_result_is_immutable():
    r = clip_segments(ACROSS, W10)
    with pytest.raises(AttributeError):
        r.segments = None


def random_segments(rng, n=400):
    """Mixed segments around W10: random, lattice (on edges and corners), zero-length."""
    random = rng.uniform(-10.0, 20.0, size=(n, 4))
    lattice = rng.integers(-2, 7, size=(n, 4)) * 2.5
    zero = np.repeat(rng.integers(-1, 6, size=(n // 4, 2)) * 2.5, 2, axis=0).reshape(-1, 4)
    return np.concatenate([random, lattice, zero])


def test_result_contract_on_random_segments(rng, method, mode, backend):
    segs = random_segments(rng)
    r = clip_segments(segs, W10, method=method, mode=mode, backend=backend,
                      tolerance=0.01 if mode is Mode.EXACT else None)
    assert_well_formed(r, segs.shape[0])
    assert_inside_window(r, W10)
    assert_t_matches_pieces(r, segs)


def test_source_is_strictly_increasing_over_many_blocks(backend):
    # More segments than one parallel block holds, every other one kept.
    n = 20_001
    segs = np.zeros((n, 4))
    segs[:, 0] = np.where(np.arange(n) % 2 == 0, 1.0, 20.0)
    segs[:, 2] = segs[:, 0] + 1.0
    r = clip_segments(segs, W10, backend=backend)
    np.testing.assert_array_equal(r.source, np.arange(0, n, 2))
    np.testing.assert_array_equal(r.segments, segs[::2])
