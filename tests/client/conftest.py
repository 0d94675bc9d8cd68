"""One real server (uvicorn on a loopback port) for the SDK tests, with small limits so
that every error status can be reached with small requests."""

import pytest

import rnsca_client
from tests.e2e.server import LiveServer

#: The server's limits (see `server`).
MAX_BODY_BYTES = 2**20
MAX_VERTICES = 20_000
WORK_BUDGET = 1_000_000


@pytest.fixture(scope="session")
def server():
    with LiveServer(env={"RNSCA_MAX_BODY_BYTES": str(MAX_BODY_BYTES),
                         "RNSCA_MAX_VERTICES": str(MAX_VERTICES),
                         "RNSCA_WORK_BUDGET": str(WORK_BUDGET),
                         "RNSCA_VERIFY_MAX_VERTICES": "5000",
                         # No such device: backend "opencl" answers 422 backend-unavailable.
                         "RNSCA_OPENCL_DEVICE": "no such device"}) as live:
        yield live


@pytest.fixture
def client(server):
    # No retries: an error must surface at once (retries have their own tests).
    with rnsca_client.Client(server.url, retries=None, timeout=120) as c:
        yield c
