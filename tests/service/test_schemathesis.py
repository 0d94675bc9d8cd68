"""Bad-input fuzzing: schemathesis generates requests from the app's own OpenAPI schema.

Every answer must be below 500, and every error must be an RFC 9457 problem document.
"""

import warnings

import pytest
import schemathesis
from hypothesis import HealthCheck, settings

from service import Settings, create_app
from service.warmup import ENDPOINT_STEPS, steps_for

app = create_app(Settings(warm_up=False, verify_max_vertices=50, max_vertices=10_000,
                          max_body_bytes=2**20))
schema = schemathesis.openapi.from_asgi("/openapi.json", app)
# GeoArrow bodies are bytes (Arrow IPC streams): sent as the bytes generated, as binary is.
schemathesis.serializer.alias("application/vnd.apache.arrow.stream", "application/octet-stream")
# Streamed GeoJSON bodies too (POST /v1/clip/geojson-seq): bytes, framed or not.
schemathesis.serializer.alias(["application/geo+json-seq", "application/json-seq",
                               "application/x-ndjson", "application/ndjson",
                               "application/jsonl"], "application/octet-stream")


@pytest.fixture(scope="module", autouse=True)
def _compiled():
    """Compile the kernels first: a cold compile inside a request would time it out."""
    app.state.runner.warm_up(steps_for(), ENDPOINT_STEPS)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@schema.parametrize()
@settings(max_examples=25, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
def test_no_server_error_and_every_error_is_a_problem(case):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        response = case.call()
    status = response.status_code
    key = (case.method.upper(), case.path)
    assert status < 500, (key, status, response.text)
    if status >= 400:
        assert response.headers["content-type"][0].startswith("application/problem+json"), \
            (key, status, response.text)
        body = response.json()
        assert body["status"] == status and body["type"].startswith("urn:rnsca:problem:")
