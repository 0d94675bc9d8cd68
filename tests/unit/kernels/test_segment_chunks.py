"""The one-pass segment driver: chunks of blocks, and the in-place move that joins them."""

import numba
import numpy as np
import pytest

import rnsca
from rnsca.backends.numba_cpu import BLOCK_SIZE, SERIAL_BLOCKS
from rnsca.kernels import segments as K


def _output(n: int, rng: np.random.Generator) -> K.SegmentOutput:
    return K.SegmentOutput(rng.random((n, 4)), rng.integers(0, 1 << 40, n), rng.random((n, 2)),
                           np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64),
                           np.zeros((1, 1), dtype=np.int64))


@pytest.mark.parametrize(("start", "to", "count"), [
    (10, 3, 50),                               # short shift: one thread, overlapping
    (K.MIN_PARALLEL_SHIFT, 0, 5 * K.MIN_PARALLEL_SHIFT + 17),   # rounds of the shift
    (3 * K.MIN_PARALLEL_SHIFT, K.MIN_PARALLEL_SHIFT, 7),         # one partial round
    (100_000, 1, 0),                            # nothing to move
])
def test_move_rows_equals_a_copy_of_the_rows(start, to, count):
    rng = np.random.default_rng(start + count)
    out = _output(start + count + 5, rng)
    expected = [a.copy() for a in (out.pieces, out.source, out.t)]
    for a in expected:
        a[to:to + count] = a[start:start + count].copy()
    K.move_rows(out, start, to, count)
    for got, want in zip((out.pieces, out.source, out.t), expected, strict=True):
        np.testing.assert_array_equal(got, want)


def test_chunk_blocks_cover_every_block_once():
    for n_blocks in (1, 2, 3, 7, 100):
        for n_chunks in range(1, 9):
            ranges = [K.chunk_blocks(c, n_chunks, n_blocks) for c in range(n_chunks)]
            assert ranges[0][0] == 0 and ranges[-1][1] == n_blocks
            assert all(a[1] == b[0] for a, b in zip(ranges, ranges[1:], strict=False))


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("method", ["rnsca", "liang_barsky"])
def test_parallel_chunks_equal_the_serial_driver(threads, method):
    """Every thread count gives the serial driver's pieces, in input order, and its stats."""
    n = (SERIAL_BLOCKS + 3) * BLOCK_SIZE + 123  # past the serial limit: the parallel driver
    rng = np.random.default_rng(11)
    segments = rng.random((n, 4)) * 1000.0
    window = (250.0, 250.0, 750.0, 750.0)
    previous = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        got = rnsca.clip_segments(segments, window, method=method)
    finally:
        numba.set_num_threads(previous)
    parts = [rnsca.clip_segments(segments[i:i + BLOCK_SIZE], window, method=method)
             for i in range(0, n, BLOCK_SIZE)]  # each small enough for the serial driver
    np.testing.assert_array_equal(got.segments, np.concatenate([p.segments for p in parts]))
    np.testing.assert_array_equal(
        got.source, np.concatenate([p.source + i * BLOCK_SIZE for i, p in enumerate(parts)]))
    np.testing.assert_array_equal(got.t, np.concatenate([p.t for p in parts]))
    assert got.stats.fragments_evaluated == sum(p.stats.fragments_evaluated for p in parts)
    assert got.stats.intersections == sum(p.stats.intersections for p in parts)


@pytest.mark.parametrize("method", ["rnsca", "cohen_sutherland", "midpoint"])
@pytest.mark.parametrize(("bad", "message"), [
    ([0.0, 0.0, np.nan, 1.0], "non-finite coordinate"),
    ([0.0, -np.inf, 1.0, 1.0], "non-finite coordinate"),
    ([-1e308, 0.0, 1e308, 1.0], "overflows"),
])
def test_the_check_fused_into_the_clip_names_the_first_bad_segment(method, bad, message):
    """In the parallel driver, with bad rows in two chunks: the first is named."""
    n = (SERIAL_BLOCKS + 3) * BLOCK_SIZE
    segments = np.random.default_rng(5).random((n, 4))
    first = n // 2 + 7
    segments[first] = bad
    segments[n - 3] = [np.nan] * 4
    with pytest.raises(rnsca.InvalidGeometryError, match=f"segment {first} .*{message}") as info:
        rnsca.clip_segments(segments, (0.25, 0.25, 0.75, 0.75), method=method)
    assert info.value.row == first
