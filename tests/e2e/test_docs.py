"""The API docs in a real headless Chromium with every request to another host cut off:
Swagger UI (/docs) and ReDoc (/redoc) must render the API from the service's own files.

The server runs without warm-up: the docs need no kernel.
"""

from __future__ import annotations

from urllib.parse import urlsplit

import pytest

from tests.e2e.server import ROOT, LiveServer

pytestmark = pytest.mark.e2e

WAIT_MS = 30_000
LOCAL = {"127.0.0.1"}
#: The one thing ReDoc fetches from elsewhere: the Redocly logo of its "API docs by
#: Redocly" line, an <img> that removes itself when it fails to load (redoc 2.x offers no
#: option to leave it out). Nothing the page needs.
REDOC_LOGO = "https://cdn.redoc.ly/redoc/logo-mini.svg"


def screenshot(page, name: str) -> None:
    (ROOT / "test-artifacts").mkdir(exist_ok=True)
    page.screenshot(path=str(ROOT / "test-artifacts" / f"docs-{name}.png"))


@pytest.fixture(scope="module")
def server():
    with LiveServer(env={"RNSCA_WARM_UP": "false"}) as live:
        yield live


@pytest.fixture
def offline(browser):
    """Return (page, log): a page whose requests off 127.0.0.1 are aborted and listed.

    `log` holds "blocked", the URLs aborted, and "failed", local answers of 400 or more.
    """
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    log = {"blocked": [], "failed": [], "errors": []}

    def only_local(route):
        url = route.request.url
        if urlsplit(url).hostname in LOCAL:
            route.continue_()
        else:
            log["blocked"].append(url)
            route.abort("internetdisconnected")

    context.route("**/*", only_local)
    page = context.new_page()
    page.set_default_timeout(WAIT_MS)
    page.on("response", lambda r: r.status >= 400 and log["failed"].append(
        f"{r.status} {r.url}"))
    page.on("pageerror", lambda e: log["errors"].append(str(e)))
    yield page, log
    context.close()


def test_swagger_ui_renders_the_operations_offline(offline, server):
    page, log = offline
    page.goto(server.url + "/docs")
    operation = page.locator(".opblock-summary-path", has_text="/v1/clip/geojson")
    operation.first.wait_for()
    assert page.locator(".opblock-post .opblock-summary-path").count() >= 3
    assert "rnsca" in page.locator(".info .title").inner_text()
    operation.first.click()                   # the operation opens, with its request body
    page.locator(".opblock.is-open .opblock-section-request-body").first.wait_for()
    screenshot(page, "swagger-ui")
    assert log == {"blocked": [], "failed": [], "errors": []}


def test_redoc_renders_the_operations_offline(offline, server):
    page, log = offline
    page.goto(server.url + "/redoc")
    page.get_by_text("/v1/clip/geojson", exact=True).first.wait_for(state="attached")
    assert page.locator("h1").first.inner_text().startswith("rnsca")
    assert page.locator("h2", has_text="Clip a GeoJSON Geometry").count() == 1
    assert page.locator("h2", has_text="Clip SVG path data").count() == 1
    screenshot(page, "redoc")
    assert set(log["blocked"]) <= {REDOC_LOGO}
    assert log["failed"] == [] and log["errors"] == []
