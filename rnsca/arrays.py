"""Ragged geometry arrays: flat coordinates plus offsets, the layout of GeoArrow.

This is the layout ``shapely.to_ragged_array`` returns: ``coords`` (n, 2) or (n, 3),
and int offset arrays innermost level first. For a polygon with a hole::

    coords  = [shell: 0..4, hole: 5..9]        ring_offsets    = [0, 5, 10]
                                               geometry_offsets = [0, 2]   (rings per polygon)

`Ragged` validates that layout once; the clipping functions take its levels apart into
the three shapes the kernels know: points, lines (parts) and polygons (rings).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np
import numpy.typing as npt
import shapely

from rnsca.errors import InvalidGeometryError, UnsupportedGeometryError
from rnsca.kernels.validate import all_finite, first_open_ring

__all__ = ["GeometryKind", "Ragged", "OUTPUT_KIND", "exclusive_sum", "geometry_error",
           "group_offsets"]


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


def _offsets(array: npt.ArrayLike, name: str, length: int) -> np.ndarray:
    """Return `array` as int64 offsets into a level of `length` items, or raise."""
    try:
        out = np.asarray(array)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"{name} must be an integer array") from None
    if out.ndim != 1 or out.dtype.kind not in "iu" or out.shape[0] < 1:
        raise InvalidGeometryError(
            f"{name} must be a non-empty 1-d integer array, got shape {out.shape} "
            f"of {out.dtype}")
    out = np.ascontiguousarray(out, dtype=np.int64)
    if out[0] != 0 or out[-1] != length:
        raise InvalidGeometryError(
            f"{name} must start at 0 and end at {length} (the length of the level below), "
            f"got {out[0]} and {out[-1]}")
    steps = np.diff(out)
    if (steps < 0).any():
        at = int(np.argmax(steps < 0))
        raise InvalidGeometryError(f"{name} decreases at index {at + 1}")
    return out


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
        C-contiguous; finite (an all-NaN row is an empty POINT, as Shapely writes it).
    offsets : tuple of ndarray of int64
        Innermost level first, ``kind.depth`` arrays.
    """

    kind: GeometryKind
    coords: np.ndarray
    offsets: tuple

    @classmethod
    def of(cls, geometry_type: GeometryKind | shapely.GeometryType | str,
           coords: npt.ArrayLike, offsets: Sequence[npt.ArrayLike], *,
           check_finite: bool = True) -> Ragged:
        """Return a validated `Ragged` from the triple ``shapely.to_ragged_array`` gives.

        With ``check_finite=False`` the caller takes over the finiteness check (it must
        call `check_finite` itself, or check as it reads the coordinates): the line
        clip does it in its first pass over the coordinates.

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
        ragged = cls(kind, xy, tuple(levels))
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

    def to_shapely(self) -> np.ndarray:
        """Return the geometries as a Shapely array."""
        return shapely.from_ragged_array(self.kind.shapely_type, self.coords, self.offsets)

    def geometry_of_coordinate(self, index: int) -> int:
        """Return the index of the geometry that holds coordinate row `index`."""
        g = index
        for level in self.offsets:
            g = int(np.searchsorted(level, g, side="right")) - 1
        return g

    def check_finite(self) -> None:
        """Raise `InvalidGeometryError` naming the first non-finite coordinate, if any.

        An all-NaN row of a POINT array is an empty point, not an error.
        """
        if all_finite(self.coords):
            return
        finite = np.isfinite(self.coords)
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
