"""The contract every backend implements: the operations, their inputs and their results.

A backend is a place where the kernels run (`NumbaBackend` on the CPU, `OpenCLBackend`
on an OpenCL device). The library (`rnsca.clip`, `rnsca.ragged`, `rnsca.clip_svg`)
resolves options, takes the caller's objects apart into the containers below, calls
one operation of the backend, and builds its public result from what comes back. It
never asks which backend it holds: what a backend can do is its `Capabilities`.

Operations (one method each, the same signature on every backend):

===========  =======================================  ===========================
operation    input                                    result
===========  =======================================  ===========================
segments     (n, 4) float64 array, `Window`           `SegmentPieces`
windows      (n, 4) float64 array, (k, 4) windows     `SegmentPieces` (+ window)
lines        `Ragged` lines, `WindowTable`            `GeometryPieces`
polygons     `Ragged` polygons, `WindowTable`         `GeometryPieces`
paths        `PathArrays`, `WindowTable`              `PathPieces`
flatten      `PathArrays`, tolerance                  `Polylines`
tiles        pieces sorted by window, `TileLayer`     `TileBytes`
===========  =======================================  ===========================

Every result says where each output came from (`source`, or offsets per input) and
carries the kernels' counter rows (`rnsca.kernels.counters`) and, for a device, its
`DeviceStats`; the library turns them into `ClipStats`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

import numpy as np

from rnsca.errors import BackendUnavailableError
from rnsca.kernels import segments as K
from rnsca.options import Backend, Method, Mode, PathOptions, Precision, SegmentOptions, _ChoiceEnum
from rnsca.window import Window, WindowTable

if TYPE_CHECKING:
    from rnsca.arrays import PathArrays, Ragged
    from rnsca.stats import ClipStats, DeviceStats

__all__ = [
    "METHOD_ID",
    "Capabilities",
    "ClipBackend",
    "GeometryPieces",
    "Operation",
    "PathPieces",
    "Polylines",
    "SegmentPieces",
    "TileBytes",
    "TileLayer",
]

#: The number each segment kernel (Numba and OpenCL) knows a method by.
METHOD_ID = {
    Method.RNSCA: K.RNSCA,
    Method.COHEN_SUTHERLAND: K.COHEN_SUTHERLAND,
    Method.LIANG_BARSKY: K.LIANG_BARSKY,
    Method.NICHOLL_LEE_NICHOLL: K.NICHOLL_LEE_NICHOLL,
    Method.MIDPOINT: K.MIDPOINT,
}


class Operation(_ChoiceEnum):
    """An operation a backend runs (a method of `ClipBackend`)."""

    SEGMENTS = "segments"
    """Clip line segments (`ClipBackend.clip_segments`)."""
    WINDOWS = "windows"
    """Clip line segments against many windows (`ClipBackend.clip_segment_windows`)."""
    LINES = "lines"
    """Clip lines and multi-lines into chains (`ClipBackend.clip_lines`)."""
    POLYGONS = "polygons"
    """Clip polygons into valid polygons (`ClipBackend.clip_polygons`)."""
    PATHS = "paths"
    """Clip Bézier paths (`ClipBackend.clip_paths`)."""
    FLATTEN = "flatten"
    """Turn Bézier paths into polylines (`ClipBackend.flatten_paths`)."""
    TILES = "tiles"
    """Encode pieces sorted by window as vector tiles (`ClipBackend.encode_segment_tiles`)."""

    @property
    def methods(self) -> tuple[Method, ...]:
        """Return the methods the operation accepts, on every backend (in `Method` order).

        Curves are clipped by RNSCA only (the line baselines clip them after
        `flatten_paths`); flattening and encoding tiles take no method.

        Examples
        --------
        >>> [m.value for m in Operation.PATHS.methods]
        ['rnsca']
        """
        if self in (Operation.FLATTEN, Operation.TILES):
            return ()
        return (Method.RNSCA,) if self is Operation.PATHS else tuple(Method)

    @property
    def modes(self) -> tuple[Mode, ...]:
        """Return the modes the operation accepts, on every backend (in `Mode` order).

        Polygons are clipped in exact mode only: valid polygon output needs the exact
        boundary crossings. Flattening and encoding tiles take no mode. A backend may
        run fewer (`Capabilities.modes`).

        Examples
        --------
        >>> [m.value for m in Operation.POLYGONS.modes]
        ['exact']
        """
        if self in (Operation.FLATTEN, Operation.TILES):
            return ()
        return (Mode.EXACT,) if self is Operation.POLYGONS else tuple(Mode)


@dataclass(frozen=True, slots=True)
class Capabilities:
    """What a backend can run here: the one answer the library, the CLI and the service use.

    Attributes
    ----------
    backend : Backend
    operations : frozenset of Operation
    modes : frozenset of Mode
        Modes the backend runs (an operation may still refuse one for its own reasons:
        polygons need exact mode everywhere).
    precision : Precision
        The floating-point precision of its kernels (FLOAT64 or FLOAT32).
    devices : tuple of str
        Where it runs: ``("cpu",)``, or the OpenCL device's ``"platform:device"`` id.
    device_arrays : bool
        Whether it takes segments already on its device (``pyopencl.array.Array``) and
        leaves the pieces there.
    """

    backend: Backend
    operations: frozenset[Operation] = field(default_factory=lambda: frozenset(Operation))
    modes: frozenset[Mode] = field(default_factory=lambda: frozenset(Mode))
    precision: Precision = Precision.FLOAT64
    devices: tuple[str, ...] = ("cpu",)
    device_arrays: bool = False

    def supports(self, operation: Operation | str, mode: Mode | str = Mode.EXACT) -> bool:
        """Return whether `operation` runs here in `mode`."""
        return Operation(operation) in self.operations and Mode(mode) in self.modes

    def require(self, operation: Operation | str, mode: Mode | str = Mode.EXACT) -> None:
        """Raise `BackendUnavailableError` naming what is missing, unless `supports`."""
        operation, mode = Operation(operation), Mode(mode)
        if operation not in self.operations:
            runs = ", ".join(sorted(o.value for o in self.operations))
            raise BackendUnavailableError(
                f"backend {self.backend.value!r} does not clip {operation.value} "
                f"(it runs: {runs})")
        if mode not in self.modes:
            raise BackendUnavailableError(
                f"backend {self.backend.value!r} does not run mode={mode.value!r}")

    def to_dict(self) -> dict[str, Any]:
        """Return the capabilities as JSON-ready values (sorted lists of names)."""
        return {"backend": self.backend.value,
                "operations": sorted(o.value for o in self.operations),
                "modes": sorted(m.value for m in self.modes),
                "precision": self.precision.value,
                "devices": list(self.devices)}


@dataclass(frozen=True, slots=True)
class SegmentPieces:
    """The visible pieces of segments: at most one per segment, in input order.

    Attributes
    ----------
    pieces : ndarray of float64, shape (m, 4)
        (A device array in the device's precision for device input.)
    source : ndarray of int64, shape (m,), or None
        The segment each piece came from (strictly increasing); None if not asked for.
    t : ndarray of float64, shape (m, 2), or None
        Each piece's parameter interval on its segment; None if not asked for.
    stats : ClipStats
    window : ndarray of int32, shape (m,), or None
        Many windows (`ClipBackend.clip_segment_windows`): the window of each piece;
        the pieces are sorted by window, then source. None for one window.
    window_offsets : ndarray of int64, shape (k + 1,), or None
        Many windows: window ``w``'s pieces are ``window_offsets[w]:window_offsets[w + 1]``.
    """

    pieces: Any
    source: Any
    t: Any
    stats: ClipStats
    window: Any = None
    window_offsets: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class GeometryPieces:
    """Clipped lines or polygons, grouped by input geometry, in the GeoArrow layout.

    Attributes
    ----------
    xy : ndarray of float64, shape (v, 2)
    z : ndarray of float64, shape (v,) or (0,)
        Interpolated Z, empty for 2D input.
    offsets : tuple of ndarray of int64
        Innermost level first, as ``shapely.from_ragged_array`` takes them. Lines:
        vertex offsets of the chains (connected visible parts), then chain offsets of
        the input geometries. Polygons: vertex offsets of the rings (closed; shells CCW,
        holes CW), ring offsets of the output polygons (shell first), then polygon
        offsets of the input geometries. Geometry ``i``'s outputs are
        ``offsets[-1][i]:offsets[-1][i + 1]`` (none: nothing is left of it).
    counters : ndarray of int64, shape (rows, counters.WIDTH)
    device : DeviceStats or None
    """

    xy: np.ndarray
    z: np.ndarray
    offsets: tuple
    counters: np.ndarray
    device: DeviceStats | None = None


@dataclass(frozen=True, slots=True)
class PathPieces:
    """Clipped paths: output path ``i`` is the clip of input path ``i`` in its window.

    Attributes
    ----------
    paths : PathArrays
        One path per input path (empty where nothing is left).
    segments_in : int
        Segments the clip took in (with the closing edges of filled subpaths).
    counters : ndarray of int64, shape (rows, counters.WIDTH)
    device : DeviceStats or None
    """

    paths: PathArrays
    segments_in: int
    counters: np.ndarray
    device: DeviceStats | None = None


class Polylines(NamedTuple):
    """Paths turned into polylines: one per subpath that has a segment (a named tuple).

    Attributes
    ----------
    coords : ndarray of float64, shape (v, 2)
    line_offsets : ndarray of int64, shape (k + 1,)
    line_path : ndarray of int64, shape (k,)
        The path of each polyline.
    """

    coords: np.ndarray
    line_offsets: np.ndarray
    line_path: np.ndarray


@dataclass(frozen=True, slots=True)
class TileLayer:
    """How pieces sorted by window become one MVT layer per window (`encode_segment_tiles`).

    Attributes
    ----------
    window_offsets : ndarray of int64, shape (k + 1,)
        Tile ``w``'s pieces are rows ``window_offsets[w]:window_offsets[w + 1]``.
    quantisation : ndarray of float64, shape (k, 4)
        ``(x0, y1, sx, sy)`` of each tile: its window's left and top edges and its
        scales, tile units per unit. A piece end ``(x, y)`` becomes
        ``floor((x - x0) * sx + 0.5)``, ``floor((y1 - y) * sy + 0.5)`` (y down), each
        operation rounded on its own (no fused multiply-add), on every backend.
    head, tail : ndarray of uint8
        The layer's fields before its features (name) and after them (extent,
        version), as protobuf serializes them.
    """

    window_offsets: np.ndarray
    quantisation: np.ndarray
    head: np.ndarray
    tail: np.ndarray


@dataclass(frozen=True, slots=True)
class TileBytes:
    """Encoded tiles, back to back: tile ``w`` is ``data[offsets[w]:offsets[w + 1]]``.

    Attributes
    ----------
    data : ndarray of uint8
    offsets : ndarray of int64, shape (k + 1,)
        A tile left with no feature is empty (no bytes).
    device : DeviceStats or None
    """

    data: np.ndarray
    offsets: np.ndarray
    device: DeviceStats | None = None


class ClipBackend(Protocol):
    """A place where the clipping kernels run; every backend gives the same outputs."""

    kind: Backend

    @property
    def capabilities(self) -> Capabilities:
        """Return what this backend runs here."""
        ...

    def clip_segments(self, segments: np.ndarray, window: Window, options: SegmentOptions,
                      *, source: bool = True, t: bool = True) -> SegmentPieces:
        """Return the visible piece of each segment.

        `segments` is float64 (n, 4), C-contiguous (or, on a device backend, a device
        array it accepts); its values are not yet checked: the backend raises
        `InvalidGeometryError` (`rnsca.arrays.segment_error`) for a segment that is not
        finite or whose differences overflow, and returns nothing. `source` and `t`
        False: those outputs are None (a device leaves them on the device).
        """
        ...

    def clip_segment_windows(self, segments: np.ndarray, windows: np.ndarray,
                             options: SegmentOptions, *, source: bool = True,
                             t: bool = True) -> SegmentPieces:
        """Return the piece of each segment in each window it crosses.

        `windows` is a checked float64 (k, 4) table (`rnsca.many_windows.as_windows`);
        the pairs are `rnsca.many_windows.assign`'s (a device backend may make them
        itself, the same pairs). `segments` as for `clip_segments`: a device backend
        also takes a device array it accepts, and then returns device arrays
        (``window_offsets`` stays a host array). The pieces are sorted by window, then
        source, with ``window`` and ``window_offsets`` set; the counters count the
        (segment, window) pairs clipped. Bad segments as `clip_segments`.
        """
        ...

    def clip_lines(self, lines: Ragged, windows: WindowTable, options: SegmentOptions,
                   drop_edge_runs: bool) -> GeometryPieces:
        """Return the chains of each line geometry inside its window.

        `lines` is a LINESTRING or MULTILINESTRING `Ragged` (coordinates not yet checked
        for finiteness: the backend raises `InvalidGeometryError` naming the first bad
        one). `drop_edge_runs` drops parts that only run along the window's edge
        (``boundary="interior"``).
        """
        ...

    def clip_polygons(self, polygons: Ragged, windows: WindowTable,
                      options: SegmentOptions) -> GeometryPieces:
        """Return the valid polygons each POLYGON or MULTIPOLYGON gives inside its window."""
        ...

    def clip_polygon_pairs(self, polygons: Ragged, geometry: np.ndarray, windows: np.ndarray,
                           options: SegmentOptions) -> GeometryPieces:
        """Return ``clip_polygons`` of ``polygons.take(geometry)``, row j against ``windows[j]``.

        The tile cascade's operation (`rnsca.tiles.pyramid`): many (geometry, window)
        pairs of one MULTIPOLYGON array, whose coordinates were checked when it was made.
        A backend may clip simple pairs straight from `polygons` (no gather), with the
        same output bit for bit. Output geometry j is pair j's (maybe empty).
        """
        ...

    def clip_paths(self, paths: PathArrays, windows: WindowTable,
                   options: PathOptions) -> PathPieces:
        """Return each path clipped to its window (curves kept or flattened, strokes or fills).

        `windows` gives one window for all paths or one per path (``rnsca.clip_paths(...,
        windows=)`` passes the (path, window) pairs' paths, sorted by window).
        """
        ...

    def flatten_paths(self, paths: PathArrays, tolerance: float, close: bool) -> Polylines:
        """Return the paths as polylines within `tolerance` (`close`: every subpath closed)."""
        ...

    def encode_segment_tiles(self, pieces: Any, source: Any, layer: TileLayer) -> TileBytes:
        """Return each window's pieces as a Mapbox Vector Tile of one layer.

        `pieces` (m, 4) float64 are sorted by window (``layer.window_offsets``), a host
        array or, on a device backend, a device array it accepts; `source` (m,) int64
        (host or device) or None. Each piece is a LINESTRING feature: id ``source[i]``
        (none without `source`), no tags, MoveTo its first end, LineTo its second
        (zigzag deltas from (0, 0)); a piece whose ends quantise to one position is left
        out. The bytes are the same on every backend. Raises `InvalidGeometryError`
        naming the first piece that quantises beyond ``MVT_COORDINATE_LIMIT``
        (`rnsca.constants`) or is not finite.
        """
        ...

    def warm_up(self) -> None:
        """Compile (or load from the caches) every kernel, so the first real call is fast."""
        ...
