"""Every segment method on the backends, on cases small enough to work out by hand.

(These were the NumPy reference backend's tests; the backend is gone, the cases stay.)
"""

import sys

import numpy as np
import pytest

from rnsca import Method, Window, clip_segments

WINDOW = Window(0.0, 0.0, 10.0, 10.0)
EXACT_METHODS = list(Method)  # every method is exact in exact mode


BACKEND = "numba"


@pytest.fixture(autouse=True)
def _on_each_backend(backend, monkeypatch):
    """Run every case on each backend (the `backend` fixture sets `BACKEND`)."""
    monkeypatch.setattr(sys.modules[__name__], "BACKEND", backend)


def clip(segments, method="rnsca", window=WINDOW, **options):
    """Return (pieces, source, t, stats) of the backend under test."""
    array = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    r = clip_segments(array, window, method=method, backend=BACKEND, **options)
    return r.segments, r.source, r.t, r.stats


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_crossing_left_edge_is_cut_at_the_edge(method):
    pieces, source, t, _ = clip([[-5.0, 2.0, 5.0, 6.0]], method)
    np.testing.assert_array_equal(pieces, [[0.0, 4.0, 5.0, 6.0]])
    np.testing.assert_array_equal(source, [0])
    np.testing.assert_array_equal(t, [[0.5, 1.0]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_crossing_the_window_is_cut_at_both_edges(method):
    pieces, _, t, _ = clip([[-5.0, 5.0, 15.0, 5.0]], method)
    np.testing.assert_array_equal(pieces, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_array_equal(t, [[0.25, 0.75]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_diagonal_through_two_corners_is_cut_at_the_corners(method):
    pieces, _, t, _ = clip([[-5.0, -5.0, 15.0, 15.0]], method)
    np.testing.assert_array_equal(pieces, [[0.0, 0.0, 10.0, 10.0]])
    np.testing.assert_array_equal(t, [[0.25, 0.75]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_piece_keeps_the_direction_of_its_segment(method):
    pieces, _, t, _ = clip([[15.0, 5.0, -5.0, 5.0]], method)
    np.testing.assert_array_equal(pieces, [[10.0, 5.0, 0.0, 5.0]])
    np.testing.assert_array_equal(t, [[0.25, 0.75]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_entering_from_below_left_is_cut_at_the_bottom_edge(method):
    # Direction (10, 10) from (-2, -3): below the bottom-left corner's ray, so it meets
    # the bottom edge (at t = 0.3) after passing the left edge's line outside.
    pieces, _, t, _ = clip([[-2.0, -3.0, 8.0, 7.0]], method)
    np.testing.assert_array_equal(pieces, [[1.0, 0.0, 8.0, 7.0]])
    np.testing.assert_array_equal(t, [[0.3, 1.0]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_inside_is_kept_whole(method):
    pieces, source, t, stats = clip([[1.0, 2.0, 3.0, 4.0]], method)
    np.testing.assert_array_equal(pieces, [[1.0, 2.0, 3.0, 4.0]])
    np.testing.assert_array_equal(source, [0])
    np.testing.assert_array_equal(t, [[0.0, 1.0]])
    assert (stats.accepted, stats.fragments_evaluated) == (1, 1)


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_along_an_edge_is_inside(method):
    pieces, _, t, _ = clip([[0.0, 2.0, 0.0, 8.0], [3.0, 10.0, 12.0, 10.0]], method)
    np.testing.assert_array_equal(pieces, [[0.0, 2.0, 0.0, 8.0], [3.0, 10.0, 10.0, 10.0]])
    np.testing.assert_array_equal(t, [[0.0, 1.0], [0.0, 7.0 / 9.0]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_beyond_one_edge_is_dropped(method):
    pieces, source, t, stats = clip([[11.0, -5.0, 20.0, 15.0]], method)
    assert pieces.shape == (0, 4) and source.shape == (0,) and t.shape == (0, 2)
    assert stats.rejected == 1


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_segment_touching_only_a_corner_gives_no_piece(method):
    pieces, _, _, _ = clip([[-5.0, 5.0, 5.0, -5.0]], method)
    assert pieces.shape == (0, 4)


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_zero_length_segment_is_kept_inside_and_dropped_outside(method):
    pieces, source, t, _ = clip([[5.0, 5.0, 5.0, 5.0], [-1.0, 5.0, -1.0, 5.0]], method)
    np.testing.assert_array_equal(pieces, [[5.0, 5.0, 5.0, 5.0]])
    np.testing.assert_array_equal(source, [0])
    np.testing.assert_array_equal(t, [[0.0, 1.0]])


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_source_names_the_input_segment_of_each_piece(method):
    segments = [[20.0, 20.0, 30.0, 30.0], [1.0, 1.0, 2.0, 2.0], [-9.0, -9.0, -1.0, -1.0],
                [5.0, 5.0, 15.0, 5.0]]
    pieces, source, _, stats = clip(segments, method)
    np.testing.assert_array_equal(source, [1, 3])
    np.testing.assert_array_equal(pieces, [[1.0, 1.0, 2.0, 2.0], [5.0, 5.0, 10.0, 5.0]])
    assert (stats.segments_in, stats.pieces_out) == (4, 2)


@pytest.mark.parametrize("method", EXACT_METHODS)
def test_empty_input_gives_empty_arrays_and_zero_stats(method):
    pieces, source, t, stats = clip(np.empty((0, 4)), method)
    assert pieces.shape == (0, 4) and source.shape == (0,) and t.shape == (0, 2)
    assert source.dtype == np.int64
    assert stats.fragments_evaluated == 0 and stats.decided_per_level == (0,) * 33


def test_rnsca_exact_mode_decides_at_level_0_by_default():
    _, _, t, stats = clip([[-1.0, 5.0, 11.0, 5.0]], mode="exact")
    np.testing.assert_allclose(t, [[1.0 / 12.0, 11.0 / 12.0]], rtol=1e-15)
    assert (stats.fragments_evaluated, stats.clipped, stats.deepest_level) == (1, 1, 0)


def test_rnsca_splits_level_by_level_and_counts_every_fragment():
    # N = 2, depth 3, in approx mode: the edges x = 0 and x = 10 fall on the division
    # points t = 1/4 and t = 3/4, so the accepted pieces of level 2 already give the
    # exact piece; the two leaves beside them at level 3 are dropped.
    pieces, _, t, stats = clip([[-5.0, 5.0, 15.0, 5.0]], n=2, max_depth=3, mode="approx")
    np.testing.assert_array_equal(pieces, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_array_equal(t, [[0.25, 0.75]])
    assert (stats.fragments_evaluated, stats.accepted, stats.rejected, stats.subdivided,
            stats.clipped, stats.dropped, stats.intersections) == (11, 2, 2, 5, 0, 2, 0)
    assert stats.deepest_level == 3
    assert stats.decided_per_level[:4] == (0, 0, 2, 4)


def test_rnsca_approx_mode_loses_at_most_the_dropped_leaves():
    # Depth 2, N = 2: leaves [0, 1/4] and [3/4, 1] straddle the edges and are dropped,
    # so the piece is the accepted middle half: no intersection is computed.
    pieces, _, t, stats = clip([[-1.0, 5.0, 11.0, 5.0]], n=2, max_depth=2, mode="approx")
    np.testing.assert_array_equal(pieces, [[2.0, 5.0, 8.0, 5.0]])
    np.testing.assert_array_equal(t, [[0.25, 0.75]])
    assert (stats.dropped, stats.intersections) == (2, 0)


def test_rnsca_exact_mode_clips_the_straddling_leaves():
    # A finite tolerance makes exact mode subdivide; each leaf is cut at its one edge.
    pieces, _, t, stats = clip([[-1.0, 5.0, 11.0, 5.0]], n=2, max_depth=2, mode="exact",
                               tolerance=0.1)
    np.testing.assert_array_equal(pieces, [[0.0, 5.0, 10.0, 5.0]])
    np.testing.assert_allclose(t, [[1.0 / 12.0, 11.0 / 12.0]], rtol=1e-15)
    assert (stats.clipped, stats.dropped, stats.intersections) == (2, 0, 2)


def test_midpoint_approx_mode_keeps_the_visible_end_of_each_bracket():
    pieces, _, t, stats = clip([[-1.0, 5.0, 11.0, 5.0]], "midpoint", max_depth=2,
                               mode="approx")
    np.testing.assert_array_equal(pieces, [[2.0, 5.0, 8.0, 5.0]])
    np.testing.assert_array_equal(t, [[0.25, 0.75]])
    assert (stats.dropped, stats.intersections, stats.deepest_level) == (2, 0, 2)


def test_liang_barsky_divides_once_per_edge_line_it_is_not_parallel_to():
    _, _, _, stats = clip([[-5.0, 5.0, 15.0, 5.0], [-5.0, 1.0, 15.0, 6.0]], "liang_barsky")
    # Horizontal: left and right only. Sloped: all four.
    assert (stats.clipped, stats.intersections) == (2, 6)


def test_cohen_sutherland_counts_one_evaluation_per_pass():
    # Both ends outside: pass 1 moves P0 to x = 0, pass 2 moves P1 to x = 10, pass 3 accepts.
    _, _, _, stats = clip([[-5.0, 5.0, 15.0, 5.0]], "cohen_sutherland")
    assert (stats.fragments_evaluated, stats.clipped, stats.accepted,
            stats.intersections) == (3, 2, 1, 2)


def test_nicholl_lee_nicholl_computes_at_most_two_intersections():
    _, _, _, stats = clip([[-5.0, -5.0, 15.0, 15.0], [-2.0, -3.0, 8.0, 7.0]],
                          "nicholl_lee_nicholl")
    assert (stats.clipped, stats.intersections) == (2, 3)


def test_every_piece_lies_in_the_closed_window():
    rng = np.random.default_rng(3)
    window = Window(-1.5, 2.0, 0.7, 2.1)
    segments = rng.uniform(-4.0, 4.0, size=(300, 4))
    for method in Method:
        for mode in ("exact", "approx"):
            pieces, source, t, stats = clip(segments, method, window, mode=mode)
            assert np.all((pieces[:, 0::2] >= window.xmin) & (pieces[:, 0::2] <= window.xmax))
            assert np.all((pieces[:, 1::2] >= window.ymin) & (pieces[:, 1::2] <= window.ymax))
            assert np.all(np.diff(source) > 0)
            assert np.all((0.0 <= t[:, 0]) & (t[:, 0] <= t[:, 1]) & (t[:, 1] <= 1.0))
            assert (stats.accepted + stats.rejected + stats.subdivided + stats.clipped
                    + stats.dropped) == stats.fragments_evaluated


def test_equal_parameters_keep_the_end_the_depth_first_kernel_meets_first():
    # Two exact leaves meet at t = 0.28, a hair above the bottom edge: the left one's
    # clipped start is on the edge, (0.99, 0.0); the right one starts at the computed
    # point (0.99, 8.3e-17: the true position at that t, not its 1.1e-16 rounding).
    # Both start the merged interval at t = 0.28. The Numba kernel
    # walks the subdivision tree depth first, rightmost child first, and keeps the first
    # of equal starts it meets: the right leaf's. Breadth first, the reference must
    # break the tie by the same walk order to give the same point.
    pieces, _, t, stats = clip([[0.5, -0.875, 2.25, 2.25]], window=Window(0.0, 0.0, 1.0, 1.0),
                               n=5, max_depth=3, tolerance=1e-9)
    np.testing.assert_array_equal(pieces, [[0.99, 8.326672684688674e-17,
                                            1.0, 0.017857142857142856]])
    np.testing.assert_array_equal(t, [[0.28, 0.2857142857142857]])
    assert (stats.clipped, stats.deepest_level) == (2, 3)
