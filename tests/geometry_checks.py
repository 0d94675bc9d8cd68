"""Comparisons of clipped geometries with Shapely, shared by the geometry test layers.

Shapely is the oracle: ``shapely.intersection(geometry, box)`` for ``boundary="closed"``
and ``shapely.clip_by_rect(geometry, *window)`` for ``boundary="interior"``. rnsca keeps the
input's dimension, so only the parts of Shapely's result with that dimension are
compared (a line that touches the window at a point gives nothing, where Shapely gives a
POINT; a polygon that shares only an edge gives nothing, where Shapely gives a LINESTRING).

Geometric equality, never vertex lists (ring start, orientation, part splitting and
repeated vertices differ between implementations), within ``TOLERANCE = 1e-9`` of the
window's size:

- every kind: line parts shorter than the tolerance and polygon parts thinner than it
  are left out on both sides (within the tolerance of nothing; GEOS returns such slivers
  where a line grazes a corner in floating point);
- every kind: Hausdorff distance between the normalized geometries (``densify=0.01``, so
  the middles of long segments count, not only the vertices) within the tolerance;
  a side that is empty is equal to a side whose whole extent is within the tolerance;
- points: that and the same number of distinct points;
- lines: total lengths equal within ``2 * tolerance`` per vertex, each side measured
  after a union snap-rounded to a grid of the tolerance (``grid_size``), so that how
  often a line runs over the same place, or a hair beside it, does not count (Shapely's
  overlay merges a line that doubles back on itself, unless rounding keeps the two
  passes an ulp apart), and GEOS's snap-rounding keeps the measure robust where
  buffers and plain overlays of such lines are not;
- polygons: the symmetric difference's area within ``tolerance * (perimeter of both)``,
  the area that moving every boundary point by the tolerance can sweep; the output
  passes ``shapely.is_valid``; Shapely's ``clip_by_rect`` output, which GEOS does not
  promise to be valid, is made valid first.

Every output coordinate must lie in the closed window, with no tolerance.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely import GeometryType

from rnsca import Window
from tests.cases import exact_clip

__all__ = [
    "TOLERANCE",
    "DENSIFY",
    "assert_dimension",
    "assert_equal_geometry",
    "assert_inside_window",
    "assert_matches_shapely",
    "assert_valid_polygons",
    "assert_z_on_input",
    "dimension_of_type",
    "exact_line_clip",
    "flat_parts",
    "geometries_of",
    "parts_of_dimension",
    "shapely_can_judge",
    "shapely_clip",
]

#: Geometric equality within this fraction of the window's size (rnsca's exact promise).
TOLERANCE = 1e-9
#: Hausdorff densification: each segment is split into 100 for the distance.
DENSIFY = 0.01

_DIMENSION = {
    GeometryType.POINT: 0,
    GeometryType.MULTIPOINT: 0,
    GeometryType.LINESTRING: 1,
    GeometryType.LINEARRING: 1,
    GeometryType.MULTILINESTRING: 1,
    GeometryType.POLYGON: 2,
    GeometryType.MULTIPOLYGON: 2,
}


def dimension_of_type(geometry) -> int:
    """Return the dimension of `geometry`'s type (0, 1, 2), empty or not; -1 for collections."""
    return _DIMENSION.get(GeometryType(shapely.get_type_id(geometry)), -1)


def flat_parts(geometry) -> list:
    """Return the non-empty single parts of `geometry`, collections flattened recursively."""
    out = []
    for part in shapely.get_parts(geometry):
        kind = GeometryType(shapely.get_type_id(part))
        if kind in (GeometryType.GEOMETRYCOLLECTION, GeometryType.MULTIPOINT,
                    GeometryType.MULTILINESTRING, GeometryType.MULTIPOLYGON):
            out.extend(flat_parts(part))
        elif not part.is_empty:
            out.append(part)
    return out


def parts_of_dimension(geometry, dimension: int):
    """Return the parts of `geometry` of one dimension, as one geometry.

    Points as a MULTIPOINT; lines of non-zero length as a MULTILINESTRING (rings as
    lines); polygons of non-zero area as their union (made valid first, if a part is
    invalid), a POLYGON or MULTIPOLYGON. Empty if there are none.
    """
    parts = [p for p in flat_parts(geometry) if dimension_of_type(p) == dimension]
    if dimension == 0:
        return shapely.MultiPoint(parts)
    if dimension == 1:
        return shapely.MultiLineString([shapely.LineString(p.coords) for p in parts
                                        if shapely.length(p) > 0])
    polygons = [shapely.make_valid(p) if not p.is_valid else p for p in parts]
    polygons = [q for p in polygons for q in flat_parts(p)
                if dimension_of_type(q) == 2 and shapely.area(q) > 0]
    if not polygons:
        return shapely.MultiPolygon()
    return shapely.union_all(polygons)


def geometries_of(result) -> np.ndarray:
    """Return the geometries of a `rnsca.RaggedClipResult` as a Shapely array.

    ``shapely.from_ragged_array`` (2.2.0) fails with an IndexError on a LINESTRING or
    MULTIPOINT array without a single coordinate (all geometries empty), even on what
    ``to_ragged_array`` itself writes; such arrays are built here as empties.
    """
    kind = GeometryType(result.geometry_type)
    if result.coords.shape[0] == 0 and kind != GeometryType.POINT:
        count = result.offsets[-1].shape[0] - 1
        return shapely.empty(count, geom_type=kind)
    return shapely.from_ragged_array(kind, result.coords, result.offsets)


def shapely_clip(geometry, window, boundary: str):
    """Return Shapely's clip of `geometry`: intersection (closed) or clip_by_rect (interior)."""
    bounds = Window.of(window).bounds
    if boundary == "closed":
        return shapely.intersection(geometry, shapely.box(*bounds))
    assert boundary == "interior", boundary
    return shapely.clip_by_rect(geometry, *bounds)


def _segments_of(geometry) -> np.ndarray:
    """Return every segment ``[x0, y0, x1, y1]`` of the lines and rings of `geometry`."""
    rows = []
    for part in flat_parts(geometry):
        lines = shapely.get_rings(part) if dimension_of_type(part) == 2 else [part]
        for line in lines:
            c = shapely.get_coordinates(line)
            if len(c) > 1:
                rows.append(np.hstack([c[:-1], c[1:]]))
    return np.concatenate(rows) if rows else np.empty((0, 4))


def shapely_can_judge(geometries, window, boundary: str) -> bool:
    """Return whether GEOS's clip of `geometries` is accurate to 1e-9 of the window.

    Two ways GEOS misses (rnsca does not: its cut points are exact, double-double from
    the nearer end, and `exact_line_clip` judges them there instead):

    - GEOS cuts a segment at an edge line in double precision, y = y0 + (c - x0) dy/dx:
      a few ulps of the coordinates, times the segment's steepness against that edge.
      For a segment nearly parallel to an edge (|dy/dx| of 1e7 and more) that passes
      the 1e-9 * window size the comparison allows.
    - GEOS's overlay nodes a line against itself: where the line runs back over itself
      a sub-ulp distance away (0.25 0.25 back to 0 1.4e-45), its snapping fallback drops
      pieces or adds ones outside the window. For lines, GEOS's answer is therefore
      also checked against `exact_line_clip`.
    """
    w = Window.of(window)
    segments = np.concatenate([_segments_of(g) for g in geometries] + [np.empty((0, 4))])
    if segments.shape[0]:
        dx = np.abs(segments[:, 2] - segments[:, 0])
        dy = np.abs(segments[:, 3] - segments[:, 1])
        sloped = (dx > 0) & (dy > 0)
        if sloped.any():
            steep = float(np.max(np.maximum(dx, dy)[sloped] / np.minimum(dx, dy)[sloped]))
            scale = max(float(np.abs(segments).max()), *(abs(b) for b in w.bounds))
            eps = float(np.finfo(np.float64).eps)
            if 16 * eps * scale * steep > 0.1 * TOLERANCE * w.size:
                return False
    for geometry in geometries:
        if dimension_of_type(geometry) != 1:
            continue
        geos = parts_of_dimension(shapely_clip(geometry, w, boundary), 1)
        try:
            assert_equal_geometry(geos, exact_line_clip(geometry, w, boundary),
                                  TOLERANCE * w.size)
        except AssertionError:
            return False
    return True


def exact_line_clip(geometry, window, boundary: str):
    """Return the clip of a (multi)line in exact rational arithmetic, as a MULTILINESTRING.

    Segment by segment (`tests.cases.exact_clip`, rounded to the nearest floats): a
    point of contact is no piece; with ``boundary="interior"`` a piece lying on an edge
    line is dropped too. Pieces are not joined: compare geometrically.
    """
    w = Window.of(window)
    pieces = []
    for segment in _segments_of(geometry):
        clipped = exact_clip(segment, w.bounds)
        if clipped is None:
            continue
        x0, y0, x1, y1 = clipped[0]
        on_edge = ((x0 == x1 and x0 in (w.xmin, w.xmax))
                   or (y0 == y1 and y0 in (w.ymin, w.ymax)))
        if boundary == "interior" and on_edge:
            continue
        pieces.append([(x0, y0), (x1, y1)])
    return shapely.MultiLineString(pieces)


def _extent(geometry) -> float:
    if geometry.is_empty:
        return 0.0
    xmin, ymin, xmax, ymax = shapely.bounds(geometry)
    return float(np.hypot(xmax - xmin, ymax - ymin))


def _count_parts(geometry) -> int:
    return len(flat_parts(geometry))


def _without_slivers(geometry, tolerance: float):
    """Return `geometry` without line parts shorter than `tolerance` and polygon parts
    thinner than it (area below tolerance times half the perimeter): within the
    tolerance of nothing. GEOS returns such slivers where a line grazes a corner."""
    parts = flat_parts(geometry)
    kept = [p for p in parts
            if dimension_of_type(p) == 0
            or (dimension_of_type(p) == 1 and shapely.length(p) > tolerance)
            or (dimension_of_type(p) == 2
                and shapely.area(p) > tolerance * shapely.length(p) / 2)]
    if len(kept) == len(parts):
        return geometry
    dimensions = {dimension_of_type(p) for p in kept}
    if len(dimensions) != 1:
        return shapely.GeometryCollection(kept)
    return parts_of_dimension(shapely.GeometryCollection(kept), dimensions.pop())


def assert_equal_geometry(ours, expected, tolerance: float, where: str = "") -> None:
    """Check that two geometries of the same dimension are equal within `tolerance`.

    See the module docstring for what is compared per dimension. `ours` may be invalid
    only if the caller allows it (invalid input); it is then made valid for the area test.
    """
    context = f"{where}\n  ours:     {ours.wkt}\n  expected: {expected.wkt}"
    ours, expected = _without_slivers(ours, tolerance), _without_slivers(expected, tolerance)
    if ours.is_empty or expected.is_empty:
        assert _extent(ours) <= tolerance and _extent(expected) <= tolerance, (
            f"one side is empty, the other is not: {context}")
        return
    dims = {dimension_of_type(p) for p in flat_parts(ours) + flat_parts(expected)}
    assert len(dims) == 1, f"dimensions differ {dims}: {context}"
    dim = dims.pop()
    distance = shapely.hausdorff_distance(shapely.normalize(ours), shapely.normalize(expected),
                                          densify=DENSIFY)
    assert distance <= tolerance, f"Hausdorff distance {distance} > {tolerance}: {context}"
    if dim == 0:
        ours_points = {tuple(c) for c in shapely.get_coordinates(ours)}
        expected_points = {tuple(c) for c in shapely.get_coordinates(expected)}
        assert len(ours_points) == len(expected_points), (
            f"{len(ours_points)} distinct points, expected {len(expected_points)}: {context}")
    elif dim == 1:
        # Snap-rounded to the tolerance's grid, the two sides' near-identical pieces become
        # identical and a line running back over itself counts once (GEOS's snap-rounding
        # overlay is robust where buffers and plain overlays of such lines are not).
        ours_length = shapely.length(shapely.union_all(ours, grid_size=tolerance))
        expected_length = shapely.length(shapely.union_all(expected, grid_size=tolerance))
        allowed = 2 * tolerance * (shapely.get_num_coordinates(ours)
                                   + shapely.get_num_coordinates(expected))
        assert abs(ours_length - expected_length) <= allowed, (
            f"length {ours_length} != {expected_length} (allowed {allowed}): {context}")
    else:
        a = ours if ours.is_valid else shapely.make_valid(ours)
        b = expected if expected.is_valid else shapely.make_valid(expected)
        swept = shapely.area(shapely.symmetric_difference(a, b))
        allowed = tolerance * (shapely.length(a) + shapely.length(b))
        assert swept <= allowed, (
            f"symmetric difference area {swept} > {allowed} "
            f"(areas {shapely.area(a)} and {shapely.area(b)}): {context}")


def assert_inside_window(geometry, window, where: str = "") -> None:
    """Check that every coordinate of `geometry` lies in the closed window (no tolerance)."""
    w = Window.of(window)
    xy = shapely.get_coordinates(geometry)
    outside = ((xy[:, 0] < w.xmin) | (xy[:, 0] > w.xmax)
               | (xy[:, 1] < w.ymin) | (xy[:, 1] > w.ymax))
    assert not outside.any(), (
        f"{where}: vertices {xy[outside].tolist()} outside the window {w.bounds}: "
        f"{geometry.wkt}")


def assert_dimension(geometry, dimension: int, where: str = "") -> None:
    """Check that `geometry` is empty or has only parts of `dimension` (no leftovers)."""
    found = {dimension_of_type(p) for p in flat_parts(geometry)}
    assert found <= {dimension}, (
        f"{where}: parts of dimension {sorted(found)}, expected only {dimension}: "
        f"{geometry.wkt}")


def assert_valid_polygons(geometry, where: str = "") -> None:
    """Check ``shapely.is_valid`` on polygonal output, with GEOS's reason on failure."""
    assert shapely.is_valid(geometry), (
        f"{where}: invalid output ({shapely.is_valid_reason(geometry)}): {geometry.wkt}")


def assert_matches_shapely(ours, geometry, window, boundary: str, where: str = "") -> None:
    """Check one clipped geometry against Shapely's clip of its input, per the module rules.

    Checks, in order: every vertex in the closed window; only parts of the input's
    dimension; polygon output valid; equal to the parts of Shapely's result with the
    input's dimension.
    """
    w = Window.of(window)
    dimension = dimension_of_type(geometry)
    where = f"{where} {boundary} clip of {geometry.wkt} to {w.bounds}"
    assert_inside_window(ours, w, where)
    assert_dimension(ours, dimension, where)
    if dimension == 2:
        assert_valid_polygons(ours, where)
    reference = parts_of_dimension(shapely_clip(geometry, w, boundary), dimension)
    assert_equal_geometry(parts_of_dimension(ours, dimension), reference,
                          TOLERANCE * w.size, where)


def assert_z_on_input(ours, geometry, window, where: str = "") -> None:
    """Check Z: kept on the input's vertices, linearly interpolated on new vertices.

    Each output vertex must carry either the Z of an input vertex at the same XY
    (exactly) or the Z linearly interpolated along an input segment it lies on (within
    1e-9 of the window's size), within ``1e-9 * (|z0| + |z1| + 1)`` plus the effect of
    the cut point's own rounding (``|dz| * 64 eps * scale / length``). Either is allowed
    because a cut point can land on the XY of another input vertex (a line that comes
    back to a vertex on the edge). Output vertices on no input segment (window corners a
    polygon's boundary walk adds inside the polygon) are not checked.
    """
    w = Window.of(window)
    xyz = shapely.get_coordinates(ours, include_z=True)
    if xyz.shape[0] == 0:
        return
    assert not np.isnan(xyz[:, 2]).any(), f"{where}: output lost its Z: {ours.wkt}"
    lines = [p for p in flat_parts(geometry) if dimension_of_type(p) > 0]
    rings = []
    for part in lines:
        rings.extend(shapely.get_rings(part) if dimension_of_type(part) == 2 else [part])
    coords = [shapely.get_coordinates(r, include_z=True) for r in rings]
    vertices = np.concatenate(coords + [shapely.get_coordinates(geometry, include_z=True)])
    segments = np.concatenate([np.hstack([c[:-1], c[1:]]) for c in coords if len(c) > 1]
                              or [np.empty((0, 6))])
    a, b = segments[:, 0:3], segments[:, 3:6]
    d = b[:, :2] - a[:, :2]
    dd = (d * d).sum(axis=1)
    length = np.sqrt(dd)
    dz = np.abs(b[:, 2] - a[:, 2])
    eps = float(np.finfo(np.float64).eps)
    scale = max(abs(v) for v in w.bounds) + w.size
    with np.errstate(divide="ignore", invalid="ignore"):
        cut = np.where(dd > 0, dz * 64 * eps * scale / length, 0.0)
    allowed = TOLERANCE * (np.abs(a[:, 2]) + np.abs(b[:, 2]) + 1.0) + cut
    for p in xyz:
        same = (vertices[:, 0] == p[0]) & (vertices[:, 1] == p[1])
        if (vertices[same, 2] == p[2]).any():
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(((p[:2] - a[:, :2]) * d).sum(axis=1) / dd, 0.0, 1.0)
        t = np.where(dd > 0, t, 0.0)
        foot = a[:, :2] + t[:, None] * d
        on = np.hypot(*(foot - p[:2]).T) <= TOLERANCE * w.size
        if not on.any() and not same.any():
            continue  # a window corner added by the boundary walk
        z = a[on, 2] + t[on] * (b[on, 2] - a[on, 2])
        assert (np.abs(z - p[2]) <= allowed[on]).any(), (
            f"{where}: vertex {p[:2].tolist()} has Z {p[2]}; input vertices there have "
            f"{vertices[same, 2].tolist()}, interpolation on the input segments through it "
            f"gives {z.tolist()}: {ours.wkt}")
