"""The playground in a real headless Chromium (Debian's ``chromium``, driven by Playwright)
against a live server: load an example, drag and resize the window with the mouse, and
check that what is drawn and the numbers shown are the API's answer for that window.

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
