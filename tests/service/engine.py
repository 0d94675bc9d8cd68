"""The Docker engine for the image's tests: the `docker` command, the image, containers.

The image is built once per test session from the repository's Dockerfile (Docker's
layer cache makes a second build, e.g. by the other xdist worker, a matter of seconds).
Where its base image cannot be pulled (no registry of images is reachable from CI), the
Debian stand-ins of `.ci/docker-base-images` are built first. Without the `docker`
command or an engine the tests skip, and fail under ``CI=true`` (`tests.missing`).
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import subprocess
import tempfile
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx

from tests.e2e.server import ROOT
from tests.missing import missing

__all__ = ["IMAGE", "Container", "build_image", "build_lock", "docker", "inspect",
           "require_engine"]

#: The tag the tests build the Dockerfile under.
IMAGE = "rnsca:test"
#: The script that builds the base images' stand-ins (needs root and debootstrap).
BASE_IMAGES = ROOT / ".ci/docker-base-images"


def docker(*args: str, timeout: float = 120, check: bool = True,
           **kwargs) -> subprocess.CompletedProcess:
    """Run ``docker ARGS``; return the finished process (text output captured)."""
    result = subprocess.run(["docker", *args], capture_output=True, text=True,
                            timeout=timeout, **kwargs)
    if check and result.returncode != 0:
        raise AssertionError(f"docker {' '.join(args)}: exit {result.returncode}\n"
                             f"{result.stdout[-3000:]}{result.stderr[-3000:]}")
    return result


def require_engine() -> None:
    """Skip (fail in CI) unless the `docker` command reaches an engine."""
    if shutil.which("docker") is None:
        missing("the docker command is not installed (apt-get install docker.io; "
                ".ci/run installs it)")
    if docker("info", timeout=30, check=False).returncode != 0:
        missing("no Docker engine answers (start one as root: .ci/docker-engine)")


def inspect(name: str, template: str) -> str:
    """Return ``docker inspect --format TEMPLATE NAME``, stripped."""
    return docker("inspect", "--format", template, name).stdout.strip()


@contextmanager
def build_lock() -> Iterator[None]:
    """Hold the lock of image builds inside the block.

    The xdist workers build one after the other: the second finds every layer cached.
    """
    with open(Path(tempfile.gettempdir()) / "rnsca-docker-build.lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _build_args() -> list[str]:
    """Return ``--build-arg`` options for the proxy variables set here.

    pip inside the build uses them; Docker keeps these out of the image's history.
    """
    names = ("HTTP_PROXY", "HTTPS_PROXY", "NO_PROXY", "http_proxy", "https_proxy", "no_proxy")
    return [f"--build-arg={name}" for name in names if os.environ.get(name)]


def build_image(tag: str = IMAGE) -> str:
    """Build the Dockerfile as `tag` (base images stood in if need be); return `tag`.

    ``RNSCA_TEST_IMAGE=name`` tests that image as it is instead (nothing is built).
    """
    require_engine()
    if os.environ.get("RNSCA_TEST_IMAGE"):
        return os.environ["RNSCA_TEST_IMAGE"]
    with build_lock():
        # The Dockerfile's base, and the proxy's of docker/compose.yml.
        bases = ("python:3.11-slim", "debian:bookworm-slim")
        if docker("image", "inspect", *bases, check=False).returncode != 0:
            result = subprocess.run([str(BASE_IMAGES)], capture_output=True, text=True,
                                    timeout=1800)
            assert result.returncode == 0, (
                f"{BASE_IMAGES.name} failed (root and debootstrap needed):\n"
                + result.stdout[-3000:] + result.stderr[-3000:])
        docker("build", "--tag", tag, *_build_args(), str(ROOT), timeout=3600)
    return tag


def _host_port(name: str, port: int) -> int:
    published = docker("port", name, f"{port}/tcp").stdout.split()[0]
    return int(published.rsplit(":", 1)[1])


class Container:
    """``docker run --detach`` of an image, its port 8000 published on loopback.

    Removed (with ``--force``) when the ``with`` block ends; `logs` says what it wrote.
    """

    def __init__(self, image: str, *run_args: str, command: tuple[str, ...] = ()) -> None:
        self.name = f"rnsca-test-{uuid.uuid4().hex[:10]}"
        docker("run", "--detach", "--name", self.name, "--publish", "127.0.0.1::8000",
               *run_args, image, *command)
        self.url = f"http://127.0.0.1:{_host_port(self.name, 8000)}"

    def logs(self) -> str:
        """Return what the container wrote (stdout and stderr)."""
        result = docker("logs", self.name, check=False)
        return result.stdout + result.stderr

    def log_records(self) -> list[dict]:
        """Return the service's JSON log records."""
        return [json.loads(line) for line in self.logs().splitlines()
                if line.startswith("{")]

    def wait_ready(self, timeout: float = 120) -> float:
        """Wait until `/readyz` answers 200; return the seconds waited."""
        started = time.monotonic()
        while time.monotonic() - started < timeout:
            if inspect(self.name, "{{.State.Running}}") != "true":
                raise AssertionError("the container stopped:\n" + self.logs()[-5000:])
            try:
                if httpx.get(self.url + "/readyz", timeout=2).status_code == 200:
                    return time.monotonic() - started
            except httpx.TransportError:
                pass
            time.sleep(0.1)
        raise AssertionError(f"not ready within {timeout} s:\n" + self.logs()[-5000:])

    def warm_up_seconds(self) -> float:
        """Return the service's own warm-up time (its "kernels ready" log record)."""
        for record in self.log_records():
            if record.get("message") == "kernels ready":
                return float(record["warm_up_seconds"])
        raise AssertionError("no 'kernels ready' record:\n" + self.logs()[-5000:])

    def __enter__(self) -> Container:
        return self

    def __exit__(self, *exc) -> None:
        docker("rm", "--force", "--volumes", self.name, check=False)
