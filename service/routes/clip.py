"""``/v1/clip/*``: read the body, hand it to the conversion layer in the thread pool."""

from __future__ import annotations

import time
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Request
from pydantic import BaseModel, ConfigDict, Field, FiniteFloat
from starlette.responses import Response

from rnsca.options import Boundary, Method, Mode
from rnsca.window import Window
from service import convert
from service.deps import MetricsDep, RunnerDep, SettingsDep
from service.errors import UnsupportedMediaTypeError
from service.metrics import Metrics
from service.runner import ClipRunner
from service.schemas import (
    BackendName,
    ClipGeoJSONRequest,
    ClipGeoJSONResponse,
    ClipOptions,
    ClipSegmentsRequest,
    ClipSegmentsResponse,
    ClipSVGRequest,
    ClipSVGResponse,
    GeometryOptions,
    Problem,
)

__all__ = ["router"]

router = APIRouter(prefix="/v1/clip", tags=["clip"])

_PROBLEM: dict[str, Any] = {"model": Problem, "content": {"application/problem+json": {}}}
_ERRORS: dict[int | str, dict[str, Any]] = {
    400: {**_PROBLEM, "description": "Malformed JSON"},
    413: {**_PROBLEM, "description": "Body or vertex count over the limit"},
    415: {**_PROBLEM, "description": "Unsupported Content-Type"},
    422: {**_PROBLEM, "description": "Invalid window, options, geometry or coordinates; work "
                                     "over budget; backend not available"},
    503: {**_PROBLEM, "description": "Request time limit exceeded (server busy)"}}


def _json_body(model: type[BaseModel], binary: bool = False) -> dict:
    """Return the OpenAPI ``requestBody`` of a route that validates `model` itself."""
    content = {"application/json": {"schema": {"$ref": f"#/components/schemas/{model.__name__}"}}}
    if binary:
        content["application/octet-stream"] = {
            "schema": {"type": "string", "format": "binary",
                       "description": "Little-endian float64 rows x0, y0, x1, y1; window "
                                      "and options as query parameters."}}
    return {"requestBody": {"required": True, "content": content}}


def _media_type(request: Request) -> str:
    return request.headers.get("content-type", "").split(";")[0].strip().lower()


async def _read_json(request: Request, runner: ClipRunner) -> tuple[bytes, float]:
    """Return the JSON body (unparsed) and the time the request has left."""
    media = _media_type(request)
    if media != "application/json" and not media.endswith("+json"):
        raise UnsupportedMediaTypeError(
            f"send the body as application/json, got {media or 'no Content-Type'}")
    return await runner.read_body(request)


def _deadline(time_left: float) -> float:
    """Return when the answer is due, as a `time.monotonic` value (for verification)."""
    return time.monotonic() + time_left


def _respond(outcome: convert.Outcome, metrics: Metrics) -> Response:
    if outcome.stats is not None:
        metrics.observe_clip(outcome.stats)
    return Response(outcome.content, media_type=outcome.media_type, headers=outcome.headers)


@router.post("/geojson", response_model=ClipGeoJSONResponse, responses=_ERRORS,
             openapi_extra=_json_body(ClipGeoJSONRequest),
             summary="Clip a GeoJSON Geometry, Feature or FeatureCollection")
async def clip_geojson(request: Request, settings: SettingsDep, runner: RunnerDep,
                       metrics: MetricsDep) -> Response:
    """Return the document clipped to the window, with the stats (and verification).

    Properties, ids and foreign members are kept; a geometry takes the type of what is
    left (a LineString cut in two becomes a MultiLineString).
    """
    body, time_left = await _read_json(request, runner)
    return _respond(await runner.run(convert.clip_geojson, body, settings,
                                     _deadline(time_left), time_left=time_left,
                                     endpoint="geojson"), metrics)


@router.post("/svg", response_model=ClipSVGResponse,
             responses=_ERRORS,
             openapi_extra=_json_body(ClipSVGRequest), summary="Clip SVG path data")
async def clip_svg(request: Request, settings: SettingsDep, runner: RunnerDep,
                   metrics: MetricsDep) -> Response:
    """Return each path's data clipped to the window (curves kept or flattened)."""
    body, time_left = await _read_json(request, runner)
    return _respond(await runner.run(convert.clip_svg, body, settings, _deadline(time_left),
                                     time_left=time_left, endpoint="svg"), metrics)


class SegmentQuery(BaseModel):
    """Window and options of a binary request (ignored for JSON bodies).

    Unknown parameters are refused (422), as unknown members of a JSON body are: a
    misspelt option must not silently clip with the default.
    """

    model_config = ConfigDict(extra="forbid")

    xmin: FiniteFloat | None = None
    ymin: FiniteFloat | None = None
    xmax: FiniteFloat | None = None
    ymax: FiniteFloat | None = None
    method: Method | None = None
    n: Annotated[int, Field(ge=2, le=64)] | None = Field(None, description="Omitted: auto.")
    max_depth: Annotated[int, Field(ge=0, le=32)] | None = None
    tolerance: Annotated[float, Field(gt=0)] | None = None
    resolution: str | None = Field(None, description="Approx mode: a length, or `<k>px`.")
    mode: Mode | None = None
    backend: BackendName | None = None
    verify: bool | Literal["all"] | None = Field(
        None, description="true: within the verification budget (a random sample past it); "
                          "all: every segment, as far as the request's time limit allows "
                          "(X-Rnsca-Verification says how many); false: none.")


@router.post("/segments", response_model=ClipSegmentsResponse,
             responses={**_ERRORS, 200: {"content": {"application/octet-stream": {}},
                                         "description": "JSON, or binary for a binary "
                                                        "request (see the description)"}},
             openapi_extra=_json_body(ClipSegmentsRequest, binary=True),
             summary="Clip line segments (JSON or binary)")
async def clip_segments(request: Request, query: Annotated[SegmentQuery, Query()],
                        settings: SettingsDep, runner: RunnerDep,
                        metrics: MetricsDep) -> Response:
    """Return the visible piece of each segment, with its source index and interval.

    JSON: the body is `ClipSegmentsRequest`. Binary (`application/octet-stream`): the
    body is little-endian float64 rows `x0, y0, x1, y1`, the window is the query
    parameters `xmin, ymin, xmax, ymax` and the options further query parameters; the
    answer is binary too: the pieces as float64 rows of 4, then their source indices as
    int64, then their intervals `t` as float64 rows of 2 (header `X-Rnsca-Pieces` gives
    their number; `X-Rnsca-Stats` and `X-Rnsca-Verification` hold JSON).
    """
    media = _media_type(request)
    if media == "application/octet-stream":
        window = _query_window(query)
        options = ClipOptions.model_validate({
            k: v for k, v in query.model_dump(
                include={"method", "n", "max_depth", "tolerance", "mode", "backend"}).items()
            if v is not None} | _query_resolution(query.resolution), strict=False)
        body, time_left = await runner.read_body(request)
        outcome = await runner.run(convert.clip_segments_binary, body, window, options,
                                   query.verify, settings, _deadline(time_left),
                                   time_left=time_left, endpoint="segments")
    else:
        body, time_left = await _read_json(request, runner)
        outcome = await runner.run(convert.clip_segments_json, body, settings,
                                   _deadline(time_left), time_left=time_left,
                                   endpoint="segments")
    return _respond(outcome, metrics)


def _query_resolution(text: str | None) -> dict:
    """Return ``{"resolution": ...}`` for ClipOptions: a number, or the ``<k>px`` text."""
    if text is None:
        return {}
    try:
        return {"resolution": float(text)}
    except ValueError:
        return {"resolution": text}  # ClipOptions checks the '<k>px' form


def _query_window(query: SegmentQuery) -> Window:
    bounds = (query.xmin, query.ymin, query.xmax, query.ymax)
    given = [b for b in bounds if b is not None]
    if len(given) < len(bounds):
        from fastapi.exceptions import RequestValidationError

        missing = [name for name, b in zip(("xmin", "ymin", "xmax", "ymax"), bounds,
                                           strict=True) if b is None]
        raise RequestValidationError([{
            "loc": ("query", name), "msg": "Field required (the window of a binary request)",
            "type": "missing"} for name in missing])
    return Window(*given)


class GeoArrowQuery(SegmentQuery):
    """Window and options of ``POST /v1/clip/geoarrow`` (the body is the Arrow stream)."""

    boundary: Boundary | None = Field(None, description="As in the GeoJSON options.")
    keep_empty: bool | None = Field(
        None, description="Keep rows whose geometry is clipped away, empty or null (an "
                          "empty geometry; null stays null) instead of dropping them.")
    check_validity: bool | None = None
    column: str | None = Field(
        None, description="The geometry column (default: the one tagged geoarrow.*, else a "
                          "binary column named `geometry`, read as WKB).")


_ARROW_BODY = {"requestBody": {"required": True, "content": {convert.ARROW_STREAM: {
    "schema": {"type": "string", "format": "binary",
               "description": "An Arrow IPC stream with one GeoArrow geometry column."}}}}}


@router.post("/geoarrow", responses={
    **_ERRORS, 200: {"content": {convert.ARROW_STREAM: {
        "schema": {"type": "string", "format": "binary"}}},
        "description": "The table, its geometry column clipped (an Arrow IPC stream)"}},
    openapi_extra=_ARROW_BODY, response_class=Response,
    summary="Clip the geometry column of an Arrow table (GeoArrow)")
async def clip_geoarrow(request: Request, query: Annotated[GeoArrowQuery, Query()],
                        settings: SettingsDep, runner: RunnerDep,
                        metrics: MetricsDep) -> Response:
    """Return the table with its geometry column clipped to the window.

    The body is an Arrow IPC stream (`application/vnd.apache.arrow.stream`) whose
    geometry column is GeoArrow: `geoarrow.point`, `linestring`, `polygon`,
    `multipoint`, `multilinestring` or `multipolygon` (coordinates separated or
    interleaved, xy or xyz), `geoarrow.wkb` or `geoarrow.wkt`, named by the field's
    `ARROW:extension:name`; a binary column named `geometry` without it is read as WKB.
    The window (`xmin, ymin, xmax, ymax`) and options are query parameters, as for
    binary segments, with `boundary`, `keep_empty`, `check_validity` and `column`.

    The answer is an Arrow IPC stream of the same columns and encoding: lines and
    polygons come back as multilinestrings and multipolygons (a cut may leave several
    parts), WKB and WKT values keep a single kind left in one part. Other columns are
    passed through; rows whose geometry is clipped away (or empty, or null) are dropped
    unless `keep_empty`. Headers: `X-Rnsca-Rows` (rows out), `X-Rnsca-Stats` and
    `X-Rnsca-Verification` (JSON; verification by default up to the server's
    `verify_max_vertices`, never in approx mode).
    """
    media = _media_type(request)
    if media != convert.ARROW_STREAM:
        raise UnsupportedMediaTypeError(
            f"send the body as {convert.ARROW_STREAM}, got {media or 'no Content-Type'}")
    window = _query_window(query)
    options = GeometryOptions.model_validate({
        k: v for k, v in query.model_dump(
            include={"method", "n", "max_depth", "tolerance", "mode", "backend", "boundary",
                     "keep_empty", "check_validity"}).items()
        if v is not None} | _query_resolution(query.resolution), strict=False)
    body, time_left = await runner.read_body(request)
    outcome = await runner.run(convert.clip_geoarrow, body, window, options, query.column,
                               query.verify, settings, _deadline(time_left),
                               time_left=time_left, endpoint="geoarrow")
    return _respond(outcome, metrics)
