"""The OpenCL segment pipeline: chunks over two queues, outputs asked for, device arrays.

Against the Numba backend (the same pieces bit for bit in float64, the same counters),
with chunks small enough that a call crosses many of them and both slots.
"""

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rnsca import clip_segments
from rnsca.errors import InvalidGeometryError, InvalidOptionError

pytestmark = pytest.mark.opencl

W = (250.0, 250.0, 750.0, 750.0)


@pytest.fixture
def small_chunks(opencl64, monkeypatch):
    """Chunks of 4,096 segments (the smallest slot), so a call of 30,000 has eight."""
    from rnsca.backends.opencl import segments

    monkeypatch.setattr(segments, "CHUNK_SEGMENTS", 1 << 12)
    return opencl64  # float32: test_opencl.py


def _uniform(rng, n):
    return rng.uniform(0.0, 1000.0, size=(n, 4))


def _same(a, b):
    np.testing.assert_array_equal(a.segments, b.segments)
    np.testing.assert_array_equal(a.source, b.source)
    np.testing.assert_array_equal(a.t, b.t)
    assert dataclasses.replace(a.stats, device=None) == dataclasses.replace(b.stats,
                                                                            device=None)


@pytest.mark.parametrize("n", [1, 4095, 4096, 4097, 30_000])
@pytest.mark.parametrize("method", ["rnsca", "liang_barsky", "midpoint"])
def test_chunked_calls_equal_the_numba_backend(small_chunks, rng, n, method):
    segs = _uniform(rng, n)
    expected = clip_segments(segs, W, method=method)
    got = clip_segments(segs, W, method=method, backend="opencl")
    _same(got, expected)
    assert got.stats.device.bytes_to_device == (n + 1) * 4 * 8


def test_approx_mode_counters_add_up_over_chunks(small_chunks, rng):
    segs = _uniform(rng, 20_000)
    expected = clip_segments(segs, W, mode="approx", resolution=1.0)
    _same(clip_segments(segs, W, mode="approx", resolution=1.0, backend="opencl"), expected)


@given(st.lists(st.tuples(*[st.floats(-2e3, 3e3)] * 4), max_size=9000),
       st.sampled_from(["rnsca", "cohen_sutherland", "nicholl_lee_nicholl"]))
@settings(max_examples=15, deadline=None,
          # The fixture only sets the chunk size: the same for every example.
          suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_input_equals_the_numba_backend(small_chunks, rows, method):
    segs = np.array(rows, dtype=np.float64).reshape(-1, 4)
    _same(clip_segments(segs, W, method=method, backend="opencl"),
          clip_segments(segs, W, method=method))


def test_outputs_left_out_are_none_and_do_not_come_back(small_chunks, rng):
    segs = _uniform(rng, 10_000)
    every = clip_segments(segs, W, backend="opencl")
    only = clip_segments(segs, W, backend="opencl", outputs=("segments",))
    assert only.source is None and only.t is None
    np.testing.assert_array_equal(only.segments, every.segments)
    m = len(every)
    assert every.stats.device.bytes_from_device - only.stats.device.bytes_from_device == (
        m * (8 + 2 * 8))
    numba = clip_segments(segs, W, outputs=["segments", "t"])
    assert numba.source is None
    np.testing.assert_array_equal(numba.t, every.t)


def test_an_unknown_output_is_an_error():
    with pytest.raises(InvalidOptionError, match=r"\['pieces'\].*segments"):
        clip_segments([[0.0, 0.0, 1.0, 1.0]], W, outputs=("pieces",))


@pytest.mark.parametrize("bad_row", [0, 4095, 4096, 17_000, 29_999])
@pytest.mark.parametrize("value", [np.nan, np.inf, "overflow"])
def test_the_first_non_finite_segment_is_named_whatever_its_chunk(small_chunks, rng,
                                                                   bad_row, value):
    segs = _uniform(rng, 30_000)
    if value == "overflow":
        segs[bad_row] = [-1.5e308, 0.0, 1.5e308, 1.0]
    else:
        segs[bad_row, 1] = value
        segs[bad_row + 1:, 3] = value  # later ones too: the first is named
    with pytest.raises(InvalidGeometryError) as numba_error:
        clip_segments(segs, W)
    with pytest.raises(InvalidGeometryError) as device_error:
        clip_segments(segs, W, backend="opencl")
    assert device_error.value.row == numba_error.value.row == bad_row
    assert str(device_error.value) == str(numba_error.value)


def test_device_input_gives_device_output_equal_to_the_host_call(small_chunks, rng):
    import pyopencl.array as cl_array

    backend = small_chunks
    segs = _uniform(rng, 30_000)
    expected = clip_segments(segs, W)
    queue = backend._device.queue
    on_device = cl_array.to_device(queue, segs)
    got = clip_segments(on_device, W, backend="opencl")
    assert isinstance(got.segments, cl_array.Array) and got.segments.shape == (len(expected), 4)
    np.testing.assert_array_equal(got.segments.get(), expected.segments)
    np.testing.assert_array_equal(got.source.get(), expected.source)
    np.testing.assert_array_equal(got.t.get(), expected.t)
    assert dataclasses.replace(got.stats, device=None) == expected.stats
    # Nothing crossed the bus but the window, the count and the counters.
    assert got.stats.device.bytes_to_device == 4 * 8
    assert got.stats.device.bytes_from_device == 43 * 8
    # A pipeline step on the device: the pieces clipped again, to a smaller window.
    again = clip_segments(got.segments, (300.0, 300.0, 700.0, 700.0), backend="opencl",
                          outputs=("segments",))
    np.testing.assert_array_equal(
        again.segments.get(),
        clip_segments(expected.segments, (300.0, 300.0, 700.0, 700.0)).segments)


def test_device_input_with_a_bad_segment_names_it(small_chunks, rng):
    import pyopencl.array as cl_array

    segs = _uniform(rng, 5000)
    segs[1234, 0] = np.inf
    on_device = cl_array.to_device(small_chunks._device.queue, segs)
    with pytest.raises(InvalidGeometryError, match="segment 1234 has a non-finite"):
        clip_segments(on_device, W, backend="opencl")


def test_device_input_of_the_wrong_shape_or_dtype_is_an_error(small_chunks):
    import pyopencl.array as cl_array

    queue = small_chunks._device.queue
    with pytest.raises(ValueError, match=r"\(n, 4\) float64"):
        clip_segments(cl_array.zeros(queue, (10, 4), np.float32), W, backend="opencl")
    with pytest.raises(ValueError, match=r"\(n, 4\) float64"):
        clip_segments(cl_array.zeros(queue, (10, 2), np.float64), W, backend="opencl")


def test_device_input_needs_the_opencl_backend(small_chunks):
    import pyopencl.array as cl_array

    on_device = cl_array.zeros(small_chunks._device.queue, (3, 4), np.float64)
    with pytest.raises(InvalidGeometryError, match="backend='opencl'"):
        clip_segments(on_device, W, backend="numba")


# --- the caller's arrays in pinned memory: the pieces land where they stay ----------------

def _pool(backend):
    return backend._device.staging.outputs


def test_float64_pieces_land_in_pinned_arrays_that_go_back_to_the_pool(small_chunks, rng):
    import gc

    segs = _uniform(rng, 30_000)
    expected = clip_segments(segs, W)
    pool = _pool(small_chunks)
    first = clip_segments(segs, W, backend="opencl")
    _same(first, expected)
    assert first.segments.flags.c_contiguous and first.segments.dtype == np.float64
    pinned = pool.allocated
    del first
    gc.collect()
    # The next call of the same size pins nothing: it reuses what the first gave back.
    again = clip_segments(segs, W, backend="opencl")
    assert pool.allocated == pinned
    _same(again, expected)


def test_pinned_results_held_by_the_caller_are_never_reused(small_chunks, rng):
    segs = _uniform(rng, 30_000)
    held = [clip_segments(segs, W, backend="opencl") for _ in range(3)]
    copies = [h.segments.copy() for h in held]
    other = clip_segments(_uniform(rng, 30_000), W, backend="opencl")
    for h, c in zip(held, copies, strict=True):
        np.testing.assert_array_equal(h.segments, c)
        assert not np.shares_memory(h.segments, other.segments)
    assert not np.shares_memory(held[0].segments, held[1].segments)


def test_a_call_that_keeps_few_pieces_returns_them_out_of_the_pool(small_chunks, rng):
    pool = _pool(small_chunks)
    segs = _uniform(rng, 30_000)
    got = clip_segments(segs, (0.0, 0.0, 10.0, 10.0), backend="opencl")
    _same(got, clip_segments(segs, (0.0, 0.0, 10.0, 10.0)))
    # Fewer than a quarter kept: copied out, and the pinned memory is free again.
    assert 0 < got.segments.shape[0] < 30_000 // 4
    assert got.segments.base is None
    assert pool.free_bytes > 0


def test_the_pool_keeps_at_most_its_budget_free(opencl):
    import gc

    from rnsca.backends.opencl.segments import PinnedPool

    device = opencl._device
    pool = PinnedPool(device.context, device.queue, keep_bytes=1 << 20)
    arrays = [pool.empty((1 << 15,), np.float64) for _ in range(8)]  # 256 KiB each
    for a in arrays:
        a[:] = 1.0
    del arrays, a
    gc.collect()
    assert pool.free_bytes == 1 << 20
    assert pool.empty((3, 4), np.int32).shape == (3, 4)


def test_the_pool_keeps_the_latest_returns_not_the_first(opencl):
    """A large call's buffers, once returned, must not crowd out the sizes used after it."""
    import gc

    from rnsca.backends.opencl.segments import PinnedPool

    device = opencl._device
    pool = PinnedPool(device.context, device.queue, keep_bytes=1 << 20)
    big = pool.empty((1 << 16,), np.float64)  # 512 KiB
    big2 = pool.empty((1 << 16,), np.float64)
    del big, big2
    gc.collect()
    assert pool.free_bytes == 1 << 20
    small = [pool.empty((1 << 13,), np.float64) for _ in range(2)]  # 64 KiB each
    pinned = pool.allocated
    del small
    gc.collect()
    # The two small buffers are kept; an old 512 KiB one went to make room.
    assert pool.free_bytes == (1 << 19) + 2 * (1 << 16)
    again = [pool.empty((1 << 13,), np.float64) for _ in range(2)]
    assert pool.allocated == pinned and all(a.shape == (1 << 13,) for a in again)


def test_outputs_too_large_to_keep_are_staged_not_pinned(small_chunks, rng, monkeypatch):
    """Pinning anew each call costs more than the copy out (run D: 2.1 s against 0.15 s)."""
    segs = _uniform(rng, 30_000)
    expected = clip_segments(segs, W)
    pool = _pool(small_chunks)
    assert pool.owns(clip_segments(segs, W, backend="opencl").segments)
    monkeypatch.setattr(pool, "keep_bytes", 1 << 20)  # 30,000 segments' outputs: 2 MiB
    pinned = pool.allocated
    got = clip_segments(segs, W, backend="opencl")
    _same(got, expected)
    assert not pool.owns(got.segments) and pool.allocated == pinned


def test_pinned_input_goes_up_without_the_staging_copy(small_chunks, rng, monkeypatch):
    from rnsca.backends.opencl import segments

    segs = _uniform(rng, 30_000)
    expected = clip_segments(segs, W)
    filled = small_chunks.empty_pinned(segs.shape)
    filled[:] = segs
    first = clip_segments(segs, W, backend="opencl")  # staged (ordinary memory)

    def no_staging(*args, **kwargs):
        raise AssertionError("pinned input was copied into the staging buffer")

    monkeypatch.setattr(segments._Slot, "stage", no_staging)
    _same(clip_segments(filled, W, backend="opencl"), expected)
    # A result is pinned: fed to the next call, it goes up as it is.
    chained = clip_segments(first.segments, (300.0, 300.0, 700.0, 700.0), backend="opencl")
    _same(chained, clip_segments(expected.segments, (300.0, 300.0, 700.0, 700.0)))
    # So do many windows' segments (uploaded whole).
    grid = np.array([[x, y, x + 250.0, y + 250.0] for x in (250.0, 500.0)
                     for y in (250.0, 500.0)])
    np.testing.assert_array_equal(
        clip_segments(filled, windows=grid, backend="opencl").segments,
        clip_segments(segs, windows=grid).segments)
