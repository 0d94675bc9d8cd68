"""`Client` and `AsyncClient`: the API's calls over one pooled httpx connection each."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterable, AsyncIterator, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from typing import Any, TypeVar

import httpx

from rnsca_client import calls, clipping
from rnsca_client.clipping import DEFAULT_BATCH_SIZE
from rnsca_client.errors import (
    ApiError,
    ConnectError,
    InvalidInputError,
    RequestTimeoutError,
    RnscaClientError,
    ServiceUnavailableError,
    TransportError,
    api_error,
    retry_after_seconds,
)
from rnsca_client.results import (
    Capabilities,
    ClipResult,
    GeoArrowResult,
    GeoJSONResult,
    GeoJSONWindowsResult,
    Health,
    SegmentsResult,
    SVGResult,
    SVGWindowsResult,
    TileArchive,
    VectorTile,
)
from rnsca_client.retry import Retry
from rnsca_client.streams import (
    NDJSON,
    SEQ_OPTIONS,
    SEQ_PATH,
    AsyncClippedRecords,
    ClippedRecords,
    async_record_pieces,
    record_pieces,
)

__all__ = ["Client", "AsyncClient", "DEFAULT_TIMEOUT", "DEFAULT_URL", "DEFAULT_RETRY",
           "DEFAULT_CONCURRENCY"]

T = TypeVar("T")
DEFAULT_URL = "http://127.0.0.1:8000"
#: Reads wait longer than the server's default request time limit (30 s), so a busy
#: server answers 503 (retried) before the client gives up on its own.
DEFAULT_TIMEOUT = httpx.Timeout(60.0, connect=5.0)
#: Up to 4 tries, waiting about 0.25, 0.5 and 1 s (or what ``Retry-After`` says).
DEFAULT_RETRY = Retry()
#: Requests of ``clip_many`` in flight at once.
DEFAULT_CONCURRENCY = 4


def _check_concurrency(concurrency: int) -> int:
    if isinstance(concurrency, bool) or not isinstance(concurrency, int) or concurrency < 1:
        raise InvalidInputError(f"concurrency must be a whole number >= 1, got "
                                f"{concurrency!r}")
    return concurrency


def _transport_error(exc: httpx.TransportError, attempts: int) -> TransportError:
    """Return the SDK's exception for an httpx network failure."""
    tries = f"{attempts} attempt{'s' if attempts > 1 else ''}"
    message = f"{type(exc).__name__}: {exc or 'no detail'} (after {tries})"
    if isinstance(exc, (httpx.ConnectError, httpx.ConnectTimeout)):
        return ConnectError(f"could not connect to the rnsca server: {message}",
                            attempts=attempts)
    if isinstance(exc, httpx.TimeoutException):
        return RequestTimeoutError(f"the rnsca server did not answer in time: {message}",
                                   attempts=attempts)
    return TransportError(f"the request to the rnsca server failed: {message}",
                          attempts=attempts)


def _wait_before_retry(retry: Retry, call: calls.Call, attempt: int, *,
                       response: httpx.Response | None = None,
                       failure: httpx.TransportError | None = None) -> float | None:
    """Return the seconds to wait before trying `call` again, or None not to retry."""
    if attempt >= retry.attempts:
        return None
    if failure is not None:
        connect_failed = isinstance(failure, (httpx.ConnectError, httpx.ConnectTimeout))
        return retry.delay(attempt) if connect_failed else None
    if response is not None and response.status_code == 503 and call.retry_unavailable:
        return retry.delay(attempt, retry_after_seconds(response))
    return None


def _finish(call: calls.Call[T], response: httpx.Response, attempts: int) -> T:
    try:
        return call.finish(response)
    except ApiError as error:
        error.attempts = attempts
        raise


def _assemble(plan: Any, finished: dict[Any, Any]) -> Any:
    """Return the plan's result from its batches' finished futures or tasks.

    `finished` maps each `concurrent.futures.Future` or `asyncio.Task` (both have
    ``cancelled``, ``exception`` and ``result``) to its batch; cancelled ones (after a
    failure) are left out. Raises the plan's failure naming every batch that failed, or
    an error that is not the client's as it is.
    """
    failures: dict[int, RnscaClientError] = {}
    pieces = {}
    for future, batch in finished.items():
        if future.cancelled():
            continue
        error = future.exception()
        if error is None:
            pieces[batch.number] = future.result()
        elif isinstance(error, RnscaClientError):
            failures[batch.number] = error
        else:
            raise error
    if failures:
        raise plan.failure(failures)
    return plan.assemble(pieces)


class _Options:
    """What both clients keep: the retry policy and how to make the httpx client."""

    def __init__(self, base_url: str, timeout: float | httpx.Timeout,
                 retries: Retry | int | None, headers: dict[str, str] | None) -> None:
        from rnsca_client import __version__

        self.retry = Retry.of(retries)
        self.http_options: dict[str, Any] = dict(
            base_url=base_url, timeout=timeout,
            headers={"User-Agent": f"rnsca-client/{__version__}", **(headers or {})})


class Client:
    """A synchronous client of the rnsca HTTP API.

    One pooled connection is reused across calls; use it as a context manager, or call
    `close`, to release it.

    Parameters
    ----------
    base_url : str
        The service's root, e.g. ``http://127.0.0.1:8000``.
    timeout : float or httpx.Timeout
        Seconds to wait; default 5 s to connect and 60 s for the rest.
    retries : Retry, int or None
        A `Retry` policy, or the number of retries after the first try (None: none).
        Failures to connect and 503 answers are retried with exponential backoff,
        honouring ``Retry-After`` up to the policy's bound.
    headers : dict, optional
        Extra headers of every request (an API gateway's key, say).
    http_client : httpx.Client, optional
        Send through this client instead (e.g. a ``fastapi.testclient.TestClient``);
        its own base URL, timeout and headers apply, and `close` leaves it open.
    transport : httpx.BaseTransport, optional
        The transport of the httpx client made here (e.g. ``httpx.MockTransport``).

    Examples
    --------
    With a server on the default address (``make serve``)::

        with Client("http://127.0.0.1:8000") as client:
            result = client.clip_geojson(
                {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}, (0, 0, 10, 10))
        result.geojson   # {'type': 'LineString', 'coordinates': [[0.0, 5.0], [10.0, 5.0]]}
    """

    def __init__(self, base_url: str = DEFAULT_URL, *, timeout: float | httpx.Timeout =
                 DEFAULT_TIMEOUT, retries: Retry | int | None = DEFAULT_RETRY,
                 headers: dict[str, str] | None = None,
                 http_client: httpx.Client | None = None,
                 transport: httpx.BaseTransport | None = None) -> None:
        options = _Options(base_url, timeout, retries, headers)
        self.retry = options.retry
        self._owned = http_client is None
        self._http = http_client or httpx.Client(transport=transport, **options.http_options)

    @property
    def base_url(self) -> httpx.URL:
        """The service's root URL."""
        return self._http.base_url

    def close(self) -> None:
        """Close the connection pool (not an `http_client` passed in)."""
        if self._owned:
            self._http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def send(self, call: calls.Call[T]) -> T:
        """Return the result of `call`, retrying as the policy says."""
        attempt = 0
        while True:
            attempt += 1
            try:
                response = self._http.request(call.method, call.path, content=call.content,
                                              params=call.params, headers=call.headers)
            except httpx.TransportError as failure:
                wait = _wait_before_retry(self.retry, call, attempt, failure=failure)
                if wait is None:
                    raise _transport_error(failure, attempt) from failure
            else:
                wait = _wait_before_retry(self.retry, call, attempt, response=response)
                if wait is None:
                    return _finish(call, response, attempt)
            time.sleep(wait)

    def clip_geojson(self, obj: Any, window: Any, *, verify: bool | str | None = None,
                     approx_bound: float | None = None, **options: Any) -> GeoJSONResult:
        """Return a GeoJSON Geometry, Feature or FeatureCollection clipped to `window`.

        Parameters
        ----------
        obj : dict, str or geometry
            GeoJSON (a dict or its text), or an object with ``__geo_interface__`` such
            as a Shapely geometry.
        window : sequence of 4 float, or an object with ``bounds``
            ``[xmin, ymin, xmax, ymax]``.
        verify : bool or "all", optional
            Compare with Shapely on the server (default: the server decides by size):
            within its verification budget (a random sample past it; the answer's
            verification says how many were checked), or ``"all"`` for every input
            the request's time limit allows (``timed_out`` says it stopped).
        approx_bound : float, optional
            In approx mode, the largest deviation that passes verification.
        **options
            ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``, ``backend``,
            ``boundary``, ``keep_empty``, ``check_validity`` (None: server default).

        Returns
        -------
        GeoJSONResult
            ``geojson`` (dict; ``to_shapely()`` for Shapely), ``stats``, ``verification``.

        Raises
        ------
        InvalidRequestError
            422 with `path` naming the offending value; see `ApiError` for the rest.
        """
        return self.send(calls.clip_geojson(obj, window, verify=verify,
                                            approx_bound=approx_bound, options=options))

    def clip_geojson_windows(self, obj: Any, windows: Any, *,
                             verify: bool | str | None = None,
                             approx_bound: float | None = None,
                             **options: Any) -> GeoJSONWindowsResult:
        """Return a GeoJSON document clipped to each of many windows, in one request.

        Parameters
        ----------
        obj : dict, str or geometry
            As for `clip_geojson`.
        windows : sequence of [xmin, ymin, xmax, ymax], or an (k, 4) array
            The windows; the server clips the document against all of them in one
            library call (every geometry against every window its box touches), and the
            work budget counts every vertex once per window.
        verify, approx_bound, **options
            As for `clip_geojson`. Verification compares every (geometry, window) pair
            whose boxes touch; one `Verification` covers them all.

        Returns
        -------
        GeoJSONWindowsResult
            ``geojson``: one document per window, in order; ``results()`` one
            `GeoJSONResult` each; ``stats``, ``verification`` of the whole request.

        Raises
        ------
        InvalidInputError
            No windows, or a row that is not four numbers (before any request).
        InvalidRequestError
            422: a window the server refuses (``min >= max``), naming it in ``path`` or
            the detail; see `ApiError` for the rest.

        Examples
        --------
        With a server on the default address (``make serve``)::

            line = {"type": "LineString", "coordinates": [[-5, 1], [15, 1]]}
            with Client() as client:
                result = client.clip_geojson_windows(line, [[0, 0, 5, 5], [5, 0, 10, 5]])
            [d["coordinates"] for d in result.geojson]
            # [[[0.0, 1.0], [5.0, 1.0]], [[5.0, 1.0], [10.0, 1.0]]]
        """
        return self.send(calls.clip_geojson_windows(obj, windows, verify=verify,
                                                    approx_bound=approx_bound,
                                                    options=options))

    def clip(self, data: Any, window: Any, *, via: str | None = None,
             column: str | None = None, verify: bool | str | None = None,
             **options: Any) -> ClipResult:
        """Return a collection of geometries clipped to `window`, in the kind it came in.

        Parameters
        ----------
        data : GeoDataFrame, GeoSeries, ndarray, list, tuple, pyarrow.Table or RecordBatch
            The geometries: a GeoPandas frame (its active geometry column, or `column`)
            or series, a 1-D array or a list or tuple of Shapely geometries (None: a
            missing one), or a pyarrow table with a GeoArrow geometry column (native,
            WKB or WKT; the one tagged ``geoarrow.*``, or `column`).
        window : sequence of 4 float, or an object with ``bounds``
            ``[xmin, ymin, xmax, ymax]``.
        via : {"geoarrow", "geojson"}, optional
            The endpoint to send the geometries through: ``POST /v1/clip/geoarrow``
            (the default, needs pyarrow; several times faster) or
            ``POST /v1/clip/geojson``. A pyarrow table goes as GeoArrow.
        column : str, optional
            The geometry column of a frame or table.
        verify : bool or "all", optional
            Compare with Shapely on the server (see `clip_geojson`).
        **options
            ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``, ``backend``,
            ``boundary``, ``keep_empty``, ``check_validity`` (and, via GeoArrow,
            ``resolution``).

        Returns
        -------
        ClipResult
            ``data``: the same kind as `data`, holding the rows left in their input
            order, each with its clipped geometry and the rest as it was (other columns,
            index labels, name, CRS). **A row whose geometry is clipped away (or is
            empty, or missing) is dropped**, unless ``keep_empty=True`` (then it holds an
            empty geometry; a missing one stays missing). ``rows`` gives each kept row's
            position in `data`; also ``stats``, ``verifications``, ``passed``. A line or
            polygon left in several parts is a multi kind; one left whole is its own.

        Raises
        ------
        InvalidInputError
            `data` is not a collection, or holds something that is not a geometry.
        ApiError
            As for every call: e.g. `InvalidRequestError`, whose ``row`` is the position
            in `data` of the row the server names (its ``path`` names it in the request:
            a collection mixing points, lines and polygons goes as GeoArrow in one
            request per family).

        Examples
        --------
        With a server on the default address (``make serve``)::

            import geopandas, shapely
            frame = geopandas.GeoDataFrame(
                {"name": ["in", "across", "out"]}, index=["a", "b", "c"], crs=3857,
                geometry=[shapely.box(1, 1, 2, 2), shapely.box(5, 5, 15, 15),
                          shapely.box(20, 20, 30, 30)])
            with Client() as client:
                clipped = client.clip(frame, (0, 0, 10, 10)).data
            clipped.index.tolist(), clipped.crs   # ['a', 'b'], <Projected CRS: EPSG:3857>
        """
        plan = clipping.plan(data, window, via=via, column=column, verify=verify,
                             options=options)
        pieces = {}
        for batch in plan.batches:
            try:
                pieces[batch.number] = self._answer(plan, batch)
            except ApiError as error:
                plan.locate(batch, error)
                raise
        return plan.assemble(pieces)

    def _answer(self, plan: clipping.Plan, batch: clipping.Batch) -> Any:
        local = plan.local(batch)
        if local is not None:
            return local
        return plan.decode(batch, self.send(plan.call(batch)))

    def clip_many(self, items: Any, window: Any, *, batch_size: int = DEFAULT_BATCH_SIZE,
                  concurrency: int = DEFAULT_CONCURRENCY, via: str | None = None,
                  column: str | None = None, verify: bool | str | None = None,
                  **options: Any) -> Any:
        """Return many geometries clipped to `window`: in batches, several requests at once.

        Parameters
        ----------
        items
            One collection (anything `clip` takes), split into batches of `batch_size`
            rows; or a list (or any iterable) of items, each a collection (split too,
            where longer) or a GeoJSON document (one request each, as `clip_geojson`).
        window : sequence of 4 float
            ``[xmin, ymin, xmax, ymax]``.
        batch_size : int
            Rows per request (default 10,000).
        concurrency : int
            Requests in flight at once (default 4), on a pool of as many threads; each
            one is retried as the client's `retry` policy says.
        via, column, verify, **options
            As `clip` takes them.

        Returns
        -------
        ClipResult or list
            For one collection, its `ClipResult`, as `clip` gives it (``stats`` of all
            the requests together, ``verifications`` one per request). For a list of
            items, one result per item, in order: a `ClipResult` per collection, a
            `GeoJSONResult` per document. Rows clipped to nothing are dropped unless
            ``keep_empty=True``.

        Raises
        ------
        BatchError
            A request failed (after its retries): its ``batch``, ``item``, rows
            ``start:stop``, the ``row`` the server names, and the ``error`` it raised.
            The requests not yet sent are not sent.
        InvalidInputError
            Something cannot be sent (raised before any request).
        """
        concurrency = _check_concurrency(concurrency)
        plan = clipping.plan(items, window, via=via, column=column, verify=verify,
                             options=options, batch_size=batch_size, many=True)
        if not plan.batches:
            return plan.assemble({})

        with ThreadPoolExecutor(max_workers=min(concurrency, len(plan.batches)),
                                thread_name_prefix="rnsca-clip") as pool:
            futures = {pool.submit(self._answer, plan, batch): batch
                       for batch in plan.batches}
            done, pending = wait(futures, return_when=FIRST_EXCEPTION)
            if any(f.exception() is not None for f in done):
                for future in pending:
                    future.cancel()
                wait(pending)
        return _assemble(plan, futures)

    def clip_svg(self, paths: str | Sequence[str], window: Any, *, curves: str | None = None,
                 fill: str | None = None, fill_output: str | None = None,
                 verify: bool | str | None = None, **options: Any) -> SVGResult:
        """Return SVG path data clipped to `window`, one string per path.

        Parameters
        ----------
        paths : str or sequence of str
            Path data (the ``d`` attribute), e.g. ``"M 0 0 C 5 10 10 -5 15 5"``.
        window : sequence of 4 float
            ``[xmin, ymin, xmax, ymax]`` in the paths' coordinates.
        curves : {"preserve", "flatten"}, optional
            Keep Bézier segments as curves (default) or flatten them to lines.
        fill : {"nonzero", "evenodd"}, optional
            Clip as filled areas with this rule; default: as strokes.
        fill_output : {"clean", "raw"}, optional
            How fills come back (the server's default: ``"clean"``, subpaths that are
            simple rings); ``"raw"``: each subpath clamped onto the window's edges
            (faster, paints the same).
        verify : bool or "all", optional
            Compare with Shapely on the server (``"all"``: every input, no sample, within
            the request's time limit).
        **options
            ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``, ``backend``.

        Returns
        -------
        SVGResult
            ``paths``, ``stats``, ``verification``.
        """
        return self.send(calls.clip_svg(paths, window, verify=verify,
                                        options={**options, "curves": curves, "fill": fill,
                                                 "fill_output": fill_output}))

    def clip_svg_windows(self, paths: str | Sequence[str], windows: Any, *,
                         curves: str | None = None, fill: str | None = None,
                         fill_output: str | None = None, verify: bool | str | None = None,
                         **options: Any) -> SVGWindowsResult:
        """Return SVG path data clipped to each of many windows, in one request.

        Parameters
        ----------
        paths : str or sequence of str
            Path data, as for `clip_svg`.
        windows : sequence of [xmin, ymin, xmax, ymax], or an (k, 4) array
            The windows; the server clips every path against every window its box
            touches in one library call (``rnsca.clip_paths(..., windows=)``).
        curves, fill, fill_output, verify, **options
            As for `clip_svg`; verification compares every (path, window) pair whose
            boxes touch.

        Returns
        -------
        SVGWindowsResult
            ``paths[w][i]``: path ``i`` clipped to window ``w`` (``""`` where nothing of
            it is there); ``results()`` one `SVGResult` per window; ``stats``,
            ``verification`` of the whole request.

        Raises
        ------
        InvalidInputError
            No windows, or a row that is not four numbers (before any request).
        """
        return self.send(calls.clip_svg_windows(
            paths, windows, verify=verify,
            options={**options, "curves": curves, "fill": fill, "fill_output": fill_output}))

    def tile(self, obj: Any, z: int, x: int, y: int, **options: Any) -> VectorTile:
        """Return tile z/x/y (WebMercatorQuad, XYZ) of a GeoJSON document as a vector tile.

        Parameters
        ----------
        obj : dict, str or geometry
            GeoJSON (lon/lat, or Web Mercator metres with ``crs="EPSG:3857"``), or what
            `clip_geojson` takes.
        z, x, y : int
            The tile.
        **options
            ``extent`` (4096), ``buffer`` (64), ``layer`` (``"features"``), ``mode``
            (``"exact"``), ``crs`` (``"EPSG:4326"``); None: the server's default.

        Returns
        -------
        VectorTile
            ``data``: the Mapbox Vector Tile's bytes (``b""`` when no feature reaches
            the tile), ``features``: features in the body.

        Raises
        ------
        InvalidInputError
            An unknown option or a negative tile number (before any request).
        InvalidRequestError
            422: a tile outside zoom z's grid, bad GeoJSON or options.
        """
        return self.send(calls.tile(obj, z, x, y, options=options))

    def tiles(self, obj: Any, *, minzoom: int | None = None, maxzoom: int | None = None,
              **options: Any) -> TileArchive:
        """Return the tiles of zooms minzoom..maxzoom of a GeoJSON document, as PMTiles.

        Parameters
        ----------
        obj : dict, str or geometry
            As for `tile`.
        minzoom, maxzoom : int, optional
            The zooms (the server's defaults: 0 and 10); the work budget counts every
            vertex once per zoom, and a zoom may cut at most the server's ``max_tiles``
            (`capabilities`).
        **options
            As for `tile`.

        Returns
        -------
        TileArchive
            ``data``: the PMTiles v3 archive's bytes; ``tiles``, ``features``.

        Raises
        ------
        PayloadTooLargeError
            413: a zoom would cut more than the server's ``max_tiles``.
        InvalidRequestError
            422: no feature in any tile, bad GeoJSON, zooms or options.
        """
        return self.send(calls.tiles(obj, minzoom=minzoom, maxzoom=maxzoom, options=options))

    def clip_segments(self, segments: Any, window: Any, *, binary: bool | None = None,
                      verify: bool | str | None = None, **options: Any) -> SegmentsResult:
        """Return the visible piece of each line segment ``[x0, y0, x1, y1]``.

        Parameters
        ----------
        segments : array_like, shape (n, 4)
            A NumPy array goes through the binary endpoint (float64 rows, no JSON) and
            gives NumPy arrays back; a list of rows goes as JSON and gives lists.
        window : sequence of 4 float
            ``[xmin, ymin, xmax, ymax]``.
        binary : bool, optional
            Force the binary (True, needs NumPy) or the JSON (False) form.
        verify : bool or "all", optional
            Compare with Shapely on the server (``"all"``: every input, no sample, within
            the request's time limit).
        **options
            ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``, ``backend``.

        Returns
        -------
        SegmentsResult
            ``segments`` (m, 4), ``source`` (m,), ``t`` (m, 2), ``stats``,
            ``verification``, and the ``method``, ``mode`` and ``backend`` that ran.
        """
        return self.send(calls.clip_segments(segments, window, binary=binary, verify=verify,
                                             options=options))

    def clip_geoarrow(self, table: Any, window: Any, *, column: str | None = None,
                      verify: bool | str | None = None, **options: Any) -> GeoArrowResult:
        """Return a table with its GeoArrow geometry column clipped to `window`.

        Parameters
        ----------
        table : bytes, pyarrow.Table or pyarrow.RecordBatch
            An Arrow IPC stream, or a table to send as one (needs pyarrow), with a
            GeoArrow geometry column (native, WKB or WKT; see the server's README).
        window : sequence of 4 float
            ``[xmin, ymin, xmax, ymax]``.
        column : str, optional
            The geometry column, where several are tagged.
        verify : bool or "all", optional
            Compare with Shapely on the server.
        **options
            ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``, ``backend``,
            ``resolution``, ``boundary``, ``keep_empty``, ``check_validity``.

        Returns
        -------
        GeoArrowResult
            ``stream`` (the answer's bytes; ``table()`` reads it), ``rows``, ``stats``,
            ``verification``.
        """
        return self.send(calls.clip_geoarrow(table, window, column=column, verify=verify,
                                             options=options))

    def clip_geojson_seq(self, records: Iterable[Any], window: Any,
                         **options: Any) -> ClippedRecords:
        """Return the records clipped to `window`, streamed: sent and read as they come.

        The records go to ``POST /v1/clip/geojson-seq`` as newline-delimited GeoJSON,
        made from `records` while they are sent; the server clips them a chunk at a
        time and the clipped ones are read back as it answers, so neither side holds
        the whole stream (the server keeps what is not read yet in a file, so sending
        first and reading after, as httpx does, is fine).

        Parameters
        ----------
        records : iterable
            Features, Geometries or FeatureCollections: dicts, their JSON text, or
            objects with ``__geo_interface__`` (Shapely geometries). A generator is
            read lazily.
        window : sequence of 4 float
            ``[xmin, ymin, xmax, ymax]``.
        **options
            ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``, ``backend``,
            ``resolution``, ``boundary``, ``keep_empty``, ``check_validity``.

        Returns
        -------
        ClippedRecords
            An iterator over the clipped records, each of its input's kind, in input
            order (those left empty dropped unless ``keep_empty``); once read whole,
            ``stats`` and ``records_in``. Not retried (its records cannot be resent).

        Raises
        ------
        ApiError
            While iterating: the server refused the request, or a record (``record``
            names it; the records before it have been given out).
        InvalidInputError
            A record cannot be sent (not GeoJSON, NaN coordinates).

        Examples
        --------
        ::

            features = ({"type": "Feature", "properties": {"i": i}, "geometry": {
                "type": "LineString", "coordinates": [[-5, i], [15, i]]}}
                for i in range(100_000))
            with Client() as client:
                for feature in client.clip_geojson_seq(features, (0, 0, 10, 10)):
                    ...
        """
        params = calls._query(window, options, None, SEQ_OPTIONS, "streamed GeoJSON")
        return ClippedRecords(self._stream_lines(record_pieces(records), params))

    def _stream_lines(self, pieces: Iterator[bytes], params: dict[str, str]
                      ) -> Iterator[str]:
        try:
            with self._http.stream("POST", SEQ_PATH, content=pieces,
                                   params={**params, "summary": "true"},
                                   headers={"Content-Type": NDJSON, "Accept": NDJSON}
                                   ) as response:
                if response.status_code >= 400:
                    response.read()
                    raise api_error(response)
                yield from response.iter_lines()
        except httpx.TransportError as failure:
            raise _transport_error(failure, 1) from failure

    def capabilities(self) -> Capabilities:
        """Return the server's methods, modes, backends (and why one is missing), limits."""
        return self.send(calls.capabilities())

    def health(self) -> Health:
        """Return the liveness answer (``status == "ok"``) of ``/healthz``."""
        return self.send(calls.health())

    def ready(self) -> bool:
        """Return whether ``/readyz`` says the kernels are ready (no retry on 503)."""
        return self.send(calls.readiness())

    def wait_until_ready(self, timeout: float = 300.0, interval: float = 0.5) -> None:
        """Return once the server is ready; raise if it is not within `timeout` seconds.

        Raises
        ------
        ServiceUnavailableError
            The server answered but stayed not ready.
        ConnectError
            The server could not be reached at all.
        """
        deadline = time.monotonic() + timeout
        while True:
            try:
                if self.ready():
                    return
                failure: Exception = ServiceUnavailableError(
                    {"status": 503, "title": "Not ready",
                     "detail": f"not ready within {timeout} s"})
            except ConnectError as exc:
                failure = exc
            if time.monotonic() + interval > deadline:
                raise failure
            time.sleep(interval)


class AsyncClient:
    """An asyncio client of the rnsca HTTP API: `Client`'s methods, to be awaited.

    Parameters are those of `Client` (`http_client` is an ``httpx.AsyncClient``,
    `transport` an ``httpx.AsyncBaseTransport``). Use ``async with``, or ``await
    aclose()``.

    Examples
    --------
    ::

        async def main():
            async with AsyncClient("http://127.0.0.1:8000") as client:
                return await client.clip_svg("M -5 5 L 15 5", (0, 0, 10, 10))
    """

    def __init__(self, base_url: str = DEFAULT_URL, *, timeout: float | httpx.Timeout =
                 DEFAULT_TIMEOUT, retries: Retry | int | None = DEFAULT_RETRY,
                 headers: dict[str, str] | None = None,
                 http_client: httpx.AsyncClient | None = None,
                 transport: httpx.AsyncBaseTransport | None = None) -> None:
        options = _Options(base_url, timeout, retries, headers)
        self.retry = options.retry
        self._owned = http_client is None
        self._http = http_client or httpx.AsyncClient(transport=transport,
                                                      **options.http_options)

    @property
    def base_url(self) -> httpx.URL:
        """The service's root URL."""
        return self._http.base_url

    async def aclose(self) -> None:
        """Close the connection pool (not an `http_client` passed in)."""
        if self._owned:
            await self._http.aclose()

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    async def send(self, call: calls.Call[T]) -> T:
        """Return the result of `call`, retrying as the policy says."""
        attempt = 0
        while True:
            attempt += 1
            try:
                response = await self._http.request(
                    call.method, call.path, content=call.content, params=call.params,
                    headers=call.headers)
            except httpx.TransportError as failure:
                wait = _wait_before_retry(self.retry, call, attempt, failure=failure)
                if wait is None:
                    raise _transport_error(failure, attempt) from failure
            else:
                wait = _wait_before_retry(self.retry, call, attempt, response=response)
                if wait is None:
                    return _finish(call, response, attempt)
            await asyncio.sleep(wait)

    async def clip_geojson(self, obj: Any, window: Any, *, verify: bool | str | None = None,
                           approx_bound: float | None = None,
                           **options: Any) -> GeoJSONResult:
        """Return a GeoJSON document clipped to `window` (see `Client.clip_geojson`)."""
        return await self.send(calls.clip_geojson(obj, window, verify=verify,
                                                  approx_bound=approx_bound, options=options))

    async def clip_geojson_windows(self, obj: Any, windows: Any, *,
                                   verify: bool | str | None = None,
                                   approx_bound: float | None = None,
                                   **options: Any) -> GeoJSONWindowsResult:
        """Return a document clipped to each window (see `Client.clip_geojson_windows`)."""
        return await self.send(calls.clip_geojson_windows(obj, windows, verify=verify,
                                                          approx_bound=approx_bound,
                                                          options=options))

    async def clip(self, data: Any, window: Any, *, via: str | None = None,
                   column: str | None = None, verify: bool | str | None = None,
                   **options: Any) -> ClipResult:
        """Return a collection clipped to `window`, in its kind (see `Client.clip`).

        Encoding and decoding run in a worker thread, off the event loop.
        """
        plan = clipping.plan(data, window, via=via, column=column, verify=verify,
                             options=options)
        pieces = {}
        for batch in plan.batches:
            try:
                pieces[batch.number] = await self._answer(plan, batch)
            except ApiError as error:
                plan.locate(batch, error)
                raise
        return plan.assemble(pieces)

    async def _answer(self, plan: clipping.Plan, batch: clipping.Batch) -> Any:
        local = plan.local(batch)
        if local is not None:
            return local
        call = await asyncio.to_thread(plan.call, batch)
        answer = await self.send(call)
        return await asyncio.to_thread(plan.decode, batch, answer)

    async def clip_many(self, items: Any, window: Any, *,
                        batch_size: int = DEFAULT_BATCH_SIZE,
                        concurrency: int = DEFAULT_CONCURRENCY, via: str | None = None,
                        column: str | None = None, verify: bool | str | None = None,
                        **options: Any) -> Any:
        """Return many geometries clipped, in batches (see `Client.clip_many`).

        At most `concurrency` requests are in flight (tasks on this event loop); each
        batch is encoded and decoded in a worker thread. A failed request raises
        `BatchError` once the requests in flight have ended; the others are cancelled.
        """
        concurrency = _check_concurrency(concurrency)
        plan = clipping.plan(items, window, via=via, column=column, verify=verify,
                             options=options, batch_size=batch_size, many=True)
        slots = asyncio.Semaphore(concurrency)

        async def answer(batch: clipping.Batch) -> Any:
            async with slots:
                return await self._answer(plan, batch)

        tasks = {asyncio.ensure_future(answer(batch)): batch for batch in plan.batches}
        if not tasks:
            return plan.assemble({})
        done, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_EXCEPTION)
        if pending:
            for task in pending:
                task.cancel()
            await asyncio.wait(pending)
        return _assemble(plan, tasks)

    async def clip_svg(self, paths: str | Sequence[str], window: Any, *,
                       curves: str | None = None, fill: str | None = None,
                       fill_output: str | None = None, verify: bool | str | None = None,
                       **options: Any) -> SVGResult:
        """Return SVG path data clipped to `window` (see `Client.clip_svg`)."""
        return await self.send(calls.clip_svg(
            paths, window, verify=verify, options={**options, "curves": curves, "fill": fill,
                                                   "fill_output": fill_output}))

    async def clip_svg_windows(self, paths: str | Sequence[str], windows: Any, *,
                               curves: str | None = None, fill: str | None = None,
                               fill_output: str | None = None,
                               verify: bool | str | None = None,
                               **options: Any) -> SVGWindowsResult:
        """Return path data clipped to each window (see `Client.clip_svg_windows`)."""
        return await self.send(calls.clip_svg_windows(
            paths, windows, verify=verify,
            options={**options, "curves": curves, "fill": fill, "fill_output": fill_output}))

    async def tile(self, obj: Any, z: int, x: int, y: int, **options: Any) -> VectorTile:
        """Return tile z/x/y of a GeoJSON document (see `Client.tile`)."""
        return await self.send(calls.tile(obj, z, x, y, options=options))

    async def tiles(self, obj: Any, *, minzoom: int | None = None,
                    maxzoom: int | None = None, **options: Any) -> TileArchive:
        """Return a PMTiles archive of a GeoJSON document's tiles (see `Client.tiles`)."""
        return await self.send(calls.tiles(obj, minzoom=minzoom, maxzoom=maxzoom,
                                           options=options))

    async def clip_segments(self, segments: Any, window: Any, *, binary: bool | None = None,
                            verify: bool | str | None = None, **options: Any) -> SegmentsResult:
        """Return the visible piece of each segment (see `Client.clip_segments`)."""
        return await self.send(calls.clip_segments(segments, window, binary=binary,
                                                   verify=verify, options=options))

    async def clip_geoarrow(self, table: Any, window: Any, *, column: str | None = None,
                            verify: bool | str | None = None,
                            **options: Any) -> GeoArrowResult:
        """Return a table with its geometry column clipped (see `Client.clip_geoarrow`)."""
        return await self.send(calls.clip_geoarrow(table, window, column=column,
                                                   verify=verify, options=options))

    def clip_geojson_seq(self, records: Iterable[Any] | AsyncIterable[Any], window: Any,
                         **options: Any) -> AsyncClippedRecords:
        """Return the records clipped, streamed (see `Client.clip_geojson_seq`).

        `records` may be an async iterable; iterate the result with ``async for``.
        """
        params = calls._query(window, options, None, SEQ_OPTIONS, "streamed GeoJSON")
        return AsyncClippedRecords(self._stream_lines(async_record_pieces(records), params))

    async def _stream_lines(self, pieces: AsyncIterator[bytes], params: dict[str, str]
                            ) -> AsyncIterator[str]:
        try:
            async with self._http.stream("POST", SEQ_PATH, content=pieces,
                                         params={**params, "summary": "true"},
                                         headers={"Content-Type": NDJSON, "Accept": NDJSON}
                                         ) as response:
                if response.status_code >= 400:
                    await response.aread()
                    raise api_error(response)
                async for line in response.aiter_lines():
                    yield line
        except httpx.TransportError as failure:
            raise _transport_error(failure, 1) from failure

    async def capabilities(self) -> Capabilities:
        """Return what the server can do (see `Client.capabilities`)."""
        return await self.send(calls.capabilities())

    async def health(self) -> Health:
        """Return the liveness answer of ``/healthz``."""
        return await self.send(calls.health())

    async def ready(self) -> bool:
        """Return whether ``/readyz`` says the kernels are ready (no retry on 503)."""
        return await self.send(calls.readiness())

    async def wait_until_ready(self, timeout: float = 300.0, interval: float = 0.5) -> None:
        """Return once the server is ready (see `Client.wait_until_ready`)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                if await self.ready():
                    return
                failure: Exception = ServiceUnavailableError(
                    {"status": 503, "title": "Not ready",
                     "detail": f"not ready within {timeout} s"})
            except ConnectError as exc:
                failure = exc
            if time.monotonic() + interval > deadline:
                raise failure
            await asyncio.sleep(interval)
