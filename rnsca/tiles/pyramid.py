"""The tile pyramid: each zoom's clipped geometry, cascaded from its parent zoom's.

A `Level` holds one kind's geometry (MULTIPOINT, MULTILINESTRING or MULTIPOLYGON, world
coordinates) at one zoom, grouped by tile: the tiles in quadkey order, the geometries of
a tile in source order. `cascade` makes zoom z + 1 from zoom z in one pass: each clipped
geometry is paired with those of its tile's four children whose padded box its
bounding box touches (`rnsca.kernels.tiles.cascade_counts`, by arithmetic on the tile
grid), the pairs' geometries are gathered (`Ragged.take`) and clipped in one call, each
against its child's padded box (`rnsca.clip_ragged` with one window per pair; a
geometry whose box lies inside its child's padded box is copied instead). A child
sees only its parent's clipped geometry, so the work of a zoom follows its output; and
as a child's padded box lies inside its parent's, cascading gives the tiles a direct
clip of the input gives (to rounding). A polygon covering a whole tile comes out as the
tile's padded square, and its children are cut from those four corners, never from the
input again.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnsca.arrays import GeometryKind, Ragged, exclusive_sum
from rnsca.kernels import tiles as K
from rnsca.many_windows import vertex_boxes
from rnsca.options import Backend, Mode
from rnsca.ragged import clip_ragged, resolve_geometry_options
from rnsca.window import WindowTable

__all__ = ["Level", "root", "cascade", "clip_polygon_pairs", "tile_windows", "wrapped"]


@dataclass(frozen=True, slots=True, eq=False)
class Level:
    """One kind's geometry clipped to the tiles of one zoom.

    Attributes
    ----------
    zoom : int
    ragged : Ragged
        MULTI kind, world coordinates; the geometries of tile ``t`` are
        ``tile_offsets[t]:tile_offsets[t + 1]``, in source order.
    source : ndarray of int64
        The feature of each geometry.
    tile_offsets : ndarray of int64, shape (t + 1,)
    tile_x, tile_y : ndarray of int64, shape (t,)
        The tiles that hold something, in quadkey order.
    boxes : ndarray of float64, shape (n, 4), or None
        Each geometry's bounding box, if known (the cascade keeps them: a child reads
        its parent's instead of every vertex again).
    """

    zoom: int
    ragged: Ragged
    source: np.ndarray
    tile_offsets: np.ndarray
    tile_x: np.ndarray
    tile_y: np.ndarray
    boxes: np.ndarray | None = None

    @property
    def geometry_tile(self) -> np.ndarray:
        """Return the tile (row of `tile_x`) of each geometry."""
        return np.repeat(np.arange(self.tile_x.shape[0], dtype=np.int64),
                         np.diff(self.tile_offsets))


def tile_windows(zoom: int, x: np.ndarray, y: np.ndarray, pad_units: float) -> np.ndarray:
    """Return the padded boxes (t, 4) of tiles ``(zoom, x, y)`` in world coordinates.

    `pad_units` is the buffer as a fraction of a tile's side (``buffer / extent``).

    Examples
    --------
    >>> tile_windows(1, np.array([1]), np.array([0]), 0.25).tolist()
    [[0.375, -0.125, 1.125, 0.625]]
    """
    cell = 2.0 ** -zoom
    pad = pad_units * cell
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    return np.column_stack([x * cell - pad, y * cell - pad, (x + 1) * cell + pad,
                            (y + 1) * cell + pad])


def wrapped(ragged: Ragged, source: np.ndarray, pad_units: float,
            ) -> tuple[Ragged, np.ndarray]:
    """Return the geometries with their parts near the antimeridian copied across it.

    The map is a cylinder: the buffer of a tile at the world's west edge (x = 0) holds
    what lies just east of the east edge (x = 1), and the other way round, as map
    clients draw the tiles of a wrapping map side by side. What lies within `pad_units`
    (the buffer at zoom 0, ``buffer / extent``) of either edge is clipped to that band
    and moved by a whole turn (x -= 1 for the east band, x += 1 for the west one) as
    another geometry of the same feature, after its own; the zoom-0 tile's padded box
    and its children's (smaller pads) take from those copies what they need. Points
    likewise.
    """
    if pad_units <= 0.0 or ragged.count == 0:
        return ragged, source
    boxes = vertex_boxes(ragged.coords, ragged.vertex_offsets())
    east = np.flatnonzero(boxes[:, 2] >= 1.0 - pad_units)
    west = np.flatnonzero(boxes[:, 0] <= pad_units)
    if east.shape[0] == 0 and west.shape[0] == 0:
        return ragged, source
    # y is not wrapped: the bands reach past the world square's top and bottom.
    bands = np.array([[1.0 - pad_units, -1.0, 1.0, 2.0], [0.0, -1.0, pad_units, 2.0]])
    rows = np.concatenate([east, west])
    band = np.repeat(np.array([0, 1]), [east.shape[0], west.shape[0]])
    taken = ragged.take(rows)
    cut = clip_ragged(ragged.kind, taken.coords, taken.offsets, bands[band],
                      mode=Mode.EXACT)
    copies = Ragged(ragged.kind, cut.coords.copy(), cut.offsets)
    turn = np.where(band[cut.source] == 0, -1.0, 1.0)
    copies.coords[:, 0] += np.repeat(turn, np.diff(copies.vertex_offsets()))
    merged = ragged.concat(copies)
    merged_source = np.concatenate([source, source[rows[cut.source]]])
    order = np.argsort(merged_source, kind="stable")
    return merged.take(order), merged_source[order]


def root(ragged: Ragged, source: np.ndarray, pad_units: float = 0.0) -> Level:
    """Return zoom 0: every geometry (in the world square) in tile (0, 0).

    With `pad_units` (``buffer / extent``), the parts near the antimeridian are copied
    across it as well (`wrapped`).
    """
    ragged, source = wrapped(ragged, source, pad_units)
    one = np.zeros(1, dtype=np.int64)
    return Level(0, ragged, source, np.array([0, ragged.count], dtype=np.int64), one, one)


def cascade(level: Level, pad_units: float, mode: Mode, extent: int,
            backend: Backend | str = Backend.NUMBA) -> Level:
    """Return zoom ``level.zoom + 1`` clipped from `level` (see the module docstring).

    `pad_units` is ``buffer / extent``. In approx mode lines are clipped with a
    tolerance of one tile unit (``cell / extent``): a cut lands within one unit of the
    padded edge, inside the buffer, so the tile's visible square is unchanged; points
    and polygons are clipped exactly in either mode.
    """
    zoom = level.zoom + 1
    cell = 2.0 ** -zoom
    ragged = level.ragged
    n_tiles = level.tile_x.shape[0]
    boxes = level.boxes if level.boxes is not None else vertex_boxes(
        ragged.coords, ragged.vertex_offsets())
    counts = np.zeros((n_tiles, 4), dtype=np.int64)
    K.cascade_counts(boxes, level.tile_offsets, level.tile_x, level.tile_y, cell,
                     pad_units * cell, counts)
    per_child = counts.ravel()  # parents in quadkey order, then quadrants: children's
    child_offsets = exclusive_sum(per_child)
    cursor = np.ascontiguousarray(child_offsets[:-1].reshape(n_tiles, 4))
    pairs = np.empty(int(child_offsets[-1]), dtype=np.int64)
    K.cascade_write(boxes, level.tile_offsets, level.tile_x, level.tile_y, cell,
                    pad_units * cell, cursor, pairs)
    children = np.flatnonzero(per_child)
    child_x = 2 * level.tile_x[children // 4] + (children % 4 & 1)
    child_y = 2 * level.tile_y[children // 4] + (children % 4 >> 1)
    pair_child = np.repeat(np.arange(children.shape[0], dtype=np.int64), per_child[children])
    windows = tile_windows(zoom, child_x, child_y, pad_units)
    # A geometry whose box lies inside its child's padded box is its own clip: it is
    # copied, not clipped (most of them, once tiles are larger than the geometries).
    box = boxes[pairs]
    window = windows[pair_child]
    inside = ((box[:, 0] >= window[:, 0]) & (box[:, 2] <= window[:, 2])
              & (box[:, 1] >= window[:, 1]) & (box[:, 3] <= window[:, 3]))
    crossing = np.flatnonzero(~inside)
    if ragged.kind.dimension == 2:
        clipped, source = clip_polygon_pairs(ragged, pairs[crossing], window[crossing],
                                              backend)
    else:
        taken = ragged.take(pairs[crossing])
        approx = mode is Mode.APPROX and ragged.kind.dimension == 1
        result = clip_ragged(ragged.kind, taken.coords, taken.offsets, window[crossing],
                             backend=backend, mode=Mode.APPROX if approx else Mode.EXACT,
                             tolerance=cell / extent if approx else None)
        clipped, source = Ragged(ragged.kind, result.coords, result.offsets), result.source
    kept_pairs = crossing[source]
    out_boxes = vertex_boxes(clipped.coords, clipped.vertex_offsets())
    if crossing.shape[0] < pairs.shape[0]:
        whole = np.flatnonzero(inside)
        # Back in pair order (children in quadkey order, sources in order in each): each
        # pair's geometry is its own (copied) or its clip's, if anything is left.
        geometry = np.empty(pairs.shape[0], dtype=np.int64)
        geometry[whole] = pairs[whole]
        geometry[kept_pairs] = ragged.count + np.arange(clipped.count, dtype=np.int64)
        present = inside.copy()
        present[kept_pairs] = True
        clipped = ragged.concat_take(clipped, geometry[present])
        out_boxes = np.concatenate([boxes, out_boxes])[geometry[present]]
        kept_pairs = np.flatnonzero(present)
    out_child = pair_child[kept_pairs]
    per_tile = np.bincount(out_child, minlength=children.shape[0])
    kept = per_tile > 0
    return Level(zoom, clipped, level.source[pairs[kept_pairs]],
                 exclusive_sum(per_tile[kept]), child_x[kept], child_y[kept], out_boxes)


def clip_polygon_pairs(polygons: Ragged, geometry: np.ndarray, windows: np.ndarray,
                       backend: Backend | str = Backend.NUMBA) -> tuple[Ragged, np.ndarray]:
    """Return the pairs' polygons clipped (exact) and the pair of each non-empty output.

    What ``clip_ragged`` gives for ``polygons.take(geometry)`` against one window each,
    by the backend's pair operation (`ClipBackend.clip_polygon_pairs`: the Numba backend
    clips the simple pairs from the parent's arrays, with no gather).
    """
    if geometry.shape[0] == 0:  # nothing crosses (lines only: no polygon kernel to load)
        return polygons.take(geometry), np.empty(0, dtype=np.int64)
    table = WindowTable(windows, np.arange(geometry.shape[0], dtype=np.int64))
    options, _, engine = resolve_geometry_options(table, 2, mode=Mode.EXACT, backend=backend,
                                                  size=polygons.coords.shape[0])
    pieces = engine.clip_polygon_pairs(polygons, geometry, windows, options)
    rings, polygon_rings, pair_polygons = pieces.offsets
    source = np.flatnonzero(np.diff(pair_polygons) > 0)
    kept = np.append(pair_polygons[source], pair_polygons[-1])
    coords = pieces.xy if pieces.z.shape[0] == 0 else np.column_stack([pieces.xy, pieces.z])
    return Ragged(GeometryKind.MULTIPOLYGON, coords, (rings, polygon_rings, kept)), source
