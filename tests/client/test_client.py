"""Every method of `rnsca_client.Client` and `AsyncClient` against a real server."""

from __future__ import annotations

import asyncio
import json
import warnings

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon, box, mapping

import rnsca
import rnsca_client
from rnsca_client import AsyncClient, Client
from tests.cases import MIXED_DIMENSIONS, MIXED_DIMENSIONS_CLIPPED
from tests.client.conftest import MAX_VERTICES
from tests.geoarrow_tables import decode, table, to_stream

pytestmark = pytest.mark.e2e

WINDOW = (0.0, 0.0, 10.0, 10.0)
ROAD = {"type": "Feature", "id": 7, "properties": {"name": "road"},
        "geometry": {"type": "LineString",
                     "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5], [15, 5]]}}
HOLED = Polygon([(-5, -5), (6, -5), (6, 6), (-5, 6)], [[(1, 1), (3, 1), (3, 3), (1, 3)]])


def crossing_segments(count: int, seed: int = 3) -> np.ndarray:
    ends = np.random.default_rng(seed).uniform(-20, 30, (count, 4))
    return ends


def same_geometry(a, b, tolerance=1e-9) -> bool:
    return (a.geom_type == b.geom_type and shapely.hausdorff_distance(a, b) <= tolerance
            and abs(a.length - b.length) <= tolerance)


# --- health, readiness, capabilities ------------------------------------------------------


def test_health_and_ready(client):
    assert client.health() == rnsca_client.Health("ok")
    assert client.ready() is True
    client.wait_until_ready(timeout=5)


def test_capabilities_are_typed_and_name_the_servers_limits(client):
    caps = client.capabilities()
    assert isinstance(caps, rnsca_client.Capabilities)
    assert caps.version == rnsca.__version__
    assert "rnsca" in caps.methods and caps.modes == ["exact", "approx"]
    assert "numba" in caps.available_backends
    missing = [b for b in caps.backends if not b.available]
    assert all(b.reason for b in missing)
    assert caps.limits.max_vertices == MAX_VERTICES and caps.svg is True


# --- GeoJSON ------------------------------------------------------------------------------


def test_clip_geojson_feature_keeps_properties_and_matches_shapely(client):
    result = client.clip_geojson(ROAD, WINDOW)
    assert isinstance(result, rnsca_client.GeoJSONResult)
    assert result.geojson["id"] == 7 and result.geojson["properties"] == {"name": "road"}
    expected = shapely.intersection(LineString(ROAD["geometry"]["coordinates"]), box(*WINDOW))
    assert same_geometry(result.to_shapely(), expected)
    assert result.stats.geometries_in == 1 and result.stats.vertices_in == 6
    assert result.stats.accepted + result.stats.rejected + result.stats.subdivided \
        + result.stats.clipped + result.stats.dropped == result.stats.fragments_evaluated
    assert result.verification.passed and result.verification.mode == "exact"


def test_clip_geojson_takes_json_text(client):
    assert client.clip_geojson(json.dumps(ROAD), WINDOW).geojson["id"] == 7


def test_shapely_in_shapely_out(client):
    result = client.clip_geojson(HOLED, box(*WINDOW))   # the window as a Shapely box too
    clipped = result.to_shapely()
    assert isinstance(clipped, Polygon) and len(clipped.interiors) == 1
    expected = shapely.intersection(HOLED, box(*WINDOW))
    assert shapely.equals_exact(shapely.normalize(clipped), shapely.normalize(expected),
                                tolerance=1e-12)
    assert result.verification.passed and result.verification.ratio == pytest.approx(1.0)


def test_feature_collection_gives_a_list_of_shapely_geometries(client):
    collection = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"i": i}, "geometry": mapping(g)}
        for i, g in enumerate([HOLED, LineString([(-1, -1), (11, 11)]),
                               LineString([(20, 20), (30, 30)])])]}
    result = client.clip_geojson(collection, rnsca.Window(*WINDOW), keep_empty=True)
    geoms = result.to_shapely()
    assert [g.geom_type for g in geoms] == ["Polygon", "LineString", "LineString"]
    assert geoms[2].is_empty and geoms[1].length == pytest.approx(10 * 2**0.5)
    assert [f["properties"]["i"] for f in result.geojson["features"]] == [0, 1, 2]


def test_a_document_mixing_2d_and_3d_positions_comes_back_in_kind(client):
    result = client.clip_geojson(MIXED_DIMENSIONS, rnsca.Window(*WINDOW))
    assert [f["geometry"] for f in result.geojson["features"]] == MIXED_DIMENSIONS_CLIPPED
    line, polygon, points = result.to_shapely()
    assert shapely.has_z(line) and shapely.get_coordinates(line, include_z=True)[:, 2] \
        .tolist()[1:] == [1.0, 2.0]
    assert polygon.area == 25.0 and len(points.geoms) == 2


def test_geojson_options_reach_the_server(client):
    line = LineString([(-3.3, 2.7), (13.1, 7.9)])
    exact = client.clip_geojson(line, WINDOW)
    approx = client.clip_geojson(line, WINDOW, mode="approx", n=4, max_depth=6,
                                 approx_bound=1.0, verify=True)
    assert approx.verification.mode == "approx" and approx.verification.passed
    assert approx.stats.dropped > 0 and approx.stats.deepest_level == 6
    assert approx.to_shapely().length < exact.to_shapely().length
    interior = client.clip_geojson(LineString([(0, -5), (0, 15)]), WINDOW, boundary="interior")
    assert interior.to_shapely().is_empty
    unverified = client.clip_geojson(line, WINDOW, verify=False, method="liang_barsky",
                                     backend="numba")
    assert unverified.verification is None


# --- SVG ----------------------------------------------------------------------------------


def test_clip_svg_one_string_and_a_list(client):
    curve = "M -5 5 C 0 15 10 -5 15 5"
    one = client.clip_svg(curve, WINDOW)
    assert isinstance(one, rnsca_client.SVGResult) and len(one.paths) == 1
    assert "C" in one.paths[0]                        # the cubic stays a cubic
    local, _ = rnsca.clip_svg([curve], WINDOW)
    assert one.paths == list(local)
    two = client.clip_svg([curve, "M 20 20 L 30 30"], WINDOW, curves="flatten",
                          tolerance=1e-3)
    assert "C" not in two.paths[0] and two.paths[1] == ""
    assert two.verification.passed


def test_clip_svg_fill(client):
    square = "M -5 -5 H 5 V 5 H -5 Z"
    result = client.clip_svg(square, WINDOW, fill="nonzero")
    local, _ = rnsca.clip_svg([square], WINDOW, fill="nonzero")
    assert result.paths == list(local) and result.verification.passed


@pytest.mark.parametrize("fill_output", ["clean", "raw"])
def test_clip_svg_fill_output_is_passed_on(client, fill_output):
    # Runs along the bottom edge back and forth: raw keeps them, clean does not.
    notch = "M2 -1L1 1L3 -1L1 -1Z"
    result = client.clip_svg(notch, WINDOW, fill="nonzero", fill_output=fill_output)
    local, _ = rnsca.clip_svg([notch], WINDOW, fill="nonzero", fill_output=fill_output)
    assert result.paths == list(local)


# --- segments -----------------------------------------------------------------------------


def test_clip_segments_numpy_goes_binary_and_equals_the_library(client):
    segments = crossing_segments(500)
    result = client.clip_segments(segments, WINDOW)
    assert isinstance(result.segments, np.ndarray) and result.segments.dtype == np.float64
    assert result.segments.shape == (len(result), 4) and result.t.shape == (len(result), 2)
    assert result.source.dtype == np.int64
    local = rnsca.clip_segments(segments, WINDOW)
    np.testing.assert_array_equal(result.segments, local.segments)
    np.testing.assert_array_equal(result.source, local.source)
    np.testing.assert_array_equal(result.t, local.t)
    assert result.stats.pieces_out == len(local) and result.verification.passed
    assert (result.method, result.mode, result.backend) == ("rnsca", "exact", "numba")


def test_clip_segments_json_and_binary_agree(client):
    segments = crossing_segments(50)
    binary = client.clip_segments(segments, WINDOW, mode="approx", n=8, max_depth=5)
    listed = client.clip_segments(segments.tolist(), WINDOW, mode="approx", n=8, max_depth=5)
    forced = client.clip_segments(segments, WINDOW, binary=False, mode="approx", n=8,
                                  max_depth=5)
    assert isinstance(listed.segments, list) and listed.segments == forced.segments
    np.testing.assert_array_equal(binary.segments, np.array(listed.segments))
    assert list(binary.source) == listed.source and binary.stats == listed.stats
    assert binary.mode == listed.mode == "approx"


def test_clip_segments_binary_options_and_empty_input(client):
    segments = crossing_segments(20)
    result = client.clip_segments(segments, WINDOW, method="cohen_sutherland",
                                  backend="numba", verify=False)
    assert result.method == "cohen_sutherland" and result.backend == "numba"
    assert result.verification is None
    empty = client.clip_segments(np.empty((0, 4)), WINDOW)
    assert len(empty) == 0 and empty.segments.shape == (0, 4)


# --- connection handling ------------------------------------------------------------------


def test_clip_geoarrow_table_in_table_out(client):
    lines = [LineString([(-5, 1), (15, 1)]), LineString([(20, 20), (30, 30)])]
    sent = table(lines, "linestring", "interleaved", False)
    result = client.clip_geoarrow(sent, WINDOW, keep_empty=True, verify=True)
    assert result.rows == len(result) == 2 and result.verification.passed
    got = result.table()
    assert got.column("name").to_pylist() == ["row 0", "row 1"]
    clipped = decode(got.column("geometry"), got.schema.field("geometry"))
    assert clipped[0].equals(shapely.MultiLineString([[(0, 1), (10, 1)]]))
    assert clipped[1].is_empty
    assert client.clip_geoarrow(to_stream(sent), WINDOW).rows == 1  # bytes go as they are


def test_clip_geoarrow_refuses_unknown_options_and_inputs_before_sending(client):
    with pytest.raises(rnsca_client.InvalidInputError, match="keep_emtpy"):
        client.clip_geoarrow(b"", WINDOW, keep_emtpy=True)
    with pytest.raises(rnsca_client.InvalidInputError, match="Arrow IPC stream"):
        client.clip_geoarrow([1, 2], WINDOW)
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_geoarrow(b"not arrow", WINDOW)
    assert info.value.kind == "invalid-body"


def test_context_manager_closes_and_an_injected_client_stays_open(server):
    with Client(server.url) as c:
        c.health()
    assert c._http.is_closed
    import httpx

    with httpx.Client(base_url=server.url) as http:
        with Client(http_client=http) as c:
            assert c.health().status == "ok" and c.base_url == http.base_url
        assert not http.is_closed


def test_a_test_client_of_the_app_can_be_injected():
    from service import Settings, create_app

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from fastapi.testclient import TestClient
    with TestClient(create_app(Settings(warm_up=False))) as app_client:
        result = Client(http_client=app_client).clip_segments([[-5, 5, 15, 5]], WINDOW)
    assert result.segments == [[0.0, 5.0, 10.0, 5.0]] and result.t == [[0.25, 0.75]]


# --- async --------------------------------------------------------------------------------


def test_async_client_every_method(server):
    async def run():
        async with AsyncClient(server.url, retries=None) as client:
            health, ready, caps = await asyncio.gather(
                client.health(), client.ready(), client.capabilities())
            geo, svg, binary, listed, arrow = await asyncio.gather(
                client.clip_geojson(HOLED, WINDOW),
                client.clip_svg("M -5 5 L 15 5", WINDOW),
                client.clip_segments(crossing_segments(30), WINDOW),
                client.clip_segments([[-5, 5, 15, 5]], WINDOW),
                client.clip_geoarrow(table([HOLED], "polygon", "separated", False),
                                     WINDOW))
            await client.wait_until_ready(timeout=5)
            with pytest.raises(rnsca_client.InvalidRequestError) as info:
                await client.clip_geojson(ROAD, (0, 0, 0, 10))
        assert client._http.is_closed
        return health, ready, caps, geo, svg, binary, listed, arrow, info.value

    health, ready, caps, geo, svg, binary, listed, arrow, error = asyncio.run(run())
    assert arrow.rows == 1 and arrow.verification.passed
    assert health.status == "ok" and ready and "numba" in caps.available_backends
    assert geo.verification.passed and isinstance(geo.to_shapely(), Polygon)
    assert svg.paths == list(rnsca.clip_svg(["M -5 5 L 15 5"], WINDOW)[0])
    np.testing.assert_array_equal(binary.segments,
                                  rnsca.clip_segments(crossing_segments(30), WINDOW).segments)
    assert listed.segments == [[0.0, 5.0, 10.0, 5.0]]
    assert error.kind == "invalid-window" and error.path == "window"
