"""One zoom's clipped geometry as MVT tiles: quantised, checked, encoded, framed.

`encode_zoom` takes the three `Level` s of a zoom (points, lines, polygons) and returns
each tile's bytes (a ``Tile`` with one layer):

1. Quantise: world coordinates to integer tile units, ``round((X * 2**z - x) * extent)``
   (y down, as MVT counts), all vertices at once (polygons: with step 2).
2. Valid polygons (`Validation`): rounding can make a polygon invalid (a spike folded
   onto itself, rings that touch along an edge). Polygons are rounded and cleaned in one
   kernel pass first (`clean_polygons`: repeated and collinear positions and spikes
   removed, rings left with fewer than three positions dropped with a shell's holes),
   which fixes most small polygons of the low zooms; of the rest, those a kernel cannot
   prove valid and GEOS finds invalid are repaired by GEOS (``make_valid``, then
   snap-rounding by ``shapely.set_precision`` where that is not enough).
3. Features in tile order, then source order (`rnsca.kernels.mvt.Features`); each
   feature's tags are its properties' keys and values, numbered per tile (each key and
   value once per layer, as the spec asks), all tiles at once with one sort.
4. The features' messages, geometry commands included, are written by the kernels
   (`rnsca.kernels.mvt.feature_sizes`, `write_features`): degenerate parts are dropped
   and the winding the spec asks for is written there.
5. Each tile's message is framed (`Framing`): by a kernel around the layer header that
   protobuf serializes (default), or tile by tile by the protobuf library (the fields
   merged into a ``Tile.Layer``, the ``Tile`` serialized); the bytes are the same.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from rnsca.arrays import GeometryKind, Ragged, exclusive_sum, in_threads
from rnsca.kernels import mvt as K
from rnsca.kernels import tiles as KT
from rnsca.options import _ChoiceEnum
from rnsca.tiles.features import FeatureTable
from rnsca.tiles.pyramid import Level
from rnsca.tiles.vector_tile import Layer, Tile

__all__ = ["Framing", "Validation", "ZoomTiles", "clean_polygons", "encode_zoom", "quantise"]

_KIND_CODE = {GeometryKind.MULTIPOINT: K.POINT, GeometryKind.MULTILINESTRING: K.LINESTRING,
              GeometryKind.MULTIPOLYGON: K.POLYGON}


@dataclass(frozen=True, slots=True, eq=False)
class ZoomTiles:
    """The tiles of one zoom that hold a feature.

    Attributes
    ----------
    zoom : int
    x, y : ndarray of int64
        The tiles, in (x, y) order.
    data : list of bytes
        Each tile's ``Tile`` message (uncompressed).
    features : ndarray of int64
        How many features each tile holds.
    """

    zoom: int
    x: np.ndarray
    y: np.ndarray
    data: list
    features: np.ndarray

    def __len__(self) -> int:
        return self.x.shape[0]


def quantise(level: Level, extent: int) -> np.ndarray:
    """Return the level's vertices in integer tile units of their tile, int64 (v, 2)."""
    ragged = level.ragged
    q = np.empty((ragged.coords.shape[0], 2), dtype=np.int64)
    KT.quantise(ragged.coords, ragged.vertex_offsets(), level.tile_offsets, level.tile_x,
                level.tile_y, float(2**level.zoom), float(extent), q)
    return q


class Validation(_ChoiceEnum):
    """Which polygons are checked (GEOS ``is_valid``) once rounded, and snapped if invalid."""

    AT_RISK = "at-risk"
    """Those a kernel cannot prove valid (`rnsca.kernels.tiles.polygons_at_risk`: exact
    integer tests of the rounded rings: no edges meeting, holes inside their shells);
    the same result as ALL, for less."""
    ALL = "all"
    """Every polygon."""
    NONE = "none"
    """None: rounding may leave invalid polygons (degenerate rings are still dropped)."""


def _shapes(level: Level, q: np.ndarray) -> K.Shapes:
    offsets = list(level.ragged.offsets) + [np.empty(0, dtype=np.int64)] * 3
    return K.Shapes(q, *offsets[:3])


def clean_polygons(coords: np.ndarray, offsets: tuple, origin: np.ndarray | None = None,
                   scale: float = 1.0, extent: float = 1.0) -> tuple[np.ndarray, tuple]:
    """Return polygons rounded to tile units and cleaned: ``(positions int64 (v, 2), offsets)``.

    `coords` float64 (v, 2); geometry ``g``'s position ``X`` becomes ``round((X * scale -
    origin[g]) * extent)``, as `quantise` rounds it (default: integer positions as they
    are). Per ring (`rnsca.kernels.tiles.clean_rings`): repeated positions, collinear
    vertices and spikes (edges going back along themselves) removed; a ring left with
    fewer than three positions is dropped, and a shell's holes with it. `offsets` are a
    MULTIPOLYGON's (rings, polygons, geometries, innermost first); the geometries are the
    same (some may be left empty).
    """
    ring_offsets, polygon_rings, geometry_polygons = offsets
    n_rings = ring_offsets.shape[0] - 1
    if origin is None:
        origin = np.zeros((geometry_polygons.shape[0] - 1, 2), dtype=np.int64)
    work = np.empty(coords.shape, dtype=np.int64)
    begin = np.empty(n_rings, dtype=np.int64)
    end = np.empty(n_rings, dtype=np.int64)
    KT.clean_rings(np.ascontiguousarray(coords, dtype=np.float64), ring_offsets, polygon_rings,
                   geometry_polygons, np.ascontiguousarray(origin, dtype=np.int64),
                   float(scale), float(extent), work, begin, end)
    kept = end > begin
    starts = exclusive_sum(np.where(kept, end - begin + 1, 0))
    out = np.empty((int(starts[-1]), 2), dtype=np.int64)
    KT.write_clean_rings(work, begin, end, starts[:-1], out)
    n_polygons = polygon_rings.shape[0] - 1
    ring_polygon = np.repeat(np.arange(n_polygons, dtype=np.int64), np.diff(polygon_rings))
    rings_per_polygon = np.bincount(ring_polygon[kept], minlength=n_polygons)
    polygon_kept = rings_per_polygon > 0
    n_geometries = geometry_polygons.shape[0] - 1
    polygon_geometry = np.repeat(np.arange(n_geometries, dtype=np.int64),
                                 np.diff(geometry_polygons))
    polygons_per_geometry = np.bincount(polygon_geometry[polygon_kept],
                                        minlength=n_geometries)
    return out, (np.append(starts[:-1][kept], starts[-1]),
                 exclusive_sum(rings_per_polygon[polygon_kept]),
                 exclusive_sum(polygons_per_geometry))


def _valid_polygons(level: Level, extent: int, validation: Validation,
                    ) -> tuple[K.Shapes, np.ndarray, K.Shapes]:
    """Return the rounded polygons cleaned, those still invalid, and their repairs.

    The rounded rings are cleaned first (`clean_polygons`: most of what rounding breaks
    in small polygons is a ring collapsed, a spike or a vertex on a line). The repairs
    are `Shapes` in tile units, one geometry per invalid polygon (in the order of
    `bad`), written instead of the cleaned ones (`rnsca.kernels.mvt.REPAIRED`).
    """
    ragged = level.ragged
    tile = level.geometry_tile
    q, offsets = clean_polygons(ragged.coords, ragged.offsets,
                                np.column_stack([level.tile_x[tile], level.tile_y[tile]]),
                                float(2**level.zoom), float(extent))
    shapes = K.Shapes(q, *offsets)
    nothing = np.empty(0, dtype=np.int64)
    if ragged.count == 0 or validation is Validation.NONE:
        return shapes, nothing, _no_polygons()
    rounded = Ragged(ragged.kind, q.astype(np.float64), offsets)
    if validation is Validation.ALL:
        candidates = np.arange(ragged.count, dtype=np.int64)
    else:
        at_risk = np.empty(ragged.count, dtype=np.bool_)
        KT.polygons_at_risk(q, *offsets, at_risk)
        candidates = np.flatnonzero(at_risk)
    if candidates.shape[0] == 0:
        return shapes, nothing, _no_polygons()
    bad = candidates[~in_threads(shapely.is_valid, rounded.take(candidates).to_shapely())]
    if bad.shape[0] == 0:
        return shapes, nothing, _no_polygons()
    # First the cheap repair: GEOS's make_valid (structure) of the rounded polygon, its
    # new vertices (where edges crossed) rounded; what that leaves invalid is snapped
    # from its unrounded coordinates in tile units onto the integer grid by GEOS's
    # snap-rounding (set_precision: valid output whose vertices are on the grid).
    # Measured on 3,650 invalid small stars: 0.6 s repaired, 0.95 s snapped, and 24
    # left to snap after the repair.
    snapped = shapely.set_precision(
        in_threads(shapely.make_valid, rounded.take(bad).to_shapely(), method="structure",
                  keep_collapsed=False), 1.0, mode="pointwise")
    still = np.flatnonzero(~in_threads(shapely.is_valid, snapped))
    if still.shape[0]:
        scale = float(2**level.zoom)
        taken = ragged.take(bad[still])
        tile = np.repeat(level.geometry_tile[bad[still]], np.diff(taken.vertex_offsets()))
        units = np.empty_like(taken.coords)
        units[:, 0] = (taken.coords[:, 0] * scale - level.tile_x[tile]) * extent
        units[:, 1] = (taken.coords[:, 1] * scale - level.tile_y[tile]) * extent
        snapped[still] = in_threads(shapely.set_precision,
                                   Ragged(ragged.kind, units, taken.offsets).to_shapely(),
                                   grid_size=1.0)
    # Only the polygonal parts (snapping may collapse a sliver to a line).
    parts, part_of = shapely.get_parts(snapped, return_index=True)
    polygonal = shapely.get_type_id(parts) == shapely.GeometryType.POLYGON
    fixed = np.array([shapely.MultiPolygon()] * bad.shape[0], dtype=object)
    if polygonal.any():
        shapely.multipolygons(parts[polygonal], indices=part_of[polygonal], out=fixed)
    if shapely.get_num_coordinates(fixed).sum():
        _, coords, offsets = shapely.to_ragged_array(fixed)
        repaired = K.Shapes(coords.astype(np.int64),
                            *(np.asarray(o, dtype=np.int64) for o in offsets))
    else:
        repaired = _no_polygons(bad.shape[0])
    return shapes, bad, repaired


def _no_polygons(count: int = 0) -> K.Shapes:
    """Return polygon `Shapes` of `count` empty geometries."""
    none = np.zeros(1, dtype=np.int64)
    return K.Shapes(np.empty((0, 2), dtype=np.int64), none, none,
                    np.zeros(count + 1, dtype=np.int64))


class Framing(_ChoiceEnum):
    """How a tile's message is put together around the fields the kernels wrote."""

    DIRECT = "direct"
    """By a kernel, every tile at once: the Tile's tag and length, then the layer's name
    (serialized by protobuf once per zoom), features, keys, values, extent and version
    (the same). The same bytes as PROTOBUF (tested), without two calls per tile."""
    PROTOBUF = "protobuf"
    """By the protobuf library, tile by tile: the fields merged into a ``Tile.Layer``
    (parsed), its header set, the ``Tile`` serialized."""


def encode_zoom(levels: list[Level], table: FeatureTable, *, extent: int, layer: str,
                validate: Validation | str = Validation.AT_RISK,
                framing: Framing | str = Framing.DIRECT) -> ZoomTiles:
    """Return the MVT tiles of one zoom from its points, lines and polygons `levels`."""
    framing = Framing(framing)
    validation = Validation(validate)
    zoom = levels[0].zoom
    shapes, kinds, indices, sources, keys = [], [], [], [], []
    side = np.int64(2**zoom)
    repaired = _no_polygons()
    for level in levels:
        tile = level.geometry_tile
        key = level.tile_x[tile] * side + level.tile_y[tile]
        count = level.ragged.count
        index = np.arange(count, dtype=np.int64)
        if level.ragged.kind is GeometryKind.MULTIPOLYGON:
            polygon_shapes, bad, repaired = _valid_polygons(level, extent, validation)
            if bad.shape[0]:
                # The repaired polygons are written from their own shapes instead.
                kinds.append(np.full(bad.shape[0], K.REPAIRED, dtype=np.int8))
                indices.append(np.arange(bad.shape[0], dtype=np.int64))
                sources.append(level.source[bad])
                keys.append(key[bad])
                good = np.ones(count, dtype=bool)
                good[bad] = False
                index = index[good]
            shapes.append(polygon_shapes)
        else:
            shapes.append(_shapes(level, quantise(level, extent)))
        kinds.append(np.full(index.shape[0], _KIND_CODE[level.ragged.kind], dtype=np.int8))
        indices.append(index)
        sources.append(level.source[index])
        keys.append(key[index])
    kind = np.concatenate(kinds)
    index = np.concatenate(indices)
    source = np.concatenate(sources)
    key = np.concatenate(keys)
    order = np.lexsort((kind, source, key))
    kind, index, source, key = kind[order], index[order], source[order], key[order]
    tile_keys, tile_first = np.unique(key, return_index=True)
    feature_tile = np.repeat(np.arange(tile_keys.shape[0], dtype=np.int64),
                             np.diff(np.append(tile_first, key.shape[0])))
    tags = table.tags
    # Each feature's (key, value) pairs, numbered per tile.
    counts = tags.tag_offsets[source + 1] - tags.tag_offsets[source]
    tag_offsets = exclusive_sum(counts)
    rows = np.arange(int(tag_offsets[-1]), dtype=np.int64) + np.repeat(
        tags.tag_offsets[source] - tag_offsets[:-1], counts)
    tag_tile = np.repeat(feature_tile, counts)
    local_key, tile_keys_used, key_starts = _number_per_tile(
        tag_tile, tags.tag_key[rows], len(tags.keys), tile_keys.shape[0])
    local_value, tile_values_used, value_starts = _number_per_tile(
        tag_tile, tags.tag_value[rows], tags.value_field_offsets.shape[0] - 1,
        tile_keys.shape[0])
    pairs = np.empty(2 * local_key.shape[0], dtype=np.uint32)
    pairs[0::2] = local_key
    pairs[1::2] = local_value
    features = K.Features(kind, index, table.ids[source], 2 * tag_offsets, pairs)
    sizes = np.empty(kind.shape[0], dtype=np.int64)
    geometry_bytes = np.empty(kind.shape[0], dtype=np.int64)
    K.feature_sizes(features, *shapes, repaired, sizes, geometry_bytes)
    starts = exclusive_sum(sizes)
    out = np.empty(int(starts[-1]), dtype=np.uint8)
    K.write_features(features, *shapes, repaired, starts, sizes, geometry_bytes, out)
    byte_start = starts[np.append(tile_first, key.shape[0])]
    key_blob, key_offsets = _gather_fields(tags.key_fields, tags.key_field_offsets,
                                           tile_keys_used, key_starts)
    value_blob, value_offsets = _gather_fields(tags.value_fields, tags.value_field_offsets,
                                               tile_values_used, value_starts)
    written = np.add.reduceat(sizes > 0, tile_first) if key.shape[0] else np.zeros(0, int)
    holding = np.flatnonzero(written > 0)
    x = (tile_keys // side)[holding]
    y = (tile_keys % side)[holding]
    # Each tile's ranges of features, keys and values (tiles left with no feature out).
    ranges = np.ascontiguousarray(np.column_stack([
        byte_start[holding], byte_start[holding + 1], key_offsets[holding],
        key_offsets[holding + 1], value_offsets[holding], value_offsets[holding + 1]]))
    if framing is Framing.PROTOBUF:
        data = _frame_with_protobuf(out, key_blob, value_blob, ranges, layer, extent)
    else:
        # The layer's other fields, serialized by protobuf: before the features (name, 1)
        # and after the values (extent, 5; version, 15), in field order as it writes them.
        head = np.frombuffer(Layer(name=layer).SerializePartialToString(), dtype=np.uint8)
        tail = np.frombuffer(Layer(version=2, extent=extent).SerializePartialToString(),
                             dtype=np.uint8)
        tile_bytes = np.empty(holding.shape[0], dtype=np.int64)
        K.tile_sizes(head, tail, ranges, tile_bytes)
        tile_start = exclusive_sum(tile_bytes)
        buffer = np.empty(int(tile_start[-1]), dtype=np.uint8)
        K.write_tiles(head, tail, out, key_blob, value_blob, ranges, tile_start, buffer)
        blob = buffer.tobytes()
        bounds = tile_start.tolist()
        data = [blob[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=False)]
    return ZoomTiles(zoom, x, y, data, written[holding])


def _frame_with_protobuf(features: np.ndarray, keys: np.ndarray, values: np.ndarray,
                         ranges: np.ndarray, layer: str, extent: int) -> list[bytes]:
    """Return each tile's bytes framed by protobuf: fields merged into a Layer, serialized."""
    payload, keys_bytes, values_bytes = features.tobytes(), keys.tobytes(), values.tobytes()
    data = []
    for f0, f1, k0, k1, v0, v1 in ranges.tolist():
        tile = Tile()
        message = tile.layers.add()
        message.MergeFromString(payload[f0:f1] + keys_bytes[k0:k1] + values_bytes[v0:v1])
        message.name = layer
        message.version = 2
        message.extent = extent
        data.append(tile.SerializeToString())
    return data


def _number_per_tile(tag_tile: np.ndarray, ids: np.ndarray, n_ids: int, n_tiles: int,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return each tag's id numbered within its tile, the ids each tile uses, and starts.

    Tile ``t`` uses ids ``used[starts[t]:starts[t + 1]]`` (increasing); a tag whose id
    is ``used[starts[t] + k]`` gets ``k``.
    """
    combined = tag_tile * np.int64(max(n_ids, 1)) + ids
    unique, inverse = np.unique(combined, return_inverse=True)
    unique_tile = unique // max(n_ids, 1)
    starts = np.searchsorted(unique_tile, np.arange(n_tiles + 1))
    local = inverse - starts[tag_tile]
    return local.astype(np.uint32), (unique % max(n_ids, 1)).astype(np.int64), starts


def _gather_fields(blob: np.ndarray, offsets: np.ndarray, used: np.ndarray,
                   starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the fields `used` (by id) back to back, and each tile's byte offsets."""
    lengths = offsets[used + 1] - offsets[used]
    out_offsets = exclusive_sum(lengths)
    rows = np.arange(int(out_offsets[-1]), dtype=np.int64) + np.repeat(
        offsets[used] - out_offsets[:-1], lengths)
    return blob[rows], out_offsets[starts]
