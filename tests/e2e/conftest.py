"""The headless Chromium the browser tests share (Debian's ``chromium``, driven by
Playwright through its executable path; Playwright's own browser download is not used)."""

from __future__ import annotations

import shutil

import pytest

from tests.missing import missing


def _launch_options() -> dict:
    executable = shutil.which("chromium")
    message = None
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        message = "playwright is not installed (pip install playwright, in the dev extra)"
    if message is None and executable is None:
        message = "chromium is not installed (apt-get install chromium; .ci/run does)"
    if message is not None:
        missing(message)
    return dict(executable_path=executable, headless=True,
                args=["--no-sandbox", "--disable-gpu", "--disable-background-networking"])


@pytest.fixture(scope="module")
def browser():
    options = _launch_options()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(**options)
        yield chromium
        chromium.close()
