"""Structured logs: one JSON object per line, for the service and uvicorn alike."""

from __future__ import annotations

import logging
import time

import orjson

__all__ = ["JsonFormatter", "configure_logging", "uvicorn_log_config", "ACCESS_LOGGER"]

#: The logger of the one line per request (method, path, status, duration, sizes).
ACCESS_LOGGER = "rnsca.service.access"


class JsonFormatter(logging.Formatter):
    """Format a record as one JSON line: time, level, logger, message and its fields.

    Fields come from ``extra={"fields": {...}}``.

    Examples
    --------
    >>> record = logging.LogRecord("x", logging.INFO, "", 0, "request", None, None)
    >>> record.fields = {"status": 200}
    >>> line = orjson.loads(JsonFormatter().format(record))
    >>> line["message"], line["status"], line["level"]
    ('request', 200, 'info')
    """

    def format(self, record: logging.LogRecord) -> str:
        """Return the record as a JSON line."""
        line = {
            "time": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(record.created))
            + f".{int(record.msecs):03d}Z",
            "level": record.levelname.lower(),
            "logger": record.name,
            "message": record.getMessage(),
        }
        line.update(getattr(record, "fields", None) or {})
        if record.exc_info:
            line["exception"] = self.formatException(record.exc_info)
        return orjson.dumps(line, default=str).decode()


class _ServiceHandler(logging.StreamHandler):
    """The handler `configure_logging` adds: found again, so that it is added once."""


def configure_logging(level: str) -> None:
    """Send the service's loggers to stderr as JSON lines at `level` (idempotent)."""
    logger = logging.getLogger("rnsca.service")
    logger.setLevel(level.upper())
    if not any(isinstance(h, _ServiceHandler) for h in logger.handlers):
        handler = _ServiceHandler()
        handler.setFormatter(JsonFormatter())
        logger.addHandler(handler)
    logger.propagate = False


def uvicorn_log_config(level: str) -> dict:
    """Return uvicorn's ``log_config``: its own messages as JSON lines too.

    uvicorn's access log is off (the service writes its own line per request).
    """
    return {
        "version": 1,
        "disable_existing_loggers": False,
        "formatters": {"json": {"()": "service.logs.JsonFormatter"}},
        "handlers": {"stderr": {"class": "logging.StreamHandler", "formatter": "json",
                                "stream": "ext://sys.stderr"}},
        "loggers": {"uvicorn": {"handlers": ["stderr"], "level": level.upper(),
                                "propagate": False},
                    "uvicorn.error": {"level": level.upper()}},
    }
