"""The playground in a real headless Chromium (Debian's ``chromium``, driven by Playwright)
against a live server: load an example, drag and resize the window with the mouse, and
check that what is drawn and the numbers shown are the API's answer for that window; in
the tile view, check the grid and that a clicked tile's decoded content is what
`mapbox-vector-tile` reads from the same tile.

Screenshots go to ``test-artifacts/`` at the repository's root (ignored by git).
"""

from __future__ import annotations

import json
import math
import re
import xml.etree.ElementTree as ET

import httpx
import pytest
import shapely

from tests.e2e.server import ROOT, LiveServer

pytestmark = pytest.mark.e2e

ARTIFACTS = ROOT / "test-artifacts"
#: Every wait in the page is bounded by this (ms): a stuck page fails, never hangs.
WAIT_MS = 30_000

# What the page shows, read back in one go (see the test hooks in playground.js).
SNAPSHOT = """() => {
  const value = (el) => Number(el.dataset.value);
  const byKey = (sel) => Object.fromEntries([...document.querySelectorAll(sel)].map(
      (el) => [el.dataset.key || el.closest("tr").dataset.key, value(el)]));
  return {
    state: document.body.dataset.state,
    inputs: ["xmin", "ymin", "xmax", "ymax"].map((id) => Number(document.getElementById(id).value)),
    shownWindow: JSON.parse(document.getElementById("results").dataset.window || "null"),
    summary: byKey("#summary dd"),
    stats: byKey("#stats td[data-value]"),
    passed: document.getElementById("verification").dataset.passed,
    drawn: [...document.querySelectorAll("#output-layer path")].map((p) => p.getAttribute("d")),
    error: document.getElementById("error").hidden ? null
                                                   : document.getElementById("error").innerText,
  };
}"""


@pytest.fixture(scope="module")
def server():
    with LiveServer() as live:
        yield live


@pytest.fixture
def page(browser, server):
    # Clipboard permissions: the Copy button writes there, and the tests read it back.
    context = browser.new_context(viewport={"width": 1400, "height": 900},
                                  permissions=["clipboard-read", "clipboard-write"])
    page = context.new_page()
    page.set_default_timeout(WAIT_MS)
    errors, missing = [], []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("response", lambda r: r.status == 404 and missing.append(r.url))
    page.goto(server.url + "/")
    page.wait_for_selector("body[data-state=idle]")
    yield page
    context.close()
    assert not errors, errors
    assert not missing, missing   # the page's files, its icon (/favicon.ico) included


@pytest.fixture(scope="module")
def api(server):
    with httpx.Client(base_url=server.url, timeout=60) as client:
        yield client


def settled(page) -> dict:
    """Return the page's snapshot once no request is pending or in flight."""
    page.wait_for_selector("body[data-state=idle], body[data-state=error]")
    return page.evaluate(SNAPSHOT)


def screenshot(page, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / f"playground-{name}.png"
    page.screenshot(path=str(path), full_page=True)
    print(f"screenshot: {path}")


def drag(page, selector: str, dx: float, dy: float) -> None:
    """Drag the element at `selector` by (dx, dy) screen pixels, in steps, with the mouse."""
    box = page.locator(selector).bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + dx, y + dy, steps=8)
    page.mouse.up()


def numbers(d: str) -> list[float]:
    return [float(v) for v in re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", d)]


def coordinates(geojson: dict) -> list[float]:
    """Every coordinate of a document in the order the page draws them."""
    out = []

    def walk(value):
        if isinstance(value, (int, float)):
            out.append(float(value))
        else:
            for item in value:
                walk(item)

    for feature in geojson.get("features", [geojson]):
        geometry = feature.get("geometry", feature)
        if geometry:
            walk(geometry["coordinates"])
    return out


def example_text(api, name: str) -> str:
    return api.get(f"/playground/examples/{name}").text


def check_geojson_against_api(api, shown: dict, document: dict, options: dict,
                              **extra) -> dict:
    """The page's output, stats and summary equal the API's answer for the shown window."""
    assert shown["state"] == "idle" and shown["error"] is None
    assert shown["shownWindow"] == shown["inputs"]
    answer = api.post("/v1/clip/geojson", json={
        "window": shown["inputs"], "geojson": document, "options": options, **extra})
    assert answer.status_code == 200, answer.text
    result = answer.json()
    assert [v for d in shown["drawn"] for v in numbers(d)] == coordinates(result["geojson"])
    for key, value in shown["stats"].items():
        assert value == pytest.approx(result["stats"][key], rel=1e-12), key
    geometries = [shapely.geometry.shape(f["geometry"]) for f in result["geojson"]["features"]]
    length = sum(g.length for g in geometries if g.geom_type.endswith("LineString"))
    area = sum(g.area for g in geometries)
    if length:
        assert math.isclose(shown["summary"]["length"], length, rel_tol=1e-9)
    if area:
        assert math.isclose(shown["summary"]["area"], area, rel_tol=1e-9)
    assert shown["summary"]["vertices"] == result["stats"]["vertices_out"]
    verified = result["verification"]
    # As JavaScript's String() writes it: "true", "false" or "null" (no verdict).
    assert shown["passed"] == ("" if verified is None else json.dumps(verified["passed"]))
    return result


def test_coastline_window_moved_and_resized_with_the_mouse(page, api):
    document = json.loads(example_text(api, "coastline.geojson"))
    options = {"method": "rnsca", "mode": "exact", "boundary": "closed"}
    page.select_option("#example", "coastline")
    first = settled(page)
    assert first["inputs"] == [25, 20, 70, 55] and first["drawn"]
    check_geojson_against_api(api, first, document, options, verify=True)

    drag(page, "#window-rect", 90, -60)                 # move right and up (north)
    moved = settled(page)
    width = lambda w: (w[2] - w[0], w[3] - w[1])  # noqa: E731
    assert moved["inputs"][0] > first["inputs"][0] and moved["inputs"][1] > first["inputs"][1]
    assert width(moved["inputs"]) == pytest.approx(width(first["inputs"]), abs=0.2)
    assert moved["drawn"] != first["drawn"] and moved["stats"] != first["stats"]
    check_geojson_against_api(api, moved, document, options, verify=True)

    drag(page, '#handles circle[data-handle="xmax,ymax"]', 70, -50)   # resize the NE corner
    resized = settled(page)
    assert resized["inputs"][:2] == moved["inputs"][:2]
    assert resized["inputs"][2] > moved["inputs"][2] and resized["inputs"][3] > moved["inputs"][3]
    assert resized["summary"]["length"] != moved["summary"]["length"]
    check_geojson_against_api(api, resized, document, options, verify=True)
    assert resized["passed"] == "true"
    screenshot(page, "coastline")


def test_polygons_window_widened_with_an_edge_handle(page, api):
    document = json.loads(example_text(api, "polygons-with-holes.geojson"))
    page.select_option("#example", "polygons")
    first = settled(page)
    check_geojson_against_api(api, first, document, {"boundary": "closed"}, verify=True)

    drag(page, '#handles circle[data-handle="xmin"]', -40, 0)      # widen to the west
    wider = settled(page)
    assert wider["inputs"][0] < first["inputs"][0] and wider["inputs"][1:] == first["inputs"][1:]
    assert wider["summary"]["area"] > first["summary"]["area"]
    check_geojson_against_api(api, wider, document, {"boundary": "closed"}, verify=True)
    screenshot(page, "polygons")
    # Polygons have no approx mode (the server would answer 422): it is not offered.
    assert offered(page, "#mode") == {"exact": True, "approx": False}
    assert page.input_value("#mode") == "exact"
    assert "polygons: mode exact only" in page.inner_text("#options-note")


def test_options_reach_the_server_and_change_the_statistics(page, api):
    document = json.loads(example_text(api, "coastline.geojson"))
    page.select_option("#example", "coastline")
    exact = settled(page)
    page.fill("#n", "4")
    page.fill("#max_depth", "3")
    page.fill("#approx_bound", "5")
    page.select_option("#mode", "approx")
    approx = settled(page)
    assert approx["stats"]["dropped"] > 0 and approx["stats"]["deepest_level"] == 3
    assert approx["stats"]["fragments_evaluated"] != exact["stats"]["fragments_evaluated"]
    assert approx["summary"]["length"] < exact["summary"]["length"]
    options = {"method": "rnsca", "mode": "approx", "n": 4, "max_depth": 3,
               "boundary": "closed"}
    check_geojson_against_api(api, approx, document, options, verify=True, approx_bound=5)
    assert approx["passed"] == "true"
    screenshot(page, "approx")


def test_glyph_outlines_are_clipped_as_the_svg_endpoint_clips_them(page, api):
    paths = example_text(api, "glyphs-dejavu-sans.txt").splitlines()
    page.select_option("#example", "glyphs")
    first = settled(page)
    drag(page, "#window-rect", 120, 40)
    moved = settled(page)
    assert moved["inputs"] != first["inputs"] and moved["shownWindow"] == moved["inputs"]
    answer = api.post("/v1/clip/svg", json={
        "window": moved["inputs"], "paths": paths,
        "options": {"method": "rnsca", "mode": "exact", "curves": "preserve",
                    "fill": "nonzero"}}).json()
    assert moved["drawn"] == [d for d in answer["paths"] if d]
    assert moved["stats"]["pieces_out"] == answer["stats"]["pieces_out"]
    assert moved["passed"] == "true" and answer["verification"]["passed"]
    assert moved["summary"]["paths"] == len(moved["drawn"])
    screenshot(page, "glyphs")


def test_errors_are_shown_readably(page):
    page.fill("#input-text", "{not json")
    shown = settled(page)
    assert shown["state"] == "error" and "not valid JSON" in shown["error"]

    broken = {"type": "Polygon", "coordinates": [[[0, 0], [4, 0], [4, 4]]]}
    page.fill("#input-text", json.dumps(broken))
    shown = settled(page)
    assert shown["state"] == "error" and shown["drawn"] == []
    assert "422" in shown["error"] and "Invalid geometry" in shown["error"]
    assert "geojson.coordinates[0]" in shown["error"]

    page.fill("#input-text", json.dumps({"type": "LineString",
                                         "coordinates": [[-5, 1], [5, 1]]}))
    shown = settled(page)   # a flat input still gets a window, and a result
    assert shown["state"] == "idle" and shown["summary"]["length"] == 5
    page.fill("#xmin", "100")
    page.dispatch_event("#xmin", "change")
    shown = settled(page)
    assert "Invalid window" in shown["error"] and "xmin" in shown["error"]
    screenshot(page, "error")


def test_an_svg_document_loaded_from_a_file(page, api):
    document = (b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 20 20">'
                b'<path d="M -5 5 L 15 5"/><g><path d="M 2 -3 Q 5 20 8 -3"/></g></svg>')
    page.set_input_files("#file", files=[{"name": "shapes.svg", "mimeType": "image/svg+xml",
                                          "buffer": document}])
    shown = settled(page)
    assert "2 path(s)" in page.inner_text("#input-info")
    assert shown["state"] == "idle" and shown["shownWindow"] == shown["inputs"]
    answer = api.post("/v1/clip/svg", json={
        "window": shown["inputs"], "paths": ["M -5 5 L 15 5", "M 2 -3 Q 5 20 8 -3"],
        "options": {"curves": "preserve", "fill": None}}).json()
    assert shown["drawn"] == [d for d in answer["paths"] if d] and len(shown["drawn"]) == 2
    assert shown["stats"]["pieces_out"] == answer["stats"]["pieces_out"]


def offered(page, select: str) -> dict:
    """Return {value: enabled} of the options of `select`."""
    return page.eval_on_selector(select, """(s) => Object.fromEntries(
        [...s.options].map((o) => [o.value, !o.disabled]))""")


def test_options_offered_follow_the_capabilities_for_the_input(page, api):
    operations = api.get("/v1/capabilities").json()["operations"]
    page.select_option("#example", "coastline")            # lines: every method and mode
    settled(page)
    assert all(offered(page, "#mode").values()) and all(offered(page, "#method").values())
    assert page.inner_text("#options-note") == ""
    page.select_option("#mode", "approx")
    assert settled(page)["state"] == "idle"

    page.select_option("#example", "polygons")             # approx falls back to exact
    shown = settled(page)
    assert shown["state"] == "idle" and shown["error"] is None and shown["drawn"]
    assert page.input_value("#mode") == "exact"
    assert [m for m, on in offered(page, "#mode").items() if on] == \
        operations["polygons"]["modes"]

    page.select_option("#method", "liang_barsky")
    settled(page)
    page.select_option("#example", "glyphs")               # curves: method rnsca only
    shown = settled(page)
    assert shown["state"] == "idle" and page.input_value("#method") == "rnsca"
    assert [m for m, on in offered(page, "#method").items() if on] == \
        operations["paths"]["methods"] == ["rnsca"]
    assert all(offered(page, "#mode").values())
    assert "paths: method rnsca only" in page.inner_text("#options-note")


def test_the_geojson_result_is_copied_and_downloaded(page, api):
    document = json.loads(example_text(api, "coastline.geojson"))
    page.select_option("#example", "coastline")
    shown = settled(page)
    result = check_geojson_against_api(api, shown, document,
                                       {"method": "rnsca", "mode": "exact",
                                        "boundary": "closed"}, verify=True)
    page.click("#copy")
    page.wait_for_selector("#copy-status[data-copied=true]")
    assert json.loads(page.evaluate("navigator.clipboard.readText()")) == result["geojson"]
    with page.expect_download() as info:
        page.click("#download")
    download = info.value
    assert download.suggested_filename == "clipped.geojson"
    with open(download.path(), encoding="utf-8") as f:
        assert json.load(f) == result["geojson"]


def test_the_svg_result_is_copied_and_downloaded_as_an_svg_document(page, api):
    paths = example_text(api, "glyphs-dejavu-sans.txt").splitlines()
    page.select_option("#example", "glyphs")
    shown = settled(page)
    answer = api.post("/v1/clip/svg", json={
        "window": shown["inputs"], "paths": paths,
        "options": {"curves": "preserve", "fill": "nonzero"}}).json()
    page.click("#copy")
    page.wait_for_selector("#copy-status[data-copied=true]")
    copied = page.evaluate("navigator.clipboard.readText()")
    with page.expect_download() as info:
        page.click("#download")
    assert info.value.suggested_filename == "clipped.svg"
    with open(info.value.path(), encoding="utf-8") as f:
        downloaded = f.read()
    assert downloaded == copied
    svg = ET.fromstring(downloaded)
    ns = "{http://www.w3.org/2000/svg}"
    assert svg.tag == ns + "svg"
    x0, y0, x1, y1 = shown["inputs"]
    assert [float(v) for v in svg.get("viewBox").split()] == pytest.approx(
        [x0, y0, x1 - x0, y1 - y0])
    drawn = svg.findall(ns + "path")
    assert [p.get("d") for p in drawn] == [d for d in answer["paths"] if d]
    assert {p.get("fill-rule") for p in drawn} == {"nonzero"}


def test_counts_are_written_in_one_format(page, api):
    document = json.loads(example_text(api, "coastline.geojson"))
    page.select_option("#example", "coastline")
    shown = settled(page)
    vertices = len(coordinates(document)) // 2
    assert vertices >= 1000   # so that the digits are grouped
    assert f"{vertices:,} vertices" in page.inner_text("#input-info")
    out = page.inner_text('#summary dd[data-key="vertices"]')
    assert out == f"{shown['summary']['vertices']:,.0f}"
    for text in page.eval_on_selector_all(
            "#summary dd, #stats td[data-value]",
            "(cells) => cells.filter((c) => Number.isInteger(Number(c.dataset.value)))"
            ".map((c) => c.textContent)"):
        assert re.fullmatch(r"\d{1,3}(,\d{3})*", text), text


def test_the_page_has_an_icon(page, server, api):
    href = page.get_attribute('link[rel="icon"]', "href")
    icon = api.get("/" + href)
    assert icon.status_code == 200 and icon.headers["content-type"] == "image/svg+xml"
    assert api.get("/favicon.ico").content == icon.content


# --- the tile view -----------------------------------------------------------------

#: Lon/lat features for the tile view: a polygon with a hole and properties of every kind
#: MVT stores (a negative int64, an int past 2**53, a double, a bool, a string), a line
#: and a point; their bounds are lon -5..20, lat 40..55.
TILE_INPUT = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "id": 11, "properties": {
        "name": "block", "rank": -3, "big": 2**60 + 1, "area": 12.5, "open": True},
     "geometry": {"type": "Polygon", "coordinates": [
         [[2, 45], [14, 45], [14, 52], [2, 52], [2, 45]],
         [[5, 47], [5, 50], [9, 50], [9, 47], [5, 47]]]}},
    {"type": "Feature", "properties": {"name": "road", "lanes": 2},
     "geometry": {"type": "LineString", "coordinates": [[-5, 40], [8, 48.5], [20, 55]]}},
    {"type": "Feature", "id": 3, "properties": {"name": "well"},
     "geometry": {"type": "Point", "coordinates": [8.25, 49.5]}},
]}


def world_tile(lon: float, lat: float, z: int) -> tuple[float, float]:
    """Return the (fractional) WebMercatorQuad column and row of a lon/lat at zoom z."""
    n = 2**z
    lat = math.radians(lat)
    return (lon + 180) / 360 * n, (1 - math.asinh(math.tan(lat)) / math.pi) / 2 * n


def tiles_over_bounds(bounds, z: int) -> set[str]:
    """The tiles of zoom z from the one holding the bounds' north-west corner to the one
    holding their south-east corner (an edge on a tile line counts to the east / south)."""
    x0, y0 = world_tile(bounds[0], bounds[3], z)
    x1, y1 = world_tile(bounds[2], bounds[1], z)
    columns = range(math.floor(x0), max(math.floor(x0), math.ceil(x1) - 1) + 1)
    rows = range(math.floor(y0), max(math.floor(y0), math.ceil(y1) - 1) + 1)
    return {f"{z}/{x}/{y}" for x in columns for y in rows}


def open_tile_view(page, document: dict) -> None:
    page.check("#view-tiles")
    page.fill("#input-text", json.dumps(document))
    assert settled(page)["state"] == "idle"


def grid_tiles(page) -> list[str]:
    return page.eval_on_selector_all("#grid-tiles rect[data-tile]",
                                     "(rects) => rects.map((r) => r.dataset.tile)")


def set_tile_option(page, selector: str, value: str) -> None:
    page.fill(selector, value)
    page.dispatch_event(selector, "change")


def shown_tile(page, tile: str) -> dict:
    """Click `tile` in the grid; return the decoded content the page shows (its JSON)."""
    page.click(f'#grid-tiles rect[data-tile="{tile}"]')
    page.wait_for_selector(f'#tile-result[data-tile="{tile}"]')
    assert settled(page)["error"] is None
    return json.loads(page.text_content("#tile-json"))


def decoded_by_mapbox_vector_tile(data: bytes) -> list[dict]:
    """The tile's layers as `mapbox_vector_tile` reads them, in the page's JSON shape."""
    import mapbox_vector_tile

    layers = mapbox_vector_tile.decode(data, default_options={"y_coord_down": True})
    return [{"name": name, "version": layer["version"], "extent": layer["extent"],
             "features": [{"id": f["id"], "properties": f["properties"],
                           "geometry": f["geometry"]} for f in layer["features"]]}
            for name, layer in layers.items()]


def comparable(layer: dict) -> dict:
    """A layer the page decoded, in the shape of `decoded_by_mapbox_vector_tile`'s: an id
    the tile does not have (null on the page) is 0 there."""
    return {"name": layer["name"], "version": layer["version"], "extent": layer["extent"],
            "features": [{"id": 0 if f["id"] is None else f["id"],
                          "properties": f["properties"], "geometry": f["geometry"]}
                         for f in layer["features"]]}


def zigzag_commands(parts: list[tuple[str, list[tuple[int, int]]]]) -> list[int]:
    """MVT geometry commands for parts [(kind, points)]: kind "line" (MoveTo, LineTo),
    "ring" (the same, then ClosePath) or "points" (one MoveTo of them all)."""
    out, x, y = [], 0, 0

    def deltas(points):
        nonlocal x, y
        for px, py in points:
            out.extend([((px - x) << 1) ^ ((px - x) >> 31), ((py - y) << 1) ^ ((py - y) >> 31)])
            x, y = px, py

    for kind, points in parts:
        first = points if kind == "points" else points[:1]
        out.append((len(first) << 3) | 1)
        deltas(first)
        if kind != "points":
            out.append(((len(points) - 1) << 3) | 2)
            deltas(points[1:])
        if kind == "ring":
            out.append((1 << 3) | 7)
    return out


def test_the_page_decoder_reads_what_mapbox_vector_tile_reads(page):
    """Every kind of value (float32 and 64-bit integers among them), ids past 2**53 and
    none, multi-part geometry, holes and a zero-area ring, in a tile written by protobuf."""
    from mapbox_vector_tile.Mapbox import vector_tile_pb2

    tile = vector_tile_pb2.tile()
    layer = tile.layers.add(name="kinds", version=2, extent=256)
    values = [("string_value", "é ünïcode"), ("float_value", 0.1),
              ("double_value", -2.5e300), ("int_value", -(2**63)),
              ("uint_value", 2**64 - 1), ("sint_value", -(2**62) - 1),
              ("bool_value", False), ("int_value", 7)]
    for i, (kind, value) in enumerate(values):
        layer.keys.append(f"k{i}")
        layer.values.add(**{kind: value})
    polygon = layer.features.add(id=2**64 - 1, type=3, tags=[0, 0, 1, 1, 2, 2, 3, 3])
    polygon.geometry.extend(zigzag_commands([
        ("ring", [(0, 0), (10, 0), (10, 10), (0, 10)]),
        ("ring", [(2, 2), (2, 8), (8, 8), (8, 2)]),              # a hole
        ("ring", [(40, 40), (50, 40), (60, 40)]),                # zero area: dropped
        ("ring", [(-20, 20), (-10, 20), (-10, 30), (-20, 30)])]))
    lines = layer.features.add(id=5, type=2, tags=[4, 4, 5, 5, 6, 6])
    lines.geometry.extend(zigzag_commands([("line", [(-64, 3), (300, 4), (7, 250)]),
                                           ("line", [(1, 1), (2, 2)])]))
    points = layer.features.add(type=1, tags=[7, 7])
    points.geometry.extend(zigzag_commands([("points", [(5, 5), (-3, 9), (256, 256)])]))
    single = layer.features.add(type=1)
    single.geometry.extend(zigzag_commands([("points", [(1, 2)])]))
    data = tile.SerializeToString()

    decoded = json.loads(page.evaluate("""async (bytes) => {
        const mvt = await import("./playground/mvt.js");
        return mvt.tileJson(mvt.decodeTile(new Uint8Array(bytes)));
    }""", list(data)))
    assert [comparable(layer) for layer in decoded] == decoded_by_mapbox_vector_tile(data)
    features = decoded[0]["features"]
    assert features[0]["id"] == 2**64 - 1 and features[0]["properties"]["k3"] == -(2**63)
    assert features[1]["properties"] == {"k4": 2**64 - 1, "k5": -(2**62) - 1, "k6": False}
    assert features[0]["properties"]["k1"] == 0.10000000149011612     # float32 0.1
    assert [f["geometry"]["type"] for f in features] == [
        "MultiPolygon", "MultiLineString", "MultiPoint", "Point"]
    assert [len(p) for p in features[0]["geometry"]["coordinates"]] == [2, 1]
    assert features[2]["id"] is None


def test_the_tile_grid_covers_the_input_bounds(page):
    open_tile_view(page, TILE_INPUT)
    assert page.is_hidden("#canvas") and page.is_visible("#grid-canvas")
    assert page.is_hidden("#window-rect") and page.is_visible("#zoom")
    page.select_option("#zoom", "4")
    assert sorted(grid_tiles(page)) == ["4/7/5", "4/7/6", "4/8/5", "4/8/6"]
    assert set(grid_tiles(page)) == tiles_over_bounds([-5, 40, 20, 55], 4)
    labels = page.eval_on_selector_all("#grid-tiles text", "(ts) => ts.map((t) => t.textContent)")
    assert sorted(labels) == sorted(grid_tiles(page))
    page.select_option("#zoom", "7")
    assert set(grid_tiles(page)) == tiles_over_bounds([-5, 40, 20, 55], 7)
    assert len(grid_tiles(page)) == 90 and "90 tile(s)" in page.inner_text("#grid-note")
    page.select_option("#zoom", "12")                # too many tiles to draw: a note says so
    assert grid_tiles(page) == []
    assert "72,960 tiles at zoom 12" in page.inner_text("#grid-note")
    assert "zoom 8 or less" in page.inner_text("#grid-note")
    screenshot(page, "tile-grid")


def test_a_clicked_tile_shows_what_an_independent_decoder_reads(page, api):
    open_tile_view(page, TILE_INPUT)
    page.select_option("#zoom", "4")
    set_tile_option(page, "#tile-extent", "512")
    set_tile_option(page, "#tile-buffer", "16")
    features = 0
    for tile in ["4/8/5", "4/7/5", "4/8/6", "4/7/6"]:
        shown = shown_tile(page, tile)
        answer = api.post(f"/v1/tiles/{tile}", params={"extent": 512, "buffer": 16},
                          content=json.dumps(TILE_INPUT),
                          headers={"Content-Type": "application/geo+json"})
        assert answer.status_code in (200, 204), answer.text
        assert shown["tile"] == tile and shown["bytes"] == len(answer.content)
        assert page.get_attribute("#tile-result", "data-bytes") == str(len(answer.content))
        expected = decoded_by_mapbox_vector_tile(answer.content)
        assert [comparable(layer) for layer in shown["layers"]] == expected
        for layer in shown["layers"]:
            for feature in layer["features"]:        # the feature's type, as the tile has it
                assert feature["geometry"]["type"].removeprefix("Multi") == feature["type"]
        count = sum(len(layer["features"]) for layer in expected)
        features += count
        drawn = page.eval_on_selector_all("#tile-features path", "(ps) => ps.length")
        assert (drawn >= count) and (drawn > 0) == (count > 0)
        listed = page.eval_on_selector_all(".tile-layer tbody tr", "(rows) => rows.length")
        assert listed == count
        assert page.get_attribute("#tile-summary dd[data-key=bytes]", "data-value") == \
            str(len(answer.content))
    assert features >= 4            # the polygon, the line and the point, in some tile
    # The tile is drawn in its own units, the buffer shown around the extent square.
    view_box = [float(v) for v in page.get_attribute("#tile-canvas", "viewBox").split()]
    assert view_box[0] < -16 and view_box[0] + view_box[2] > 512 + 16
    assert page.get_attribute("#tile-extent-rect", "width") == "512"
    assert page.get_attribute("#tile-buffer-rect", "x") == "-16"
    screenshot(page, "tile")


def test_the_polygon_tile_keeps_properties_of_every_kind(page, api):
    open_tile_view(page, TILE_INPUT)
    page.select_option("#zoom", "4")
    shown = shown_tile(page, "4/8/5")
    block = [f for layer in shown["layers"] for f in layer["features"]
             if f["properties"].get("name") == "block"]
    assert len(block) == 1 and block[0]["id"] == 11
    assert block[0]["properties"] == {"name": "block", "rank": -3, "big": 2**60 + 1,
                                      "area": 12.5, "open": True}
    assert block[0]["geometry"]["type"] == "Polygon"
    assert len(block[0]["geometry"]["coordinates"]) == 2      # the hole kept
    assert "big: 1152921504606846977" in page.inner_text("#tile-layers")


def test_an_empty_tile_and_a_bad_input_are_shown(page, api):
    line = {"type": "LineString", "coordinates": [[0.5, 0.5], [60, 60]]}
    open_tile_view(page, line)
    page.select_option("#zoom", "3")
    assert sorted(grid_tiles(page)) == ["3/4/2", "3/4/3", "3/5/2", "3/5/3"]
    empty = api.post("/v1/tiles/3/5/3", content=json.dumps(line),
                     headers={"Content-Type": "application/geo+json"})
    assert empty.status_code == 204
    shown = shown_tile(page, "3/5/3")         # the bounds' corner, off the diagonal
    assert shown == {"tile": "3/5/3", "bytes": 0, "layers": []}
    assert "No feature reaches this tile" in page.inner_text("#tile-layers")

    broken = {"type": "Polygon", "coordinates": [[[2, 45], [14, 45], [14, 52]]]}
    page.fill("#input-text", json.dumps(broken))
    assert settled(page)["state"] == "idle"
    page.select_option("#zoom", "3")
    tile = grid_tiles(page)[0]
    page.click(f'#grid-tiles rect[data-tile="{tile}"]')
    shown = settled(page)
    problem = api.post(f"/v1/tiles/{tile}", content=json.dumps(broken),
                       headers={"Content-Type": "application/json"})
    assert problem.status_code == 422
    assert problem.headers["content-type"] == "application/problem+json"
    assert shown["state"] == "error" and problem.json()["detail"] in shown["error"]
    assert "422" in shown["error"]
    assert page.get_attribute("#tile-result", "data-tile") is None

    set_tile_option(page, "#tile-buffer", "-1")    # refused by the route's validation
    page.fill("#input-text", json.dumps(TILE_INPUT))
    settled(page)
    assert "3 geometries" in page.inner_text("#input-info")
    page.click(f'#grid-tiles rect[data-tile="{grid_tiles(page)[0]}"]')
    shown = settled(page)
    assert shown["state"] == "error" and "422" in shown["error"] and "buffer" in shown["error"]
    screenshot(page, "tile-error")


def test_switching_views_keeps_the_clip_view_working(page, api):
    document = json.loads(example_text(api, "coastline.geojson"))
    page.check("#view-tiles")
    page.select_option("#example", "coastline")
    assert settled(page)["state"] == "idle" and grid_tiles(page)
    page.check("#view-clip")
    shown = settled(page)
    assert shown["inputs"] == [25, 20, 70, 55] and shown["drawn"]
    check_geojson_against_api(api, shown, document,
                              {"method": "rnsca", "mode": "exact", "boundary": "closed"},
                              verify=True)
    page.check("#view-tiles")
    page.select_option("#example", "glyphs")         # SVG: no tiles, a note says why
    assert settled(page)["state"] == "idle" and grid_tiles(page) == []
    assert "takes GeoJSON" in page.inner_text("#grid-note")
