"""Run the service under uvicorn, with settings from the environment (``RNSCA_*``)."""

from __future__ import annotations

import uvicorn

from service.config import Settings
from service.logs import uvicorn_log_config
from service.protocol import HeadTimeoutProtocol

__all__ = ["serve"]


def serve(settings: Settings | None = None) -> None:
    """Serve until SIGINT or SIGTERM, then finish the requests in flight and stop.

    The app is built in each worker process by `service.main.create_app` from the
    environment, so `host`, `port` and `workers` given here must also be in it (the
    `rnsca serve` command puts them there).
    """
    settings = settings or Settings()
    uvicorn.run("service.main:create_app", factory=True, host=settings.host,
                port=settings.port, workers=settings.workers,
                log_config=uvicorn_log_config(settings.log_level),
                log_level=settings.log_level, access_log=False,
                timeout_graceful_shutdown=int(settings.graceful_shutdown_seconds),
                server_header=False, proxy_headers=True,
                # Hostile clients: a deadline for request heads, idle connections closed,
                # and a cap on connections.
                http=HeadTimeoutProtocol, timeout_keep_alive=settings.idle_timeout_seconds,
                limit_concurrency=settings.max_connections)
