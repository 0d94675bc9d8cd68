"""``windows`` beside ``window`` on ``POST /v1/clip/geojson`` and ``/v1/clip/svg``: one
document or path list per window, each equal to a request with that window alone, and
a work budget that counts the windows."""

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
    assert len(body["geojson"]) == len(WINDOWS) and body["verification"] is None
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
