"""The API docs (/docs, /redoc) as the service serves them: every script, style and icon
from the service itself, nothing from another origin (the browser tests, with the network
cut off, are in tests/e2e/test_docs.py)."""

from __future__ import annotations

import re

import pytest

from service import Settings, create_app
from tests.service.conftest import ReadyClient, make_client

PAGES = ["/docs", "/redoc"]


@pytest.fixture(scope="module")
def client():
    with make_client(warm_up=False) as c:  # no clipping here: no kernels needed
        yield c


def references(html: str) -> list[str]:
    """Return every URL the page names: src, href and spec-url attributes, url: in scripts."""
    return (re.findall(r'(?:src|href|spec-url)="([^"]*)"', html)
            + re.findall(r"url: '([^']*)'", html))


@pytest.mark.parametrize("page", PAGES)
def test_the_docs_page_names_no_other_origin(client, page):
    answer = client.get(page)
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("text/html")
    assert not re.search(r"https?://|//[a-z0-9.-]+\.[a-z]{2,}", answer.text), answer.text
    found = references(answer.text)
    assert "/openapi.json" in found and "/favicon.ico" in found
    for url in found:
        assert url.startswith("/") and not url.startswith("//"), url
        assert client.get(url).status_code == 200, url


def test_swagger_ui_and_redoc_load_their_assets_from_here(client):
    docs, redoc = client.get("/docs").text, client.get("/redoc").text
    assert '"/docs/assets/swagger-ui-bundle.js"' in docs
    assert '"/docs/assets/swagger-ui.css"' in docs
    assert '"/docs/assets/redoc.standalone.js"' in redoc
    script = client.get("/docs/assets/swagger-ui-bundle.js")
    assert script.headers["content-type"].split(";")[0] in ("text/javascript",
                                                            "application/javascript")
    assert "SwaggerUIBundle" in script.text[:1000]
    assert client.get("/docs/assets/swagger-ui.css").headers["content-type"].startswith(
        "text/css")


def test_the_docs_follow_the_prefix_a_proxy_mounts_them_under():
    app = create_app(Settings(warm_up=False))
    with ReadyClient(app, root_path="/rnsca") as prefixed:
        html = prefixed.get("/docs").text
    assert '"/rnsca/docs/assets/swagger-ui-bundle.js"' in html
    assert "'/rnsca/openapi.json'" in html and '"/rnsca/favicon.ico"' in html


@pytest.mark.parametrize("path", ["nothing.js", "", "../core.py", "%2e%2e/core.py"])
def test_anything_but_an_asset_is_a_problem_404(client, path):
    answer = client.get("/docs/assets/" + path)
    assert answer.status_code == 404
    assert answer.headers["content-type"] == "application/problem+json"


def test_the_icon_is_served_at_favicon_ico(client):
    answer = client.get("/favicon.ico")
    assert answer.status_code == 200 and answer.headers["content-type"] == "image/svg+xml"
    assert answer.text.lstrip().startswith("<svg")
    page = client.get("/").text
    assert '<link rel="icon" href="playground/favicon.svg" type="image/svg+xml">' in page
    assert client.get("/playground/favicon.svg").content == answer.content


def test_the_docs_and_the_icon_are_not_in_the_api_schema(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert not {"/docs", "/redoc", "/favicon.ico"} & set(paths)
    assert not any(p.startswith("/docs") for p in paths)
