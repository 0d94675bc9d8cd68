"""The playground's files as the service serves them (the browser tests are in tests/e2e):
the page and its assets, kept out of the API schema, nothing fetched from elsewhere, every
bundled example clipped and verified, and the glyph example traced back to its font."""

from __future__ import annotations

import fnmatch
import json
import re

import pytest

from service.routes.playground import STATIC_DIR
from tests.e2e.server import ROOT
from tests.fonts import require_font

EXAMPLES = json.loads((STATIC_DIR / "examples" / "index.json").read_text())


def test_the_page_is_served_at_the_root(client):
    page = client.get("/")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    for asset in re.findall(r'(?:src|href)="(playground/[^"]+)"', page.text):
        answer = client.get("/" + asset)
        assert answer.status_code == 200, asset
    assert client.get("/playground/playground.js").headers["content-type"].split(";")[0] in (
        "text/javascript", "application/javascript")


@pytest.mark.parametrize("path", ["nothing.js", "", "examples", "../main.py",
                                  "%2e%2e/main.py", "..%2fconfig.py"])
def test_anything_but_an_asset_is_a_problem_404(client, path):
    answer = client.get("/playground/" + path)
    assert answer.status_code == 404
    assert answer.headers["content-type"] == "application/problem+json"


def test_assets_are_cached_by_etag_and_counted_under_their_route(client):
    first = client.get("/playground/playground.css")
    again = client.get("/playground/playground.css",
                       headers={"If-None-Match": first.headers["etag"]})
    assert again.status_code == 304
    metrics = client.get("/metrics").text
    assert 'route="/playground/{path:path}",status="304"' in metrics


def test_the_playground_is_not_in_the_api_schema(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert "/" not in paths and not any(p.startswith("/playground") for p in paths)


def test_nothing_is_loaded_from_another_origin():
    for path in STATIC_DIR.glob("*.*"):
        text = path.read_text()
        # The SVG namespace is a name, not a fetch.
        text = text.replace("http://www.w3.org/2000/svg", "")
        assert not re.search(r"https?://|//[a-z0-9.-]+\.[a-z]{2,}/", text), path.name


def test_every_static_file_is_package_data():
    """A non-editable install (the Docker image) must carry the page and its examples."""
    # (read without tomllib, which Python 3.10 lacks)
    section = (ROOT / "pyproject.toml").read_text().split("[tool.setuptools.package-data]")[1]
    globs = json.loads(re.search(r"^service = (\[.*\])$", section, re.M).group(1))
    for path in STATIC_DIR.rglob("*"):
        if path.is_file():
            relative = path.relative_to(STATIC_DIR.parent).as_posix()
            assert any(fnmatch.fnmatch(relative, g) and relative.count("/") == g.count("/")
                       for g in globs), relative


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda e: e["id"])
def test_every_example_clips_and_verifies(client, example):
    text = client.get(f"/playground/examples/{example['file']}").text
    if example["format"] == "geojson":
        body = {"window": example["window"], "geojson": json.loads(text),
                "options": example["options"], "verify": True}
    else:
        body = {"window": example["window"], "paths": text.splitlines(),
                "options": example["options"], "verify": True}
    answer = client.post(f"/v1/clip/{example['format']}", json=body)
    assert answer.status_code == 200, answer.text
    result = answer.json()
    assert result["verification"]["passed"]
    assert 0 < result["stats"]["pieces_out"] < result["stats"]["segments_in"]


def glyph_paths(font_path, text: str) -> list[str]:
    """Return the outlines of `text`'s glyphs as SVG path data, one per glyph, laid out
    by their advance widths and flipped to SVG's y-down axis (y' = ascent - y)."""
    from fontTools.pens.svgPathPen import SVGPathPen
    from fontTools.pens.transformPen import TransformPen
    from fontTools.ttLib import TTFont

    font = TTFont(font_path)
    glyphs, cmap, ascent = font.getGlyphSet(), font.getBestCmap(), font["hhea"].ascent
    paths, x = [], 0
    for char in text:
        glyph = glyphs[cmap[ord(char)]]
        pen = SVGPathPen(glyphs, ntos=lambda v: f"{v:.0f}" if v == int(v) else repr(v))
        glyph.draw(TransformPen(pen, (1, 0, 0, -1, x, ascent)))
        paths.append(pen.getCommands())
        x += glyph.width
    return paths


def test_the_glyph_example_is_dejavu_sans_as_fonttools_reads_it():
    font = require_font("dejavu-sans")
    stored = (STATIC_DIR / "examples" / "glyphs-dejavu-sans.txt").read_text().splitlines()
    assert stored == glyph_paths(font.path, "&@g")
    license_text = (STATIC_DIR / "examples" / "DejaVu-LICENSE.txt").read_text()
    assert "Bitstream" in license_text and "Permission is hereby granted" in license_text
