"""Request and response models of the HTTP API (v1), documented in the OpenAPI schema.

Request models are strict (a number is a JSON number, not a string or a boolean) and
refuse unknown members, so a misspelt option is a 422 rather than silently ignored.
Option values are the library's own enums (`rnsca.Method`, `rnsca.Mode`,
`rnsca.Boundary`), converted here at the edge.
"""

from __future__ import annotations

import dataclasses
import typing
from enum import Enum
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, FiniteFloat, create_model, model_validator

from rnsca.options import MAX_DEPTH_LIMIT, N_MAX, N_MIN, Boundary, Method, Mode
from rnsca.stats import ClipStats
from rnsca.verify import Verification

__all__ = [
    "BackendName",
    "ClipOptions",
    "GeometryOptions",
    "SVGOptions",
    "ClipGeoJSONRequest",
    "ClipGeoJSONResponse",
    "ClipSVGRequest",
    "ClipSVGResponse",
    "ClipSegmentsRequest",
    "ClipSegmentsResponse",
    "StatsModel",
    "VerificationModel",
    "Capabilities",
    "OperationOptions",
    "Health",
    "Problem",
    "REQUEST_MODELS",
]

_STRICT = ConfigDict(strict=True, extra="forbid")

WindowBounds = Annotated[
    tuple[FiniteFloat, FiniteFloat, FiniteFloat, FiniteFloat],
    Field(description="The clip window `[xmin, ymin, xmax, ymax]`, closed; finite, "
                      "xmin < xmax and ymin < ymax.", examples=[[0, 0, 10, 10]])]


class BackendName(str, Enum):
    """Backends the API names (DESIGN.md); `/v1/capabilities` lists those present here.

    ``auto`` is not a backend but the measured choice between them (the library's
    ``backend="auto"``): OpenCL for a call at or above its crossover size on this
    machine, else Numba.
    """

    NUMBA = "numba"
    OPENCL = "opencl"
    AUTO = "auto"


class ClipOptions(BaseModel):
    """How to clip; every field has the library's default."""

    model_config = _STRICT

    method: Method = Field(Method.RNSCA, description="Segment clipping algorithm.")
    n: Annotated[int, Field(ge=N_MIN, le=N_MAX)] | Literal["auto"] = Field(
        "auto", description=f"Pieces per subdivision, {N_MIN}..{N_MAX}, or `auto` (chosen "
                            "per piece from its length).")
    max_depth: Annotated[int, Field(ge=0, le=MAX_DEPTH_LIMIT)] | None = Field(
        None, description=f"Deepest subdivision level, 0..{MAX_DEPTH_LIMIT} (default "
                          f"{MAX_DEPTH_LIMIT}).")
    tolerance: Annotated[float, Field(gt=0)] | None = Field(
        None, description="A piece no longer than this is a leaf (default: the "
                          "`resolution` in approx mode, infinite in exact mode).")
    resolution: Annotated[float, Field(gt=0, allow_inf_nan=False)] | Annotated[
        str, Field(pattern=r"^[1-9][0-9]{0,8}px$")] | None = Field(
        None, description="Approx mode: the output's resolution, which sets the tolerance: "
                          "a length in output units, or `<k>px`, the window's longer side "
                          "as k pixels (default `4096px`, a vector tile's grid). Not with "
                          "`tolerance`, nor in exact mode.")
    mode: Mode = Field(Mode.EXACT, description="`exact`: undecided leaves are clipped; "
                                               "`approx`: dropped (no intersections).")
    backend: BackendName | None = Field(
        None, description="Where it runs (default: the server's `default_backend`); one "
                          "not present here gives 422 with the reason. `auto`: OpenCL "
                          "where it measured faster here for this operation and size, "
                          "else Numba.")


class GeometryOptions(ClipOptions):
    """Options for GeoJSON geometry (points, lines, polygons)."""

    boundary: Boundary = Field(Boundary.CLOSED, description="`closed` keeps parts on the "
                               "window's edge (shapely.intersection); `interior` drops them "
                               "(shapely.clip_by_rect).")
    keep_empty: bool = Field(False, description="Keep features left empty (with empty "
                                                "coordinates) instead of dropping them.")
    check_validity: bool = Field(False, description="Count invalid input polygons with "
                                                    "GEOS in the stats (slower).")


class SVGOptions(ClipOptions):
    """Options for SVG paths."""

    curves: Literal["preserve", "flatten"] = Field(
        "preserve", description="Keep Bézier segments as curves, or flatten them to lines.")
    fill: Literal["nonzero", "evenodd"] | None = Field(
        None, description="Clip as filled areas with this fill rule, or as strokes (null).")
    fill_output: Literal["clean", "raw"] = Field(
        "clean", description="How fills are written (strokes ignore it); both paint the "
                             "same region. `clean`: closed subpaths whose rings are simple "
                             "(the visible parts joined along the window's edges, one line "
                             "per edge run, never along an edge twice), so any "
                             "polygoniser gives the painted region. `raw`: one closed "
                             "subpath per input subpath, its outside parts clamped onto "
                             "the edges: faster, but it may run along an edge back and "
                             "forth and touch itself.")


_VERIFY = Field(None, description="Compare with Shapely's exact intersection. true: "
                                  "within the server's verification budget (as long as the "
                                  "clip, `verify_cost_ratio`); past it a random sample of "
                                  "the inputs is compared and `verification` says how many "
                                  "(`checked` of `inputs`, `sampling`); \"all\": every "
                                  "input, as far as the request's time limit allows: "
                                  "comparing stops in time to answer, and `verification` "
                                  "says so (`timed_out`, `checked`, `note`); false: none. "
                                  "Either way an input GEOS would take too long to compare "
                                  "(an outline crossing itself more than the server's "
                                  "`verify_max_crossings` times) is counted in `skipped`, "
                                  "and `passed` is null (no verdict) when some inputs were "
                                  "not compared and none of those compared failed. "
                                  "Default: true for inputs of up to the server's "
                                  "`verify_max_vertices`. With `windows`, every (input, "
                                  "window) pair whose bounding boxes touch is one input, "
                                  "compared in its window, and one `verification` covers "
                                  "them all (`inputs` counts the pairs; the allowed "
                                  "deviation is that of the largest window).")


def _stats_fields() -> dict[str, Any]:
    hints = typing.get_type_hints(ClipStats)
    fields = {f.name: (list[int] if hints[f.name] == tuple[int, ...] else hints[f.name], ...)
              for f in dataclasses.fields(ClipStats)}
    fields["decided_shallow_fraction"] = (float, ...)
    return fields


StatsModel = create_model(
    "ClipStats", __doc__="What the clip did (see `rnsca.ClipStats` for each counter).",
    **_stats_fields())
_VERIFICATION_FIELDS: dict[str, Any] = {
    f.name: (typing.get_type_hints(Verification)[f.name], ...)
    for f in dataclasses.fields(Verification)}
VerificationModel = create_model(
    "Verification", __doc__="The comparison with Shapely's intersection (`rnsca.verify`).",
    **_VERIFICATION_FIELDS)

WindowList = Annotated[
    list[WindowBounds],
    Field(min_length=1, description="Many windows instead of `window`: the input is clipped "
                                    "to each (in one library call), and the answer holds one "
                                    "result per window, in this order. The work budget "
                                    "counts every vertex once per window.",
          examples=[[[0, 0, 5, 5], [5, 0, 10, 5]]])]


class _OneOrManyWindows(BaseModel):
    """A request with `window` or `windows`, exactly one of them."""

    window: WindowBounds | None = None
    windows: WindowList | None = None

    @model_validator(mode="after")
    def _one_of(self) -> _OneOrManyWindows:
        if (self.window is None) == (self.windows is None):
            raise ValueError("give one of window and windows")
        return self

    def window_table(self) -> list[tuple[float, float, float, float]]:
        """Return the windows asked for: `windows`, or `window` alone."""
        if self.windows is not None:
            return list(self.windows)
        assert self.window is not None
        return [self.window]


_LINE: dict[str, Any] = {"type": "Feature", "id": 1, "properties": {"name": "road"},
         "geometry": {"type": "LineString",
                      "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5], [15, 5]]}}


class ClipGeoJSONRequest(_OneOrManyWindows):
    """A GeoJSON Geometry, Feature or FeatureCollection and the window(s) to clip it to."""

    model_config = ConfigDict(**_STRICT, json_schema_extra={"examples": [
        {"window": [0, 0, 10, 10], "geojson": _LINE},
        {"windows": [[0, 0, 5, 5], [5, 0, 10, 5]], "geojson": _LINE}]})

    geojson: dict[str, Any] = Field(
        description="GeoJSON (RFC 7946) Geometry, Feature or FeatureCollection. Positions "
                    "have 2 or 3 numbers (more are checked, then dropped), and one document "
                    "may mix both: each position is answered with the dimension it came "
                    "in, and a new one (a cut point, a window corner) has Z only where "
                    "every Z it is computed from is known.")
    options: GeometryOptions = Field(default_factory=GeometryOptions)
    verify: bool | Literal["all"] | None = _VERIFY
    approx_bound: Annotated[float, Field(gt=0)] | None = Field(
        None, description="With verify in approx mode: the largest deviation to accept "
                          "(without it, approx results are not verified by default).")


class ClipGeoJSONResponse(BaseModel):
    """The clipped document (properties, ids and foreign members kept).

    With `windows`: `geojson` is a list, the document clipped to each window in order,
    and `verification` covers every (geometry, window) pair (see `verify`).
    """

    model_config = ConfigDict(json_schema_extra={"examples": [{
        "geojson": {**_LINE, "geometry": {"type": "MultiLineString", "coordinates": [
            [[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]}},
        "stats": {"segments_in": 5, "pieces_out": 4}, "verification": None}]})

    geojson: dict[str, Any] | list[dict[str, Any]]
    stats: StatsModel
    verification: VerificationModel | None


class ClipSVGRequest(_OneOrManyWindows):
    """SVG path data (the ``d`` attribute) and the window(s) to clip it to."""

    model_config = ConfigDict(**_STRICT, json_schema_extra={"examples": [
        {"window": [0, 0, 10, 10], "paths": ["M -5 5 C 0 15 10 -5 15 5"],
         "options": {"curves": "preserve"}}]})

    paths: list[str] = Field(description="Path data strings, e.g. `M 0 0 L 10 10`.")
    options: SVGOptions = Field(default_factory=SVGOptions)
    verify: bool | Literal["all"] | None = _VERIFY


class ClipSVGResponse(BaseModel):
    """The clipped path data, one string per input path.

    With `windows`: `paths` is a list per window (in order) of one string per input
    path (`""` where nothing of it is in that window), and `verification` covers every
    (path, window) pair (see `verify`).
    """

    paths: list[str] | list[list[str]]
    stats: StatsModel
    verification: VerificationModel | None


class ClipSegmentsRequest(BaseModel):
    """Line segments ``[x0, y0, x1, y1]`` and the window to clip them to."""

    model_config = ConfigDict(**_STRICT, json_schema_extra={"examples": [
        {"window": [0, 0, 10, 10], "segments": [[-5, 5, 15, 5], [20, 20, 30, 30]],
         "options": {"method": "rnsca", "mode": "exact"}}]})

    window: WindowBounds
    segments: list[tuple[float, float, float, float]] = Field(
        description="Segments as rows `[x0, y0, x1, y1]`; finite.")
    options: ClipOptions = Field(default_factory=ClipOptions)
    verify: bool | Literal["all"] | None = _VERIFY


class ClipSegmentsResponse(BaseModel):
    """The visible piece of each segment that has one, in input order."""

    model_config = ConfigDict(json_schema_extra={"examples": [{
        "segments": [[0.0, 5.0, 10.0, 5.0]], "source": [0], "t": [[0.25, 0.75]],
        "stats": {"segments_in": 2, "pieces_out": 1}, "verification": None,
        "method": "rnsca", "mode": "exact", "backend": "numba"}]})

    segments: list[tuple[float, float, float, float]] = Field(
        description="The pieces, inside the window, in input order and direction.")
    source: list[int] = Field(description="Index of the input segment of each piece.")
    t: list[tuple[float, float]] = Field(
        description="Parameter interval of each piece on its input segment.")
    stats: StatsModel
    verification: VerificationModel | None
    method: Method
    mode: Mode
    backend: str


class Limits(BaseModel):
    """The limits a request must stay within."""

    max_body_bytes: int = Field(description="Largest body (not of streamed GeoJSON).")
    max_vertices: int
    work_budget: int
    request_time_limit: float
    verify_max_vertices: int
    stream_chunk_bytes: int = Field(description="Streamed GeoJSON is clipped in chunks of "
                                                "about this many bytes of records ...")
    stream_chunk_records: int = Field(description="... or this many records.")
    stream_max_record_bytes: int = Field(description="Longest record of streamed GeoJSON.")
    max_tiles: int = Field(description="Most tiles `POST /v1/tiles` cuts in one zoom; more "
                                       "gives 413.")


class OperationOptions(BaseModel):
    """The methods and modes one kind of input is clipped with (others are refused)."""

    methods: list[str]
    modes: list[str]


class Capabilities(BaseModel):
    """What this server can do."""

    version: str
    methods: list[str]
    modes: list[str]
    operations: dict[str, OperationOptions] = Field(
        description="By kind of input (`segments`; `lines` and `polygons` of GeoJSON, "
                    "points take any; `paths` of SVG): the methods and modes it accepts, "
                    "on every backend. Polygons need exact mode; curves, method `rnsca`.")
    backends: list[dict[str, Any]] = Field(description="Each backend: name, available, "
                                                       "devices, and the reason if not; "
                                                       "where available, the operations "
                                                       "and modes it runs and its "
                                                       "precision.")
    threading_layer: str | None = Field(description="Numba's threading layer in use.")
    serialized: bool = Field(description="Whether clipping calls run one at a time.")
    svg: bool = Field(description="Whether `/v1/clip/svg` is implemented here.")
    limits: Limits


class Health(BaseModel):
    """Liveness or readiness."""

    status: str


class Problem(BaseModel):
    """An RFC 9457 problem (``application/problem+json``)."""

    model_config = ConfigDict(extra="allow", json_schema_extra={"examples": [{
        "type": "urn:rnsca:problem:invalid-geometry", "title": "Invalid geometry",
        "status": 422, "detail": "invalid GeoJSON at features[0].geometry.coordinates[1]: "
                                 "expected a position", "instance": "/v1/clip/geojson",
        "path": "geojson.features[0].geometry.coordinates[1]"}]})

    type: str
    title: str
    status: int
    detail: str
    instance: str | None = None
    path: str | None = Field(None, description="JSON path of the offending value.")
    position: int | None = Field(None, description="Character offset of a syntax error.")
    record: int | None = Field(None, description="Streamed GeoJSON: the number (from 0) of "
                                                 "the record at fault; `path` and `position` "
                                                 "are then within it.")


#: Models read from request bodies in a worker thread (see `service.routes.clip`); the
#: OpenAPI schema gets them from here.
REQUEST_MODELS = (ClipGeoJSONRequest, ClipSVGRequest, ClipSegmentsRequest)
