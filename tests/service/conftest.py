"""An app and a TestClient for the service tests (the live-server ones are in tests/e2e)."""

import warnings

import pytest

from service import Settings, create_app

with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)  # Starlette prefers httpx2 now
    from fastapi.testclient import TestClient


def make_client(**settings) -> TestClient:
    """Return a TestClient (lifespan not started) of an app with these settings."""
    return TestClient(create_app(Settings(**settings)))


@pytest.fixture(scope="module")
def client():
    with make_client(verify_max_vertices=100) as c:
        yield c
