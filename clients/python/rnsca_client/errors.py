"""The SDK's exceptions: one root, network failures apart from answers the server refused.

::

    RnscaClientError
    ├── InvalidInputError (ValueError)        refused before sending (not JSON-encodable)
    ├── ResponseFormatError                   a success answer the SDK cannot read
    ├── BatchError                            one request of clip_many failed (`error`: why)
    ├── TransportError                        no HTTP answer at all
    │   ├── ConnectError (ConnectionError)    could not connect (after the retries)
    │   └── RequestTimeoutError (TimeoutError)
    └── ApiError                              an HTTP error answer (RFC 9457 problem)
        ├── BadRequestError            400    the body is not JSON
        ├── NotFoundError              404
        ├── MethodNotAllowedError      405
        ├── PayloadTooLargeError       413    body or vertex count over the server's limit
        ├── UnsupportedMediaTypeError  415
        ├── InvalidRequestError        422    window, options, geometry, coordinates, ...
        │   ├── BackendUnavailableError       the backend asked for is not on the server
        │   └── WorkOverBudgetError           N and depth would make too much work
        └── ServerError                5xx
            ├── NotImplementedOnServerError  501
            └── ServiceUnavailableError      503  busy or warming up (after the retries)
"""

from __future__ import annotations

import builtins
import json
from typing import Any

import httpx

__all__ = [
    "RnscaClientError",
    "InvalidInputError",
    "ResponseFormatError",
    "BatchError",
    "TransportError",
    "ConnectError",
    "RequestTimeoutError",
    "ApiError",
    "BadRequestError",
    "NotFoundError",
    "MethodNotAllowedError",
    "PayloadTooLargeError",
    "UnsupportedMediaTypeError",
    "InvalidRequestError",
    "BackendUnavailableError",
    "WorkOverBudgetError",
    "ServerError",
    "NotImplementedOnServerError",
    "ServiceUnavailableError",
    "api_error",
    "problem_error",
    "retry_after_seconds",
    "PROBLEM_TYPE_PREFIX",
]

#: The service's problem types are ``urn:rnsca:problem:<name>``.
PROBLEM_TYPE_PREFIX = "urn:rnsca:problem:"


class RnscaClientError(Exception):
    """Root of every exception the SDK raises."""


class InvalidInputError(RnscaClientError, ValueError):
    """The input cannot be sent (e.g. NaN or infinity, which JSON cannot carry)."""


class ResponseFormatError(RnscaClientError):
    """A success answer that is not what the API documents (wrong server or proxy?)."""


class BatchError(RnscaClientError):
    """A request of `clip_many` failed: which one, which rows, and the error it raised.

    The error itself (an `ApiError`, a `TransportError`, ...) is `error`, and the
    exception's ``__cause__``; the retries of the client were made before it counted.

    Attributes
    ----------
    batch : int
        The request's number among the call's requests (from 0, in input order).
    item : int or None
        The item of the `items` list it belongs to (None: one collection was given).
    start, stop : int or None
        Its rows: positions ``start:stop`` of the item (or of the collection); None for
        a GeoJSON document (sent whole).
    row : int or None
        The position, in the item, of the row the server's answer names (its `path`),
        where it names one.
    error : RnscaClientError
        What the request raised.
    others : list of BatchError
        The other requests that failed before the call stopped (requests not yet sent
        then are not sent).
    """

    def __init__(self, error: RnscaClientError, *, batch: int, item: int | None,
                 start: int | None, stop: int | None, row: int | None = None) -> None:
        self.error = error
        self.batch = batch
        self.item = item
        self.start = start
        self.stop = stop
        self.row = row
        self.others: list[BatchError] = []
        where = [f"item {item}"] if item is not None else []
        if start is not None:
            where.append(f"rows {start}:{stop}")
        if row is not None:
            where.append(f"row {row}")
        super().__init__(f"request {batch} ({', '.join(where)}) failed: "
                         f"{type(error).__name__}: {error}")


class TransportError(RnscaClientError):
    """No HTTP answer: the request failed on the network; `attempts` were made."""

    def __init__(self, message: str, *, attempts: int = 1) -> None:
        super().__init__(message)
        self.attempts = attempts


class ConnectError(TransportError, ConnectionError):
    """The server could not be reached (refused, unresolvable, connect timeout)."""


class RequestTimeoutError(TransportError, builtins.TimeoutError):
    """The server took longer than the timeout to answer (not retried: it may be busy)."""


class ApiError(RnscaClientError):
    """The server answered with an error: the fields of its RFC 9457 problem document.

    Attributes
    ----------
    status : int
        The HTTP status.
    title, detail : str
        The problem's short title and its explanation.
    type : str
        The problem type, e.g. ``urn:rnsca:problem:invalid-geometry``.
    kind : str
        The type's last part, e.g. ``invalid-geometry`` (empty if not the service's).
    instance : str or None
        The request path.
    path : str or None
        JSON path of the offending value, e.g. ``geojson.features[3].geometry``.
    position : int or None
        Character offset of a syntax error (SVG path data).
    record : int or None
        Streamed GeoJSON: the number (from 0) of the record at fault.
    errors : list of dict
        Each validation error (``path``, ``message``, ``type``) for ``invalid-request``.
    retry_after : float or None
        Seconds the server asked to wait (``Retry-After``), if it said.
    attempts : int
        How many times the request was sent (more than 1 after retried 503s).
    row : int or None
        For `Client.clip` and ``clip_many``: the position, in the collection clipped,
        of the row the problem names (`path` names it in the request, which may hold
        only some of the rows).
    problem : dict
        The whole problem document (extension members included).
    """

    def __init__(self, problem: dict[str, Any], *, retry_after: float | None = None) -> None:
        self.problem = problem
        self.status = int(problem.get("status", 0))
        self.title = str(problem.get("title", ""))
        self.detail = str(problem.get("detail", ""))
        self.type = str(problem.get("type", "about:blank"))
        self.kind = (self.type[len(PROBLEM_TYPE_PREFIX):]
                     if self.type.startswith(PROBLEM_TYPE_PREFIX) else "")
        self.instance = problem.get("instance")
        self.path = problem.get("path")
        self.position = problem.get("position")
        self.record = problem.get("record")
        self.errors = list(problem.get("errors") or [])
        self.retry_after = retry_after
        self.attempts = 1
        self.row: int | None = None
        where = f" at {self.path}" if self.path else ""
        if self.record is not None:
            where = f" in record {self.record}" + where
        super().__init__(f"{self.status} {self.title}{where}: {self.detail}")


class BadRequestError(ApiError):
    """400: the request body is not valid JSON."""


class NotFoundError(ApiError):
    """404: no such route (is `base_url` the service's root?)."""


class MethodNotAllowedError(ApiError):
    """405: the route exists but not for this HTTP method."""


class PayloadTooLargeError(ApiError):
    """413: the body or its vertex count is over the server's limit (see `limit`)."""


class UnsupportedMediaTypeError(ApiError):
    """415: the Content-Type is not one the endpoint reads."""


class InvalidRequestError(ApiError, ValueError):
    """422: well-formed but unacceptable: window, options, geometry, coordinates, syntax."""


class BackendUnavailableError(InvalidRequestError):
    """422: the backend asked for is not available on the server (`detail` says why)."""


class WorkOverBudgetError(InvalidRequestError):
    """422: the options would make more work than the server's budget allows."""


class ServerError(ApiError):
    """5xx: the server could not answer the request."""


class NotImplementedOnServerError(ServerError):
    """501: the endpoint exists but this server's release does not implement it."""


class ServiceUnavailableError(ServerError):
    """503: busy (request time limit) or still warming up; still so after the retries."""


_BY_KIND: dict[str, type[ApiError]] = {
    "backend-unavailable": BackendUnavailableError,
    "work-over-budget": WorkOverBudgetError,
}
_BY_STATUS: dict[int, type[ApiError]] = {
    400: BadRequestError,
    404: NotFoundError,
    405: MethodNotAllowedError,
    413: PayloadTooLargeError,
    415: UnsupportedMediaTypeError,
    422: InvalidRequestError,
    501: NotImplementedOnServerError,
    503: ServiceUnavailableError,
}


def retry_after_seconds(response: httpx.Response) -> float | None:
    """Return the ``Retry-After`` of `response` in seconds (delay-seconds form), or None.

    The HTTP-date form is read too; a value that is neither is ignored.
    """
    value = response.headers.get("retry-after")
    if value is None:
        return None
    value = value.strip()
    try:
        return max(0.0, float(value))
    except ValueError:
        pass
    from email.utils import parsedate_to_datetime

    try:
        when = parsedate_to_datetime(value)
    except (TypeError, ValueError):
        return None
    from datetime import datetime, timezone

    if when.tzinfo is None:
        when = when.replace(tzinfo=timezone.utc)
    return max(0.0, (when - datetime.now(timezone.utc)).total_seconds())


def api_error(response: httpx.Response) -> ApiError:
    """Return the exception for an error `response` (status 400 or more).

    A body that is not a problem document (a proxy's HTML page, say) becomes one with
    the status and the start of the text as `detail`.

    Examples
    --------
    >>> r = httpx.Response(422, json={"type": "urn:rnsca:problem:invalid-window",
    ...     "title": "Invalid window", "status": 422, "detail": "xmin must be < xmax",
    ...     "path": "window"})
    >>> error = api_error(r)
    >>> type(error).__name__, error.kind, error.path
    ('InvalidRequestError', 'invalid-window', 'window')
    >>> api_error(httpx.Response(502, text="<html>Bad gateway</html>"))
    ServerError('502 Bad Gateway: <html>Bad gateway</html>')
    """
    try:
        problem = response.json()
    except (json.JSONDecodeError, UnicodeDecodeError):
        problem = None
    if not isinstance(problem, dict) or "status" not in problem:
        problem = {"status": response.status_code, "title": response.reason_phrase,
                   "detail": response.text[:500]}
    return problem_error(problem, response.status_code, retry_after_seconds(response))


def problem_error(problem: dict[str, Any], status: int | None = None,
                  retry_after: float | None = None) -> ApiError:
    """Return the exception for a problem document (`status`: the HTTP one, if known).

    A streamed answer ends with such a document as its last record when a problem is
    met after the answer started (its HTTP status was already 200).

    Examples
    --------
    >>> error = problem_error({"type": "urn:rnsca:problem:parse-error", "status": 422,
    ...                        "title": "Malformed input", "record": 12,
    ...                        "detail": "record 12 is not valid JSON"})
    >>> type(error).__name__, error.record
    ('InvalidRequestError', 12)
    """
    kind = str(problem.get("type", ""))[len(PROBLEM_TYPE_PREFIX):]
    if status is None:
        status = int(problem.get("status", 0))
    cls = _BY_KIND.get(kind) or _BY_STATUS.get(status) or (
        ServerError if status >= 500 else ApiError)
    return cls(problem, retry_after=retry_after)
