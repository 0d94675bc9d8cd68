"""Many windows on the OpenCL device: the pairs made there, and device-resident calls.

The device's (segment, window) pairs (`OpenCLBackend.assign_windows`) must be
`rnsca.many_windows.assign`'s bit for bit (the same pairs, sorted by window then
segment), and the many-window clip the Numba backend's (pieces, source, t, window,
window_offsets, counters), on every path of the assignment: uniform grids (the
arithmetic guess), uneven grids (binary search), other window sets (the sweep), and few
work-items for many windows. Chunks are small, so the pairs' clip crosses many of them.
"""

import dataclasses

import numpy as np
import pytest

from rnsca import clip_segments
from rnsca.backends.opencl import OpenCLBackend
from rnsca.errors import InvalidGeometryError
from rnsca.many_windows import as_windows, assign, grid_of, window_finder
from rnsca.options import Backend

pytestmark = pytest.mark.opencl


@pytest.fixture
def device(opencl64, monkeypatch):
    """The float64 OpenCL backend, with chunks of 4,096 pairs (the smallest slot)."""
    from rnsca.backends.opencl import segments

    monkeypatch.setattr(segments, "CHUNK_SEGMENTS", 1 << 12)
    return opencl64  # float32: test below


@pytest.fixture
def few_items(monkeypatch):
    """Make the count table hold 3 entries per window: 3 work-items (or fewer) at most."""
    from rnsca.backends.opencl import windows

    def limit(k):
        monkeypatch.setattr(windows, "ASSIGN_TABLE_ENTRIES", 3 * k)
        monkeypatch.setattr(windows, "MIN_ASSIGN_ITEMS", 1)

    return limit


def _grid(xs, ys=None):
    ys = xs if ys is None else ys
    return np.array([(xs[i], ys[j], xs[i + 1], ys[j + 1]) for j in range(len(ys) - 1)
                     for i in range(len(xs) - 1)])


def _segments(rng, n, low=-100.0, high=1100.0):
    """Random segments, short and long, with ends snapped onto a lattice of edges."""
    segs = rng.uniform(low, high, size=(n, 4))
    short = rng.random(n) < 0.5
    segs[short, 2:] = segs[short, :2] + rng.normal(0.0, 20.0, size=(short.sum(), 2))
    snapped = rng.random((n, 4)) < 0.3
    segs[snapped] = np.round(segs[snapped] / 125.0) * 125.0
    return segs


def _check(backend, segs, windows, **options):
    """The device's pairs are `assign`'s, and the clip equals the Numba backend's."""
    table = as_windows(windows)
    pairs = assign(segs, table)
    pair_segment, pair_window = backend.assign_windows(segs, table)
    np.testing.assert_array_equal(pair_segment, pairs.segment)
    np.testing.assert_array_equal(pair_window, pairs.window())
    assert pair_segment.dtype == np.int64 and pair_window.dtype == np.int32
    expected = clip_segments(segs, windows=windows, **options)
    got = clip_segments(segs, windows=windows, backend="opencl", **options)
    for name in ("segments", "source", "t", "window", "window_offsets"):
        np.testing.assert_array_equal(getattr(got, name), getattr(expected, name), name)
    assert dataclasses.replace(got.stats, device=None) == expected.stats
    return got


UNIFORM = _grid(np.linspace(0.0, 1000.0, 9))
# Equally spaced in exact terms but not in floats: the arithmetic guess needs correcting.
UNIFORM_INEXACT = _grid(np.linspace(-0.1, 0.7, 8) * 1000.0, np.linspace(0.3, 1.1, 5) * 1000.0)
UNEVEN = _grid(np.sort(np.r_[0.0, np.random.default_rng(3).uniform(0, 1000, 6), 1000.0]))
SHUFFLED = np.random.default_rng(4).permutation(UNIFORM)


def _boxes(seed, k):
    rng = np.random.default_rng(seed)
    lo = rng.uniform(0.0, 900.0, size=(k, 2))
    boxes = np.c_[lo, lo + rng.uniform(0.5, 300.0, size=(k, 2))]
    boxes[5] = boxes[6]  # the same window twice
    return boxes


# Touching and overlapping, not a grid: shared edges, a window over a corner, one inside.
TOUCHING = np.array([[0.0, 0.0, 500.0, 500.0], [500.0, 0.0, 1000.0, 500.0],
                     [250.0, 250.0, 750.0, 750.0], [500.0, 500.0, 1000.0, 1000.0],
                     [600.0, 600.0, 700.0, 700.0], [0.0, 500.0, 500.0, 1000.0],
                     [0.0, 0.0, 1000.0, 1000.0]])
WINDOW_SETS = {"uniform grid": UNIFORM, "inexact uniform grid": UNIFORM_INEXACT,
               "uneven grid": UNEVEN, "shuffled grid": SHUFFLED, "boxes": _boxes(1, 40),
               "touching": TOUCHING, "one window": np.array([[250.0, 250.0, 750.0, 750.0]])}


@pytest.mark.parametrize("windows", WINDOW_SETS.values(), ids=WINDOW_SETS.keys())
def test_pairs_and_pieces_equal_the_numba_backend(device, rng, windows):
    _check(device, _segments(rng, 20_000), windows)


def test_the_window_sets_take_the_paths_they_are_named_for():
    assert window_finder(UNIFORM).uniform and window_finder(UNIFORM_INEXACT).uniform
    assert window_finder(UNEVEN).grid and not window_finder(UNEVEN).uniform
    assert grid_of(TOUCHING) is None and grid_of(_boxes(1, 40)) is None


@pytest.mark.parametrize("windows", [UNIFORM, UNEVEN, _boxes(2, 30)],
                         ids=["uniform grid", "uneven grid", "boxes"])
def test_three_work_items_give_the_same_pairs(device, rng, few_items, windows):
    few_items(windows.shape[0])
    _check(device, _segments(rng, 5000), windows)


def test_more_windows_than_the_device_assigns_are_assigned_on_the_host(device, rng,
                                                                        monkeypatch):
    from rnsca.backends.opencl import windows as device_windows

    table = _grid(np.linspace(0.0, 1000.0, 41))
    monkeypatch.setattr(device_windows, "ASSIGN_TABLE_ENTRIES", table.shape[0])
    assert device_windows.assign_items(1000, table.shape[0]) == 0
    _check(device, _segments(rng, 3000), table)


def test_segments_on_edges_and_corners_and_degenerate_ones(device):
    edges = np.linspace(0.0, 1000.0, 5)  # cells of 250
    corners = np.array([(x, y) for x in edges for y in edges])
    along = np.array([[0.0, 250.0, 1000.0, 250.0], [500.0, -10.0, 500.0, 1010.0],
                      [250.0, 250.0, 750.0, 750.0], [0.0, 1000.0, 1000.0, 0.0],
                      [-5.0, 500.0, 0.0, 500.0], [1000.0, 0.0, 1200.0, -200.0]])
    segs = np.vstack([np.c_[corners, corners], np.c_[corners, corners[::-1]], along,
                      np.c_[corners + 1e-13, corners - 1e-13]])
    for windows in (_grid(edges), TOUCHING):
        _check(device, segs, windows)


def test_the_window_whose_width_rounds_down_is_found(device):
    segs = np.array([[1.0, 0.0, 1.0, 0.0], [0.5, 0.5, 1.0, 0.5]])
    windows = np.array([[0.0, 0.0, 1.0, 1.0], [-3.654671209400125e-67, 0.0, 1.0, 1.0]])
    got = _check(device, segs, windows)
    assert got.window.tolist() == [0, 0, 1, 1]


def test_no_segments_and_segments_far_outside(device):
    _check(device, np.empty((0, 4)), UNIFORM)
    far = np.array([[1e300, 1e300, 2e300, 2e300], [-1e300, 500.0, -1e299, 500.0],
                    [500.0, 2000.0, 600.0, 3000.0]])
    got = _check(device, far, UNIFORM)
    assert len(got) == 0 and got.window_offsets.tolist() == [0] * (len(UNIFORM) + 1)
    _check(device, far, _boxes(1, 40))


def test_approx_mode_and_a_baseline_method(device, rng):
    segs = _segments(rng, 5000)
    _check(device, segs, UNEVEN, mode="approx", resolution=0.5)
    _check(device, segs, _boxes(3, 20), method="liang_barsky")


def _on_device(backend, array):
    import pyopencl.array as cl_array

    return cl_array.to_device(backend._device.queue, np.ascontiguousarray(array))


@pytest.mark.parametrize("windows", [UNIFORM, UNEVEN, _boxes(1, 40)],
                         ids=["uniform grid", "uneven grid", "boxes"])
def test_device_input_gives_device_output_equal_to_the_host_call(device, rng, windows):
    import pyopencl.array as cl_array

    segs = _segments(rng, 20_000)
    expected = clip_segments(segs, windows=windows)
    got = clip_segments(_on_device(device, segs), windows=windows, backend="opencl")
    for name in ("segments", "source", "t", "window"):
        value = getattr(got, name)
        assert isinstance(value, cl_array.Array), name
        np.testing.assert_array_equal(value.get(), getattr(expected, name), name)
    assert got.window.dtype == np.int32
    np.testing.assert_array_equal(got.window_offsets, expected.window_offsets)
    assert dataclasses.replace(got.stats, device=None) == expected.stats
    # Only the window table and the finder's arrays went up; only counts came back:
    # the assignment's (pairs, first bad), the clip's counter row, the window offsets.
    finder = window_finder(as_windows(windows))
    finder_bytes = sum(a.nbytes for a in (finder.xs, finder.ys, finder.cell_window,
                                          finder.order, finder.xmins))
    assert got.stats.device.bytes_to_device == windows.nbytes + finder_bytes
    assert got.stats.device.bytes_from_device == (2 + 43 + len(windows) + 1) * 8


def test_device_input_and_outputs_left_out(device, rng):
    segs = _segments(rng, 3000)
    got = clip_segments(_on_device(device, segs), windows=UNIFORM, backend="opencl",
                        outputs=("segments",))
    expected = clip_segments(segs, windows=UNIFORM)
    assert got.source is None and got.t is None
    np.testing.assert_array_equal(got.segments.get(), expected.segments)
    np.testing.assert_array_equal(got.window.get(), expected.window)


def test_device_input_without_segments(device):
    got = clip_segments(_on_device(device, np.empty((0, 4))), windows=UNIFORM,
                        backend="opencl")
    assert got.segments.shape == (0, 4) and got.window.shape == (0,)
    assert got.window_offsets.tolist() == [0] * (len(UNIFORM) + 1)


@pytest.mark.parametrize("bad", [[np.nan, 1.0, 2.0, 3.0], [1.0, 2.0, np.inf, 3.0],
                                 [-1e308, 0.0, 1e308, 0.0]],
                         ids=["nan", "infinite", "overflowing difference"])
@pytest.mark.parametrize("windows", [UNIFORM, _boxes(1, 40)], ids=["grid", "boxes"])
def test_a_bad_device_segment_raises_the_host_error(device, rng, windows, bad):
    segs = _segments(rng, 5000)
    segs[[3210, 4321]] = bad
    with pytest.raises(InvalidGeometryError) as host:
        clip_segments(segs, windows=windows)
    for segments in (segs, _on_device(device, segs)):
        with pytest.raises(InvalidGeometryError) as got:
            clip_segments(segments, windows=windows, backend="opencl")
        assert str(got.value) == str(host.value)
        assert "segment 3210 " in str(got.value)


def test_device_input_of_another_dtype_is_an_error(device):
    with pytest.raises(ValueError, match=r"\(n, 4\) float64"):
        clip_segments(_on_device(device, np.zeros((10, 4), np.float32)), windows=UNIFORM,
                      backend="opencl")


def test_device_input_with_windows_needs_the_opencl_backend(device):
    with pytest.raises(InvalidGeometryError, match="backend='opencl'"):
        clip_segments(_on_device(device, np.zeros((3, 4))), windows=UNIFORM)


def test_float32_assigns_on_the_host_and_keeps_device_input_there(opencl, rng):
    import pyopencl.array as cl_array

    backend = OpenCLBackend(opencl.device["id"], precision="float32")
    segs = _segments(rng, 5000).astype(np.float32).astype(np.float64)
    options = clip_segments(segs, windows=UNEVEN).options
    table = as_windows(UNEVEN)
    host = backend.clip_segment_windows(segs, table, options)
    on_device = cl_array.to_device(opencl._device.queue, segs.astype(np.float32))
    got = backend.clip_segment_windows(on_device, table, options)
    pairs = assign(segs, table)
    np.testing.assert_array_equal(backend.assign_windows(on_device, table)[0], pairs.segment)
    np.testing.assert_array_equal(got.source.get(), host.source)
    np.testing.assert_array_equal(got.window.get(), host.window)
    np.testing.assert_array_equal(got.window_offsets, host.window_offsets)
    # The host call clamps its float64 copy into the float64 windows; the device's
    # float32 pieces are within float32 rounding of them.
    np.testing.assert_allclose(got.pieces.get(), host.pieces, rtol=0, atol=1e-3)


def test_the_readme_pipeline_clip_then_tiles_stays_on_the_device(opencl64, rng):
    """README, "Data kept on the device": clip, then a grid of tiles, all device arrays,
    then the tiles encoded there: the Numba backend's bytes from the host's pieces."""
    import pyopencl.array as cl_array

    from rnsca.tiles import encode_segment_tiles

    opencl = opencl64
    host = rng.uniform(0, 100, (20_000, 4))
    segments = cl_array.to_device(opencl.queue, host)
    region = clip_segments(segments, (0, 0, 50, 50), backend="opencl", outputs=("segments",))
    edges = np.linspace(0, 50, 5)
    tiles = np.array([(x0, y0, x1, y1) for y0, y1 in zip(edges, edges[1:], strict=False)
                      for x0, x1 in zip(edges, edges[1:], strict=False)])
    tiled = clip_segments(region.segments, windows=tiles, backend="opencl")
    assert isinstance(tiled.segments, cl_array.Array)
    expected = clip_segments(clip_segments(host, (0, 0, 50, 50)).segments, windows=tiles)
    np.testing.assert_array_equal(tiled.segments.get(), expected.segments)
    np.testing.assert_array_equal(tiled.window.get(), expected.window)
    np.testing.assert_array_equal(tiled.window_offsets, expected.window_offsets)
    encoded = encode_segment_tiles(tiled, tiles)  # on the device: the pieces are there
    assert encoded.backend is Backend.OPENCL
    assert encoded.device.bytes_from_device == 8 * (len(tiles) + 2) + encoded.data.nbytes
    on_host = encode_segment_tiles(expected, tiles)
    assert [encoded.tile(w) for w in range(16)] == [on_host.tile(w) for w in range(16)]
    assert all(encoded.tile(w) for w in range(16))  # every tile holds features
