"""An app and a TestClient for the service tests (the live-server ones are in tests/e2e)."""

import time
import warnings

import pytest

from service import Settings, create_app

with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)  # Starlette prefers httpx2 now
    from fastapi.testclient import TestClient


class ReadyClient(TestClient):
    """A TestClient whose ``with`` block starts once `/readyz` answers 200.

    A clip sent while the kernels warm up is answered 503 ``not-ready`` at once (as a
    real client would see it); tests about other things wait, as a load balancer does.
    """

    def __enter__(self) -> "ReadyClient":
        super().__enter__()
        deadline = time.monotonic() + 900  # a cold cache compiles for minutes
        while self.get("/readyz").status_code != 200:
            if time.monotonic() > deadline:
                raise TimeoutError("the app did not become ready")
            time.sleep(0.02)
        return self


def make_client(**settings) -> TestClient:
    """Return a TestClient (lifespan not started) of an app with these settings.

    Entering it (``with``) starts the app and waits until it is ready (`ReadyClient`).
    """
    return ReadyClient(create_app(Settings(**settings)))


@pytest.fixture(scope="module")
def client():
    with make_client(verify_max_vertices=100) as c:
        yield c
