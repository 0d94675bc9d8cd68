"""Python client of the rnsca HTTP API: clip GeoJSON, GeoArrow, SVG paths, segments remotely.

GeoJSON goes whole (`Client.clip_geojson`) or streamed (`Client.clip_geojson_seq`).

Examples
--------
>>> import rnsca_client
>>> rnsca_client.Retry.of(2).attempts
3
"""

from rnsca_client.client import DEFAULT_RETRY, DEFAULT_TIMEOUT, DEFAULT_URL, AsyncClient, Client
from rnsca_client.errors import (
    ApiError,
    BackendUnavailableError,
    BadRequestError,
    ConnectError,
    InvalidInputError,
    InvalidRequestError,
    MethodNotAllowedError,
    NotFoundError,
    NotImplementedOnServerError,
    PayloadTooLargeError,
    RequestTimeoutError,
    ResponseFormatError,
    RnscaClientError,
    ServerError,
    ServiceUnavailableError,
    TransportError,
    UnsupportedMediaTypeError,
    WorkOverBudgetError,
)
from rnsca_client.results import (
    Backend,
    Capabilities,
    ClipStats,
    GeoArrowResult,
    GeoJSONResult,
    Health,
    Limits,
    SegmentsResult,
    SVGResult,
    Verification,
)
from rnsca_client.retry import Retry
from rnsca_client.streams import AsyncClippedRecords, ClippedRecords

__version__ = "0.1.0"

__all__ = [
    "Client", "AsyncClient", "Retry", "DEFAULT_URL", "DEFAULT_TIMEOUT", "DEFAULT_RETRY",
    "GeoJSONResult", "SVGResult", "SegmentsResult", "GeoArrowResult", "ClipStats", "Verification",
    "ClippedRecords", "AsyncClippedRecords",
    "Capabilities", "Backend", "Limits", "Health",
    "RnscaClientError", "InvalidInputError", "ResponseFormatError", "TransportError",
    "ConnectError", "RequestTimeoutError", "ApiError", "BadRequestError", "NotFoundError",
    "MethodNotAllowedError", "PayloadTooLargeError", "UnsupportedMediaTypeError",
    "InvalidRequestError", "BackendUnavailableError", "WorkOverBudgetError", "ServerError",
    "NotImplementedOnServerError", "ServiceUnavailableError",
]
