"""The clip and the tiles over Dask: frames by partition, segments by block, tiles by subtree.

`clip` takes a ``dask_geopandas`` GeoDataFrame or GeoSeries (clipped with
``map_partitions``: one task per partition, each calling `clip_frame`), a plain
``geopandas`` one (clipped here, in this process, by the same `clip_frame`), or a
``dask.array`` of segments ``(n, 4)`` chunked by rows (one `rnsca.clip_segments` call per
block). Nothing is computed until the caller asks; options are checked at once, so a bad
option fails here rather than on a worker.

Rows clipped to nothing are dropped, as the SDK's ``Client.clip`` drops them: a row whose
geometry is left empty, or was empty or missing, is not in the result unless
``keep_empty=True`` (then an emptied row holds an empty geometry, and a missing one stays
missing). The rows kept are in input order with their index labels and other columns as
they were.

With ``windows=`` a frame is clipped to many windows: each row gives one row per window
its geometry meets (clipped to that window), in input order, then window order, with the
window's row in ``windows`` in a column (``window`` by default).

`tiles` builds a vector tile pyramid (`rnsca.tiles`) on a ``dask.distributed`` cluster:
one task per part of the pyramid (`rnsca.tiles.split`: the subtrees below some tiles of
a split zoom, and one task for the zooms above it), no two writing the same tile, merged
here into one PMTiles archive (or z/x/y.mvt directory) equal to ``rnsca tiles``'s.

This module needs the ``dask`` extra (``pip install 'rnsca[dask]'``); ``import rnsca``
does not import it.

Numba's workqueue threading layer aborts when two threads of a process call parallel
kernels at once; Dask workers with several threads would do that. Where that layer is
the one loaded, the calls of one process are made one at a time (`_kernel_calls`); the
``omp`` and ``tbb`` layers (the usual ones: libgomp, or ``pip install tbb``) take
concurrent calls.
"""

from __future__ import annotations

import threading
import uuid
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import shapely

try:
    import dask
    import dask.array as da
except ImportError as _error:  # pragma: no cover - the extra is part of the dev install
    raise ImportError("rnsca.dask needs Dask: pip install 'rnsca[dask]'") from _error

from rnsca.arrays import geometry_error
from rnsca.clip import SegmentClipResult, WindowsClipResult, clip_segments
from rnsca.clip import clip as clip_geometries
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    UnsupportedGeometryError,
)
from rnsca.many_windows import as_windows
from rnsca.ragged import clip_ragged
from rnsca.stats import ClipStats
from rnsca.window import Window

if TYPE_CHECKING:
    from rnsca.tiles import ArchiveSummary, FeatureTable
    from rnsca.tiles.encode import ZoomTiles
    from rnsca.tiles.split import Part

__all__ = ["clip", "clip_frame", "SegmentsClip", "tiles", "use_threads"]

#: Numba threading layers that take parallel kernel calls from several threads at once.
_THREAD_SAFE_LAYERS = ("omp", "tbb")
_serial = threading.Lock()
_layer_known = False


@contextmanager
def _kernel_calls() -> Iterator[None]:
    """Run the block alone in this process unless Numba's threading layer is thread-safe.

    The layer is known only once a parallel kernel has run: until then calls are made one
    at a time too.
    """
    global _layer_known
    if _layer_known:
        yield
        return
    with _serial:
        yield
        import numba

        from rnsca.runtime import numba_threads_started

        if numba_threads_started() and numba.threading_layer() in _THREAD_SAFE_LAYERS:
            _layer_known = True


def clip(data: Any, window: Window | Iterable[float] | None = None, *,
         windows: npt.ArrayLike | None = None, keep_empty: bool = False,
         window_column: str = "window", **options: Any) -> Any:
    """Return `data` clipped to the window, lazily for Dask collections.

    Parameters
    ----------
    data : dask_geopandas.GeoDataFrame or GeoSeries, geopandas.GeoDataFrame or GeoSeries, \
or dask.array.Array
        A frame or series: its (active) geometry column is clipped. A dask array: segments
        ``(n, 4)`` ``[x0, y0, x1, y1]``, chunked by rows (chunks across the 4 columns are
        joined), with known chunk sizes.
    window : Window or sequence of 4 floats
        ``(xmin, ymin, xmax, ymax)``.
    windows : array_like, shape (k, 4), optional
        Many windows instead of `window`. Segments: as `rnsca.clip_segments`. Frames and
        series: every row against every window its geometry touches (`clip_frame`), a
        frame out with the window of each row in `window_column`.
    keep_empty : bool
        Frames, one window: keep rows clipped to nothing (with an empty geometry)
        instead of dropping them; a missing geometry stays missing.
    window_column : str
        Frames with ``windows=``: the column of the window index (int64; a column of
        that name must not be in `data`).
    **options
        ``method``, ``n``, ``max_depth``, ``tolerance``, ``resolution``, ``mode``,
        ``backend``; for frames also ``boundary`` and ``check_validity`` (see
        `rnsca.clip_ragged`).

    Returns
    -------
    dask_geopandas.GeoDataFrame or GeoSeries
        For a Dask frame or series: the same kind, with the same columns, dtypes, CRS and
        divisions (rows are only dropped); its ``spatial_partitions``, if known, are cut
        to the window. With ``windows=``: a GeoDataFrame (rows repeated per window, the
        window column added), the same divisions.
    geopandas.GeoDataFrame or GeoSeries
        For a plain one, computed here (`clip_frame`).
    SegmentsClip
        For a dask array: the pieces as dask arrays of unknown chunk sizes (one chunk per
        input block), with global ``source`` rows.

    Raises
    ------
    UnsupportedGeometryError
        For another kind of `data`.
    InvalidWindowError, InvalidOptionError
        For a bad window or option (checked here, before any task runs).
    InvalidGeometryError
        When computed: a bad geometry or segment, named by its row.

    Examples
    --------
    >>> import dask.array as da, numpy as np
    >>> segments = da.from_array(np.array([[-5.0, 5, 15, 5], [1, 1, 2, 2]]), chunks=1)
    >>> clipped = clip(segments, (0, 0, 10, 10)).compute()
    >>> clipped.segments.tolist(), clipped.source.tolist()
    ([[0.0, 5.0, 10.0, 5.0], [1.0, 1.0, 2.0, 2.0]], [0, 1])
    """
    if isinstance(data, da.Array):
        if keep_empty:
            raise InvalidOptionError("keep_empty applies to frames, not to segments")
        return _clip_segment_array(data, window, windows, options)
    module = type(data).__module__
    if module.startswith(("geopandas", "dask_geopandas")):
        if (window is None) == (windows is None):
            raise InvalidWindowError("give one of window= and windows=")
        if windows is not None:
            table = as_windows(windows)
            _check_windows_options(data, table, keep_empty, window_column, options)
            if module.startswith("dask_geopandas"):
                return _clip_dask_frame_windows(data, table, window_column, options)
            return clip_frame(data, windows=table, window_column=window_column, **options)
        assert window is not None
        bounds = Window.of(window)
        _check_geometry_options(bounds, options)
        if module.startswith("dask_geopandas"):
            return _clip_dask_frame(data, bounds, keep_empty, options)
        return clip_frame(data, bounds, keep_empty=keep_empty, **options)
    raise UnsupportedGeometryError(
        "rnsca.dask.clip takes a dask_geopandas or geopandas GeoDataFrame or GeoSeries, or "
        f"a dask array of segments (n, 4); got {type(data).__module__}."
        f"{type(data).__name__} (rnsca.clip takes Shapely geometries and arrays)")


def _check_geometry_options(window: Window, options: dict[str, Any]) -> None:
    """Raise the library's error for a bad option now, not on a worker.

    Clipping no geometry runs every check that does not depend on the input (whether
    approx mode meets a polygon is found when clipping).
    """
    clip_ragged("Point", np.empty((0, 2)), (), window, **options)


def _check_windows_options(data: Any, table: np.ndarray, keep_empty: bool,
                           window_column: str, options: dict[str, Any]) -> None:
    """Raise now for an option that a clip of a frame to many windows refuses."""
    if keep_empty:
        raise InvalidOptionError(
            "keep_empty applies to one window: with windows= a row gives a row per window "
            "its geometry meets, and none for the others")
    columns = getattr(data, "columns", ())
    if window_column in columns:
        raise InvalidOptionError(
            f"the input has a column {window_column!r}: give window_column= another name")
    clip_ragged("Point", np.empty((0, 2)), (), windows=table, **options)


def clip_frame(frame: Any, window: Window | Iterable[float] | None = None, *,
               windows: npt.ArrayLike | None = None, keep_empty: bool = False,
               window_column: str = "window", **options: Any) -> Any:
    """Return a geopandas GeoDataFrame or GeoSeries clipped to the window, in this process.

    The rows kept are in input order, with their index labels, other columns and CRS;
    rows clipped to nothing (or empty, or missing) are dropped unless `keep_empty` (then
    an emptied row holds an empty geometry; a missing one stays missing). A line or
    polygon cut in several parts becomes a multi kind; one left whole keeps its type.

    With `windows` (k, 4), each row is clipped to every window its geometry touches
    (`rnsca.clip` with ``windows=``) and gives one row per window left with something:
    in input order, then window order (the library's result, sorted by source then
    window), with the window's row in `windows` as an int64 column `window_column`
    (last). A GeoSeries gives a GeoDataFrame of its geometry (named after it, or
    ``geometry``) and that column.

    Parameters
    ----------
    frame : geopandas.GeoDataFrame or GeoSeries
        Its active geometry column is clipped (any mix of types, see `rnsca.clip`).
    window : Window or sequence of 4 floats
    windows : array_like, shape (k, 4), optional
        Instead of `window`.
    keep_empty : bool
        One window only.
    window_column : str
    **options
        As `rnsca.clip`.

    Raises
    ------
    InvalidGeometryError
        Naming the row by its index label; ``geometry`` is its position in `frame`.

    Examples
    --------
    >>> import geopandas, shapely
    >>> frame = geopandas.GeoDataFrame(
    ...     {"name": ["across", "out"]}, index=[7, 9],
    ...     geometry=[shapely.LineString([(-5, 5), (15, 5)]), shapely.Point(20, 20)])
    >>> clipped = clip_frame(frame, (0, 0, 10, 10))
    >>> clipped.index.tolist(), clipped.geometry.to_wkt().tolist()
    ([7], ['LINESTRING (0 5, 10 5)'])
    """
    import geopandas

    is_frame = isinstance(frame, geopandas.GeoDataFrame)
    series = frame.geometry if is_frame else frame
    geometries = np.asarray(series.array, dtype=object)
    if (window is None) == (windows is None):
        raise InvalidWindowError("give one of window= and windows=")
    try:
        with _kernel_calls():
            clipped = clip_geometries(geometries, window, windows=windows, **options)
    except InvalidGeometryError as exc:
        if exc.geometry is None or exc.detail is None:
            raise
        label = series.index[exc.geometry]
        error = geometry_error(exc.geometry, exc.detail)
        error.args = (f"row {label!r} (position {exc.geometry}){exc.detail}",)
        raise error from None
    if isinstance(clipped, WindowsClipResult):
        return _frame_of_windows(frame if is_frame else None, series, clipped,
                                 window_column)
    if keep_empty:
        kept = np.ones(len(clipped), dtype=bool)
    else:
        kept = ~shapely.is_missing(clipped) & ~shapely.is_empty(clipped)
    rows = np.flatnonzero(kept)
    values = geopandas.GeoSeries(clipped[rows], index=series.index[rows], crs=series.crs,
                                 name=series.name)
    if not is_frame:
        return values
    out = frame.iloc[rows].copy()
    out[frame.geometry.name] = values
    return out


def _frame_of_windows(frame: Any, series: Any, clipped: WindowsClipResult,
                      window_column: str) -> Any:
    """Return the rows of a many-window clip in source, then window order."""
    import geopandas

    order = np.lexsort((clipped.window, clipped.source))
    rows, window = clipped.source[order], clipped.window[order].astype(np.int64)
    name = series.name if series.name is not None else "geometry"
    if frame is None:
        frame = geopandas.GeoDataFrame(geometry=series.rename(name))
    elif window_column in frame.columns:
        raise InvalidOptionError(
            f"the input has a column {window_column!r}: give window_column= another name")
    out = frame.iloc[rows].copy()
    out[frame.geometry.name] = geopandas.GeoSeries(clipped.geometries[order],
                                                   index=out.index, crs=series.crs)
    out[window_column] = window
    return out


def _clip_partition(frame: Any, window: Window, keep_empty: bool,
                    options: dict[str, Any]) -> Any:
    """Clip one partition (what each task runs)."""
    return clip_frame(frame, window, keep_empty=keep_empty, **options)


def _clip_dask_frame(frame: Any, window: Window, keep_empty: bool,
                     options: dict[str, Any]) -> Any:
    # Rows are only dropped or their geometry replaced (a geometry column stays one),
    # so the input's meta (columns, dtypes, CRS) and divisions hold for the result.
    out = frame.map_partitions(_clip_partition, window, keep_empty, options,
                               meta=frame._meta)
    regions = getattr(frame, "spatial_partitions", None)
    if regions is not None:
        # Each clipped row lies in its partition's region and in the (closed) window.
        out.spatial_partitions = regions.intersection(shapely.box(*window.bounds))
    return out


def _clip_partition_windows(frame: Any, table: np.ndarray, window_column: str,
                            options: dict[str, Any]) -> Any:
    """Clip one partition to many windows (what each task runs)."""
    return clip_frame(frame, windows=table, window_column=window_column, **options)


def _clip_dask_frame_windows(frame: Any, table: np.ndarray, window_column: str,
                             options: dict[str, Any]) -> Any:
    # Rows are repeated (one per window) in index order: the divisions hold. The meta is
    # the clip of the input's (empty) meta: its columns, the window column added.
    meta = clip_frame(frame._meta, windows=table, window_column=window_column, **options)
    out = frame.map_partitions(_clip_partition_windows, table, window_column, options,
                               meta=meta)
    regions = getattr(frame, "spatial_partitions", None)
    if regions is not None:
        envelope = shapely.box(*table[:, :2].min(axis=0), *table[:, 2:].max(axis=0))
        out.spatial_partitions = regions.intersection(envelope)
    return out


@dataclass(frozen=True)
class SegmentsClip:
    """Segments of a dask array clipped, lazily: one block of pieces per input block.

    The pieces of block ``b`` are those of its rows, in row order (with ``windows=``: by
    window, then row, within the block). Each attribute is a dask array of unknown chunk
    sizes; compute them together (``dask.compute(c.segments, c.source)``, or `compute`),
    since each computed alone clips the blocks again.

    Attributes
    ----------
    segments : dask.array.Array of float64, shape (nan, 4)
    source : dask.array.Array of int64, shape (nan,)
        The global row of the input segment of each piece.
    t : dask.array.Array of float64, shape (nan, 2)
    window : dask.array.Array of int32, shape (nan,), or None
        With ``windows=``: the window of each piece.
    blocks : tuple of dask.delayed.Delayed
        Each block's `rnsca.SegmentClipResult` (its ``source`` global).
    """

    segments: Any
    source: Any
    t: Any
    window: Any
    blocks: tuple[Any, ...]

    def compute(self, **kwargs: Any) -> SegmentClipResult:
        """Return the whole clip as `rnsca.clip_segments` gives it for the whole array.

        The blocks' results are computed (``dask.compute(..., **kwargs)``: a scheduler or
        the Distributed client in use), joined, and their stats combined; with
        ``windows=`` the pieces are sorted by window, then source, with
        ``window_offsets``.
        """
        parts: tuple[SegmentClipResult, ...] = dask.compute(*self.blocks, **kwargs)
        return join_segment_results(parts)


def join_segment_results(parts: Iterable[SegmentClipResult]) -> SegmentClipResult:
    """Return consecutive blocks' results (global ``source``) as one result.

    Pieces are concatenated in block order; with many windows they are then sorted by
    window (stable, so by source within a window), as one call would give them.
    """
    parts = list(parts)
    first = parts[0]
    segments = np.concatenate([p.segments for p in parts]).reshape(-1, 4)
    source = np.concatenate([p.source for p in parts]) if first.source is not None else None
    t = np.concatenate([p.t for p in parts]).reshape(-1, 2) if first.t is not None else None
    window, window_offsets = None, None
    if first.window_offsets is not None:
        window = np.concatenate([p.window for p in parts])
        order = np.argsort(window, kind="stable")
        window, segments = window[order], segments[order]
        source = source[order] if source is not None else None
        t = t[order] if t is not None else None
        k = first.window_offsets.shape[0] - 1
        window_offsets = np.searchsorted(window, np.arange(k + 1), side="left").astype(
            np.int64)
    stats = ClipStats.combine(p.stats for p in parts)
    return replace(first, segments=segments, source=source, t=t, stats=stats,
                   window=window, window_offsets=window_offsets)


def _clip_block(block: np.ndarray, start: int, window: Any, windows: Any,
                options: dict[str, Any]) -> SegmentClipResult:
    """Clip one block of rows starting at global row `start`; ``source`` made global."""
    try:
        with _kernel_calls():
            result = clip_segments(block, window, windows=windows, **options)
    except InvalidGeometryError as exc:
        if exc.row is None:
            raise
        local = f"segment {exc.row}"
        text = str(exc)
        error = InvalidGeometryError(
            f"segment {start + exc.row}{text[len(local):]}" if text.startswith(local)
            else f"segment {start + exc.row}: {text}")
        error.row = start + exc.row
        raise error from None
    source = result.source + start if result.source is not None else None
    return replace(result, source=source)


def _clip_segment_array(array: Any, window: Any, windows: Any,
                        options: dict[str, Any]) -> SegmentsClip:
    if array.ndim != 2 or array.shape[1] != 4:
        raise InvalidGeometryError(
            f"a dask array of segments must have shape (n, 4), got {array.shape}")
    if array.dtype.kind not in "iuf":
        raise InvalidGeometryError(
            f"segments must have a real numeric dtype (float64 preferred), got {array.dtype}")
    rows = array.chunks[0]
    if any(np.isnan(size) for size in rows):
        raise InvalidGeometryError(
            "the sizes of the segment array's row chunks must be known: call "
            "array.compute_chunk_sizes() first")
    if len(array.chunks[1]) != 1:
        array = array.rechunk({1: 4})
    # Checks the window(s) and options now, on no segments.
    clip_segments(np.empty((0, 4)), window, windows=windows, **options)
    starts = np.concatenate([[0], np.cumsum(rows)[:-1]]).astype(np.int64).tolist()
    blocks = array.to_delayed().ravel()
    results = tuple(dask.delayed(_clip_block, pure=True)(block, start, window, windows,
                                                         options)
                    for block, start in zip(blocks, starts, strict=True))
    many = windows is not None

    def column(name: str, shape: tuple[float, ...], dtype: Any) -> Any:
        return da.concatenate([da.from_delayed(getattr(r, name), shape=shape, dtype=dtype)
                               for r in results]) if results else \
            da.empty((0,) + shape[1:], dtype=dtype)

    return SegmentsClip(
        segments=column("segments", (np.nan, 4), np.float64),
        source=column("source", (np.nan,), np.int64),
        t=column("t", (np.nan, 2), np.float64),
        window=column("window", (np.nan,), np.int32) if many else None,
        blocks=results)


def use_threads(threads: int) -> None:
    """Run this thread's parallel kernels on `threads` threads, and pyarrow's pool too.

    What a task runs first when its worker process has a share of the cores
    (`rnsca.batch.local_cluster`): Numba may have been imported before the worker's
    environment (``NUMBA_NUM_THREADS``) was set.
    """
    import numba

    numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    try:
        import pyarrow
    except ImportError:  # pragma: no cover - the dask extra installs it
        return
    pyarrow.set_cpu_count(max(1, threads))


def _build_tiles(table: FeatureTable, part: Part | None, split_zoom: int,
                 threads: int | None, options: dict[str, Any]) -> list[ZoomTiles]:
    """Build one part of the pyramid (`part`), or the zooms above the split (None)."""
    from rnsca.tiles.split import build_part, build_top

    if threads is not None:
        use_threads(threads)
    with _kernel_calls():
        if part is None:
            return build_top(table, split_zoom=split_zoom, **options)
        return build_part(table, part, **options)


def tiles(table: FeatureTable, output: str | Path, *, client: Any = None,
          minzoom: int = 0, maxzoom: int = 14, extent: int = 4096, buffer: int = 64,
          layer: str = "features", compression: str | None = None,
          split_zoom: int | None = None, parts: int | None = None,
          threads: int | None = None,
          on_part: Callable[[int, int], None] | None = None,
          **options: Any) -> ArchiveSummary:
    """Build the tile pyramid of `table` on a Dask cluster; write one archive at `output`.

    The tiles equal `rnsca.tiles.tile_table`'s (the same bytes). The work is split by
    tile (`rnsca.tiles.split`): the zooms down to the split zoom are cascaded here, once;
    each task builds the subtrees below a run of that zoom's tiles (sent to it with
    their geometry), one more the zooms above it, and no two build the same tile. Tasks
    compress their tiles; this process merges them and writes the archive once all are
    built (it holds the stored tiles meanwhile: about the archive's size in memory).

    Parameters
    ----------
    table : rnsca.tiles.FeatureTable
        Sent once to each worker (the tasks encode its ids and properties).
    output : str or Path
        A ``.pmtiles`` archive, or a directory (``z/x/y.mvt``), as ``rnsca tiles``.
    client : distributed.Client, optional
        Default: the current client (``distributed.get_client()``).
    minzoom, maxzoom, extent, buffer, layer
        As `rnsca.tiles.tile_table`.
    compression : {"gzip", "none"}, optional
        Default: gzip for PMTiles, none for a directory.
    split_zoom : int, optional
        Where the pyramid is cut (``0..min(maxzoom, rnsca.tiles.split.MAX_SPLIT_ZOOM)``).
        Default: the first zoom with `parts` tiles holding something; the zooms above it
        are cascaded here, and built by one task.
    parts : int, optional
        Tasks below the split zoom (default: four per worker, for balance).
    threads : int, optional
        Threads of each task's kernels (`use_threads`); None leaves the worker's.
    on_part : callable, optional
        ``on_part(done, total)``, in this process as each task ends (progress).
    **options
        ``mode``, ``validate``, ``backend``, ``framing`` of `rnsca.tiles.tile_table`.

    Returns
    -------
    rnsca.tiles.ArchiveSummary
        Tiles, features and bytes per zoom (its seconds: the merge and the write).

    Raises
    ------
    InvalidOptionError
        For options out of range, or no client.
    ValueError
        When no tile holds a feature (PMTiles).
    """
    from distributed import as_completed, get_client

    from rnsca import tiles as T
    from rnsca.options import Mode
    from rnsca.tiles.split import merge, split

    T.check_options(minzoom, maxzoom, extent, buffer, Mode(options.get("mode", Mode.EXACT)))
    if client is None:
        try:
            client = get_client()
        except ValueError:
            raise InvalidOptionError("rnsca.dask.tiles needs a dask.distributed Client: "
                                     "give client=, or start one first") from None
    workers = max(1, len(client.scheduler_info().get("workers", {})))
    pmtiles = Path(output).suffix.lower() == ".pmtiles"
    stored = T.Compression(compression or ("gzip" if pmtiles else "none"))
    zoom, pieces = split(table, parts=4 * workers if parts is None else parts,
                         split_zoom=split_zoom, maxzoom=maxzoom, extent=extent,
                         buffer=buffer, mode=options.get("mode", Mode.EXACT),
                         backend=options.get("backend", "numba"))
    build = dict(options, minzoom=minzoom, maxzoom=maxzoom, extent=extent, buffer=buffer,
                 layer=layer, compression=stored)
    [shared] = client.scatter([table], broadcast=True, hash=False)
    sent = client.scatter(pieces, hash=False)
    token = uuid.uuid4().hex[:12]
    futures = [client.submit(_build_tiles, shared, piece, zoom, threads, build,
                             key=f"rnsca-tiles-{k}-{token}", pure=False)
               for k, piece in enumerate(sent)]
    if zoom > minzoom:  # the zooms above the split
        futures.append(client.submit(_build_tiles, shared, None, zoom, threads, build,
                                     key=f"rnsca-tiles-top-{token}", pure=False))
    del pieces
    built: list[list[ZoomTiles]] = []
    try:
        for done, future in enumerate(as_completed(futures), start=1):
            built.append(future.result())  # a task's error is raised here
            future.release()
            if on_part is not None:
                on_part(done, len(futures))
    finally:
        client.cancel([f for f in futures if not f.done()])
        client.cancel([shared, *sent])
    zooms = merge(built)
    if pmtiles:
        return T.write_pmtiles(output, zooms, layer=layer, compression=stored,
                               compressed=True)
    return T.write_directory(output, zooms, compression=stored, compressed=True)
