"""A small HTTP/1.1 server on a loopback port that answers from a script, for retry tests.

Each request takes the next `Reply` of the script (the last one repeats); the server
records when each request arrived and how many TCP connections were opened, so tests
can check the waits between retries and that a client reuses its connection.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

__all__ = ["Reply", "ScriptedServer", "CLIP_GEOJSON_ANSWER", "unavailable"]

_STATS = {"segments_in": 1, "pieces_out": 1, "fragments_evaluated": 1, "accepted": 0,
          "rejected": 0, "subdivided": 0, "clipped": 1, "dropped": 0, "intersections": 2,
          "deepest_level": 0, "decided_per_level": [1]}
#: What ``POST /v1/clip/geojson`` answers for a line through the window (abridged stats).
CLIP_GEOJSON_ANSWER = {"geojson": {"type": "LineString", "coordinates": [[0, 5], [10, 5]]},
                       "stats": _STATS, "verification": None}


@dataclass
class Reply:
    """One scripted answer: status, JSON body (or raw bytes), headers, delay before it."""

    status: int = 200
    body: object = field(default_factory=lambda: {"status": "ok"})
    headers: dict = field(default_factory=dict)
    delay: float = 0.0
    content_type: str | None = None


def unavailable(retry_after: str | None = None) -> Reply:
    """Return a 503 problem answer, with ``Retry-After`` if given."""
    return Reply(503, {"type": "urn:rnsca:problem:time-limit", "status": 503,
                       "title": "Request time limit exceeded", "detail": "busy"},
                 {"Retry-After": retry_after} if retry_after is not None else {},
                 content_type="application/problem+json")


class ScriptedServer:
    """Serve `script` on ``http://127.0.0.1:<port>`` (a given port, or a free one)."""

    def __init__(self, script: list[Reply], port: int = 0) -> None:
        self.script = list(script)
        self.arrivals: list[tuple[float, str, str]] = []  # (monotonic time, method, path)
        self.bodies: list[bytes] = []
        self.connections = 0
        lock = threading.Lock()
        outer = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"  # keep-alive, so connection reuse shows

            def setup(self):
                super().setup()
                with lock:
                    outer.connections += 1

            def log_message(self, *args):  # quiet
                pass

            def _answer(self):
                length = int(self.headers.get("Content-Length") or 0)
                body = self.rfile.read(length) if length else b""
                with lock:
                    outer.arrivals.append((time.monotonic(), self.command, self.path))
                    outer.bodies.append(body)
                    index = min(len(outer.arrivals), len(outer.script)) - 1
                reply = outer.script[index]
                if reply.delay:
                    time.sleep(reply.delay)
                content = (reply.body if isinstance(reply.body, bytes)
                           else json.dumps(reply.body).encode())
                self.send_response(reply.status)
                self.send_header("Content-Type", reply.content_type or "application/json")
                self.send_header("Content-Length", str(len(content)))
                for name, value in reply.headers.items():
                    self.send_header(name, value)
                self.end_headers()
                try:
                    self.wfile.write(content)
                except (BrokenPipeError, ConnectionResetError):
                    pass  # the client gave up waiting (the timeout test)

            do_GET = do_POST = _answer

        self._server = ThreadingHTTPServer(("127.0.0.1", port), Handler)
        self._server.daemon_threads = True
        self.port = self._server.server_address[1]
        self.url = f"http://127.0.0.1:{self.port}"
        self._thread = threading.Thread(target=self._server.serve_forever, daemon=True)
        self._thread.start()

    @property
    def requests(self) -> int:
        """Return how many requests arrived."""
        return len(self.arrivals)

    def gaps(self) -> list[float]:
        """Return the seconds between consecutive requests."""
        times = [t for t, _, _ in self.arrivals]
        return [b - a for a, b in zip(times, times[1:], strict=False)]

    def close(self) -> None:
        """Stop serving and release the port."""
        self._server.shutdown()
        self._server.server_close()

    def __enter__(self) -> ScriptedServer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
