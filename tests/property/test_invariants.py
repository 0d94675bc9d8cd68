"""Invariants of clipping that need no oracle, for every method, mode and backend.

- a segment inside the closed window comes back unchanged, with t = [0, 1];
- a segment with both ends beyond one edge gives nothing;
- clipping the output again gives the same output (idempotence);
- every output vertex lies in the closed window (no tolerance), pieces keep their
  segment's direction, and t places each piece's ends on its segment;
- approx mode gives a sub-interval of the exact clip, at most one leaf shorter at each
  end (`rnsca.verify.approx_leaf_bound`);
- all exact methods agree with each other within 1e-9 of the window's size.
"""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from rnsca import Method, Mode, clip_segments
from rnsca.verify import approx_leaf_bound
from tests.checks import (
    EPS,
    EXACT_RELATIVE,
    assert_inside_window,
    assert_t_matches_pieces,
    assert_well_formed,
    hausdorff,
    lengths,
    pieces_by_source,
)
from tests.property.strategies import (
    beyond_one_edge_batches,
    clip_inputs,
    inside_batches,
    options,
    windows,
)


@st.composite
def inside_inputs(draw):
    w = draw(windows())
    return w, draw(inside_batches(w)), draw(options(w))


@st.composite
def beyond_one_edge_inputs(draw):
    w = draw(windows())
    return w, draw(beyond_one_edge_batches(w)), draw(options(w))


@given(case=inside_inputs())
def test_segments_inside_are_returned_unchanged(method, mode, backend, case):
    window, segments, opts = case
    r = clip_segments(segments, window, method=method, mode=mode, backend=backend, **opts)
    np.testing.assert_array_equal(r.segments, segments)
    np.testing.assert_array_equal(r.source, np.arange(segments.shape[0]))
    np.testing.assert_array_equal(r.t, np.tile([0.0, 1.0], (segments.shape[0], 1)))


@given(case=beyond_one_edge_inputs())
def test_segments_beyond_one_edge_give_nothing(method, mode, backend, case):
    window, segments, opts = case
    r = clip_segments(segments, window, method=method, mode=mode, backend=backend, **opts)
    assert len(r) == 0, r.segments


@given(case=clip_inputs())
def test_clipping_twice_equals_clipping_once(method, mode, backend, case):
    window, segments, opts = case
    once = clip_segments(segments, window, method=method, mode=mode, backend=backend, **opts)
    twice = clip_segments(once.segments, window, method=method, mode=mode, backend=backend,
                          **opts)
    np.testing.assert_array_equal(twice.segments, once.segments)
    np.testing.assert_array_equal(twice.source, np.arange(len(once)))


@given(case=clip_inputs())
def test_pieces_are_inside_on_their_segment_and_in_its_direction(method, mode, backend, case):
    window, segments, opts = case
    r = clip_segments(segments, window, method=method, mode=mode, backend=backend, **opts)
    assert_well_formed(r, segments.shape[0])
    assert_inside_window(r, window)
    assert_t_matches_pieces(r, segments)
    src = segments[r.source]
    piece_direction = r.segments[:, 2:] - r.segments[:, :2]
    along = np.einsum("ij,ij->i", piece_direction, src[:, 2:] - src[:, :2])
    # A piece shorter than rounding has no meaningful direction.
    rounding = 16 * EPS * np.abs(src).max(axis=1)
    long_enough = lengths(r.segments) > rounding
    assert (along[long_enough] >= 0).all(), r.segments[long_enough & (along < 0)]


@given(case=clip_inputs())
def test_approx_piece_is_a_sub_interval_of_the_exact_piece(backend, case):
    window, segments, opts = case
    margin = EXACT_RELATIVE * window.size
    length = lengths(segments)
    exact = pieces_by_source(clip_segments(segments, window, method="liang_barsky",
                                           backend=backend), segments.shape[0])
    exact_t = _t_by_source(clip_segments(segments, window, method="liang_barsky",
                                         backend=backend), segments.shape[0])
    for method in (Method.RNSCA, Method.MIDPOINT):
        r = clip_segments(segments, window, method=method, mode="approx", backend=backend,
                          **opts)
        bound = approx_leaf_bound(length, r) + margin
        got_t = _t_by_source(r, segments.shape[0])
        for i in range(segments.shape[0]):
            where = f"{method.value} segment {i} {segments[i].tolist()} in {window.bounds}"
            if got_t[i] is None:
                assert exact[i] is None or lengths(exact[i])[0] <= 2 * bound[i], where
                continue
            if exact_t[i] is None:  # at most a rounding-sized piece where there is none
                assert lengths(r.segments[r.source == i])[0] <= margin, where
                continue
            lost_start = (got_t[i][0] - exact_t[i][0]) * length[i]
            lost_end = (exact_t[i][1] - got_t[i][1]) * length[i]
            assert -margin <= lost_start <= bound[i], (where, lost_start, bound[i])
            assert -margin <= lost_end <= bound[i], (where, lost_end, bound[i])


@given(case=clip_inputs())
def test_exact_methods_agree_with_each_other(backend, case):
    window, segments, opts = case
    n = segments.shape[0]
    reference = pieces_by_source(clip_segments(segments, window, method="liang_barsky",
                                               backend=backend), n)
    for method in Method:
        r = clip_segments(segments, window, method=method, mode=Mode.EXACT, backend=backend,
                          **opts)
        for i, (got, want) in enumerate(zip(pieces_by_source(r, n), reference, strict=True)):
            assert hausdorff(got, want) <= EXACT_RELATIVE * window.size, (
                f"{method.value} vs liang_barsky, segment {i} {segments[i].tolist()} in "
                f"{window.bounds}: {got} vs {want}")


def _t_by_source(result, n):
    out = [None] * n
    for t, i in zip(result.t, result.source, strict=True):
        out[int(i)] = t
    return out
