"""GeoArrow that Shapely 2.2 crashes on, sent to a real server: it answers and stays up.

A multipolygon with a polygon of no rings (or a polygon whose exterior is empty but has
holes) is valid GeoArrow; ``shapely.from_ragged_array`` segfaults on it, which used to
kill the server process as soon as verification (the default) read the input back. The
TestClient tests (`tests/service/test_geoarrow.py`) would die with the server here, so
this one runs it in a subprocess and checks that it is still alive after each request.
"""

from __future__ import annotations

import httpx
import pytest
import shapely

from tests.e2e.server import LiveServer
from tests.geoarrow_tables import ARROW_STREAM, from_stream, raw_native, table, to_stream

pytestmark = pytest.mark.e2e

SQUARE = [[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]
HOLE = [[1, 1], [1, 2], [2, 2], [2, 1], [1, 1]]
BODIES = {
    "ringless polygon": raw_native("multipolygon", SQUARE, [0, 2, 3], [0, 0, 1, 1], [0, 5]),
    "empty exterior": raw_native("multipolygon", HOLE, [0, 1], [0, 2], [0, 0, 5]),
    "empty exterior, polygon": raw_native("polygon", HOLE, [0, 2], [0, 0, 5]),
    "wkb empty polygon": to_stream(table([shapely.from_wkt(
        "MULTIPOLYGON (EMPTY, ((-5 -5, 5 -5, 5 5, -5 5, -5 -5)))")], "wkb", "wkb", False)),
}


@pytest.fixture(scope="module")
def server():
    with LiveServer() as live:
        yield live


@pytest.mark.parametrize("verify", ["true", "false", "all"])
@pytest.mark.parametrize("name", BODIES)
def test_the_server_answers_and_stays_up(server, name, verify):
    r = httpx.post(server.url + "/v1/clip/geoarrow", content=BODIES[name],
                   params={"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10, "verify": verify,
                           "check_validity": "true"},
                   headers={"Content-Type": ARROW_STREAM}, timeout=60)
    assert r.status_code == 200, r.text
    rows = from_stream(r.content).num_rows
    assert rows == (0 if "exterior" in name else 1)
    assert server.process.poll() is None, server.log()
    assert httpx.get(server.url + "/healthz", timeout=10).status_code == 200
