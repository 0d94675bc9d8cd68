"""The app in-process (TestClient): settings, limits, the work budget, the time limit, the
threading-layer decision and the problem documents."""

import numpy as np
import orjson
import pytest

import rnsca
from service import Settings, create_app
from service.budget import segment_work
from service.errors import json_path
from service.runner import ClipRunner
from service.schemas import ClipOptions
from tests.cases import MIXED_DIMENSIONS, MIXED_DIMENSIONS_CLIPPED
from tests.service.conftest import TestClient, make_client

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

    def slow(*args):
        time.sleep(0.5)
        return original(*args)

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


@pytest.mark.parametrize("verify", [True, False, "all"])
def test_a_collection_mixing_2d_and_3d_positions_keeps_each_positions_dimension(
        client, verify):
    r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": MIXED_DIMENSIONS,
                                              "verify": verify})
    assert r.status_code == 200, r.text
    body = r.json()
    assert [f["geometry"] for f in body["geojson"]["features"]] == MIXED_DIMENSIONS_CLIPPED
    assert [f["id"] for f in body["geojson"]["features"]] == [1, 2, 3]
    assert body["stats"]["vertices_in"] == 12
    if verify is False:
        assert body["verification"] is None
    else:
        assert body["verification"]["passed"] is True
        assert body["verification"]["inputs"] == 3
        # true: within the verification budget (a sample, if the running cost estimate
        # says so); all: every input.
        checked = body["verification"]["checked"]
        assert checked == 3 if verify == "all" else 1 <= checked <= 3


def test_polygons_refuse_approx_mode_with_422(client):
    square = {"type": "Polygon", "coordinates": [[[-1, -1], [5, -1], [5, 5], [-1, 5],
                                                  [-1, -1]]]}
    r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": square,
                                              "options": {"mode": "approx"}})
    assert r.status_code == 422 and r.json()["type"].endswith("invalid-option")


def test_capabilities_say_which_methods_and_modes_each_kind_of_input_takes(client):
    """What the playground offers per input: polygons exact only, curves rnsca only (the
    library's refusals match these lists: tests/unit/backends/test_contract.py)."""
    caps = client.get("/v1/capabilities").json()
    operations = caps["operations"]
    assert set(operations) == {"segments", "lines", "polygons", "paths"}
    assert operations["polygons"] == {"methods": caps["methods"], "modes": ["exact"]}
    assert operations["paths"] == {"methods": ["rnsca"], "modes": ["exact", "approx"]}
    assert operations["lines"] == operations["segments"] == {"methods": caps["methods"],
                                                             "modes": caps["modes"]}


def test_binary_body_not_a_multiple_of_32_bytes_is_422(client):
    r = client.post("/v1/clip/segments", content=b"\0" * 33,
                    params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422 and r.json()["type"].endswith("invalid-body")
    r = client.post("/v1/clip/segments", content=b"\0" * 32,
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422 and r.json()["path"].startswith("query.")


def test_binary_request_refuses_unknown_query_parameters_naming_them(client):
    body = np.array([[-5.0, 5.0, 15.0, 5.0]], dtype="<f8").tobytes()
    window = {"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10}
    r = client.post("/v1/clip/segments", content=body,
                    params={**window, "metod": "liang_barsky"},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422 and r.json()["path"] == "query.metod", r.text
    r = client.post("/v1/clip/segments", content=body, params={**window, "method": "liang_barsky"},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 200 and r.headers["X-Rnsca-Method"] == "liang_barsky"


@pytest.mark.parametrize(("resolution", "depth"), [("16px", 5), ("0.625", 5), (None, 13)])
def test_binary_and_json_requests_take_the_approx_resolution(client, resolution, depth):
    """20 long across a window of 10: bisection down to 10/16 takes 5 levels."""
    body = np.array([[-5.0, 5.0, 15.0, 5.0]], dtype="<f8").tobytes()
    params = {"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10, "mode": "approx"}
    if resolution is not None:
        params["resolution"] = resolution
    r = client.post("/v1/clip/segments", content=body, params=params,
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    assert orjson.loads(r.headers["X-Rnsca-Stats"])["deepest_level"] == depth
    options = {"mode": "approx"} | ({} if resolution is None else {
        "resolution": resolution if resolution.endswith("px") else float(resolution)})
    r = client.post("/v1/clip/segments", json={"window": WINDOW, "segments": [[-5, 5, 15, 5]],
                                               "options": options})
    assert r.status_code == 200 and r.json()["stats"]["deepest_level"] == depth


@pytest.mark.parametrize("resolution", ["abc", "0px", "-1", "nan"])
def test_a_bad_resolution_is_422(client, resolution):
    r = client.post("/v1/clip/segments", content=b"\0" * 32,
                    params={"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1, "mode": "approx",
                            "resolution": resolution},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422, r.text


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


@pytest.mark.parametrize("fill_output, expected", [
    (None, "M1.5 0 1 1 2 0Z"), ("clean", "M1.5 0 1 1 2 0Z"), ("raw", "M2 0H1.5L1 1 2 0Z")])
def test_svg_fill_output_is_clean_by_default_and_raw_on_request(fill_output, expected):
    options = {"fill": "nonzero"} | ({} if fill_output is None else
                                     {"fill_output": fill_output})
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/svg", json={"window": [0, 0, 10, 10], "verify": True,
                                              "paths": ["M2 -1L1 1L3 -1L1 -1Z"],
                                              "options": options})
        assert r.status_code == 200, r.text
        assert r.json()["paths"] == [expected]
        assert r.json()["verification"]["passed"] is True
        r = client.post("/v1/clip/svg", json={"window": [0, 0, 10, 10], "paths": ["M0 0H1"],
                                              "options": {"fill_output": "tidy"}})
        assert r.status_code == 422, r.text
        assert r.json()["path"].endswith("fill_output")


def _gzip_members(member: bytes, count: int) -> bytes:
    return b"".join([member] * count)


def test_gzip_request_bodies_are_inflated_within_the_body_limit():
    import gzip

    request = {"window": WINDOW, "segments": [[-5, 5, 15, 5]] * 200, "verify": False}
    plain = orjson.dumps(request)
    with make_client(max_body_bytes=1 << 20, warm_up=False) as client:
        expected = client.post("/v1/clip/segments", content=plain,
                               headers={"Content-Type": "application/json"})
        assert expected.status_code == 200
        for body in (gzip.compress(plain), _gzip_members(gzip.compress(plain[:100]), 1)
                     + gzip.compress(plain[100:])):  # one member, or two
            r = client.post("/v1/clip/segments", content=body,
                            headers={"Content-Type": "application/json",
                                     "Content-Encoding": "gzip"})
            assert r.status_code == 200, r.text
            assert r.json()["segments"] == expected.json()["segments"]


def test_a_gzip_bomb_is_413_after_inflating_no_more_than_the_limit():
    import gzip
    import time

    # 2,048 members of 1 MiB of zeros: 2 GiB inflated from about 2 MB sent.
    bomb = _gzip_members(gzip.compress(b"\0" * (1 << 20), 9), 2048)
    with make_client(max_body_bytes=8 << 20, warm_up=False) as client:
        started = time.perf_counter()
        r = client.post("/v1/clip/segments", content=bomb,
                        headers={"Content-Type": "application/json", "Content-Encoding": "gzip"})
        assert r.status_code == 413 and r.json()["type"].endswith("body-too-large"), r.text
        assert "inflates to more than" in r.json()["detail"]
        assert time.perf_counter() - started < 10  # inflating 2 GiB would take far longer


def test_binary_answers_are_not_compressed_and_json_ones_are():
    """Arrow streams and binary segments go as they are: gzip saved ~12% at ~10x the time."""
    import pyarrow as pa
    import shapely

    from tests.geoarrow_tables import ARROW_STREAM, table, to_stream

    gzip_ok = {"Accept-Encoding": "gzip"}
    segments = np.column_stack([np.full(500, -5.0), np.arange(500.0) % 10,
                                np.full(500, 15.0), np.arange(500.0) % 10])
    lines = shapely.linestrings(segments.reshape(-1, 2, 2))
    window = dict(zip(("xmin", "ymin", "xmax", "ymax"), WINDOW, strict=True))
    with make_client(warm_up=False, gzip_min_bytes=1024) as client:
        binary = client.post("/v1/clip/segments", content=segments.astype("<f8").tobytes(),
                             params={**window, "verify": "false"},
                             headers={**gzip_ok, "Content-Type": "application/octet-stream"})
        arrow = client.post("/v1/clip/geoarrow",
                            content=to_stream(table(list(lines), "linestring", "wkb", False)),
                            params={**window, "verify": "false"},
                            headers={**gzip_ok, "Content-Type": ARROW_STREAM})
        json = client.post("/v1/clip/segments", headers=gzip_ok, json={
            "window": WINDOW, "segments": segments.tolist(), "verify": False})
    for r, media in ((binary, "application/octet-stream"), (arrow, ARROW_STREAM)):
        assert r.status_code == 200, r.text
        assert r.headers["content-type"] == media and "content-encoding" not in r.headers
        assert int(r.headers["content-length"]) == len(r.content) > 1024
    assert pa.ipc.open_stream(arrow.content).read_all().num_rows == 500
    assert json.status_code == 200 and json.headers["content-encoding"] == "gzip"
    assert len(json.json()["segments"]) == 500  # httpx inflates it


@pytest.mark.parametrize(("body", "encoding", "status"), [
    (b"not gzip at all", "gzip", 422),
    (b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03", "gzip", 422),  # a header, then nothing
    (b"{}", "br", 415),
])
def test_broken_or_unknown_request_encodings_are_refused(body, encoding, status):
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/segments", content=body,
                        headers={"Content-Type": "application/json",
                                 "Content-Encoding": encoding})
        assert r.status_code == status, r.text
        assert r.headers["content-type"] == "application/problem+json"


@pytest.mark.parametrize("verify", [True, False])
def test_positions_of_four_numbers_give_one_answer_with_or_without_verification(verify):
    """RFC 7946 positions beyond three numbers: read as 3D (the rest dropped), documented."""
    line = {"type": "LineString", "coordinates": [[-5, 5, 1, 2], [15, 5, 3, 4]]}
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": line,
                                                  "verify": verify})
        assert r.status_code == 200, r.text
        assert r.json()["geojson"]["coordinates"] == [[0.0, 5.0, 1.5], [10.0, 5.0, 2.5]]
        if verify:
            assert r.json()["verification"]["passed"]


def test_during_warm_up_each_endpoint_is_served_once_its_kernels_are(monkeypatch):
    """A clip whose kernels are not ready is 503 not-ready at once; ready ones are served."""
    import dataclasses
    import gc
    import logging
    import threading
    import time

    from service import main, warmup

    release = threading.Event()

    def slow_svg():  # stands in for a cold compile of the SVG kernels
        release.wait(20)

    # The tiles step left out: when it finishes (before or after the blocked SVG step)
    # depends on whether warm-up runs in child processes; this test is about SVG.
    steps = tuple(dataclasses.replace(s, run=slow_svg) if s.name == "svg" else s
                  for s in warmup.steps_for() if s.name != "tiles")
    monkeypatch.setattr(main, "steps_for", lambda: steps)
    segments = {"window": WINDOW, "segments": [[-5, 5, 15, 5]]}
    svg = {"window": WINDOW, "paths": ["M -5 5 L 15 5"]}
    records: list[logging.LogRecord] = []
    handler = logging.Handler()
    handler.emit = records.append  # type: ignore[method-assign]
    logger = logging.getLogger("rnsca.service")
    # The app (and its logging) is made here; a plain TestClient does not wait for ready.
    unstarted = TestClient(create_app(Settings(warm_up=True)))
    logger.addHandler(handler)
    with unstarted as client:
        deadline = time.monotonic() + 120
        while "geojson" not in client.get("/readyz").json().get("served", []):
            assert time.monotonic() < deadline
            time.sleep(0.05)
        assert client.post("/v1/clip/segments", json=segments).status_code == 200
        started = time.perf_counter()
        r = client.post("/v1/clip/svg", json=svg)
        assert r.status_code == 503 and r.json()["type"].endswith("not-ready"), r.text
        assert r.headers["Retry-After"] == "2" and "of svg" in r.json()["detail"]
        assert time.perf_counter() - started < 5  # not after the 30 s time limit
        ready = client.get("/readyz")
        assert ready.status_code == 503
        assert ready.json()["served"] == ["geoarrow", "geojson", "segments"]
        release.set()
        while client.get("/readyz").status_code != 200:
            assert time.monotonic() < deadline
            time.sleep(0.05)
        assert client.post("/v1/clip/svg", json=svg).status_code == 200
        assert gc.get_freeze_count() > 0  # start-up's objects are out of the collector's way
    logger.removeHandler(handler)
    steps_logged = [getattr(r, "fields", {}).get("step") for r in records
                    if r.getMessage() == "warmed up"]
    # Segments first; the others in the order they finish (in child processes if the
    # first step found the cache cold, as on a loaded machine it may seem).
    assert steps_logged[0] == "segments"
    assert {"lines", "polygons", "geojson", "svg"} <= set(steps_logged)
    served = [getattr(r, "fields", {}).get("endpoint") for r in records
              if r.getMessage() == "serving"]
    assert served == ["segments", "geoarrow", "geojson", "svg"]


def test_verification_within_its_budget_is_a_random_sample_and_all_is_everything():
    lines = [{"type": "Feature", "properties": {"i": i},
              "geometry": {"type": "LineString", "coordinates": [[-5, i % 10], [15, i % 10]]}}
             for i in range(400)]
    document = {"type": "FeatureCollection", "features": lines}
    # A tiny budget: verification may take a billionth of the clip's time.
    with make_client(verify_cost_ratio=1e-9, warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": document})
        v = r.json()["verification"]
        assert r.status_code == 200 and v["passed"]
        assert v["inputs"] == 400 and v["checked"] == 1
        assert v["sampling"].startswith("random 1 of 400")
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "geojson": document,
                                                  "verify": "all"})
        v = r.json()["verification"]
        assert (v["inputs"], v["checked"], v["sampling"]) == (400, 400, "all")
        segments = [[-5, i % 10, 15, i % 10] for i in range(300)]
        r = client.post("/v1/clip/segments", json={"window": WINDOW, "segments": segments})
        assert r.json()["verification"]["checked"] == 1
        body = np.array(segments, dtype="<f8").tobytes()
        r = client.post("/v1/clip/segments", content=body,
                        params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10, "verify": "all"},
                        headers={"Content-Type": "application/octet-stream"})
        assert orjson.loads(r.headers["X-Rnsca-Verification"])["checked"] == 300
        r = client.post("/v1/clip/svg", json={"window": WINDOW,
                                              "paths": ["M-5 5 L15 5"] * 50})
        assert r.json()["verification"]["checked"] == 1


def random_lines(count: int, vertices: int, seed: int = 0) -> dict:
    """A FeatureCollection of lines of random vertices across the window (each crossing
    itself about vertices**2 / 10 times)."""
    rng = np.random.default_rng(seed)
    return {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"i": i}, "geometry": {
            "type": "LineString", "coordinates": rng.uniform(-2, 12, (vertices, 2)).tolist()}}
        for i in range(count)]}


def test_verify_all_stops_at_the_time_limit_and_the_answer_says_what_it_compared():
    # 21 MB of lines of 2,000 random vertices: GEOS's overlay of each with the window
    # would node 400,000 crossings (past 12 GB in all); compared segment by segment they
    # take about 15 s here, and the server has 10 (of which verification leaves the
    # answer at least as long as reading and clipping took).
    document = random_lines(250, 2000)
    with make_client(request_time_limit=10, warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "verify": "all",
                                                  "geojson": document})
    assert r.status_code == 200, r.text
    body = r.json()
    assert len(body["geojson"]["features"]) == 250
    v = body["verification"]
    assert (v["inputs"], v["sampling"], v["skipped"], v["timed_out"]) == (250, "all", 0, True)
    assert v["checked"] < 250 and v["passed"] is None and v["false_positives"] == 0
    assert v["note"].startswith("stopped at the time limit of ")
    assert v["note"].endswith(f": {250 - v['checked']} of the 250 inputs chosen were not "
                              "compared")


def test_an_input_too_costly_to_verify_is_skipped_and_the_answer_says_so():
    knot = np.random.default_rng(5).uniform(-2, 12, (40, 2)).tolist()  # ~200 crossings
    polygons = [[[*knot, knot[0]]], [[[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]]]
    document = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Polygon",
                                                           "coordinates": rings}}
        for rings in polygons]}
    with make_client(verify_max_crossings=50, warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"window": WINDOW, "verify": "all",
                                                  "geojson": document})
    assert r.status_code == 200, r.text
    v = r.json()["verification"]
    assert (v["inputs"], v["checked"], v["skipped"], v["timed_out"], v["passed"]) == (
        2, 1, 1, False, None)
    assert "max_crossings is 50" in v["note"]
