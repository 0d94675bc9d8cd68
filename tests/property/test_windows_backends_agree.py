"""Many windows on the OpenCL device against the host, on drawn windows and segments.

The device makes the (segment, window) pairs itself (`OpenCLBackend.assign_windows`,
the port of `rnsca.kernels.windows._visit`): they must be `rnsca.many_windows.assign`'s
bit for bit (the same pairs in the same order), and the many-window clip the Numba
backend's (pieces, source, t, window, window_offsets, counters), in float64.

Windows are drawn as grids, equally spaced (the arithmetic guess, with edges that are
equal steps only up to rounding) or not (binary search), in any order, or as free boxes
(the sweep: overlapping, touching, repeated, any width). Segment ends are drawn on the
windows' edges and corners, one ulp either side, between them, and far outside, with
zero-length segments among them; host and device inputs both.
"""

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rnsca import clip_segments
from rnsca.many_windows import as_windows, assign

pytestmark = pytest.mark.opencl

SETTINGS = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                          HealthCheck.data_too_large])


@st.composite
def uniform_edges(draw):
    """Edges ``start + i * step``: equally spaced as `_equally_spaced` tests it."""
    start = draw(st.floats(-1e3, 1e3))
    step = draw(st.floats(1e-3, 1e3))
    count = draw(st.integers(2, 8))
    edges = start + step * np.arange(count)
    return np.unique(edges)


@st.composite
def uneven_edges(draw):
    values = draw(st.lists(st.floats(-1e3, 1e3), min_size=2, max_size=8, unique=True))
    return np.unique(np.array(values))


@st.composite
def grids(draw):
    """The cells of a grid, in a drawn order."""
    xs = draw(st.one_of(uniform_edges(), uneven_edges()))
    ys = draw(st.one_of(uniform_edges(), uneven_edges()))
    if xs.shape[0] < 2 or ys.shape[0] < 2:  # the steps vanished in the rounding
        xs, ys = np.array([0.0, 1.0]), np.array([0.0, 1.0])
    cells = np.array([(xs[i], ys[j], xs[i + 1], ys[j + 1]) for j in range(len(ys) - 1)
                      for i in range(len(xs) - 1)])
    order = draw(st.permutations(range(cells.shape[0])))
    return cells[list(order)]


@st.composite
def boxes(draw):
    """Free boxes: overlapping, touching (shared bounds), repeated, of any width."""
    bounds = st.floats(-1e3, 1e3)
    rows = draw(st.lists(st.tuples(bounds, bounds, bounds, bounds), min_size=1, max_size=12))
    out = []
    for x0, y0, x1, y1 in rows:
        xmin, xmax = min(x0, x1), max(x0, x1)
        ymin, ymax = min(y0, y1), max(y0, y1)
        out.append((xmin, ymin, xmax if xmax > xmin else np.nextafter(xmin, np.inf),
                    ymax if ymax > ymin else np.nextafter(ymin, np.inf)))
    table = np.array(out)
    if table.shape[0] > 1 and draw(st.booleans()):
        table[-1] = table[0]  # the same window twice
    return table


@st.composite
def segments_near(draw, windows):
    """Segments whose ends lie on, beside, between or far from the windows' bounds."""
    values = np.unique(windows)
    near = np.concatenate([values, np.nextafter(values, np.inf),
                           np.nextafter(values, -np.inf), (values[:-1] + values[1:]) / 2,
                           [-1e300, 1e300, values.min() - 1.0, values.max() + 1.0]])
    coordinate = st.one_of(st.sampled_from(near.tolist()), st.floats(-1.2e3, 1.2e3))
    rows = draw(st.lists(st.tuples(*[coordinate] * 4), max_size=120))
    segs = np.array(rows, dtype=np.float64).reshape(-1, 4)
    if segs.shape[0] and draw(st.booleans()):
        segs[::3, 2:] = segs[::3, :2]  # zero-length segments
    return segs


@pytest.fixture(scope="module")
def device(opencl64):
    return opencl64


@SETTINGS
@given(st.data())
def test_device_pairs_and_pieces_equal_the_host(device, data):
    import pyopencl.array as cl_array

    windows = data.draw(st.one_of(grids(), boxes()), label="windows")
    segs = data.draw(segments_near(windows), label="segments")
    table = as_windows(windows)
    pairs = assign(segs, table)
    pair_segment, pair_window = device.assign_windows(segs, table)
    np.testing.assert_array_equal(pair_segment, pairs.segment)
    np.testing.assert_array_equal(pair_window, pairs.window())
    expected = clip_segments(segs, windows=windows)
    got = clip_segments(segs, windows=windows, backend="opencl")
    on_device = clip_segments(cl_array.to_device(device._device.queue, segs),
                              windows=windows, backend="opencl")
    for name in ("segments", "source", "t", "window"):
        np.testing.assert_array_equal(getattr(got, name), getattr(expected, name), name)
        np.testing.assert_array_equal(getattr(on_device, name).get(),
                                      getattr(expected, name), name)
    np.testing.assert_array_equal(got.window_offsets, expected.window_offsets)
    np.testing.assert_array_equal(on_device.window_offsets, expected.window_offsets)
    assert dataclasses.replace(got.stats, device=None) == expected.stats
    assert dataclasses.replace(on_device.stats, device=None) == expected.stats
