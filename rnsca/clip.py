"""The public clipping functions: validate, dispatch to a backend, nothing else."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, SupportsIndex, cast

import numpy as np
import numpy.typing as npt

from rnsca.arrays import GeometryKind, check_segment_values, geometry_error
from rnsca.backends.auto import backend_for
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    UnsupportedGeometryError,
)
from rnsca.kernels.validate import all_finite
from rnsca.many_windows import as_windows
from rnsca.options import Backend, Method, Mode, SegmentOptions
from rnsca.ragged import clip_ragged, resolve_geometry_options
from rnsca.stats import ClipStats
from rnsca.window import Window, WindowTable

__all__ = ["SegmentClipResult", "WindowsClipResult", "clip_segments", "as_segments", "clip",
           "SEGMENT_OUTPUTS"]

#: What `clip_segments` can return (``outputs``).
SEGMENT_OUTPUTS = ("segments", "source", "t")


@dataclass(frozen=True, slots=True)
class SegmentClipResult:
    """The visible pieces of clipped segments.

    Attributes
    ----------
    segments : ndarray of float64, shape (m, 4)
        ``[x0, y0, x1, y1]`` of each piece, in input order and direction, inside the window.
        For device input (OpenCL), a ``pyopencl.array.Array`` in the device's precision.
    source : ndarray of int64, shape (m,), or None
        Index of the input segment each piece came from (strictly increasing); None
        where ``outputs`` leaves it out.
    t : ndarray of float64, shape (m, 2), or None
        Parameter interval ``[t0, t1]`` of each piece on its source segment, where
        ``P(t) = P0 + t (P1 - P0)``; use it to interpolate attributes. None where
        ``outputs`` leaves it out.
    stats : ClipStats
    method, mode, backend : Method, Mode, Backend
        What ran.
    options : SegmentOptions
        The resolved options (defaults filled in).
    window : ndarray of int32, shape (m,), or None
        With ``windows=``: the window of each piece (its row in `windows`); the pieces
        are sorted by window, then source. None for one window.
    window_offsets : ndarray of int64, shape (k + 1,), or None
        With ``windows=``: window ``w``'s pieces are rows
        ``window_offsets[w]:window_offsets[w + 1]``.
    """

    segments: Any
    source: Any
    t: Any
    stats: ClipStats
    method: Method
    mode: Mode
    backend: Backend
    options: SegmentOptions
    window: Any = None
    window_offsets: np.ndarray | None = None

    def __len__(self) -> int:
        return self.segments.shape[0]


def as_segments(segments: npt.ArrayLike, *, check_values: bool = True) -> np.ndarray:
    """Return `segments` as a validated float64 (n, 4) C-contiguous array.

    Accepts (n, 4) ``[x0, y0, x1, y1]`` rows or (n, 2, 2) ``[[x0, y0], [x1, y1]]``, of any
    real numeric dtype (converted to float64). ``check_values=False`` leaves the values
    to the backend (`ClipBackend.clip_segments` checks them in its own pass).

    Raises
    ------
    InvalidGeometryError
        (a ValueError) for another shape or dtype, a NaN or infinite coordinate, or a
        segment whose coordinate differences overflow float64; the message (and the
        ``row`` attribute) names the first bad row.
    """
    try:
        array = np.asarray(segments)
    except (TypeError, ValueError) as exc:
        raise InvalidGeometryError(f"segments must be a numeric array: {exc}") from None
    if array.dtype.kind not in "iuf":
        raise InvalidGeometryError(
            f"segments must have a real numeric dtype (float64 preferred), got {array.dtype}")
    if array.ndim == 3 and array.shape[1:] == (2, 2):
        array = array.reshape(array.shape[0], 4)
    elif array.ndim == 1 and array.shape[0] == 0:
        array = array.reshape(0, 4)
    elif not (array.ndim == 2 and array.shape[1] == 4):
        raise InvalidGeometryError(
            f"segments must have shape (n, 4) or (n, 2, 2), got {array.shape}")
    array = np.ascontiguousarray(array, dtype=np.float64)
    if check_values:
        check_segment_values(array)
    return array


def clip_segments(segments: npt.ArrayLike, window: Window | Iterable[float] | None = None, *,
                  windows: npt.ArrayLike | None = None,
                  method: Method | str = "rnsca", n: SupportsIndex | str = "auto",
                  max_depth: SupportsIndex | None = None, tolerance: float | None = None,
                  mode: Mode | str = "exact", backend: Backend | str = "numba",
                  resolution: float | str | None = None,
                  outputs: Iterable[str] = SEGMENT_OUTPUTS) -> SegmentClipResult:
    """Return the parts of line segments inside a closed rectangular window.

    Each segment gives at most one piece (the window is convex). Boundary rules, the
    same for every method: a segment lying on an edge is inside; a segment that only
    touches the window at one point gives no piece; a zero-length segment inside is
    kept; no output coordinate lies outside the window.

    Parameters
    ----------
    segments : array_like, shape (n, 4) or (n, 2, 2), or pyopencl.array.Array
        ``[x0, y0, x1, y1]`` per segment; finite; converted to float64. With
        ``backend="opencl"``, an (n, 4) device array in the device's precision stays on
        the device, and so do the pieces (see README, "Data kept on the device"); with
        ``windows=`` too: the pairs are found and clipped there, and `segments`,
        `source`, `t` and ``window`` come back as device arrays (``window_offsets`` on
        the host).
    window : Window or sequence of 4 floats
        ``(xmin, ymin, xmax, ymax)``.
    windows : array_like, shape (k, 4), optional
        Many windows instead of `window`: every segment is clipped against every window
        its bounding box touches, in one call; the result says the window of each piece
        (``window``, ``window_offsets``). A regular grid of windows (the cells between
        sorted x and y edges, any order) is recognised and found by arithmetic; other
        sets by a sweep. Default tolerances follow the smallest window.
    method : {"rnsca", "cohen_sutherland", "liang_barsky", "nicholl_lee_nicholl", "midpoint"}
    n : int in 2..64 or "auto"
        Pieces per subdivision (RNSCA). ``"auto"`` picks it per piece from the piece's
        length and the window's size (see README, "Choosing N").
    max_depth : int in 0..32, default 32
        Deepest subdivision level (RNSCA, midpoint).
    tolerance : float > 0 (may be inf), optional
        A piece no longer than this is a leaf. Default: the `resolution` in approx mode;
        infinite in exact mode, where splitting cannot save the clip at a boundary
        crossing, so every segment is decided at level 0 (see README, "Exact mode").
    mode : {"exact", "approx"}
        What happens to undecided leaves: clipped with Liang–Barsky, or dropped. In
        approx mode the length lost at each boundary crossing is at most one leaf,
        ``max(tolerance, length / 2**max_depth)``-ish; see README, "Approx mode".
        The analytic methods (Cohen–Sutherland, Liang–Barsky, NLN) are always exact.
    backend : {"numba", "opencl", "auto"}
        ``"auto"``: OpenCL where it measured faster than Numba here for this operation
        and size (a calibration at the first such call, cached; `rnsca.backends.auto`).
    resolution : float > 0 or str, optional
        Approx mode: the output's resolution, which sets the tolerance: a length in
        output units, or ``"<k>px"``, the window's longer side as k pixels. Default
        ``"4096px"`` (a vector tile's grid). Not with `tolerance`, nor in exact mode.
    outputs : iterable of {"segments", "source", "t"}
        The outputs to compute; those left out are None in the result. ``"segments"``
        is always computed. On a device, leaving out ``source`` and ``t`` saves their
        writes and transfers (a third of the bytes back).

    Returns
    -------
    SegmentClipResult

    Raises
    ------
    InvalidGeometryError, InvalidWindowError, InvalidOptionError
        (all ValueError) naming what is wrong.
    BackendUnavailableError
        If `backend` cannot run here.

    Examples
    --------
    >>> r = clip_segments([[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0]], (0, 0, 10, 10))
    >>> r.segments.tolist(), r.source.tolist(), r.t.tolist()
    ([[0.0, 5.0, 10.0, 5.0]], [0], [[0.25, 0.75]])
    """
    if (window is None) == (windows is None):
        raise InvalidWindowError("give one of window= and windows=")
    table = None
    if windows is not None:
        table = as_windows(windows)
        smallest = int(np.argmin((table[:, 2] - table[:, 0]) * (table[:, 3] - table[:, 1])))
        window = Window(*table[smallest].tolist())
    assert window is not None
    window = Window.of(window)
    options = SegmentOptions.resolve(window, method=method, n=n, max_depth=max_depth,
                                     tolerance=tolerance, mode=mode, resolution=resolution)
    wanted = _segment_outputs(outputs)
    engine = backend_for(backend, "segments" if table is None else "windows",
                         _rows(segments))
    # The backend checks the values: the Numba one in its clipping pass (a second
    # read of the input cost 3% of the call, 10M segments), the OpenCL one on the device.
    if is_device_array(segments):
        if not engine.capabilities.device_arrays:
            raise InvalidGeometryError(
                "segments in a pyopencl array are on an OpenCL device: clip them with "
                "backend='opencl', or bring them to the host (.get())")
        array: Any = segments
    else:
        array = as_segments(segments, check_values=False)
    if table is not None:
        engine.capabilities.require("windows", options.mode)
        out = engine.clip_segment_windows(array, table, options, source="source" in wanted,
                                          t="t" in wanted)
    else:
        out = engine.clip_segments(array, window, options, source="source" in wanted,
                                   t="t" in wanted)
    return SegmentClipResult(out.pieces, out.source, out.t, out.stats, options.method,
                             options.mode, engine.kind, options, out.window,
                             out.window_offsets)


def _check_decided_finite(geometries: np.ndarray, rows: np.ndarray, include_z: bool) -> None:
    """Raise `InvalidGeometryError` for a geometry decided by its box that is not finite.

    GEOS leaves NaN coordinates out of a geometry's bounds, so a line with a NaN vertex
    can have finite bounds inside (or beyond) the window and never reach the ragged
    arrays' check: its coordinates are checked here.
    """
    import shapely

    if rows.shape[0] == 0:
        return
    decided = geometries[rows]
    coords = shapely.get_coordinates(decided, include_z=include_z)
    if all_finite(np.ascontiguousarray(coords)):
        return
    bad = int(np.argmax(~np.isfinite(coords).all(axis=1)))
    ends = np.cumsum(shapely.get_num_coordinates(decided))
    row = int(rows[int(np.searchsorted(ends, bad, side="right"))])
    raise geometry_error(row, f" has a non-finite coordinate ({coords[bad].tolist()})")


def _rows(segments: Any) -> int:
    """Return the number of segments (for ``backend="auto"``), 0 if unknown yet."""
    shape = getattr(segments, "shape", None)
    return int(shape[0]) if shape else len(segments) if hasattr(segments, "__len__") else 0


def _segment_outputs(outputs: Iterable[str]) -> frozenset[str]:
    if isinstance(outputs, str):
        outputs = (outputs,)
    wanted = frozenset(outputs)
    unknown = sorted(wanted - frozenset(SEGMENT_OUTPUTS))
    if unknown:
        raise InvalidOptionError(
            f"outputs {unknown} are not outputs of clip_segments; choose from "
            f"{list(SEGMENT_OUTPUTS)}")
    return wanted


def is_device_array(obj: Any) -> bool:
    """Return whether `obj` is a ``pyopencl.array.Array`` (without importing pyopencl)."""
    return type(obj).__module__.startswith("pyopencl") and hasattr(obj, "queue")


@dataclass(frozen=True, slots=True)
class WindowsClipResult:
    """Shapely geometries clipped to many windows (`clip` with ``windows=``).

    Attributes
    ----------
    geometries : ndarray of object
        The non-empty clipped geometries, sorted by window, then source.
    source : ndarray of int64
        The input geometry of each.
    window : ndarray of int64
        The window of each (its row in ``windows``).
    window_offsets : ndarray of int64, shape (k + 1,)
        Window ``w``'s geometries are ``window_offsets[w]:window_offsets[w + 1]``.
    """

    geometries: np.ndarray
    source: np.ndarray
    window: np.ndarray
    window_offsets: np.ndarray

    def __len__(self) -> int:
        return self.geometries.shape[0]

    def of_window(self, w: int) -> np.ndarray:
        """Return window `w`'s geometries."""
        return self.geometries[self.window_offsets[w]:self.window_offsets[w + 1]]


def clip(obj: Any, window: Window | Iterable[float] | Iterable[Iterable[float]] | None = None,
         *, windows: npt.ArrayLike | None = None, **options: Any) -> Any:
    """Return `obj` clipped to the window, in the form it came in.

    Parameters
    ----------
    obj : shapely.Geometry, array_like of shapely.Geometry, GeoJSON dict or tuple
        A Shapely geometry gives a Shapely geometry (a LineString cut in two becomes a
        MultiLineString, as ``shapely.intersection`` gives it; nothing left gives an
        empty geometry of the input's type). An array of geometries (types may mix;
        collections are clipped member by member) gives an aligned array. A GeoJSON
        dict (Geometry, Feature or FeatureCollection) gives a GeoJSON dict (see
        `clip_geojson`, which also returns the stats). A ``(geometry_type, coords,
        offsets)`` triple gives a `RaggedClipResult` (see `clip_ragged`).
    window : Window, sequence of 4 floats, or array_like of shape (n, 4)
        One window, or one per geometry of an array or triple.
    windows : array_like, shape (k, 4), optional
        Many windows instead of `window`: every geometry against every window its box
        touches, in one call (see `clip_ragged`). A GeoJSON dict then gives a list of k
        documents, one per window; a triple a `RaggedClipResult` with ``window`` and
        ``window_offsets``; Shapely geometries a `WindowsClipResult` (the non-empty
        clips, sorted by window then source).
    **options
        ``boundary``, ``method``, ``n``, ``max_depth``, ``tolerance``, ``resolution``, ``mode``,
        ``backend`` (see `clip_ragged`); ``keep_empty`` for GeoJSON and triples.

    Returns
    -------
    Same kind as `obj`.

    Raises
    ------
    UnsupportedGeometryError
        For an object of another kind.

    Examples
    --------
    >>> import shapely
    >>> clip(shapely.LineString([(-5, 5), (15, 5)]), (0, 0, 10, 10)).wkt
    'LINESTRING (0 5, 10 5)'
    """
    import shapely

    if (window is None) == (windows is None):
        raise InvalidWindowError("give one of window= and windows=")
    if windows is not None:
        return _clip_windows(obj, as_windows(windows), options)
    assert window is not None
    if isinstance(obj, dict):
        from rnsca.clip_geojson import clip_geojson

        # A document takes one window (`Window.of` refuses a table of them).
        return clip_geojson(obj, cast("Window | Iterable[float]", window), **options)[0]
    if isinstance(obj, tuple) and len(obj) == 3:
        geometry_type, coords, offsets = obj
        return clip_ragged(geometry_type, coords, offsets, window, **options)
    if isinstance(obj, shapely.Geometry):
        return _clip_geometries(np.array([obj], dtype=object), window, options)[0]
    try:
        array = np.asarray(obj, dtype=object)
    except (TypeError, ValueError):
        array = None
    if array is None or array.ndim != 1 or not all(
            g is None or isinstance(g, shapely.Geometry) for g in array):
        raise UnsupportedGeometryError(
            "clip takes a Shapely geometry, a 1-d array of them, a GeoJSON dict or a "
            f"(geometry_type, coords, offsets) triple, got {type(obj).__name__}")
    return _clip_geometries(array, window, options)


def _clip_windows(obj: Any, table: np.ndarray, options: dict[str, Any]) -> Any:
    """`clip` with many windows: documents per window, a ragged result, or geometries."""
    import shapely

    if isinstance(obj, dict):
        from rnsca.clip_geojson import clip_geojson_windows

        return clip_geojson_windows(obj, table, **options).documents
    if isinstance(obj, tuple) and len(obj) == 3:
        geometry_type, coords, offsets = obj
        return clip_ragged(geometry_type, coords, offsets, windows=table, **options)
    array = np.asarray([obj] if isinstance(obj, shapely.Geometry) else obj, dtype=object)
    if array.ndim != 1 or not all(g is None or isinstance(g, shapely.Geometry) for g in array):
        raise UnsupportedGeometryError(
            "clip takes a Shapely geometry, a 1-d array of them, a GeoJSON dict or a "
            f"(geometry_type, coords, offsets) triple, got {type(obj).__name__}")
    # Collections member by member: their members stand for them (source = collection).
    parts, part_source = shapely.get_parts(array, return_index=True)
    rings = shapely.get_type_id(parts) == shapely.GeometryType.LINEARRING
    if rings.any():  # a ring clipped is a line (GEOS gives line strings too)
        parts[rings] = [shapely.LineString(g.coords) for g in parts[rings]]
    type_ids, has_z = shapely.get_type_id(parts), shapely.has_z(parts)
    pieces: list[np.ndarray] = []
    sources: list[np.ndarray] = []
    windows_of: list[np.ndarray] = []
    for type_id, include_z in sorted({(int(t), bool(z)) for t, z in zip(type_ids, has_z,
                                                                           strict=True)}):
        rows = np.flatnonzero((type_ids == type_id) & (has_z == include_z)
                              & ~shapely.is_empty(parts))
        if rows.shape[0] == 0:
            continue
        geometry_type, coords, offsets = shapely.to_ragged_array(parts[rows],
                                                                 include_z=include_z)
        result = clip_ragged(geometry_type, coords, offsets, windows=table,
                             **{k: v for k, v in options.items() if k != "keep_empty"})
        clipped = result.to_shapely()
        if _SINGLE_OF_MULTI.get(result.geometry_type.name) == shapely.GeometryType(
                type_id).name:  # a single-part input cut into one part stays single
            one = shapely.get_num_geometries(clipped) == 1
            clipped[one] = shapely.get_geometry(clipped[one], 0)
        pieces.append(clipped)
        sources.append(part_source[rows[result.source]])
        assert result.window is not None
        windows_of.append(result.window)
    if not pieces:
        return WindowsClipResult(np.empty(0, dtype=object), np.empty(0, dtype=np.int64),
                                 np.empty(0, dtype=np.int64),
                                 np.zeros(table.shape[0] + 1, dtype=np.int64))
    geometries = np.concatenate(pieces)
    source, window = np.concatenate(sources), np.concatenate(windows_of)
    order = np.lexsort((source, window))
    counts = np.bincount(window, minlength=table.shape[0])
    offsets_out = np.zeros(table.shape[0] + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets_out[1:])
    return WindowsClipResult(geometries[order], source[order].astype(np.int64),
                             window[order].astype(np.int64), offsets_out)


_SINGLE_OF_MULTI = {"MULTIPOINT": "POINT", "MULTILINESTRING": "LINESTRING",
                    "MULTIPOLYGON": "POLYGON"}


def _clip_geometries(geometries: np.ndarray,
                     window: Window | Iterable[float] | Iterable[Iterable[float]],
                     options: dict[str, Any]) -> np.ndarray:
    """Clip a Shapely array, one `clip_ragged` call per geometry type present."""
    import shapely

    options = {k: v for k, v in options.items() if k != "keep_empty"}
    count = geometries.shape[0]
    table = WindowTable.of(window, count)
    windows, index = table.bounds, table.index
    rings = shapely.get_type_id(geometries) == shapely.GeometryType.LINEARRING
    if rings.any():
        # A ring clipped is a line: its visible parts (GEOS gives line strings too).
        geometries = geometries.copy()
        geometries[rings] = [shapely.LineString(g.coords) for g in geometries[rings]]
    out = np.empty(count, dtype=object)
    type_ids = shapely.get_type_id(geometries)
    collections = np.flatnonzero(type_ids == shapely.GeometryType.GEOMETRYCOLLECTION)
    for i in collections:
        members = shapely.get_parts(geometries[i])
        clipped_members: np.ndarray | list[Any] = _clip_geometries(
            np.asarray(members, dtype=object),
            np.repeat(windows[index[i]][None, :], len(members), axis=0),
            options) if len(members) else []
        kept = [g for g in clipped_members if not g.is_empty]
        out[i] = shapely.GeometryCollection(kept)
    has_z = shapely.has_z(geometries)
    # One call per (type, 2D or 3D): a ragged array has one type and one dimension.
    groups = sorted({(int(t), bool(z)) for t, z in zip(type_ids, has_z, strict=True)})
    for type_id, include_z in groups:
        if type_id < 0 or type_id == shapely.GeometryType.GEOMETRYCOLLECTION:
            continue  # None stays None; collections went member by member
        rows = np.flatnonzero((type_ids == type_id) & (has_z == include_z))
        input_name = shapely.GeometryType(type_id).name
        # Options are checked even if every geometry is decided by its bounding box.
        resolve_geometry_options(table, GeometryKind.of(input_name).dimension,
                                 **{k: v for k, v in options.items() if k != "check_validity"})
        empty_geometry = shapely.from_wkt(f"{input_name} EMPTY")
        # Bounding boxes first: geometries beyond the window or strictly inside it need
        # no conversion to ragged arrays (most of the cost for Shapely objects).
        box = shapely.bounds(geometries[rows])
        win = windows[index[rows]]
        finite = np.isfinite(box).all(axis=1)  # the others go on, to be checked there
        outside = finite & ((box[:, 2] < win[:, 0]) | (box[:, 0] > win[:, 2])
                            | (box[:, 3] < win[:, 1]) | (box[:, 1] > win[:, 3]))
        inside = finite & ((box[:, 0] > win[:, 0]) & (box[:, 2] < win[:, 2])
                           & (box[:, 1] > win[:, 1]) & (box[:, 3] < win[:, 3]))
        _check_decided_finite(geometries, rows[outside | inside], include_z)
        out[rows[outside]] = empty_geometry
        kept = geometries[rows[inside]]
        if "POLYGON" in input_name:
            kept = shapely.orient_polygons(kept)  # shells CCW, holes CW, as clipped ones
        out[rows[inside]] = kept
        rows = rows[~outside & ~inside]
        if rows.shape[0] == 0:
            continue
        subset = geometries[rows]
        geometry_type, coords, offsets = shapely.to_ragged_array(subset, include_z=include_z)
        try:
            result = clip_ragged(geometry_type, coords, offsets, windows[index[rows]],
                                 keep_empty=True, **options)
        except InvalidGeometryError as exc:
            # `geometry_error` sets both; an error without them is not about one geometry.
            if exc.geometry is None or exc.detail is None:
                raise
            raise geometry_error(int(rows[exc.geometry]), exc.detail) from None
        clipped = result.to_shapely()
        if _SINGLE_OF_MULTI.get(result.geometry_type.name) == input_name:
            # A single-part input cut into one part stays single, as shapely gives it.
            one = shapely.get_num_geometries(clipped) == 1
            clipped[one] = shapely.get_geometry(clipped[one], 0)
        empty = shapely.is_empty(clipped)
        if empty.any():
            clipped[empty] = empty_geometry
        out[rows] = clipped
    return out
