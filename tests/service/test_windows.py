"""``windows`` beside ``window`` on ``POST /v1/clip/geojson`` and ``/v1/clip/svg``: one
document or path list per window, each equal to a request with that window alone, one
verification of every (input, window) pair, a work budget that counts the windows, and
``max_tiles`` among the limits of ``GET /v1/capabilities``."""

import pytest

import rnsca
from tests.service.conftest import make_client

WINDOWS = [[0, 0, 5, 5], [5, 0, 10, 5], [0, 5, 5, 10], [20, 20, 30, 30]]
DOCUMENT = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "id": 1, "properties": {"name": "road"},
     "geometry": {"type": "LineString", "coordinates": [[-5, 1], [15, 1], [15, 8], [1, 8]]}},
    {"type": "Feature", "properties": {"name": "park"},
     "geometry": {"type": "Polygon", "coordinates": [[[2, 2], [8, 2], [8, 8], [2, 2]]]}},
    {"type": "Feature", "properties": {"name": "well"},
     "geometry": {"type": "Point", "coordinates": [6, 1]}}]}


def test_geojson_windows_answer_one_document_per_window(client):
    r = client.post("/v1/clip/geojson", json={"windows": WINDOWS, "geojson": DOCUMENT})
    assert r.status_code == 200, r.text
    body = r.json()
    assert len(body["geojson"]) == len(WINDOWS)
    for window, document in zip(WINDOWS, body["geojson"], strict=True):
        one = client.post("/v1/clip/geojson", json={"window": window, "geojson": DOCUMENT,
                                                    "verify": False})
        assert one.status_code == 200
        assert document == one.json()["geojson"]
    assert [f["properties"]["name"] for f in body["geojson"][1]["features"]] == [
        "road", "park", "well"]
    assert body["geojson"][3]["features"] == []


def test_svg_windows_answer_one_path_list_per_window(client):
    paths = ["M -5 5 C 0 15 10 -5 15 5", "M 1 1 L 9 9"]
    r = client.post("/v1/clip/svg", json={"windows": WINDOWS, "paths": paths})
    assert r.status_code == 200, r.text
    body = r.json()
    assert len(body["paths"]) == len(WINDOWS)
    for window, clipped in zip(WINDOWS, body["paths"], strict=True):
        assert clipped == rnsca.clip_svg(paths, window)[0]
    assert body["paths"][3] == ["", ""]


@pytest.mark.parametrize("body", [
    {"geojson": DOCUMENT},
    {"window": [0, 0, 1, 1], "windows": WINDOWS, "geojson": DOCUMENT},
    {"windows": [], "geojson": DOCUMENT},
])
def test_exactly_one_of_window_and_windows_else_422(client, body):
    r = client.post("/v1/clip/geojson", json=body)
    assert r.status_code == 422, r.text


def test_a_bad_window_among_many_is_422_naming_it(client):
    r = client.post("/v1/clip/geojson", json={"windows": [[0, 0, 1, 1], [5, 5, 1, 1]],
                                              "geojson": DOCUMENT})
    assert r.status_code == 422 and "window 1" in r.json()["detail"]
    r = client.post("/v1/clip/svg", json={"windows": [[0, 0, 1, 1], [5, 5, 1, 1]],
                                          "paths": ["M 0 0 L 1 1"]})
    assert r.status_code == 422 and "window 1" in r.json()["detail"]


def test_the_work_budget_counts_every_vertex_once_per_window():
    line = {"type": "LineString", "coordinates": [[i, 1] for i in range(-5, 45)]}
    # 50 vertices; approx mode with n=2, max_depth=4 charges 33 fragments a vertex.
    options = {"mode": "approx", "n": 2, "max_depth": 4}
    with make_client(work_budget=50 * 33 * 3, warm_up=False) as client:
        r = client.post("/v1/clip/geojson", json={"windows": WINDOWS[:3], "geojson": line,
                                                  "options": options})
        assert r.status_code == 200, r.text
        r = client.post("/v1/clip/geojson", json={"windows": WINDOWS, "geojson": line,
                                                  "options": options})
        assert r.status_code == 422 and r.json()["type"].endswith("work-over-budget")
        path = {"paths": ["M " + " L ".join(f"{i} 1" for i in range(50))],
                "options": options}
        assert client.post("/v1/clip/svg", json={**path, "windows": WINDOWS[:3]}
                           ).status_code == 200
        r = client.post("/v1/clip/svg", json={**path, "windows": WINDOWS})
        assert r.status_code == 422 and r.json()["type"].endswith("work-over-budget")


PATHS = ["M -5 5 C 0 15 10 -5 15 5", "M 1 1 L 9 9", "M 2 2 Q 12 4 8 8 Z"]


@pytest.mark.parametrize("options", [{}, {"fill": "nonzero"}, {"fill": "evenodd"},
                                     {"curves": "flatten"}, {"fill": "nonzero",
                                                             "fill_output": "raw"}])
def test_svg_windows_equal_one_request_per_window(client, options):
    r = client.post("/v1/clip/svg", json={"windows": WINDOWS, "paths": PATHS,
                                          "options": options, "verify": False})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["verification"] is None
    for window, clipped in zip(WINDOWS, body["paths"], strict=True):
        one = client.post("/v1/clip/svg", json={"window": window, "paths": PATHS,
                                                "options": options, "verify": False})
        assert one.status_code == 200
        assert clipped == one.json()["paths"], window


def test_svg_windows_are_clipped_in_one_library_call(client, monkeypatch):
    calls = []
    clip_paths = rnsca.clip_paths

    def counted(*args, **kwargs):
        calls.append(kwargs.get("windows") is not None)
        return clip_paths(*args, **kwargs)

    monkeypatch.setattr(rnsca, "clip_paths", counted)
    r = client.post("/v1/clip/svg", json={"windows": WINDOWS, "paths": PATHS,
                                          "verify": False})
    assert r.status_code == 200, r.text
    assert calls == [True]


@pytest.mark.parametrize("endpoint, body", [
    ("/v1/clip/svg", {"paths": PATHS}),
    ("/v1/clip/svg", {"paths": PATHS, "options": {"fill": "nonzero"}}),
    ("/v1/clip/geojson", {"geojson": DOCUMENT}),
])
def test_verify_with_windows_compares_every_pair_with_shapely(client, endpoint, body):
    r = client.post(endpoint, json={**body, "windows": WINDOWS, "verify": "all"})
    assert r.status_code == 200, r.text
    verification = r.json()["verification"]
    assert verification["passed"] is True and verification["mode"] == "exact"
    # The pairs whose boxes touch: none in the far window, some in each of the others.
    assert verification["inputs"] == verification["checked"] > len(WINDOWS) - 1
    assert verification["false_positives"] == 0 and verification["sampling"] == "all"
    # true: within the verification budget (a sample past it), as for one window; and
    # by default (inputs under the server's verify_max_vertices).
    for verify in ({"verify": True}, {}):
        r = client.post(endpoint, json={**body, "windows": WINDOWS, **verify})
        budgeted = r.json()["verification"]
        assert budgeted["inputs"] == verification["inputs"] >= budgeted["checked"] >= 1
        assert budgeted["passed"] is not False


def test_geojson_windows_verification_counts_the_pairs(client):
    line = {"type": "LineString", "coordinates": [[-5, 1], [15, 1]]}
    r = client.post("/v1/clip/geojson", json={"windows": WINDOWS, "geojson": line,
                                              "verify": "all"})
    assert r.status_code == 200, r.text
    verification = r.json()["verification"]
    # The line's box (y = 1) touches the two lower windows only.
    assert verification["inputs"] == verification["checked"] == 2
    assert verification["passed"] is True


def test_approx_windows_are_verified_with_a_bound_only(client):
    line = {"type": "LineString", "coordinates": [[-5, 1], [15, 1]]}
    options = {"mode": "approx", "resolution": 0.01}
    r = client.post("/v1/clip/geojson", json={"windows": WINDOWS, "geojson": line,
                                              "options": options})
    assert r.status_code == 200 and r.json()["verification"] is None
    r = client.post("/v1/clip/geojson", json={"windows": WINDOWS, "geojson": line,
                                              "options": options, "verify": "all",
                                              "approx_bound": 0.05})
    assert r.status_code == 200 and r.json()["verification"]["passed"] is True
    r = client.post("/v1/clip/svg", json={"windows": WINDOWS, "paths": PATHS,
                                          "options": options, "verify": True})
    assert r.status_code == 200 and r.json()["verification"] is None


@pytest.mark.parametrize("windows, where", [
    ([[0, 0, 1, 1], [0, 0, 1]], "windows[1]"),
    ([[0, 0, 1, 1], [0, 0, 1, float("nan")]], "windows[1]"),
    ([[0, 0, 1, 1], [0, 0, 1, "1"]], "windows[1]"),
    ([], "windows"),
])
def test_bad_windows_are_problem_json_422_naming_them(client, windows, where):
    import json

    for endpoint, extra in (("/v1/clip/svg", {"paths": PATHS}),
                            ("/v1/clip/geojson", {"geojson": DOCUMENT})):
        # NaN is not JSON: sent as the text Python writes (the server must still refuse).
        r = client.post(endpoint, content=json.dumps({**extra, "windows": windows}),
                        headers={"Content-Type": "application/json"})
        assert r.status_code in (400, 422), r.text
        assert r.headers["content-type"].startswith("application/problem+json")
        problem = r.json()
        assert problem["status"] == r.status_code
        if r.status_code == 422:
            assert where in (problem.get("path") or "") + problem["detail"], problem


def test_capabilities_name_max_tiles_beside_the_other_limits():
    with make_client(max_tiles=321, warm_up=False) as client:
        r = client.get("/v1/capabilities")
    assert r.status_code == 200
    limits = r.json()["limits"]
    assert limits["max_tiles"] == 321
    assert {"max_body_bytes", "max_vertices", "work_budget"} <= set(limits)
