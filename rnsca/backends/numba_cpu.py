"""The Numba backend: count, prefix-sum, write over the parallel segment kernel."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import NamedTuple

import numba
import numpy as np

from rnsca.arrays import (
    GeometryKind,
    PathArrays,
    Ragged,
    check_segment_values,
    exclusive_sum,
    group_offsets,
    tile_piece_error,
)
from rnsca.backends.base import (
    METHOD_ID,
    Capabilities,
    ClipBackend,
    GeometryPieces,
    PathPieces,
    Polylines,
    SegmentPieces,
    TileBytes,
    TileLayer,
)
from rnsca.constants import MVT_COORDINATE_LIMIT
from rnsca.errors import LimitExceededError
from rnsca.kernels import bezier as BZ
from rnsca.kernels import counters as C
from rnsca.kernels import fill_rings as FR
from rnsca.kernels import mvt as MVT
from rnsca.kernels import polygons as PG
from rnsca.kernels import polylines as PL
from rnsca.kernels import records as R
from rnsca.kernels import segments as K
from rnsca.kernels import tile_polygons as TP
from rnsca.kernels import windows as WK
from rnsca.kernels.copies import copy_ranges
from rnsca.kernels.validate import all_finite
from rnsca.many_windows import assign
from rnsca.options import (
    Backend,
    Curves,
    Fill,
    FillOutput,
    Method,
    Mode,
    PathOptions,
    SegmentOptions,
)
from rnsca.stats import ClipStats, DeviceStats
from rnsca.window import Window, WindowTable

__all__ = ["DevicePaths", "DevicePolygons", "NumbaBackend", "PathRange", "PolygonRange"]

# Segments per prange iteration: large enough that per-block scratch and counters cost
# nothing, small enough that the scratch columns (14 x 16 KiB) stay in L2 cache.
BLOCK_SIZE = 2048
# Inputs of at most this many blocks run on the calling thread (see the serial driver).
SERIAL_BLOCKS = 4
# Flattening paths writes at most this many points (2 GiB of float64 pairs): a tolerance
# far below the curves' size (or coordinates far beyond the window a verification's
# tolerance is taken from) would otherwise ask for tens of gigabytes (measured: a
# verification of 52,000 wandering cubic paths asked for 59 GiB) and fail with MemoryError.
MAX_FLATTENED_POINTS = 2**27
_CAPABILITIES = Capabilities(Backend.NUMBA)
_NO_INDEX = np.empty(0, dtype=np.int64)
_NO_BYTES = np.empty(0, dtype=np.uint8)
# The geometries of the kinds a tile of segment pieces has none of.
_NO_SHAPES = MVT.Shapes(np.empty((0, 2), dtype=np.int64), _NO_INDEX, _NO_INDEX, _NO_INDEX)
# Subpaths per block of the parallel path kernel: enough work per block to pay for its
# scratch arrays, enough blocks to balance the threads (at most _PATH_BLOCK subpaths, and
# at least _PATH_MIN_BLOCKS blocks when there are that many subpaths: a few long paths,
# such as the 200 curves of 500 cubics of the benchmark, are still shared out evenly).
_PATH_BLOCK = 64
_PATH_MIN_BLOCKS = 32


class PolygonRange(NamedTuple):
    """Decisions for polygons ``first`` to ``end - 1`` of a call (their rings' tables)."""

    first: int
    end: int
    decisions: PL.Decisions


class DevicePolygons(NamedTuple):
    """What the OpenCL backend's device decided for `NumbaBackend.clip_polygons`.

    `polygon_class` (int8 per polygon: `polygons.classify_polygons`'s where
    `classified`, else filled by the count pass); `ranges`, the rings' run decisions and
    clipped pieces range by range, in polygon order, each given as the device finishes
    it (the count pass of one range runs while the device works on the next); `totals`,
    called once every range is read, the device's counter rows and stats.
    """

    classified: bool
    polygon_class: np.ndarray
    ranges: Iterable[PolygonRange]
    totals: Callable[[], tuple[np.ndarray, DeviceStats | None]]


class PathRange(NamedTuple):
    """Decisions for subpaths ``first`` to ``end - 1`` of a call.

    `decisions` (`bezier.Decisions`) is indexed by the range's segments, from its first:
    each segment's class, each run's decision and the flattened points of the curves
    accepted whole (or, not given, the runs' table the count pass fills).
    """

    first: int
    end: int
    decisions: BZ.Decisions


class DevicePaths(NamedTuple):
    """What the OpenCL backend's device decided for `NumbaBackend.clip_paths`.

    `ranges`, in subpath order, each given as the device finishes it (the count pass of
    one range runs while the device works on the next), and `totals`, called once every
    range is read: the device's stats.
    """

    ranges: Iterable[PathRange]
    totals: Callable[[], DeviceStats | None]


# Without a device, no segment classes nor flattened points are given to the path kernel.
_NO_CLASSES = (np.empty(0, np.uint8), np.empty(0, dtype=np.int64), np.empty((0, 2)))


class NumbaBackend:
    """Run the Numba kernels on the CPU, in parallel over blocks of segments."""

    kind = Backend.NUMBA

    @property
    def capabilities(self) -> Capabilities:
        """Return what this backend runs: every operation, both modes, in float64."""
        return _CAPABILITIES

    def clip_segments(self, segments: np.ndarray, window: Window, options: SegmentOptions,
                      *, source: bool = True, t: bool = True) -> SegmentPieces:
        """Return the visible piece of each segment; see `ClipBackend.clip_segments`.

        The kernel writes `source` and `t` in its one pass (cheaper than a second
        kernel); those not asked for are dropped (None).
        """
        n = segments.shape[0]
        n_blocks = max(1, -(-n // BLOCK_SIZE))
        bounds = R.Window(window.xmin, window.ymin, window.xmax, window.ymax)
        settings = core_options(options)
        # One pass: a segment gives at most one piece, so each chunk of blocks (one per
        # thread) writes its pieces one after another from the row of its first segment;
        # then the chunks after the first are moved up in place and the arrays shrunk.
        # Clipping once instead of counting then writing saved about 40% of the call,
        # moving one chunk per thread instead of every block another 10-15% (10M uniform
        # segments, benchmarks/README.md "Results of the committed run: issue 15").
        out = K.SegmentOutput(
            np.empty((n, 4)), np.empty(n, dtype=np.int64), np.empty((n, 2)),
            np.empty(n_blocks, dtype=np.int64), np.empty(n_blocks, dtype=np.int64),
            np.zeros((n_blocks, C.WIDTH), dtype=np.int64))
        if n_blocks <= SERIAL_BLOCKS:
            n_chunks = 1
            K.clip_segment_blocks_serial(segments, bounds, settings, BLOCK_SIZE, out)
        else:
            n_chunks = min(numba.get_num_threads(), n_blocks)
            K.clip_segment_blocks(segments, bounds, settings, BLOCK_SIZE, n_chunks, out)
        if (out.block_count == K.INVALID_BLOCK).any():
            check_segment_values(segments)  # raises, naming the first bad segment
            raise AssertionError("the segment kernel found a segment that is not finite, "
                                 "the check did not")
        m = 0
        for chunk in range(n_chunks):
            first, last = K.chunk_blocks(chunk, n_chunks, n_blocks)
            count = int(out.block_count[first:last].sum())
            start = int(out.block_start[first]) if count else m
            if start != m:
                K.move_rows(out, start, m, count)
            m += count
        pieces, sources, ts = out.pieces, out.source, out.t
        if m < n:  # new arrays no one else holds: realloc shrinks them where they are
            pieces.resize((m, 4), refcheck=False)
            sources.resize(m, refcheck=False)
            ts.resize((m, 2), refcheck=False)
        return SegmentPieces(pieces, sources if source else None, ts if t else None,
                             ClipStats.from_counters(out.counters, n, m))

    def clip_segment_windows(self, segments: np.ndarray, windows: np.ndarray,
                             options: SegmentOptions, *, source: bool = True,
                             t: bool = True) -> SegmentPieces:
        """Return each segment's piece in each window; see `ClipBackend.clip_segment_windows`.

        The pairs' segments are gathered so each window's are consecutive rows, clipped
        in blocks of one window each (`windows.clip_pairs`) and compacted as one window's
        are.
        """
        check_segment_values(segments)  # the assignment reads the boxes
        pairs = assign(segments, windows)
        p = pairs.segment.shape[0]
        gathered = np.empty((p, 4))
        WK.gather_rows(segments, pairs.segment, gathered)
        per_window = np.diff(pairs.window_offsets)
        blocks_per_window = -(-per_window // BLOCK_SIZE)
        block_window = np.repeat(np.arange(windows.shape[0], dtype=np.int64),
                                 blocks_per_window)
        n_blocks = block_window.shape[0]
        within = np.arange(n_blocks) - np.repeat(exclusive_sum(blocks_per_window)[:-1],
                                                 blocks_per_window)
        block_first = pairs.window_offsets[block_window] + within * BLOCK_SIZE
        block_end = np.minimum(block_first + BLOCK_SIZE, pairs.window_offsets[block_window + 1])
        out = K.SegmentOutput(
            np.empty((p, 4)), np.empty(p, dtype=np.int64), np.empty((p, 2)),
            np.empty(n_blocks, dtype=np.int64), np.empty(n_blocks, dtype=np.int64),
            np.zeros((max(1, n_blocks), C.WIDTH), dtype=np.int64))
        n_chunks = max(1, min(numba.get_num_threads(), n_blocks))
        WK.clip_pairs(gathered, windows, block_window, block_first, block_end,
                      core_options(options), n_chunks, out)
        m = 0
        for chunk in range(n_chunks if n_blocks else 0):
            first, last = K.chunk_blocks(chunk, n_chunks, n_blocks)
            count = int(out.block_count[first:last].sum())
            start = int(out.block_start[first]) if count else m
            if start != m:
                K.move_rows(out, start, m, count)
            m += count
        rows = out.source[:m]  # each piece's pair
        # `rows` ascend (pairs are sorted by window): k + 1 binary searches give the
        # offsets, not a search per piece (12M pieces: 9 ms against 150 ms on 2 cores).
        window_offsets = np.searchsorted(rows, pairs.window_offsets).astype(np.int64)
        window = np.repeat(np.arange(windows.shape[0], dtype=np.int32),
                           np.diff(window_offsets))
        sources = pairs.segment[rows] if source else None
        pieces, ts = out.pieces, out.t
        if m < p:  # new arrays no one else holds: realloc shrinks them where they are
            pieces.resize((m, 4), refcheck=False)
            ts.resize((m, 2), refcheck=False)
        return SegmentPieces(pieces, sources, ts if t else None,
                             ClipStats.from_counters(out.counters, p, m), window,
                             window_offsets)

    def clip_lines(self, lines: Ragged, windows: WindowTable, options: SegmentOptions,
                   drop_edge_runs: bool) -> GeometryPieces:
        """Return the chains of each line geometry; see `ClipBackend.clip_lines`.

        Count, prefix sum and write run in one kernel call (`polylines.clip_lines`), which
        also checks the coordinates (their first pass) and reports the first part with a
        non-finite one (nothing is clipped then; the error names it).
        """
        xy, z = lines.split_z()
        if lines.has_z and not all_finite(z):
            lines.check_finite()  # raises, naming the first bad coordinate
        part_offsets, geometry_parts = lines.item_offsets()
        # One window for all: the kernel takes row 0 of the table for every geometry.
        geometry_window = _NO_INDEX if windows.is_single else windows.index
        out_xy, out_z, chain_offsets, geometry_chains, counters, bad_part = PL.clip_lines(
            R.vertices(xy, z), PL.Lines(part_offsets, geometry_parts, windows.bounds,
                                        geometry_window),
            core_options(options), drop_edge_runs)
        if bad_part >= 0:
            lines.check_finite()  # raises, naming the first bad coordinate
            raise AssertionError(f"the line kernel found a non-finite coordinate in part "
                                 f"{bad_part} that the full check did not")
        return GeometryPieces(out_xy, out_z, (chain_offsets, geometry_chains), counters)

    def clip_polygon_pairs(self, polygons: Ragged, geometry: np.ndarray, windows: np.ndarray,
                           options: SegmentOptions) -> GeometryPieces:
        """Return each (geometry, window) pair clipped; see `ClipBackend.clip_polygon_pairs`.

        The simple pairs of a 2D array (rings inside, outside, or a shell crossing the
        boundary at isolated points: `rnsca.kernels.tile_polygons`) are clipped from
        `polygons` by index, into slots a first pass bounds; the others (and 3D input)
        are gathered and clipped by `clip_polygons`. The same output bit for bit
        (`tests/property/test_tiles_polygon_pairs.py`). At zoom 8 of the polygons
        benchmark 250k of 291k pairs are simple, clipped at about 50 ns a vertex against
        160-190 by the general kernel.
        """
        geometry = np.ascontiguousarray(geometry, dtype=np.int64)
        windows = np.ascontiguousarray(windows, dtype=np.float64)
        n = geometry.shape[0]
        if polygons.has_z:
            return self.clip_polygons(polygons.take(geometry),
                                      WindowTable(windows, np.arange(n, dtype=np.int64)),
                                      options)
        polygon_offsets, geometry_offsets = polygons.item_offsets()
        src = TP.Parent(polygons.coords, polygons.offsets[0], polygon_offsets,
                        geometry_offsets)
        status = np.empty(n, dtype=np.int8)
        bounds = TP.PairRows(*(np.empty(n, dtype=np.int64) for _ in range(3)))
        TP.plan_pairs(*src, geometry, windows, status, *bounds)
        slots = [exclusive_sum(b) for b in bounds]
        written = TP.Written(np.empty((int(slots[0][-1]), 2)),
                             np.empty(int(slots[1][-1]), dtype=np.int64),
                             np.empty(int(slots[2][-1]), dtype=np.int64))
        counts = TP.PairRows(*(np.empty(n, dtype=np.int64) for _ in range(3)))
        core = core_options(options)._replace(exact=True)
        TP.write_pairs(src, geometry, windows, core, max(1, min(n, 256)), status,
                       TP.PairRows(*(s[:-1] for s in slots)), written, counts)
        fast = np.flatnonzero(status == TP.FAST)
        fast_ragged = _compact(written, [s[:-1][fast] for s in slots],
                               [c[fast] for c in counts])
        slow = np.flatnonzero(status == TP.FALLBACK)
        if slow.shape[0] == 0:  # already in pair order: no second copy
            return GeometryPieces(fast_ragged.coords, np.empty(0), fast_ragged.offsets,
                                  np.zeros((1, C.WIDTH), dtype=np.int64))
        pieces = self.clip_polygons(polygons.take(geometry[slow]),
                                    WindowTable(windows[slow],
                                                np.arange(slow.shape[0], dtype=np.int64)),
                                    options)
        slow_ragged = Ragged(GeometryKind.MULTIPOLYGON, pieces.xy, pieces.offsets)
        # Each pair's output in pair order: its fast geometry or its general one.
        row = np.empty(n, dtype=np.int64)
        row[fast] = np.arange(fast.shape[0], dtype=np.int64)
        row[slow] = fast.shape[0] + np.arange(slow.shape[0], dtype=np.int64)
        merged = fast_ragged.concat_take(slow_ragged, row)
        return GeometryPieces(merged.coords, np.empty(0), merged.offsets, pieces.counters)

    def clip_polygons(self, polygons: Ragged, windows: WindowTable, options: SegmentOptions,
                      *, device: DevicePolygons | None = None) -> GeometryPieces:
        """Return the output polygons of each geometry; see `ClipBackend.clip_polygons`.

        The polygon kernel's count pass, prefix sums and write pass. `device` is for the
        OpenCL backend, which assembles here from what its device decided: the polygons'
        classes and the rings' run decisions and pieces (its counters and stats are
        added to the result). Without it, the kernel decides everything itself.
        """
        xy, z = polygons.split_z()
        ring_offsets = polygons.offsets[0]
        polygon_offsets, geometry_polygons = polygons.item_offsets()
        n_polygons = polygon_offsets.shape[0] - 1
        polygon_window = windows.of_items(polygon_geometry(geometry_polygons))
        nothing_i = np.empty(0, dtype=np.int64)
        if device is None:
            # Runs and segments are clipped here, not decided elsewhere: no decision tables.
            decisions = PL.Decisions(False, nothing_i, np.empty(0, dtype=np.uint8), nothing_i,
                                     np.empty(0, dtype=np.bool_), np.empty((0, 6)))
            device = DevicePolygons(False, np.empty(n_polygons, dtype=np.int8),
                                    [PolygonRange(0, n_polygons, decisions)], _no_device_totals)
        has_z = z.shape[0] > 0
        vertices = R.vertices(xy, z)
        plan = (device.polygon_class, np.zeros(n_polygons, dtype=np.int64),
                np.zeros(n_polygons, dtype=np.int64))
        sizes = tuple(np.empty(n_polygons, dtype=np.int64) for _ in range(3))
        nowhere = PG.PolygonsOut(False, np.empty((0, 2)), np.empty(0), nothing_i, nothing_i)
        # Polygons are always clipped exactly: valid output needs exact cut points.
        kernel_options = core_options(options)._replace(exact=True)

        def arguments(part: PolygonRange, starts: tuple[np.ndarray, ...]) -> tuple:
            # Polygons first..end-1 alone: rings and output slots stay the call's (the
            # offsets are global), the per-polygon arrays are views of the range.
            a, b = part.first, part.end
            return (PG.Polygons(ring_offsets, polygon_offsets[a:b + 1], windows.bounds,
                                polygon_window[a:b]),
                    kernel_options, _block_size(b - a),
                    PG.PolygonPlan(device.classified, *(column[a:b] for column in plan)),
                    PG.PolygonCounts(*(column[a:b] for column in sizes),
                                     *(s[a:b] for s in starts)))

        parts = []
        for part in device.ranges:  # each as soon as the device has finished it
            rows = max(1, -(-(part.end - part.first) // _block_size(part.end - part.first)))
            parts.append((part, np.zeros((rows, C.WIDTH), dtype=np.int64)))
            PG.clip_polygon_blocks(vertices, *arguments(part, (nothing_i,) * 3), nowhere,
                                   parts[-1][1], part.decisions)
        vertex_start, ring_start, poly_start = (exclusive_sum(column) for column in sizes)
        out_xy = np.empty((int(vertex_start[-1]), 2))
        out_z = np.empty(int(vertex_start[-1]) if has_z else 0)
        out_rings = np.empty(int(ring_start[-1]) + 1, dtype=np.int64)
        out_rings[-1] = out_xy.shape[0]
        out_poly_rings = np.empty(int(poly_start[-1]), dtype=np.int64)
        out = PG.PolygonsOut(True, out_xy, out_z, out_rings, out_poly_rings)
        for part, counters in parts:
            PG.clip_polygon_blocks(vertices, *arguments(part, (vertex_start, ring_start,
                                                               poly_start)),
                                   out, counters, part.decisions)
        device_counters, device_stats = device.totals()
        return GeometryPieces(out_xy, out_z, (
            out_rings, exclusive_sum(out_poly_rings),
            group_offsets(sizes[2], geometry_polygons)),
            np.concatenate([counters for _, counters in parts] + [device_counters]),
            device_stats)

    def clip_paths(self, paths: PathArrays, windows: WindowTable, options: PathOptions,
                   *, device: DevicePaths | None = None) -> PathPieces:
        """Return each path clipped to its window; see `ClipBackend.clip_paths`.

        The path kernel's count pass, prefix sums and write pass. `device` is for the
        OpenCL backend, which assembles here from what its device decided: each segment's
        class, the runs' decisions and the flattened points of the curves accepted whole.
        Without it, the kernel decides everything itself.
        """
        clean = options.fill is not None and options.fill_output is FillOutput.CLEAN
        n_subpaths = paths.closed.shape[0]
        sub = paths.subpath_offsets
        if device is None:
            # The kernel decides each run in its count pass and keeps the decision here.
            device = DevicePaths([PathRange(0, n_subpaths, BZ.Decisions(
                False, np.empty(paths.degree.shape[0], dtype=np.int8), *_NO_CLASSES))],
                _no_device_stats)
        subpath_source = np.repeat(np.arange(len(paths), dtype=np.int64),
                                   np.diff(paths.path_offsets))
        n_segments = np.zeros(n_subpaths, dtype=np.int64)
        n_out = np.zeros(n_subpaths, dtype=np.int64)
        window_rows = _window_rows(windows)
        kernel_options = BZ.Options(
            fill=options.fill is not None, flatten=options.curves is Curves.FLATTEN,
            exact=options.mode is Mode.EXACT, n_split=int(options.n_split),
            leaf_depth=int(options.leaf_depth), tolerance=float(options.tolerance),
            clean=clean)

        def arguments(part: PathRange, starts: tuple[np.ndarray, np.ndarray]) -> tuple:
            # Subpaths first..end-1 alone, their segments from the range's first (as the
            # decisions are), their output slots the call's.
            a, b = part.first, part.end
            g0, g1 = int(sub[a]), int(sub[b])
            return (BZ.PathInput(paths.controls[g0:g1], paths.degree[g0:g1],
                                 sub[a:b + 1] - g0, paths.closed[a:b], paths.start[a:b],
                                 subpath_source[a:b]),
                    window_rows, kernel_options, part.decisions,
                    BZ.Layout(n_segments[a:b], n_out[a:b], *(s[a:b] for s in starts)))

        nothing = np.empty(0, dtype=np.int64)
        parts = []
        for part in device.ranges:  # each as soon as the device has finished it
            block = max(1, min(_PATH_BLOCK, (part.end - part.first) // _PATH_MIN_BLOCKS))
            counters = np.zeros((max(1, -(-(part.end - part.first) // block)), C.WIDTH),
                                dtype=np.int64)
            parts.append((part, block, counters))
            BZ.clip_path_blocks(*arguments(part, (nothing, nothing)),
                                BZ.Output(False, np.empty((0, 4, 2)), np.empty(0, np.int8),
                                          nothing, np.empty((0, 2)), np.empty(0, bool),
                                          nothing),
                                counters, block)
        segment_start = exclusive_sum(n_segments)
        subpath_start = exclusive_sum(n_out)
        m = int(segment_start[-1])
        k = int(subpath_start[-1])
        out_ctrl = np.empty((m, 4, 2))
        out_deg = np.empty(m, dtype=np.int8)
        out_first = np.empty(k + 1, dtype=np.int64)
        out_first[k] = m
        out_start = np.empty((k, 2))
        out_closed = np.empty(k, dtype=bool)
        out_from = np.empty(k, dtype=np.int64)
        for part, block, counters in parts:
            BZ.clip_path_blocks(*arguments(part, (segment_start, subpath_start)),
                                BZ.Output(True, out_ctrl, out_deg, out_first, out_start,
                                          out_closed, out_from),
                                np.zeros_like(counters), block)
        kept = out_from >= 0
        if not kept.all():  # entries freed by joining the two ends of a closed stroke
            out_first = np.append(out_first[:-1][kept], m)
            out_start, out_closed, out_from = out_start[kept], out_closed[kept], out_from[kept]
        path_offsets = exclusive_sum(np.bincount(out_from, minlength=len(paths)))
        clipped = PathArrays.from_kernel(controls=out_ctrl, degree=out_deg,
                                         subpath_offsets=out_first, closed=out_closed,
                                         start=out_start, path_offsets=path_offsets)
        if clean:
            clipped = clean_fills(clipped, windows, options.fill is Fill.EVENODD)
        segments_in = paths.degree.shape[0] + BZ.closing_edges(
            paths.controls, paths.subpath_offsets, paths.closed, paths.start,
            options.fill is not None)
        counters = (np.concatenate([counters for _, _, counters in parts]) if parts
                    else np.zeros((1, C.WIDTH), dtype=np.int64))
        return PathPieces(clipped, int(segments_in), counters, device.totals())

    def flatten_paths(self, paths: PathArrays, tolerance: float, close: bool) -> Polylines:
        """Return the paths as polylines within `tolerance`; see `ClipBackend.flatten_paths`."""
        steps = BZ.flatten_steps(paths.controls, paths.degree, float(tolerance))
        segment_points = exclusive_sum(steps)
        lines, closes, line_offsets = polyline_layout(paths, segment_points, close)
        coords = np.empty((int(line_offsets[-1]), 2))
        BZ.flatten_into(paths.controls, paths.degree, float(tolerance), paths.subpath_offsets,
                        paths.start, lines, closes, steps, segment_points, line_offsets, coords)
        line_path = np.repeat(np.arange(len(paths), dtype=np.int64), np.diff(paths.path_offsets))
        return Polylines(coords, line_offsets, line_path[lines])

    def encode_segment_tiles(self, pieces: np.ndarray, source: np.ndarray | None,
                             layer: TileLayer) -> TileBytes:
        """Return each window's pieces as a vector tile; see `ClipBackend.encode_segment_tiles`.

        The pieces are quantised here (NumPy, one rounding per operation) and encoded
        by the kernels of `rnsca.tiles.encode_zoom` (`kernels.mvt`): each piece a
        LINESTRING of one part of two positions, written by `feature_sizes` and
        `write_features`, each tile framed around them by `tile_sizes` and `write_tiles`.
        """
        pieces = np.ascontiguousarray(pieces, dtype=np.float64)
        window_offsets = layer.window_offsets
        k = window_offsets.shape[0] - 1
        m = pieces.shape[0]
        origin_scale = layer.quantisation[np.repeat(np.arange(k), np.diff(window_offsets))]
        with np.errstate(invalid="ignore", over="ignore"):
            unrounded = np.empty((m, 4))
            unrounded[:, 0::2] = ((pieces[:, 0::2] - origin_scale[:, 0:1]) * origin_scale[:, 2:3]
                                  + 0.5)
            unrounded[:, 1::2] = ((origin_scale[:, 1:2] - pieces[:, 1::2]) * origin_scale[:, 3:4]
                                  + 0.5)
            beyond = ~(np.abs(unrounded) < MVT_COORDINATE_LIMIT).all(axis=1)
        if beyond.any():
            row = int(np.argmax(beyond))
            raise tile_piece_error(row, int(np.searchsorted(window_offsets, row, "right")) - 1,
                                   pieces[row])
        lines = MVT.Shapes(np.floor(unrounded).astype(np.int64).reshape(-1, 2),
                           np.arange(0, 2 * m + 1, 2, dtype=np.int64),
                           np.arange(m + 1, dtype=np.int64), _NO_INDEX)
        features = MVT.Features(
            np.full(m, MVT.LINESTRING, dtype=np.int8), np.arange(m, dtype=np.int64),
            np.full(m, -1, dtype=np.int64) if source is None
            else np.ascontiguousarray(source, dtype=np.int64),
            np.zeros(m + 1, dtype=np.int64), np.empty(0, dtype=np.uint32))
        sizes = np.empty(m, dtype=np.int64)
        geometry_bytes = np.empty(m, dtype=np.int64)
        MVT.feature_sizes(features, _NO_SHAPES, lines, _NO_SHAPES, _NO_SHAPES, sizes,
                          geometry_bytes)
        starts = exclusive_sum(sizes)
        written = np.empty(int(starts[-1]), dtype=np.uint8)
        MVT.write_features(features, _NO_SHAPES, lines, _NO_SHAPES, _NO_SHAPES, starts, sizes,
                           geometry_bytes, written)
        holding, ranges, offsets = MVT.segment_tile_layout(starts[window_offsets],
                                                           layer.head, layer.tail)
        data = np.empty(int(offsets[-1]), dtype=np.uint8)
        # The tiles holding features are back to back (the others are empty).
        MVT.write_tiles(layer.head, layer.tail, written, _NO_BYTES, _NO_BYTES, ranges,
                        np.append(offsets[holding], offsets[-1]), data)
        return TileBytes(data, offsets)

    def warm_up(self) -> None:
        """Compile (or load from the cache) the kernels, so the first real call is fast."""
        warm_up_segments(self)
        warm_up_geometry(self)
        warm_up_paths(self)
        warm_up_tiles(self)


def warm_up_segments(backend: ClipBackend) -> None:
    """Clip segments on `backend` with every method, through both drivers of the Numba one.

    Then against many windows: a grid (found by arithmetic) and a set of two (a sweep).
    """
    window = Window(0.0, 0.0, 1.0, 1.0)
    for n in (1, BLOCK_SIZE * (SERIAL_BLOCKS + 1)):  # the serial and the parallel driver
        segments = np.tile([[-1.0, 0.5, 2.0, 0.5]], (n, 1))
        for method in Method:
            backend.clip_segments(segments, window, SegmentOptions.resolve(window, method=method))
    segments = np.array([[-1.0, 0.5, 2.0, 0.5], [0.2, 0.2, 0.8, 0.3]])
    grid = np.array([[0.0, 0.0, 0.5, 1.0], [0.5, 0.0, 1.0, 1.0]])
    for windows in (grid, grid[[0, 0]] + [[0.0, 0.0, 0.0, 0.5], [0.1, 0.0, 0.0, 0.0]]):
        for method in (Method.RNSCA, Method.LIANG_BARSKY):
            backend.clip_segment_windows(segments, windows,
                                         SegmentOptions.resolve(window, method=method))


def warm_up_tiles(backend: ClipBackend) -> None:
    """Encode two tiles of pieces on `backend`, with ids and without (one tile empty)."""
    pieces = np.array([[0.0, 0.0, 0.5, 1.0], [0.5, 0.5, 0.5, 0.5]])
    layer = TileLayer(np.array([0, 2, 2], dtype=np.int64),
                      np.array([[0.0, 1.0, 16.0, 16.0], [1.0, 1.0, 16.0, 16.0]]),
                      np.array([0x0A, 0x01, 0x73], dtype=np.uint8),
                      np.array([0x28, 0x10, 0x78, 0x02], dtype=np.uint8))
    for source in (np.array([3, 4], dtype=np.int64), None):
        backend.encode_segment_tiles(pieces, source, layer)


def warm_up_paths(backend: ClipBackend) -> None:
    """Clip and flatten Bézier paths on `backend` in each curve handling, fill and mode.

    Three subpaths: lines, quadratic and cubic curves crossing the window, and a closed
    one (``M-1 .5 C0 2 1-1 2 .5 Q.5 3-1 .5Z``, ``M-1 .25 H2 V.75Z``, ``M.2 .2 L.8 .8``).
    """
    cubic = [[-1.0, 0.5], [0.0, 2.0], [1.0, -1.0], [2.0, 0.5]]
    quadratic = [[2.0, 0.5], [0.5, 3.0], [-1.0, 0.5], [-1.0, 0.5]]
    square = [[[-1.0, 0.25], [2.0, 0.25]], [[2.0, 0.25], [2.0, 0.75]]]
    paths = PathArrays(
        controls=np.array([cubic, quadratic]
                          + [[a, b, b, b] for a, b in square] + [[[0.2, 0.2], [0.8, 0.8],
                                                                    [0.8, 0.8], [0.8, 0.8]]]),
        degree=np.array([3, 2, 1, 1, 1], dtype=np.int8),
        subpath_offsets=np.array([0, 2, 4, 5], dtype=np.int64),
        closed=np.array([True, True, False]), start=np.array([[-1.0, 0.5], [-1.0, 0.25],
                                                              [0.2, 0.2]]),
        path_offsets=np.array([0, 1, 2, 3], dtype=np.int64))
    window = Window(0.0, 0.0, 1.0, 1.0)
    for curves, fill, mode in (("preserve", None, "exact"), ("preserve", "nonzero", "exact"),
                               ("flatten", None, "exact"), ("preserve", None, "approx")):
        backend.clip_paths(paths, WindowTable.of(window, len(paths)),
                           PathOptions.resolve(window, curves=curves, fill=fill, mode=mode))
    backend.flatten_paths(paths, 1e-3, True)


def _window_rows(windows: WindowTable) -> R.WindowRows:
    """Return the kernels' form of `windows` (one row for all: an empty index)."""
    bounds = np.ascontiguousarray(windows.bounds, dtype=np.float64)
    if bounds.shape[0] == 1:
        return R.WindowRows(bounds, np.empty(0, dtype=np.int64))
    return R.WindowRows(bounds, np.ascontiguousarray(windows.index, dtype=np.int64))


def clean_fills(clipped: PathArrays, windows: Window | WindowTable,
                evenodd: bool) -> PathArrays:
    """Return the fill clip's output rebuilt as simple rings (`kernels.fill_rings`).

    `windows`: the window of every path, or a `WindowTable` of one per path.

    The same count, prefix-sum, write passes as the clip, over paths. Host code for both
    backends: the OpenCL backend's paths are assembled by `NumbaBackend.clip_paths` too.
    """
    n = len(clipped)
    kernel_input = (FR.FillPaths(clipped.controls, clipped.degree, clipped.subpath_offsets,
                                 clipped.path_offsets),
                    _window_rows(WindowTable.of(windows, n) if isinstance(windows, Window)
                                 else windows))
    n_segments = np.zeros(n, dtype=np.int64)
    n_rings = np.zeros(n, dtype=np.int64)
    nothing = np.empty(0, dtype=np.int64)
    block = max(1, min(_PATH_BLOCK, n // _PATH_MIN_BLOCKS))
    FR.clean_fill_paths(*kernel_input, FR.RingLayout(n_segments, n_rings, nothing, nothing),
                        FR.RingOutput(False, np.empty((0, 4, 2)), np.empty(0, np.int8),
                                      nothing, np.empty((0, 2))), block, evenodd)
    if (n_rings < 0).any():  # the edge lines of a path do not add up: a bug, not the input
        raise RuntimeError(f"clean fill: the clip of path {int(np.argmax(n_rings < 0))} is "
                           "not closed along the window's boundary (please report)")
    segment_start = exclusive_sum(n_segments)
    ring_start = exclusive_sum(n_rings)
    m = int(segment_start[-1])
    k = int(ring_start[-1])
    controls = np.empty((m, 4, 2))
    degree = np.empty(m, dtype=np.int8)
    first = np.empty(k + 1, dtype=np.int64)
    first[k] = m
    start = np.empty((k, 2))
    FR.clean_fill_paths(*kernel_input,
                        FR.RingLayout(n_segments, n_rings, segment_start, ring_start),
                        FR.RingOutput(True, controls, degree, first, start), block, evenodd)
    return PathArrays.from_kernel(controls=controls, degree=degree, subpath_offsets=first,
                                  closed=np.ones(k, dtype=bool), start=start,
                                  path_offsets=ring_start)


def polyline_layout(paths: PathArrays, segment_points: np.ndarray,
                    close: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return where each subpath's polyline goes when paths are flattened.

    `segment_points` are the offsets of each segment's flattened points (after the
    subpath's start). Returns ``(lines, closes, line_offsets)``: the subpaths that have
    a segment (one polyline each), whether each subpath's polyline returns to its start,
    and the point offsets of the polylines.
    """
    sub = paths.subpath_offsets
    has_line = np.diff(sub) > 0
    closes = has_line & (paths.closed | close)
    ends = paths.start.copy()
    ends[has_line] = paths.controls[sub[1:][has_line] - 1, 3]
    closes &= (ends != paths.start).any(axis=1)
    points_per_line = segment_points[sub[1:]] - segment_points[sub[:-1]] + has_line + closes
    line_offsets = exclusive_sum(points_per_line[has_line])
    if line_offsets[-1] > MAX_FLATTENED_POINTS:
        raise LimitExceededError(
            f"flattening these paths within the tolerance asked for gives "
            f"{int(line_offsets[-1])} points, more than the limit of {MAX_FLATTENED_POINTS}: "
            "use a larger tolerance")
    return np.flatnonzero(has_line), closes, line_offsets


def polygon_geometry(geometry_polygons: np.ndarray) -> np.ndarray:
    """Return the geometry of each polygon, given the polygon offsets of the geometries."""
    return np.repeat(np.arange(geometry_polygons.shape[0] - 1, dtype=np.int64),
                     np.diff(geometry_polygons))


def warm_up_geometry(backend: ClipBackend) -> None:
    """Clip lines and polygons on `backend`: `warm_up_lines`, then `warm_up_polygons`."""
    warm_up_lines(backend)
    warm_up_polygons(backend)


def _warm_up_rings() -> tuple[list[np.ndarray], np.ndarray, np.ndarray, WindowTable,
                              SegmentOptions]:
    """Return one square ring across the unit window, 2D and 3D, and what clips it."""
    ring = [[-1.0, 0.25], [2.0, 0.25], [2.0, 0.75], [-1.0, 0.75], [-1.0, 0.25]]
    coords = [np.array(ring), np.array([[x, y, 0.0] for x, y in ring])]
    window = Window(0.0, 0.0, 1.0, 1.0)
    return (coords, np.array([0, 5], dtype=np.int64), np.array([0, 1], dtype=np.int64),
            WindowTable.of(window, 1), SegmentOptions.resolve(window))


def warm_up_lines(backend: ClipBackend) -> None:
    """Clip lines on `backend` (a square ring as a line, 2D and 3D, edge runs kept or not).

    Every kernel specialisation a line clip uses is compiled (or loaded) by it.
    """
    coords_2d_3d, offsets, one, windows, options = _warm_up_rings()
    for coords in coords_2d_3d:
        for kind, levels in ((GeometryKind.LINESTRING, (offsets,)),
                             (GeometryKind.MULTILINESTRING, (offsets, one))):
            for drop in (False, True):
                backend.clip_lines(Ragged.of(kind, coords, levels), windows, options, drop)


def warm_up_polygons(backend: ClipBackend) -> None:
    """Clip a polygon on `backend` (a square across the window, 2D and 3D)."""
    coords_2d_3d, offsets, one, windows, options = _warm_up_rings()
    for coords in coords_2d_3d:
        backend.clip_polygons(Ragged.of(GeometryKind.POLYGON, coords, (offsets, one)),
                              windows, options)


def core_options(options: SegmentOptions) -> R.CoreOptions:
    """Return the kernels' record of the segment core's options (one type per field)."""
    return R.CoreOptions(METHOD_ID[options.method], int(options.n), int(options.max_depth),
                         float(options.tolerance),
                         options.mode is Mode.EXACT)


def _no_device_stats() -> None:
    """Return the stats of no device: none."""
    return None


def _no_device_totals() -> tuple[np.ndarray, None]:
    """Return the counters and stats of no device: none."""
    return np.zeros((0, C.WIDTH), dtype=np.int64), None


def _block_size(n_items: int) -> int:
    """Return items per prange block: about 64 blocks for load balance, 1..1024 items each."""
    return max(1, min(1024, -(-n_items // 64)))


def _compact(written: TP.Written, starts: list[np.ndarray], counts: list[np.ndarray]
             ) -> Ragged:
    """Return the MULTIPOLYGON array of the pairs written into slots (`starts`, `counts`)."""
    taken = [exclusive_sum(c) for c in counts]
    coords = np.empty((int(taken[0][-1]), 2))
    copy_ranges(written.out, starts[0], counts[0], taken[0][:-1], coords)
    levels = []
    for source, start, count, at in zip((written.ring_len, written.poly_rings), starts[1:],
                                        counts[1:], taken[1:], strict=True):
        gathered = np.empty((int(at[-1]), 1), dtype=np.int64)
        copy_ranges(source.reshape(-1, 1), start, count, at[:-1], gathered)
        levels.append(exclusive_sum(gathered[:, 0]))
    return Ragged(GeometryKind.MULTIPOLYGON, coords, (levels[0], levels[1], taken[2]))
