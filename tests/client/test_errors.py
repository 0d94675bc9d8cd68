"""Every kind of error, from a real server (and, for those a correct server never sends, a
scripted one): the SDK's exception class, and the problem+json fields it carries."""

from __future__ import annotations

import math

import httpx
import numpy as np
import pytest

import rnsca_client
from rnsca_client import Client
from rnsca_client.calls import Call
from tests.client.conftest import MAX_BODY_BYTES, MAX_VERTICES
from tests.client.scripted import Reply, ScriptedServer
from tests.e2e.server import free_port

pytestmark = pytest.mark.e2e

WINDOW = (0, 0, 10, 10)
LINE = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}


def raw(method: str, path: str, content: bytes | None = None,
        content_type: str = "application/json") -> Call:
    """A call the SDK's own methods would never make (to reach 400, 405, 415)."""
    return Call(method, path, lambda r: r.json(), content=content,
                headers={"Content-Type": content_type})


def check(error: rnsca_client.ApiError, status: int, kind: str) -> None:
    assert error.status == status and error.kind == kind
    assert error.type == f"urn:rnsca:problem:{kind}" and error.title and error.detail
    assert error.problem["status"] == status and str(status) in str(error)


# --- 4xx ----------------------------------------------------------------------------------


def test_400_body_not_json(client):
    with pytest.raises(rnsca_client.BadRequestError) as info:
        client.send(raw("POST", "/v1/clip/geojson", b"{not json"))
    check(info.value, 400, "malformed-json")


def test_404_unknown_route(server):
    with Client(server.url + "/not-here", retries=None) as c, \
            pytest.raises(rnsca_client.NotFoundError) as info:
        c.capabilities()
    check(info.value, 404, "not-found")
    assert info.value.instance == "/not-here/v1/capabilities"


def test_405_wrong_method(client):
    with pytest.raises(rnsca_client.MethodNotAllowedError) as info:
        client.send(raw("GET", "/v1/clip/geojson"))
    check(info.value, 405, "method-not-allowed")


def test_413_body_over_the_limit(client):
    too_many_bytes = np.zeros((MAX_BODY_BYTES // 32 + 1, 4))
    with pytest.raises(rnsca_client.PayloadTooLargeError) as info:
        client.clip_segments(too_many_bytes, WINDOW)
    check(info.value, 413, "body-too-large")
    assert info.value.problem["limit"] == MAX_BODY_BYTES


def test_413_too_many_vertices(client):
    too_many_vertices = np.ones((MAX_VERTICES // 2 + 1, 4))
    with pytest.raises(rnsca_client.PayloadTooLargeError) as info:
        client.clip_segments(too_many_vertices, WINDOW)
    check(info.value, 413, "too-many-vertices")


def test_415_wrong_content_type(client):
    with pytest.raises(rnsca_client.UnsupportedMediaTypeError) as info:
        client.send(raw("POST", "/v1/clip/svg", b"M 0 0 L 1 1", "text/plain"))
    check(info.value, 415, "unsupported-media-type")


def test_422_invalid_window_names_it(client):
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_geojson(LINE, (10, 0, 0, 10))
    check(info.value, 422, "invalid-window")
    assert info.value.path == "window" and isinstance(info.value, ValueError)


def test_422_invalid_geometry_names_the_json_path(client):
    collection = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": LINE},
        {"type": "Feature", "properties": {},
         "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1]]]}}]}
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_geojson(collection, WINDOW)
    check(info.value, 422, "invalid-geometry")
    assert info.value.path.startswith("geojson.features[1].geometry")


def test_422_invalid_options_list_every_error(client):
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_geojson(LINE, WINDOW, n=1, mode="fast", colour="red")
    check(info.value, 422, "invalid-request")
    paths = {e["path"] for e in info.value.errors}
    assert {"options.n", "options.mode", "options.colour"} <= paths


def test_422_svg_syntax_error_has_a_position(client):
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_svg(["M 0 0 L 1 1", "M 0 0 L 5 X"], WINDOW)
    check(info.value, 422, "parse-error")
    assert info.value.path == "paths[1]" and isinstance(info.value.position, int)


def test_422_non_finite_binary_coordinate_names_the_row(client):
    segments = np.zeros((3, 4))
    segments[2, 1] = math.nan
    with pytest.raises(rnsca_client.InvalidRequestError) as info:
        client.clip_segments(segments, WINDOW)
    assert info.value.kind == "invalid-geometry" and "2" in info.value.detail


def test_422_backend_unavailable(client):
    # The server's OpenCL device does not exist (see conftest): the reason is named.
    with pytest.raises(rnsca_client.BackendUnavailableError) as info:
        client.clip_geojson(LINE, WINDOW, backend="opencl")
    check(info.value, 422, "backend-unavailable")
    assert "no such device" in info.value.detail


def test_422_work_over_budget(client):
    long_segments = np.tile([[-1000.0, 5.0, 1000.0, 5.5]], (2000, 1))
    with pytest.raises(rnsca_client.WorkOverBudgetError) as info:
        client.clip_segments(long_segments, WINDOW, mode="approx", n=64, max_depth=32)
    check(info.value, 422, "work-over-budget")


# --- what a correct rnsca server does not send: a scripted server -------------------------


@pytest.mark.parametrize("status, cls", [
    (501, rnsca_client.NotImplementedOnServerError),
    (503, rnsca_client.ServiceUnavailableError),
    (500, rnsca_client.ServerError),
])
def test_5xx_problems(status, cls):
    problem = {"type": f"urn:rnsca:problem:x{status}", "title": "T", "status": status,
               "detail": "D"}
    with ScriptedServer([Reply(status, problem, content_type="application/problem+json")]) \
            as scripted, Client(scripted.url, retries=None) as c, pytest.raises(cls) as info:
        c.clip_svg("M 0 0 L 1 1", WINDOW)
    assert info.value.status == status and info.value.detail == "D"


def test_a_proxy_error_page_still_becomes_an_api_error():
    page = Reply(502, b"<html><body>Bad gateway</body></html>", content_type="text/html")
    with ScriptedServer([page]) as scripted, Client(scripted.url, retries=None) as c, \
            pytest.raises(rnsca_client.ServerError) as info:
        c.health()
    assert info.value.status == 502 and "Bad gateway" in info.value.detail
    assert info.value.kind == ""


def test_a_success_answer_that_is_not_the_api_is_a_response_format_error():
    with ScriptedServer([Reply(200, b"<html>hello</html>", content_type="text/html"),
                         Reply(200, {"unexpected": True})]) as scripted, \
            Client(scripted.url, retries=None) as c:
        with pytest.raises(rnsca_client.ResponseFormatError, match="not JSON"):
            c.capabilities()
        with pytest.raises(rnsca_client.ResponseFormatError, match="documented members"):
            c.capabilities()


# --- network errors are not HTTP errors -----------------------------------------------------


def test_connection_refused_is_a_connect_error_after_the_retries():
    port = free_port()  # nothing listens there
    policy = rnsca_client.Retry(attempts=3, backoff=0.01)
    with Client(f"http://127.0.0.1:{port}", retries=policy) as c, \
            pytest.raises(rnsca_client.ConnectError) as info:
        c.clip_geojson(LINE, WINDOW)
    error = info.value
    assert error.attempts == 3 and isinstance(error, ConnectionError)
    assert isinstance(error, rnsca_client.TransportError)
    assert not isinstance(error, rnsca_client.ApiError)
    assert isinstance(error.__cause__, httpx.ConnectError)


def test_a_slow_answer_is_a_timeout_and_is_not_retried():
    with ScriptedServer([Reply(delay=1.0)]) as scripted, \
            Client(scripted.url, timeout=httpx.Timeout(0.2), retries=3) as c, \
            pytest.raises(rnsca_client.RequestTimeoutError) as info:
        c.health()
    assert isinstance(info.value, TimeoutError) and info.value.attempts == 1
    assert scripted.requests == 1


# --- refused before sending -----------------------------------------------------------------


def test_non_finite_json_input_is_refused_before_sending(client):
    with pytest.raises(rnsca_client.InvalidInputError, match="NaN or infinity"):
        client.clip_geojson({"type": "Point", "coordinates": [math.nan, 1]}, WINDOW)
    with pytest.raises(rnsca_client.InvalidInputError, match="xmin, ymin, xmax, ymax"):
        client.clip_svg("M 0 0 L 1 1", (0, 0, 1))
    with pytest.raises(rnsca_client.InvalidInputError, match="shape"):
        client.clip_segments(np.zeros((3, 3)), WINDOW)
    with pytest.raises(rnsca_client.InvalidInputError, match="unknown option"):
        client.clip_segments(np.zeros((3, 4)), WINDOW, boundary="interior")
    with pytest.raises(rnsca_client.InvalidInputError, match="__geo_interface__"):
        client.clip_geojson(42, WINDOW)
