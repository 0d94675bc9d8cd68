"""A real uvicorn server on a free loopback port, started as the Docker image starts it."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[2]
#: The image's start command (Dockerfile CMD), run by `python` of the environment.
START = ["-m", "service"]


def free_port() -> int:
    """Return a TCP port on 127.0.0.1 that nothing listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LiveServer:
    """``python -m service`` in a subprocess; `url` once `/readyz` answers 200.

    The first server of a fresh checkout compiles every kernel (Numba's cache is empty),
    which takes minutes on a loaded two-core machine: hence the long ready timeout.
    """

    def __init__(self, python: str = sys.executable, env: dict | None = None,
                 cwd: Path | None = None, ready_timeout: float = 900.0) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        environment = {k: v for k, v in os.environ.items()
                       if not k.startswith(("RNSCA_", "NUMBA_THREADING"))}
        environment.update({"RNSCA_HOST": "127.0.0.1", "RNSCA_PORT": str(self.port),
                            "PYTHONUNBUFFERED": "1"})
        environment.update(env or {})
        self.log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"rnsca-server-{self.port}.log"
        self._log = open(self.log_path, "wb")
        self.process = subprocess.Popen([python, *START], cwd=cwd or ROOT, env=environment,
                                        stdout=self._log, stderr=subprocess.STDOUT)
        self._wait_ready(ready_timeout)

    def _wait_ready(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"server exited with {self.process.returncode}:\n"
                                   + self.log())
            try:
                if httpx.get(self.url + "/readyz", timeout=2).status_code == 200:
                    return
            except httpx.TransportError:
                pass
            time.sleep(0.2)
        text = self.log()
        self.stop()
        raise RuntimeError(f"server not ready within {timeout} s:\n" + text)

    def log(self) -> str:
        """Return what the server wrote so far."""
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def terminate(self) -> None:
        """Send SIGTERM (graceful shutdown)."""
        self.process.send_signal(signal.SIGTERM)

    def stop(self, timeout: float = 30.0) -> int:
        """Stop the server (SIGTERM, then SIGKILL after `timeout`); return its exit code."""
        if self.process.poll() is None:
            self.terminate()
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)
        self._log.close()
        return self.process.returncode

    def __enter__(self) -> LiveServer:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
