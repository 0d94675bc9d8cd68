"""Every method, mode and backend against the clip computed in exact rational arithmetic.

The same promises as `test_vs_shapely` (exact mode within 1e-9 of the window's size per
segment; approx mode never more than the true clip, and within one leaf of it at each
cut end), but the oracle is `tests.cases.exact_clip`: Python fractions on the float
inputs, rounded once at the end. It has no magnitude limits, so it takes what GEOS
cannot: subnormal offsets next to edges at zero, windows from 1e-290 to 1e290, and
coordinates far larger than the window.
"""

from hypothesis import given

from rnsca import clip_segments
from tests.checks import (
    assert_inside_window,
    assert_piece_is_expected,
    assert_well_formed,
    exact_pieces,
)
from tests.property.strategies import clip_inputs


@given(case=clip_inputs())
def test_pieces_match_the_exact_rational_clip(method, mode, backend, case):
    window, segments, options = case
    result = clip_segments(segments, window, method=method, mode=mode, backend=backend,
                           **options)
    assert_well_formed(result, segments.shape[0])
    assert_inside_window(result, window)
    assert_piece_is_expected(result, segments, exact_pieces(segments, window), window,
                             method, mode)
