"""Clip ragged geometry arrays: take the levels apart, run the kernels, put them back.

Every kind comes down to one of three kernels: points (a mask), lines (each part cut
into chains, `kernels/polylines.py`) and polygons (rings cut and closed along the
window, `kernels/polygons.py`). The kernels see parts, rings and polygons with the
index of their window; this module maps geometries onto those and the results back
onto geometries, with `source` saying which input each output geometry came from.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any, SupportsIndex

import numpy as np
import numpy.typing as npt
import shapely

from rnsca.arrays import GeometryKind, Ragged, exclusive_sum, to_shapely
from rnsca.backends.auto import backend_for
from rnsca.backends.base import ClipBackend, GeometryPieces, Operation
from rnsca.errors import InvalidOptionError, InvalidWindowError
from rnsca.kernels import counters as C
from rnsca.many_windows import WindowPairs, as_windows, assign_boxes, vertex_boxes
from rnsca.options import Backend, Boundary, Method, Mode, SegmentOptions
from rnsca.stats import ClipStats, DeviceStats
from rnsca.window import Window, WindowTable

__all__ = ["RaggedClipResult", "clip_ragged", "resolve_geometry_options"]


@dataclass(frozen=True, slots=True)
class RaggedClipResult:
    """Clipped geometries as a ragged array, with where each came from.

    Attributes
    ----------
    geometry_type : shapely.GeometryType
        The output kind: as the input, except that LINESTRING and POLYGON become
        MULTILINESTRING and MULTIPOLYGON when some geometry is cut into several parts.
    coords : ndarray of float64, shape (m, 2) or (m, 3)
    offsets : tuple of ndarray of int64
        Innermost level first, as ``shapely.from_ragged_array`` takes them.
    source : ndarray of int64
        Index of the input geometry of each output geometry (increasing; with
        ``windows=``, increasing within each window).
    stats : ClipStats
    window : ndarray of int64, or None
        With ``windows=``: the window of each output geometry (its row in `windows`); the
        outputs are sorted by window, then source. None for one window (or one per
        geometry).
    window_offsets : ndarray of int64, shape (k + 1,), or None
        With ``windows=``: window ``w``'s outputs are ``window_offsets[w]:window_offsets[w
        + 1]``.
    """

    geometry_type: shapely.GeometryType
    coords: np.ndarray
    offsets: tuple
    source: np.ndarray
    stats: ClipStats
    window: np.ndarray | None = None
    window_offsets: np.ndarray | None = None

    def __len__(self) -> int:
        return self.source.shape[0]

    def __iter__(self) -> Iterator[Any]:
        """Unpack as ``geometry_type, coords, offsets, source, stats``."""
        return iter((self.geometry_type, self.coords, self.offsets, self.source, self.stats))

    def to_shapely(self) -> np.ndarray:
        """Return the output geometries as a Shapely array."""
        return to_shapely(self.geometry_type, self.coords, self.offsets)


def _with_z(xy: np.ndarray, z: np.ndarray, has_z: bool) -> np.ndarray:
    if not has_z:
        return xy
    return np.ascontiguousarray(np.column_stack([xy, z]))


def resolve_geometry_options(
        windows: WindowTable, dimension: int, *, boundary: Boundary | str = "closed",
        method: Method | str = "rnsca", n: SupportsIndex | str = "auto",
        max_depth: SupportsIndex | None = None, tolerance: float | None = None,
        mode: Mode | str = "exact", backend: Backend | str = "numba",
        resolution: float | str | None = None, size: int = 0,
) -> tuple[SegmentOptions, Boundary, ClipBackend]:
    """Return ``(SegmentOptions, Boundary, backend)`` for clipping geometry of `dimension`.

    Default tolerances follow the smallest of the `windows`.

    Raises
    ------
    InvalidOptionError
        For a bad option, or ``mode="approx"`` with polygons (dimension 2).
    BackendUnavailableError
        For a backend that cannot run here or does not clip this kind.
    """
    options = SegmentOptions.resolve(windows.smallest(), method=method, n=n,
                                     max_depth=max_depth, tolerance=tolerance, mode=mode,
                                     resolution=resolution)
    side = Boundary(boundary)
    engine = backend_for(backend, "lines" if dimension == 1 else "polygons", size)
    if dimension == 2 and options.mode not in Operation.POLYGONS.modes:
        raise InvalidOptionError(
            "mode='approx' cannot clip polygons: valid polygon output needs the exact "
            "boundary crossings (use mode='exact')")
    if dimension > 0:
        engine.capabilities.require(
            Operation.LINES if dimension == 1 else Operation.POLYGONS, options.mode)
    return options, side, engine


def clip_ragged(geometry_type: shapely.GeometryType | GeometryKind | str, coords: npt.ArrayLike,
                offsets: Sequence[npt.ArrayLike],
                window: Window | Iterable[float] | Iterable[Iterable[float]] | None = None,
                *, windows: npt.ArrayLike | None = None,
                boundary: Boundary | str = "closed", keep_empty: bool = False,
                check_validity: bool = False, method: Method | str = "rnsca",
                n: SupportsIndex | str = "auto", max_depth: SupportsIndex | None = None,
                tolerance: float | None = None, mode: Mode | str = "exact",
                backend: Backend | str = "numba",
                resolution: float | str | None = None,
                partial_z: bool = False) -> RaggedClipResult:
    """Return the geometries of a ragged array clipped to a rectangular window.

    The columnar fast path: the triple ``shapely.to_ragged_array`` returns (and GeoArrow
    stores) in, the same layout out.

    Parameters
    ----------
    geometry_type : shapely.GeometryType, GeometryKind or str
        POINT, LINESTRING, POLYGON or their MULTI kinds (names case-insensitive).
    coords : array_like, shape (n, 2) or (n, 3)
        Finite coordinates; Z is kept on input vertices and interpolated linearly on
        new ones (along the boundary for the corners a polygon gains).
    offsets : tuple of array_like of int
        Innermost level first; polygon rings closed, with at least four positions.
    window : Window, sequence of 4 floats, or array_like of shape (G, 4)
        One window for all, or one per input geometry.
    windows : array_like, shape (k, 4), optional
        Many windows instead of `window`: every geometry is clipped against every window
        its bounding box touches, in one call, and the result says the window of each
        output (``window``, ``window_offsets``; sorted by window, then source). The
        (geometry, window) pairs come from `rnsca.many_windows.assign_boxes` (a regular
        grid of windows by arithmetic, other sets by a sweep); the pairs' geometries are
        gathered into one ragged array and clipped with one window each. Default
        tolerances follow the smallest window; the stats count pairs as inputs.
    boundary : {"closed", "interior"}
        "closed" keeps parts lying on the window's edge (``shapely.intersection``);
        "interior" drops points on the edge and line parts that only run along it
        (``shapely.clip_by_rect``). Polygon results are the same under both. Results
        keep the input's dimension: a line touching the window at a point, or a polygon
        sharing only an edge with it, gives nothing.
    keep_empty : bool
        Keep one output geometry per input (empty where nothing is left) instead of
        dropping the empty ones; with ``windows=``, one per (geometry, window) pair whose
        boxes touch.
    check_validity : bool
        Polygons: count invalid inputs in ``stats.invalid_polygons`` with GEOS
        (``shapely.is_valid``, a full check that costs more than the clip). Without it,
        the count holds what clipping meets: rings without area and rings that cannot
        be closed consistently. Invalid polygons are clipped ring by ring either way,
        never repaired.
    method, n, max_depth, tolerance, mode, resolution
        As for `clip_segments`; runs of vertices are pruned by RNSCA with N runs per
        split (``n="auto"``: 16). Polygons need ``mode="exact"``.
    backend : {"numba", "opencl", "auto"}
        ``"auto"``: OpenCL where it measured faster than Numba here for this operation
        and size (a calibration at the first such call, cached; `rnsca.backends.auto`).
        OpenCL: the run pruning of lines and rings and the clip of their undecided
        segments on the device; chains and polygons assembled on the host (Numba).
    partial_z : bool
        False (default): every coordinate must be finite. True: a Z may be NaN, for a
        position without one (a 2D position among 3D ones, as GeoJSON allows). It
        propagates: an input vertex keeps its NaN, and a new vertex whose Z is computed
        from a NaN (a cut point on a segment with such an end, a corner interpolated
        from one, the corners of a window covered by a shell that has one) gets NaN.
        X and Y must still be finite, Z not infinite.

    Returns
    -------
    RaggedClipResult

    Raises
    ------
    InvalidGeometryError, InvalidWindowError, InvalidOptionError
        (ValueError) naming what is wrong and where.
    UnsupportedGeometryError
        For an unknown geometry type.
    BackendUnavailableError
        For a backend that does not clip geometry (NumPy).

    Examples
    --------
    >>> import shapely
    >>> line = shapely.LineString([(-5, 1), (5, 1), (5, 20), (8, 20), (8, 5), (15, 5)])
    >>> r = clip_ragged(*shapely.to_ragged_array([line]), (0, 0, 10, 10))
    >>> r.to_shapely()[0].wkt
    'MULTILINESTRING ((0 1, 5 1, 5 10), (8 10, 8 5, 10 5))'
    """
    kind = GeometryKind.of(geometry_type)
    if (window is None) == (windows is None):
        raise InvalidWindowError("give one of window= and windows=")
    # Lines are checked for non-finite coordinates by the clip's first pass over them
    # (with many windows, here: the pairs are found from the boxes).
    ragged = Ragged.of(kind, coords, offsets,
                       check_finite=kind.dimension != 1 or windows is not None,
                       partial_z=partial_z)
    # One body for one window and many (the pairs' geometries, one window each): the
    # service's path to the kernel stays short (tests/service/test_hops.py).
    pairs = None
    if windows is not None:
        ragged, table, pairs = _pair_windows(ragged, as_windows(windows))
    else:
        assert window is not None
        table = WindowTable.of(window, ragged.count)
    options, side, engine = resolve_geometry_options(
        table, ragged.kind.dimension, boundary=boundary, method=method, n=n,
        max_depth=max_depth, tolerance=tolerance, mode=mode, backend=backend,
        resolution=resolution, size=ragged.coords.shape[0])
    if ragged.kind.dimension == 0:
        result = _clip_points(ragged, table, side, keep_empty)
    elif ragged.kind.dimension == 1:
        result = _line_result(ragged, engine.clip_lines(ragged, table, options,
                                                        side is Boundary.INTERIOR), keep_empty)
    else:
        result = _polygon_result(ragged, engine.clip_polygons(ragged, table, options),
                                 keep_empty)
        if check_validity:
            invalid = int((~shapely.is_valid(ragged.to_shapely())).sum())
            result = replace(result, stats=replace(result.stats, invalid_polygons=invalid))
    return result if pairs is None else _window_result(result, pairs, table)


def _pair_windows(ragged: Ragged, bounds: np.ndarray
                  ) -> tuple[Ragged, WindowTable, WindowPairs]:
    """Return the (geometry, window) pairs' geometries, their windows and the pairs."""
    pairs = assign_boxes(vertex_boxes(ragged.coords, ragged.vertex_offsets()), bounds)
    pair_window = np.repeat(np.arange(bounds.shape[0], dtype=np.int64),
                            np.diff(pairs.window_offsets))
    return ragged.take(pairs.segment), WindowTable(bounds, pair_window), pairs


def _window_result(result: RaggedClipResult, pairs: WindowPairs,
                   table: WindowTable) -> RaggedClipResult:
    """Name each output of the pairs' clip by its source geometry and its window."""
    window = table.index[result.source]
    return replace(result, source=pairs.segment[result.source], window=window,
                   window_offsets=exclusive_sum(np.bincount(
                       window, minlength=table.bounds.shape[0])))


def _stats(counters: np.ndarray, segments_in: int, pieces_out: int, ragged: Ragged,
           vertices_out: int, geometries_out: int, device: DeviceStats | None) -> ClipStats:
    return ClipStats.from_counters(
        counters, segments_in, pieces_out, geometries_in=ragged.count,
        geometries_out=geometries_out, vertices_in=ragged.coords.shape[0],
        vertices_out=vertices_out, device=device)


def _clip_points(ragged: Ragged, windows: WindowTable, side: Boundary,
                 keep_empty: bool) -> RaggedClipResult:
    xy = ragged.coords
    count = ragged.count
    if ragged.kind is GeometryKind.POINT:
        geometry_of_point = np.arange(count, dtype=np.int64)
    else:
        geometry_of_point = np.repeat(np.arange(count, dtype=np.int64),
                                      np.diff(ragged.offsets[0]))
    w = windows.bounds[windows.index[geometry_of_point]]
    x = xy[:, 0]
    y = xy[:, 1]
    if side is Boundary.CLOSED:
        inside = (x >= w[:, 0]) & (x <= w[:, 2]) & (y >= w[:, 1]) & (y <= w[:, 3])
    else:
        inside = (x > w[:, 0]) & (x < w[:, 2]) & (y > w[:, 1]) & (y < w[:, 3])
    per_geometry = np.bincount(geometry_of_point[inside], minlength=count).astype(np.int64)
    kept = xy[inside]
    stats = ClipStats.from_counters(
        np.zeros((1, C.WIDTH), dtype=np.int64), 0, int(inside.sum()), geometries_in=count,
        geometries_out=int((per_geometry > 0).sum()), vertices_in=xy.shape[0],
        vertices_out=int(inside.sum()))
    if ragged.kind is GeometryKind.POINT:
        if keep_empty:
            out = np.full_like(xy, np.nan)
            out[inside] = xy[inside]
            return RaggedClipResult(ragged.kind.shapely_type, out, (), np.arange(count), stats)
        return RaggedClipResult(ragged.kind.shapely_type, np.ascontiguousarray(kept), (),
                                np.flatnonzero(inside).astype(np.int64), stats)
    offsets = np.concatenate([[0], np.cumsum(per_geometry)]).astype(np.int64)
    source = np.arange(count, dtype=np.int64)
    if not keep_empty:
        source = np.flatnonzero(per_geometry > 0).astype(np.int64)
        offsets = np.concatenate([[0], np.cumsum(per_geometry[source])]).astype(np.int64)
    return RaggedClipResult(ragged.kind.shapely_type, np.ascontiguousarray(kept), (offsets,),
                            source, stats)


def _line_result(ragged: Ragged, out: GeometryPieces, keep_empty: bool) -> RaggedClipResult:
    """Return the result of lines clipped into `out`: one output geometry per input kept."""
    part_offsets, _ = ragged.item_offsets()
    xy = ragged.coords
    chain_offsets, geometry_chains = out.offsets
    chains_per_geometry = np.diff(geometry_chains)
    # Parts of one position are refused by `Ragged.of`: every part but an empty one has
    # one segment fewer than positions.
    segments_in = xy.shape[0] - int(np.count_nonzero(np.diff(part_offsets)))
    count = chains_per_geometry.shape[0]
    source = np.flatnonzero(chains_per_geometry)
    stats = _stats(out.counters, segments_in, chain_offsets.shape[0] - 1, ragged,
                   out.xy.shape[0], source.shape[0], out.device)
    coords = _with_z(out.xy, out.z, ragged.has_z)
    if keep_empty or source.shape[0] == count:
        source = np.arange(count, dtype=np.int64)
        geometry_offsets = geometry_chains
    else:
        # Dropped geometries own no chain: the chain offsets stay as they are.
        geometry_offsets = np.empty(source.shape[0] + 1, dtype=np.int64)
        geometry_offsets[0] = 0
        geometry_offsets[1:] = geometry_chains[source + 1]
    if ragged.kind is GeometryKind.LINESTRING and (count == 0 or chains_per_geometry.max() <= 1):
        # At most one chain each: the chain offsets, one per geometry (empty ones repeat).
        return RaggedClipResult(ragged.kind.shapely_type, coords,
                                (chain_offsets[geometry_offsets],), source, stats)
    return RaggedClipResult(GeometryKind.MULTILINESTRING.shapely_type, coords,
                            (chain_offsets, geometry_offsets), source, stats)


def _polygon_result(ragged: Ragged, out: GeometryPieces, keep_empty: bool) -> RaggedClipResult:
    """Return the result of polygons clipped into `out`: one output per input kept."""
    ring_offsets = ragged.offsets[0]
    out_rings, output_ring_offsets, geometry_offsets = out.offsets
    per_geometry = np.diff(geometry_offsets)
    segments_in = int(np.maximum(np.diff(ring_offsets) - 1, 0).sum())
    stats = _stats(out.counters, segments_in, out_rings.shape[0] - 1, ragged, out.xy.shape[0],
                   int((per_geometry > 0).sum()), out.device)
    coords = _with_z(out.xy, out.z, ragged.has_z)
    count = ragged.count
    source = np.arange(count, dtype=np.int64)
    if not keep_empty:
        source = np.flatnonzero(per_geometry > 0).astype(np.int64)
        geometry_offsets = np.concatenate([[0], np.cumsum(per_geometry[source])]).astype(np.int64)
    if ragged.kind is GeometryKind.POLYGON and (count == 0 or per_geometry.max() <= 1):
        return RaggedClipResult(ragged.kind.shapely_type, coords,
                                (out_rings, output_ring_offsets[geometry_offsets]), source,
                                stats)
    return RaggedClipResult(GeometryKind.MULTIPOLYGON.shapely_type, coords,
                            (out_rings, output_ring_offsets, geometry_offsets), source, stats)
