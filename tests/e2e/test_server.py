"""The service through a real uvicorn server on a loopback port: every endpoint, every
error status, the binary form, gzip, concurrency and graceful shutdown."""

from __future__ import annotations

import gzip
import re
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import httpx
import numpy as np
import orjson
import pytest

from tests.cases import MIXED_DIMENSIONS, MIXED_DIMENSIONS_CLIPPED
from tests.e2e.server import LiveServer

pytestmark = pytest.mark.e2e

PROBLEM = "application/problem+json"
WINDOW = [0, 0, 10, 10]
LINE = {"type": "Feature", "id": 7, "properties": {"name": "road"},
        "geometry": {"type": "LineString",
                     "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5], [15, 5]]}}


@pytest.fixture(scope="module")
def server():
    with LiveServer(env={"RNSCA_CLIP_THREADS": "3", "RNSCA_MAX_BODY_BYTES": str(8 * 2**20),
                         "RNSCA_STREAM_CHUNK_BYTES": str(2**20),
                         "RNSCA_MAX_VERTICES": "400000",
                         "RNSCA_VERIFY_MAX_VERTICES": "1000"}) as live:
        yield live


@pytest.fixture(scope="module")
def client(server):
    with httpx.Client(base_url=server.url, timeout=60) as c:
        yield c


def crossing_segments(count: int, seed: int = 0) -> np.ndarray:
    """Long segments through the unit window (every one ambiguous: the costly case)."""
    a = np.random.default_rng(seed).uniform(-500, 500, (count, 2))
    return np.column_stack([a, -a])


def big_binary_request(client, count=100_000, seed=0):
    return client.post(
        "/v1/clip/segments", content=crossing_segments(count, seed).astype("<f8").tobytes(),
        params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1, "mode": "approx", "n": 64,
                "verify": "false"},
        headers={"Content-Type": "application/octet-stream"})


def assert_problem(response, status, slug=None):
    assert response.status_code == status, response.text
    assert response.headers["content-type"] == PROBLEM
    body = response.json()
    assert body["status"] == status and body["title"] and body["detail"]
    if slug:
        assert body["type"] == f"urn:rnsca:problem:{slug}"
    return body


# --- every endpoint ---------------------------------------------------------------------


def test_healthz_readyz_capabilities(client):
    assert client.get("/healthz").json() == {"status": "ok"}
    assert client.get("/readyz").json() == {"status": "ready"}
    caps = client.get("/v1/capabilities").json()
    assert "rnsca" in caps["methods"] and caps["limits"]["max_vertices"] == 400000
    assert caps["threading_layer"] in ("omp", "tbb") and caps["serialized"] is False


def test_clip_geojson_keeps_properties_and_verifies(client):
    r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": LINE})
    assert r.status_code == 200
    body = r.json()
    assert body["geojson"]["id"] == 7 and body["geojson"]["properties"] == {"name": "road"}
    assert body["geojson"]["geometry"]["coordinates"] == [
        [[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]
    assert body["stats"]["segments_in"] == 5 and body["verification"]["passed"] is True


def test_clip_geojson_mixing_2d_and_3d_positions(client):
    for verify in (True, False):
        r = client.post("/v1/clip/geojson", json={
            "window": WINDOW, "geojson": MIXED_DIMENSIONS, "verify": verify})
        assert r.status_code == 200, r.text
        body = r.json()
        assert [f["geometry"] for f in body["geojson"]["features"]] == \
            MIXED_DIMENSIONS_CLIPPED
        if verify:
            assert body["verification"]["passed"] is True
        else:
            assert body["verification"] is None


def test_clip_segments_json(client):
    r = client.post("/v1/clip/segments", json={
        "window": WINDOW, "segments": [[-5, 5, 15, 5], [20, 20, 30, 30]],
        "options": {"method": "liang_barsky"}})
    assert r.status_code == 200
    body = r.json()
    assert body["segments"] == [[0.0, 5.0, 10.0, 5.0]] and body["source"] == [0]
    assert body["t"] == [[0.25, 0.75]] and body["method"] == "liang_barsky"
    assert body["verification"]["passed"] is True


def test_clip_segments_binary_in_and_out(client):
    segments = np.array([[-5.0, 5, 15, 5], [20, 20, 30, 30], [1, 1, 2, 2]])
    r = client.post("/v1/clip/segments", content=segments.astype("<f8").tobytes(),
                    params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10, "verify": "true"},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/octet-stream"
    m = int(r.headers["x-rnsca-pieces"])
    assert m == 2 and len(r.content) == m * (32 + 8 + 16)
    pieces = np.frombuffer(r.content[:32 * m], "<f8").reshape(m, 4)
    source = np.frombuffer(r.content[32 * m:40 * m], "<i8")
    t = np.frombuffer(r.content[40 * m:], "<f8").reshape(m, 2)
    assert pieces.tolist() == [[0.0, 5.0, 10.0, 5.0], [1.0, 1.0, 2.0, 2.0]]
    assert source.tolist() == [0, 2] and t.tolist() == [[0.25, 0.75], [0.0, 1.0]]
    assert orjson.loads(r.headers["x-rnsca-stats"])["segments_in"] == 3
    assert orjson.loads(r.headers["x-rnsca-verification"])["passed"] is True


def test_clip_geoarrow_stream_in_and_out(client):
    """An Arrow IPC stream of ids and GeoArrow polygons (interleaved) in, the same out."""
    import shapely

    from tests.geoarrow_tables import ARROW_STREAM, decode, from_stream, table, to_stream

    polygons = [shapely.box(-5, -5, 5, 5), shapely.box(20, 20, 30, 30),
                shapely.box(1, 1, 2, 2)]
    r = client.post("/v1/clip/geoarrow",
                    content=to_stream(table(polygons, "polygon", "interleaved", False)),
                    params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10},
                    headers={"Content-Type": ARROW_STREAM})
    assert r.status_code == 200 and r.headers["content-type"] == ARROW_STREAM, r.text
    got = from_stream(r.content)
    assert got.column("id").to_pylist() == [0, 2] and r.headers["x-rnsca-rows"] == "2"
    assert got.column("name").to_pylist() == ["row 0", "row 2"]
    clipped = decode(got.column("geometry"), got.schema.field("geometry"))
    expected = shapely.intersection(np.array(polygons)[[0, 2]], shapely.box(0, 0, 10, 10))
    assert shapely.equals(np.array(clipped), expected).all()
    assert orjson.loads(r.headers["x-rnsca-verification"])["passed"] is True
    # Not an Arrow stream: a problem naming it, and the server goes on serving.
    bad = client.post("/v1/clip/geoarrow", content=b"not arrow",
                      params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10},
                      headers={"Content-Type": ARROW_STREAM})
    assert_problem(bad, 422, "invalid-body")
    nan = shapely.LineString([(0, 0), (np.nan, 1)])
    bad = client.post("/v1/clip/geoarrow",
                      content=to_stream(table([nan], "linestring", "separated", False)),
                      params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10},
                      headers={"Content-Type": ARROW_STREAM})
    assert_problem(bad, 422, "invalid-geometry")
    assert client.get("/healthz").status_code == 200


def test_clip_svg_clips_keeps_curves_and_verifies(client):
    assert client.get("/v1/capabilities").json()["svg"] is True
    r = client.post("/v1/clip/svg", json={"window": WINDOW,
                                          "paths": ["M -5 5 L 15 5", "M-5 5 Q5 15 15 5"]})
    assert r.status_code == 200
    body = r.json()
    assert body["paths"] == ["M0 5H10", "M0 8.75Q5 11.25 10 8.75"]
    assert body["stats"]["segments_in"] == 2
    assert body["verification"]["passed"] is True


def test_clip_svg_fills_close_along_the_window(client):
    r = client.post("/v1/clip/svg", json={"window": WINDOW, "paths": ["M-20 -20 h50 v50 h-50 z"],
                                          "options": {"fill": "evenodd"}})
    assert r.status_code == 200
    assert r.json()["paths"] == ["M0 0H10V10H0Z"]
    assert r.json()["verification"]["passed"] is True


def test_clip_svg_syntax_error_names_the_path_and_position(client):
    r = client.post("/v1/clip/svg", json={"window": WINDOW, "paths": ["M0 0 L1 1", "M0 0 L1 x"]})
    assert_problem(r, 422)
    assert "paths[1]" in r.text and "position 8" in r.text


def test_metrics_count_requests_and_clipping(client):
    client.post("/v1/clip/segments", json={"window": WINDOW, "segments": [[-5, 5, 15, 5]]})
    text = client.get("/metrics").text
    assert 'rnsca_http_requests_total{method="POST",route="/v1/clip/segments",status="200"}' \
        in text
    assert "rnsca_http_request_duration_seconds_bucket" in text
    for name in ("rnsca_segments_clipped_total", "rnsca_fragments_pruned_total",
                 "rnsca_intersections_total"):
        assert name in text


def test_docs_and_openapi(client):
    assert client.get("/docs").status_code == 200
    schema = client.get("/openapi.json").json()
    assert "ClipGeoJSONRequest" in schema["components"]["schemas"]


def test_gzip_when_accepted(client):
    request = {"window": [0, 0, 1000, 1000],
               "segments": crossing_segments(2000).tolist(), "verify": False}
    r = client.post("/v1/clip/segments", json=request, headers={"Accept-Encoding": "gzip"})
    assert r.status_code == 200 and r.headers["content-encoding"] == "gzip"
    assert r.json()["stats"]["segments_in"] == 2000  # httpx decodes it
    raw = client.post("/v1/clip/segments", json=request,
                      headers={"Accept-Encoding": "identity"})
    assert "content-encoding" not in raw.headers
    assert len(gzip.compress(raw.content)) < len(raw.content)


def test_one_json_log_line_per_request(server, client):
    client.get("/healthz", params={"marker": "log-line-check"})
    time.sleep(0.2)
    lines = [orjson.loads(line) for line in server.log().splitlines()
             if line.startswith("{") and '"rnsca.service.access"' in line]
    line = lines[-1]
    assert line["method"] == "GET" and line["path"] == "/healthz" and line["status"] == 200
    assert {"duration_ms", "request_bytes", "response_bytes"} <= set(line)


# --- every error status -----------------------------------------------------------------


def test_malformed_json_400(client):
    r = client.post("/v1/clip/geojson", content=b'{"window": [0,0,1,1], ',
                    headers={"Content-Type": "application/json"})
    assert_problem(r, 400, "malformed-json")


@pytest.mark.parametrize("text, path", [
    ('{"window": [10, 0, 0, 10], "segments": []}', "window"),
    ('{"window": [0, 0, 10], "segments": []}', "window[3]"),
    ('{"window": [0, 0, 10, NaN], "segments": []}', "window[3]"),
    ('{"window": [0, 0, 10, 10], "segments": [], "options": {"n": 1}}', "options.n"),
    ('{"window": [0, 0, 10, 10], "segments": [], "options": {"nn": 4}}', "options.nn"),
    ('{"window": [0, 0, 10, 10], "segments": [], "options": {"mode": "fast"}}',
     "options.mode"),
    ('{"window": [0, 0, 10, 10], "segments": [[0, 0, 1, "2"]]}', "segments[0][3]"),
    ('{"window": [0, 0, 10, 10], "segments": [[0, 0, 1, 2], [0, 0, 1, 1e999]]}',
     "segments[1]"),
    ('{"window": [0, 0, 10, 10], "segments": [[0, 0, 1, 2], [NaN, 0, 1, 1]]}',
     "segments[1]"),
])
def test_invalid_segment_requests_422_name_the_path(client, text, path):
    r = client.post("/v1/clip/segments", content=text.encode(),
                    headers={"Content-Type": "application/json"})
    body = assert_problem(r, 422)
    assert body["path"] == path, body


def test_invalid_geojson_422_names_the_json_path(client):
    feature = {**LINE, "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, True]]}}
    r = client.post("/v1/clip/geojson", json={
        "window": WINDOW, "geojson": {"type": "FeatureCollection", "features": [LINE, feature]}})
    body = assert_problem(r, 422, "invalid-geometry")
    assert body["path"] == "geojson.features[1].geometry.coordinates[1][1]"


def test_unavailable_backend_422_with_reason():
    # A server configured for an OpenCL device that is not there: OpenCL is installed for
    # the tests, so the device setting is what makes the backend unavailable.
    with LiveServer(env={"RNSCA_OPENCL_DEVICE": "no-such-device"}) as live, \
            httpx.Client(base_url=live.url, timeout=60) as c:
        r = c.post("/v1/clip/segments", json={"window": WINDOW, "segments": [],
                                              "options": {"backend": "opencl"}})
        body = assert_problem(r, 422, "backend-unavailable")
        assert "opencl" in body["detail"].lower() and "no-such-device" in body["detail"]
        assert c.get("/healthz").status_code == 200


def test_body_over_the_limit_413_from_content_length(client):
    r = client.post("/v1/clip/segments", content=b"0" * (8 * 2**20 + 1),
                    headers={"Content-Type": "application/octet-stream"})
    assert_problem(r, 413, "body-too-large")


def test_body_over_the_limit_413_while_reading_a_chunked_body(client):
    def chunks():
        for _ in range(9):
            yield b"\0" * 2**20

    r = client.post("/v1/clip/segments", content=chunks(),
                    params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1},
                    headers={"Content-Type": "application/octet-stream"})
    assert_problem(r, 413, "body-too-large")
    assert client.get("/healthz").status_code == 200


def _seq_records(count: int, start: int = 0) -> list[bytes]:
    """`count` RS-framed features, each with one vertex left and right of the window."""
    return [b"\x1e" + orjson.dumps({
        "type": "Feature", "id": i, "properties": {"n": i},
        "geometry": {"type": "LineString", "coordinates": [[-5, 1 + i % 8], [15, 2 + i % 8]]}})
        + b"\n" for i in range(start, start + count)]


def test_clip_geojson_seq_to_a_client_that_reads_only_after_sending(client):
    """httpx sends the whole body before it reads: 28 MB of records (over this server's
    8 MiB body limit) whose answer, 25 MB, is more than the sockets hold (about 10 MB
    measured on loopback). The rest waits in the server's spool, and everything arrives."""
    count = 200_000
    spilled = _metric(client, "rnsca_stream_spilled_bytes_total")

    def body():
        for start in range(0, count, 1000):
            yield b"".join(_seq_records(1000, start))

    with client.stream("POST", "/v1/clip/geojson-seq", content=body(),
                       params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10,
                               "summary": "true"},
                       headers={"Content-Type": "application/geo+json-seq",
                                "Accept-Encoding": "identity"}) as r:
        assert r.status_code == 200
        texts = r.read().split(b"\x1e")[1:]
    *records, summary = [orjson.loads(t) for t in texts]
    assert [f["id"] for f in records] == list(range(count))
    assert records[3]["geometry"]["coordinates"] == [[0.0, 4.25], [10.0, 4.75]]
    assert summary["records_in"] == count and summary["chunks"] >= count // 8000
    # What the sockets could not hold went through the spool's file.
    assert _metric(client, "rnsca_stream_spilled_bytes_total") > spilled
    assert client.get("/healthz").status_code == 200


def _metric(client, name: str) -> float:
    text = client.get("/metrics").text
    return float(re.search(rf"^{name} (\S+)$", text, re.MULTILINE).group(1))


def _chunked(payload: bytes) -> bytes:
    return b"%x\r\n" % len(payload) + payload + b"\r\n"


def test_clip_geojson_seq_answers_the_first_records_before_the_body_ends(server):
    """A client that reads while it sends (a raw socket, chunked): the first chunk's
    records arrive while the body is still open, the rest once it ends."""
    import socket

    port = int(server.url.rsplit(":", 1)[1])
    first, rest = b"".join(_seq_records(6000)), b"".join(_seq_records(3000, 6000))
    with socket.create_connection(("127.0.0.1", port), timeout=60) as sock:
        sock.sendall(b"POST /v1/clip/geojson-seq?xmin=0&ymin=0&xmax=10&ymax=10 HTTP/1.1\r\n"
                     b"Host: test\r\nContent-Type: application/geo+json-seq\r\n"
                     b"Transfer-Encoding: chunked\r\n\r\n" + _chunked(first))
        received = b""
        deadline = time.monotonic() + 60
        while received.count(b"\x1e") < 5000 and time.monotonic() < deadline:
            received += sock.recv(1 << 16)  # the body is still open
        assert received.startswith(b"HTTP/1.1 200"), received[:200]
        assert received.count(b"\x1e") >= 5000
        sock.sendall(_chunked(rest) + b"0\r\n\r\n")
        while not received.endswith(b"\r\n0\r\n\r\n"):
            data = sock.recv(1 << 16)
            assert data, "the connection closed before the answer ended"
            received += data
    head, _, chunked = received.partition(b"\r\n\r\n")
    answer = b""
    while True:
        size, _, chunked = chunked.partition(b"\r\n")
        if int(size, 16) == 0:
            break
        answer += chunked[:int(size, 16)]
        chunked = chunked[int(size, 16) + 2:]
    ids = [orjson.loads(t)["id"] for t in answer.split(b"\x1e")[1:]]
    assert ids == list(range(9000))


def test_clip_geojson_seq_client_leaving_mid_stream_is_no_server_error(server, client):
    """A client that goes away after its answer started: the server stops, logs it as a
    client that left (no traceback) and goes on serving."""
    import socket

    port = int(server.url.rsplit(":", 1)[1])
    with socket.create_connection(("127.0.0.1", port), timeout=60) as sock:
        sock.sendall(b"POST /v1/clip/geojson-seq?xmin=0&ymin=0&xmax=10&ymax=10 HTTP/1.1\r\n"
                     b"Host: test\r\nContent-Type: application/geo+json-seq\r\n"
                     b"Transfer-Encoding: chunked\r\n\r\n"
                     + _chunked(b"".join(_seq_records(6000))))
        received = b""
        while b"\x1e" not in received:
            received += sock.recv(1 << 16)
    deadline = time.monotonic() + 30
    while "client disconnected during a streamed request" not in server.log():
        assert time.monotonic() < deadline, server.log()[-2000:]
        time.sleep(0.1)
    assert client.get("/healthz").status_code == 200
    assert "Traceback" not in server.log() and "unhandled" not in server.log()


def test_too_many_vertices_413(client):
    r = client.post("/v1/clip/segments", content=np.zeros((200_001, 4)).tobytes(),
                    params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1},
                    headers={"Content-Type": "application/octet-stream"})
    body = assert_problem(r, 413, "too-many-vertices")
    assert "400002" in body["detail"]


def test_work_over_budget_422(client):
    r = client.post("/v1/clip/segments", content=crossing_segments(150_000).tobytes(),
                    params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1, "mode": "approx",
                            "n": 64, "tolerance": 1e-300},
                    headers={"Content-Type": "application/octet-stream"})
    assert_problem(r, 422, "work-over-budget")


def test_unknown_route_404_and_wrong_method_405(client):
    assert_problem(client.get("/v2/nothing"), 404, "not-found")
    r = client.get("/v1/clip/geojson")
    assert_problem(r, 405, "method-not-allowed")
    assert r.headers["allow"] == "POST"


def test_unsupported_media_type_415(client):
    r = client.post("/v1/clip/geojson", content=b"window=0", headers={
        "Content-Type": "application/x-www-form-urlencoded"})
    assert_problem(r, 415, "unsupported-media-type")


# --- load ---------------------------------------------------------------------------


def test_healthz_answers_during_a_large_request(client, server):
    result = {}

    def large():
        result["response"] = big_binary_request(client)

    worker = threading.Thread(target=large)
    worker.start()
    time.sleep(0.3)
    latencies = []
    with httpx.Client(base_url=server.url, timeout=5) as other:
        while worker.is_alive() and len(latencies) < 50:
            started = time.perf_counter()
            assert other.get("/healthz").status_code == 200
            latencies.append(time.perf_counter() - started)
            time.sleep(0.05)
    worker.join(60)
    assert result["response"].status_code == 200
    assert len(latencies) >= 3, "the large request finished too soon to overlap"
    assert max(latencies) < 0.5, latencies


def test_concurrent_large_requests_all_succeed_and_the_server_survives(client, server):
    with ThreadPoolExecutor(4) as pool:
        responses = list(pool.map(lambda seed: big_binary_request(client, 60_000, seed),
                                  range(4)))
    assert [r.status_code for r in responses] == [200] * 4
    for seed, r in enumerate(responses):
        pieces = int(r.headers["x-rnsca-pieces"])
        assert pieces > 0 and len(r.content) == 56 * pieces, seed
    assert server.process.poll() is None
    assert client.get("/healthz").status_code == 200


def test_serialized_when_the_threading_layer_is_not_thread_safe():
    """With Numba's workqueue layer forced, calls are serialized and still all succeed."""
    with LiveServer(env={"NUMBA_THREADING_LAYER": "workqueue", "RNSCA_CLIP_THREADS": "3"}) \
            as live, httpx.Client(base_url=live.url, timeout=60) as c:
        caps = c.get("/v1/capabilities").json()
        assert caps["threading_layer"] == "workqueue" and caps["serialized"] is True
        with ThreadPoolExecutor(3) as pool:
            responses = list(pool.map(lambda seed: big_binary_request(c, 30_000, seed),
                                      range(3)))
        assert [r.status_code for r in responses] == [200] * 3
        assert live.process.poll() is None


def test_graceful_shutdown_finishes_the_request_in_flight():
    live = LiveServer()
    try:
        with httpx.Client(base_url=live.url, timeout=60) as c:
            result = {}
            worker = threading.Thread(
                target=lambda: result.update(response=big_binary_request(c)))
            worker.start()
            time.sleep(0.5)
            live.terminate()
            worker.join(60)
            assert result["response"].status_code == 200
            assert int(result["response"].headers["x-rnsca-pieces"]) > 0
        live.process.wait(30)
        with pytest.raises(httpx.TransportError):
            httpx.get(live.url + "/healthz", timeout=2)
    finally:
        live.stop()


def test_a_client_that_disconnects_mid_upload_is_a_499_not_a_server_error(server, client):
    """Content-Length 1000, 22 bytes, then close: logged and counted as 499, no traceback."""
    import socket

    seen = len(server.log())
    before = client.get("/metrics").text
    assert 'route="/v1/clip/geojson",status="499"' not in before
    for _ in range(2):
        with socket.create_connection(("127.0.0.1", server.port)) as raw:
            raw.sendall(b"POST /v1/clip/geojson HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                        b"Content-Type: application/json\r\nContent-Length: 1000\r\n\r\n"
                        b'{"window": [0, 0, 1, 1')
    # Both disconnects counted (the server sees them one at a time, under load later).
    counted = re.compile(r'rnsca_http_requests_total\{method="POST",route="/v1/clip/geojson",'
                         r'status="499"\} 2(\.0)?\n')
    deadline = time.monotonic() + 10
    text = ""
    while time.monotonic() < deadline:
        text = client.get("/metrics").text
        if counted.search(text):
            break
        time.sleep(0.1)
    assert counted.search(text), text
    assert 'route="/v1/clip/geojson",status="500"' not in text
    log = server.log()[seen:]  # what the server wrote since
    assert "client disconnected" in log
    assert "Traceback" not in log and "ClientDisconnect" not in log, log
    assert client.get("/healthz").status_code == 200


def test_the_time_limit_covers_reading_the_body():
    """A client that stops sending its body gets 408 when the request's time limit ends."""
    import socket

    with LiveServer(env={"RNSCA_REQUEST_TIME_LIMIT": "2"}) as live:
        with socket.create_connection(("127.0.0.1", live.port), timeout=20) as raw:
            started = time.monotonic()
            raw.sendall(b"POST /v1/clip/segments HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                        b"Content-Type: application/json\r\nContent-Length: 100\r\n\r\n"
                        b'{"window": [0, 0,')  # then nothing more
            answer = b""
            while b"\r\n\r\n" not in answer:
                chunk = raw.recv(65536)
                if not chunk:
                    break
                answer += chunk
            waited = time.monotonic() - started
        assert answer.startswith(b"HTTP/1.1 408"), answer[:200]
        assert b"application/problem+json" in answer
        assert 1.5 < waited < 10
        with httpx.Client(base_url=live.url, timeout=30) as client:  # it keeps serving
            assert client.post("/v1/clip/segments", json={
                "window": WINDOW, "segments": [[-5, 5, 15, 5]]}).status_code == 200


def test_verify_all_on_self_crossing_lines_answers_within_the_time_limit():
    """20 MB of lines of 2,000 random vertices with ``verify: "all"``: each line crosses
    itself ~400,000 times, and comparing them with GEOS's clip of the whole line grew
    past 12 GB. The answer is 200 within the limit, says how far it got, and the server's
    peak memory stays far from that."""
    rng = np.random.default_rng(0)
    document = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"i": i}, "geometry": {
            "type": "LineString", "coordinates": rng.uniform(-2, 12, (2000, 2)).tolist()}}
        for i in range(250)]}
    body = orjson.dumps({"window": WINDOW, "verify": "all", "geojson": document})
    assert len(body) > 19 * 10**6
    with LiveServer(env={"RNSCA_REQUEST_TIME_LIMIT": "5"}) as live, \
            httpx.Client(base_url=live.url, timeout=60) as client:
        r = client.post("/v1/clip/geojson", content=body,
                        headers={"Content-Type": "application/json"})
        status = open(f"/proc/{live.process.pid}/status").read()
    assert r.status_code == 200, r.text
    v = r.json()["verification"]
    assert (v["inputs"], v["timed_out"], v["passed"]) == (250, True, None)
    assert v["checked"] < 250 and f"{250 - v['checked']} of the 250 inputs" in v["note"]
    peak_kib = int(re.search(r"VmHWM:\s+(\d+) kB", status).group(1))
    assert peak_kib < 3 * 2**20, f"peak RSS {peak_kib} KiB"


def test_silent_and_slow_clients_are_closed_and_connections_capped():
    """Request heads have a deadline (1 s here), and past 4 connections uvicorn says 503."""
    import socket

    def closed_within(raw: socket.socket, seconds: float, trickle: bytes = b"") -> float:
        started = time.monotonic()
        raw.settimeout(0.3)
        for byte in trickle or b"\0" * 1000:
            if trickle:
                try:
                    raw.sendall(bytes([byte]))
                except OSError:
                    return time.monotonic() - started
            try:
                if raw.recv(65536) == b"":
                    return time.monotonic() - started
            except TimeoutError:
                pass
            except OSError:
                return time.monotonic() - started
            if time.monotonic() - started > seconds:
                break
        return float("inf")

    with LiveServer(env={"RNSCA_HEADER_TIMEOUT_SECONDS": "1", "RNSCA_MAX_CONNECTIONS": "4"}
                    ) as live:
        address = ("127.0.0.1", live.port)
        with socket.create_connection(address) as silent:
            assert closed_within(silent, 10) < 5
        with socket.create_connection(address) as slow:  # one byte every 0.3 s
            head = b"GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Padding: " + b"a" * 100
            assert closed_within(slow, 10, trickle=head) < 5
        idle = [socket.create_connection(address) for _ in range(4)]
        try:
            with httpx.Client(base_url=live.url, timeout=10) as client:
                assert client.get("/healthz").status_code == 503  # the fifth connection
        finally:
            for raw in idle:
                raw.close()
        time.sleep(0.5)
        with httpx.Client(base_url=live.url, timeout=10) as client:
            assert client.get("/healthz").status_code == 200
        assert "request head did not arrive in time" in live.log()
