"""The Docker image built from the Dockerfile and run by a real engine.

The image serves every endpoint, reports healthy, runs as rnsca (10001:10001), answers the
request in flight when stopped, starts from its baked Numba cache on a read-only root, and
stays within its size budget. `.ci/run` starts the engine; without one these tests skip
(fail under ``CI=true``). See tests/service/engine.py.
"""

from __future__ import annotations

import socket
import struct
import threading
import time

import httpx
import numpy as np
import orjson
import pytest
import shapely

from tests.geoarrow_tables import ARROW_STREAM, decode, from_stream, table, to_stream
from tests.service.engine import Container, build_image, docker, inspect

pytestmark = pytest.mark.slow

#: The image's size budget, in MB (10**6 bytes, as ``docker images`` counts). Measured
#: with the Debian stand-in base (126 MB): see docker/README.md, "Image size".
SIZE_BUDGET_MB = 520
#: A read-only root loads the baked cache: the service's warm-up stays under this.
READ_ONLY_WARM_UP_SECONDS = 5.0

LINE = {"type": "LineString", "coordinates": [[-5.0, 5.0], [15.0, 5.0]]}


@pytest.fixture(scope="session")
def image() -> str:
    return build_image()


@pytest.fixture(scope="module")
def served(image) -> Container:
    """One container of the image as `docker run` starts it, ready."""
    with Container(image) as container:
        container.wait_ready()
        yield container


def test_image_serves_health_readiness_and_a_clip_of_each_endpoint(served):
    url = served.url
    assert httpx.get(url + "/healthz").json() == {"status": "ok"}
    assert httpx.get(url + "/readyz").json() == {"status": "ready"}
    window = {"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10}

    r = httpx.post(url + "/v1/clip/segments",
                   json={"window": [0, 0, 10, 10], "segments": [[-5, 5, 15, 5]]})
    assert r.status_code == 200 and r.json()["segments"] == [[0.0, 5.0, 10.0, 5.0]]

    r = httpx.post(url + "/v1/clip/segments", params=window,
                   content=struct.pack("<4d", -5, 5, 15, 5),
                   headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 200 and r.headers["X-Rnsca-Pieces"] == "1"
    assert np.frombuffer(r.content[:32], "<f8").tolist() == [0.0, 5.0, 10.0, 5.0]

    r = httpx.post(url + "/v1/clip/geojson", json={"window": [0, 0, 10, 10], "geojson": LINE})
    assert r.status_code == 200
    assert r.json()["geojson"]["coordinates"] == [[0.0, 5.0], [10.0, 5.0]]
    assert r.json()["verification"]["passed"] is True

    r = httpx.post(url + "/v1/clip/svg",
                   json={"window": [0, 0, 10, 10], "paths": ["M -5 5 L 15 5"]})
    assert r.status_code == 200 and r.json()["paths"] == ["M0 5H10"]

    line = shapely.from_geojson(orjson.dumps(LINE))
    r = httpx.post(url + "/v1/clip/geoarrow", params=window,
                   content=to_stream(table([line], "linestring", "interleaved", False)),
                   headers={"Content-Type": ARROW_STREAM})
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    [clipped] = decode(got.column("geometry"), got.schema.field("geometry"))
    assert shapely.equals(clipped, shapely.from_wkt("MULTILINESTRING ((0 5, 10 5))"))

    r = httpx.post(url + "/v1/clip/geojson-seq", params=window,
                   content=orjson.dumps(LINE) + b"\n",
                   headers={"Content-Type": "application/x-ndjson"})
    assert r.status_code == 200
    [record] = [orjson.loads(text) for text in r.content.splitlines() if text.strip()]
    assert record["coordinates"] == [[0.0, 5.0], [10.0, 5.0]]


def test_health_check_reaches_healthy(served):
    """The image's HEALTHCHECK (python -m service.healthcheck, every 15 s) passes."""
    deadline = time.monotonic() + 90
    while (status := inspect(served.name, "{{.State.Health.Status}}")) != "healthy":
        assert status == "starting" and time.monotonic() < deadline, (
            status, inspect(served.name, "{{json .State.Health}}"))
        time.sleep(1)
    last = orjson.loads(inspect(served.name, "{{json .State.Health}}"))["Log"][-1]
    assert last["ExitCode"] == 0


def test_runs_as_user_and_group_rnsca_10001(served, image):
    assert inspect(image, "{{.Config.User}}") == "10001:10001"
    assert docker("exec", served.name, "id").stdout.split() == [
        "uid=10001(rnsca)", "gid=10001(rnsca)", "groups=10001(rnsca)"]
    # The server itself (PID 1, through the entry point's exec), not only an exec'd shell.
    status = docker("exec", served.name, "cat", "/proc/1/status").stdout
    ids = {line.split(":")[0]: line.split()[1:] for line in status.splitlines()
           if line.startswith(("Uid:", "Gid:"))}
    assert ids == {"Uid": ["10001"] * 4, "Gid": ["10001"] * 4}  # real, effective, saved, fs
    owner = docker("exec", served.name, "stat", "-c", "%U:%G", "/var/cache/numba").stdout
    assert owner.strip() == "rnsca:rnsca"


def test_stop_answers_the_request_in_flight(image):
    """``docker stop`` (SIGTERM) while a request is being received: it is answered, then
    the server exits 0 well before Docker's 10 s would kill it."""
    body = orjson.dumps({"window": [0, 0, 10, 10], "segments": [[-5, 5, 15, 5]]})
    with Container(image) as container:
        container.wait_ready()
        host, port = container.url.removeprefix("http://").split(":")
        with socket.create_connection((host, int(port)), timeout=30) as connection:
            connection.sendall(b"POST /v1/clip/segments HTTP/1.1\r\nHost: rnsca\r\n"
                               b"Content-Type: application/json\r\n"
                               + f"Content-Length: {len(body)}\r\n\r\n".encode()
                               + body[:-1])
            stop = threading.Thread(target=docker, args=("stop", container.name),
                                    kwargs={"timeout": 60})
            started = time.monotonic()
            stop.start()
            deadline = time.monotonic() + 30
            while "Shutting down" not in container.logs():  # uvicorn got SIGTERM
                assert time.monotonic() < deadline, container.logs()[-3000:]
                time.sleep(0.05)
            connection.sendall(body[-1:])
            answer = b""
            while chunk := connection.recv(65536):
                answer += chunk
        stop.join()
        stopped_after = time.monotonic() - started
        head, _, content = answer.partition(b"\r\n\r\n")
        assert head.startswith(b"HTTP/1.1 200"), answer[:500]
        assert orjson.loads(content)["segments"] == [[0.0, 5.0, 10.0, 5.0]]
        assert inspect(container.name, "{{.State.ExitCode}}") == "0", container.logs()[-3000:]
        assert stopped_after < 8


def test_read_only_root_loads_the_baked_numba_cache(image):
    """``--read-only``: the entry point gives Numba a writable view of the baked cache, so
    nothing is compiled and the warm-up stays under 5 s."""
    with Container(image, "--read-only", "--tmpfs", "/tmp") as container:
        container.wait_ready(timeout=60)
        seconds = container.warm_up_seconds()
        print(f"read-only root: warm-up {seconds:.2f} s")
        assert seconds < READ_ONLY_WARM_UP_SECONDS, container.logs()[-5000:]
        assert "cold" not in container.logs()  # no "the kernel cache is cold" record
        r = httpx.post(container.url + "/v1/clip/geojson",
                       json={"window": [0, 0, 10, 10], "geojson": LINE})
        assert r.status_code == 200, r.text
        written = docker("exec", container.name, "sh", "-c",
                         "touch /opt/venv/x 2>&1; find /tmp/numba-cache -type f | wc -l")
        assert "Read-only file system" in written.stdout
        assert written.stdout.split()[-1] == "0"  # links to the baked files, none compiled


def test_image_size_within_budget(image):
    size_mb = int(inspect(image, "{{.Size}}")) / 1e6
    print(f"image {image}: {size_mb:.0f} MB")
    assert size_mb <= SIZE_BUDGET_MB
    venv = docker("run", "--rm", "--entrypoint", "sh", image, "-c",
                  "ls /opt/venv/bin; find /opt/venv -type d -name tests | wc -l").stdout
    assert "pip" not in venv.split() and venv.split()[-1] == "0"
