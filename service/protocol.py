"""uvicorn's HTTP protocol with a deadline for the request head.

uvicorn closes a kept-alive connection that stays idle after a response, but it waits
forever for the first bytes of a new connection and for the rest of a request head that
trickles in (measured: 5 silent connections still open after 105 s; headers sent at 2
bytes/s all waited for). `HeadTimeoutProtocol` gives every request head, the first on a
connection or the next on a kept-alive one, `Settings.header_timeout_seconds` to
arrive; a connection past it is closed (logged). The body's own deadline is the request's
time limit (`ClipRunner.read_body`, 408).
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

from service.config import Settings

__all__ = ["HeadTimeoutProtocol"]

_log = logging.getLogger("rnsca.service")


class HeadTimeoutProtocol(HttpToolsProtocol):
    """HttpToolsProtocol whose request heads must arrive within a deadline."""

    #: Seconds a request head may take; read once per process from the settings.
    head_timeout: float | None = None

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if HeadTimeoutProtocol.head_timeout is None:
            HeadTimeoutProtocol.head_timeout = Settings().header_timeout_seconds
        self._head_deadline: asyncio.TimerHandle | None = None

    def _arm(self) -> None:
        self._disarm()
        self._head_deadline = self.loop.call_later(self.head_timeout or 0.0, self._expired)

    def _disarm(self) -> None:
        if self._head_deadline is not None:
            self._head_deadline.cancel()
            self._head_deadline = None

    def _expired(self) -> None:
        self._head_deadline = None
        if not self.transport.is_closing():
            _log.info("closed a connection whose request head did not arrive in time",
                      extra={"fields": {"client": list(self.client or ()),
                                        "header_timeout_seconds": self.head_timeout}})
            self.transport.close()

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]  # noqa: D102
        super().connection_made(transport)
        self._arm()

    def on_headers_complete(self) -> None:  # noqa: D102
        self._disarm()  # the head is in; the body has the request's time limit
        super().on_headers_complete()

    def on_response_complete(self) -> None:  # noqa: D102
        super().on_response_complete()
        if not self.transport.is_closing():
            self._arm()  # the next request's head on this kept-alive connection

    def connection_lost(self, exc: Exception | None) -> None:  # noqa: D102
        self._disarm()
        super().connection_lost(exc)
