"""Python client of the rnsca HTTP API: clip GeoJSON, GeoPandas, GeoArrow, SVG and segments.

GeoJSON goes whole (`Client.clip_geojson`) or streamed (`Client.clip_geojson_seq`);
GeoJSON and SVG to many windows in one request (`Client.clip_geojson_windows`,
`Client.clip_svg_windows`); vector tiles and PMTiles archives (`Client.tile`,
`Client.tiles`).

Examples
--------
>>> import rnsca_client
>>> rnsca_client.Retry.of(2).attempts
3
"""

from rnsca_client.client import (
    DEFAULT_CONCURRENCY,
    DEFAULT_RETRY,
    DEFAULT_TIMEOUT,
    DEFAULT_URL,
    AsyncClient,
    Client,
)
from rnsca_client.clipping import DEFAULT_BATCH_SIZE
from rnsca_client.errors import (
    ApiError,
    BackendUnavailableError,
    BadRequestError,
    BatchError,
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
    ClipResult,
    ClipStats,
    GeoArrowResult,
    GeoJSONResult,
    GeoJSONWindowsResult,
    Health,
    Limits,
    SegmentsResult,
    SVGResult,
    SVGWindowsResult,
    TileArchive,
    VectorTile,
    Verification,
)
from rnsca_client.retry import Retry
from rnsca_client.streams import AsyncClippedRecords, ClippedRecords

__version__ = "0.1.0"

__all__ = [
    "Client", "AsyncClient", "Retry", "DEFAULT_URL", "DEFAULT_TIMEOUT", "DEFAULT_RETRY",
    "DEFAULT_CONCURRENCY", "DEFAULT_BATCH_SIZE",
    "ClipResult", "GeoJSONResult", "SVGResult", "SegmentsResult", "GeoArrowResult", "ClipStats",
    "GeoJSONWindowsResult", "SVGWindowsResult", "VectorTile", "TileArchive",
    "Verification", "ClippedRecords", "AsyncClippedRecords",
    "Capabilities", "Backend", "Limits", "Health",
    "RnscaClientError", "InvalidInputError", "ResponseFormatError", "BatchError",
    "TransportError",
    "ConnectError", "RequestTimeoutError", "ApiError", "BadRequestError", "NotFoundError",
    "MethodNotAllowedError", "PayloadTooLargeError", "UnsupportedMediaTypeError",
    "InvalidRequestError", "BackendUnavailableError", "WorkOverBudgetError", "ServerError",
    "NotImplementedOnServerError", "ServiceUnavailableError",
]
