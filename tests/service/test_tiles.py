"""``POST /v1/tiles/{z}/{x}/{y}`` (one Mapbox Vector Tile) and ``POST /v1/tiles`` (a
PMTiles archive) of a GeoJSON body: the library's tiles, within the limits."""

import gzip

import mapbox_vector_tile
import pytest
import shapely
import shapely.geometry

from rnsca.tiles import FeatureTable, tile_one, tile_table
from tests.service.conftest import make_client

DOCUMENT = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "id": 7, "properties": {"name": "road"},
     "geometry": {"type": "LineString", "coordinates": [[-20, -10], [30, 25]]}},
    {"type": "Feature", "properties": {"name": "park"},
     "geometry": {"type": "Polygon", "coordinates": [[[5, 5], [15, 5], [15, 15], [5, 5]]]}}]}


def _table():
    geometries = [shapely.geometry.shape(f["geometry"]) for f in DOCUMENT["features"]]
    return FeatureTable.of(geometries, [f["properties"] for f in DOCUMENT["features"]],
                           [f.get("id") for f in DOCUMENT["features"]])


def test_one_tile_is_the_library_s(client):
    r = client.post("/v1/tiles/2/2/1?layer=things", json=DOCUMENT)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "application/vnd.mapbox-vector-tile"
    assert r.content == tile_one(_table(), 2, 2, 1, layer="things")
    features = mapbox_vector_tile.decode(r.content)["things"]["features"]
    assert {f["properties"]["name"] for f in features} == {"road", "park"}


def test_a_tile_with_no_feature_is_204(client):
    r = client.post("/v1/tiles/3/0/0", json=DOCUMENT)
    assert r.status_code == 204 and r.content == b""


@pytest.mark.parametrize("path, query", [("/v1/tiles/2/4/0", ""), ("/v1/tiles/25/0/0", ""),
                                         ("/v1/tiles/2/0/0", "?extent=0"),
                                         ("/v1/tiles/2/0/0", "?colour=red")])
def test_bad_tiles_and_options_are_422(client, path, query):
    r = client.post(path + query, json=DOCUMENT)
    assert r.status_code == 422, r.text
    assert r.headers["content-type"] == "application/problem+json"


def test_invalid_geojson_is_422_and_text_is_415(client):
    r = client.post("/v1/tiles/0/0/0", json={"type": "LineString", "coordinates": [[0, 0]]})
    assert r.status_code == 422
    r = client.post("/v1/tiles/0/0/0", content=b"x", headers={"Content-Type": "text/plain"})
    assert r.status_code == 415


@pytest.mark.parametrize("body", [
    {"type": {"a": 1}},  # once a TypeError (a 500): a type that is not a string
    {"type": "Feature", "properties": None, "geometry": {"type": ["Point"],
                                                         "coordinates": [1, 2]}},
    {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": None, "geometry": {"type": "Polygonx",
                                                             "coordinates": []}}]},
], ids=["object", "array", "unknown"])
def test_a_geometry_type_that_is_no_type_is_422_naming_where(client, body):
    for path in ("/v1/tiles/0/0/0", "/v1/tiles"):
        r = client.post(path, json=body)
        assert r.status_code == 422, r.text
        assert r.headers["content-type"] == "application/problem+json"
        assert "geometry.type" in r.json()["detail"]


def test_a_pyramid_is_a_pmtiles_archive_of_the_library_s_tiles(client, tmp_path):
    from pmtiles.reader import MmapSource, Reader, all_tiles

    r = client.post("/v1/tiles?minzoom=1&maxzoom=3", json=DOCUMENT)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "application/vnd.pmtiles"
    path = tmp_path / "a.pmtiles"
    path.write_bytes(r.content)
    with open(path, "rb") as f:
        read = {zxy: gzip.decompress(d) for zxy, d in all_tiles(Reader(MmapSource(f)).get_bytes)}
    expected = {(z.zoom, int(x), int(y)): d for z in tile_table(_table(), minzoom=1, maxzoom=3)
                for x, y, d in zip(z.x, z.y, z.data, strict=True)}
    assert read == expected
    assert r.headers["x-rnsca-tiles"] == str(len(expected))


def test_the_work_budget_counts_every_zoom():
    line = {"type": "LineString", "coordinates": [[i / 10, 0] for i in range(100)]}
    with make_client(work_budget=100 * 5, warm_up=False) as client:
        assert client.post("/v1/tiles?maxzoom=4", json=line).status_code == 200
        r = client.post("/v1/tiles?maxzoom=5", json=line)
        assert r.status_code == 422 and r.json()["type"].endswith("work-over-budget")


def test_too_many_tiles_in_a_zoom_is_413():
    line = {"type": "LineString", "coordinates": [[-170, 0], [0, 1], [170, 1]]}
    with make_client(max_tiles=20, warm_up=False) as client:
        assert client.post("/v1/tiles?maxzoom=3", json=line).status_code == 200
        r = client.post("/v1/tiles?maxzoom=6", json=line)
        assert r.status_code == 413, r.text
