"""The vectorised PMTiles writer (`rnsca.tiles.pmtiles_v3`) against the ``pmtiles`` package.

The package's ``Writer`` is the reference: on the same tiles the archives are equal byte
for byte, except where the module's docstring says the writer differs on purpose (runs
across zooms, empty tiles, hash collisions); there the package's reader, an independent
decoder, checks every tile and header field.
"""

from __future__ import annotations

import gzip
import io
import json

import numpy as np
import pytest

pmtiles = pytest.importorskip("pmtiles", reason="the tiles extra (pmtiles) is not installed")

from pmtiles.reader import MemorySource, Reader, all_tiles  # noqa: E402
from pmtiles.tile import Compression as PMCompression  # noqa: E402
from pmtiles.tile import Entry, TileType, tileid_to_zxy  # noqa: E402
from pmtiles.writer import Writer, optimize_directories  # noqa: E402

from rnsca.tiles import pmtiles_v3 as V  # noqa: E402
from rnsca.tiles import tile_ids, write_pmtiles  # noqa: E402
from rnsca.tiles.encode import ZoomTiles  # noqa: E402

HEADER = {"tile_type": TileType.MVT, "tile_compression": PMCompression.NONE,
          "min_lon_e7": -1_800_000_000, "min_lat_e7": -850_511_287,
          "max_lon_e7": 1_800_000_000, "max_lat_e7": 850_511_287, "center_zoom": 0}
METADATA = {"name": "t", "vector_layers": [{"id": "t", "fields": {}}]}


def _ours(calls: list[tuple[np.ndarray, list[bytes]]]) -> bytes:
    out = io.BytesIO()
    with V.PMTilesWriter(out) as writer:
        for ids, data in calls:
            writer.add(ids, data)
        writer.finalize(HEADER, METADATA)
    return out.getvalue()


def _package(calls: list[tuple[np.ndarray, list[bytes]]]) -> bytes:
    """The package's writer, fed each call's tiles in tile-id order (what `add` stores)."""
    out = io.BytesIO()
    writer = Writer(out)
    for ids, data in calls:
        for k in np.argsort(ids, kind="stable").tolist():
            writer.write_tile(int(ids[k]), data[k])
    writer.finalize(dict(HEADER), METADATA)
    return out.getvalue()


def _read(archive: bytes) -> tuple[dict, dict, dict]:
    reader = Reader(MemorySource(archive))
    return reader.header(), reader.metadata(), dict(all_tiles(reader.get_bytes))


def _expected(calls: list[tuple[np.ndarray, list[bytes]]]) -> dict:
    return {tileid_to_zxy(int(i)): d for ids, data in calls
            for i, d in zip(ids.tolist(), data, strict=True)}


def _runs(calls: list[tuple[np.ndarray, list[bytes]]]) -> int:
    """Return the entries the specification asks for: runs of consecutive ids, same bytes."""
    tiles = sorted((int(i), d) for ids, data in calls for i, d in zip(ids, data, strict=True))
    return sum(1 for k, (i, d) in enumerate(tiles)
               if k == 0 or (i, d) != (tiles[k - 1][0] + 1, tiles[k - 1][1]))


def _zoom(zoom: int, rng: np.random.Generator, count: int | None = None) -> np.ndarray:
    """Return the ids of `count` tiles of `zoom` (all of them by default), shuffled."""
    side = 1 << zoom
    cells = rng.permutation(side * side)[:count]
    return tile_ids(zoom, cells % side, cells // side)


def _check(calls: list[tuple[np.ndarray, list[bytes]]], archive: bytes) -> dict:
    header, metadata, read = _read(archive)
    expected = _expected(calls)
    assert read == expected
    assert metadata == METADATA
    assert header["addressed_tiles_count"] == len(expected)
    assert header["tile_contents_count"] == len(set(expected.values()))
    assert header["tile_entries_count"] == _runs(calls)
    zooms = [z for z, _, _ in expected]
    assert (header["min_zoom"], header["max_zoom"]) == (min(zooms), max(zooms))
    assert header["clustered"]
    assert header["root_offset"] + header["root_length"] <= 16_384
    return header


def test_varints_are_the_package_s_varints():
    from pmtiles.tile import write_varint

    values = np.array([0, 1, 127, 128, 255, 16_383, 16_384, 2**21, 2**35 + 3, 2**56,
                       2**63, 2**64 - 1], dtype=np.uint64)
    expected = io.BytesIO()
    for v in values.tolist():
        write_varint(expected, v)
    assert V.varints(values) == expected.getvalue()
    assert V.varints(np.array([], dtype=np.uint64)) == b""


def test_directories_are_the_package_s_directories(rng):
    from pmtiles.tile import serialize_directory

    n = 5000
    tile_id = np.cumsum(rng.integers(1, 4, n)).astype(np.uint64)
    length = rng.integers(0, 300, n)
    # Most entries follow the previous one's data (offset 0 in the column), some not.
    offset = np.cumsum(length) - length
    jump = rng.random(n) < 0.2
    offset[jump] = rng.integers(0, 10_000, jump.sum())
    run_length = rng.integers(1, 5, n)
    entries = V.Entries(tile_id, offset, length, run_length)
    package = [Entry(*e) for e in zip(tile_id.tolist(), offset.tolist(), length.tolist(),
                                      run_length.tolist(), strict=True)]
    assert V.serialize_directory(entries) == serialize_directory(package)
    assert V.build_directories(entries) == optimize_directories(package, V.ROOT_LIMIT)


def test_a_small_archive_equals_the_package_s_byte_for_byte(rng):
    calls = [(_zoom(z, rng), [b"tile %d" % k for k in range(4**z)]) for z in range(4)]
    archive = _ours(calls)
    assert archive == _package(calls)
    header = _check(calls, archive)
    assert header["leaf_directory_length"] == 0


def test_duplicates_make_runs_and_are_stored_once(rng):
    """Runs of equal tiles, and equal tiles far apart, in one zoom and across zooms."""
    calls = []
    for z in range(2, 7):
        ids = np.sort(_zoom(z, rng))
        # Blocks of consecutive ids with the same bytes (runs), a few contents repeated
        # all over the zoom (not consecutive), and one content seen in every zoom.
        block = np.arange(ids.size) // rng.integers(1, 9)
        data = [b"sea" if k % 7 == 0 else b"block %d" % (b % 5) if k % 3 else b"tile %d" % b
                for k, b in enumerate(block.tolist())]
        perm = rng.permutation(ids.size)  # given in any order: `add` sorts
        calls.append((ids[perm], [data[k] for k in perm.tolist()]))
    archive = _ours(calls)
    assert archive == _package(calls)
    header = _check(calls, archive)
    assert header["tile_entries_count"] < header["addressed_tiles_count"]
    assert header["tile_contents_count"] < header["tile_entries_count"]
    _, _, _, _, data_length = _sections(archive)
    assert data_length == sum(map(len, set(_expected(calls).values())))


def _sections(archive: bytes) -> tuple[int, int, int, int, int]:
    header = Reader(MemorySource(archive)).header()
    return (header["root_length"], header["metadata_length"],
            header["leaf_directory_length"], header["tile_data_offset"],
            header["tile_data_length"])


@pytest.fixture(scope="module")
def large():
    """130,000 tiny distinct tiles (zooms 0-7 whole, part of zoom 9): leaf directories.

    Returns the zooms, the same as `add`'s calls, and the archive the calls give.
    """
    rng = np.random.default_rng(7)
    zooms = []
    for z, count in [(z, 4**z) for z in range(8)] + [(9, 130_000 - (4**8 - 1) // 3)]:
        cells = rng.permutation(4**z)[:count]
        x, y = cells % (1 << z), cells // (1 << z)
        zooms.append(ZoomTiles(z, x, y, [b"%d/%d" % (z, k) for k in range(count)],
                               np.ones(count, dtype=np.int64)))
    calls = [(tile_ids(z.zoom, z.x, z.y), z.data) for z in zooms]
    return zooms, calls, _ours(calls)


def test_a_large_archive_has_leaves_and_equals_the_package_s(large):
    _, calls, archive = large
    assert archive == _package(calls)
    header = _check(calls, archive)
    assert header["leaf_directory_length"] > 0
    assert header["tile_entries_count"] == 130_000


def test_leaves_double_until_the_root_fits(monkeypatch, rng):
    """The package's search: leaves of 4,096 entries, then 8,192, ... (here from 16)."""
    from pmtiles.writer import build_roots_leaves

    monkeypatch.setattr(V, "FIRST_LEAF_SIZE", 16)
    monkeypatch.setattr(V, "ROOT_LIMIT", 400)
    n = 3000
    length = rng.integers(1, 1000, n)
    entries = V.Entries(np.cumsum(rng.integers(1, 100, n)).astype(np.uint64),
                        np.cumsum(length) - length, length, rng.integers(1, 3, n))
    root, leaves, count = V.build_directories(entries)
    leaf_size = 16 * 2 ** int(np.ceil(np.log2(n / 16 / count)))
    assert leaf_size >= 32 and count == -(-n // leaf_size) and len(root) < 400
    package = [Entry(*e) for e in zip(entries.tile_id.tolist(), entries.offset.tolist(),
                                      entries.length.tolist(), entries.run_length.tolist(),
                                      strict=True)]
    assert (root, leaves, count) == build_roots_leaves(package, leaf_size)
    assert len(build_roots_leaves(package, leaf_size // 2)[0]) >= 400


def test_a_run_across_zooms_gives_the_last_zoom_as_max_zoom():
    """Every tile the same (a world polygon): one run from zoom 0 into zoom 2.

    The package takes the zoom of the last entry's first tile (0); otherwise the
    archives are equal.
    """
    calls = [(tile_ids(z, *np.divmod(np.arange(4**z), 2**z)), [b"full"] * 4**z)
             for z in range(3)]
    archive = _ours(calls)
    header = _check(calls, archive)
    assert header["tile_entries_count"] == 1 and header["max_zoom"] == 2
    package = _package(calls)
    assert package[101] == 0
    assert archive[:101] + archive[102:] == package[:101] + package[102:]


def test_an_empty_tile_and_the_content_stored_after_it_stay_apart():
    """Both start at one offset; the package would join the third tile to the second's run."""
    calls = [(np.array([5, 6, 7], dtype=np.uint64), [b"", b"a", b""])]
    header = _check(calls, _ours(calls))
    assert header["tile_contents_count"] == 2


class _Colliding(bytes):
    """Bytes whose hashes all collide: contents must still be told apart by their bytes."""

    def __hash__(self) -> int:
        return 7


def test_contents_whose_hashes_collide_are_stored_apart():
    tiles = [_Colliding(b) for b in (b"a", b"b", b"a", b"c")]
    calls = [(np.array([1, 2], dtype=np.uint64), tiles[:2]),
             (np.array([5, 6, 7], dtype=np.uint64), tiles[1:]),
             (np.array([9], dtype=np.uint64), [_Colliding(b"b")])]
    header = _check(calls, _ours(calls))
    assert header["tile_contents_count"] == 3


def test_calls_out_of_order_give_an_unclustered_archive(rng):
    calls = [(_zoom(3, rng), [b"%d" % k for k in range(64)]),
             (_zoom(2, rng), [b"%d" % k for k in range(16)])]
    archive = _ours(calls)
    assert archive == _package(calls)
    header, _, read = _read(archive)
    assert not header["clustered"]
    assert read == _expected(calls)


def test_finalize_without_tiles_and_tiles_without_ids_are_refused():
    with V.PMTilesWriter(io.BytesIO()) as writer:
        with pytest.raises(ValueError, match="no tile"):
            writer.finalize(HEADER, METADATA)
        with pytest.raises(ValueError, match="3 tile ids for 2 tiles"):
            writer.add(np.arange(3, dtype=np.uint64), [b"a", b"b"])


@pytest.mark.parametrize("compressed", [False, True])
def test_write_pmtiles_equals_the_package_s_writer_on_many_tiles(tmp_path, large, compressed):
    """`write_pmtiles` as it was (the package's ``Writer``, tile by tile) gives the same bytes."""
    from rnsca.tiles.archive import Compression, compress_tiles

    zooms, _, _ = large
    if compressed:
        zooms = [compress_tiles(z, Compression.GZIP) for z in zooms[:7]]
    seen = []
    path = tmp_path / "a.pmtiles"
    summary = write_pmtiles(path, iter(zooms), layer="t", compressed=compressed,
                            compression="gzip" if compressed else "none",
                            on_zoom=lambda z, stored: seen.append((z.zoom, stored)))
    assert seen == [(z.zoom, sum(map(len, z.data))) for z in zooms]
    assert summary.tiles == sum(len(z) for z in zooms)
    archive = path.read_bytes()
    header, metadata, read = _read(archive)
    assert metadata["vector_layers"][0]["id"] == "t"
    expected = {(z.zoom, x, y): d for z in zooms
                for x, y, d in zip(z.x.tolist(), z.y.tolist(), z.data, strict=True)}
    assert read == expected
    assert header["addressed_tiles_count"] == header["tile_entries_count"] == len(expected)
    assert header["tile_compression"] == (PMCompression.GZIP if compressed
                                          else PMCompression.NONE)
    assert (header["min_zoom"], header["max_zoom"]) == (0, zooms[-1].zoom)
    assert header["center_zoom"] == 0 and header["clustered"]
    assert header["min_lon_e7"] == -1_800_000_000 and header["max_lat_e7"] > 850_000_000
    assert header["center_lon_e7"] == 0
    # The package's writer, tile by tile in tile-id order, with the same header fields.
    out = io.BytesIO()
    writer = Writer(out)
    for z in zooms:
        ids = tile_ids(z.zoom, z.x, z.y)
        for k in np.argsort(ids, kind="stable").tolist():
            writer.write_tile(int(ids[k]), z.data[k])
    writer.finalize({key: header[key] for key in ("tile_type", "tile_compression",
                                                  "min_lon_e7", "min_lat_e7", "max_lon_e7",
                                                  "max_lat_e7", "center_zoom")}, metadata)
    assert archive == out.getvalue()
    assert json.loads(gzip.decompress(archive[header["metadata_offset"]:][
        :header["metadata_length"]])) == metadata
