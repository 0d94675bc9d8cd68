"""Vector tiles of segment pieces (`rnsca.tiles.encode_segment_tiles`), on every backend.

Two oracles, both written here: each tile built by the protobuf library from features
quantised in plain Python floats (``math.floor((x - x0) * sx + 0.5)``, one rounding per
operation, as the specification of the function says), compared byte for byte; and
every tile decoded by an independent decoder (mapbox-vector-tile), its positions
compared with the exact rational rounding (`fractions.Fraction`) where the inputs make
every float operation exact.
"""

import math
from fractions import Fraction

import mapbox_vector_tile
import numpy as np
import pytest

import rnsca
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
)
from rnsca.tiles import EncodedTiles, encode_segment_tiles
from rnsca.tiles.vector_tile import Feature, Layer, Tile


def _zigzag(n):
    return (n << 1) ^ (n >> 63)


def expected_tiles(pieces, source, window_offsets, windows, extent, layer):
    """Return each tile's bytes: quantised in Python floats, serialized by protobuf."""
    out = []
    for w, (x0, y0, x1, y1) in enumerate(np.asarray(windows, dtype=float).tolist()):
        sx, sy = extent / (x1 - x0), extent / (y1 - y0)
        features = []
        for i in range(int(window_offsets[w]), int(window_offsets[w + 1])):
            ax, ay, bx, by = (float(v) for v in pieces[i])
            qa = (math.floor((ax - x0) * sx + 0.5), math.floor((y1 - ay) * sy + 0.5))
            qb = (math.floor((bx - x0) * sx + 0.5), math.floor((y1 - by) * sy + 0.5))
            if qa == qb:
                continue
            feature = Feature(type=2, geometry=[
                9, _zigzag(qa[0]), _zigzag(qa[1]),
                10, _zigzag(qb[0] - qa[0]), _zigzag(qb[1] - qa[1])])
            if source is not None:
                feature.id = int(source[i])
            features.append(feature)
        if not features:
            out.append(b"")
            continue
        out.append(Tile(layers=[Layer(name=layer, features=features, extent=extent,
                                      version=2)]).SerializeToString())
    return out


def decode(data, layer="segments", extent=4096):
    """Return the features of one tile, decoded by mapbox-vector-tile (y down as stored)."""
    layers = mapbox_vector_tile.decode(data, default_options={"y_coord_down": True})
    assert list(layers) == [layer]
    assert layers[layer]["extent"] == extent and layers[layer]["version"] == 2
    return layers[layer]["features"]


def encode_and_check(segments, windows, backend, *, extent=4096, layer="segments",
                     outputs=("segments", "source", "t")):
    """Clip, encode on `backend`, and compare every tile with the protobuf oracle."""
    tiled = rnsca.clip_segments(segments, windows=windows, outputs=outputs)
    tiles = encode_segment_tiles(tiled, windows, extent=extent, layer=layer, backend=backend)
    assert isinstance(tiles, EncodedTiles) and tiles.backend is backend
    assert tiles.data.dtype == np.uint8 and tiles.offsets.dtype == np.int64
    assert tiles.offsets.shape == (len(windows) + 1,) and tiles.offsets[0] == 0
    assert tiles.offsets[-1] == tiles.data.shape[0]
    expected = expected_tiles(tiled.segments, tiled.source, tiled.window_offsets, windows,
                              extent, layer)
    assert [tiles.tile(w) for w in range(len(tiles))] == expected
    return tiled, tiles


GRID = np.array([(x, y, x + 10.0, y + 10.0) for y in (0.0, 10.0) for x in (0.0, 10.0)])


def test_each_piece_is_a_line_feature_with_its_source_as_id(backend, rng):
    segs = rng.uniform(-5, 25, (300, 4))
    tiled, tiles = encode_and_check(segs, GRID, backend)
    for w in range(len(GRID)):
        features = decode(tiles.tile(w))
        first, end = tiled.window_offsets[w], tiled.window_offsets[w + 1]
        assert len(features) == end - first  # random pieces: none shorter than a unit
        assert [f["id"] for f in features] == tiled.source[first:end].tolist()
        for feature in features:
            assert feature["geometry"]["type"] == "LineString"
            assert feature["properties"] == {}


def test_positions_are_the_exact_rounding_where_every_float_operation_is_exact(backend, rng):
    # Windows 16 units wide at multiples of 16, extent 4096 (scale 256), ends on a grid
    # of 1/1024: the differences, products and sums are exact, so the positions are
    # floor(exact + 1/2), halves included (1/512 * 256 = 1/2).
    windows = np.array([(16.0 * i, 0.0, 16.0 * i + 16.0, 16.0) for i in range(3)])
    segs = rng.integers(-2 * 1024, 50 * 1024, (400, 4)) / 1024.0
    tiled, tiles = encode_and_check(segs, windows, backend)
    for w, (x0, _, _, y1) in enumerate(windows.tolist()):
        rows = range(tiled.window_offsets[w], tiled.window_offsets[w + 1])
        expected = {}
        for i in rows:
            ax, ay, bx, by = (Fraction(float(v)) for v in tiled.segments[i])
            ends = [(math.floor((x - Fraction(x0)) * 256 + Fraction(1, 2)),
                     math.floor((Fraction(y1) - y) * 256 + Fraction(1, 2)))
                    for x, y in ((ax, ay), (bx, by))]
            if ends[0] != ends[1]:
                expected[int(tiled.source[i])] = [list(p) for p in ends]
        got = {f["id"]: f["geometry"]["coordinates"] for f in decode(tiles.tile(w) or _EMPTY)}
        assert got == expected


_EMPTY = Tile(layers=[Layer(name="segments", extent=4096, version=2)]).SerializeToString()


def test_pieces_that_round_to_one_position_are_dropped_and_their_tile_left_empty(backend):
    windows = np.array([(0.0, 0.0, 4096.0, 4096.0), (4096.0, 0.0, 8192.0, 4096.0)])
    segs = np.array([[10.0, 10.0, 10.4, 10.4],     # one position: dropped
                     [20.0, 20.0, 20.0, 20.0],     # zero length: dropped
                     [30.0, 30.0, 30.6, 30.0],     # rounds to two positions: kept
                     [5000.0, 1.0, 5000.2, 1.3]])  # the only piece of tile 1: dropped
    tiled, tiles = encode_and_check(segs, windows, backend)
    assert [f["id"] for f in decode(tiles.tile(0))] == [2]
    assert tiles.tile(1) == b"" and tiles.offsets[2] == tiles.offsets[1]


def test_pieces_on_the_tile_edges_and_corners_quantise_to_0_and_extent(backend):
    windows = np.array([(-3.0, 7.0, 0.1, 9.3)])
    x0, y0, x1, y1 = windows[0]
    segs = np.array([[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0],
                     [x0, y0, x1, y1]])
    _, tiles = encode_and_check(segs, windows, backend, extent=512)
    coordinates = [f["geometry"]["coordinates"] for f in decode(tiles.tile(0), extent=512)]
    assert coordinates == [[[0, 512], [512, 512]], [[512, 512], [512, 0]],
                           [[512, 0], [0, 0]], [[0, 0], [0, 512]], [[0, 512], [512, 0]]]


def test_steps_in_every_direction_and_the_largest_varints(backend):
    # Extent 2**20: positions up to 2**20 (three varint bytes once zigzagged), steps
    # of either sign along both axes.
    windows = np.array([(0.0, 0.0, 1.0, 1.0)])
    segs = np.array([[0.0, 0.0, 1.0, 1.0], [1.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0],
                     [0.5, 0.25, 0.5, 0.75], [0.75, 0.5, 0.0, 0.5]])
    _, tiles = encode_and_check(segs, windows, backend, extent=2**20)
    big = 2**20
    assert [f["geometry"]["coordinates"] for f in decode(tiles.tile(0), extent=big)] == [
        [[0, big], [big, 0]], [[big, 0], [0, big]], [[big, big], [0, 0]],
        [[big // 2, 3 * big // 4], [big // 2, big // 4]], [[3 * big // 4, big // 2],
                                                           [0, big // 2]]]


@pytest.mark.parametrize("width", [1e-12, 1e-300, 1e150], ids=["tiny", "tinier", "huge"])
def test_tiny_and_huge_windows(backend, rng, width):
    windows = np.array([(1.0, -2.0, 1.0 + width, -2.0 + width),
                        (1.0 + width, -2.0, 1.0 + 2 * width, -2.0 + width)])
    if width < 1e-100:  # 1 + 1e-300 is 1: windows at the origin instead
        windows = np.array([(0.0, 0.0, width, width), (width, 0.0, 2 * width, width)])
    x0, y0, _, y1 = windows[0]
    segs = np.column_stack([x0 + rng.uniform(-0.5, 2.5, (200, 2)) * width,
                            y0 + rng.uniform(-0.5, 1.5, (200, 2)) * width])[:, [0, 2, 1, 3]]
    tiled, tiles = encode_and_check(segs, windows, backend)
    assert len(tiled) > 0 and tiles.data.shape[0] > 0


def test_without_sources_features_have_no_id(backend, rng):
    segs = rng.uniform(-5, 25, (50, 4))
    tiled, tiles = encode_and_check(segs, GRID, backend, outputs=("segments",))
    assert tiled.source is None
    for w in range(len(GRID)):
        message = Tile.FromString(tiles.tile(w))
        assert all(not f.HasField("id") for f in message.layers[0].features)


def test_no_pieces_at_all_gives_empty_tiles(backend):
    segs = np.array([[100.0, 100.0, 200.0, 200.0]])
    _, tiles = encode_and_check(segs, GRID, backend)
    assert tiles.data.shape == (0,) and tiles.offsets.tolist() == [0] * 5
    _, tiles = encode_and_check(np.empty((0, 4)), GRID, backend)
    assert tiles.offsets.tolist() == [0] * 5


def test_the_layer_name_and_extent_are_those_asked_for(backend, rng):
    segs = rng.uniform(-5, 25, (40, 4))
    _, tiles = encode_and_check(segs, GRID, backend, extent=256, layer="roads é")
    assert decode(tiles.tile(0), layer="roads é", extent=256)


def test_numba_and_opencl_give_the_same_bytes(opencl64, rng):
    from rnsca.options import Backend

    # opencl64: a float64 device (float32 devices refuse tiles: test_opencl_tiles.py)
    segs = rng.uniform(-10, 1010, (20_000, 4))
    segs[::2, 2:] = segs[::2, :2] + rng.normal(0, 3, (10_000, 2))
    edges = np.linspace(0, 1000, 9)
    windows = np.array([(a, c, b, d) for c, d in zip(edges, edges[1:], strict=False)
                        for a, b in zip(edges, edges[1:], strict=False)])
    tiled = rnsca.clip_segments(segs, windows=windows)
    numba = encode_segment_tiles(tiled, windows, extent=1024, backend="numba")
    device = encode_segment_tiles(tiled, windows, extent=1024, backend=Backend.OPENCL)
    assert np.array_equal(numba.data, device.data)
    assert np.array_equal(numba.offsets, device.offsets)
    assert device.device is not None and numba.device is None


# --- bad input ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiled():
    return rnsca.clip_segments([[1.0, 1.0, 15.0, 15.0]], windows=GRID)


@pytest.mark.parametrize("extent", [0, -1, 2**20 + 1, 4096.0, True, "4096", None])
def test_an_extent_out_of_range_is_refused(tiled, extent):
    with pytest.raises(InvalidOptionError, match="extent must be an int in 1..1048576"):
        encode_segment_tiles(tiled, GRID, extent=extent)


@pytest.mark.parametrize("layer", ["", None, b"segments"])
def test_an_empty_or_non_string_layer_name_is_refused(tiled, layer):
    with pytest.raises(InvalidOptionError, match="layer must be a non-empty name"):
        encode_segment_tiles(tiled, GRID, layer=layer)


def test_a_one_window_result_is_refused():
    one = rnsca.clip_segments([[1.0, 1.0, 15.0, 15.0]], (0, 0, 10, 10))
    with pytest.raises(InvalidOptionError, match="no window_offsets.*windows=windows"):
        encode_segment_tiles(one, GRID)


def test_windows_that_are_not_the_results_are_refused(tiled):
    with pytest.raises(InvalidOptionError,
                       match=r"\(shape \(5,\), \[2\] pieces\) do not match the 3 windows"):
        encode_segment_tiles(tiled, GRID[:3])
    with pytest.raises(InvalidOptionError, match="do not match the 8 windows"):
        encode_segment_tiles(tiled, np.vstack([GRID, GRID]))


@pytest.mark.parametrize("offsets", [[], [0, 2, 1, 1, 2], [1, 1, 1, 1, 2], [0, 1, 1, 1, 3]],
                         ids=["empty", "decreasing", "not-from-0", "not-to-m"])
def test_window_offsets_that_do_not_describe_the_pieces_are_refused(tiled, offsets):
    import dataclasses

    broken = dataclasses.replace(tiled, window_offsets=np.array(offsets, dtype=np.int64))
    with pytest.raises(InvalidOptionError, match="window_offsets .* do not match"):
        encode_segment_tiles(broken, GRID)


def test_bad_windows_are_refused(tiled):
    bad = GRID.copy()
    bad[2, 2] = bad[2, 0]
    with pytest.raises(InvalidWindowError, match="window 2"):
        encode_segment_tiles(tiled, bad)
    wide = GRID.copy()
    wide[1] = (-1e308, 0.0, 1e308, 10.0)  # x1 - x0 overflows: the scale is 0
    with pytest.raises(InvalidWindowError, match="window 1 .*too narrow or too wide"):
        encode_segment_tiles(tiled, wide)
    narrow = GRID.copy()
    narrow[3] = (0.0, 0.0, 5e-324, 10.0)  # extent / width overflows
    with pytest.raises(InvalidWindowError, match="window 3 "):
        encode_segment_tiles(tiled, narrow)


def test_pieces_far_beyond_their_tile_are_refused_naming_the_piece(backend):
    tiled = rnsca.clip_segments([[1.0, 1.0, 15.0, 15.0]], windows=GRID, backend=backend)
    assert tiled.window_offsets.tolist() == [0, 1, 1, 1, 2]
    far = GRID.copy()
    far[3] = (1e9, 1e9, 1e9 + 10.0, 1e9 + 10.0)
    # Piece 1 (of window 3) lies 1e9 units, 4e11 tile units, from far[3]: not its piece.
    with pytest.raises(InvalidGeometryError, match=r"piece 1 \[10.0, 10.0, 15.0, 15.0\] "
                                                   r"of tile 3 lies 1073741824 tile units"):
        encode_segment_tiles(tiled, far, backend=backend)


def test_a_result_on_a_device_is_refused_by_a_host_backend(opencl64):
    import pyopencl.array as cl_array

    opencl = opencl64
    segs = cl_array.to_device(opencl.queue, np.array([[1.0, 1.0, 15.0, 15.0]]))
    tiled = rnsca.clip_segments(segs, windows=GRID, backend="opencl")
    with pytest.raises(InvalidGeometryError, match="pyopencl arrays.*backend='opencl'"):
        encode_segment_tiles(tiled, GRID, backend="numba")
    assert encode_segment_tiles(tiled, GRID).backend is rnsca.Backend.OPENCL  # the default


def test_an_unknown_backend_is_refused(tiled):
    with pytest.raises(ValueError, match="backend"):
        encode_segment_tiles(tiled, GRID, backend="cuda")
