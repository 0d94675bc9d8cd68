"""POST /v1/clip/geojson-seq: streamed GeoJSON in, clipped records streamed out.

The oracles: the non-streaming ``/v1/clip/geojson`` answer for the same features (one
FeatureCollection), and Shapely's intersection of each input with the window. Bodies are
sent in pieces through httpx's ASGI transport (each piece one ASGI message, as the
network delivers them), cut anywhere, records split across pieces.
"""

from __future__ import annotations

import asyncio
import gzip
import tracemalloc

import httpx
import orjson
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from service import Settings, create_app
from service.middleware import INFLATED_PIECE_BYTES, _inflating_in_pieces
from service.routes import clip as clip_routes
from service.streaming import SUMMARY_TYPE, Spool
from tests.geometry_checks import assert_matches_shapely, shapely_can_judge
from tests.property.geometry_strategies import KINDS, cases

RS = b"\x1e"
SEQ = "application/geo+json-seq"
NDJSON = "application/x-ndjson"
PROBLEM = "application/problem+json"
WINDOW = {"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10}
BOX = shapely.box(0, 0, 10, 10)


def features(n: int, start: int = 0) -> list[dict]:
    """Lines, polygons and points around the window: some inside, crossing, outside."""
    out = []
    for i in range(start, start + n):
        x = (i * 7) % 23 - 6.5
        y = (i * 5) % 19 - 4.5
        kind = i % 3
        if kind == 0:
            geometry = {"type": "LineString", "coordinates": [[x, y], [x + 8, y + 3],
                                                              [x + 2, y + 9]]}
        elif kind == 1:
            geometry = {"type": "Polygon", "coordinates": [[[x, y], [x + 6, y], [x + 6, y + 6],
                                                            [x, y + 6], [x, y]]]}
        else:
            geometry = {"type": "MultiPoint", "coordinates": [[x, y], [x + 3, y + 3]]}
        out.append({"type": "Feature", "id": i, "properties": {"i": i, "name": f"f{i}"},
                    "geometry": geometry})
    return out


def framed(records, media: str = SEQ) -> bytes:
    if media == SEQ:
        return b"".join(RS + orjson.dumps(r) + b"\n" for r in records)
    return b"".join(orjson.dumps(r) + b"\n" for r in records)


def records_of(body: bytes, media: str) -> list:
    if media == SEQ:
        assert body == b"" or body.startswith(RS), body[:50]
        texts = body.split(RS)[1:]
        assert all(t.endswith(b"\n") for t in texts)
    else:
        texts = body.splitlines()
    return [orjson.loads(t) for t in texts]


def assert_problem(r, status: int, slug: str, *words: str) -> dict:
    assert r.status_code == status, r.text
    assert r.headers["content-type"] == PROBLEM
    body = r.json()
    assert body["type"] == f"urn:rnsca:problem:{slug}", body
    for word in words:
        assert word in body["detail"], body
    return body


def stream_app(**settings):
    """An app with small chunks (a few records), compiled on first use."""
    options = dict(warm_up=False, stream_chunk_records=7, stream_chunk_bytes=4096,
                   stream_max_record_bytes=16 << 10, max_body_bytes=50_000)
    return create_app(Settings(**{**options, **settings}))


@pytest.fixture(scope="module")
def app():
    return stream_app()


def post_pieces(app, pieces, media: str = SEQ, accept: str | None = None, **params):
    """POST `pieces` (each one ASGI message); return (status, headers, body)."""

    async def run():
        async def body():
            for piece in pieces:
                yield piece

        headers = {"Content-Type": media, "Accept-Encoding": "identity"}
        if accept is not None:
            headers["Accept"] = accept
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://test") as client:
            r = await client.post("/v1/clip/geojson-seq", content=body(),
                                  params={**WINDOW, **params}, headers=headers)
            return r.status_code, r.headers, r.content

    return asyncio.run(run())


def expected_features(client, records) -> list:
    """The non-streaming endpoint's answer for the same features."""
    r = client.post("/v1/clip/geojson", json={
        "window": [0, 0, 10, 10], "geojson": {"type": "FeatureCollection",
                                              "features": records}, "verify": False})
    assert r.status_code == 200, r.text
    return r.json()["geojson"]["features"]


# --- answers -------------------------------------------------------------------------


@pytest.mark.parametrize("media", [SEQ, NDJSON])
def test_the_answer_is_the_geojson_endpoints_and_shapelys(client, media):
    records = features(60)
    r = client.post("/v1/clip/geojson-seq", content=framed(records, media), params=WINDOW,
                    headers={"Content-Type": media})
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == media
    got = records_of(r.content, media)
    assert got == expected_features(client, records)
    by_id = {f["id"]: f for f in records}
    assert [f["id"] for f in got] == sorted(f["id"] for f in got)  # input order
    for feature in got:
        source = by_id[feature["id"]]
        assert feature["properties"] == source["properties"]
        assert_matches_shapely(shapely.geometry.shape(feature["geometry"]),
                               shapely.geometry.shape(source["geometry"]), (0, 0, 10, 10),
                               "closed", where=f"feature {feature['id']}")
    kept = {f["id"] for f in got}
    for feature in records:  # dropped: nothing of its dimension in the window
        if feature["id"] not in kept:
            geometry = shapely.geometry.shape(feature["geometry"])
            inside = shapely.intersection(geometry, BOX)
            assert inside.is_empty or shapely.get_dimensions(inside) < \
                shapely.get_dimensions(geometry)


def test_records_split_across_network_pieces_anywhere(app, client):
    records = features(40)
    body = framed(records)
    expected = expected_features(client, records)
    for step in (1, 5, 13, 64, 1000):
        pieces = [body[k:k + step] for k in range(0, len(body), step)]
        status, headers, answer = post_pieces(app, pieces)
        assert status == 200, answer
        assert records_of(answer, SEQ) == expected, step


def test_accept_chooses_the_answers_framing(app):
    records = features(9)
    status, headers, answer = post_pieces(app, [framed(records, NDJSON)], media=NDJSON,
                                          accept=f"text/html, {SEQ};q=0.9")
    assert status == 200 and headers["content-type"] == SEQ
    same = post_pieces(app, [framed(records)], accept="*/*")
    assert same[1]["content-type"] == SEQ and records_of(same[2], SEQ) == records_of(
        answer, SEQ)
    lines = post_pieces(app, [framed(records)], accept="application/jsonl")
    assert lines[1]["content-type"] == "application/jsonl"
    assert records_of(lines[2], NDJSON) == records_of(answer, SEQ)


def test_geometries_and_feature_collections_keep_their_kind(app):
    line = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
    collection = {"type": "FeatureCollection", "name": "c", "features": features(6)}
    status, _, answer = post_pieces(app, [framed([line, collection, line])])
    assert status == 200
    first, middle, last = records_of(answer, SEQ)
    assert first == last == {"type": "LineString", "coordinates": [[0.0, 5.0], [10.0, 5.0]]}
    assert middle["type"] == "FeatureCollection" and middle["name"] == "c"


def test_keep_empty_keeps_every_record(app):
    records = features(12)
    status, _, kept = post_pieces(app, [framed(records)], keep_empty="true")
    _, _, dropped = post_pieces(app, [framed(records)])
    assert [f["id"] for f in records_of(kept, SEQ)] == list(range(12))
    assert len(records_of(dropped, SEQ)) < 12


def test_options_are_query_parameters(app):
    line = {"type": "LineString", "coordinates": [[0, 5], [10, 5]]}  # on no edge
    edge = {"type": "LineString", "coordinates": [[0, 10], [10, 10]]}  # along the top edge
    status, _, closed = post_pieces(app, [framed([line, edge])])
    assert len(records_of(closed, SEQ)) == 2
    status, _, interior = post_pieces(app, [framed([line, edge])], boundary="interior",
                                      method="liang_barsky")
    assert status == 200 and len(records_of(interior, SEQ)) == 1


def test_the_summary_record_ends_the_answer(app):
    records = features(30)
    status, _, answer = post_pieces(app, [framed(records)], summary="true")
    *clipped, summary = records_of(answer, SEQ)
    assert summary["type"] == SUMMARY_TYPE
    assert summary["records_in"] == 30 and summary["records_out"] == len(clipped)
    assert summary["chunks"] >= 30 // 7
    assert summary["stats"]["geometries_in"] == 30


@pytest.mark.parametrize("body", [b"", b"\n\n  \r\n", RS + RS + b"\n"])
def test_an_empty_sequence_is_an_empty_answer(app, body):
    status, headers, answer = post_pieces(app, [body])
    assert status == 200 and answer == b""


def test_an_empty_body_still_checks_the_window():
    status, headers, answer = post_pieces(stream_app(), [b""], xmin=20)
    assert status == 422 and orjson.loads(answer)["type"].endswith("invalid-window")


# --- errors --------------------------------------------------------------------------


def test_a_bad_record_in_the_first_chunk_is_a_problem_naming_it(client):
    records = [framed([f]) for f in features(5)]
    records[3] = RS + b'{"type": "Feature", "geometry": {"type": "Point", "coordinates":' \
                      b' [1, 2]}, oops}\n'
    r = client.post("/v1/clip/geojson-seq", content=b"".join(records), params=WINDOW,
                    headers={"Content-Type": SEQ})
    body = assert_problem(r, 422, "parse-error", "record 3 is not valid JSON")
    assert body["record"] == 3 and body["position"] > 0


@pytest.mark.parametrize("record, slug, path, words", [
    ({"type": "Topology", "objects": {}}, "invalid-geometry", "", "got type 'Topology'"),
    ([1, 2], "invalid-geometry", "", "got a JSON list"),
    ({"type": "Feature", "properties": {}, "geometry": {
        "type": "LineString", "coordinates": [[0, 0], [1, "2"]]}}, "invalid-geometry",
     "geometry.coordinates[1][1]", "expected a number"),
    ({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0.5]]]},
     "invalid-geometry", "coordinates[0]", "not closed"),
])
def test_an_invalid_record_is_422_with_its_number_and_path(client, record, slug, path, words):
    body = framed(features(2) + [record] + features(2, start=2), NDJSON)
    r = client.post("/v1/clip/geojson-seq", content=body, params=WINDOW,
                    headers={"Content-Type": NDJSON})
    problem = assert_problem(r, 422, slug, "record 2", words)
    assert problem["record"] == 2 and problem["path"] == path


def test_a_record_over_the_length_limit_is_413(app):
    long = {"type": "Feature", "properties": {"pad": "x" * (20 << 10)},
            "geometry": None}
    status, headers, answer = post_pieces(app, [framed(features(2) + [long])])
    assert status == 413, answer
    problem = orjson.loads(answer)
    assert problem["type"].endswith("limit-exceeded") and problem["record"] == 2
    assert headers["connection"] == "close"  # the rest of the body is not read


def test_a_body_not_starting_with_rs_is_refused_as_a_sequence(app):
    status, _, answer = post_pieces(app, [framed(features(3), NDJSON)], media=SEQ)
    assert status == 422 and "RS (0x1E)" in orjson.loads(answer)["detail"]


def test_media_type_window_and_parameters_are_checked(client):
    body = framed(features(3))
    r = client.post("/v1/clip/geojson-seq", content=body, params=WINDOW,
                    headers={"Content-Type": "application/json"})
    assert_problem(r, 415, "unsupported-media-type", SEQ, NDJSON)
    r = client.post("/v1/clip/geojson-seq", content=body, params={"xmin": 0},
                    headers={"Content-Type": SEQ})
    assert assert_problem(r, 422, "invalid-request")["path"] == "query.ymin"
    r = client.post("/v1/clip/geojson-seq", content=body, params={**WINDOW, "verify": "true"},
                    headers={"Content-Type": SEQ})
    assert_problem(r, 422, "invalid-request", "verify")
    r = client.post("/v1/clip/geojson-seq", content=body, params={**WINDOW, "mode": "approx"},
                    headers={"Content-Type": SEQ})  # polygons need exact mode
    assert r.status_code == 422, r.text


def test_a_problem_after_the_answer_started_ends_it_with_a_problem_record(app, client):
    good = features(30)
    bad = RS + b'{"type": "Feature", "properties": {}, "geometry": {"type": "Point", ' \
               b'"coordinates": [1, NaN]}}\n'
    # Records 0..22 good, 23 bad (in the fourth chunk of 7), then more good ones.
    body = framed(good[:23]) + bad + framed(good[23:])
    status, headers, answer = post_pieces(app, [body[k:k + 100]
                                                for k in range(0, len(body), 100)])
    assert status == 200
    *clipped, last = records_of(answer, SEQ)
    assert clipped == expected_features(client, good[:23])  # all before it, none after
    assert last["type"] == "urn:rnsca:problem:parse-error" and last["status"] == 422
    assert last["record"] == 23 and "record 23" in last["detail"]
    assert last["instance"] == "/v1/clip/geojson-seq"


def test_a_record_too_long_after_the_answer_started_ends_it_too(app, client):
    long = {"type": "Feature", "properties": {"pad": "x" * (20 << 10)}, "geometry": None}
    status, _, answer = post_pieces(app, [framed(features(20) + [long] + features(3))])
    assert status == 200
    *clipped, last = records_of(answer, SEQ)
    assert clipped == expected_features(client, features(20))
    assert last["type"].endswith("limit-exceeded") and last["record"] == 20


# --- limits and memory ---------------------------------------------------------------


def test_the_json_body_limit_does_not_apply_to_a_stream(app):
    records = features(600)
    body = framed(records)
    assert len(body) > 50_000  # the app's max_body_bytes
    status, _, answer = post_pieces(app, [body[k:k + 8192] for k in range(0, len(body), 8192)],
                                    summary="true")
    assert status == 200
    *clipped, summary = records_of(answer, SEQ)
    assert summary["records_in"] == 600 and clipped[-1]["id"] == 599


def test_a_gzip_stream_is_inflated_in_pieces(app):
    records = features(50)
    status, _, answer = post_pieces(app, [framed(records)])

    async def run():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://test") as client:
            return await client.post(
                "/v1/clip/geojson-seq", content=gzip.compress(framed(records)), params=WINDOW,
                headers={"Content-Type": SEQ, "Content-Encoding": "gzip"})

    r = asyncio.run(run())
    assert r.status_code == 200 and r.content == answer


def test_a_highly_compressed_body_reaches_the_endpoint_in_bounded_pieces():
    inflated = b"\n" * (5 * INFLATED_PIECE_BYTES + 123)
    compressed = gzip.compress(inflated) + gzip.compress(b"{}\n")  # two gzip members
    messages = [{"type": "http.request", "body": compressed[:40], "more_body": True},
                {"type": "http.request", "body": compressed[40:], "more_body": False}]

    async def receive():
        return messages.pop(0)

    async def read_all():
        pieces = []
        receive_inflated = _inflating_in_pieces(receive)
        while True:
            message = await receive_inflated()
            pieces.append(message["body"])
            if not message["more_body"]:
                return pieces

    pieces = asyncio.run(read_all())
    assert max(map(len, pieces)) <= INFLATED_PIECE_BYTES
    assert b"".join(pieces) == inflated + b"{}\n"


def test_the_spool_keeps_order_and_moves_what_waits_to_a_file():
    async def run():
        spool = Spool(memory_bytes=100)
        blocks = [bytes([i]) * 60 for i in range(10)]
        for block in blocks:
            spool.put(block)
        # The first waits in memory; the next would pass 100 bytes: it and all after it
        # go to the file, read back in order.
        assert (spool.peak_memory, spool.spilled) == (60, 540)
        taken = []
        while sum(map(len, taken)) < 600:
            taken.append(await spool.get())
        assert b"".join(taken) == b"".join(blocks)
        assert spool._file is None  # read back whole: dropped
        spool.put(b"tail")
        spool.close()
        assert await spool.get() == b"tail" and spool.spilled == 540
        assert await spool.get() is None

    asyncio.run(run())


def _lines(n: int, inside_every: int):
    """`n` NDJSON features, one in `inside_every` crossing the window, the rest outside."""
    for i in range(n):
        y = 5.0 if i % inside_every == 0 else 50.0 + i % 7
        yield orjson.dumps({"type": "Feature", "id": i, "properties": {"n": i},
                            "geometry": {"type": "LineString",
                                         "coordinates": [[-5.0, y], [15.0, y + 0.25]]}}
                           ) + b"\n"


def test_a_large_stream_is_clipped_in_bounded_memory(monkeypatch):
    """200,000 features (about 26 MB) through the endpoint, holding a chunk at a time.

    Two measures: the largest chunk of record text the endpoint held (its own counter),
    and the peak of Python's traced allocations (tracemalloc: Python objects and NumPy
    arrays) over the whole request, against the body's size. The body is generated as
    it is sent and 1 feature in 100 is left after the clip, so neither the test's body nor
    the collected answer is large.
    """
    n, chunk_bytes = 200_000, 256 << 10
    app = stream_app(stream_chunk_bytes=chunk_bytes, stream_chunk_records=2000,
                     stream_max_record_bytes=64 << 10)
    made = []

    class Recorded(clip_routes.StreamedClip):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(clip_routes, "StreamedClip", Recorded)
    post_pieces(app, [next(_lines(1, 1))], media=NDJSON)  # compiled before measuring
    sent = 0

    def pieces():
        nonlocal sent
        batch = []
        for line in _lines(n, 100):
            batch.append(line)
            if len(batch) == 50:
                piece = b"".join(batch)
                sent += len(piece)
                batch = []
                yield piece
        yield b"".join(batch)

    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        status, _, answer = post_pieces(app, pieces(), media=NDJSON, summary="true")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert status == 200
    *clipped, summary = records_of(answer, NDJSON)
    assert summary["records_in"] == n and len(clipped) == n // 100
    assert [f["id"] for f in clipped] == list(range(0, n, 100))
    stream = made[-1]
    assert stream.records_in == n and stream.chunks >= sent // chunk_bytes
    assert stream.largest_chunk <= chunk_bytes
    assert sent > 24 << 20
    assert peak < sent / 4, (peak, sent)
    assert peak < 32 * chunk_bytes, (peak, sent)  # measured: 3.5 MB, 14 chunks


# --- random features -----------------------------------------------------------------


@settings(max_examples=20)
@given(case=st.sampled_from(sorted(KINDS)).flatmap(lambda kind: cases(kind, 4, z=None)),
       media=st.sampled_from([SEQ, NDJSON]))
def test_random_features_equal_the_geojson_endpoint_and_shapely(client, case, media):
    geometries, window = case
    records = [{"type": "Feature", "id": i, "properties": {"k": i},
                "geometry": shapely.geometry.mapping(g)} for i, g in enumerate(geometries)]
    body = framed(records, media)
    bounds = dict(zip(("xmin", "ymin", "xmax", "ymax"), window.bounds, strict=True))
    r = client.post("/v1/clip/geojson-seq", params=bounds, headers={"Content-Type": media},
                    content=body)
    assert r.status_code == 200, r.text
    got = records_of(r.content, media)
    whole = client.post("/v1/clip/geojson", json={
        "window": list(window.bounds), "verify": False,
        "geojson": {"type": "FeatureCollection", "features": records}})
    assert got == whole.json()["geojson"]["features"]
    if shapely_can_judge(geometries, window, "closed"):
        for feature in got:
            assert_matches_shapely(shapely.geometry.shape(feature["geometry"]),
                                   geometries[feature["id"]], window, "closed",
                                   where=f"feature {feature['id']}")


def test_capabilities_name_the_stream_limits():
    from fastapi.testclient import TestClient

    with TestClient(stream_app()) as client:
        limits = client.get("/v1/capabilities").json()["limits"]
    assert (limits["stream_chunk_records"], limits["stream_chunk_bytes"],
            limits["stream_max_record_bytes"]) == (7, 4096, 16 << 10)


def test_a_client_gone_while_the_answer_is_sent_stops_the_clip(app, caplog):
    """A server whose ``send`` raises OSError once the client is gone: the answer stops,
    the clip with it (the rest of the body is never read), and the app returns."""
    body = framed(features(100))
    messages = [{"type": "http.request", "body": body[i:i + 500],
                 "more_body": i + 500 < len(body)} for i in range(0, len(body), 500)]
    sent = []

    async def receive():
        return messages.pop(0)

    async def send(message):
        sent.append(message)
        if len(sent) == 3:
            raise OSError("connection reset")

    scope = {"type": "http", "asgi": {"version": "3.0", "spec_version": "2.3"},
             "http_version": "1.1", "method": "POST", "scheme": "http",
             "path": "/v1/clip/geojson-seq", "raw_path": b"/v1/clip/geojson-seq",
             "query_string": b"xmin=0&ymin=0&xmax=10&ymax=10", "root_path": "",
             "headers": [(b"content-type", SEQ.encode())], "client": ("127.0.0.1", 1),
             "server": ("test", 80)}
    asyncio.run(asyncio.wait_for(app(scope, receive, send), 30))
    assert [m["type"] for m in sent] == ["http.response.start"] + 2 * ["http.response.body"]
    assert messages, "the rest of the body was not read"
    assert "client disconnected during a streamed answer" in caplog.text
