"""PMTiles v3 archives, written a zoom at a time with the per-entry work in NumPy.

`PMTilesWriter` stores what the ``pmtiles`` package's ``Writer`` stores (the
specification's reference implementation, https://github.com/protomaps/PMTiles,
``spec/v3/spec.md``), byte for byte where the tiles allow (see "Differences" below),
but it takes a zoom's tiles at once and does the work per tile and per entry with
arrays, not a Python object and a Python varint per field:

- tile data in the order the tiles come (tile-id order: "clustered"), each distinct
  content stored once, at the offset of its first tile;
- one directory entry per run of consecutive tile ids with the same content;
- directories as varint columns (the count, then tile-id deltas, run lengths, lengths,
  offsets + 1 or 0 where an entry's data follows the previous entry's), each gzipped
  (level 9, mtime 0, as ``gzip.compress``);
- the root directory alone when it gzips under 16,384 - 127 bytes, otherwise leaf
  directories of 4,096 entries (8,192, ... until the root of leaves fits), the
  package's search;
- sections in the package's order: header, root directory, metadata (gzipped JSON),
  leaf directories, tile data. The tile data goes to a temporary file as the zooms
  come (memory holds the entries, never the tiles of earlier zooms) and is copied
  after the directories once they are known.

The header's layout is the package's (``pmtiles.tile.serialize_header``).

Measured on the lines benchmark (``benchmarks/bench_tiles.py``: 533,200 tiles of zooms
0-10, one entry each, gzipped beforehand so that only the writer runs; CPU seconds by
``time.process_time``, this 2-core machine): the package's ``Writer`` 3.0 s (per tile,
``write_tile``: Python's hashing and an ``Entry`` object; ``finalize``: a Python varint
per field per entry in ``serialize_directory``, for the whole directory and again for
each leaf, and zlib level 9 of the whole directory), this writer 0.9-1.0 s. Of that,
the directories take 0.33 s: 0.14 s for zlib to show that the root alone does not fit
(given up after 256 KB of its 2.3 MB), 0.13 s zlib level 9 of the 131 leaves (what the
package stores; the leaves are compressed across a pool's threads), and only 0.05 s for
NumPy's varints of every leaf, so no Numba kernel is needed for them. The rest is per
tile and mostly Python's own: taking each tile's length and ``hash``, the argsorts
(tile ids, hashes), and joining the new contents in tile-id order for one write per
zoom.

Differences from the package, each deliberate:

- Content is compared byte for byte. The package keys its table on Python's 64-bit
  ``hash`` of the data alone (two contents whose hashes collide would share one);
  here the hash only groups candidates: a zoom's tiles are compared with the first
  of their group, and a content stored by an earlier zoom is read back and compared.
- Runs join tiles whose content has the same offset *and length*. The package compares
  offsets only: an empty tile (length 0) shares its offset with the content stored
  after it, and a later copy of the empty tile would join that content's run.
- ``max_zoom`` is the zoom of the archive's last tile. The package takes the zoom of
  the last entry's first tile, which is lower when a run crosses into the next zoom
  (a world-covering polygon gives every tile of every zoom the same content: one run).
- The archive is clustered while each call's first tile comes after the previous
  call's last; the package compares with the first tile of the last entry (a run).
"""

from __future__ import annotations

import gzip
import json
import operator
import os
import shutil
import tempfile
import zlib
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, BinaryIO, cast

import numpy as np

__all__ = ["Entries", "PMTilesWriter", "varints", "serialize_directory", "build_directories",
           "HEADER_LENGTH", "ROOT_LIMIT", "FIRST_LEAF_SIZE"]

#: Bytes of the header; it and the root directory must fit in the first 16,384 bytes.
HEADER_LENGTH = 127
#: The root directory's gzipped bytes must be fewer than this (the package's test).
ROOT_LIMIT = 16_384 - HEADER_LENGTH
#: Entries per leaf directory tried first; doubled until the root of leaves fits.
FIRST_LEAF_SIZE = 4096
#: gzip's header (10 bytes, no file name) and trailer (CRC-32 and size, 8 bytes).
_GZIP_FRAME = 18


@dataclass(frozen=True)
class Entries:
    """Directory entries: one per run of tiles (``run_length`` >= 1) or per leaf (0).

    Attributes
    ----------
    tile_id : ndarray of uint64
        The first tile of each run (of each leaf: its first entry's), nondecreasing.
    offset, length : ndarray of int64
        The content's bytes in the tile data (a leaf's in the leaf directories).
    run_length : ndarray of int64
        Consecutive tile ids with this content; 0 for an entry that points to a leaf.
    """

    tile_id: np.ndarray
    offset: np.ndarray
    length: np.ndarray
    run_length: np.ndarray

    def __len__(self) -> int:
        return self.tile_id.shape[0]

    def __getitem__(self, index: slice | np.ndarray) -> Entries:
        return Entries(self.tile_id[index], self.offset[index], self.length[index],
                       self.run_length[index])

    @classmethod
    def concatenate(cls, parts: Sequence[Entries]) -> Entries:
        """Return the entries of `parts` one after the other."""
        return cls(*(np.concatenate([getattr(p, name) for p in parts]) for name in
                     ("tile_id", "offset", "length", "run_length")))


def varints(values: np.ndarray) -> bytes:
    """Return `values` as unsigned LEB128 varints, one after the other (vectorised).

    Seven bits a byte, least significant first, the high bit set on all bytes but a
    value's last: the package's ``write_varint`` for every value at once.

    Parameters
    ----------
    values : array_like of uint64

    Examples
    --------
    >>> varints(np.array([0, 1, 127, 128, 300], dtype=np.uint64)).hex(" ")
    '00 01 7f 80 01 ac 02'
    """
    v = np.asarray(values, dtype=np.uint64).ravel()
    # A value takes one byte, and one more for each 7 bits past the first 7.
    size = np.ones(v.shape, dtype=np.int64)
    for k in range(1, 10):
        size += v >= np.uint64(1 << (7 * k))
    ends = np.cumsum(size)
    out = np.empty(int(ends[-1]) if v.size else 0, dtype=np.uint8)
    starts = ends - size
    at, left, rest = starts, size, v
    for k in range(int(size.max()) if v.size else 0):
        if k:  # only the values with a byte k
            keep = left > k
            at, left, rest = at[keep], left[keep], rest[keep]
        more = (left > k + 1).astype(np.uint8) << np.uint8(7)
        out[at + k] = ((rest >> np.uint64(7 * k)) & np.uint64(0x7F)).astype(np.uint8) | more
    return out.tobytes()


def _directory_parts(entries: Entries, piece: int = 1 << 16) -> Iterator[bytes]:
    """Yield the directory's uncompressed bytes: the count, then the four columns.

    Each column comes in varints of `piece` entries at most, so that a reader that
    stops early (`_gzipped_if_under`) has not encoded the rest.
    """
    n = len(entries)
    follows = np.zeros(n, dtype=bool)
    follows[1:] = entries.offset[1:] == entries.offset[:-1] + entries.length[:-1]
    columns: tuple[np.ndarray, ...] = (
        np.array([n], dtype=np.uint64),
        np.diff(entries.tile_id, prepend=np.uint64(0)),
        entries.run_length,
        entries.length,
        np.where(follows, 0, entries.offset + 1),  # 0: the data follow the entry before
    )
    for column in columns:
        for start in range(0, column.shape[0], piece):
            yield varints(column[start:start + piece])


def serialize_directory(entries: Entries) -> bytes:
    """Return the directory of `entries`, gzipped: ``pmtiles.tile.serialize_directory``."""
    return gzip.compress(b"".join(_directory_parts(entries)), mtime=0)


def _gzipped_if_under(parts: Iterable[bytes], limit: int) -> bytes | None:
    """Return ``gzip.compress(b"".join(parts), mtime=0)`` if shorter than `limit`, else None.

    The deflate stream is fed a part at a time and given up as soon as its output
    reaches `limit`: a directory of many entries is never encoded and compressed whole
    only to learn that it does not fit (the package does both).
    """
    deflate = zlib.compressobj(9, zlib.DEFLATED, -15)
    produced = _GZIP_FRAME
    raw = []
    for part in parts:
        raw.append(part)
        produced += len(deflate.compress(part))
        if produced >= limit:
            return None
    whole = gzip.compress(b"".join(raw), mtime=0)
    return whole if len(whole) < limit else None


def build_directories(entries: Entries, map_: Callable[..., Iterable[bytes]] = map
                      ) -> tuple[bytes, bytes, int]:
    """Return the root directory, the leaf directories and how many leaves, all gzipped.

    ``pmtiles.writer.optimize_directories``: the root alone if it gzips under
    `ROOT_LIMIT`, otherwise leaves of `FIRST_LEAF_SIZE` entries, doubled until the root
    of leaves fits. `map_` compresses the leaves (``pool.map`` spreads them over threads;
    zlib releases the GIL).
    """
    root = _gzipped_if_under(_directory_parts(entries), ROOT_LIMIT)
    if root is not None:
        return root, b"", 0
    n = len(entries)
    leaf_size = FIRST_LEAF_SIZE
    while True:
        starts = np.arange(0, n, leaf_size)
        leaves = list(map_(serialize_directory,
                           [entries[s:s + leaf_size] for s in starts.tolist()]))
        lengths = np.fromiter(map(len, leaves), dtype=np.int64, count=len(leaves))
        root = serialize_directory(Entries(
            entries.tile_id[starts], np.cumsum(lengths) - lengths, lengths,
            np.zeros(len(leaves), dtype=np.int64)))
        if len(root) < ROOT_LIMIT:
            return root, b"".join(leaves), len(leaves)
        leaf_size *= 2


def _first_of_content(data: Sequence[bytes], order: np.ndarray,
                      hashes: np.ndarray) -> np.ndarray:
    """Return, for each tile ``data[order[i]]``, the first ``i`` with the same bytes.

    Tiles are grouped by `hashes` (Python's ``hash`` of ``data[order]``), and each tile
    of a group compared with the group's first; should two different contents share a
    hash, the tiles are grouped by a dict of their bytes instead (exact, slower:
    measured 0.23 s against 0.05 s for the 366,653 tiles of the lines benchmark's zoom
    10).
    """
    n = order.shape[0]
    by_hash = np.argsort(hashes, kind="stable")  # stable: a group's first tile first
    sorted_hashes = hashes[by_hash]
    starts = np.ones(n, dtype=bool)
    starts[1:] = sorted_hashes[1:] != sorted_hashes[:-1]
    first = np.empty(n, dtype=np.int64)
    first[by_hash] = by_hash[starts][np.cumsum(starts) - 1]
    repeated = np.flatnonzero(first != np.arange(n))
    if all(map(operator.eq, [data[k] for k in order[repeated].tolist()],
               [data[k] for k in order[first[repeated]].tolist()])):
        return first
    in_order = [data[k] for k in order.tolist()]
    # Filled backwards: each content keeps its first tile's index.
    first_of = dict(zip(reversed(in_order), range(n - 1, -1, -1), strict=True))
    return np.fromiter(map(first_of.__getitem__, in_order), dtype=np.int64, count=n)


def _zoom_of(tile_id: int) -> int:
    """Return the zoom of a tile id (``pmtiles.tile.tileid_to_zxy``'s first number)."""
    return ((3 * tile_id + 1).bit_length() - 1) // 2


class PMTilesWriter:
    """Write tiles to `out` as a PMTiles v3 archive: `add` them, then `finalize`.

    The ``pmtiles`` package's ``Writer``, taking many tiles at a time (the module's
    docstring). Tile data waits in a temporary file until `finalize`; close the writer
    (or use it as a context manager) to remove that file if `finalize` is never reached.
    """

    def __init__(self, out: BinaryIO) -> None:
        self._out = out
        self._data = tempfile.TemporaryFile()
        self._stored = 0  # bytes of tile data so far
        # The stored contents, sorted by Python's hash of their bytes.
        self._hash = np.empty(0, dtype=np.int64)
        self._offset = np.empty(0, dtype=np.int64)
        self._length = np.empty(0, dtype=np.int64)
        self._contents = 0
        self._entries: list[Entries] = []
        self._addressed = 0
        self._clustered = True

    def __enter__(self) -> PMTilesWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Remove the temporary file of tile data."""
        self._data.close()

    def add(self, tile_id: np.ndarray, data: Sequence[bytes]) -> int:
        """Add tiles: ``data[i]`` (stored bytes) is tile ``tile_id[i]``; return their bytes.

        A call's tiles are stored in tile-id order (a stable sort), whatever their order
        in `data`. The archive is clustered when each call's tiles come after the
        previous call's, as `write_pmtiles` gives them (a zoom each, zooms increasing).
        """
        n = len(data)
        tile_id = np.asarray(tile_id, dtype=np.uint64)
        if tile_id.shape != (n,):
            raise ValueError(f"{tile_id.size} tile ids for {n} tiles: give one id per tile")
        if n == 0:
            return 0
        order = np.argsort(tile_id, kind="stable")
        length = np.fromiter(map(len, data), dtype=np.int64, count=n)
        hashes = np.fromiter(map(hash, data), dtype=np.int64, count=n)
        # From here on, tile i is tile order[i] of the call's.
        tile_id, length, hashes = tile_id[order], length[order], hashes[order]
        first = _first_of_content(data, order, hashes)
        distinct = np.flatnonzero(first == np.arange(n))
        at = np.empty(n, dtype=np.int64)
        at[distinct] = self._store(data, order[distinct], hashes[distinct],
                                   length[distinct])
        self._add_runs(tile_id, at[first], length)
        self._addressed += n
        return int(length.sum())

    def _store(self, data: Sequence[bytes], contents: np.ndarray, hashes: np.ndarray,
               length: np.ndarray) -> np.ndarray:
        """Return the offset of each content ``data[contents[j]]``, writing the new ones.

        `contents` holds the first tile of each content of the call, in tile-id order
        (new contents are stored in that order); `hashes` and `length` are theirs. A
        content stored by an earlier call is found by its hash and read back to be
        compared (two contents whose hashes collide are both stored, each once).
        """
        offset = np.full(contents.shape[0], -1, dtype=np.int64)
        if self._hash.size:
            by_hash = np.argsort(hashes)  # sorted keys: NumPy's search starts at the last
            low, high = np.empty_like(by_hash), np.empty_like(by_hash)
            low[by_hash] = np.searchsorted(self._hash, hashes[by_hash], side="left")
            high[by_hash] = np.searchsorted(self._hash, hashes[by_hash], side="right")
            for j in np.flatnonzero(high > low).tolist():
                offset[j] = self._find(data[contents[j]], range(low[j], high[j]))
        new = np.flatnonzero(offset < 0)
        if new.size == 0:
            return offset
        ends = self._stored + np.cumsum(length[new])
        offset[new] = ends - length[new]
        self._data.write(b"".join([data[i] for i in contents[new].tolist()]))
        self._data.flush()  # read back by `os.pread` in later calls
        self._stored = int(ends[-1])
        self._contents += new.size
        merged = np.concatenate([self._hash, hashes[new]])
        order = np.argsort(merged, kind="stable")
        self._hash = merged[order]
        self._offset = np.concatenate([self._offset, offset[new]])[order]
        self._length = np.concatenate([self._length, length[new]])[order]
        return offset

    def _find(self, content: bytes, candidates: range) -> int:
        """Return the offset of `content` if stored, else -1: `candidates` share its hash."""
        for k in candidates:
            if (self._length[k] == len(content) and content
                    == os.pread(self._data.fileno(), len(content), int(self._offset[k]))):
                return int(self._offset[k])
        return -1

    def _add_runs(self, tile_id: np.ndarray, offset: np.ndarray, length: np.ndarray) -> None:
        """Add the entries of tiles whose content is at `offset`, `length` (in tile order).

        A tile continues the run before it if its id is the next and its content the
        same (same offset and length); the first tile may continue the last entry of
        the call before.
        """
        n = tile_id.shape[0]
        same = (offset[1:] == offset[:-1]) & (length[1:] == length[:-1])
        continues = np.concatenate([[False], (tile_id[1:] == tile_id[:-1] + np.uint64(1))
                                    & same])
        if self._entries:
            last = self._entries[-1]
            after_last = int(last.tile_id[-1]) + int(last.run_length[-1])
            # A call's tiles are sorted; the archive stays clustered if they follow the
            # previous call's.
            if int(tile_id[0]) < after_last:
                self._clustered = False
            continues[0] = (int(tile_id[0]) == after_last and offset[0] == last.offset[-1]
                            and length[0] == last.length[-1])
        starts = np.flatnonzero(~continues)
        run_length = np.diff(np.append(starts, n))
        if continues[0]:
            self._entries[-1].run_length[-1] += starts[0] if starts.size else n
        if starts.size:
            self._entries.append(Entries(tile_id[starts], offset[starts], length[starts],
                                         run_length))

    def finalize(self, header: dict[str, Any], metadata: dict[str, Any],
                 map_: Callable[..., Iterable[bytes]] = map) -> None:
        """Write the archive: header, root directory, metadata, leaves, tile data.

        `header` gives the fields the tiles do not (``tile_type``, ``tile_compression``,
        bounds, center), as ``pmtiles.writer.Writer.finalize`` takes them; `metadata` is
        stored as gzipped JSON. `map_` compresses the leaf directories.
        """
        from pmtiles.tile import Compression, HeaderDict, serialize_header

        if not self._entries:
            raise ValueError("no tile was added: a PMTiles archive needs one")
        entries = Entries.concatenate(self._entries)
        if not self._clustered:
            entries = entries[np.argsort(entries.tile_id, kind="stable")]
        root, leaves, _ = build_directories(entries, map_)
        meta = gzip.compress(json.dumps(metadata).encode(), mtime=0)
        last = int(np.max(entries.tile_id + (entries.run_length - 1).astype(np.uint64)))
        header = dict(header)
        header.update({
            "addressed_tiles_count": self._addressed,
            "tile_entries_count": len(entries),
            "tile_contents_count": self._contents,
            "min_zoom": _zoom_of(int(entries.tile_id[0])),
            "max_zoom": _zoom_of(last),
            "clustered": self._clustered,
            "internal_compression": Compression.GZIP,
            "root_offset": HEADER_LENGTH,
            "root_length": len(root),
            "metadata_offset": HEADER_LENGTH + len(root),
            "metadata_length": len(meta),
            "leaf_directory_offset": HEADER_LENGTH + len(root) + len(meta),
            "leaf_directory_length": len(leaves),
            "tile_data_offset": HEADER_LENGTH + len(root) + len(meta) + len(leaves),
            "tile_data_length": self._stored,
        })
        for section in (serialize_header(cast("HeaderDict", header)), root, meta, leaves):
            self._out.write(section)
        self._data.seek(0)
        shutil.copyfileobj(self._data, self._out, 1 << 20)
