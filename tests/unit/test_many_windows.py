"""Many windows at once (`rnsca.clip_segments(..., windows=)`): every segment against
every window it touches, in one call, checked window by window against the one-window
clip (itself checked against Shapely and exact arithmetic elsewhere), on every backend."""

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rnsca import clip_segments
from rnsca.errors import InvalidGeometryError, InvalidWindowError
from rnsca.many_windows import as_windows, assign, grid_of


def _grid(side, extent=1000.0, uneven=False):
    xs = np.linspace(0.0, extent, side + 1)
    if uneven:
        xs = np.sort(np.r_[0.0, np.random.default_rng(3).uniform(0, extent, side - 1), extent])
    return np.array([(xs[i], xs[j], xs[i + 1], xs[j + 1]) for j in range(side)
                     for i in range(side)])


def _per_window(segs, windows, **options):
    """The oracle: one call per window."""
    return [clip_segments(segs, w, **options) for w in windows]


def _check(result, expected, windows):
    assert result.window_offsets.shape == (len(windows) + 1,)
    for w, e in enumerate(expected):
        a, b = result.window_offsets[w], result.window_offsets[w + 1]
        np.testing.assert_array_equal(result.segments[a:b], e.segments)
        np.testing.assert_array_equal(result.source[a:b], e.source)
        np.testing.assert_array_equal(result.t[a:b], e.t)
        assert (result.window[a:b] == w).all()
    assert len(result) == sum(len(e) for e in expected)


@pytest.mark.parametrize("windows", [_grid(1), _grid(5), _grid(7, uneven=True),
                                     np.random.default_rng(1).permutation(_grid(4))],
                         ids=["one", "grid", "uneven grid", "shuffled grid"])
def test_a_grid_equals_one_call_per_window(backend, method, rng, windows):
    segs = rng.uniform(-100.0, 1100.0, size=(800, 4))
    got = clip_segments(segs, windows=windows, method=method, backend=backend)
    _check(got, _per_window(segs, windows, method=method), windows)


def test_any_windows_equal_one_call_per_window(backend, rng):
    lo = rng.uniform(0.0, 900.0, size=(25, 2))
    windows = np.c_[lo, lo + rng.uniform(0.5, 300.0, size=(25, 2))]
    windows[5] = windows[6]  # the same window twice
    segs = rng.uniform(-100.0, 1100.0, size=(800, 4))
    assert grid_of(windows) is None
    got = clip_segments(segs, windows=windows, backend=backend)
    _check(got, _per_window(segs, windows), windows)


def test_approx_mode_and_the_counters(backend, rng):
    segs = rng.uniform(0.0, 1000.0, size=(800, 4))
    windows = _grid(3)
    got = clip_segments(segs, windows=windows, mode="approx", resolution=0.5, backend=backend)
    expected = _per_window(segs, windows, mode="approx", resolution=0.5)
    _check(got, expected, windows)
    # The counters add up over the windows: each (segment, window) pair is one clip.
    assert got.stats.segments_in == len(assign(segs, windows).segment)
    for name in ("accepted", "clipped", "dropped", "intersections"):
        touched = sum(getattr(e.stats, name) for e in expected)
        assert getattr(got.stats, name) == touched, name


def test_segments_on_shared_edges_go_to_both_windows(backend):
    windows = _grid(2, extent=2.0)  # cells of side 1, edges at 0, 1, 2
    segs = np.array([[0.2, 1.0, 0.8, 1.0],     # along the edge y = 1: both bottom-left
                     [1.0, 0.2, 1.0, 1.8],     # along x = 1: all four touch, two rows
                     [0.5, 0.5, 1.5, 1.5],     # through the corner point (1, 1)
                     [-1.0, -1.0, -0.5, -0.5],  # outside the grid
                     [0.5, 2.0, 1.5, 3.0]])    # touches the top edge at one point
    got = clip_segments(segs, windows=windows, backend=backend)
    _check(got, _per_window(segs, windows), windows)
    assert sorted(got.source[got.window == 0].tolist()) == [0, 1, 2]


@given(st.lists(st.tuples(*[st.floats(-50, 150, allow_nan=False)] * 4), max_size=200),
       st.lists(st.tuples(st.floats(-20, 100), st.floats(-20, 100), st.floats(0.1, 80),
                          st.floats(0.1, 80)), min_size=1, max_size=12))
@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_random_segments_and_windows(backend, rows, boxes):
    segs = np.array(rows, dtype=np.float64).reshape(-1, 4)
    windows = np.array([(x, y, x + w, y + h) for x, y, w, h in boxes])
    got = clip_segments(segs, windows=windows, backend=backend)
    _check(got, _per_window(segs, windows), windows)


def test_a_window_whose_width_rounds_down_is_still_found(backend):
    """The sweep's reach west is the widest window's width rounded up (found by
    Hypothesis: from -3.65e-67 to 1 is 1.0 wide in floats, and the sweep stopped at 0)."""
    segs = np.array([[1.0, 0.0, 1.0, 0.0], [0.5, 0.5, 1.0, 0.5]])
    windows = np.array([[0.0, 0.0, 1.0, 1.0], [-3.654671209400125e-67, 0.0, 1.0, 1.0]])
    assert grid_of(windows) is None
    got = clip_segments(segs, windows=windows, backend=backend)
    _check(got, _per_window(segs, windows), windows)
    assert got.window.tolist() == [0, 0, 1, 1]


def test_outputs_left_out(backend, rng):
    segs = rng.uniform(0.0, 1000.0, size=(500, 4))
    got = clip_segments(segs, windows=_grid(2), backend=backend, outputs=("segments",))
    assert got.source is None and got.t is None and got.window is not None


def test_no_segment_touches_a_window(backend):
    got = clip_segments([[5000.0, 5000.0, 6000.0, 6000.0]], windows=_grid(2), backend=backend)
    assert len(got) == 0 and got.window_offsets.tolist() == [0, 0, 0, 0, 0]
    empty = clip_segments(np.empty((0, 4)), windows=_grid(2), backend=backend)
    assert len(empty) == 0 and empty.window.shape == (0,)


def test_a_grid_is_recognised_in_any_order():
    windows = _grid(3)
    xs, ys, cells = grid_of(windows[::-1])
    assert xs.tolist() == ys.tolist() == [0.0, 1000 / 3, 2000 / 3, 1000.0]
    assert sorted(cells.ravel().tolist()) == list(range(9))
    assert grid_of(windows[:-1]) is None  # a cell missing
    overlapping = windows.copy()
    overlapping[0, 2] += 1.0
    assert grid_of(overlapping) is None


@pytest.mark.parametrize("windows, message", [
    ([[0, 0, 1]], "shape"), (np.empty((0, 4)), "k >= 1"),
    ([[0, 0, 1, 1], [2, 2, 1, 3]], "window 1 .* xmin < xmax"),
    ([[0, 0, np.inf, 1]], "window 0 .* finite"), ("abc", "windows must be")])
def test_bad_windows_are_named(windows, message):
    with pytest.raises(InvalidWindowError, match=message):
        as_windows(windows)
    with pytest.raises(InvalidWindowError):
        clip_segments([[0.0, 0.0, 1.0, 1.0]], windows=windows)


def test_one_of_window_and_windows():
    with pytest.raises(InvalidWindowError, match="one of window= and windows="):
        clip_segments([[0.0, 0.0, 1.0, 1.0]], (0, 0, 1, 1), windows=_grid(2))
    with pytest.raises(InvalidWindowError, match="one of window= and windows="):
        clip_segments([[0.0, 0.0, 1.0, 1.0]])


def test_a_bad_segment_is_named(backend):
    segs = np.zeros((10, 4))
    segs[7, 2] = np.nan
    with pytest.raises(InvalidGeometryError, match="segment 7"):
        clip_segments(segs, windows=_grid(2), backend=backend)


def test_device_stats_count_one_upload_of_the_segments(opencl, rng):
    segs = rng.uniform(0.0, 1000.0, size=(2000, 4))
    windows = _grid(4)
    got = clip_segments(segs, windows=windows, backend="opencl")
    pairs = assign(segs, windows).segment.shape[0]
    if got.stats.device.precision == "float64":
        # Up: the window table, the segments once, the grid's edges (5 + 5) and cells
        # (16); the pairs are made on the device.
        assert got.stats.device.bytes_to_device == (16 * 4 + 2000 * 4 + 5 + 5 + 16) * 8
    else:  # float32: assigned on the host, each pair's segment and window sent up
        assert got.stats.device.bytes_to_device == (16 * 4 + 2000 * 4) * 4 + pairs * 12
    assert dataclasses.replace(got.stats, device=None) == clip_segments(
        segs, windows=windows).stats
