"""The SDK's many-window clips (`clip_geojson_windows`, `clip_svg_windows`) and tiles
(`tile`: one Mapbox Vector Tile, `tiles`: a PMTiles archive), sync and async, against a
real server; tiles decoded with independent readers (mapbox-vector-tile, pmtiles)."""

from __future__ import annotations

import asyncio
import gzip
import io

import mapbox_vector_tile
import numpy as np
import pytest
import shapely
from pmtiles.reader import MemorySource, Reader, all_tiles
from shapely.geometry import shape

import rnsca
import rnsca_client
from rnsca.tiles import FeatureTable, tile_one
from rnsca_client import AsyncClient

pytestmark = pytest.mark.e2e

WINDOWS = [[0, 0, 5, 5], [5, 0, 10, 5], [0, 5, 5, 10], [20, 20, 30, 30]]
DOCUMENT = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "id": 1, "properties": {"name": "road"},
     "geometry": {"type": "LineString", "coordinates": [[-5, 1], [15, 1], [15, 8], [1, 8]]}},
    {"type": "Feature", "id": 2, "properties": {"name": "park"},
     "geometry": {"type": "Polygon", "coordinates": [[[2, 2], [8, 2], [8, 8], [2, 2]]]}}]}
PATHS = ["M -5 5 C 0 15 10 -5 15 5", "M 1 1 L 9 9", "M 2 2 Q 12 4 8 8 Z"]
# Lon/lat: a road and a park around (10, 10) degrees.
WORLD = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "id": 7, "properties": {"name": "road", "lanes": 2},
     "geometry": {"type": "LineString", "coordinates": [[-20, -10], [30, 25]]}},
    {"type": "Feature", "id": 8, "properties": {"name": "park"},
     "geometry": {"type": "Polygon", "coordinates": [[[5, 5], [15, 5], [15, 15], [5, 5]]]}}]}


def _world_table() -> FeatureTable:
    return FeatureTable.of([shape(f["geometry"]) for f in WORLD["features"]],
                           [f["properties"] for f in WORLD["features"]],
                           [f["id"] for f in WORLD["features"]])


# --- many windows ---------------------------------------------------------------------------


def test_geojson_windows_give_one_document_per_window(client):
    result = client.clip_geojson_windows(DOCUMENT, WINDOWS, verify="all")
    assert isinstance(result, rnsca_client.GeoJSONWindowsResult) and len(result) == 4
    for window, document, one in zip(WINDOWS, result.geojson, result.results(), strict=True):
        alone = client.clip_geojson(DOCUMENT, window, verify=False)
        assert document == alone.geojson == one.geojson
    assert result.geojson[3]["features"] == []
    assert result.verification.passed and result.verification.checked == result.verification.inputs
    shapes = result.to_shapely()
    assert shapely.equals(shapes[0][0], shapely.LineString([(0, 1), (5, 1)]))


def test_svg_windows_give_one_path_list_per_window(client):
    result = client.clip_svg_windows(PATHS, np.array(WINDOWS, dtype=float), fill="nonzero",
                                     verify="all")
    assert isinstance(result, rnsca_client.SVGWindowsResult) and len(result) == 4
    for window, paths in zip(WINDOWS, result.paths, strict=True):
        assert paths == rnsca.clip_svg(PATHS, window, fill="nonzero")[0]
    assert result.paths[3] == ["", "", ""]
    assert [r.paths for r in result.results()] == result.paths
    assert result.verification.passed


@pytest.mark.parametrize("windows, message", [
    ([], "at least one"),
    ([[0, 0, 1]], "windows[0]"),
    ([[0, 0, 1, 1], [0, 0, float("nan"), 1]], "NaN"),
    ("0 0 1 1", "list"),
])
def test_bad_windows_are_refused_before_sending(client, windows, message):
    with pytest.raises(rnsca_client.InvalidInputError, match=message.replace("[", r"\[")):
        client.clip_geojson_windows(DOCUMENT, windows)
    with pytest.raises(ValueError):  # InvalidInputError is a ValueError
        client.clip_svg_windows(PATHS, windows)


def test_a_window_the_server_refuses_is_a_422_naming_it(client):
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_svg_windows(PATHS, [[0, 0, 1, 1], [5, 5, 1, 1]])
    assert info.value.status == 422 and "window 1" in str(info.value)


# --- tiles ----------------------------------------------------------------------------------


def test_a_tile_is_the_library_s_and_decodes(client):
    tile = client.tile(WORLD, 2, 2, 1, layer="things")
    assert isinstance(tile, rnsca_client.VectorTile) and tile.features == 2
    assert (tile.z, tile.x, tile.y) == (2, 2, 1)
    assert bytes(tile) == tile.data == tile_one(_world_table(), 2, 2, 1, layer="things")
    layer = mapbox_vector_tile.decode(tile.data)["things"]
    assert layer["extent"] == 4096
    assert {f["id"]: f["properties"]["name"] for f in layer["features"]} == {7: "road",
                                                                            8: "park"}


def test_a_tile_with_no_feature_is_empty(client):
    tile = client.tile(WORLD, 3, 0, 0)
    assert tile.data == b"" and tile.features == 2


def test_tile_options_are_checked_before_sending(client):
    with pytest.raises(rnsca_client.InvalidInputError, match="unknown option"):
        client.tile(WORLD, 1, 0, 0, zoom=3)
    with pytest.raises(rnsca_client.InvalidInputError, match="whole number"):
        client.tile(WORLD, 1, -1, 0)
    with pytest.raises(rnsca_client.InvalidRequestError):  # the server's: x past zoom 1
        client.tile(WORLD, 1, 5, 0)


def _read_archive(data: bytes) -> tuple[dict, dict]:
    reader = Reader(MemorySource(data))
    tiles = {zxy: gzip.decompress(d) for zxy, d in all_tiles(reader.get_bytes)}
    return reader.header(), tiles


def test_tiles_is_a_pmtiles_archive_of_the_library_s_tiles(client):
    archive = client.tiles(WORLD, minzoom=0, maxzoom=3, layer="things", buffer=32)
    assert isinstance(archive, rnsca_client.TileArchive) and archive.features == 2
    header, tiles = _read_archive(archive.data)
    assert (header["min_zoom"], header["max_zoom"]) == (0, 3)
    assert archive.tiles == len(tiles) > 4
    for (z, x, y), data in tiles.items():
        assert data == tile_one(_world_table(), z, x, y, layer="things", buffer=32)
        names = {f["properties"]["name"] for f in
                 mapbox_vector_tile.decode(data)["things"]["features"]}
        assert names <= {"road", "park"} and names
    assert bytes(archive) == archive.data


def test_tiles_over_max_tiles_is_413():
    from tests.service.conftest import make_client

    with make_client(max_tiles=3, warm_up=False) as test_client:
        client = rnsca_client.Client(http_client=test_client, retries=None)
        assert client.capabilities().limits.max_tiles == 3
        with pytest.raises(rnsca_client.PayloadTooLargeError):
            client.tiles(WORLD, minzoom=0, maxzoom=4)


# --- async ----------------------------------------------------------------------------------


def test_async_client_windows_and_tiles(server):
    async def run():
        async with AsyncClient(server.url, retries=None) as client:
            return await asyncio.gather(
                client.clip_geojson_windows(DOCUMENT, WINDOWS, verify=False),
                client.clip_svg_windows(PATHS, WINDOWS, verify=False),
                client.tile(WORLD, 2, 2, 1),
                client.tiles(WORLD, maxzoom=2),
                client.capabilities())

    geo, svg, tile, archive, caps = asyncio.run(run())
    with rnsca_client.Client(server.url, retries=None) as client:
        assert geo == client.clip_geojson_windows(DOCUMENT, WINDOWS, verify=False)
        assert svg == client.clip_svg_windows(PATHS, WINDOWS, verify=False)
        assert tile == client.tile(WORLD, 2, 2, 1)
        assert archive.data == client.tiles(WORLD, maxzoom=2).data
    assert mapbox_vector_tile.decode(tile.data)["features"]["features"]
    _, tiles = _read_archive(archive.data)
    assert archive.tiles == len(tiles) and caps.limits.max_tiles == 100_000
    assert io.BytesIO(archive.data).read(7) == b"PMTiles"
