"""A tile pyramid built in parts that share no tile: what `rnsca.dask.tiles` runs.

The pyramid is cut at a *split zoom* s. `split` cascades the input from zoom 0 to s once
(as `rnsca.tiles.tile_table` does) and cuts zoom s's tiles into `Part` s: runs of them
along the Hilbert curve, of about equal weight (vertices), each with its tiles'
clipped geometry. Each part then builds its tiles' subtrees, zooms s..maxzoom
(`build_part`); the zooms above s are built once, whole (`build_top`), since a tile of
zoom z < s covers the tiles of several parts. No two builds make the same tile, and
`merge` joins their zooms into the zooms `tile_table` yields.

A part's tiles equal the single-process pyramid's, byte for byte: its zoom s is that
pyramid's zoom s, restricted to its tiles, and a cascade clips each geometry against each
child's padded box on its own, and encodes each tile from its own geometries, so leaving
other tiles out changes no tile kept.

Examples
--------
>>> import shapely
>>> from rnsca.tiles import FeatureTable, tile_table
>>> table = FeatureTable.of([shapely.LineString([(-10, -10), (10, 10)])], [{"n": 1}])
>>> zoom, parts = split(table, parts=4, maxzoom=2)
>>> zoom, [(p.x.tolist(), p.y.tolist()) for p in parts]
(1, [([0], [0]), ([0], [1]), ([1], [1]), ([1], [0])])
>>> built = [build_top(table, split_zoom=zoom, maxzoom=2)]
>>> built += [build_part(table, p, maxzoom=2) for p in parts]
>>> merged = list(merge(built))
>>> whole = list(tile_table(table, maxzoom=2))
>>> all(a.data == b.data for a, b in zip(merged, whole, strict=True))
True
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from rnsca.arrays import exclusive_sum
from rnsca.errors import InvalidOptionError
from rnsca.options import Backend, Mode
from rnsca.tiles.archive import Compression, compress_tiles, tile_ids
from rnsca.tiles.encode import Framing, Validation, ZoomTiles, encode_zoom
from rnsca.tiles.features import FeatureTable
from rnsca.tiles.pyramid import Level, cascade, root

__all__ = ["Part", "MAX_SPLIT_ZOOM", "split", "build_top", "build_part", "merge"]

#: The deepest split zoom (the zooms above it are cascaded once, in one process).
MAX_SPLIT_ZOOM = 12


@dataclass(frozen=True, slots=True, eq=False)
class Part:
    """Tiles of the split zoom whose subtrees one task builds, with their geometry.

    Attributes
    ----------
    zoom : int
        The split zoom.
    x, y : ndarray of int64
        Its tiles, in Hilbert (PMTiles tile id) order.
    weight : int
        Vertices of its tiles' clipped geometry.
    levels : tuple of Level
        Points, lines and polygons of its tiles at the split zoom (`rnsca.tiles.pyramid`).
    """

    zoom: int
    x: np.ndarray
    y: np.ndarray
    weight: int
    levels: tuple


def _within(level: Level, x: np.ndarray, y: np.ndarray) -> Level:
    """Return `level` with only tiles ``(x, y)`` of its zoom (their geometries in order)."""
    side = np.int64(2**level.zoom)
    keep = np.isin(level.tile_x * side + level.tile_y, x * side + y)
    if keep.all():
        return level
    counts = np.diff(level.tile_offsets)
    rows = np.flatnonzero(np.repeat(keep, counts))
    return Level(level.zoom, level.ragged.take(rows), level.source[rows],
                 exclusive_sum(counts[keep]), level.tile_x[keep], level.tile_y[keep])


def _tile_weights(levels: list[Level]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the tiles holding something (x, y) and their vertices, all kinds together."""
    side = np.int64(2**levels[0].zoom)
    keys, weights = [], []
    for level in levels:
        if level.ragged.count == 0:  # (zoom 0 has its one tile, even empty)
            continue
        vertices = np.diff(level.ragged.vertex_offsets())
        keys.append(level.tile_x * side + level.tile_y)
        weights.append(np.add.reduceat(vertices, level.tile_offsets[:-1]) + np.diff(
            level.tile_offsets))
    if not keys:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    key, inverse = np.unique(np.concatenate(keys), return_inverse=True)
    weight = np.bincount(inverse, weights=np.concatenate(weights)).astype(np.int64)
    return key // side, key % side, weight


def split(table: FeatureTable, *, parts: int, split_zoom: int | None = None,
          maxzoom: int = 14, extent: int = 4096, buffer: int = 64,
          mode: Mode | str = Mode.EXACT, backend: Backend | str = Backend.NUMBA,
          ) -> tuple[int, list[Part]]:
    """Return the split zoom and up to `parts` parts of its tiles, with their geometry.

    The input is cascaded from zoom 0 (`rnsca.tiles.pyramid.cascade`, as
    `rnsca.tiles.tile_table` does) down to `split_zoom`, or by default to the first zoom
    with at least `parts` tiles holding something (at most `maxzoom` and
    `MAX_SPLIT_ZOOM`). Its tiles are taken along the Hilbert curve and cut into runs of
    about equal weight (vertices), so that a part's tiles lie together.

    Raises
    ------
    InvalidOptionError
        For a split zoom outside ``0..min(maxzoom, MAX_SPLIT_ZOOM)``, or fewer than one
        part.
    """
    deepest = min(maxzoom, MAX_SPLIT_ZOOM)
    if split_zoom is not None and not (isinstance(split_zoom, int)
                                       and 0 <= split_zoom <= deepest):
        raise InvalidOptionError(f"split_zoom must be an int in 0..{deepest} (at most "
                                 f"maxzoom and {MAX_SPLIT_ZOOM}), got {split_zoom!r}")
    if not (isinstance(parts, int) and parts >= 1):
        raise InvalidOptionError(f"parts must be an int >= 1, got {parts!r}")
    mode = Mode(mode)
    pad_units = buffer / extent
    levels = [root(table.points, table.points_source, pad_units),
              root(table.lines, table.lines_source, pad_units),
              root(table.polygons, table.polygons_source, pad_units)]
    zoom = 0
    while True:
        x, y, weight = _tile_weights(levels)
        if zoom == split_zoom or (split_zoom is None and (x.shape[0] >= parts
                                                          or zoom == deepest)):
            break
        levels = [cascade(level, pad_units, mode, extent, backend) for level in levels]
        zoom += 1
    order = np.argsort(tile_ids(zoom, x, y), kind="stable")
    x, y, weight = x[order], y[order], weight[order]
    total = int(weight.sum())
    parts = min(parts, max(1, x.shape[0]))
    # Cut where the running weight passes each k / parts of the total.
    ends = np.cumsum(weight)
    cuts = np.searchsorted(ends, np.arange(1, parts) * total / parts, side="left") + 1
    bounds = np.unique(np.concatenate([[0], np.minimum(cuts, x.shape[0]), [x.shape[0]]]))
    out = []
    for a, b in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True):
        if b > a:
            out.append(Part(zoom, x[a:b], y[a:b], int(weight[a:b].sum()),
                            tuple(_within(level, x[a:b], y[a:b]) for level in levels)))
    return zoom, out


def _options(mode: Mode | str, validate: Validation | str, framing: Framing | str,
             ) -> tuple[Mode, Validation, Framing]:
    return Mode(mode), Validation(validate), Framing(framing)


def build_top(table: FeatureTable, *, split_zoom: int, minzoom: int = 0, maxzoom: int = 14,
              extent: int = 4096, buffer: int = 64, layer: str = "features",
              mode: Mode | str = Mode.EXACT,
              validate: Validation | str = Validation.AT_RISK,
              backend: Backend | str = Backend.NUMBA,
              framing: Framing | str = Framing.DIRECT,
              compression: Compression | str = Compression.NONE) -> list[ZoomTiles]:
    """Return the zooms ``minzoom..min(split_zoom - 1, maxzoom)``, whole (maybe none).

    As `rnsca.tiles.tile_table` yields them; each tile's data stored with `compression`.
    """
    mode, validation, framing = _options(mode, validate, framing)
    pad_units = buffer / extent
    levels = [root(table.points, table.points_source, pad_units),
              root(table.lines, table.lines_source, pad_units),
              root(table.polygons, table.polygons_source, pad_units)]
    out = []
    for zoom in range(min(split_zoom - 1, maxzoom) + 1):
        if zoom > 0:
            levels = [cascade(level, pad_units, mode, extent, backend) for level in levels]
        if zoom >= minzoom:
            out.append(compress_tiles(encode_zoom(levels, table, extent=extent, layer=layer,
                                                  validate=validation, framing=framing),
                                      compression))
    return out


def build_part(table: FeatureTable, part: Part, *, minzoom: int = 0, maxzoom: int = 14,
               extent: int = 4096, buffer: int = 64, layer: str = "features",
               mode: Mode | str = Mode.EXACT,
               validate: Validation | str = Validation.AT_RISK,
               backend: Backend | str = Backend.NUMBA,
               framing: Framing | str = Framing.DIRECT,
               compression: Compression | str = Compression.NONE) -> list[ZoomTiles]:
    """Return the part's tiles of zooms ``max(minzoom, part.zoom)..maxzoom``, by zoom.

    Each zoom holds the tiles below the part's tiles of the split zoom, as
    `rnsca.tiles.tile_table` makes them; each tile's data stored with `compression`.
    `table` gives the features' ids and properties.
    """
    mode, validation, framing = _options(mode, validate, framing)
    pad_units = buffer / extent
    levels = list(part.levels)
    out = []
    for zoom in range(part.zoom, maxzoom + 1):
        if zoom > part.zoom:
            levels = [cascade(level, pad_units, mode, extent, backend) for level in levels]
        if zoom >= minzoom:
            out.append(compress_tiles(encode_zoom(levels, table, extent=extent, layer=layer,
                                                  validate=validation, framing=framing),
                                      compression))
    return out


def merge(built: Iterable[list[ZoomTiles]]) -> Iterator[ZoomTiles]:
    """Yield the zooms of `build_top` and `build_part` results joined, in zoom order.

    Each zoom's tiles are in (x, y) order, as `rnsca.tiles.tile_table` yields them;
    a zoom whose tiles no build holds is left out.
    """
    by_zoom: dict[int, list[ZoomTiles]] = {}
    for zooms in built:
        for tiles in zooms:
            by_zoom.setdefault(tiles.zoom, []).append(tiles)
    for zoom in sorted(by_zoom):
        pieces = by_zoom[zoom]
        x = np.concatenate([p.x for p in pieces])
        y = np.concatenate([p.y for p in pieces])
        data = [d for p in pieces for d in p.data]
        features = np.concatenate([p.features for p in pieces])
        order = np.lexsort((y, x))
        if np.any((np.diff(x[order]) == 0) & (np.diff(y[order]) == 0)):
            raise ValueError(f"zoom {zoom}: two builds hold the same tile (parts of "
                             "different plans?)")
        yield ZoomTiles(zoom, x[order], y[order], [data[k] for k in order.tolist()],
                        features[order])
