"""The input checks of rnsca.kernels.validate, compiled and (NUMBA_DISABLE_JIT=1) not."""

import numpy as np
import pytest

from rnsca.kernels.validate import BLOCK_SIZE, all_finite, first_invalid_segment

# Under NUMBA_DISABLE_JIT the kernels run as Python on NumPy scalars, which warn on inf * 0
# and on an overflowing difference.
pytestmark = [pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning"),
              pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")]


@pytest.mark.parametrize("shape", [(0, 2), (1, 2), (7, 3), (1000, 2)])
def test_all_finite_accepts_finite_coordinates(shape):
    coords = np.arange(np.prod(shape), dtype=np.float64).reshape(shape) * 1e300
    assert all_finite(coords)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("row, column", [(0, 0), (500, 1), (999, 2)])
def test_all_finite_finds_any_non_finite_value(bad, row, column):
    coords = np.ones((1000, 3))
    coords[row, column] = bad
    assert not all_finite(coords)


@pytest.mark.parametrize("bad_row", [0, 5, 99])
def test_first_invalid_segment_names_the_first_bad_row(bad_row):
    segments = np.zeros((100, 4))
    segments[bad_row, 3] = np.nan
    segments[bad_row + 1 :, 0] = np.inf
    assert first_invalid_segment(segments) == bad_row


def test_first_invalid_segment_catches_a_span_that_overflows():
    segments = np.zeros((3, 4))
    segments[1] = [-1e308, 0.0, 1e308, 0.0]
    assert first_invalid_segment(segments) == 1
    assert first_invalid_segment(segments[:1]) == -1


@pytest.mark.slow
def test_first_invalid_segment_across_parallel_blocks():
    segments = np.zeros((2 * BLOCK_SIZE + 10, 4))
    assert first_invalid_segment(segments) == -1
    segments[BLOCK_SIZE + 3, 2] = -np.inf
    segments[-1, 1] = np.nan
    assert first_invalid_segment(segments) == BLOCK_SIZE + 3


@pytest.mark.parametrize("where, value", [(0, np.nan), ((1 << 20) - 1, np.inf),
                                          (3 * (1 << 20) + 7, -np.inf), (-1, np.nan)])
def test_all_finite_in_parallel_blocks_finds_any_value(where, value):
    from rnsca.kernels.validate import FINITE_BLOCK, all_finite

    values = np.ones(4 * FINITE_BLOCK + 123)  # past the one-thread size: blocks
    assert all_finite(values)
    values[where] = value
    assert not all_finite(values)
