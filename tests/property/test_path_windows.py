"""Many windows for Bézier paths: `rnsca.clip_paths(paths, windows=)` equals a loop of
single-window calls, on each backend.

Paths: the curve tests' random and adversarial paths (loops, cusps, tangents to an edge
line, curves along an edge, control points far outside), several per call, open and
closed, as strokes and fills, preserved, flattened and in approx mode. Windows: a
regular grid over the curve tests' window (the pairs found by arithmetic), the same
cells shuffled, and overlapping windows of different sizes (the sweep), drawn around the
edge lines the paths favour. For every window, the outputs of that window are exactly
(bit for bit) the non-empty outputs of the single-window call, in source order.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, note
from hypothesis import strategies as st

from rnsca import clip_paths, parse_paths
from rnsca.options import Backend
from tests.property.test_curves_vs_shapely import paths, to_d


def _grid(side: int, extent: float = 10.0) -> np.ndarray:
    edges = np.linspace(0.0, extent, side + 1)
    return np.array([(edges[i], edges[j], edges[i + 1], edges[j + 1])
                     for j in range(side) for i in range(side)])


bound = st.sampled_from([-3.0, 0.0, 2.5, 5.0, 10.0, 13.0]) | st.floats(-15.0, 25.0)


@st.composite
def free_windows(draw) -> np.ndarray:
    """One to five windows anywhere near the paths, overlapping or not, repeated or not."""
    rows = []
    for _ in range(draw(st.integers(1, 5))):
        x0, x1 = sorted([draw(bound), draw(bound)])
        y0, y1 = sorted([draw(bound), draw(bound)])
        rows.append((x0, y0, x1 + (x1 == x0), y1 + (y1 == y0)))
    return np.array(rows)


window_sets = st.one_of(
    st.integers(1, 4).map(_grid),
    st.integers(2, 3).flatmap(lambda side: st.permutations(list(_grid(side))).map(np.array)),
    free_windows())

options = st.sampled_from([
    {}, {"fill": "nonzero"}, {"fill": "evenodd"}, {"fill": "nonzero", "fill_output": "raw"},
    {"curves": "flatten", "tolerance": 0.01}, {"mode": "approx", "tolerance": 0.01},
])


def assert_windows_equal_single_calls(source, windows, backend, **opts) -> None:
    result = clip_paths(source, windows=windows, backend=backend, **opts)
    assert result.window_offsets.shape == (windows.shape[0] + 1,)
    assert len(result) == result.window_offsets[-1] == result.source.shape[0]
    for w, window in enumerate(windows):
        one = clip_paths(source, window, backend=backend, **opts)
        kept = np.flatnonzero(np.diff(one.paths.path_offsets) > 0)
        got, got_source = result.window_paths(w)
        a, b = result.window_offsets[w], result.window_offsets[w + 1]
        assert (result.window[a:b] == w).all()
        np.testing.assert_array_equal(got_source, kept, err_msg=f"window {w} {window}")
        assert got == one.paths.take(kept), f"window {w} {window}"


@given(drawn=st.lists(paths(), min_size=1, max_size=4), windows=window_sets, opts=options)
def test_windows_equal_one_call_per_window(backend: Backend, drawn, windows, opts):
    d = [to_d(*p) for p in drawn]
    note(f"d={d!r} windows={windows.tolist()!r} options={opts!r}")
    assert_windows_equal_single_calls(parse_paths(d), windows, backend, **opts)


@given(drawn=st.lists(paths(), min_size=1, max_size=3), windows=window_sets)
def test_keep_empty_keeps_every_pair_of_touching_boxes(drawn, windows):
    source = parse_paths([to_d(*p) for p in drawn])
    dropped = clip_paths(source, windows=windows)
    kept = clip_paths(source, windows=windows, keep_empty=True)
    boxes = source.boxes()
    touching = ((boxes[:, None, 0] <= windows[None, :, 2])
                & (boxes[:, None, 2] >= windows[None, :, 0])
                & (boxes[:, None, 1] <= windows[None, :, 3])
                & (boxes[:, None, 3] >= windows[None, :, 1]))
    w_of, s_of = np.nonzero(touching.T)  # by window, then source
    np.testing.assert_array_equal(kept.window, w_of)
    np.testing.assert_array_equal(kept.source, s_of)
    non_empty = np.diff(kept.paths.path_offsets) > 0
    assert kept.paths.take(np.flatnonzero(non_empty)) == dropped.paths
    np.testing.assert_array_equal(kept.source[non_empty], dropped.source)
