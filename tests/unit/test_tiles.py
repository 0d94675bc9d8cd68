"""Vector tiles (`rnsca.tiles`): every tile decoded with an independent decoder
(mapbox-vector-tile) against Shapely's clip of the projected input to the padded tile,
within one tile unit; valid polygons with the specification's winding; the same
features with the same properties and ids; cascade equal to a direct clip; the
antimeridian, the poles, the whole world, a tile corner, empty input."""

import math

import mapbox_vector_tile
import numpy as np
import pytest
import shapely
import shapely.affinity
import shapely.geometry

from rnsca import clip_ragged
from rnsca.errors import InvalidOptionError, LimitExceededError
from rnsca.tiles import FeatureTable, tile_features, tile_table
from rnsca.tiles.pyramid import cascade, root, tile_windows

EXTENT, BUFFER = 4096, 64


def _project(lon, lat):
    """Web Mercator onto the unit square, written out independently of rnsca.tiles."""
    lat = np.clip(lat, -85.05112877980659, 85.05112877980659)
    x = (np.asarray(lon) + 180.0) / 360.0
    y = (1.0 - np.log(np.tan(np.radians(lat)) + 1.0 / np.cos(np.radians(lat))) / math.pi) / 2
    return x, y


def _to_tile(geometry, z, x, y):
    """The geometry (lon/lat) in tile units of tile (z, x, y), y down, not rounded."""
    def transform(coords):
        wx, wy = _project(coords[:, 0], coords[:, 1])
        return np.column_stack([(wx * 2**z - x) * EXTENT, (wy * 2**z - y) * EXTENT])
    return shapely.transform(geometry, transform)


def _decode(data):
    layers = mapbox_vector_tile.decode(
        data, default_options={"y_coord_down": True, "geojson": True})
    assert list(layers) == ["features"]
    layer = layers["features"]
    assert layer["extent"] == EXTENT and layer["version"] == 2
    return layer["features"]


def _walks(rng, count, steps=120):
    start = rng.uniform(-30, 30, size=(count, 1, 2))
    return [shapely.LineString(w) for w in
            start + rng.normal(0, 0.8, (count, steps, 2)).cumsum(axis=1)]


def _stars(rng, count):
    out = []
    for _ in range(count):
        cx, cy = rng.uniform(-30, 30, 2)
        r = rng.uniform(1, 12)
        angles = np.linspace(0, 2 * np.pi, 41)[:-1]
        radii = np.where(np.arange(40) % 2, r, r / 2.5)
        shell = np.c_[cx + radii * np.cos(angles), cy + radii * np.sin(angles)]
        hole = np.c_[cx + r / 6 * np.cos(-angles), cy + r / 6 * np.sin(-angles)]
        out.append(shapely.Polygon(shell, [hole]))
    return out


@pytest.fixture(scope="module")
def dataset():
    rng = np.random.default_rng(7)
    geometries = (_walks(rng, 30) + _stars(rng, 30)
                  + [shapely.Point(p) for p in rng.uniform(-30, 30, (20, 2))])
    properties = [{"i": i, "kind": ["walk", "star", "point"][i // 30], "w": i / 7,
                   "ok": i % 2 == 0, "none": None} for i in range(len(geometries))]
    return geometries, properties


@pytest.fixture(scope="module")
def tiles(dataset):
    geometries, properties = dataset
    return list(tile_features(geometries, properties, ids=list(range(len(geometries))),
                              minzoom=0, maxzoom=5))


def _thin(geometry, tolerance):
    """Whether a reference part may vanish once rounded: shorter or thinner than that."""
    if geometry.geom_type == "Point":
        return False
    if geometry.geom_type == "LineString":
        return shapely.length(geometry) < 2 * tolerance
    return shapely.buffer(geometry, -tolerance).is_empty


def _reference(geometry, z, x, y):
    """Shapely's clip of the projected input to the padded tile, and its lasting parts."""
    box = (-BUFFER, -BUFFER, EXTENT + BUFFER, EXTENT + BUFFER)
    clipped = shapely.clip_by_rect(_to_tile(geometry, z, x, y), *box)
    if geometry.geom_type == "Point":  # clip_by_rect drops points on the edge
        clipped = shapely.intersection(_to_tile(geometry, z, x, y), shapely.box(*box))
    parts = [p for p in shapely.get_parts(clipped) if not p.is_empty]
    lasting = [p for p in parts if not _thin(p, 1.0)]
    return clipped, shapely.GeometryCollection(lasting)


def test_every_tile_matches_shapely_within_one_unit(dataset, tiles):
    geometries, properties = dataset
    checked = 0
    for zoom in tiles:
        assert zoom.x.shape == zoom.y.shape == zoom.features.shape
        for x, y, data, count in zip(zoom.x, zoom.y, zoom.data, zoom.features, strict=True):
            features = _decode(data)
            assert len(features) == count
            seen = set()
            for feature in features:
                i = feature["id"]
                seen.add(i)
                assert feature["properties"] == {k: v for k, v in properties[i].items()
                                                 if v is not None}
                ours = shapely.geometry.shape(feature["geometry"])
                clipped, lasting = _reference(geometries[i], zoom.zoom, x, y)
                where = f"feature {i} in tile {zoom.zoom}/{x}/{y}"
                # Every vertex of ours lies within one unit of Shapely's clip.
                far = shapely.distance(shapely.points(shapely.get_coordinates(ours)),
                                       clipped).max()
                assert far <= 1.0, f"{where}: a vertex {far} from Shapely's clip"
                if not lasting.is_empty:
                    gap = shapely.hausdorff_distance(lasting, ours, densify=0.1) \
                        if lasting.geom_type != "GeometryCollection" else max(
                            shapely.distance(p, ours) for p in shapely.get_parts(lasting))
                    assert gap <= 1.0, f"{where}: Shapely's clip {gap} from ours"
                if ours.geom_type in ("Polygon", "MultiPolygon"):
                    assert ours.is_valid, f"{where}: {shapely.is_valid_reason(ours)}"
                assert np.allclose(shapely.get_coordinates(ours),
                                   np.round(shapely.get_coordinates(ours)))
                checked += 1
            # A feature with something lasting in the tile is in it, and only those.
            for i, geometry in enumerate(geometries):
                _, lasting = _reference(geometry, zoom.zoom, x, y)
                if not lasting.is_empty:
                    assert i in seen, f"feature {i} missing from {zoom.zoom}/{x}/{y}"
    assert checked > 500


def test_rings_are_wound_as_the_specification_asks(tiles):
    """Exterior rings: positive area by the surveyor's formula in tile coordinates."""
    from rnsca.tiles.vector_tile import Tile

    rings = 0
    for zoom in tiles:
        for data in zoom.data:
            for feature in Tile.FromString(data).layers[0].features:
                if feature.type != 3:
                    continue
                for ring, exterior in _rings(list(feature.geometry)):
                    area = 0.5 * sum(a[0] * b[1] - b[0] * a[1]
                                     for a, b in zip(ring, ring[1:] + ring[:1], strict=True))
                    assert area != 0
                    rings += 1
                    if exterior is not None:
                        assert (area > 0) == exterior
    assert rings > 100


def _rings(commands):
    """Decode a polygon's command stream into rings (tile units) by hand; the first ring
    after a ring of positive area may be a hole, so only the first is marked exterior."""
    x = y = 0
    i = 0
    rings, current = [], []
    while i < len(commands):
        command, count = commands[i] & 7, commands[i] >> 3
        i += 1
        if command == 7:
            rings.append(current)
            current = []
            continue
        for _ in range(count):
            dx, dy = commands[i], commands[i + 1]
            x += (dx >> 1) ^ -(dx & 1)
            y += (dy >> 1) ^ -(dy & 1)
            current.append((x, y))
            i += 2
    return [(ring, True if k == 0 else None) for k, ring in enumerate(rings)]


def test_cascade_equals_a_direct_clip_of_the_input(dataset):
    geometries, _ = dataset
    table = FeatureTable.of(geometries)
    for ragged, source in ((table.lines, table.lines_source),
                           (table.polygons, table.polygons_source)):
        level = root(ragged, source)
        for _ in range(5):
            level = cascade(level, BUFFER / EXTENT, "exact", EXTENT)
        windows = tile_windows(level.zoom, level.tile_x, level.tile_y, BUFFER / EXTENT)
        direct = clip_ragged(ragged.kind, ragged.coords, ragged.offsets, windows=windows)
        cascaded = level.ragged.to_shapely()
        tiles = level.geometry_tile
        direct_shapes = direct.to_shapely()
        unit = 2.0**-level.zoom / EXTENT
        assert np.array_equal(np.diff(direct.window_offsets), np.diff(level.tile_offsets))
        np.testing.assert_array_equal(source[direct.source], level.source)
        np.testing.assert_array_equal(direct.window, tiles)
        for a, b in zip(cascaded, direct_shapes, strict=True):
            assert shapely.hausdorff_distance(a, b) <= 1e-6 * unit


def test_a_line_across_the_antimeridian_is_split_and_wrapped():
    line = shapely.LineString([(170, 10), (-170, 20)])
    zoom = list(tile_features([line], minzoom=2, maxzoom=2))[0]
    assert sorted(set(zoom.x.tolist())) == [0, 3]
    for x, y, data in zip(zoom.x, zoom.y, zoom.data, strict=True):
        ours = shapely.geometry.shape(_decode(data)[0]["geometry"])
        # 10 degrees of longitude each side: about 455 units at zoom 2, not 3/4 world.
        assert shapely.length(ours) < 700, (x, y, ours.wkt)


def test_a_polygon_across_the_antimeridian_is_split_and_wrapped():
    polygon = shapely.Polygon([(170, -5), (-170, -5), (-170, 5), (170, 5), (170, -5)])
    zoom = list(tile_features([polygon], minzoom=1, maxzoom=1))[0]
    assert sorted(set(zoom.x.tolist())) == [0, 1]
    total = 0.0
    for data in zoom.data:
        ours = shapely.geometry.shape(_decode(data)[0]["geometry"])
        assert ours.is_valid
        total += ours.area
    # 20 degrees by about 10: 2048 * 20 / 180 units wide at zoom 1, twice the buffer
    # strips counted in both... the area stays far below a band round the world.
    assert 0 < total < 2 * (4096 * 20 / 180 + 2 * BUFFER) * 4096 * 0.1


def _wrapped_reference(geometry, z, x, y):
    """Shapely's clip to the padded tile of the geometry and its copies a turn east and
    west (the map wraps: a tile at the edge buffers what lies across the antimeridian)."""
    parts = []
    for turn in (-360.0, 0.0, 360.0):
        moved = shapely.affinity.translate(geometry, turn)
        clipped, _ = _reference(moved, z, x, y)
        parts += [p for p in shapely.get_parts(clipped) if not p.is_empty]
    if geometry.geom_type == "Polygon":
        return shapely.union_all(parts)
    return shapely.GeometryCollection(parts)


@pytest.mark.parametrize("geometry", [
    shapely.LineString([(170, 10), (179.5, 12)]),
    shapely.LineString([(-179.9, -20), (-175, -25), (-179.2, -30)]),
    shapely.Polygon([(178.5, -5), (179.8, -5), (179.8, 5), (178.5, 5)]),
    shapely.Polygon([(175, 30), (-175, 30), (-175, 40), (175, 40)]),  # across it: below
    shapely.Point(179.7, 0.5),
    shapely.Point(-180, 3),
], ids=["line-east", "line-west", "polygon-east", "polygon-across", "point-east",
        "point-on-the-antimeridian"])
def test_tiles_at_the_map_edge_buffer_across_the_antimeridian(geometry):
    """Every tile (zooms 0-3) holds Shapely's clip of the input and its copies a turn
    away, within one unit: the edge tiles' buffers reach across the antimeridian; the
    direct path (`tile_one`) gives the same tiles."""
    from rnsca.tiles import tile_one

    table = FeatureTable.of([geometry])
    # Shapely reads a polygon across the antimeridian the long way round: the oracle
    # gets it unwrapped (longitudes east of 180; GeoJSON cuts such polygons in two).
    unwrapped = shapely.transform(geometry, lambda c: np.where(c < -170, c + 360, c)) \
        if geometry.geom_type == "Polygon" else geometry
    across = 0
    for zoom in tile_table(table, maxzoom=3):
        held = {(int(x), int(y)): d for x, y, d in zip(zoom.x, zoom.y, zoom.data,
                                                        strict=True)}
        side = 2**zoom.zoom
        for x in range(side):
            for y in range(side):
                reference = _wrapped_reference(unwrapped, zoom.zoom, x, y)
                where = f"tile {zoom.zoom}/{x}/{y}"
                if (x, y) not in held:
                    assert reference.is_empty or all(_thin(p, 1.0) for p in
                                                     shapely.get_parts(reference)), where
                    continue
                assert tile_one(table, zoom.zoom, x, y) == held[(x, y)], where
                ours = shapely.union_all([shapely.geometry.shape(f["geometry"])
                                          for f in _decode(held[(x, y)])])
                far = shapely.distance(shapely.points(shapely.get_coordinates(ours)),
                                       reference).max()
                assert far <= 1.0, f"{where}: a vertex {far} from Shapely's clip"
                assert shapely.hausdorff_distance(reference, ours) <= 1.0, where
                if ours.geom_type in ("Polygon", "MultiPolygon"):
                    assert ours.is_valid, where
                # What the tile holds across the antimeridian (west of 0, or from
                # the east edge on: the point on the antimeridian is at 0 and 4096).
                xs = shapely.get_coordinates(ours)[:, 0]
                across += int((x == 0 and xs.min() < 0) or (x == side - 1
                                                            and xs.max() >= EXTENT))
    assert across > 0


def test_the_world_polygon_fills_each_tile_with_its_padded_square():
    world = shapely.box(-180, -90, 180, 90)
    zoom = list(tile_features([world], minzoom=2, maxzoom=2))[0]
    assert len(zoom) == 16
    # Every tile with a neighbour on each side across x (the map wraps round): the
    # tiles at the antimeridian get their buffer from the other edge, as a second
    # feature of the world (its copy a turn away), side by side with the first.
    inner = [(x, d) for x, y, d in zip(zoom.x, zoom.y, zoom.data, strict=True)
             if 0 < y < 3]
    assert len(inner) == 8
    for x, data in inner:
        features = [shapely.geometry.shape(f["geometry"]) for f in _decode(data)]
        assert len(features) == (2 if x in (0, 3) else 1)
        assert shapely.union_all(features).area == sum(f.area for f in features)
        assert shapely.equals(shapely.union_all(features), shapely.box(
            -BUFFER, -BUFFER, EXTENT + BUFFER, EXTENT + BUFFER))


def test_latitudes_past_the_square_are_clamped():
    line = shapely.LineString([(-10, 89.9), (10, 89.9)])
    zoom = list(tile_features([line], minzoom=1, maxzoom=1))[0]
    assert set(zoom.y.tolist()) == {0}
    ys = {c[1] for data in zoom.data
          for c in shapely.get_coordinates(shapely.geometry.shape(
              _decode(data)[0]["geometry"]))}
    assert ys == {0}


def test_a_point_on_a_tile_corner_is_in_the_four_tiles():
    zoom = list(tile_features([shapely.Point(0, 0)], minzoom=1, maxzoom=1))[0]
    got = {(x, y): _decode(d)[0]["geometry"]["coordinates"]
           for x, y, d in zip(zoom.x.tolist(), zoom.y.tolist(), zoom.data, strict=True)}
    assert got == {(0, 0): [4096, 4096], (1, 0): [0, 4096], (0, 1): [4096, 0],
                   (1, 1): [0, 0]}


def test_a_point_in_the_buffer_of_a_neighbour():
    # 32 units right of the line x = 0.5 at zoom 1: in tile 1, and in tile 0's buffer.
    lon = (0.5 + 32 / (2 * EXTENT)) * 360 - 180
    zoom = list(tile_features([shapely.Point(lon, 10)], minzoom=1, maxzoom=1))[0]
    assert sorted(zoom.x.tolist()) == [0, 1]
    zoom = list(tile_features([shapely.Point(lon, 10)], minzoom=1, maxzoom=1,
                              buffer=16))[0]
    assert zoom.x.tolist() == [1]


def test_empty_input_gives_no_tile():
    assert [len(z) for z in tile_features([], minzoom=0, maxzoom=3)] == [0, 0, 0, 0]
    assert [len(z) for z in tile_features([None, shapely.LineString()])] == [0] * 15


def test_degenerate_parts_are_dropped():
    # A line of 0.1 unit at zoom 0 rounds to one position: no feature.
    tiny = shapely.LineString([(0.0, 0.0), (0.1 * 360 / 4096 / 2, 0.0)])
    assert [len(z) for z in tile_features([tiny], maxzoom=0)] == [0]


def test_approx_mode_shows_the_same_visible_tile(dataset):
    geometries, _ = dataset
    lines = geometries[:30]
    exact = list(tile_features(lines, minzoom=4, maxzoom=4))[0]
    approx = list(tile_features(lines, minzoom=4, maxzoom=4, mode="approx"))[0]
    assert exact.x.tolist() == approx.x.tolist() and exact.y.tolist() == approx.y.tolist()
    square = shapely.box(0, 0, EXTENT, EXTENT)
    for a, b in zip(exact.data, approx.data, strict=True):
        for fa, fb in zip(_decode(a), _decode(b), strict=True):
            assert fa["id"] == fb["id"]
            ga = shapely.intersection(shapely.geometry.shape(fa["geometry"]), square)
            gb = shapely.intersection(shapely.geometry.shape(fb["geometry"]), square)
            assert shapely.hausdorff_distance(ga, gb) <= 1.0 if not ga.is_empty else True


@pytest.mark.parametrize("options", [dict(minzoom=3, maxzoom=2), dict(maxzoom=25),
                                     dict(buffer=-1), dict(extent=0),
                                     dict(mode="approx", buffer=0)])
def test_bad_options_are_refused(options):
    with pytest.raises(InvalidOptionError):
        next(tile_table(FeatureTable.of([shapely.Point(0, 0)]), **options))


def test_web_mercator_input_gives_the_same_tiles(dataset):
    geometries, properties = dataset
    radius = 6378137.0

    def to_metres(coords):
        x, y = _project(coords[:, 0], coords[:, 1])
        return np.column_stack([(x - 0.5) * 2 * math.pi * radius,
                                (0.5 - y) * 2 * math.pi * radius])
    metres = shapely.transform(np.asarray(geometries, dtype=object), to_metres)
    a = list(tile_features(geometries, properties, minzoom=3, maxzoom=3))[0]
    b = list(tile_features(metres, properties, crs="EPSG:3857", minzoom=3, maxzoom=3))[0]
    assert a.x.tolist() == b.x.tolist() and a.features.tolist() == b.features.tolist()


def test_pmtiles_archive_reads_back_with_the_pmtiles_reader(tmp_path, dataset, tiles):
    import gzip

    from pmtiles.reader import MmapSource, Reader, all_tiles
    from pmtiles.tile import Compression, TileType, zxy_to_tileid

    from rnsca.tiles import tile_ids, write_pmtiles

    path = tmp_path / "out.pmtiles"
    summary = write_pmtiles(path, tiles, layer="features")
    expected = {(z.zoom, int(x), int(y)): d for z in tiles
                for x, y, d in zip(z.x, z.y, z.data, strict=True)}
    assert summary.tiles == len(expected)
    with open(path, "rb") as f:
        reader = Reader(MmapSource(f))
        header = reader.header()
        assert header["tile_type"] == TileType.MVT
        assert header["tile_compression"] == Compression.GZIP
        assert (header["min_zoom"], header["max_zoom"]) == (0, 5)
        assert header["clustered"]
        assert reader.metadata()["vector_layers"][0]["id"] == "features"
        read = {zxy: gzip.decompress(data) for zxy, data in all_tiles(reader.get_bytes)}
        assert read == expected
        z, x, y = next(iter(expected))
        assert gzip.decompress(reader.get(z, x, y)) == expected[(z, x, y)]
    # The vectorised tile ids are the specification's.
    for zoom in tiles:
        assert tile_ids(zoom.zoom, zoom.x, zoom.y).tolist() == [
            zxy_to_tileid(zoom.zoom, int(x), int(y)) for x, y in zip(zoom.x, zoom.y,
                                                                      strict=True)]


def test_stored_tiles_are_each_tile_gzipped_in_order(tiles):
    """Chunks of tiles by bytes across threads: each tile its own gzip member, in order."""
    import gzip
    from concurrent.futures import ThreadPoolExecutor

    from rnsca.tiles.archive import Compression, _compressor, _stored
    from rnsca.tiles.encode import ZoomTiles

    compress = _compressor(Compression.GZIP)
    sizes = [1, 70_000, 3, 0, 500_000, 10, 10, 300_000] + [17] * 600
    data = [bytes(range(256)) * (n // 256) + bytes(n % 256) for n in sizes]
    zoom = ZoomTiles(3, np.arange(len(data)), np.zeros(len(data), dtype=np.int64), data,
                     np.ones(len(data), dtype=np.int64))
    with ThreadPoolExecutor(4) as pool:
        stored = _stored(zoom, compress, pool)
        assert [gzip.decompress(d) for d in stored] == data
        assert stored == [compress(d) for d in data]
        for few in (data[:1], data[:2], []):
            assert _stored(ZoomTiles(3, np.arange(len(few)), np.zeros(len(few), dtype=int),
                                     few, np.ones(len(few), dtype=int)), compress,
                           pool) == [compress(d) for d in few]
    # A gzip member with mtime 0: the same bytes every run.
    assert stored[0][4:8] == bytes(4) and stored[0][:3] == b"\x1f\x8b\x08"


def test_the_next_zoom_is_made_while_one_is_written_and_errors_reach_the_writer(tmp_path,
                                                                                 tiles):
    import threading

    from rnsca.tiles import write_pmtiles
    from rnsca.tiles.archive import _made_ahead

    made = []

    def zooms():
        for zoom in tiles:
            made.append((zoom.zoom, threading.current_thread().name))
            yield zoom

    assert [z.zoom for z in _made_ahead(zooms())] == [z.zoom for z in tiles]
    assert {name for _, name in made} == {"rnsca-tiles-maker"}

    def failing():
        yield tiles[0]
        raise LimitExceededError("zoom 1 cuts too many tiles")

    with pytest.raises(LimitExceededError, match="too many tiles"):
        write_pmtiles(tmp_path / "a.pmtiles", failing(), layer="x")
    # A writer that stops early stops the maker after the zoom it is making.
    made.clear()
    ahead = _made_ahead(zooms())
    next(ahead)
    ahead.close()
    assert len(made) <= 3
    assert not any(t.name == "rnsca-tiles-maker" for t in threading.enumerate())


def test_directory_archive_holds_z_x_y_mvt(tmp_path, tiles):
    from rnsca.tiles import write_directory

    summary = write_directory(tmp_path / "tiles", tiles)
    files = sorted(p.relative_to(tmp_path / "tiles").as_posix()
                   for p in (tmp_path / "tiles").rglob("*.mvt"))
    assert len(files) == summary.tiles == sum(len(z) for z in tiles)
    zoom = tiles[-1]
    x, y = int(zoom.x[0]), int(zoom.y[0])
    assert (tmp_path / "tiles" / str(zoom.zoom) / str(x) / f"{y}.mvt").read_bytes() == \
        zoom.data[0]


def test_direct_framing_gives_protobuf_s_bytes(dataset):
    geometries, properties = dataset
    options = dict(minzoom=2, maxzoom=4)
    direct = list(tile_features(geometries, properties, **options))
    framed = list(tile_features(geometries, properties, framing="protobuf", **options))
    for a, b in zip(direct, framed, strict=True):
        assert a.data == b.data and a.x.tolist() == b.x.tolist()


def test_polygons_proved_valid_by_the_kernel_are_valid(rng):
    """`polygons_at_risk` leaves unmarked only polygons GEOS finds valid once rounded."""
    from rnsca.arrays import Ragged
    from rnsca.kernels.tiles import polygons_at_risk

    shapes = []
    for scale in (0.8, 2.0, 5.0, 40.0):
        for star in _stars(rng, 150):
            # A star of radius 1..12 scaled to a few units: rounding breaks many.
            shapes.append(shapely.affinity.scale(star, scale, scale, origin=(0, 0)))
        shapes += [shapely.MultiPolygon([a, b]) for a, b in zip(
            _stars(rng, 40), _stars(rng, 40), strict=True)
            if a.disjoint(b)]
    parts, index = shapely.get_parts(np.asarray(shapes, dtype=object), return_index=True)
    ragged = Ragged.from_shapely(shapely.multipolygons(parts, indices=index))
    rounded = Ragged(ragged.kind, np.round(ragged.coords), ragged.offsets)
    at_risk = np.empty(rounded.count, dtype=bool)
    polygons_at_risk(rounded.coords.astype(np.int64), *rounded.offsets, at_risk)
    valid = shapely.is_valid(rounded.to_shapely())
    assert (~at_risk).sum() > 100 and (~valid).sum() > 50

    def written(geometry):
        """What the encoder writes: rings of zero area dropped, a shell's with its holes."""
        polygons = []
        for polygon in shapely.get_parts(geometry):
            shell, holes = polygon.exterior, list(polygon.interiors)
            if shapely.Polygon(shell).area == 0:
                continue
            polygons.append(shapely.Polygon(shell, [h for h in holes
                                                    if shapely.Polygon(h).area > 0]))
        return shapely.MultiPolygon(polygons)
    for geometry in rounded.to_shapely()[~at_risk]:
        assert written(geometry).is_valid, geometry.wkt


def test_validating_at_risk_polygons_gives_what_validating_all_gives(dataset):
    geometries, properties = dataset
    polygons = [shapely.affinity.scale(g, 0.05, 0.05) for g in geometries[30:60]]
    options = dict(minzoom=0, maxzoom=4)
    at_risk = list(tile_features(polygons, **options))
    every = list(tile_features(polygons, validate="all", **options))
    for a, b in zip(at_risk, every, strict=True):
        assert a.data == b.data


def test_one_tile_equals_the_pyramid_s(dataset):
    """A tile clipped directly equals the cascade's to rounding: within one unit."""
    from rnsca.tiles import tile_one

    geometries, properties = dataset
    table = FeatureTable.of(geometries, properties, ids=list(range(len(geometries))))
    zoom = list(tile_table(table, minzoom=4, maxzoom=4))[0]
    for x, y, data in zip(zoom.x.tolist(), zoom.y.tolist(), zoom.data, strict=True):
        direct, cascaded = _decode(tile_one(table, 4, x, y)), _decode(data)
        assert [f["id"] for f in direct] == [f["id"] for f in cascaded]
        for a, b in zip(direct, cascaded, strict=True):
            assert a["properties"] == b["properties"]
            assert shapely.hausdorff_distance(shapely.geometry.shape(a["geometry"]),
                                              shapely.geometry.shape(b["geometry"])) <= 1
    assert tile_one(table, 4, 0, 0) is None  # the far north-west: nothing there
    with pytest.raises(InvalidOptionError, match="outside"):
        tile_one(table, 2, 4, 0)


def test_rounded_rings_are_cleaned_before_they_are_checked():
    """Repeated and collinear positions and spikes go; a collapsed shell takes its holes."""
    from rnsca.tiles.encode import clean_polygons

    spiky = [(0, 0), (2, 0), (4, 0), (4, 0), (4, 2), (4, 4), (7, 4), (4, 4), (0, 4), (0, 2),
             (0, 0)]
    line = [(0, 0), (3, 3), (1, 1), (0, 0)]  # a shell rounded onto a line
    hole = [(1, 1), (1, 2), (2, 2), (1, 1)]
    q = np.array(spiky + line + hole, dtype=np.int64)
    offsets = (np.array([0, 11, 15, 19]), np.array([0, 1, 3]), np.array([0, 1, 2]))
    out, (rings, polygons, geometries) = clean_polygons(q, offsets)
    assert out.tolist() == [[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]]
    assert rings.tolist() == [0, 5] and polygons.tolist() == [0, 1]
    assert geometries.tolist() == [0, 1, 1]  # the second geometry is left empty


def test_tag_values_are_told_apart_by_type_and_sign_and_stored_once():
    from rnsca.tiles.features import tag_table
    from rnsca.tiles.vector_tile import Value

    values = [0.0, -0.0, 1, True, 1.0, float("nan"), "x", 1, "x", 2**70, -0.0, None, [1]]
    table = tag_table([{"a": v} for v in values])
    # NaN and None are not written; the rest numbered by first appearance.
    assert table.tag_offsets.tolist() == [0, 1, 2, 3, 4, 5, 5, 6, 7, 8, 9, 10, 10, 11]
    assert table.tag_value.tolist() == [0, 1, 2, 3, 4, 5, 2, 5, 6, 1, 7]
    offsets = table.value_field_offsets
    decoded = [Value.FromString(table.value_fields[a + 2:b].tobytes())
               for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
    assert [d.ListFields()[0][0].name for d in decoded] == [
        "double_value", "double_value", "int_value", "bool_value", "double_value",
        "string_value", "double_value", "string_value"]
    assert str(decoded[1].double_value) == "-0.0" and decoded[7].string_value == "[1]"
