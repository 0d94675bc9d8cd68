"""The SDK's streamed GeoJSON (`Client.clip_geojson_seq`) against a real server."""

import asyncio
import math

import pytest
import shapely

import rnsca
import rnsca_client
from rnsca_client import AsyncClient

WINDOW = (0, 0, 10, 10)


def features(n: int):
    """A generator of `n` features, made as they are sent."""
    for i in range(n):
        y = (i % 40) / 2 - 5
        yield {"type": "Feature", "id": i, "properties": {"i": i},
               "geometry": {"type": "LineString", "coordinates": [[-5, y], [15, y + 3]]}}


def test_a_generator_of_features_streams_through_and_equals_the_library(client):
    n = 20_000
    clipped = client.clip_geojson_seq(features(n), WINDOW)
    got = list(clipped)
    expected, stats = rnsca.clip_geojson({"type": "FeatureCollection",
                                          "features": list(features(n))}, WINDOW)
    assert got == expected["features"]
    assert clipped.records_in == n and clipped.records_out == len(got)
    assert clipped.stats.geometries_in == n and clipped.stats.geometries_out == len(got)
    assert clipped.stats.segments_in == stats.segments_in


def test_shapely_geometries_in_geometry_records_out(client):
    lines = [shapely.LineString([(-5, i), (15, i)]) for i in range(12)]
    got = list(client.clip_geojson_seq(lines, WINDOW, boundary="interior"))
    # Interior: the lines along y = 0 and y = 10 lie on the boundary, and go.
    assert [shapely.geometry.shape(g) for g in got] == [
        shapely.LineString([(0, i), (10, i)]) for i in range(1, 10)]


def test_a_bad_record_after_the_first_chunk_is_raised_after_the_records_before_it(client):
    def records():
        yield from features(6000)
        yield {"type": "Feature", "properties": {}, "geometry": {"type": "Point"}}
        yield from features(10)

    clipped = client.clip_geojson_seq(records(), WINDOW)
    ids = []
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        for feature in clipped:
            ids.append(feature["id"])
    assert info.value.record == 6000 and info.value.kind == "invalid-geometry"
    assert "record 6000" in str(info.value)
    assert ids == [f["id"] for f in rnsca.clip_geojson(
        {"type": "FeatureCollection", "features": list(features(6000))}, WINDOW)[0]["features"]]


def test_a_bad_record_in_the_first_chunk_is_the_requests_status(client):
    clipped = client.clip_geojson_seq([{"type": "Nope"}], WINDOW)
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        next(clipped)
    assert info.value.status == 422 and info.value.record == 0 and info.value.path == ""


def test_what_cannot_be_sent_is_refused_by_the_client(client):
    with pytest.raises(rnsca_client.InvalidInputError, match="unknown option"):
        client.clip_geojson_seq(features(1), WINDOW, verify=True)
    nan = {"type": "Point", "coordinates": [math.nan, 0]}
    with pytest.raises(rnsca_client.InvalidInputError, match="record 1: .*NaN"):
        list(client.clip_geojson_seq([{"type": "Point", "coordinates": [1, 1]}, nan], WINDOW))
    assert client.health().status == "ok"


def test_the_async_client_streams_an_async_generator(server):
    async def records():
        for feature in features(3000):
            yield feature

    async def run():
        async with AsyncClient(server.url, retries=None) as client:
            clipped = client.clip_geojson_seq(records(), WINDOW, keep_empty=True)
            got = [feature async for feature in clipped]
            return got, clipped

    got, clipped = asyncio.run(run())
    assert [f["id"] for f in got] == list(range(3000))  # keep_empty: every one
    assert clipped.records_in == 3000 and clipped.stats.geometries_in == 3000
