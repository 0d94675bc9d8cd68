"""Vector tiles: a WebMercatorQuad (XYZ) tile pyramid in one clipping pass per zoom.

`tile_features` clips features to every tile of zooms ``minzoom..maxzoom`` and yields
each zoom's tiles as Mapbox Vector Tiles (specification 2.1): coordinates quantised to
``extent`` units per tile side, ``buffer`` units around each tile, polygons valid after
quantisation and wound as the specification asks, degenerate parts dropped, properties
and ids kept. Zoom z + 1 is cut from zoom z's clipped geometry (`rnsca.tiles.pyramid`),
so each zoom costs what it outputs. `write_pmtiles` and `write_directory` store them.

Examples
--------
>>> import shapely
>>> line = shapely.LineString([(-10, -10), (10, 10)])
>>> zooms = list(tile_features([line], [{"name": "a"}], minzoom=0, maxzoom=1))
>>> [(z.zoom, sorted(zip(z.x.tolist(), z.y.tolist()))) for z in zooms]
[(0, [(0, 0)]), (1, [(0, 0), (0, 1), (1, 0), (1, 1)])]
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from rnsca.arrays import Ragged
from rnsca.errors import InvalidOptionError, LimitExceededError
from rnsca.options import Backend, Mode
from rnsca.ragged import clip_ragged
from rnsca.tiles.archive import (
    ArchiveSummary,
    Compression,
    tile_ids,
    write_directory,
    write_pmtiles,
)
from rnsca.tiles.encode import Framing, Validation, ZoomTiles, encode_zoom
from rnsca.tiles.features import FeatureTable
from rnsca.tiles.mercator import Crs
from rnsca.tiles.pyramid import Level, cascade, root, tile_windows, wrapped
from rnsca.tiles.segment_tiles import EncodedTiles, encode_segment_tiles

__all__ = ["ArchiveSummary", "Compression", "Crs", "EncodedTiles", "FeatureTable", "Framing",
           "Validation", "ZoomTiles", "encode_segment_tiles",
           "MAX_ZOOM", "check_options", "tile_features", "tile_one", "tile_table", "tile_ids",
           "write_directory", "write_pmtiles"]

#: The deepest zoom: world coordinates in float64 keep 2**-52 of the world, so tile
#: units (2**-(z + 12) at extent 4096) stay exact to 2**-16 of a unit up to zoom 24.
MAX_ZOOM = 24


def tile_features(geometries: Any, properties: Sequence[Mapping[str, Any] | None] | None = None,
                  ids: Sequence[Any] | None = None, *, crs: Crs | str = Crs.EPSG_4326,
                  **options: Any) -> Iterator[ZoomTiles]:
    """Yield the MVT tiles of Shapely geometries, zoom by zoom (see `tile_table`).

    Parameters
    ----------
    geometries : array_like of shapely.Geometry
        One per feature, in `crs`.
    properties, ids : sequence, optional
        One per feature (see `FeatureTable.of`).
    crs : {"EPSG:4326", "EPSG:3857"}
    **options
        Of `tile_table`.
    """
    yield from tile_table(FeatureTable.of(geometries, properties, ids, crs=crs), **options)


def check_options(minzoom: int, maxzoom: int, extent: int, buffer: int, mode: Mode) -> None:
    """Raise `InvalidOptionError` for zooms, extent or buffer out of range (`tile_table`)."""
    if not (isinstance(minzoom, int) and isinstance(maxzoom, int)
            and 0 <= minzoom <= maxzoom <= MAX_ZOOM):
        raise InvalidOptionError(
            f"zooms must satisfy 0 <= minzoom <= maxzoom <= {MAX_ZOOM}, got {minzoom}, "
            f"{maxzoom}")
    if not (isinstance(extent, int) and 1 <= extent <= 2**20):
        raise InvalidOptionError(f"extent must be an int in 1..{2**20}, got {extent!r}")
    if not (isinstance(buffer, int) and 0 <= buffer <= extent):
        raise InvalidOptionError(f"buffer must be an int in 0..extent, got {buffer!r}")
    if mode is Mode.APPROX and buffer < 1:
        raise InvalidOptionError("approx mode cuts within one tile unit of the padded "
                                 "edge: it needs buffer >= 1")


def tile_one(table: FeatureTable, zoom: int, x: int, y: int, *, extent: int = 4096,
             buffer: int = 64, layer: str = "features", mode: Mode | str = Mode.EXACT,
             validate: Validation | str = Validation.AT_RISK) -> bytes | None:
    """Return tile ``(zoom, x, y)`` of a `FeatureTable` (a ``Tile`` message), None if empty.

    The features are clipped to the one padded tile directly (no cascade); otherwise as
    `tile_table`, whose tile it equals.

    Raises
    ------
    InvalidOptionError
        For a tile outside the zoom's grid, or options out of range.
    """
    mode = Mode(mode)
    check_options(zoom, zoom, extent, buffer, mode)
    if not (isinstance(x, int) and isinstance(y, int) and 0 <= x < 2**zoom
            and 0 <= y < 2**zoom):
        raise InvalidOptionError(f"tile {zoom}/{x}/{y} is outside zoom {zoom}'s grid "
                                 f"(x and y in 0..{2**zoom - 1})")
    window = tile_windows(zoom, np.array([x]), np.array([y]), buffer / extent)[0]
    levels = []
    for ragged, source in ((table.points, table.points_source),
                           (table.lines, table.lines_source),
                           (table.polygons, table.polygons_source)):
        if x in (0, 2**zoom - 1):  # its buffer reaches across the antimeridian
            ragged, source = wrapped(ragged, source, buffer / extent)
        approx = mode is Mode.APPROX and ragged.kind.dimension == 1
        result = clip_ragged(ragged.kind, ragged.coords, ragged.offsets, window,
                             mode=mode if approx else Mode.EXACT,
                             tolerance=2.0**-zoom / extent if approx else None)
        levels.append(Level(zoom, Ragged(ragged.kind, result.coords, result.offsets),
                            source[result.source],
                            np.array([0, len(result)], dtype=np.int64),
                            np.array([x], dtype=np.int64), np.array([y], dtype=np.int64)))
    tiles = encode_zoom(levels, table, extent=extent, layer=layer, validate=validate)
    return tiles.data[0] if len(tiles) else None


def tile_table(table: FeatureTable, *, minzoom: int = 0, maxzoom: int = 14,
               extent: int = 4096, buffer: int = 64, layer: str = "features",
               mode: Mode | str = Mode.EXACT,
               validate: Validation | str = Validation.AT_RISK,
               backend: Backend | str = Backend.NUMBA,
               framing: Framing | str = Framing.DIRECT,
               max_tiles: int | None = None) -> Iterator[ZoomTiles]:
    """Yield the MVT tiles of a `FeatureTable`, one `ZoomTiles` per zoom, in order.

    Parameters
    ----------
    table : FeatureTable
    minzoom, maxzoom : int
        ``0 <= minzoom <= maxzoom <= MAX_ZOOM``. Zooms below `minzoom` are cut (the
        cascade starts at zoom 0) but not yielded.
    extent : int
        Tile units per tile side (default 4096).
    buffer : int
        Tile units kept around each tile (default 64).
    layer : str
        The layer's name.
    mode : {"exact", "approx"}
        Exact (default): lines are cut at the padded tile edges. Approx: lines are cut by
        the paper's intersection-free subdivision to one tile unit, a cut within one
        unit of the padded edge, inside the buffer (the visible tile is the same;
        needs ``buffer >= 1``). Points and polygons are clipped exactly in both modes
        (valid polygons need the exact crossings).
    validate : {"at-risk", "all", "none"}
        Which polygons are checked once rounded (GEOS), those invalid snapped onto the
        grid (`rnsca.tiles.encode.Validation`): those a kernel cannot prove valid
        (default), all, or none.
    backend : {"numba", "opencl", "auto"}
    framing : {"direct", "protobuf"}
        Who puts each tile's message together (`rnsca.tiles.encode.Framing`; the same
        bytes).
    max_tiles : int, optional
        Refuse a zoom that cuts more tiles than this (a service's limit: output grows
        with the zoom, not the input).

    Raises
    ------
    InvalidOptionError
        For zooms, extent or buffer out of range, or approx mode without a buffer.
    LimitExceededError
        When a zoom's tiles (of any kind of geometry) are more than `max_tiles`.
    """
    mode = Mode(mode)
    framing = Framing(framing)
    validate = Validation(validate)
    check_options(minzoom, maxzoom, extent, buffer, mode)
    pad_units = buffer / extent
    levels = [root(table.points, table.points_source, pad_units),
              root(table.lines, table.lines_source, pad_units),
              root(table.polygons, table.polygons_source, pad_units)]
    for zoom in range(maxzoom + 1):
        if zoom > 0:
            levels = [cascade(level, pad_units, mode, extent, backend) for level in levels]
            tiles = sum(level.tile_x.shape[0] for level in levels)
            if max_tiles is not None and tiles > max_tiles:
                raise LimitExceededError(
                    f"zoom {zoom} cuts {tiles} tiles or more, more than the limit of "
                    f"{max_tiles}: ask for fewer zooms")
        if zoom >= minzoom:
            yield encode_zoom(levels, table, extent=extent, layer=layer, validate=validate,
                              framing=framing)
