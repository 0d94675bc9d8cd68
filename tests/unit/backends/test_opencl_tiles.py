"""Vector tiles of segment pieces on the OpenCL device (`OpenCLBackend.encode_segment_tiles`).

The device's bytes must be the Numba backend's, for pieces on the device (where a
many-window clip of device segments leaves them) and on the host; only the per-tile
counts and the tiles' bytes come back. Float32 devices refuse, saying why. The oracle
of the bytes themselves is in tests/unit/test_tiles_segments.py.
"""

import numpy as np
import pytest

import rnsca
from rnsca.backends import registry
from rnsca.backends.base import Operation, TileLayer
from rnsca.errors import BackendUnavailableError, InvalidGeometryError
from rnsca.options import Backend
from rnsca.tiles import encode_segment_tiles

pytestmark = pytest.mark.opencl


@pytest.fixture(scope="module")
def device(opencl64):
    return opencl64  # a float32 device: tested below


def _grid(side, extent=1000.0):
    edges = np.linspace(0.0, extent, side + 1)
    return np.array([(x0, y0, x1, y1) for y0, y1 in zip(edges[:-1], edges[1:], strict=True)
                     for x0, x1 in zip(edges[:-1], edges[1:], strict=True)])


def _segments(rng, n):
    """Short and long segments over the grid, some beyond it, some of zero length."""
    segs = rng.uniform(-50.0, 1050.0, (n, 4))
    short = rng.random(n) < 0.7
    segs[short, 2:] = segs[short, :2] + rng.normal(0.0, 2.0, (short.sum(), 2))
    segs[::17, 2:] = segs[::17, :2]
    return segs


def _same(a, b):
    assert np.array_equal(a.data, b.data) and np.array_equal(a.offsets, b.offsets)


@pytest.mark.parametrize("outputs", [("segments", "source"), ("segments",)],
                         ids=["ids", "no-ids"])
def test_device_pieces_encode_where_they_are_to_the_numba_bytes(device, rng, outputs):
    import pyopencl.array as cl_array

    segs = _segments(rng, 30_000)
    windows = _grid(16)
    on_device = rnsca.clip_segments(cl_array.to_device(device.queue, segs), windows=windows,
                                    backend="opencl", outputs=outputs)
    assert isinstance(on_device.segments, cl_array.Array)
    host = rnsca.clip_segments(segs, windows=windows, outputs=outputs)
    tiles = encode_segment_tiles(on_device, windows, extent=4096)  # OpenCL: the default
    assert tiles.backend is Backend.OPENCL
    _same(tiles, encode_segment_tiles(host, windows, extent=4096, backend="numba"))
    # Only the per-tile counts (k + 2 numbers) and the tiles' bytes came down.
    stats = tiles.device
    assert stats is not None and stats.precision == "float64"
    assert stats.bytes_from_device == 8 * (len(windows) + 2) + tiles.data.nbytes
    # Up: the tiles' offsets and quantisation, the layout and the layer's fields; no pieces.
    assert stats.bytes_to_device < 8 * 6 * (len(windows) + 1) + 64


def test_host_pieces_are_sent_up_and_encoded_alike(device, rng):
    segs = _segments(rng, 5_000)
    windows = _grid(5)
    host = rnsca.clip_segments(segs, windows=windows)
    tiles = encode_segment_tiles(host, windows, backend="opencl")
    _same(tiles, encode_segment_tiles(host, windows))
    assert tiles.device.bytes_to_device >= host.segments.nbytes + host.source.nbytes


def test_large_host_pieces_go_up_through_the_staging_buffers(device, rng):
    # Over 1 MiB of pieces: `Ledger.staged` streams them through the pinned slots.
    segs = _segments(rng, 80_000)
    windows = _grid(3)
    host = rnsca.clip_segments(segs, windows=windows)
    assert host.segments.nbytes > 1 << 20
    _same(encode_segment_tiles(host, windows, backend="opencl"),
          encode_segment_tiles(host, windows))


def test_empty_tiles_and_no_pieces(device):
    import pyopencl.array as cl_array

    windows = _grid(4)
    for segs in (np.empty((0, 4)), np.array([[-10.0, -10.0, -5.0, -5.0]]),
                 np.array([[100.0, 100.0, 100.001, 100.0]])):  # within one tile unit
        tiled = rnsca.clip_segments(cl_array.to_device(device.queue, segs), windows=windows,
                                    backend="opencl")
        tiles = encode_segment_tiles(tiled, windows)
        assert tiles.data.shape == (0,) and tiles.offsets.tolist() == [0] * 17


def test_a_piece_beyond_its_tile_is_found_on_the_device(device):
    import pyopencl.array as cl_array

    windows = _grid(2)
    segs = cl_array.to_device(device.queue, np.array([[100.0, 100.0, 900.0, 900.0]]))
    tiled = rnsca.clip_segments(segs, windows=windows, backend="opencl")
    moved = windows.copy()
    moved[2:] += 1e12  # tiles 2 and 3 far away: piece 1 lies in tile 3
    with pytest.raises(InvalidGeometryError, match=r"piece 1 \[500.0, 500.0, 900.0, 900.0\] "
                                                   r"of tile 3"):
        encode_segment_tiles(tiled, moved)


def test_device_sources_of_another_shape_are_refused(device):
    import pyopencl.array as cl_array

    layer = TileLayer(np.array([0, 1], np.int64), np.array([[0.0, 1.0, 16.0, 16.0]]),
                      np.zeros(0, np.uint8), np.zeros(0, np.uint8))
    pieces = cl_array.to_device(device.queue, np.array([[0.0, 0.0, 1.0, 1.0]]))
    source = cl_array.to_device(device.queue, np.array([0, 1], np.int64))
    with pytest.raises(ValueError, match=r"device sources must be \(1,\) int64"):
        device.encode_segment_tiles(pieces, source, layer)
    with pytest.raises(ValueError, match="device segments must be"):
        device.encode_segment_tiles(pieces.astype(np.float32), None, layer)


def test_a_float32_device_refuses_tiles_saying_why(opencl):
    from rnsca.backends.opencl import OpenCLBackend

    float32 = OpenCLBackend(opencl.device["id"], "float32")
    assert not float32.capabilities.supports(Operation.TILES)
    assert float32.capabilities.supports(Operation.WINDOWS)
    layer = TileLayer(np.array([0, 0], np.int64), np.array([[0.0, 1.0, 16.0, 16.0]]),
                      np.zeros(0, np.uint8), np.zeros(0, np.uint8))
    with pytest.raises(BackendUnavailableError, match="float32.*needs float64"):
        float32.encode_segment_tiles(np.empty((0, 4)), None, layer)


def test_the_library_names_float32_when_the_configured_device_runs_it(opencl):
    windows = _grid(2)
    tiled = rnsca.clip_segments([[100.0, 100.0, 900.0, 900.0]], windows=windows)
    try:
        registry.configure_opencl(opencl.device["id"], "float32")
        with pytest.raises(BackendUnavailableError,
                           match="'opencl' does not encode tiles here.*float32"):
            encode_segment_tiles(tiled, windows, backend="opencl")
    finally:
        registry.configure_opencl()
