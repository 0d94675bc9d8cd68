"""A tile pyramid built in parts that share no tile: what `rnsca.dask.tiles` runs.

The pyramid is cut at a *split zoom* s. Each `Part` owns some tiles of zoom s (a run of
them along the Hilbert curve) and builds their subtrees: zooms s..maxzoom below its
tiles (`build_part`). The zooms above s are built once, whole (`build_top`): a tile of
zoom z < s covers the tiles of several parts, so no part builds it. No two builds write
the same tile, and `merge` joins their zooms into the zooms `rnsca.tiles.tile_table`
yields.

A part's tiles equal the single-process pyramid's, byte for byte: the part takes the
geometries whose box touches one of its padded tiles at zoom s (any other has nothing in
them), cascades them from zoom 0 as `tile_table` does, keeping at each zoom z <= s only
the ancestors of its tiles (`_within`), then cascades its subtrees to maxzoom. A
cascade clips each geometry against each child's padded box on its own, and encodes
each tile from its own geometries, so leaving geometries and tiles out changes no tile
kept. Each part repeats the cascade of zooms 1..s for its geometries: choose s as low
as gives enough parts (`choose_split_zoom`).

Examples
--------
>>> import shapely
>>> from rnsca.tiles import FeatureTable, tile_table
>>> table = FeatureTable.of([shapely.LineString([(-10, -10), (10, 10)])], [{"n": 1}])
>>> parts = plan_parts(table, split_zoom=1, parts=4)
>>> [(p.x.tolist(), p.y.tolist()) for p in parts]
[([0], [0]), ([0], [1]), ([1], [1]), ([1], [0])]
>>> built = [build_top(table, split_zoom=1, maxzoom=2)]
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

from rnsca.arrays import Ragged, exclusive_sum
from rnsca.errors import InvalidOptionError
from rnsca.many_windows import vertex_boxes
from rnsca.options import Backend, Mode
from rnsca.tiles.archive import Compression, compress_tiles, tile_ids
from rnsca.tiles.encode import Framing, Validation, ZoomTiles, encode_zoom
from rnsca.tiles.features import FeatureTable
from rnsca.tiles.pyramid import Level, cascade, root

__all__ = ["Part", "MAX_SPLIT_ZOOM", "choose_split_zoom", "plan_parts", "build_top",
           "build_part", "merge"]

#: The deepest split zoom: parts find their geometries on a 2**s by 2**s grid.
MAX_SPLIT_ZOOM = 10


@dataclass(frozen=True, slots=True, eq=False)
class Part:
    """Tiles of the split zoom whose subtrees one task builds.

    Attributes
    ----------
    zoom : int
        The split zoom.
    x, y : ndarray of int64
        Its tiles, in Hilbert (PMTiles tile id) order.
    weight : int
        Vertices of the geometries touching its tiles (a geometry counted in each).
    """

    zoom: int
    x: np.ndarray
    y: np.ndarray
    weight: int


def _boxes(table: FeatureTable) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Return each kind's geometry boxes (world coordinates) and vertex counts."""
    boxes, sizes = [], []
    for ragged in (table.points, table.lines, table.polygons):
        offsets = ragged.vertex_offsets()
        boxes.append(vertex_boxes(ragged.coords, offsets))
        sizes.append(np.diff(offsets))
    return boxes, sizes


def _tile_ranges(boxes: np.ndarray, zoom: int, pad_units: float) -> np.ndarray:
    """Return the tiles of `zoom` each box may touch, padded: int64 (n, 4) [x0, y0, x1, y1].

    A superset, by one tile each way: it only selects what the cascade then decides.
    """
    side = 2**zoom
    scaled = boxes * side
    ranges = np.empty(boxes.shape, dtype=np.int64)
    ranges[:, :2] = np.floor(scaled[:, :2] - pad_units) - 1
    ranges[:, 2:] = np.floor(scaled[:, 2:] + pad_units) + 1
    return np.clip(ranges, 0, side - 1)


def _painted(ranges: np.ndarray, weights: np.ndarray, side: int) -> np.ndarray:
    """Return the (side, side) grid [y, x] of the weights summed over each tile range."""
    grid = np.zeros((side + 1, side + 1), dtype=np.int64)
    x0, y0, x1, y1 = ranges.T
    np.add.at(grid, (y0, x0), weights)
    np.add.at(grid, (y0, x1 + 1), -weights)
    np.add.at(grid, (y1 + 1, x0), -weights)
    np.add.at(grid, (y1 + 1, x1 + 1), weights)
    return grid.cumsum(axis=0).cumsum(axis=1)[:side, :side]


def _weights(table: FeatureTable, zoom: int, pad_units: float) -> np.ndarray:
    """Return the vertices touching each tile of `zoom` (grid [y, x]), roughly."""
    side = 2**zoom
    grid = np.zeros((side, side), dtype=np.int64)
    for boxes, sizes in zip(*_boxes(table), strict=True):
        real = ~np.isnan(boxes[:, 0])
        if real.any():
            grid += _painted(_tile_ranges(boxes[real], zoom, pad_units), sizes[real] + 1,
                             side)
    return grid


def choose_split_zoom(table: FeatureTable, parts: int, maxzoom: int, *, extent: int = 4096,
                      buffer: int = 64) -> int:
    """Return the lowest zoom (at most `maxzoom` and `MAX_SPLIT_ZOOM`) with `parts` tiles.

    Tiles touched by a geometry's box are counted; a zoom with fewer (a small area) is
    passed over for the next, up to the limits.
    """
    for zoom in range(min(maxzoom, MAX_SPLIT_ZOOM) + 1):
        if np.count_nonzero(_weights(table, zoom, buffer / extent)) >= parts:
            return zoom
    return min(maxzoom, MAX_SPLIT_ZOOM)


def plan_parts(table: FeatureTable, *, split_zoom: int, parts: int, extent: int = 4096,
               buffer: int = 64) -> list[Part]:
    """Return up to `parts` parts owning the tiles of `split_zoom` that geometries touch.

    The tiles are taken along the Hilbert curve and cut into runs of about equal weight
    (vertices touching them), so that a part's tiles lie together.

    Raises
    ------
    InvalidOptionError
        For a split zoom outside ``0..MAX_SPLIT_ZOOM`` or fewer than one part.
    """
    if not (isinstance(split_zoom, int) and 0 <= split_zoom <= MAX_SPLIT_ZOOM):
        raise InvalidOptionError(f"split_zoom must be an int in 0..{MAX_SPLIT_ZOOM}, got "
                                 f"{split_zoom!r}")
    if not (isinstance(parts, int) and parts >= 1):
        raise InvalidOptionError(f"parts must be an int >= 1, got {parts!r}")
    grid = _weights(table, split_zoom, buffer / extent)
    y, x = np.nonzero(grid)
    order = np.argsort(tile_ids(split_zoom, x, y), kind="stable")
    x, y = x[order].astype(np.int64), y[order].astype(np.int64)
    weight = grid[y, x]
    total = int(weight.sum())
    # Cut where the running weight passes each k / parts of the total.
    ends = np.cumsum(weight)
    cuts = np.searchsorted(ends, np.arange(1, parts) * total / parts, side="left") + 1
    bounds = np.unique(np.concatenate([[0], np.minimum(cuts, x.shape[0]), [x.shape[0]]]))
    return [Part(split_zoom, x[a:b], y[a:b], int(weight[a:b].sum()))
            for a, b in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True)
            if b > a]


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


def _touching(ragged: Ragged, source: np.ndarray, part: Part, pad_units: float,
              ) -> tuple[Ragged, np.ndarray]:
    """Return the geometries whose box may touch one of the part's padded tiles."""
    side = 2**part.zoom
    boxes = vertex_boxes(ragged.coords, ragged.vertex_offsets())
    real = np.flatnonzero(~np.isnan(boxes[:, 0]))
    owned = np.zeros((side + 1, side + 1), dtype=np.int64)
    owned[part.y + 1, part.x + 1] = 1
    owned = owned.cumsum(axis=0).cumsum(axis=1)  # owned tiles in [0, y) x [0, x)
    x0, y0, x1, y1 = _tile_ranges(boxes[real], part.zoom, pad_units).T
    inside = (owned[y1 + 1, x1 + 1] - owned[y0, x1 + 1] - owned[y1 + 1, x0]
              + owned[y0, x0])
    rows = real[inside > 0]
    if rows.shape[0] == ragged.count:
        return ragged, source
    return ragged.take(rows), source[rows]


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
    levels = [root(table.points, table.points_source), root(table.lines, table.lines_source),
              root(table.polygons, table.polygons_source)]
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
    """
    mode, validation, framing = _options(mode, validate, framing)
    pad_units = buffer / extent
    levels = [root(*_touching(ragged, source, part, pad_units))
              for ragged, source in ((table.points, table.points_source),
                                     (table.lines, table.lines_source),
                                     (table.polygons, table.polygons_source))]
    out = []
    for zoom in range(maxzoom + 1):
        if zoom > 0:
            levels = [cascade(level, pad_units, mode, extent, backend) for level in levels]
        if zoom <= part.zoom:
            shift = part.zoom - zoom
            x, y = np.unique(np.column_stack([part.x >> shift, part.y >> shift]),
                             axis=0).T
            levels = [_within(level, x, y) for level in levels]
        if zoom >= max(minzoom, part.zoom):
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
