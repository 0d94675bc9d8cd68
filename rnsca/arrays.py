"""Ragged geometry arrays: flat coordinates plus offsets, the layout of GeoArrow.

This is the layout ``shapely.to_ragged_array`` returns: ``coords`` (n, 2) or (n, 3),
and int offset arrays innermost level first. For a polygon with a hole::

    coords  = [shell: 0..4, hole: 5..9]        ring_offsets    = [0, 5, 10]
                                               geometry_offsets = [0, 2]   (rings per polygon)

`Ragged` validates that layout once; the clipping functions take its levels apart into
the three shapes the kernels know: points, lines (parts) and polygons (rings).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from enum import Enum
from typing import Any

import numpy as np
import numpy.typing as npt
import shapely

from rnsca.constants import MVT_COORDINATE_LIMIT
from rnsca.errors import InvalidGeometryError, UnsupportedGeometryError
from rnsca.kernels.copies import copy_ranges
from rnsca.kernels.validate import (
    LAYOUT_MESSAGES,
    all_finite,
    check_layout,
    first_invalid_segment,
    first_open_ring,
)
from rnsca.kernels.windows import vertex_boxes

__all__ = ["GeometryKind", "Ragged", "PathArrays", "OUTPUT_KIND", "exclusive_sum",
           "geometry_error", "group_offsets", "in_threads", "to_shapely"]


class GeometryKind(str, Enum):
    """A geometry type of a ragged array (names as Shapely and GeoJSON spell them)."""

    POINT = "Point"
    LINESTRING = "LineString"
    POLYGON = "Polygon"
    MULTIPOINT = "MultiPoint"
    MULTILINESTRING = "MultiLineString"
    MULTIPOLYGON = "MultiPolygon"

    @classmethod
    def of(cls, value: GeometryKind | shapely.GeometryType | str) -> GeometryKind:
        """Return the kind for a `GeometryKind`, a ``shapely.GeometryType`` or a name.

        Names are case-insensitive (``"linestring"``, ``"MULTIPOLYGON"``).

        Raises
        ------
        UnsupportedGeometryError
            For a geometry collection, a linear ring or anything else.
        """
        if isinstance(value, cls):
            return value
        if isinstance(value, shapely.GeometryType):
            value = value.name
        if isinstance(value, str):
            for member in cls:
                if member.name == value.upper():
                    return member
        choices = ", ".join(m.value for m in cls)
        raise UnsupportedGeometryError(f"geometry type must be one of {choices}, got {value!r}")

    @property
    def shapely_type(self) -> shapely.GeometryType:
        """Return the matching ``shapely.GeometryType``."""
        return shapely.GeometryType[self.name]

    @property
    def depth(self) -> int:
        """Return how many offset arrays the kind has."""
        return _DEPTH[self]

    @property
    def dimension(self) -> int:
        """Return 0 for points, 1 for lines, 2 for polygons."""
        return _DIMENSION[self]


_DEPTH = {GeometryKind.POINT: 0, GeometryKind.LINESTRING: 1, GeometryKind.POLYGON: 2,
          GeometryKind.MULTIPOINT: 1, GeometryKind.MULTILINESTRING: 2,
          GeometryKind.MULTIPOLYGON: 3}
_DIMENSION = {GeometryKind.POINT: 0, GeometryKind.LINESTRING: 1, GeometryKind.POLYGON: 2,
              GeometryKind.MULTIPOINT: 0, GeometryKind.MULTILINESTRING: 1,
              GeometryKind.MULTIPOLYGON: 2}

#: What clipping one geometry of a kind can give: a line leaving and re-entering the
#: window becomes two parts, a concave polygon several polygons.
OUTPUT_KIND = {
    GeometryKind.POINT: GeometryKind.POINT,
    GeometryKind.LINESTRING: GeometryKind.MULTILINESTRING,
    GeometryKind.POLYGON: GeometryKind.MULTIPOLYGON,
    GeometryKind.MULTIPOINT: GeometryKind.MULTIPOINT,
    GeometryKind.MULTILINESTRING: GeometryKind.MULTILINESTRING,
    GeometryKind.MULTIPOLYGON: GeometryKind.MULTIPOLYGON,
}


def _offsets(array: npt.ArrayLike, name: str, length: int,
             of: str = "the length of the level below") -> np.ndarray:
    """Return `array` as int64 offsets into a level of `length` items (`of`), or raise."""
    try:
        out = np.asarray(array)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"{name} must be an integer array") from None
    if out.ndim != 1 or out.shape[0] < 1 or (out.size and out.dtype.kind not in "iu"):
        raise InvalidGeometryError(
            f"{name} must be a 1-d integer array of at least one offset, got shape "
            f"{out.shape} of {out.dtype}")
    out = np.ascontiguousarray(out, dtype=np.int64)
    steps = np.diff(out)
    if out[0] != 0 or out[-1] != length or (steps < 0).any():
        where = (f", decreasing at index {int(np.argmax(steps < 0)) + 1}"
                 if (steps < 0).any() else f", got {out[0]} and {out[-1]}")
        raise InvalidGeometryError(
            f"{name} must start at 0, never decrease and end at {length} ({of}){where}")
    return out


def check_segment_values(segments: np.ndarray) -> None:
    """Raise `InvalidGeometryError` naming the first segment that is not finite.

    `segments` is float64 (n, 4), C-contiguous. A segment is refused for a NaN or
    infinite coordinate, or differences ``x1 - x0``, ``y1 - y0`` that overflow; the
    error's ``row`` attribute is its index (callers name it in their own terms: the
    service, a JSON path).
    """
    row = int(first_invalid_segment(segments))
    if row >= 0:
        raise segment_error(row, segments[row])


def segment_error(row: int, values: np.ndarray) -> InvalidGeometryError:
    """Return the error for segment `row`, whose float64 `values` are not finite.

    The message says which: a NaN or infinite coordinate, or differences that overflow.
    """
    values = np.asarray(values, dtype=np.float64)
    if not np.isfinite(values).all():
        error = InvalidGeometryError(
            f"segment {row} has a non-finite coordinate: {values.tolist()}")
    else:
        error = InvalidGeometryError(
            f"segment {row} spans more than float64 can hold (x1 - x0 or y1 - y0 "
            f"overflows): {values.tolist()}")
    error.row = row
    return error


def tile_piece_error(row: int, tile: int, values: np.ndarray) -> InvalidGeometryError:
    """Return the error for piece `row` of `tile`, which does not quantise into MVT's range.

    Its coordinates are not finite, or lie ``MVT_COORDINATE_LIMIT`` (`rnsca.constants`)
    tile units or more from its tile's origin: a piece of another window, most likely.
    """
    error = InvalidGeometryError(
        f"piece {row} {np.asarray(values, dtype=np.float64).tolist()} of tile {tile} lies "
        f"{MVT_COORDINATE_LIMIT} tile units or more from the tile's origin (or is not "
        f"finite), beyond the 32-bit coordinates of a vector tile: encode the pieces of "
        f"clip_segments(..., windows=windows) with the same windows")
    error.row = row
    return error


def geometry_error(index: int, detail: str) -> InvalidGeometryError:
    """Return the error "geometry <index><detail>", carrying `geometry` and `detail`.

    Callers that clip a subset of their geometries re-raise it with their own index.
    """
    error = InvalidGeometryError(f"geometry {index}{detail}")
    error.geometry = index
    error.detail = detail
    return error


@dataclass(frozen=True, slots=True)
class Ragged:
    """A validated ragged geometry array.

    Attributes
    ----------
    kind : GeometryKind
    coords : ndarray of float64, shape (n, 2) or (n, 3)
        C-contiguous; finite (an all-NaN row is an empty POINT, as Shapely writes it),
        except Z with `partial_z`.
    offsets : tuple of ndarray of int64
        Innermost level first, ``kind.depth`` arrays.
    partial_z : bool
        Whether a Z may be NaN, for a position that has none (a 2D position among 3D
        ones, as a GeoJSON document may mix them). Clipping propagates it: a new vertex
        whose Z is computed from a NaN one has a NaN Z. X and Y must still be finite, and
        Z not infinite.
    """

    kind: GeometryKind
    coords: np.ndarray
    offsets: tuple
    partial_z: bool = False

    @classmethod
    def of(cls, geometry_type: GeometryKind | shapely.GeometryType | str,
           coords: npt.ArrayLike, offsets: Sequence[npt.ArrayLike], *,
           check_finite: bool = True, partial_z: bool = False) -> Ragged:
        """Return a validated `Ragged` from the triple ``shapely.to_ragged_array`` gives.

        With ``check_finite=False`` the caller takes over the finiteness check (it must
        call `check_finite` itself, or check as it reads the coordinates): the line
        clip does it in its first pass over the coordinates. `partial_z` is the
        attribute: NaN Z allowed.

        Raises
        ------
        InvalidGeometryError
            Wrong shapes or dtypes, offsets that do not nest, rings not closed or of
            fewer than four positions, lines of one position, or a non-finite
            coordinate; the message names the geometry index.
        UnsupportedGeometryError
            For a geometry type that is not one of `GeometryKind`.
        """
        kind = GeometryKind.of(geometry_type)
        try:
            xy = np.asarray(coords)
        except (TypeError, ValueError):
            raise InvalidGeometryError("coords must be a numeric (n, 2) or (n, 3) array") \
                from None
        if xy.ndim != 2 or xy.shape[1] not in (2, 3) or xy.dtype.kind not in "iuf":
            raise InvalidGeometryError(
                f"coords must be a numeric (n, 2) or (n, 3) array, got shape {xy.shape} "
                f"of {xy.dtype}")
        xy = np.ascontiguousarray(xy, dtype=np.float64)
        if not isinstance(offsets, (tuple, list)) or len(offsets) != kind.depth:
            got = len(offsets) if isinstance(offsets, (tuple, list)) else type(offsets).__name__
            raise InvalidGeometryError(
                f"{kind.value} needs {kind.depth} offset arrays (innermost first), got {got}")
        levels = []
        length = xy.shape[0]
        for depth, array in enumerate(offsets):
            level = _offsets(array, f"offsets[{depth}]", length)
            levels.append(level)
            length = level.shape[0] - 1
        ragged = cls(kind, xy, tuple(levels), bool(partial_z))
        if check_finite:
            ragged.check_finite()
        ragged._check_shapes()
        return ragged

    @classmethod
    def from_shapely(cls, geometries: npt.ArrayLike, include_z: bool | None = None) -> Ragged:
        """Return the ragged array of a Shapely geometry array (one geometry type).

        Raises
        ------
        UnsupportedGeometryError
            For mixed types, collections or non-geometries.
        """
        try:
            kind, coords, offsets = shapely.to_ragged_array(geometries, include_z=include_z)
        except (ValueError, TypeError) as exc:
            raise UnsupportedGeometryError(f"cannot take these geometries apart: {exc}") \
                from None
        return cls.of(kind, coords, offsets)

    @property
    def count(self) -> int:
        """Return the number of geometries."""
        if self.kind.depth == 0:
            return self.coords.shape[0]
        return self.offsets[-1].shape[0] - 1

    @property
    def has_z(self) -> bool:
        """Return whether coordinates carry Z."""
        return self.coords.shape[1] == 3

    def split_z(self) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(xy (n, 2), z (n,) or (0,))``, C-contiguous, as the kernels take them."""
        if self.has_z:
            return (np.ascontiguousarray(self.coords[:, :2]),
                    np.ascontiguousarray(self.coords[:, 2]))
        return self.coords, np.empty(0)

    def item_offsets(self) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(vertex offsets of the items, item offsets of the geometries)``.

        Items are the parts of lines (LINESTRING, MULTILINESTRING) or the polygons of
        polygon kinds (POLYGON, MULTIPOLYGON: the second array then counts polygons, the
        rings are ``offsets[0]``, the rings of each polygon ``offsets[1]``); a single
        kind has one item per geometry.
        """
        if self.kind in (GeometryKind.LINESTRING, GeometryKind.POLYGON):
            items = self.offsets[0] if self.kind is GeometryKind.LINESTRING else self.offsets[1]
            return items, np.arange(self.count + 1, dtype=np.int64)
        if self.kind is GeometryKind.MULTILINESTRING:
            return self.offsets[0], self.offsets[1]
        if self.kind is GeometryKind.MULTIPOLYGON:
            return self.offsets[1], self.offsets[2]
        raise UnsupportedGeometryError(f"{self.kind.value} has no parts or polygons")

    def vertex_offsets(self) -> np.ndarray:
        """Return the int64 vertex offsets of the geometries.

        Geometry ``g`` is coordinate rows ``[g]:[g + 1]`` (points: one row each).

        Examples
        --------
        >>> import shapely
        >>> polygons = shapely.box([0, 5], [0, 5], [1, 6], [1, 6])
        >>> Ragged.from_shapely(polygons).vertex_offsets().tolist()
        [0, 5, 10]
        """
        if self.kind.depth == 0:
            return np.arange(self.coords.shape[0] + 1, dtype=np.int64)
        offsets = self.offsets[-1]
        for level in reversed(self.offsets[:-1]):
            offsets = level[offsets]
        return np.ascontiguousarray(offsets, dtype=np.int64)

    def take(self, index: npt.ArrayLike) -> Ragged:
        """Return the geometries at `index` (int, any order, repeats allowed), as a Ragged.

        Vectorised level by level, outermost first: each level's items of the geometries
        taken are whole ranges of the level below, gathered without a loop per geometry.

        Examples
        --------
        >>> import shapely
        >>> lines = Ragged.from_shapely([shapely.LineString([(0, 0), (1, 1)]),
        ...                              shapely.LineString([(5, 5), (6, 6), (7, 5)])])
        >>> taken = lines.take([1, 1, 0])
        >>> taken.offsets[0].tolist(), taken.coords[:, 0].tolist()
        ([0, 3, 6, 8], [5.0, 6.0, 7.0, 5.0, 6.0, 7.0, 0.0, 1.0])
        """
        items = np.ascontiguousarray(index, dtype=np.int64)
        if self.kind.depth == 0:
            return Ragged(self.kind, np.ascontiguousarray(self.coords[items]), (),
                          self.partial_z)
        levels = []
        for depth, level in enumerate(reversed(self.offsets)):  # outermost first
            starts = level[items]
            counts = level[items + 1] - starts
            taken = exclusive_sum(counts)
            levels.append(taken)
            if depth == len(self.offsets) - 1:
                # The coordinates: whole ranges copied on every core, no index array.
                coords = np.empty((int(taken[-1]), self.coords.shape[1]))
                copy_ranges(self.coords, starts, counts, taken, coords)
                return Ragged(self.kind, coords, tuple(reversed(levels)), self.partial_z)
            # The items below: ranges starts[j]..starts[j] + counts[j], back to back.
            items = (np.arange(int(taken[-1]), dtype=np.int64)
                     + np.repeat(starts - taken[:-1], counts))
        raise AssertionError("unreachable: a kind with offsets has a coordinate level")

    def concat(self, other: Ragged) -> Ragged:
        """Return the geometries of `self` then those of `other` (of the same kind).

        Examples
        --------
        >>> import shapely
        >>> a = Ragged.from_shapely([shapely.LineString([(0, 0), (1, 1)])])
        >>> a.concat(a).offsets[0].tolist()
        [0, 2, 4]
        """
        levels = []
        shift = self.coords.shape[0]
        for mine, theirs in zip(self.offsets, other.offsets, strict=True):
            levels.append(np.concatenate([mine, theirs[1:] + shift]))
            shift = mine.shape[0] - 1
        return Ragged(self.kind, np.concatenate([self.coords, other.coords]), tuple(levels),
                      self.partial_z or other.partial_z)

    def concat_take(self, other: Ragged, index: npt.ArrayLike) -> Ragged:
        """Return ``self.concat(other).take(index)``, each coordinate copied once.

        The offsets are concatenated (small), the coordinates are not: each geometry
        taken is copied from whichever array holds it, straight to its place.

        Examples
        --------
        >>> import shapely
        >>> a = Ragged.from_shapely([shapely.LineString([(0, 0), (1, 1)])])
        >>> b = Ragged.from_shapely([shapely.LineString([(5, 5), (6, 6), (7, 5)])])
        >>> a.concat_take(b, [1, 0]).coords[:, 0].tolist()
        [5.0, 6.0, 7.0, 0.0, 1.0]
        """
        if self.kind.depth == 0:
            return self.concat(other).take(index)
        levels = []
        shift = self.coords.shape[0]
        for mine, theirs in zip(self.offsets, other.offsets, strict=True):
            levels.append(np.concatenate([mine, theirs[1:] + shift]))
            shift = mine.shape[0] - 1
        items = np.ascontiguousarray(index, dtype=np.int64)
        taken_levels = []
        for depth, level in enumerate(reversed(levels)):  # outermost first
            starts = level[items]
            counts = level[items + 1] - starts
            taken = exclusive_sum(counts)
            taken_levels.append(taken)
            if depth < len(levels) - 1:
                items = (np.arange(int(taken[-1]), dtype=np.int64)
                         + np.repeat(starts - taken[:-1], counts))
        coords = np.empty((int(taken[-1]), self.coords.shape[1]))
        mine = starts < self.coords.shape[0]
        theirs = ~mine
        copy_ranges(self.coords, starts[mine], counts[mine], taken[:-1][mine], coords)
        copy_ranges(other.coords, starts[theirs] - self.coords.shape[0], counts[theirs],
                    taken[:-1][theirs], coords)
        return Ragged(self.kind, coords, tuple(reversed(taken_levels)),
                      self.partial_z or other.partial_z)

    def to_shapely(self) -> np.ndarray:
        """Return the geometries as a Shapely array.

        With `partial_z` they are 2D: Shapely has no position without Z among 3D ones
        (GEOS would carry the NaN into its results).
        """
        coords = np.ascontiguousarray(self.coords[:, :2]) if self.partial_z else self.coords
        return to_shapely(self.kind, coords, self.offsets)

    def geometry_of_coordinate(self, index: int) -> int:
        """Return the index of the geometry that holds coordinate row `index`."""
        g = index
        for level in self.offsets:
            g = int(np.searchsorted(level, g, side="right")) - 1
        return g

    def check_finite(self) -> None:
        """Raise `InvalidGeometryError` naming the first non-finite coordinate, if any.

        An all-NaN row of a POINT array is an empty point, not an error; so is a NaN Z
        with `partial_z`.
        """
        if all_finite(self.coords):
            return
        finite = np.isfinite(self.coords)
        if self.partial_z and self.has_z:
            finite[:, 2] |= np.isnan(self.coords[:, 2])  # a position without Z
        rows = ~finite.all(axis=1)
        if self.kind is GeometryKind.POINT:
            rows &= ~np.isnan(self.coords).all(axis=1)  # an empty point
        if not rows.any():
            return
        bad = int(np.argmax(rows))
        raise geometry_error(self.geometry_of_coordinate(bad),
                             f" has a non-finite coordinate (coords[{bad}] = "
                             f"{self.coords[bad].tolist()})")

    def _check_shapes(self) -> None:
        if self.kind.dimension == 0:
            return
        inner = self.offsets[0]
        sizes = np.diff(inner)
        if self.kind.dimension == 1:
            short = (sizes == 1)
            if short.any():
                part = int(np.argmax(short))
                raise geometry_error(self._geometry_of_level(0, part),
                                     f": line part {part} has one position; a line needs "
                                     f"at least two")
            return
        short = (sizes > 0) & (sizes < 4)
        if short.any():
            ring = int(np.argmax(short))
            raise geometry_error(self._geometry_of_level(0, ring),
                                 f": ring {ring} has {int(sizes[ring])} positions; a ring "
                                 f"needs at least four")
        ring = int(first_open_ring(self.coords, inner))
        if ring >= 0:
            raise geometry_error(self._geometry_of_level(0, ring),
                                 f": ring {ring} is not closed (its first and last "
                                 f"positions differ)")

    def _geometry_of_level(self, depth: int, index: int) -> int:
        g = index
        for level in self.offsets[depth + 1:]:
            g = int(np.searchsorted(level, g, side="right")) - 1
        return g


def to_shapely(geometry_type: GeometryKind | shapely.GeometryType | int, coords: np.ndarray,
               offsets: Sequence[np.ndarray]) -> np.ndarray:
    """Return the geometries of a ragged array as a Shapely array, empty parts dropped.

    ``shapely.from_ragged_array``, made safe for every layout `Ragged` accepts. Shapely
    2.2 (GEOS 3.14) mishandles three of them, all valid GeoArrow:

    - a polygon of no rings inside a multipolygon: the process dies (a segfault in GEOS);
    - a polygon whose exterior ring has no positions but which has holes: the same;
    - no coordinates at all, in lines or multipoints: an ``IndexError``.

    A polygon with an empty exterior is empty (its holes bound nothing), so its rings are
    dropped, and a multipolygon's empty polygons with them: the point set is the same.
    Arrays without such polygons go to Shapely as they are.

    Parameters
    ----------
    geometry_type : GeometryKind, shapely.GeometryType or int
    coords : ndarray of float64, shape (n, 2) or (n, 3)
    offsets : sequence of ndarray of int
        Innermost level first, nested as `Ragged` checks them; rings and lines as
        Shapely takes them (`Ragged` refuses the others: one-position lines, short rings).

    Returns
    -------
    ndarray of object
        One geometry per geometry of the array.

    Examples
    --------
    A multipolygon whose first polygon has no rings (offsets innermost first):

    >>> square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)
    >>> to_shapely(GeometryKind.MULTIPOLYGON, square,
    ...            (np.array([0, 5]), np.array([0, 0, 1]), np.array([0, 2])))[0].wkt
    'MULTIPOLYGON (((0 0, 1 0, 1 1, 0 1, 0 0)))'
    """
    kind = GeometryKind.of(shapely.GeometryType(geometry_type)
                           if isinstance(geometry_type, int) else geometry_type)
    if kind.dimension == 2:
        coords, offsets = _without_empty_polygons(kind, coords, tuple(offsets))
    if coords.shape[0] == 0:
        count = offsets[-1].shape[0] - 1 if kind.depth else 0
        return np.full(count, shapely.from_wkt(f"{kind.name} EMPTY"), dtype=object)
    return shapely.from_ragged_array(kind.shapely_type, coords, tuple(offsets) or None)


def _without_empty_polygons(kind: GeometryKind, coords: np.ndarray,
                            offsets: tuple) -> tuple[np.ndarray, tuple]:
    """Return polygon arrays without the empty polygons Shapely cannot read (`to_shapely`).

    A polygon whose exterior ring is empty loses its rings (holes included, with their
    positions); in a MULTIPOLYGON it is then dropped, as is any polygon of no rings. A
    POLYGON keeps its place as a polygon of no rings (POLYGON EMPTY, which Shapely
    reads). Empty holes of a non-empty polygon are kept: Shapely reads them.
    """
    rings, polygons = offsets[0], offsets[1]
    ring_sizes = np.diff(rings)
    ring_counts = np.diff(polygons)
    has_rings = ring_counts > 0
    # The exterior is each polygon's first ring: empty when it has no positions.
    hollow = np.zeros(ring_counts.shape[0], dtype=bool)
    hollow[has_rings] = ring_sizes[polygons[:-1][has_rings]] == 0
    if kind is GeometryKind.MULTIPOLYGON:
        dropped = hollow | ~has_rings
    else:
        dropped = hollow & (ring_counts > 1)
    if not dropped.any():
        return coords, offsets
    emptied = dropped & has_rings  # polygons whose rings go
    keep_ring = ~np.repeat(emptied, ring_counts)
    coords = np.ascontiguousarray(coords[np.repeat(keep_ring, ring_sizes)])
    new_rings = exclusive_sum(ring_sizes[keep_ring])
    new_polygons = exclusive_sum(keep_ring)[polygons]  # an emptied polygon: no rings
    if kind is GeometryKind.POLYGON:
        return coords, (new_rings, new_polygons)
    # Dropping polygon j drops offset j + 1: it has no rings, so its end is its start.
    kept = ~dropped
    new_polygons = np.concatenate([new_polygons[:1], new_polygons[1:][kept]])
    new_geometries = exclusive_sum(kept)[offsets[2]]
    return coords, (new_rings, new_polygons, new_geometries)


def exclusive_sum(counts: npt.ArrayLike) -> np.ndarray:
    """Return int64 offsets ``[0, cumsum(counts)...]``.

    Where each counted run starts, and the total at the end.

    Examples
    --------
    >>> exclusive_sum([2, 0, 3]).tolist()
    [0, 2, 2, 5]
    """
    counts = np.asarray(counts, dtype=np.int64)
    out = np.zeros(counts.shape[0] + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def group_offsets(counts_per_item: np.ndarray, item_offsets: np.ndarray) -> np.ndarray:
    """Return offsets of outputs per group, where group g owns items item_offsets[g]..[g+1].

    Examples
    --------
    >>> group_offsets(np.array([1, 0, 2, 1]), np.array([0, 2, 4])).tolist()
    [0, 1, 4]
    """
    return exclusive_sum(counts_per_item)[item_offsets]


@dataclass(frozen=True, eq=False, kw_only=True)
class PathArrays:
    """Many SVG paths as columnar arrays of Bézier segments.

    Path ``i`` is subpaths ``path_offsets[i]:path_offsets[i + 1]``; subpath ``s`` is
    segments ``subpath_offsets[s]:subpath_offsets[s + 1]``, each starting where the
    previous one ends, the first at ``start[s]``.

    Attributes
    ----------
    controls : ndarray of float64, shape (m, 4, 2)
        Control points of each segment from its start point: degree 1 uses rows 0-1,
        degree 2 rows 0-2, degree 3 rows 0-3. Unused rows repeat the end point, so row
        3 is always the end point and a bounding box may take all four rows.
    degree : ndarray of int8, shape (m,)
        1 (line), 2 (quadratic) or 3 (cubic).
    subpath_offsets : ndarray of int64, shape (k + 1,)
        Segment offsets of the subpaths.
    closed : ndarray of bool, shape (k,)
        Whether the subpath ended with Z: its closing edge, from the end of its last
        segment back to `start`, is implicit (never a segment).
    start : ndarray of float64, shape (k, 2)
        Each subpath's start point (a subpath may have no segments: ``"M1 2"``).
    path_offsets : ndarray of int64, shape (n + 1,)
        Subpath offsets of the paths.

    Raises
    ------
    InvalidGeometryError
        On construction, if a shape, an offset array (must start at 0, never decrease
        and end at the length of what it indexes), a degree, the continuity of segments
        or the repetition of unused control rows is wrong, or a coordinate is not
        finite. The message and the ``path_index`` attribute name the path when one is
        at fault.

    Notes
    -----
    Arrays are converted to the dtypes above and made C-contiguous (a copy only when
    needed). ``==`` compares every array exactly.
    """

    controls: np.ndarray
    degree: np.ndarray
    subpath_offsets: np.ndarray
    closed: np.ndarray
    start: np.ndarray
    path_offsets: np.ndarray

    def __post_init__(self) -> None:
        controls = _as_array(self.controls, np.float64, "controls")
        m = controls.shape[0] if controls.ndim == 3 else -1
        if controls.shape[1:] != (4, 2):
            raise InvalidGeometryError(f"controls must have shape (m, 4, 2), "
                                       f"not {controls.shape}")
        degree = _small_ints(self.degree, np.int8, "degree", (1, 2, 3))
        if degree.shape != (m,):
            raise InvalidGeometryError(f"degree must have shape ({m},) like controls, "
                                       f"not {degree.shape}")
        subpath_offsets = _offsets(self.subpath_offsets, "subpath_offsets", m,
                                   "the number of segments")
        k = subpath_offsets.shape[0] - 1
        closed = _small_ints(self.closed, np.bool_, "closed", (0, 1))
        if closed.shape != (k,):
            raise InvalidGeometryError(f"closed must have shape ({k},), one per subpath, "
                                       f"not {closed.shape}")
        start = _as_array(self.start, np.float64, "start")
        if start.shape != (k, 2):
            raise InvalidGeometryError(f"start must have shape ({k}, 2), one per subpath, "
                                       f"not {start.shape}")
        path_offsets = _offsets(self.path_offsets, "path_offsets", k, "the number of subpaths")
        for name, value in (("controls", controls), ("degree", degree),
                            ("subpath_offsets", subpath_offsets), ("closed", closed),
                            ("start", start), ("path_offsets", path_offsets)):
            object.__setattr__(self, name, value)
        self._check_geometry()

    def _check_geometry(self) -> None:
        sub, seg, code = check_layout(self.controls, self.degree, self.subpath_offsets,
                                      self.start)
        if code != 0:
            path = int(np.searchsorted(self.path_offsets, sub, side="right") - 1)
            where = f" (segment {seg})" if seg >= 0 else " (subpath start)"
            error = InvalidGeometryError(
                f"path {path}: {LAYOUT_MESSAGES[int(code)]}{where}")
            error.path_index = path
            raise error

    @classmethod
    def from_kernel(cls, *, controls: np.ndarray, degree: np.ndarray,
                    subpath_offsets: np.ndarray, closed: np.ndarray, start: np.ndarray,
                    path_offsets: np.ndarray) -> PathArrays:
        """Return the arrays a kernel built to this layout as they are, unchecked.

        For library code whose kernel writes the layout by construction (the clip's
        output): the checks of the constructor would cost a third of a clip. The arrays
        must already have the dtypes, shapes and contents the class describes.
        """
        paths = object.__new__(cls)
        for name, value in (("controls", controls), ("degree", degree),
                            ("subpath_offsets", subpath_offsets), ("closed", closed),
                            ("start", start), ("path_offsets", path_offsets)):
            object.__setattr__(paths, name, value)
        return paths

    @classmethod
    def empty(cls) -> PathArrays:
        """Return a `PathArrays` of no paths."""
        return cls(controls=np.empty((0, 4, 2)), degree=np.empty(0, np.int8),
                   subpath_offsets=np.zeros(1, np.int64), closed=np.empty(0, bool),
                   start=np.empty((0, 2)), path_offsets=np.zeros(1, np.int64))

    def __len__(self) -> int:
        """Return the number of paths."""
        return self.path_offsets.shape[0] - 1

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PathArrays):
            return NotImplemented
        return all(np.array_equal(getattr(self, name), getattr(other, name))
                   for name in ("controls", "degree", "subpath_offsets", "closed", "start",
                                "path_offsets"))

    __hash__ = None  # type: ignore[assignment]  # unhashable: == compares arrays

    def take(self, index: npt.ArrayLike) -> PathArrays:
        """Return the paths at `index` (int, any order, repeats allowed), as a `PathArrays`.

        Copied from checked arrays: the layout holds by construction.

        Examples
        --------
        >>> from rnsca.io.svgpath import parse_paths, write_paths
        >>> write_paths(parse_paths(["M0 0L1 1", "M5 5L6 5"]).take([1, 1, 0]))
        ['M5 5H6', 'M5 5H6', 'M0 0 1 1']
        """
        rows = np.ascontiguousarray(index, dtype=np.int64)
        first, last = self.path_offsets[rows], self.path_offsets[rows + 1]
        subpaths = _ranges(first, last)
        segments = _ranges(self.subpath_offsets[subpaths], self.subpath_offsets[subpaths + 1])
        return PathArrays.from_kernel(
            controls=self.controls[segments], degree=self.degree[segments],
            subpath_offsets=exclusive_sum(np.diff(self.subpath_offsets)[subpaths]),
            closed=self.closed[subpaths], start=self.start[subpaths],
            path_offsets=exclusive_sum(last - first))

    def boxes(self) -> np.ndarray:
        """Return each path's bounding box of control and start points, float64 (n, 4).

        Rows ``[xmin, ymin, xmax, ymax]``: the curves lie in the box (convex hull
        property), and so does a filled subpath's closing line. A path of no subpaths
        has a NaN row.

        Examples
        --------
        >>> from rnsca.io.svgpath import parse_paths
        >>> parse_paths(["M0 0Q5 4 2 1", "M-1 3"]).boxes().tolist()
        [[0.0, 0.0, 5.0, 4.0], [-1.0, 3.0, -1.0, 3.0]]
        """
        n = len(self)
        controls = np.empty((n, 4))
        starts = np.empty((n, 4))
        vertex_boxes(self.controls.reshape(-1, 2), 4 * self.subpath_offsets[self.path_offsets],
                     controls)
        vertex_boxes(self.start, self.path_offsets, starts)
        return np.column_stack([np.fmin(controls[:, :2], starts[:, :2]),
                                np.fmax(controls[:, 2:], starts[:, 2:])])

    def path(self, index: int) -> PathArrays:
        """Return path `index` (negative counts from the end) as a `PathArrays` of one."""
        n = len(self)
        if not -n <= index < n:
            raise IndexError(f"path index {index} out of range for {n} paths")
        index %= n
        s0, s1 = int(self.path_offsets[index]), int(self.path_offsets[index + 1])
        g0, g1 = int(self.subpath_offsets[s0]), int(self.subpath_offsets[s1])
        return PathArrays(controls=self.controls[g0:g1], degree=self.degree[g0:g1],
                          subpath_offsets=self.subpath_offsets[s0:s1 + 1] - g0,
                          closed=self.closed[s0:s1], start=self.start[s0:s1],
                          path_offsets=np.array([0, s1 - s0], dtype=np.int64))


def _ranges(first: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Return ``first[0]..stop[0]-1, first[1]..stop[1]-1, ...`` concatenated (int64)."""
    sizes = stop - first
    offset = np.arange(int(sizes.sum()), dtype=np.int64) - np.repeat(np.cumsum(sizes) - sizes,
                                                                      sizes)
    return np.repeat(first, sizes).astype(np.int64) + offset


def _as_array(value: npt.ArrayLike, dtype: npt.DTypeLike, name: str) -> np.ndarray:
    try:
        return np.ascontiguousarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise InvalidGeometryError(f"{name} must be convertible to {np.dtype(dtype)}: "
                                   f"{exc}") from None


def _small_ints(value: npt.ArrayLike, dtype: npt.DTypeLike, name: str,
                allowed: tuple[int, ...]) -> np.ndarray:
    """Return `value` as `dtype` after checking its values (a cast must not wrap)."""
    array = np.asarray(value)
    if array.dtype != dtype:
        if array.dtype.kind not in "biu" or not np.isin(array, allowed).all():
            raise InvalidGeometryError(f"{name} values must be in {allowed}")
    elif array.dtype != np.bool_ and not np.isin(array, allowed).all():
        raise InvalidGeometryError(f"{name} values must be in {allowed}")
    return np.ascontiguousarray(array, dtype=dtype)


def in_threads(function: Callable[..., np.ndarray], rows: np.ndarray, *, min_rows: int = 1024,
               **options: Any) -> np.ndarray:
    """Return ``function(rows, **options)``, computed on chunks of rows in threads.

    For a vectorised call that releases the GIL (NumPy's ufuncs, Shapely's GEOS calls)
    and whose rows do not depend on each other: one chunk per core (at most 8), the
    results concatenated, the same values as one call. Fewer than `min_rows` rows (or
    one core): one call in this thread.
    """
    workers = min(os.cpu_count() or 1, 8)
    if workers == 1 or rows.shape[0] < min_rows:
        return function(rows, **options)
    chunks = np.array_split(rows, workers)
    with ThreadPoolExecutor(workers) as pool:
        return np.concatenate(list(pool.map(lambda chunk: function(chunk, **options),
                                            chunks)))
