"""The OpenCL backend through the service: capabilities, clipping, clear refusals."""

import numpy as np
import pytest

import rnsca
from rnsca.backends import registry
from tests.service.conftest import make_client

pytestmark = pytest.mark.opencl

WINDOW = [0.0, 0.0, 10.0, 10.0]


@pytest.fixture
def default_configuration():
    """Restore the registry's default OpenCL configuration (an app configures it)."""
    yield
    registry.configure_opencl()


def opencl_entry(client) -> dict:
    caps = client.get("/v1/capabilities").json()
    return next(b for b in caps["backends"] if b["name"] == "opencl")


def test_capabilities_list_the_opencl_devices_and_the_selected_one(opencl,
                                                                   default_configuration):
    with make_client(warm_up=False) as client:
        entry = opencl_entry(client)
    assert entry["available"] is True and "reason" not in entry
    assert opencl.device in entry["devices"]
    assert entry["selected"] == opencl.device["id"]
    assert entry["precision"] == opencl.precision.value


def test_the_settings_choose_the_device_and_precision(opencl, default_configuration):
    with make_client(warm_up=False, opencl_device=opencl.device["id"],
                     opencl_precision="float32") as client:
        assert opencl_entry(client)["precision"] == "float32"
        r = client.post("/v1/clip/segments", json={
            "window": WINDOW, "segments": [[-5, 5, 15, 5]], "options": {"backend": "opencl"}})
    assert r.status_code == 200, r.text
    assert r.json()["stats"]["device"]["precision"] == "float32"


def test_segments_clipped_on_opencl_match_numba(opencl, rng, default_configuration):
    segments = rng.uniform(-5.0, 15.0, size=(500, 4))
    expected = rnsca.clip_segments(segments, WINDOW, backend="numba")
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/segments", json={
            "window": WINDOW, "segments": segments.tolist(),
            "options": {"backend": "opencl", "method": "rnsca", "mode": "exact"}})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["backend"] == "opencl"
    np.testing.assert_allclose(np.array(body["segments"]), expected.segments, rtol=1e-12)
    device = body["stats"]["device"]
    assert device["device"] == opencl.name and device["transfers"] == 6


def test_a_device_that_is_not_there_is_a_422_with_the_reason(opencl, default_configuration):
    with make_client(warm_up=False, opencl_device="no such device") as client:
        entry = opencl_entry(client)
        assert entry["available"] is False
        assert "no OpenCL device matches 'no such device'" in entry["reason"]
        r = client.post("/v1/clip/segments", json={
            "window": WINDOW, "segments": [[-5, 5, 15, 5]], "options": {"backend": "opencl"}})
    assert r.status_code == 422
    assert r.json()["type"] == "urn:rnsca:problem:backend-unavailable"
    assert "no OpenCL device matches" in r.json()["detail"]


def test_geojson_runs_on_opencl(opencl, default_configuration):
    line = {"type": "LineString", "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5],
                                                  [15, 5]]}
    square = {"type": "Polygon", "coordinates": [[[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]]}
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={
            "window": WINDOW, "geojson": line, "options": {"backend": "opencl"}})
        assert r.status_code == 200, r.text
        assert r.json()["geojson"]["coordinates"] == [
            [[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]
        assert r.json()["stats"]["device"]["device"] == opencl.name
        r = client.post("/v1/clip/geojson", json={
            "window": WINDOW, "geojson": square, "options": {"backend": "opencl"}})
        numba = client.post("/v1/clip/geojson", json={
            "window": WINDOW, "geojson": square, "options": {"backend": "numba"}})
    assert r.status_code == 200, r.text
    assert r.json()["geojson"] == numba.json()["geojson"]
    assert r.json()["geojson"]["coordinates"][0][0] == [1.0, 0.0]
    assert r.json()["verification"]["passed"] is True


def test_svg_paths_run_on_opencl(opencl, default_configuration):
    paths = ["M-5 5 C0 10 10 10 15 5 Q 20 -20 3 3 Z", "M 2 2 C 3 9 7 9 8 2"]
    with make_client(warm_up=False) as client:
        answers = {backend: client.post("/v1/clip/svg", json={
            "window": WINDOW, "paths": paths,
            "options": {"backend": backend, "curves": "flatten", "fill": "nonzero"}})
            for backend in ("opencl", "numba")}
    assert answers["opencl"].status_code == 200, answers["opencl"].text
    assert answers["opencl"].json()["paths"] == answers["numba"].json()["paths"]
    assert answers["opencl"].json()["stats"]["device"]["device"] == opencl.name


def test_backend_auto_runs_where_the_calibration_says(opencl, rng, monkeypatch,
                                                      default_configuration):
    from rnsca.backends import auto

    with make_client(warm_up=False) as client:
        name = registry.get_backend("opencl").name
        monkeypatch.setattr(auto, "_CACHE", {name: {"crossover": {
            "segments": 100, "windows": None, "lines": None, "polygons": None}}})
        small = client.post("/v1/clip/segments", json={
            "window": WINDOW, "segments": [[-5, 5, 15, 5]], "options": {"backend": "auto"}})
        large = client.post("/v1/clip/segments", json={
            "window": WINDOW, "segments": rng.uniform(-5, 15, (200, 4)).tolist(),
            "options": {"backend": "auto"}})
        geojson = client.post("/v1/clip/geojson", json={
            "window": WINDOW, "options": {"backend": "auto"},
            "geojson": {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}})
        backends = [b["name"] for b in client.get("/v1/capabilities").json()["backends"]]
    assert small.status_code == large.status_code == geojson.status_code == 200, small.text
    assert small.json()["backend"] == "numba" and large.json()["backend"] == "opencl"
    assert geojson.headers.get("X-Rnsca-Backend", "numba") == "numba"
    assert "auto" not in backends  # a choice between the backends, not one of them
