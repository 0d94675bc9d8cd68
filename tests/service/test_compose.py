"""docker/compose.yml started by ``docker-compose up``: two replicas behind nginx.

Requests through the proxy reach both replicas, and when one replica is killed under load
every request is still answered: the proxy sends the ones the dead replica dropped or
refused to the other (its access log shows them with two upstreams). Debian's
docker-compose (1.29) runs it; without it, or without an engine, this skips (fails under
``CI=true``).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import threading
import time
import uuid

import httpx
import pytest

from tests.e2e.server import ROOT
from tests.missing import missing
from tests.service.engine import build_image, build_lock, docker

pytestmark = pytest.mark.slow

COMPOSE_FILE = ROOT / "docker/compose.yml"
#: The stack's services (not those of the profile dask).
SERVICES = ("rnsca-1", "rnsca-2", "proxy")
BODY = {"window": [0, 0, 10, 10], "segments": [[-5, 5, 15, 5]] * 2000}
#: One access-log line of the proxy (docker/proxy/nginx.conf, log_format upstreams).
ACCESS = re.compile(r'"POST (?P<path>\S+) [^"]*" (?P<status>\d+) \S+ '
                    r"upstream=\[(?P<upstreams>[^\]]*)\] upstream_status=\[(?P<statuses>[^\]]*)\]")


class Stack:
    """The compose project, under a name of its own; taken down when the block ends."""

    def __init__(self) -> None:
        self.project = f"rnsca-test-{uuid.uuid4().hex[:8]}"
        # Any free port for the proxy; no other setting changes.
        self.environment = {**os.environ, "RNSCA_PROXY_PORT": ""}

    def compose(self, *args: str, timeout: float = 600) -> subprocess.CompletedProcess:
        result = subprocess.run(
            ["docker-compose", "--project-name", self.project, "--file", str(COMPOSE_FILE),
             *args], capture_output=True, text=True, timeout=timeout, env=self.environment)
        assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
        return result

    def container(self, service: str) -> str:
        return self.compose("ps", "--quiet", service).stdout.strip()

    def address(self, service: str) -> str:
        return docker("inspect", "--format",
                      "{{range .NetworkSettings.Networks}}{{.IPAddress}}{{end}}",
                      self.container(service)).stdout.strip()

    def access_log(self) -> list[dict]:
        logs = docker("logs", self.container("proxy")).stdout
        return [m.groupdict() for m in ACCESS.finditer(logs)]

    def __enter__(self) -> Stack:
        # The replicas' image is the one the other tests built (every layer cached); the
        # profile dask's services are left out.
        with build_lock():
            self.compose("build", *SERVICES)
        self.compose("up", "--detach", *SERVICES)
        port = self.compose("port", "proxy", "8080").stdout.strip().rsplit(":", 1)[1]
        self.url = f"http://127.0.0.1:{port}"
        return self

    def __exit__(self, *exc) -> None:
        subprocess.run(["docker-compose", "--project-name", self.project, "--file",
                        str(COMPOSE_FILE), "down", "--volumes", "--timeout", "10"],
                       capture_output=True, timeout=300, env=self.environment)


def _clip(client: httpx.Client) -> int:
    r = client.post("/v1/clip/segments", json=BODY)
    assert r.status_code != 200 or r.json()["segments"][0] == [0.0, 5.0, 10.0, 5.0]
    return r.status_code


def test_two_replicas_share_requests_and_a_killed_one_loses_none():
    if shutil.which("docker-compose") is None:
        missing("docker-compose is not installed (apt-get install docker-compose; "
                ".ci/run installs it)")
    build_image()  # and the base images, stood in if need be
    with Stack() as stack:
        replicas = {stack.address("rnsca-1"): "rnsca-1", stack.address("rnsca-2"): "rnsca-2"}
        with httpx.Client(base_url=stack.url, timeout=60) as client:
            assert [_clip(client) for _ in range(20)] == [200] * 20
        answered = {replicas[entry["upstreams"].rsplit(":", 1)[0]]
                    for entry in stack.access_log()}
        assert answered == {"rnsca-1", "rnsca-2"}, stack.access_log()

        # Four clients clip in a loop; rnsca-2 is killed (SIGKILL) after a second.
        statuses: list[int] = []
        stop = threading.Event()

        def load() -> None:
            with httpx.Client(base_url=stack.url, timeout=60) as client:
                while not stop.is_set():
                    statuses.append(_clip(client))

        clients = [threading.Thread(target=load) for _ in range(4)]
        for thread in clients:
            thread.start()
        time.sleep(1.0)
        killed_at = len(statuses)
        docker("kill", stack.container("rnsca-2"))
        time.sleep(6.0)
        stop.set()
        for thread in clients:
            thread.join(60)
        assert killed_at > 0 and len(statuses) > killed_at + 10, (killed_at, len(statuses))
        assert statuses == [200] * len(statuses), {s: statuses.count(s) for s in statuses}

        log = stack.access_log()
        retried = [entry for entry in log if "," in entry["upstreams"]]
        print(f"compose: {len(statuses)} requests under load, rnsca-2 killed after "
              f"{killed_at}; {len(retried)} retried by the proxy, none lost: "
              + "; ".join(f"{e['upstreams']} {e['statuses']}" for e in retried))
        assert retried, "no request reached the killed replica"
        for entry in retried:
            first, second = (u.strip() for u in entry["upstreams"].split(","))
            assert replicas[first.rsplit(":", 1)[0]] == "rnsca-2"
            assert replicas[second.rsplit(":", 1)[0]] == "rnsca-1"
            assert entry["status"] == "200" and entry["statuses"].endswith("200")
