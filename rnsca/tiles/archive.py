"""Tile archives: PMTiles v3 (`rnsca.tiles.pmtiles_v3`) and a ``z/x/y.mvt`` tree.

Both take the zooms as `rnsca.tiles.encode.ZoomTiles` in increasing zoom order, as
`rnsca.tiles.tile_features` yields them, and write each zoom as it comes: memory holds
one zoom's tiles (and, for PMTiles, the directory entries of the zooms written). PMTiles
wants its tiles in tile-id order (zoom, then the Hilbert curve) to be "clustered": each
zoom is sorted by `tile_ids` as it is written.
Tiles are gzip-compressed (``compression="gzip"``, what map clients expect of
PMTiles and tippecanoe writes) by ISA-L (``isal``, level 2), in a pool of threads (it
releases the GIL), while the next zoom is made in another thread (`_made_ahead`).

ISA-L and not zlib, measured on the two workloads of ``benchmarks/bench_tiles.py``
(each tile compressed in one thread, this 2-core machine): 579 polygon tiles, 148 MB
raw: zlib level 6 7.3 s and 110.1 MB, ISA-L level 2 0.49 s and 110.5 MB; 533,200 line
tiles, 78 MB raw: zlib 6 5.0 s and 75.5 MB, ISA-L 2 3.0 s and 78.4 MB (MVT coordinates
are varints of deltas, nearly random bytes: every deflate level stores about the same).
"""

from __future__ import annotations

import math
import queue
import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from rnsca.options import _ChoiceEnum
from rnsca.tiles.encode import ZoomTiles
from rnsca.tiles.pmtiles_v3 import PMTilesWriter

__all__ = ["Compression", "ArchiveSummary", "tile_ids", "compress_tiles", "write_pmtiles",
           "write_directory"]


class Compression(_ChoiceEnum):
    """How tiles are stored."""

    GZIP = "gzip"
    """gzip (RFC 1952), as tippecanoe and most PMTiles archives store MVT."""
    NONE = "none"
    """Uncompressed protobuf."""


@dataclass
class ArchiveSummary:
    """What was written, per zoom: tiles, features, bytes (stored) and seconds."""

    zooms: list = field(default_factory=list)

    def add(self, zoom: int, tiles: int, features: int, stored: int, seconds: float) -> None:
        """Record one zoom."""
        self.zooms.append({"zoom": zoom, "tiles": tiles, "features": features,
                           "bytes": stored, "seconds": seconds})

    @property
    def tiles(self) -> int:
        """Return the tiles written."""
        return sum(z["tiles"] for z in self.zooms)

    @property
    def bytes(self) -> int:
        """Return the bytes of tile data written."""
        return sum(z["bytes"] for z in self.zooms)


def tile_ids(zoom: int, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Return the PMTiles v3 tile ids of tiles ``(zoom, x, y)``, uint64 (vectorised).

    The tiles of lower zooms first, then the Hilbert curve's index (the spec's
    ``zxy_to_tileid``, for every tile at once).

    Examples
    --------
    >>> tile_ids(1, np.array([0, 0, 1, 1]), np.array([0, 1, 1, 0])).tolist()
    [1, 2, 3, 4]
    """
    x = np.asarray(x, dtype=np.int64).copy()
    y = np.asarray(y, dtype=np.int64).copy()
    acc = np.full(x.shape, ((1 << (2 * zoom)) - 1) // 3, dtype=np.int64)
    for a in range(zoom - 1, -1, -1):
        s = np.int64(1 << a)
        rx = s & x
        ry = s & y
        acc += ((3 * rx) ^ ry) << a
        # Rotate the quadrant (the spec's `rotate`, with n = s).
        flip = (ry == 0) & (rx != 0)
        x = np.where(flip, s - 1 - x, x)
        y = np.where(flip, s - 1 - y, y)
        swap = ry == 0
        x, y = np.where(swap, y, x), np.where(swap, x, y)
    return acc.astype(np.uint64)


#: ISA-L's default level; its levels 0-3 all store MVT within 1% (module docstring).
GZIP_LEVEL = 2


def _compressor(compression: Compression) -> Callable[[bytes], bytes] | None:
    if compression is Compression.GZIP:
        from isal import isal_zlib

        # wbits 31: a gzip member (RFC 1952) with mtime 0, so archives are reproducible.
        return lambda data: isal_zlib.compress(data, GZIP_LEVEL, 31)
    return None


def compress_tiles(zoom: ZoomTiles, compression: Compression | str) -> ZoomTiles:
    """Return the zoom with each tile's data stored with `compression` (in this thread).

    What the writers do, done beforehand (on the worker that made the tiles): give them
    ``compressed=True``.
    """
    compress = _compressor(Compression(compression))
    if compress is None:
        return zoom
    return ZoomTiles(zoom.zoom, zoom.x, zoom.y, [compress(d) for d in zoom.data],
                     zoom.features)


def _stored(zoom: ZoomTiles, compress: Callable[[bytes], bytes] | None,
            pool: ThreadPoolExecutor) -> list[bytes]:
    """Return the tiles' stored bytes, compressed in chunks of tiles across the pool.

    One task per chunk, not per tile: a future per tile cost more than the compression
    of a small tile. Chunks hold about the same bytes, so a zoom of a few large tiles
    is spread over the threads as well as one of many small ones.
    """
    if compress is None:
        return zoom.data
    data = zoom.data
    n = len(data)
    if n == 0:
        return []
    sizes = np.fromiter((len(d) for d in data), dtype=np.int64, count=n)
    chunks = int(min(n, 64, max(1, sizes.sum() // (1 << 18), n // 256)))
    # Chunk k ends where the running byte count passes k + 1 shares.
    ends = np.searchsorted(np.cumsum(sizes), sizes.sum() * np.arange(1, chunks + 1) / chunks,
                           side="left") + 1
    bounds = [0, *np.minimum(ends, n).tolist()]
    bounds[-1] = n

    def chunk(k: int) -> list[bytes]:
        return [compress(d) for d in data[bounds[k]:bounds[k + 1]]]

    return [d for part in pool.map(chunk, range(chunks)) for d in part]


def write_pmtiles(path: str | Path | BinaryIO, zooms: Iterable[ZoomTiles], *, layer: str,
                  compression: Compression | str = Compression.GZIP,
                  metadata: dict[str, Any] | None = None,
                  on_zoom: Callable[[ZoomTiles, int], None] | None = None,
                  compressed: bool = False) -> ArchiveSummary:
    """Write the zooms' tiles as a PMTiles v3 archive at `path`; return the summary.

    `path` may be a binary file open for writing (it is not closed). With `compressed`,
    the tiles' data are already stored with `compression` (`compress_tiles`).

    `on_zoom(zoom_tiles, stored_bytes)` is called after each zoom is written (progress).
    The metadata has ``vector_layers`` (the one layer, its zooms), and any `metadata`.
    """
    from pmtiles.tile import Compression as PMCompression
    from pmtiles.tile import TileType

    compression = Compression(compression)
    compress = None if compressed else _compressor(compression)
    summary = ArchiveSummary()
    bounds = [math.inf, math.inf, -math.inf, -math.inf]
    zoom_range: list[int] = []
    with _opened(path) as f, ThreadPoolExecutor() as pool, PMTilesWriter(f) as writer:
        for zoom in _timed(zooms, summary):
            if len(zoom) == 0:
                continue
            total = writer.add(tile_ids(zoom.zoom, zoom.x, zoom.y),
                               _stored(zoom, compress, pool))
            summary.zooms[-1]["bytes"] = total
            _extend_bounds(bounds, zoom)
            zoom_range = [zoom_range[0] if zoom_range else zoom.zoom, zoom.zoom]
            if on_zoom is not None:
                on_zoom(zoom, total)
        if not zoom_range:
            raise ValueError("no tile holds a feature: nothing to write to a PMTiles archive")
        lon0, lat0, lon1, lat1 = bounds
        header = {
            "tile_type": TileType.MVT,
            "tile_compression": PMCompression.GZIP if compression is Compression.GZIP
            else PMCompression.NONE,
            "min_lon_e7": int(lon0 * 1e7), "min_lat_e7": int(lat0 * 1e7),
            "max_lon_e7": int(lon1 * 1e7), "max_lat_e7": int(lat1 * 1e7),
            "center_zoom": zoom_range[0],
        }
        meta = {"name": layer, "format": "pbf", "generator": "rnsca",
                "vector_layers": [{"id": layer, "fields": {}, "minzoom": zoom_range[0],
                                   "maxzoom": zoom_range[1]}]}
        meta.update(metadata or {})
        writer.finalize(header, meta, pool.map)
    return summary


@contextmanager
def _opened(path: str | Path | BinaryIO) -> Iterator[BinaryIO]:
    if isinstance(path, (str, Path)):
        with open(path, "wb") as f:
            yield f
        return
    yield path


def _extend_bounds(bounds: list, zoom: ZoomTiles) -> None:
    """Widen `bounds` (lon/lat) by the zoom's tiles (the archive's header bounds)."""
    from rnsca.tiles.mercator import world_to_lonlat

    side = 2.0**zoom.zoom
    corners = world_to_lonlat(np.array([[zoom.x.min() / side, (zoom.y.max() + 1) / side],
                                        [(zoom.x.max() + 1) / side, zoom.y.min() / side]]))
    bounds[0] = min(bounds[0], corners[0, 0])
    bounds[1] = min(bounds[1], corners[0, 1])
    bounds[2] = max(bounds[2], corners[1, 0])
    bounds[3] = max(bounds[3], corners[1, 1])


def _made_ahead(zooms: Iterable[ZoomTiles]) -> Iterator[ZoomTiles]:
    """Yield the zooms of `zooms`, the next one made in a thread while this one is written.

    The kernels that make a zoom and the compressor both release the GIL, so zoom
    z + 1 is cut and encoded while zoom z is compressed and written. One zoom is made
    ahead at most (memory holds two). An exception in the maker is raised here; when
    the writer stops early, the maker stops after the zoom it is making.
    """
    handoff: queue.Queue = queue.Queue(maxsize=1)
    stop = threading.Event()
    done = object()

    def make() -> None:
        try:
            for zoom in zooms:
                while not stop.is_set():
                    try:
                        handoff.put((zoom, None), timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            handoff.put((done, None))
        except BaseException as exc:  # handed to the writer's thread, raised there
            handoff.put((done, exc))

    maker = threading.Thread(target=make, name="rnsca-tiles-maker", daemon=True)
    maker.start()
    try:
        while True:
            item, error = handoff.get()
            if item is done:
                if error is not None:
                    raise error
                return
            yield item
    finally:
        stop.set()
        while maker.is_alive():  # let a maker blocked on a full handoff see `stop`
            try:
                handoff.get(timeout=0.1)
            except queue.Empty:
                pass
        maker.join()


def _timed(zooms: Iterable[ZoomTiles], summary: ArchiveSummary) -> Iterator[ZoomTiles]:
    """Yield each zoom, recording its tiles, features and the seconds until it was written.

    The zooms are made one ahead (`_made_ahead`): a zoom's seconds are those the writer
    waited for it and spent writing it, which add up to the whole run.
    """
    import time

    iterator = iter(_made_ahead(zooms))
    while True:
        started = time.perf_counter()
        try:
            zoom = next(iterator)
        except StopIteration:
            return
        summary.add(zoom.zoom, len(zoom), int(zoom.features.sum()), 0,
                    time.perf_counter() - started)
        yield zoom
        summary.zooms[-1]["seconds"] = time.perf_counter() - started


def write_directory(path: str | Path, zooms: Iterable[ZoomTiles], *,
                    compression: Compression | str = Compression.NONE,
                    on_zoom: Callable[[ZoomTiles, int], None] | None = None,
                    compressed: bool = False) -> ArchiveSummary:
    """Write each tile as ``path/z/x/y.mvt`` (uncompressed by default); return the summary.

    With `compressed`, the tiles' data are already stored with `compression`.
    """
    compress = None if compressed else _compressor(Compression(compression))
    root = Path(path)
    summary = ArchiveSummary()
    with ThreadPoolExecutor() as pool:
        for zoom in _timed(zooms, summary):
            stored = _stored(zoom, compress, pool)
            for x in np.unique(zoom.x).tolist():
                (root / str(zoom.zoom) / str(x)).mkdir(parents=True, exist_ok=True)
            total = 0
            for x, y, data in zip(zoom.x.tolist(), zoom.y.tolist(), stored, strict=True):
                (root / str(zoom.zoom) / str(x) / f"{y}.mvt").write_bytes(data)
                total += len(data)
            summary.zooms[-1]["bytes"] = total
            if on_zoom is not None:
                on_zoom(zoom, total)
    return summary
