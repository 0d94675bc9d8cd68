"""The conversion layer: request bytes in, library call, response bytes out.

Each public function runs in a worker thread (`service.runner.ClipRunner`): it validates
the request body with its pydantic model (so parsing a large body does not hold the event
loop either), checks the limits (`service.budget`), calls the library, optionally verifies
the result against Shapely, and serializes the answer with orjson. It knows nothing of
geometry beyond what the library returns.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import orjson
import pyarrow as pa

import rnsca
from rnsca.backends.registry import available_backends, get_backend, opencl_report
from rnsca.clip import SegmentClipResult, as_segments
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    LimitExceededError,
    RnscaError,
)
from rnsca.io.geoarrow import find_geometry_column, read_geoarrow, write_geoarrow
from rnsca.io.geojson_seq import Framing, record_bytes
from rnsca.many_windows import as_windows
from rnsca.options import Mode
from rnsca.stats import ClipStats
from rnsca.verify import Verification
from rnsca.window import Window
from service.budget import (
    check_vertices,
    check_work,
    geometry_vertex_cap,
    segment_work,
    subdivision_cost,
)
from service.config import Settings
from service.errors import (
    InvalidBodyError,
    ServiceError,
    TooManyVerticesError,
    WorkOverBudgetError,
)
from service.schemas import (
    BackendName,
    ClipGeoJSONRequest,
    ClipOptions,
    ClipSegmentsRequest,
    ClipSVGRequest,
    GeometryOptions,
)
from service.slices import parse_geojson_request

__all__ = ["Outcome", "ChunkOutcome", "clip_geojson", "clip_records", "clip_svg",
           "clip_segments_json", "clip_segments_binary", "clip_geoarrow", "warm_up_svg",
           "backend_report", "SEGMENT_BYTES", "ARROW_STREAM"]

#: One binary segment: four little-endian float64.
SEGMENT_BYTES = 32
#: The media type of an Arrow IPC stream (``POST /v1/clip/geoarrow``, in and out).
ARROW_STREAM = "application/vnd.apache.arrow.stream"
_JSON = orjson.OPT_SERIALIZE_NUMPY


@dataclass
class Outcome:
    """A response to send: its body, media type, extra headers, and the clip's stats."""

    content: bytes
    stats: ClipStats | None
    media_type: str = "application/json"
    headers: dict = field(default_factory=dict)


def backend_report() -> list[dict]:
    """Return each backend the API names, whether it is present here, and why not.

    OpenCL also lists every device found (``id`` "platform:device", names, type, fp64),
    the one selected and its precision.
    """
    present = {kind.value for kind in available_backends()}
    report = []
    for name in BackendName:
        if name is BackendName.AUTO:  # a choice between the others, not a backend
            continue
        entry = {"name": name.value, "available": name.value in present}
        if name.value in present:
            # What it runs: the same capability query the library checks each call with.
            capabilities = get_backend(name.value).capabilities.to_dict()
            entry["devices"] = capabilities.pop("devices")
            entry.update({k: v for k, v in capabilities.items() if k != "backend"})
        if name is BackendName.OPENCL:
            opencl = opencl_report()
            entry["devices"] = opencl["devices"]
            entry["selected"] = opencl["selected"]
            entry["precision"] = opencl["precision"]
            if not opencl["available"]:
                entry["reason"] = opencl["reason"]
        report.append(entry)
    return report


def _library_options(options: ClipOptions, settings: Settings) -> dict:
    """Return the keyword arguments of a library call (the library checks the backend)."""
    backend = options.backend.value if options.backend else settings.default_backend.value
    return dict(method=options.method, n=options.n, max_depth=options.max_depth,
                tolerance=options.tolerance, mode=options.mode, backend=backend,
                resolution=options.resolution)


#: Share of the request's time limit kept, after verification, for writing the answer, at
#: least: orjson writes the answer to a 21 MB GeoJSON body in 0.2 s (measured), and a
#: tenth of the default 30 s leaves room on a busy machine. Verification also leaves as
#: much time as reading and clipping took (`_verify_within_budget`): writing the answer
#: is of their order, and on a loaded machine slower by the same factor.
_ANSWER_SHARE = 0.1


def _verify_wanted(asked: bool | str | None, vertices: int, settings: Settings) -> bool:
    if asked is None:
        return vertices <= settings.verify_max_vertices
    return asked is not False


class _VerificationCost:
    """What verification has cost per input vertex, by endpoint: a running estimate.

    It sizes the sample that keeps a verification within `Settings.verify_cost_ratio` of
    the clip's time. The first values are rough starting guesses (paths cost more: they
    are flattened 100 times finer than the clip); each verification then corrects its
    kind's estimate (exponential average), so a few requests bring it to this machine's.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._seconds_per_vertex = {"segments": 2e-6, "geojson": 4e-6, "geoarrow": 4e-6,
                                    "svg": 2e-5}

    def sample(self, kind: str, asked: bool | str | None, clip_seconds: float, inputs: int,
               vertices: int, ratio: float) -> int | None:
        """Return how many inputs to compare (None: all of them)."""
        if asked == "all" or inputs == 0:
            return None
        with self._lock:
            per_vertex = self._seconds_per_vertex[kind]
        per_input = per_vertex * max(vertices, 1) / inputs
        affordable = int(clip_seconds * ratio / per_input)
        return None if affordable >= inputs else max(1, affordable)

    def observe(self, kind: str, seconds: float, vertices: int) -> None:
        """Fold one verification's cost into its kind's estimate."""
        if vertices <= 0:
            return
        with self._lock:
            old = self._seconds_per_vertex[kind]
            self._seconds_per_vertex[kind] = 0.8 * old + 0.2 * (seconds / vertices)


_COST = _VerificationCost()


def _verify_within_budget(kind: str, asked: bool | str | None, clip_seconds: float,
                          inputs: int, vertices: int, settings: Settings,
                          deadline: float,
                          call: Callable[..., Verification]) -> Verification:
    """Return ``call(sample=, time_limit=, max_crossings=)`` (a `rnsca.verify`).

    On all inputs or the sample the budget allows, stopping in time to write the answer
    before `deadline` (a `time.monotonic` value), and skipping what GEOS would take too
    long to node.
    """
    sample = _COST.sample(kind, asked, clip_seconds, inputs, vertices,
                          settings.verify_cost_ratio)
    left = deadline - time.monotonic()
    spent = settings.request_time_limit - left  # reading and clipping, so far
    time_limit = left - max(_ANSWER_SHARE * settings.request_time_limit, spent)
    started = time.perf_counter()
    verification = call(sample=sample, time_limit=max(time_limit, 0.0),
                        max_crossings=settings.verify_max_crossings)
    _COST.observe(kind, time.perf_counter() - started,
                  vertices * verification.checked // max(inputs, 1))
    return verification


def _due(deadline: float | None, settings: Settings) -> float:
    """Return `deadline`, or for a call without one the request's time limit from now."""
    return time.monotonic() + settings.request_time_limit if deadline is None else deadline


def _dict_or_none(value):
    return None if value is None else value.to_dict()


# --- GeoJSON -------------------------------------------------------------------------


def clip_geojson(body: bytes, settings: Settings, deadline: float | None = None) -> Outcome:
    """Answer ``POST /v1/clip/geojson`` by `deadline` (`time.monotonic`; see `clip_svg`)."""
    deadline = _due(deadline, settings)
    request = parse_geojson_request(body)  # a large body a slice of features at a time
    if request.windows is not None:
        return _clip_geojson_windows(request, settings, deadline)
    assert request.window is not None
    window = Window(*request.window)
    options = request.options
    arguments = _library_options(options, settings)
    cap, by_budget = geometry_vertex_cap(options, window, settings.max_vertices,
                                         settings.work_budget)
    started = time.perf_counter()
    try:
        result = rnsca.clip_geojson(
            request.geojson, window, keep_empty=options.keep_empty, max_vertices=cap,
            arrays=True, boundary=options.boundary, check_validity=options.check_validity,
            **arguments)
    except LimitExceededError as exc:
        raise _over_vertex_cap(str(exc), options, window, cap, by_budget, settings) from None
    except InvalidGeometryError as exc:
        path = getattr(exc, "path", None)
        if path is not None:  # a JSON path inside the document: make it one in the body
            exc.path = "geojson" + (path if not path or path.startswith("[") else "." + path)
        raise
    clip_seconds = time.perf_counter() - started
    clipped, stats = result
    verification = None
    approx_unbounded = options.mode is Mode.APPROX and request.approx_bound is None
    if _verify_wanted(request.verify, stats.vertices_in, settings) and not (
            request.verify is None and approx_unbounded):
        # The result holds the arrays clipped and their clips, one for one: nothing is
        # read again.
        # Geometries read, of every kind: the last offsets count them (points: rows).
        inputs = sum(len(offsets[-1]) - 1 if offsets else len(coords)
                     for _, coords, offsets in result.inputs.values())
        verification = _verify_within_budget(
            "geojson", request.verify, clip_seconds, inputs, stats.vertices_in, settings,
            deadline,
            lambda **limits: rnsca.verify(None, result, window, mode=options.mode,
                                          approx_bound=request.approx_bound,
                                          boundary=options.boundary, **limits))
    payload = {"geojson": clipped, "stats": stats.to_dict(),
               "verification": _dict_or_none(verification)}
    return Outcome(orjson.dumps(payload, option=_JSON), stats)


def _windows_vertex_cap(options: ClipOptions, windows: list, settings: Settings,
                        ) -> tuple[Window, int, bool]:
    """Return the smallest window, the vertex cap and whether the budget set it.

    Every vertex is charged once per window (`geometry_vertex_cap` of the budget shared
    out among the windows); invalid windows are refused (`InvalidWindowError`, naming
    the row).
    """
    table = as_windows(windows)
    area = (table[:, 2] - table[:, 0]) * (table[:, 3] - table[:, 1])
    smallest = Window(*table[int(np.argmin(area))].tolist())
    cap, by_budget = geometry_vertex_cap(options, smallest, settings.max_vertices,
                                         settings.work_budget // table.shape[0])
    return smallest, cap, by_budget


def _clip_geojson_windows(request: ClipGeoJSONRequest, settings: Settings,
                          deadline: float) -> Outcome:
    """Answer ``POST /v1/clip/geojson`` with `windows`: one document per window.

    Verified as one window is, every (geometry, window) pair whose boxes touch counted
    as one input.
    """
    options = request.options
    assert request.windows is not None
    smallest, cap, by_budget = _windows_vertex_cap(options, request.windows, settings)
    started = time.perf_counter()
    try:
        result = rnsca.clip_geojson_windows(
            request.geojson, request.windows, keep_empty=options.keep_empty,
            max_vertices=cap, arrays=True, boundary=options.boundary,
            check_validity=options.check_validity, **_library_options(options, settings))
    except LimitExceededError as exc:
        raise _over_vertex_cap(f"{exc} ({len(request.windows)} windows: each vertex counts "
                               "once per window)", options, smallest, cap, by_budget,
                               settings) from None
    except InvalidGeometryError as exc:
        path = getattr(exc, "path", None)
        if path is not None:
            exc.path = "geojson" + (path if not path or path.startswith("[") else "." + path)
        raise
    clip_seconds = time.perf_counter() - started
    stats = result.stats
    verification = None
    windows = request.windows
    approx_unbounded = options.mode is Mode.APPROX and request.approx_bound is None
    if _verify_wanted(request.verify, stats.vertices_in, settings) and not (
            request.verify is None and approx_unbounded):
        verification = _verify_within_budget(
            "geojson", request.verify, clip_seconds, stats.geometries_in, stats.vertices_in,
            settings, deadline,
            lambda **limits: rnsca.verify(None, result, windows, mode=options.mode,
                                          approx_bound=request.approx_bound,
                                          boundary=options.boundary, **limits))
    payload = {"geojson": result.documents, "stats": stats.to_dict(),
               "verification": _dict_or_none(verification)}
    return Outcome(orjson.dumps(payload, option=_JSON), stats)


def _over_vertex_cap(what: str, options: GeometryOptions, window: Window, cap: int,
                     by_budget: bool, settings: Settings) -> ServiceError:
    """Return the error of geometry over `cap` vertices (`geometry_vertex_cap`)."""
    if by_budget:
        per_vertex = 1 + subdivision_cost(options, window, None)
        return WorkOverBudgetError(
            f"{what}: with these options a vertex may cost up to {per_vertex} fragments, "
            f"so the work budget of {settings.work_budget} allows {cap} vertices; lower "
            "options.max_depth or options.n, or use exact mode with no tolerance",
            budget=settings.work_budget)
    return TooManyVerticesError(f"{what} (this server's max_vertices)", limit=cap)


# --- GeoJSON text sequences ----------------------------------------------------------


@dataclass
class ChunkOutcome:
    """One clipped chunk of a streamed request: its answer's records, framed, and stats."""

    content: bytes
    stats: ClipStats
    records_out: int


def clip_records(records: list[bytes], first: int, window: Window, options: GeometryOptions,
                 framing: Framing, settings: Settings) -> ChunkOutcome:
    """Clip one chunk of ``POST /v1/clip/geojson-seq``: record texts in, framed records out.

    `first` is the number of ``records[0]`` in the stream. The limits (``max_vertices``,
    the work budget) apply to each chunk; errors name the record at fault (`record`).
    """
    cap, by_budget = geometry_vertex_cap(options, window, settings.max_vertices,
                                         settings.work_budget)
    try:
        result = rnsca.clip_records(
            records, window, first=first, keep_empty=options.keep_empty, max_vertices=cap,
            arrays=True, boundary=options.boundary, check_validity=options.check_validity,
            **_library_options(options, settings))
    except LimitExceededError as exc:
        span = f"the chunk of records {first} to {first + len(records) - 1}"
        raise _over_vertex_cap(f"{span}: {exc}", options, window, cap, by_budget,
                               settings) from None
    content = b"".join([record_bytes(record, framing) for record in result.records])
    return ChunkOutcome(content, result.stats, len(result.records))


# --- GeoArrow ------------------------------------------------------------------------


def _read_arrow_stream(body: bytes) -> pa.Table:
    """Return the table an Arrow IPC stream holds, its buffers checked against its offsets."""
    try:
        # Zero-copy: the columns are views of `body` (read-only; the reader copies the
        # coordinates the kernels need once, `rnsca.io.geoarrow._numbers`).
        table = pa.ipc.open_stream(pa.py_buffer(body)).read_all()
        # Offsets past their child, decreasing or out of range would be read as they
        # are by the clip: a full validation refuses them here.
        table.validate(full=True)
        _check_names(table.schema)
    except (pa.ArrowException, OSError, UnicodeDecodeError) as exc:
        # A truncated buffer is an OSError; a field name that is not UTF-8 (which
        # the format requires) a UnicodeDecodeError when pyarrow decodes it.
        raise InvalidBodyError(f"the body is not a valid Arrow IPC stream ({exc}); send "
                               f"{ARROW_STREAM}, e.g. from pyarrow.ipc.new_stream") from None
    return table


def _check_names(fields: pa.Schema | pa.DataType) -> None:
    """Decode every field name, nested ones included (pyarrow decodes them lazily)."""
    for i in range(len(fields) if isinstance(fields, pa.Schema) else fields.num_fields):
        field = fields.field(i)
        _ = field.name
        _check_names(field.type)


def _arrow_stream(table: pa.Table) -> bytes:
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as writer:
        writer.write_table(table)
    return sink.getvalue().to_pybytes()


def clip_geoarrow(body: bytes, window: Window, options: GeometryOptions, column: str | None,
                  verify: bool | str | None, settings: Settings,
                  deadline: float | None = None) -> Outcome:
    """Answer ``POST /v1/clip/geoarrow``: an Arrow IPC stream in and out.

    The geometry column (`rnsca.io.geoarrow.find_geometry_column`, or `column`) is read
    into ragged arrays, clipped, and written back in its encoding; the other columns are
    kept as they are. A row whose geometry is clipped away, is empty or null is dropped
    unless ``options.keep_empty`` (then it holds an empty geometry, or stays null), as
    the GeoJSON endpoint drops features. The headers ``X-Rnsca-Stats`` and
    ``X-Rnsca-Verification`` carry the stats and the verification as JSON, ``X-Rnsca-Rows``
    the number of rows. Answered by `deadline` (see `clip_svg`).
    """
    deadline = _due(deadline, settings)
    table = _read_arrow_stream(body)
    index = find_geometry_column(table.schema, column)
    field = table.schema.field(index)
    read = read_geoarrow(table.column(index), field)
    vertices = read.coords.shape[0]
    cap, by_budget = geometry_vertex_cap(options, window, settings.max_vertices,
                                         settings.work_budget)
    if vertices > cap:
        if by_budget:
            raise WorkOverBudgetError(
                f"{vertices} vertices: with these options a vertex may cost up to "
                f"{1 + subdivision_cost(options, window, None)} fragments, so the work "
                f"budget of {settings.work_budget} allows {cap}; lower max_depth or n, or "
                "use exact mode with no tolerance", budget=settings.work_budget)
        raise TooManyVerticesError(f"{vertices} vertices, more than this server's "
                                   f"max_vertices of {cap}", limit=cap)
    arguments = _library_options(options, settings)
    started = time.perf_counter()
    try:
        result = rnsca.clip_ragged(
            read.kind, read.coords, read.offsets, window, keep_empty=options.keep_empty,
            boundary=options.boundary, check_validity=options.check_validity,
            partial_z=read.partial_z, **arguments)
    except InvalidGeometryError as exc:
        if exc.geometry is None:
            raise
        # The library counts the geometries read; the caller knows rows.
        row = int(read.rows[exc.geometry])
        error = InvalidGeometryError(f"column {field.name!r}, row {row}: "
                                     f"{exc.detail or exc}")
        error.path = f"{field.name}[{row}]"
        raise error from None
    clip_seconds = time.perf_counter() - started
    verification = None
    if _verify_wanted(verify, vertices, settings) and options.mode is not Mode.APPROX:
        geometries = len(read.rows)
        verification = _verify_within_budget(
            "geoarrow", verify, clip_seconds, geometries, vertices, settings, deadline,
            lambda **limits: rnsca.verify((read.kind.shapely_type, read.coords, read.offsets),
                                          result, window, boundary=options.boundary,
                                          **limits))
    array, out_field = write_geoarrow(read, result.geometry_type, result.coords,
                                      result.offsets, result.source)
    table = table.set_column(index, out_field, array)
    if not options.keep_empty:
        table = table.take(pa.array(read.rows[result.source]))
    headers = {"X-Rnsca-Rows": str(table.num_rows),
               "X-Rnsca-Stats": orjson.dumps(result.stats.to_dict()).decode()}
    if verification is not None:
        headers["X-Rnsca-Verification"] = orjson.dumps(verification.to_dict()).decode()
    return Outcome(_arrow_stream(table), result.stats, ARROW_STREAM, headers)


# --- Segments ------------------------------------------------------------------------


def _clip_segments(array: np.ndarray, window: Window, options: ClipOptions,
                   verify: bool | str | None, settings: Settings, deadline: float,
                   ) -> tuple[SegmentClipResult, Verification | None]:
    check_vertices(2 * array.shape[0], settings.max_vertices)
    arguments = _library_options(options, settings)
    segments = as_segments(array)
    check_work(segment_work(segments, window, options), settings.work_budget)
    started = time.perf_counter()
    result = rnsca.clip_segments(segments, window, **arguments)
    clip_seconds = time.perf_counter() - started
    verification = None
    n = segments.shape[0]
    if _verify_wanted(verify, 2 * n, settings):
        verification = _verify_within_budget(
            "segments", verify, clip_seconds, n, 2 * n, settings, deadline,
            lambda **limits: rnsca.verify(segments, result, window, **limits))
    return result, verification


def clip_segments_json(body: bytes, settings: Settings,
                       deadline: float | None = None) -> Outcome:
    """Answer ``POST /v1/clip/segments`` with a JSON body, by `deadline` (see `clip_svg`)."""
    deadline = _due(deadline, settings)
    request = ClipSegmentsRequest.model_validate_json(body)
    window = Window(*request.window)
    array = np.array(request.segments, dtype=np.float64).reshape(-1, 4)
    try:
        result, verification = _clip_segments(array, window, request.options,
                                               request.verify, settings, deadline)
    except InvalidGeometryError as exc:
        if getattr(exc, "row", None) is not None:
            exc.path = f"segments[{exc.row}]"
        raise
    payload = {"segments": result.segments, "source": result.source, "t": result.t,
               "stats": result.stats.to_dict(), "verification": _dict_or_none(verification),
               "method": result.method.value, "mode": result.mode.value,
               "backend": result.backend.value}
    return Outcome(orjson.dumps(payload, option=_JSON), result.stats)


def clip_segments_binary(body: bytes, window: Window, options: ClipOptions,
                         verify: bool | str | None, settings: Settings,
                         deadline: float | None = None) -> Outcome:
    """Answer ``POST /v1/clip/segments`` with an ``application/octet-stream`` body.

    In: little-endian float64 rows ``x0, y0, x1, y1``. Out: the pieces as float64 rows
    of 4, then their source indices as int64, then their parameter intervals as float64
    rows of 2, all little-endian; the header ``X-Rnsca-Pieces`` gives the number m of
    pieces (so the parts are 32 m, 8 m and 16 m bytes), ``X-Rnsca-Stats`` and
    ``X-Rnsca-Verification`` carry the stats and the verification as JSON. Answered by
    `deadline` (see `clip_svg`).
    """
    if len(body) % SEGMENT_BYTES:
        raise InvalidBodyError(
            f"the body has {len(body)} bytes, not a multiple of {SEGMENT_BYTES}: send "
            "segments as rows of four little-endian float64 (x0, y0, x1, y1)")
    # A writable copy: a read-only array would make Numba compile another specialization.
    array = np.frombuffer(bytearray(body), dtype="<f8").reshape(-1, 4)
    result, verification = _clip_segments(array, window, options, verify, settings,
                                           _due(deadline, settings))
    content = b"".join((result.segments.astype("<f8", copy=False).tobytes(),
                        result.source.astype("<i8", copy=False).tobytes(),
                        result.t.astype("<f8", copy=False).tobytes()))
    headers = {
        "X-Rnsca-Pieces": str(len(result)),
        "X-Rnsca-Layout": "segments:<f8[m,4];source:<i8[m];t:<f8[m,2]",
        "X-Rnsca-Stats": orjson.dumps(result.stats.to_dict()).decode(),
        "X-Rnsca-Method": result.method.value,
        "X-Rnsca-Mode": result.mode.value,
        "X-Rnsca-Backend": result.backend.value,
    }
    if verification is not None:
        headers["X-Rnsca-Verification"] = orjson.dumps(verification.to_dict()).decode()
    return Outcome(content, result.stats, "application/octet-stream", headers)


# --- SVG -----------------------------------------------------------------------------

def warm_up_svg() -> None:
    """Compile the SVG path kernels (the backends' warm-up covers segments and geometry).

    Clips a few small paths, and enough of them to take the parallel drivers too, in each
    curve handling and fill rule; a combination the library refuses is skipped.
    """
    paths = ["M -1 0.5 C 0 2 1 -1 2 0.5 Q 0.5 3 -1 0.5 Z", "M -1 0.25 L 2 0.25 L 2 0.75 Z",
             "M 0.2 0.2 A 0.3 0.3 0 0 1 0.8 0.8"]
    # Flattening many paths is slow in itself (arcs at the default tolerance): large
    # batches warm the parallel drivers with curves kept only.
    calls = [(1, curves, fill, mode) for curves in ("preserve", "flatten")
             for fill in (None, "nonzero", "evenodd") for mode in (Mode.EXACT, Mode.APPROX)]
    calls += [(2000, "preserve", fill, Mode.EXACT) for fill in (None, "nonzero", "evenodd")]
    for count, curves, fill, mode in calls:
        try:
            rnsca.clip_svg(paths * count, (0.0, 0.0, 1.0, 1.0), curves=curves, fill=fill,
                           mode=mode)
        except RnscaError:
            continue  # e.g. approx mode with a fill rule: refused, not needed


def clip_svg(body: bytes, settings: Settings, deadline: float | None = None) -> Outcome:
    """Answer ``POST /v1/clip/svg``: parse once, budget, clip, write, verify the arrays.

    `deadline` is when the answer is due (a `time.monotonic` value; None: the request's
    time limit from the call): verification stops in time to write it.
    """
    deadline = _due(deadline, settings)
    request = ClipSVGRequest.model_validate_json(body)
    if request.windows is not None:
        return _clip_svg_windows(request, settings, deadline)
    assert request.window is not None
    window = Window(*request.window)
    arguments = _library_options(request.options, settings)
    options = request.options
    # The path text is read once (the body limit bounds the time that takes); the
    # budget counts the control points read, verification compares the arrays.
    try:
        paths = rnsca.parse_paths(request.paths, tolerance=arguments["tolerance"])
        vertices = int(paths.degree.sum()) + paths.closed.shape[0]
        check_vertices(vertices, settings.max_vertices)
        check_work(vertices * (1 + subdivision_cost(options, window, None)),
                   settings.work_budget)
        started = time.perf_counter()
        result = rnsca.clip_paths(paths, window, curves=options.curves, fill=options.fill,
                                  fill_output=options.fill_output, **arguments)
        clip_seconds = time.perf_counter() - started
    except RnscaError as exc:
        if getattr(exc, "path_index", None) is not None:  # `position` is within that path
            exc.path = f"paths[{exc.path_index}]"
        raise
    written = rnsca.write_paths(result.paths, precision=None)  # exact, as clip_svg writes
    verification = None
    # Approx mode has no bound to judge against unless one is set: not verified by default.
    if (request.paths and Mode(options.mode) is not Mode.APPROX
            and _verify_wanted(request.verify, vertices, settings)):
        # A flattened clip strays from the curves by its own tolerance: compare at it.
        tolerance = arguments.get("tolerance") if options.curves == "flatten" else None
        verification = _verify_within_budget(
            "svg", request.verify, clip_seconds, len(paths), vertices, settings, deadline,
            lambda **limits: rnsca.verify(paths, result, window, tolerance=tolerance,
                                          **limits))
    payload = {"paths": written, "stats": result.stats.to_dict(),
               "verification": _dict_or_none(verification)}
    return Outcome(orjson.dumps(payload, option=_JSON), result.stats)


def _clip_svg_windows(request: ClipSVGRequest, settings: Settings, deadline: float) -> Outcome:
    """Answer ``POST /v1/clip/svg`` with `windows`: the paths clipped to each window.

    The path text is read once and clipped against every window in one library call
    (`rnsca.clip_paths` with ``windows=``); the work budget charges every control point
    once per window. Verified as one window is, every (path, window) pair whose boxes
    touch counted as one input.
    """
    assert request.windows is not None
    options = request.options
    arguments = _library_options(options, settings)
    table = as_windows(request.windows)
    try:
        paths = rnsca.parse_paths(request.paths, tolerance=arguments["tolerance"])
        vertices = int(paths.degree.sum()) + paths.closed.shape[0]
        check_vertices(vertices, settings.max_vertices)
        check_work(vertices * sum(1 + subdivision_cost(options, Window(*row), None)
                                  for row in table.tolist()), settings.work_budget)
        started = time.perf_counter()
        result = rnsca.clip_paths(paths, windows=table, curves=options.curves,
                                  fill=options.fill, fill_output=options.fill_output,
                                  **arguments)
        clip_seconds = time.perf_counter() - started
    except RnscaError as exc:
        if getattr(exc, "path_index", None) is not None:
            exc.path = f"paths[{exc.path_index}]"
        raise
    assert result.window_offsets is not None and result.source is not None
    written = rnsca.write_paths(result.paths, precision=None)
    per_window = []
    for w in range(table.shape[0]):
        # One string per input path, "" where nothing of it is in the window.
        strings = [""] * len(paths)
        for j in range(int(result.window_offsets[w]), int(result.window_offsets[w + 1])):
            strings[int(result.source[j])] = written[j]
        per_window.append(strings)
    verification = None
    stats = result.stats
    if (request.paths and Mode(options.mode) is not Mode.APPROX
            and _verify_wanted(request.verify, stats.vertices_in, settings)):
        tolerance = arguments.get("tolerance") if options.curves == "flatten" else None
        verification = _verify_within_budget(
            "svg", request.verify, clip_seconds, stats.geometries_in, stats.vertices_in,
            settings, deadline,
            lambda **limits: rnsca.verify(paths, result, table, tolerance=tolerance,
                                          **limits))
    payload = {"paths": per_window, "stats": stats.to_dict(),
               "verification": _dict_or_none(verification)}
    return Outcome(orjson.dumps(payload, option=_JSON), stats)


# --- Vector tiles ---------------------------------------------------------------------


def _tile_features(body: bytes, options: Any, zooms: int, settings: Settings) -> Any:
    """Return the `FeatureTable` of a GeoJSON body, within the vertex limit and budget.

    The work budget counts every vertex once per zoom cut.
    """
    from rnsca.tiles import Crs
    from rnsca.tiles.sources import features_of_geojson_text

    features = features_of_geojson_text(body)
    table = features.table(Crs(options.crs))
    vertices = sum(r.coords.shape[0] for r in (table.points, table.lines, table.polygons))
    check_vertices(vertices, settings.max_vertices)
    check_work(vertices * zooms, settings.work_budget)
    return table


def tile_one(body: bytes, z: int, x: int, y: int, options: Any,
             settings: Settings) -> Outcome:
    """Answer ``POST /v1/tiles/{z}/{x}/{y}``: the tile's bytes (empty: no feature)."""
    from rnsca.tiles import tile_one as one

    table = _tile_features(body, options, 1, settings)
    data = one(table, z, x, y, extent=options.extent, buffer=options.buffer,
               layer=options.layer, mode=options.mode)
    return Outcome(data or b"", None, "application/vnd.mapbox-vector-tile",
                   {"X-Rnsca-Features": str(table.count)})


def tile_pyramid(body: bytes, options: Any, settings: Settings) -> Outcome:
    """Answer ``POST /v1/tiles``: a PMTiles archive of zooms minzoom..maxzoom."""
    import io

    from rnsca.tiles import tile_table, write_pmtiles

    if options.minzoom > options.maxzoom:
        raise InvalidOptionError(f"minzoom {options.minzoom} is above maxzoom "
                                 f"{options.maxzoom}")
    table = _tile_features(body, options, options.maxzoom + 1, settings)
    zooms = tile_table(table, minzoom=options.minzoom, maxzoom=options.maxzoom,
                       extent=options.extent, buffer=options.buffer, layer=options.layer,
                       mode=options.mode, max_tiles=settings.max_tiles)
    archive = io.BytesIO()
    try:
        summary = write_pmtiles(archive, zooms, layer=options.layer)
    except ValueError as exc:  # no tile holds a feature
        raise InvalidBodyError(f"{exc}") from None
    return Outcome(archive.getvalue(), None, "application/vnd.pmtiles",
                   {"X-Rnsca-Tiles": str(summary.tiles),
                    "X-Rnsca-Features": str(table.count)})
