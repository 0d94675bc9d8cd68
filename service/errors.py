"""Every error the service answers, as RFC 9457 ``application/problem+json``, from one table.

Library errors (`rnsca.errors`) map by class, the most specific class of the exception's
MRO winning; the service's own conditions are `ServiceError` subclasses that carry their
status. FastAPI's request validation errors, Starlette's 404 and 405, pydantic validation
errors of request bodies and anything unexpected go through the same `problem` builder,
so every error body has ``type``, ``title``, ``status``, ``detail`` and ``instance``, plus
``path`` (the JSON path of the offending value) or ``position`` (a character offset)
where one is known.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable
from typing import Any

import orjson
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.requests import ClientDisconnect
from starlette.responses import Response

from rnsca.errors import (
    BackendUnavailableError,
    FontError,
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    LimitExceededError,
    ParseError,
    RnscaError,
    UnsupportedGeometryError,
)

__all__ = [
    "PROBLEM_JSON",
    "ServiceError",
    "MalformedJSONError",
    "UnsupportedMediaTypeError",
    "InvalidBodyError",
    "BodyTooLargeError",
    "TooManyVerticesError",
    "WorkOverBudgetError",
    "TimeLimitError",
    "RequestTimeoutError",
    "NotReadyError",
    "problem",
    "problem_bytes",
    "problem_document",
    "problem_fields",
    "install_handlers",
    "json_path",
    "CLIENT_CLOSED_REQUEST",
]

#: The status logged and counted for a request whose client went away before the answer
#: (nginx's 499, "client closed request"): no server error, and nothing is sent.
CLIENT_CLOSED_REQUEST = 499

PROBLEM_JSON = "application/problem+json"
_TYPE_PREFIX = "urn:rnsca:problem:"
# The tags pydantic puts in an error's location for the member of a union it tried.
_UNION_TAG = re.compile(r"^(constrained-\w+|literal\[.*\]|function-\w+\[.*\]|int|float|str|"
                        r"bool|none|tuple\[.*\]|list\[.*\]|dict\[.*\])$")
_log = logging.getLogger("rnsca.service")


class ServiceError(Exception):
    """A condition the service itself detects; subclasses set status, slug and title."""

    status = 500
    slug = "internal-error"
    title = "Internal server error"

    def __init__(self, detail: str, *, headers: dict | None = None,
                 **extensions: object) -> None:
        super().__init__(detail)
        self.detail = detail
        self.headers = headers or {}
        self.extensions = extensions


class MalformedJSONError(ServiceError):
    """The request body is not JSON."""

    status, slug, title = 400, "malformed-json", "Malformed JSON"


class UnsupportedMediaTypeError(ServiceError):
    """The request's Content-Type is not one the endpoint reads."""

    status, slug, title = 415, "unsupported-media-type", "Unsupported media type"


class InvalidBodyError(ServiceError):
    """The body has the right media type but not the right form (binary segments)."""

    status, slug, title = 422, "invalid-body", "Invalid request body"


class BodyTooLargeError(ServiceError):
    """The body is over ``max_body_bytes`` (found from Content-Length or while reading)."""

    status, slug, title = 413, "body-too-large", "Request body too large"


class TooManyVerticesError(ServiceError):
    """The input has more vertices than ``max_vertices``."""

    status, slug, title = 413, "too-many-vertices", "Too many vertices"


class WorkOverBudgetError(ServiceError):
    """The request's estimated work exceeds ``work_budget``."""

    status, slug, title = 422, "work-over-budget", "Work over budget"


class TimeLimitError(ServiceError):
    """The request waited for and ran longer than ``request_time_limit`` (server load)."""

    status, slug, title = 503, "time-limit", "Request time limit exceeded"


class RequestTimeoutError(ServiceError):
    """The client did not send its whole body within the request's time limit."""

    status, slug, title = 408, "request-timeout", "Request timeout"


class NotReadyError(ServiceError):
    """The kernels are still being compiled or loaded."""

    status, slug, title = 503, "not-ready", "Not ready"


# status, slug, title of each library error; the most specific class in the MRO wins.
_LIBRARY = {
    ParseError: (422, "parse-error", "Malformed input"),
    InvalidGeometryError: (422, "invalid-geometry", "Invalid geometry"),
    InvalidWindowError: (422, "invalid-window", "Invalid window"),
    InvalidOptionError: (422, "invalid-option", "Invalid option"),
    UnsupportedGeometryError: (422, "unsupported-geometry", "Unsupported geometry"),
    LimitExceededError: (413, "limit-exceeded", "Input over the limit"),
    BackendUnavailableError: (422, "backend-unavailable", "Backend not available"),
    # No route reads fonts today (glyph outlines arrive as path data); mapped for any that will.
    FontError: (422, "font-error", "Unreadable font or missing glyph"),
    RnscaError: (500, "internal-error", "Internal server error"),
}
_HTTP_SLUGS = {404: "not-found", 405: "method-not-allowed"}


def problem(status: int, slug: str, title: str, detail: str, *, instance: str | None = None,
            headers: dict | None = None, **extensions: object) -> Response:
    """Return an ``application/problem+json`` response.

    Examples
    --------
    >>> r = problem(422, "invalid-window", "Invalid window", "xmin must be < xmax",
    ...             path="window")
    >>> r.status_code, r.media_type
    (422, 'application/problem+json')
    >>> orjson.loads(r.body)["type"]
    'urn:rnsca:problem:invalid-window'
    """
    return Response(problem_bytes(status, slug, title, detail, instance=instance, **extensions),
                    status_code=status, headers=headers, media_type=PROBLEM_JSON)


def problem_bytes(status: int, slug: str, title: str, detail: str, *,
                  instance: str | None = None, **extensions: object) -> bytes:
    """Return the body of a problem response (also used by the pure ASGI middleware)."""
    return orjson.dumps(problem_document(status, slug, title, detail, instance=instance,
                                         **extensions), default=str)


def problem_document(status: int, slug: str, title: str, detail: str, *,
                     instance: str | None = None, **extensions: object) -> dict:
    """Return a problem document as a dict (a streamed answer's problem record)."""
    body: dict[str, Any] = {"type": _TYPE_PREFIX + slug, "title": title, "status": status,
                            "detail": detail}
    if instance is not None:
        body["instance"] = instance
    body.update({k: v for k, v in extensions.items() if v is not None})
    return body


def json_path(location: Iterable[str | int]) -> str:
    """Return a pydantic error location as a JSON path.

    Examples
    --------
    >>> json_path(("geojson", "features", 3, "geometry"))
    'geojson.features[3].geometry'
    >>> json_path(("query", "xmin"))
    'query.xmin'
    >>> json_path(("options", "n", "constrained-int"))
    'options.n'
    """
    out = ""
    for part in location:
        if isinstance(part, str) and _UNION_TAG.match(part):
            continue  # pydantic names the union member tried; not part of the document
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def problem_fields(exc: RnscaError | ServiceError) -> tuple[int, str, str, str, dict]:
    """Return ``(status, slug, title, detail, extensions)`` of a library or service error.

    The extensions are where the error is: ``path`` (a JSON path), ``position`` (an
    offset in a text) and ``record`` (a record of a GeoJSON text sequence), as known.
    """
    if isinstance(exc, ServiceError):
        return exc.status, exc.slug, exc.title, exc.detail, dict(exc.extensions)
    status, slug, title = next(
        _LIBRARY[cls] for cls in type(exc).__mro__ if cls in _LIBRARY)
    extensions: dict[str, Any] = {}
    if isinstance(exc, InvalidWindowError):
        extensions["path"] = "window"
    elif isinstance(exc, InvalidOptionError):
        extensions["path"] = "options"
    for name in ("record", "path", "position"):
        value = getattr(exc, name, None)
        if value is not None:
            extensions[name] = value
    if status >= 500:
        _log.error("unmapped library error", exc_info=exc)
    return status, slug, title, str(exc), extensions


def _library_problem(request: Request, exc: RnscaError) -> Response:
    status, slug, title, detail, extensions = problem_fields(exc)
    return problem(status, slug, title, detail, instance=request.url.path, **extensions)


def _validation_problem(request: Request, errors: list) -> Response:
    listed = [{"path": json_path(e["loc"]), "message": e["msg"], "type": e["type"]}
              for e in errors[:20]]
    if any(e["type"] == "json_invalid" for e in errors):
        detail = errors[0]["msg"]
        return problem(400, MalformedJSONError.slug, MalformedJSONError.title,
                       f"request body is not valid JSON: {detail}", instance=request.url.path)
    first = listed[0] if listed else {"path": "", "message": "invalid request"}
    detail = f"{first['path'] or 'request'}: {first['message']}"
    if len(errors) > 1:
        detail += f" (and {len(errors) - 1} more)"
    return problem(422, "invalid-request", "Invalid request", detail,
                   instance=request.url.path, path=first["path"], errors=listed)


def install_handlers(app: FastAPI) -> None:
    """Register the problem+json handlers on `app`."""

    @app.exception_handler(RnscaError)
    async def _rnsca(request: Request, exc: RnscaError) -> Response:
        return _library_problem(request, exc)

    @app.exception_handler(ServiceError)
    async def _service(request: Request, exc: ServiceError) -> Response:
        return problem(exc.status, exc.slug, exc.title, exc.detail, instance=request.url.path,
                       headers=exc.headers, **exc.extensions)

    @app.exception_handler(ValidationError)
    async def _body(request: Request, exc: ValidationError) -> Response:
        return _validation_problem(request, exc.errors(include_url=False))

    @app.exception_handler(RequestValidationError)
    async def _request(request: Request, exc: RequestValidationError) -> Response:
        return _validation_problem(request, list(exc.errors()))

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException) -> Response:
        slug = _HTTP_SLUGS.get(exc.status_code, f"http-{exc.status_code}")
        title = {404: "Not found", 405: "Method not allowed"}.get(exc.status_code, "HTTP error")
        detail = exc.detail if isinstance(exc.detail, str) else str(exc.detail)
        if exc.status_code == 404 and detail == "Not Found":
            detail = f"no route {request.url.path}; see /docs for the API"
        elif exc.status_code == 405 and detail == "Method Not Allowed":
            detail = f"{request.method} is not allowed on {request.url.path}"
        return problem(exc.status_code, slug, title, detail, instance=request.url.path,
                       headers=getattr(exc, "headers", None))

    @app.exception_handler(ClientDisconnect)
    async def _gone(request: Request, exc: ClientDisconnect) -> Response:
        # Not the server's failure: no traceback, and the access log and metrics count
        # it as 499 (the response goes nowhere; uvicorn drops it).
        _log.info("client disconnected before the request was read",
                  extra={"fields": {"path": request.url.path}})
        return Response(status_code=CLIENT_CLOSED_REQUEST)

    @app.exception_handler(Exception)
    async def _unexpected(request: Request, exc: Exception) -> Response:
        _log.error("unhandled error", exc_info=exc)
        return problem(500, "internal-error", "Internal server error",
                       "the server failed on this request; it keeps serving",
                       instance=request.url.path)
