"""The app in-process (TestClient): settings, limits, the work budget, the time limit, the
threading-layer decision and the problem documents."""

import numpy as np
import pytest

import rnsca
from service import Settings
from service.budget import segment_work
from service.errors import json_path
from service.runner import ClipRunner
from service.schemas import ClipOptions
from tests.service.conftest import make_client

WINDOW = [0, 0, 10, 10]


def test_settings_come_from_rnsca_variables(monkeypatch):
    monkeypatch.setenv("RNSCA_MAX_VERTICES", "123")
    monkeypatch.setenv("RNSCA_CORS_ORIGINS", "https://a.example, https://b.example")
    monkeypatch.setenv("RNSCA_LOG_LEVEL", "DEBUG")
    settings = Settings()
    assert settings.max_vertices == 123 and settings.log_level == "debug"
    assert settings.cors_origins == ["https://a.example", "https://b.example"]


@pytest.mark.parametrize("bad", [{"port": 0}, {"workers": 0}, {"max_body_bytes": -1},
                                 {"request_time_limit": 90, "graceful_shutdown_seconds": 10},
                                 {"default_backend": "cuda"}])
def test_invalid_settings_are_refused(bad):
    with pytest.raises(ValueError):
        Settings(**bad)


def test_json_path_drops_pydantic_union_tags():
    assert json_path(("options", "n", "literal['auto']")) == "options.n"
    assert json_path(("segments", 3, 1)) == "segments[3][1]"


@pytest.mark.parametrize("kwargs", [
    dict(mode="approx"), dict(mode="approx", n=64), dict(mode="approx", n=2, max_depth=20),
    dict(mode="exact", n=16, tolerance=1e-6), dict(method="midpoint", mode="approx"),
    dict(mode="exact"), dict(method="liang_barsky"),
])
def test_work_estimate_bounds_the_fragments_evaluated(kwargs, rng):
    a = rng.uniform(-50, 50, (2000, 2))
    segments = np.vstack([np.column_stack([a, -a]), rng.uniform(-1, 11, (2000, 4))])
    options = ClipOptions.model_validate(kwargs, strict=False)
    result = rnsca.clip_segments(segments, WINDOW, **kwargs)
    bound = segment_work(segments, rnsca.Window(*WINDOW), options)
    assert result.stats.fragments_evaluated <= bound


def test_work_over_budget_is_422_before_clipping():
    with make_client(work_budget=10_000) as client:
        r = client.post("/v1/clip/segments", json={
            "window": WINDOW, "segments": [[-500, 5, 500, 5]] * 50,
            "options": {"mode": "approx", "n": 64}})
        assert r.status_code == 422 and r.json()["type"].endswith("work-over-budget")


def test_geojson_vertex_limit_is_413_and_the_budget_caps_approx_documents():
    line = {"type": "LineString", "coordinates": [[i, 0] for i in range(-5, 50)]}
    with make_client(max_vertices=20, verify_max_vertices=10, warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": line})
        assert r.status_code == 413 and r.json()["type"].endswith("too-many-vertices")
    with make_client(work_budget=100_000, warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": line,
                                                  "options": {"mode": "approx"}})
        assert r.status_code == 422 and r.json()["type"].endswith("work-over-budget")
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": line})
        assert r.status_code == 200


def test_a_request_over_the_time_limit_is_503_and_the_server_goes_on(monkeypatch):
    import time

    from service import convert

    original = convert.clip_segments_json

    def slow(body, settings):
        time.sleep(0.5)
        return original(body, settings)

    monkeypatch.setattr(convert, "clip_segments_json", slow)
    with make_client(request_time_limit=0.1, graceful_shutdown_seconds=1,
                     warm_up=False) as client:
        r = client.post("/v1/clip/segments", json={"window": WINDOW, "segments": []})
        assert r.status_code == 503 and r.headers["retry-after"]
        assert r.headers["content-type"] == "application/problem+json"
        assert client.get("/healthz").status_code == 200


def test_approx_geojson_is_verified_only_with_a_bound(client):
    line = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
    body = {"window": WINDOW, "geojson": line, "options": {"mode": "approx"}}
    assert client.post("/v1/clip/geojson", json=body).json()["verification"] is None
    r = client.post("/v1/clip/geojson", json={**body, "verify": True})
    assert r.status_code == 422 and "approx_bound" in r.json()["detail"]
    r = client.post("/v1/clip/geojson", json={**body, "verify": True, "approx_bound": 1e-6})
    assert r.json()["verification"]["passed"] is True


def test_polygons_refuse_approx_mode_with_422(client):
    square = {"type": "Polygon", "coordinates": [[[-1, -1], [5, -1], [5, 5], [-1, 5],
                                                  [-1, -1]]]}
    r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": square,
                                              "options": {"mode": "approx"}})
    assert r.status_code == 422 and r.json()["type"].endswith("invalid-option")


def test_binary_body_not_a_multiple_of_32_bytes_is_422(client):
    r = client.post("/v1/clip/segments", content=b"\0" * 33,
                    params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422 and r.json()["type"].endswith("invalid-body")
    r = client.post("/v1/clip/segments", content=b"\0" * 32,
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422 and r.json()["path"].startswith("query.")


class _FakeNumba:
    def __init__(self, layer):
        self.layer = layer

    def threading_layer(self):
        return self.layer


@pytest.mark.parametrize("layer, serialized", [("omp", False), ("tbb", False),
                                               ("workqueue", True)])
def test_runner_serializes_calls_unless_the_layer_is_thread_safe(monkeypatch, layer,
                                                                  serialized):
    import numba

    monkeypatch.setattr(numba, "threading_layer", lambda: layer)
    monkeypatch.setattr(numba.config, "DISABLE_JIT", False)
    runner = ClipRunner(2, 5.0)
    assert runner.serialized  # until the layer is known
    runner.settle()
    assert runner.serialized is serialized and runner.threading_layer == layer


def test_svg_path_text_is_read_once_and_verified_from_the_arrays(monkeypatch):
    # Tokenising is the first pass over the text (`svgparse.count_tokens`): a request
    # that clips, writes and verifies runs it once, and verification parses nothing.
    from rnsca.io import svgparse

    calls = []
    count_tokens = svgparse.count_tokens

    def counting(*args):
        calls.append(1)
        return count_tokens(*args)

    monkeypatch.setattr(svgparse, "count_tokens", counting)
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/svg", json={
            "window": [0, 0, 10, 10], "verify": True,
            "paths": ["M -5 5 C 0 15 10 -5 15 5", "M -5 -5 H 5 V 5 H -5 Z"],
            "options": {"fill": "nonzero"}})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["verification"]["passed"] is True and len(body["paths"]) == 2
    assert len(calls) == 1
