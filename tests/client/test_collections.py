"""`Client.clip` and `clip_many` with GeoPandas, Shapely and pyarrow collections, against a
real server: the same kind back, properties, index labels and CRS kept, rows clipped to
nothing dropped, and each geometry equal to Shapely's intersection with the window."""

from __future__ import annotations

import asyncio
import threading

import httpx
import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, MultiPolygon, Point, Polygon, box

import rnsca_client
from rnsca_client import AsyncClient, BatchError, Client, ClipResult, Retry
from tests.geoarrow_tables import decode, table
from tests.geometry_checks import assert_matches_shapely, shapely_can_judge
from tests.missing import missing
from tests.property.geometry_strategies import cases

try:
    import geopandas
except ImportError:  # pragma: no cover - the dev extra installs it
    geopandas = None

pytestmark = pytest.mark.e2e

WINDOW = (0.0, 0.0, 10.0, 10.0)
HOLED = Polygon([(-5, -5), (6, -5), (6, 6), (-5, 6)], [[(1, 1), (3, 1), (3, 3), (1, 3)]])
#: Two polygons and a line across the window, one polygon wholly outside, one inside.
GEOMETRIES = [
    HOLED,
    MultiPolygon([box(-2, -2, 2, 2), box(8, 8, 12, 12)]),
    box(20, 20, 30, 30),                      # outside: dropped
    LineString([(-5, 1), (5, 1), (5, 20), (8, 20), (8, 5), (15, 5)]),  # two parts
    box(2, 2, 4, 4),                          # inside: unchanged
]
KEPT = [0, 1, 3, 4]
VIAS = ["geoarrow", "geojson"]


@pytest.fixture
def gpd():
    if geopandas is None:
        missing("geopandas is not installed (pip install './clients/python[geopandas]')")
    return geopandas


def frame(gpd, geometries=GEOMETRIES, crs="EPSG:3857"):
    n = len(geometries)
    return gpd.GeoDataFrame(
        {"name": [f"feature {i}" for i in range(n)], "value": np.arange(n) * 1.5,
         "when": np.arange(n).astype("datetime64[D]")},
        geometry=list(geometries), index=[f"id-{i}" for i in range(n)], crs=crs)


def expected(geometries, window=WINDOW):
    return [shapely.intersection(g, box(*window)) for g in geometries]


def assert_same_geometries(got, want, tolerance=1e-9):
    got, want = list(got), list(want)
    assert len(got) == len(want)
    for i, (ours, theirs) in enumerate(zip(got, want, strict=True)):
        if theirs is None:
            assert ours is None, i
            continue
        assert ours.geom_type == theirs.geom_type, (i, ours.wkt, theirs.wkt)
        assert shapely.equals_exact(shapely.normalize(ours), shapely.normalize(theirs),
                                    tolerance=tolerance), (i, ours.wkt, theirs.wkt)


# --- GeoPandas ----------------------------------------------------------------------------


@pytest.mark.parametrize("via", VIAS)
def test_geodataframe_keeps_properties_index_and_crs(client, gpd, via):
    given_frame = frame(gpd)
    result = client.clip(given_frame, WINDOW, via=via, verify=True)
    assert isinstance(result, ClipResult) and result.via == via
    out = result.data
    assert isinstance(out, gpd.GeoDataFrame)
    assert out.index.tolist() == [f"id-{i}" for i in KEPT]
    assert result.rows.tolist() == KEPT and len(result) == 4
    assert out.crs == given_frame.crs and out.geometry.name == "geometry"
    assert list(out.columns) == list(given_frame.columns)
    assert out["name"].tolist() == [f"feature {i}" for i in KEPT]
    assert out["value"].tolist() == [i * 1.5 for i in KEPT]
    assert (out["when"].to_numpy() == given_frame["when"].to_numpy()[KEPT]).all()
    assert_same_geometries(out.geometry, expected([GEOMETRIES[i] for i in KEPT]))
    # GeoArrow: one request for the polygons, one for the line (a column holds one family).
    assert result.passed and result.requests == (2 if via == "geoarrow" else 1)
    assert result.stats.geometries_in == 5
    assert given_frame.geometry.iloc[0].equals(HOLED)   # the input is left as it was


def test_both_ways_give_the_same_frame(client, gpd):
    given_frame = frame(gpd)
    arrow = client.clip(given_frame, WINDOW).data
    json = client.clip(given_frame, WINDOW, via="geojson").data
    assert client.clip(given_frame, WINDOW).via == rnsca_client.clipping.DEFAULT_VIA
    assert arrow.index.equals(json.index)
    assert_same_geometries(arrow.geometry, json.geometry)


@pytest.mark.parametrize("via", VIAS)
def test_keep_empty_keeps_every_row_and_missing_stays_missing(client, gpd, via):
    given_frame = frame(gpd, [*GEOMETRIES, None])
    out = client.clip(given_frame, WINDOW, via=via, keep_empty=True).data
    assert out.index.equals(given_frame.index)
    assert out.geometry.iloc[2].is_empty and out.geometry.iloc[5] is None
    assert_same_geometries(out.geometry.iloc[[0, 1, 3, 4]],
                           expected([GEOMETRIES[i] for i in KEPT]))
    dropped = client.clip(given_frame, WINDOW, via=via).data
    assert dropped.index.tolist() == [f"id-{i}" for i in KEPT]


def test_a_named_geometry_column_and_duplicate_labels(client, gpd):
    given_frame = frame(gpd).rename_geometry("shape")
    given_frame.index = ["a", "a", "b", "b", "c"]
    given_frame["other"] = gpd.GeoSeries([Point(0, 0)] * 5, index=given_frame.index)
    out = client.clip(given_frame, WINDOW).data
    assert out.geometry.name == "shape" and out.index.tolist() == ["a", "a", "b", "c"]
    assert out["other"].tolist() == [Point(0, 0)] * 4          # not clipped
    by_other = client.clip(given_frame, (5, 5, 10, 10), column="other").data
    assert by_other.empty                      # (0, 0) is outside the window


@pytest.mark.parametrize("via", VIAS)
def test_geoseries_keeps_name_index_and_crs(client, gpd, via):
    series = gpd.GeoSeries(GEOMETRIES, index=[10, 20, 30, 40, 50], crs=4326, name="geom")
    out = client.clip(series, WINDOW, via=via).data
    assert isinstance(out, gpd.GeoSeries)
    assert out.index.tolist() == [10, 20, 40, 50] and out.name == "geom"
    assert out.crs == series.crs
    assert_same_geometries(out, expected([GEOMETRIES[i] for i in KEPT]))


def test_points_and_3d_geometries(client, gpd):
    points = gpd.GeoSeries([Point(1, 1), Point(20, 20), Point(5, 5, 7)], crs=4326)
    out = client.clip(points, WINDOW).data
    assert out.index.tolist() == [0, 2]
    assert out.iloc[1].has_z and out.iloc[1].z == 7
    lines = [LineString([(-5, 5, 0), (15, 5, 20)]), LineString([(1, 1, 1), (2, 2, 2)])]
    clipped = client.clip(lines, WINDOW).data
    assert [g.has_z for g in clipped] == [True, True]
    assert shapely.get_coordinates(clipped[0], include_z=True).tolist() == [
        [0.0, 5.0, 5.0], [10.0, 5.0, 15.0]]
    mixed = client.clip([LineString([(-5, 5), (15, 5)]), lines[0]], WINDOW).data  # WKB
    assert [g.has_z for g in mixed] == [False, True]


def test_geometry_collections_go_as_geojson_and_missing_ones_need_no_request(client, gpd):
    collection = shapely.GeometryCollection([Point(1, 1), box(-1, -1, 2, 2)])
    series = gpd.GeoSeries([box(1, 1, 2, 2), collection, None], index=list("abc"))
    result = client.clip(series, WINDOW)                 # polygons: GeoArrow; the rest: JSON
    assert result.requests == 2 and result.data.index.tolist() == ["a", "b"]
    assert_same_geometries(result.data, [box(1, 1, 2, 2), shapely.GeometryCollection(
        [Point(1, 1), box(0, 0, 2, 2)])])
    nothing = gpd.GeoSeries([None, None], crs=4326)
    for via in VIAS:
        assert client.clip(nothing, WINDOW, via=via).data.empty
        kept = client.clip(nothing, WINDOW, via=via, keep_empty=True)
        assert kept.data.tolist() == [None, None] and kept.data.crs == nothing.crs
    assert client.clip(nothing, WINDOW).requests == 0      # nothing to clip: not sent


# --- Shapely lists and arrays -------------------------------------------------------------


@pytest.mark.parametrize("via", VIAS)
def test_a_list_of_shapely_geometries_gives_a_list(client, via):
    result = client.clip([*GEOMETRIES, None], WINDOW, via=via)
    assert isinstance(result.data, list) and result.rows.tolist() == KEPT
    assert_same_geometries(result.data, expected([GEOMETRIES[i] for i in KEPT]))
    as_tuple = client.clip(tuple(GEOMETRIES), WINDOW, via=via).data
    assert isinstance(as_tuple, tuple) and len(as_tuple) == 4


@pytest.mark.parametrize("via", VIAS)
def test_a_shapely_array_gives_an_array(client, via):
    array = np.array(GEOMETRIES, dtype=object)
    result = client.clip(array, WINDOW, via=via, keep_empty=True)
    assert isinstance(result.data, np.ndarray) and result.data.dtype == object
    assert result.rows.tolist() == [0, 1, 2, 3, 4]
    assert result.data[2].is_empty
    assert_same_geometries(result.data[KEPT], expected([GEOMETRIES[i] for i in KEPT]))


def test_an_empty_collection_sends_nothing(client, gpd):
    result = client.clip([], WINDOW)
    assert result.data == [] and result.requests == 0 and result.passed is None
    assert result.stats.geometries_in == 0
    empty = frame(gpd).iloc[:0]
    assert client.clip(empty, WINDOW).data.columns.tolist() == empty.columns.tolist()


def test_clip_geojson_takes_a_list_of_shapely_geometries(client):
    result = client.clip_geojson([*GEOMETRIES, None], WINDOW)
    features = result.geojson["features"]
    assert [f["id"] for f in features] == KEPT          # ids are the positions
    assert_same_geometries(result.to_shapely(), expected([GEOMETRIES[i] for i in KEPT]))
    kept_all = client.clip_geojson(np.array(GEOMETRIES), WINDOW, keep_empty=True)
    assert [f["id"] for f in kept_all.geojson["features"]] == [0, 1, 2, 3, 4]


# --- pyarrow tables -----------------------------------------------------------------------


@pytest.mark.parametrize("encoding", ["separated", "interleaved", "wkb"])
def test_a_geoarrow_table_gives_a_table(client, encoding):
    polygons = [HOLED, box(20, 20, 30, 30), box(2, 2, 4, 4)]
    sent = table(polygons, "polygon", encoding, False)
    result = client.clip(sent, WINDOW)
    got = result.data
    assert got.schema.names == sent.schema.names
    assert got.column("name").to_pylist() == ["row 0", "row 2"]
    field = got.schema.field("geometry")
    assert field.metadata[b"ARROW:extension:name"] == (
        b"geoarrow.wkb" if encoding == "wkb" else b"geoarrow.multipolygon")
    assert_same_geometries([shapely.normalize(g) for g in decode(got.column("geometry"),
                                                                 field)],
                           [shapely.normalize(shapely.MultiPolygon([g]) if encoding != "wkb"
                                              else g) for g in expected(polygons[::2])])
    batch = client.clip(sent.to_batches()[0], WINDOW).data
    assert type(batch).__name__ == "RecordBatch" and batch.num_rows == 2


# --- refused before sending ---------------------------------------------------------------


def test_what_clip_refuses_before_sending(client, gpd):
    with pytest.raises(rnsca_client.InvalidInputError, match="clip_geojson"):
        client.clip({"type": "Point", "coordinates": [1, 2]}, WINDOW)
    with pytest.raises(rnsca_client.InvalidInputError, match="item 1 is not a Shapely"):
        client.clip([Point(0, 0), "POINT (1 1)"], WINDOW)
    with pytest.raises(rnsca_client.InvalidInputError, match="via must be"):
        client.clip([Point(0, 0)], WINDOW, via="wkt")
    with pytest.raises(rnsca_client.InvalidInputError, match="via='geoarrow'"):
        client.clip(table([HOLED], "polygon", "wkb", False), WINDOW, via="geojson")
    with pytest.raises(rnsca_client.InvalidInputError, match="no geometry column 'nope'"):
        client.clip(frame(gpd), WINDOW, column="nope")
    with pytest.raises(rnsca_client.InvalidInputError, match="NaN"):
        client.clip([Point(np.nan, 1)], WINDOW, via="geojson")
    with pytest.raises(rnsca_client.InvalidInputError, match="batch_size"):
        client.clip_many([Point(0, 0)], WINDOW, batch_size=0)
    with pytest.raises(rnsca_client.InvalidInputError, match="concurrency"):
        client.clip_many([Point(0, 0)], WINDOW, concurrency=0)


def test_a_servers_error_names_the_row_of_the_input(client):
    geometries = [box(1, 1, 2, 2), LineString([(0, 0), (np.inf, 1)])]
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip(geometries, WINDOW, via="geoarrow")
    assert info.value.path == "geometry[0]" and info.value.row == 1   # lines: a request
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip([box(1, 1, 2, 2), Point(1, 1), box(20, 20, 21, 21), box(0, 0, np.inf, 1)],
                    WINDOW)
    assert info.value.path == "geometry[2]" and info.value.row == 3


# --- clip_many ----------------------------------------------------------------------------


def many_geometries(n: int, seed: int = 5) -> list:
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-10, 20, (n, 2))
    sizes = rng.uniform(0.5, 6, n)
    return [box(x - s, y - s, x + s, y + s) if i % 3 else
            LineString([(x - s, y), (x + s, y + s)]).buffer(0.3)
            for i, ((x, y), s) in enumerate(zip(centres, sizes, strict=True))]


@pytest.mark.parametrize("via", VIAS)
def test_clip_many_equals_one_request_and_keeps_order(client, gpd, via):
    given_frame = frame(gpd, many_geometries(97))
    one = client.clip(given_frame, WINDOW, via=via, verify=True)
    many = client.clip_many(given_frame, WINDOW, batch_size=10, concurrency=3, via=via,
                            verify=True)
    assert many.requests == 10 and many.passed
    assert many.data.index.equals(one.data.index) and many.rows.tolist() == one.rows.tolist()
    assert many.data.drop(columns="geometry").equals(one.data.drop(columns="geometry"))
    assert_same_geometries(many.data.geometry, one.data.geometry)
    assert many.stats.geometries_in == one.stats.geometries_in == 97
    assert many.stats.vertices_out == one.stats.vertices_out
    assert many.data.crs == given_frame.crs


def test_clip_many_of_a_list_of_items_equals_each_call(client, gpd):
    geometries = many_geometries(30)
    items = [frame(gpd, geometries[:12]), geometries[12:20],
             table([HOLED, box(2, 2, 4, 4)], "polygon", "interleaved", False),
             {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]},
             np.array(geometries[20:], dtype=object)]
    results = client.clip_many(items, WINDOW, batch_size=5, concurrency=4)
    assert len(results) == len(items)
    for item, result in zip(items, results, strict=True):
        if isinstance(item, dict):
            assert result.geojson == client.clip_geojson(item, WINDOW).geojson
            continue
        alone = client.clip(item, WINDOW)
        assert result.rows.tolist() == alone.rows.tolist()
        assert type(result.data) is type(alone.data)
    assert results[0].requests == 3 and results[1].requests == 2
    assert results[0].data.index.equals(client.clip(items[0], WINDOW).data.index)
    assert_same_geometries(results[1].data, client.clip(items[1], WINDOW).data)
    assert results[2].data.equals(client.clip(items[2], WINDOW).data)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
def test_clip_many_names_the_failed_batch_and_row(client):
    geometries = many_geometries(40)
    geometries[23] = Polygon([(0, 0), (np.nan, 1), (1, 1), (0, 0)])
    with pytest.raises(BatchError) as info:
        client.clip_many(geometries, WINDOW, batch_size=10, concurrency=2)
    error = info.value
    assert (error.batch, error.item, error.start, error.stop, error.row) == (2, None, 20, 30,
                                                                             23)
    assert isinstance(error.error, rnsca_client.InvalidRequestError)
    assert error.__cause__ is error.error and error.error.path == "geometry[3]"
    assert error.error.row == 23 and error.others == []
    assert "request 2 (rows 20:30, row 23) failed: InvalidRequestError" in str(error)
    assert isinstance(error, rnsca_client.RnscaClientError)
    # A line among polygons goes in a request of its own (a GeoArrow column holds one
    # family): the row named is still the row of the input.
    geometries[23] = LineString([(0, 0), (np.nan, 1)])
    with pytest.raises(BatchError) as info:
        client.clip_many(geometries, WINDOW, batch_size=10, concurrency=2)
    assert (info.value.start, info.value.row, info.value.error.path) == (20, 23,
                                                                         "geometry[0]")


def test_clip_many_names_the_failed_item(client):
    items = [[box(1, 1, 2, 2)], {"type": "LineString", "coordinates": [[0, 0]]}]
    with pytest.raises(BatchError) as info:
        client.clip_many(items, WINDOW)
    assert info.value.item == 1 and info.value.batch == 1 and info.value.start is None
    assert info.value.error.status == 422
    assert "request 1 (item 1) failed" in str(info.value)


def test_clip_many_retries_each_batch_as_the_client_does(server):
    """Every batch's first try answers 503: each is retried, and all come back."""
    forward = httpx.Client(base_url=server.url, timeout=120)
    seen: dict[bytes, int] = {}
    lock = threading.Lock()

    def handler(request: httpx.Request) -> httpx.Response:
        body = request.read()
        with lock:
            seen[body] = seen.get(body, 0) + 1
            first = seen[body] == 1
        if first:
            return httpx.Response(503, headers={"Retry-After": "0"}, json={
                "type": "urn:rnsca:problem:time-limit", "status": 503, "title": "Busy"})
        answer = forward.request(request.method, request.url.path, content=body,
                                 params=request.url.params, headers=request.headers)
        headers = {k: v for k, v in answer.headers.items()
                   if k not in ("content-encoding", "content-length", "transfer-encoding")}
        return httpx.Response(answer.status_code, headers=headers, content=answer.content)

    retry = Retry(attempts=2, backoff=0.01, jitter=0.0)
    geometries = many_geometries(25)
    with forward, Client("http://rnsca.test", transport=httpx.MockTransport(handler),
                         retries=retry) as client:
        result = client.clip_many(geometries, WINDOW, batch_size=5, concurrency=3)
    assert result.requests == 5 and sorted(seen.values()) == [2] * 5
    with Client(server.url, retries=None) as direct:
        assert result.rows.tolist() == direct.clip(geometries, WINDOW).rows.tolist()
    with Client("http://rnsca.test", transport=httpx.MockTransport(handler),
                retries=None) as no_retry, pytest.raises(BatchError) as info:
        no_retry.clip_many(many_geometries(3, seed=9), WINDOW, batch_size=1)
    assert isinstance(info.value.error, rnsca_client.ServiceUnavailableError)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
def test_async_clip_and_clip_many(server, gpd):
    given_frame = frame(gpd, many_geometries(33))

    async def run():
        async with AsyncClient(server.url, retries=None) as client:
            one = await client.clip(given_frame, WINDOW)
            many = await client.clip_many(given_frame, WINDOW, batch_size=4, concurrency=3)
            listed = await client.clip_many([GEOMETRIES, given_frame], WINDOW)
            bad = many_geometries(12)
            bad[7] = LineString([(0, 0), (np.nan, 1)])
            with pytest.raises(BatchError) as info:
                await client.clip_many(bad, WINDOW, batch_size=3, concurrency=2)
            return one, many, listed, info.value

    one, many, listed, error = asyncio.run(run())
    assert many.requests == 9 and many.data.index.equals(one.data.index)
    assert_same_geometries(many.data.geometry, one.data.geometry)
    assert listed[0].rows.tolist() == KEPT and listed[1].data.index.equals(one.data.index)
    assert (error.batch, error.start, error.row) == (2, 6, 7)


# --- against Shapely, drawn -----------------------------------------------------------------


KINDS = ["point", "multipoint", "linestring", "multilinestring", "polygon", "multipolygon"]


@pytest.mark.parametrize("via", VIAS)
@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_each_geometry_equals_shapely(client, via, data):
    """Geometries of one kind, or two (GeoArrow: a request per family), and a None."""
    kind = data.draw(st.sampled_from(KINDS), label="kind")
    geometries, window = data.draw(cases(kind, z=None), label="case")
    if data.draw(st.booleans(), label="two kinds"):
        other = data.draw(st.sampled_from(KINDS), label="other kind")
        more, _ = data.draw(cases(other, z=None), label="other case")
        geometries = [*geometries, *more]
    assume(shapely_can_judge(geometries, window, "closed"))
    keep_empty = data.draw(st.booleans(), label="keep_empty")
    position = data.draw(st.integers(0, len(geometries)), label="None at")
    rows = [*geometries[:position], None, *geometries[position:]]
    result = client.clip(rows, window.bounds, via=via, keep_empty=keep_empty, verify=False)
    assert len(result.data) == len(result.rows)
    out = dict(zip(result.rows.tolist(), result.data, strict=True))
    for row, geometry in enumerate(rows):
        if geometry is None:
            assert (out[row] is None) if keep_empty else row not in out
            continue
        ours = out.get(row)
        if keep_empty:
            assert ours is not None
        else:
            assert ours is None or not ours.is_empty
            ours = shapely.GeometryCollection() if ours is None else ours
        assert_matches_shapely(ours, geometry, window, "closed", where=f"row {row}")


# --- the README, and what goes on the wire ------------------------------------------------


def readme_block(text: str, first_line: str) -> str:
    start = text.index(first_line)
    return text[start:text.index("```", start)]


def test_the_readme_geopandas_examples_run_as_written(server, gpd):
    from tests.e2e.server import ROOT

    top = (ROOT / "README.md").read_text()
    top = top[top.index("## Python client (SDK)"):]
    scope: dict = {}
    exec(readme_block(top, "import geopandas\n").replace("http://127.0.0.1:8000", server.url),
         scope)  # noqa: S102 - our own README
    assert scope["clipped"].index.tolist() == ["p1", "r7"] and scope["result"].verification
    text = (ROOT / "clients/python/README.md").read_text()
    scope: dict = {}
    for first_line in ("import geopandas\n", "from rnsca_client import BatchError\n"):
        code = readme_block(text, first_line).replace("http://127.0.0.1:8000", server.url)
        exec(code, scope)  # noqa: S102 - our own README
    clipped = scope["clipped"]
    assert clipped.index.tolist() == ["p1", "r7"] and clipped.crs == "EPSG:3857"
    assert clipped.geometry.iloc[1].geom_type == "MultiLineString"
    assert scope["result"].rows.tolist() == [0, 1]
    assert [type(r).__name__ for r in scope["by_item"]] == ["ClipResult", "ClipResult",
                                                            "GeoJSONResult"]


def test_binary_answers_are_asked_for_uncompressed():
    seen = []

    def handler(request: httpx.Request) -> httpx.Response:
        seen.append((request.url.path, request.headers.get("accept-encoding")))
        return httpx.Response(422, json={"status": 422, "title": "Invalid", "detail": "x"})

    with Client("http://rnsca.test", transport=httpx.MockTransport(handler),
                retries=None) as client:
        for call in (lambda: client.clip([box(1, 1, 2, 2)], WINDOW),
                     lambda: client.clip_segments(np.zeros((1, 4)), WINDOW),
                     lambda: client.clip([box(1, 1, 2, 2)], WINDOW, via="geojson")):
            with pytest.raises(rnsca_client.InvalidRequestError):
                call()
    assert seen[:2] == [("/v1/clip/geoarrow", "identity"), ("/v1/clip/segments", "identity")]
    assert seen[2][0] == "/v1/clip/geojson" and "gzip" in seen[2][1]   # JSON: httpx's default
