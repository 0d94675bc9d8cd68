"""``/v1/tiles``: a GeoJSON body cut into vector tiles (one tile, or a PMTiles archive)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Query, Request
from pydantic import BaseModel, ConfigDict, Field
from starlette.responses import Response

from rnsca.options import Mode
from service import convert
from service.deps import RunnerDep, SettingsDep
from service.errors import UnsupportedMediaTypeError
from service.schemas import Problem

__all__ = ["router", "MVT", "PMTILES"]

router = APIRouter(prefix="/v1/tiles", tags=["tiles"])

#: The media types of an answer: one Mapbox Vector Tile, a PMTiles archive.
MVT = "application/vnd.mapbox-vector-tile"
PMTILES = "application/vnd.pmtiles"

_PROBLEM: dict[str, Any] = {"model": Problem, "content": {"application/problem+json": {}}}
_ERRORS: dict[int | str, dict[str, Any]] = {
    413: {**_PROBLEM, "description": "Body or vertex count over the limit"},
    415: {**_PROBLEM, "description": "Unsupported Content-Type"},
    422: {**_PROBLEM, "description": "Invalid GeoJSON, tile, zooms or options; work over "
                                     "budget"},
    503: {**_PROBLEM, "description": "Request time limit exceeded (server busy)"}}
_BODY = {"requestBody": {"required": True, "content": {"application/json": {"schema": {
    "type": "object", "description": "A GeoJSON FeatureCollection, Feature or Geometry "
                                     "(lon/lat, or Web Mercator metres with crs)"}}}}}


class TileOptions(BaseModel):
    """How the tiles are cut (query parameters); unknown ones are refused."""

    model_config = ConfigDict(extra="forbid")

    extent: Annotated[int, Field(ge=1, le=2**20)] = Field(4096, description="Tile units "
                                                          "per tile side.")
    buffer: Annotated[int, Field(ge=0)] = Field(64, description="Tile units around a tile.")
    layer: str = Field("features", min_length=1, max_length=200, description="Layer name.")
    mode: Mode = Field(Mode.EXACT, description="`approx`: lines cut within a unit, inside "
                                               "the buffer.")
    crs: str = Field("EPSG:4326", description="`EPSG:4326` (lon/lat) or `EPSG:3857`.")


class PyramidOptions(TileOptions):
    """The zooms of a PMTiles archive, and how its tiles are cut."""

    minzoom: Annotated[int, Field(ge=0, le=24)] = 0
    maxzoom: Annotated[int, Field(ge=0, le=24)] = Field(
        10, description="Last zoom; the work budget counts every vertex once per zoom.")


async def _read_geojson(request: Request, runner: Any) -> tuple[bytes, float]:
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media not in ("application/json", "application/geo+json"):
        raise UnsupportedMediaTypeError(
            f"send the GeoJSON as application/json or application/geo+json, got "
            f"{media or 'no Content-Type'}")
    return await runner.read_body(request)


def _answer(outcome: convert.Outcome) -> Response:
    if not outcome.content and outcome.media_type == MVT:
        return Response(status_code=204, headers=outcome.headers)
    return Response(outcome.content, media_type=outcome.media_type, headers=outcome.headers)


@router.post("/{z}/{x}/{y}", responses={
    **_ERRORS, 200: {"content": {MVT: {"schema": {"type": "string", "format": "binary"}}},
                     "description": "The tile (uncompressed protobuf)"},
    204: {"description": "No feature in the tile"}},
    openapi_extra=_BODY, response_class=Response,
    summary="One vector tile of a GeoJSON document")
async def tile(request: Request, z: Annotated[int, Path(ge=0, le=24)],
               x: Annotated[int, Path(ge=0)], y: Annotated[int, Path(ge=0)],
               options: Annotated[TileOptions, Query()], settings: SettingsDep,
               runner: RunnerDep) -> Response:
    """Return tile `z/x/y` (WebMercatorQuad) of the body's features as a Mapbox Vector Tile.

    The body is a GeoJSON FeatureCollection, Feature or Geometry; the tile has one layer
    (`layer`), coordinates in `extent` units, `buffer` units around it, properties and
    integer ids kept (`rnsca.tiles.tile_one`). 204 when no feature reaches the tile.
    Headers: `X-Rnsca-Features`.
    """
    body, time_left = await _read_geojson(request, runner)
    return _answer(await runner.run(convert.tile_one, body, z, x, y, options, settings,
                                    time_left=time_left, endpoint="tiles"))


@router.post("", responses={
    **_ERRORS, 200: {"content": {PMTILES: {"schema": {"type": "string", "format": "binary"}}},
                     "description": "A PMTiles v3 archive (tiles gzip-compressed)"}},
    openapi_extra=_BODY, response_class=Response,
    summary="A PMTiles archive of a GeoJSON document's tiles")
async def pyramid(request: Request, options: Annotated[PyramidOptions, Query()],
                  settings: SettingsDep, runner: RunnerDep) -> Response:
    """Return the tiles of zooms `minzoom..maxzoom` of the body's features as PMTiles v3.

    As `POST /v1/tiles/{z}/{x}/{y}` for each tile (`rnsca.tiles.tile_table`, one clipping
    pass per zoom). Headers: `X-Rnsca-Tiles`, `X-Rnsca-Features`.
    """
    body, time_left = await _read_geojson(request, runner)
    return _answer(await runner.run(convert.tile_pyramid, body, options, settings,
                                    time_left=time_left, endpoint="tiles"))
