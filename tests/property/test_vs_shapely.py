"""Every method, mode and backend against Shapely, the spec, on drawn adversarial inputs.

Two independent comparisons of the same results:

- `rnsca.verify` must pass: exact mode within 1e-9 of the window's size (Hausdorff, per
  segment); approx mode with no false positive and within its leaf bound;
- `tests.checks.shapely_pieces` (its own Shapely calls and NumPy distances): per segment,
  exact mode within 1e-9 of the window's size of ``shapely.intersection``; approx mode
  no piece where Shapely has none, each end on Shapely's piece and within one leaf of
  its end, a missing piece only if Shapely's is at most two leaves long.

Both treat the window as closed: a point of contact is no piece, a zero-length segment
inside is its own piece. Inputs are drawn by `tests.property.strategies`; the same
comparison against exact rational arithmetic, which needs no rescaling and so also takes
the inputs Shapely cannot, is `tests/property/test_vs_exact.py`.
"""

import numpy as np
from hypothesis import assume, example, given

from rnsca import Window, clip_segments, verify
from tests import cases
from tests.checks import (
    assert_inside_window,
    assert_piece_is_expected,
    assert_well_formed,
    is_exact,
    shapely_can_judge,
    shapely_pieces,
)
from tests.property.strategies import clip_inputs

#: Every hand-made case in the 10 x 10 window, as one batch.
W10_BATCH = (Window(*cases.W10), np.array([c.segment for c in cases.CASES.values()
                                  if c.window == cases.W10]), {})


def judgeable(case):
    """Return `case` without the segments GEOS mishandles (subnormal coordinates);
    `test_vs_exact` covers those."""
    window, segments, options = case
    segments = segments[shapely_can_judge(window, segments)]
    assume(segments.shape[0] > 0)
    return window, segments, options


def clip(case, method, mode, backend):
    window, segments, options = case
    result = clip_segments(segments, window, method=method, mode=mode, backend=backend,
                           **options)
    assert_well_formed(result, segments.shape[0])
    assert_inside_window(result, window)
    return result


@given(case=clip_inputs())
@example(case=W10_BATCH)
def test_pieces_match_shapely_intersection(method, mode, backend, case):
    case = judgeable(case)
    window, segments, _ = case
    result = clip(case, method, mode, backend)
    expected = shapely_pieces(segments, window)
    assert_piece_is_expected(result, segments, expected, window, method, mode)


@given(case=clip_inputs())
@example(case=W10_BATCH)
def test_verify_passes(method, mode, backend, case):
    case = judgeable(case)
    window, segments, _ = case
    result = clip(case, method, mode, backend)
    v = verify(segments, result, window)
    assert v.false_positives == 0, v
    assert v.passed, v
    assert v.mode == result.mode.value
    if is_exact(method, mode):
        assert v.max_deviation <= 1e-9 * window.size, v


@given(case=clip_inputs(kinds=("boundary", "along_edge", "touching_corner", "zero_length",
                               "lattice"), min_exponent=-3, max_exponent=3))
def test_boundary_cases_match_shapely_intersection(method, mode, backend, case):
    # Concentrated on the closed-boundary rules, at everyday magnitudes.
    case = judgeable(case)
    window, segments, _ = case
    result = clip(case, method, mode, backend)
    expected = shapely_pieces(segments, window)
    assert_piece_is_expected(result, segments, expected, window, method, mode)
