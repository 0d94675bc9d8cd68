"""``/v1/clip/*``: read the body, hand it to the conversion layer in the thread pool."""

from __future__ import annotations

import time
from typing import Annotated, Any, Literal, TypeVar

from fastapi import APIRouter, Query, Request
from pydantic import BaseModel, ConfigDict, Field, FiniteFloat
from starlette.responses import Response

from rnsca.errors import RnscaError
from rnsca.io.geojson_seq import Framing
from rnsca.options import Boundary, Method, Mode
from rnsca.window import Window
from service import convert
from service.deps import MetricsDep, RunnerDep, SettingsDep
from service.errors import ServiceError, UnsupportedMediaTypeError
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
from service.streaming import SUMMARY_TYPE, SequenceResponse, StreamedClip, refusal

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


class WindowQuery(BaseModel):
    """Window and options given as query parameters (binary and streamed bodies).

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


_VERIFY_QUERY = Field(
    None, description="true: within the verification budget (a random sample past it); "
                      "all: every segment, as far as the request's time limit allows "
                      "(X-Rnsca-Verification says how many); false: none.")


class SegmentQuery(WindowQuery):
    """Window and options of a binary request (ignored for JSON bodies)."""

    verify: bool | Literal["all"] | None = _VERIFY_QUERY


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
        options = _query_options(query, ClipOptions)
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


def _query_window(query: WindowQuery) -> Window:
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


class GeometryQuery(WindowQuery):
    """Window and options of a geometry request given as query parameters."""

    boundary: Boundary | None = Field(None, description="As in the GeoJSON options.")
    keep_empty: bool | None = Field(
        None, description="Keep rows (records) whose geometry is clipped away, empty or "
                          "null (an empty geometry; null stays null) instead of dropping "
                          "them.")
    check_validity: bool | None = None


class GeoArrowQuery(GeometryQuery):
    """Window and options of ``POST /v1/clip/geoarrow`` (the body is the Arrow stream)."""

    verify: bool | Literal["all"] | None = _VERIFY_QUERY
    column: str | None = Field(
        None, description="The geometry column (default: the one tagged geoarrow.*, else a "
                          "binary column named `geometry`, read as WKB).")


_Options = TypeVar("_Options", bound=ClipOptions)


def _query_options(query: WindowQuery, model: type[_Options]) -> _Options:
    """Return the options `query` gives, validated by `model` (the JSON body's options)."""
    names = set(model.model_fields) & set(type(query).model_fields) - {"resolution"}
    given = {k: v for k, v in query.model_dump(include=names).items() if v is not None}
    return model.model_validate(given | _query_resolution(query.resolution), strict=False)


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
    parts), WKB and WKT values keep a single kind left in one part and their own
    dimension (2D values beside 3D ones stay 2D). Other columns are passed through; rows
    whose geometry is clipped away (or empty, or null) are dropped unless `keep_empty`,
    also when every row is null. Empty parts (a polygon of no rings, or whose exterior is
    empty) are dropped. Headers: `X-Rnsca-Rows` (rows out), `X-Rnsca-Stats` and
    `X-Rnsca-Verification` (JSON; verification by default up to the server's
    `verify_max_vertices`, never in approx mode).
    """
    media = _media_type(request)
    if media != convert.ARROW_STREAM:
        raise UnsupportedMediaTypeError(
            f"send the body as {convert.ARROW_STREAM}, got {media or 'no Content-Type'}")
    window = _query_window(query)
    options = _query_options(query, GeometryOptions)
    body, time_left = await runner.read_body(request)
    outcome = await runner.run(convert.clip_geoarrow, body, window, options, query.column,
                               query.verify, settings, _deadline(time_left),
                               time_left=time_left, endpoint="geoarrow")
    return _respond(outcome, metrics)


# --- Streamed GeoJSON ----------------------------------------------------------------

#: Body media types of ``POST /v1/clip/geojson-seq`` and the framing each stands for.
SEQUENCE_MEDIA = {
    "application/geo+json-seq": Framing.RS,   # RFC 8142
    "application/json-seq": Framing.RS,       # RFC 7464
    "application/x-ndjson": Framing.LINES,
    "application/ndjson": Framing.LINES,
    "application/jsonl": Framing.LINES,
}


class GeoJSONSeqQuery(GeometryQuery):
    """Window and options of ``POST /v1/clip/geojson-seq`` (the body is the records)."""

    summary: bool = Field(
        False, description=f"End the answer with one summary record (`type` "
                           f"`{SUMMARY_TYPE}`: `records_in`, `records_out`, `chunks` and "
                           f"the clip's `stats`).")


def _answer_media(request: Request, sent: str) -> str:
    """Return the answer's media type: the first sequence type `Accept` names, else `sent`."""
    for item in request.headers.get("accept", "").split(","):
        media = item.split(";")[0].strip().lower()
        if media in SEQUENCE_MEDIA:
            return media
    return sent


_SEQUENCE_BODY = {"requestBody": {"required": True, "content": {
    media: {"schema": {"type": "string", "format": "binary",
                       "description": "GeoJSON texts, one Feature, Geometry or "
                                      "FeatureCollection each: "
                                      + ("RS before each, LF after it (RFC 8142)"
                                         if framing is Framing.RS else "one per line")}}
    for media, framing in SEQUENCE_MEDIA.items()}}}


@router.post("/geojson-seq", responses={
    **_ERRORS, 200: {"content": {media: {"schema": {"type": "string", "format": "binary"}}
                                 for media in SEQUENCE_MEDIA},
                     "description": "The records clipped, streamed in the request's framing "
                                    "(or the one Accept names)"}},
    openapi_extra=_SEQUENCE_BODY, response_class=Response,
    summary="Clip streamed GeoJSON (text sequences or newline-delimited), chunk by chunk")
async def clip_geojson_seq(request: Request, query: Annotated[GeoJSONSeqQuery, Query()],
                           settings: SettingsDep, runner: RunnerDep,
                           metrics: MetricsDep) -> Response:
    """Return each record clipped, streamed as the body arrives, in input order.

    The body is a sequence of GeoJSON texts, each a Feature, a Geometry or a
    FeatureCollection: `application/geo+json-seq` (RFC 8142: RS 0x1E before each text,
    LF after it; also `application/json-seq`), or newline-delimited GeoJSON
    (`application/x-ndjson`, `application/ndjson`, `application/jsonl`: one text per
    line). Blank lines are skipped. The window (`xmin, ymin, xmax, ymax`) and the
    options are query parameters, as for GeoArrow, with `summary`; there is no
    verification on this endpoint (`/v1/clip/geojson` verifies).

    The body is read and clipped a chunk of records at a time (the server's
    `stream_chunk_bytes` or `stream_chunk_records`, whichever is reached first, or
    what has arrived when the body pauses), and each chunk's answer is sent as soon as
    it is clipped: memory holds one chunk whatever the body's length, and no limit on
    the body's length applies (a record is at most `stream_max_record_bytes`;
    `max_vertices` and the work budget apply to each chunk, the time limit to each
    chunk's wait for its body and for its clip). The answer is in the request's framing
    (or the first sequence type `Accept` names): each record clipped as
    `/v1/clip/geojson` clips it (a Geometry stays a Geometry, a Feature keeps its
    `properties`, `id` and foreign members), in input order; records left empty are
    dropped unless `keep_empty`.

    Errors: a problem in the first chunk (or with the options) is the request's status
    with a problem document, which names the `record` (from 0) and the `path` in it.
    After the first chunk the status is sent: a problem ends the answer with the
    records before the bad one, then a problem record (RFC 9457 members, `type`
    `urn:rnsca:problem:...`) as the last record. Read the answer while you send the
    body, or not: what you have not read yet waits on the server's disk.
    """
    media = _media_type(request)
    framing = SEQUENCE_MEDIA.get(media)
    if framing is None:
        raise UnsupportedMediaTypeError(
            f"send GeoJSON text sequences as {', '.join(SEQUENCE_MEDIA)}, got "
            f"{media or 'no Content-Type'}")
    window = _query_window(query)
    options = _query_options(query, GeometryOptions)
    answer = _answer_media(request, media)
    clip = StreamedClip(request.receive, framing, SEQUENCE_MEDIA[answer], window, options,
                        query.summary, settings, runner, metrics, request.url.path)
    try:
        await clip.start()
    except (RnscaError, ServiceError) as exc:
        return refusal(exc, request.url.path, clip.body_ended)
    return SequenceResponse(clip, answer)
