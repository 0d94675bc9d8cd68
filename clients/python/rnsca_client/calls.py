"""The API's calls, free of I/O: each builds a request and knows how to read its answer.

`Client` and `AsyncClient` only send a `Call` (with retries) and hand the response to
`Call.finish`, so the two clients cannot drift apart.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Generic, TypeVar

import httpx

from rnsca_client.errors import InvalidInputError, ResponseFormatError, api_error
from rnsca_client.inputs import (
    arrow_stream,
    encode_json,
    geojson_document,
    is_numpy_array,
    segment_rows,
    svg_paths,
    window_bounds,
)
from rnsca_client.results import (
    Capabilities,
    ClipStats,
    GeoArrowResult,
    GeoJSONResult,
    GeoJSONWindowsResult,
    Health,
    SegmentsResult,
    SVGResult,
    SVGWindowsResult,
    TileArchive,
    VectorTile,
    Verification,
)

__all__ = ["Call", "clip_geojson", "clip_geojson_windows", "clip_feature_collection",
           "clip_svg", "clip_svg_windows", "clip_segments", "clip_geoarrow", "tile", "tiles",
           "capabilities", "health", "readiness", "BINARY_OPTIONS", "TILE_OPTIONS"]

T = TypeVar("T")
_JSON = {"Content-Type": "application/json", "Accept": "application/json"}
#: Binary answers are asked for uncompressed: float64 coordinates gain little from gzip
#: (an Arrow stream of 10,000 polygons: 12 % smaller) and compressing them costs the
#: server far more than sending them (that stream: 440 ms gzip, 60 ms identity, on
#: loopback; 200,000 binary segments: 1.7 s against 24 ms; benchmarks/sdk_frames.py).
_UNCOMPRESSED = {"Accept-Encoding": "identity"}
#: Options the binary segments form takes as query parameters (the JSON form's options).
BINARY_OPTIONS = ("method", "n", "max_depth", "tolerance", "mode", "backend")


@dataclass(frozen=True)
class Call(Generic[T]):
    """One request to the API and the reader of its success answer.

    `retry_unavailable` is False where a 503 is an answer rather than a failure
    (``/readyz``).
    """

    method: str
    path: str
    read: Callable[[httpx.Response], T]
    content: bytes | None = None
    params: dict[str, str] | None = None
    headers: Mapping[str, str] = field(default_factory=lambda: {"Accept": "application/json"})
    retry_unavailable: bool = True
    accept: tuple[int, ...] = ()

    def finish(self, response: httpx.Response) -> T:
        """Return the result read from `response`, or raise its `ApiError`."""
        if response.status_code >= 400 and response.status_code not in self.accept:
            raise api_error(response)
        return self.read(response)


def _json(response: httpx.Response) -> Any:
    try:
        return response.json()
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ResponseFormatError(
            f"{response.request.method} {response.request.url.path} answered "
            f"{response.status_code} with a body that is not JSON: {exc}") from None


def _reader(build: Callable[[dict], T]) -> Callable[[httpx.Response], T]:
    def read(response: httpx.Response) -> T:
        data = _json(response)
        try:
            return build(data)
        except (KeyError, TypeError, AttributeError) as exc:
            raise ResponseFormatError(
                f"{response.request.url.path} answered JSON without the documented "
                f"members ({type(exc).__name__}: {exc}); is this an rnsca server?") from None
    return read


def _plain(value: Any) -> Any:
    """Return an option value as JSON sends it (enums by their value)."""
    return value.value if isinstance(value, Enum) else value


def _options(options: Mapping[str, Any]) -> dict[str, Any]:
    """Return the options object: None means the server's default, so it is left out."""
    return {name: _plain(value) for name, value in options.items() if value is not None}


def _post_json(path: str, payload: dict[str, Any], build: Callable[[dict], T]) -> Call[T]:
    return Call("POST", path, _reader(build), content=encode_json(payload), headers=_JSON)


def clip_geojson(obj: Any, window: Any, *, verify: bool | str | None, approx_bound: float | None,
                 options: Mapping[str, Any]) -> Call[GeoJSONResult]:
    """Return the call ``POST /v1/clip/geojson``."""
    payload = _clip_payload("window", window_bounds(window), "geojson", geojson_document(obj),
                            verify, approx_bound, options)
    return _post_json("/v1/clip/geojson", payload, GeoJSONResult.from_dict)


def _clip_payload(window_key: str, bounds: Any, input_key: str, data: Any,
                  verify: bool | str | None, approx_bound: float | None,
                  options: Mapping[str, Any]) -> dict[str, Any]:
    """Return a clip's JSON body: `bounds` under `window_key`, `data` under `input_key`."""
    payload: dict[str, Any] = {window_key: bounds, input_key: data,
                               "options": _options(options)}
    if verify is not None:
        payload["verify"] = verify
    if approx_bound is not None:
        payload["approx_bound"] = approx_bound
    return payload


def _window_list(windows: Any) -> list[list[float]]:
    """Return `windows` as ``[[xmin, ymin, xmax, ymax], ...]``, at least one."""
    if isinstance(windows, (str, bytes)) or not hasattr(windows, "__iter__"):
        raise InvalidInputError(f"windows must be a list of [xmin, ymin, xmax, ymax], got "
                                f"{windows!r:.80}")
    rows = windows.tolist() if is_numpy_array(windows) else list(windows)
    if not rows:
        raise InvalidInputError("windows must hold at least one [xmin, ymin, xmax, ymax]")
    bounds = []
    for i, row in enumerate(rows):
        try:
            bounds.append(window_bounds(row))
        except InvalidInputError as exc:
            raise InvalidInputError(f"windows[{i}]: {exc}") from None
    return bounds


def clip_geojson_windows(obj: Any, windows: Any, *, verify: bool | str | None,
                         approx_bound: float | None,
                         options: Mapping[str, Any]) -> Call[GeoJSONWindowsResult]:
    """Return the call ``POST /v1/clip/geojson`` with ``windows``."""
    payload = _clip_payload("windows", _window_list(windows), "geojson",
                            geojson_document(obj), verify, approx_bound, options)
    return _post_json("/v1/clip/geojson", payload, GeoJSONWindowsResult.from_dict)


def clip_feature_collection(features: bytes, window: Any, *, verify: bool | str | None,
                            options: Mapping[str, Any]) -> Call[GeoJSONResult]:
    """Return the call ``POST /v1/clip/geojson`` of a FeatureCollection's JSON bytes.

    The bytes go into the body as they are (not parsed and written again).
    """
    payload: dict[str, Any] = {"window": window_bounds(window), "options": _options(options)}
    if verify is not None:
        payload["verify"] = verify
    content = encode_json(payload)[:-1] + b',"geojson":' + features + b"}"
    return Call("POST", "/v1/clip/geojson", _reader(GeoJSONResult.from_dict),
                content=content, headers=_JSON)


def clip_svg(paths: str | Sequence[str], window: Any, *, verify: bool | str | None,
             options: Mapping[str, Any]) -> Call[SVGResult]:
    """Return the call ``POST /v1/clip/svg``."""
    payload = _clip_payload("window", window_bounds(window), "paths", svg_paths(paths),
                            verify, None, options)
    return _post_json("/v1/clip/svg", payload, SVGResult.from_dict)


def clip_svg_windows(paths: str | Sequence[str], windows: Any, *, verify: bool | str | None,
                     options: Mapping[str, Any]) -> Call[SVGWindowsResult]:
    """Return the call ``POST /v1/clip/svg`` with ``windows``."""
    payload = _clip_payload("windows", _window_list(windows), "paths", svg_paths(paths),
                            verify, None, options)
    return _post_json("/v1/clip/svg", payload, SVGWindowsResult.from_dict)


def clip_segments(segments: Any, window: Any, *, binary: bool | None, verify: bool | str | None,
                  options: Mapping[str, Any]) -> Call[SegmentsResult]:
    """Return the call ``POST /v1/clip/segments``: binary for NumPy input, else JSON."""
    if binary is None:
        binary = is_numpy_array(segments)
    if not binary:
        rows = segments.tolist() if is_numpy_array(segments) else [list(s) for s in segments]
        payload: dict[str, Any] = {"window": window_bounds(window), "segments": rows,
                   "options": _options(options)}
        if verify is not None:
            payload["verify"] = verify
        return _post_json("/v1/clip/segments", payload, SegmentsResult.from_dict)
    params = _query(window, options, verify, BINARY_OPTIONS, "segments")
    return Call("POST", "/v1/clip/segments", _read_binary_segments,
                content=segment_rows(segments).tobytes(), params=params,
                headers={"Content-Type": "application/octet-stream",
                         "Accept": "application/octet-stream", **_UNCOMPRESSED})


#: The media type of ``POST /v1/clip/geoarrow``'s body and answer.
ARROW_STREAM = "application/vnd.apache.arrow.stream"
#: Options the GeoArrow endpoint takes as query parameters.
GEOARROW_OPTIONS = (*BINARY_OPTIONS, "resolution", "boundary", "keep_empty",
                    "check_validity")


def clip_geoarrow(table: Any, window: Any, *, column: str | None,
                  verify: bool | str | None, options: Mapping[str, Any]
                  ) -> Call[GeoArrowResult]:
    """Return the call ``POST /v1/clip/geoarrow``: an Arrow IPC stream in and out.

    `table` is the stream's bytes, or a ``pyarrow.Table`` or ``RecordBatch`` (written
    as a stream here, with pyarrow).
    """
    params = _query(window, options, verify, GEOARROW_OPTIONS, "GeoArrow")
    if column is not None:
        params["column"] = column
    return Call("POST", "/v1/clip/geoarrow", _read_geoarrow, content=arrow_stream(table),
                params=params, headers={"Content-Type": ARROW_STREAM, "Accept": ARROW_STREAM,
                                        **_UNCOMPRESSED})


def _query(window: Any, options: Mapping[str, Any], verify: bool | str | None,
           accepted: tuple[str, ...], endpoint: str) -> dict[str, str]:
    """Return the query parameters of a binary endpoint: window, options and verify."""
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise InvalidInputError(
            f"unknown option(s) {', '.join(unknown)} for {endpoint}; accepted: "
            f"{', '.join(accepted)}")
    params = dict(zip(("xmin", "ymin", "xmax", "ymax"),
                      (repr(b) for b in window_bounds(window)), strict=True))
    for name, value in {**_options(options), "verify": verify}.items():
        if value is None or (name == "n" and value == "auto"):  # the query's defaults
            continue
        params[name] = ("true" if value else "false") if isinstance(value, bool) \
            else str(value)
    return params


def _stats_and_verification(headers: httpx.Headers) -> tuple[ClipStats, Verification | None]:
    """Return a binary answer's stats and verification, read from its headers."""
    stats = ClipStats.from_dict(json.loads(headers["x-rnsca-stats"]))
    verified = headers.get("x-rnsca-verification")
    return stats, None if verified is None else Verification.from_dict(json.loads(verified))


def _read_geoarrow(response: httpx.Response) -> GeoArrowResult:
    headers = response.headers
    try:
        rows = int(headers["x-rnsca-rows"])
        stats, verification = _stats_and_verification(headers)
    except (KeyError, ValueError, TypeError) as exc:
        raise ResponseFormatError(
            f"the GeoArrow answer lacks a readable header ({exc})") from None
    return GeoArrowResult(response.content, rows, stats, verification)


def _read_binary_segments(response: httpx.Response) -> SegmentsResult:
    """Return the pieces of a binary answer: rows of 4 float64, int64 sources, t rows of 2."""
    import numpy as np

    headers = response.headers
    try:
        count = int(headers["x-rnsca-pieces"])
        stats, verification = _stats_and_verification(headers)
        method, mode, backend = (headers["x-rnsca-method"], headers["x-rnsca-mode"],
                                 headers["x-rnsca-backend"])
    except (KeyError, ValueError, TypeError) as exc:
        raise ResponseFormatError(
            f"the binary segments answer lacks a readable header ({exc})") from None
    body = response.content
    if len(body) != 56 * count:
        raise ResponseFormatError(
            f"the binary segments answer has {len(body)} bytes, not 56 x {count} pieces")
    segments = np.frombuffer(body, "<f8", 4 * count, 0).reshape(count, 4)
    source = np.frombuffer(body, "<i8", count, 32 * count)
    t = np.frombuffer(body, "<f8", 2 * count, 40 * count).reshape(count, 2)
    return SegmentsResult(segments, source, t, stats, verification, method, mode, backend)


#: The media types of the tiles endpoints' answers.
MVT = "application/vnd.mapbox-vector-tile"
PMTILES = "application/vnd.pmtiles"
#: Options the tiles endpoints take as query parameters (``minzoom``, ``maxzoom``: the
#: archive only).
TILE_OPTIONS = ("extent", "buffer", "layer", "mode", "crs")


def _tile_query(options: Mapping[str, Any], accepted: tuple[str, ...],
                endpoint: str) -> dict[str, str]:
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise InvalidInputError(
            f"unknown option(s) {', '.join(unknown)} for {endpoint}; accepted: "
            f"{', '.join(accepted)}")
    return {name: str(value) for name, value in _options(options).items()}


def _whole(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise InvalidInputError(f"{name} must be a whole number >= 0, got {value!r}")
    return value


def _count(response: httpx.Response, header: str) -> int:
    try:
        return int(response.headers[header])
    except (KeyError, ValueError) as exc:
        raise ResponseFormatError(
            f"{response.request.url.path} answered without a readable {header} header "
            f"({exc})") from None


def tile(obj: Any, z: int, x: int, y: int, *,
         options: Mapping[str, Any]) -> Call[VectorTile]:
    """Return the call ``POST /v1/tiles/{z}/{x}/{y}``: one Mapbox Vector Tile."""
    z, x, y = _whole(z, "z"), _whole(x, "x"), _whole(y, "y")

    def read(response: httpx.Response) -> VectorTile:
        data = b"" if response.status_code == 204 else response.content
        return VectorTile(data, z, x, y, _count(response, "x-rnsca-features"))

    return Call("POST", f"/v1/tiles/{z}/{x}/{y}", read,
                content=encode_json(geojson_document(obj)),
                params=_tile_query(options, TILE_OPTIONS, "a tile"),
                headers={"Content-Type": "application/json", "Accept": MVT,
                         **_UNCOMPRESSED})


def tiles(obj: Any, *, minzoom: int | None, maxzoom: int | None,
          options: Mapping[str, Any]) -> Call[TileArchive]:
    """Return the call ``POST /v1/tiles``: a PMTiles archive of zooms minzoom..maxzoom."""
    params = _tile_query(options, TILE_OPTIONS, "tiles")
    for name, value in (("minzoom", minzoom), ("maxzoom", maxzoom)):
        if value is not None:
            params[name] = str(_whole(value, name))

    def read(response: httpx.Response) -> TileArchive:
        return TileArchive(response.content, _count(response, "x-rnsca-tiles"),
                           _count(response, "x-rnsca-features"))

    return Call("POST", "/v1/tiles", read, content=encode_json(geojson_document(obj)),
                params=params, headers={"Content-Type": "application/json",
                                        "Accept": PMTILES, **_UNCOMPRESSED})


def capabilities() -> Call[Capabilities]:
    """Return the call ``GET /v1/capabilities``."""
    return Call("GET", "/v1/capabilities", _reader(Capabilities.from_dict))


def health() -> Call[Health]:
    """Return the call ``GET /healthz`` (liveness)."""
    return Call("GET", "/healthz", _reader(lambda data: Health(data["status"])))


def readiness() -> Call[bool]:
    """Return the call ``GET /readyz``: True once ready, False while warming up (503)."""
    return Call("GET", "/readyz", lambda response: response.status_code == 200,
                retry_unavailable=False, accept=(503,))
