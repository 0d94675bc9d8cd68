"""Paths as Shapely geometries, for checking clipped curves against Shapely.

Both sides are flattened finely (`flatten_paths`): strokes become (multi)line strings;
filled paths become the region their fill rule paints, built from the faces of the
noded outlines, each kept by the winding number at a point inside it. `rnsca.verify`
then compares them as it compares any lines or polygons.
"""

from __future__ import annotations

import numpy as np
import shapely

from rnsca.arrays import PathArrays
from rnsca.clip_svg import Fill, flatten_paths
from rnsca.verify.cost import estimated_crossings

__all__ = ["paths_to_shapely", "select_paths", "filled_region", "winding_numbers"]

# Points x edges evaluated at once by `winding_numbers` (memory bound for big inputs).
_WINDING_CHUNK = 1 << 22


def paths_to_shapely(paths: PathArrays, tolerance: float, fill: Fill | None,
                     max_crossings: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Return one Shapely geometry per path (its strokes, or its filled region), and cost.

    Parameters
    ----------
    paths : PathArrays
    tolerance : float
        Flattening accuracy (user units).
    fill : Fill or None
        None: each path as a MultiLineString of its subpaths (empty if none). A fill
        rule: the region painted under it, a (Multi)Polygon, every subpath closed.
    max_crossings : float, optional
        With a fill rule: a path whose flattened outlines cross one another more than
        about this many times (`rnsca.verify.cost`) is not built; its geometry is None.

    Returns
    -------
    geometries : ndarray of object, shape (n,)
    crossings : ndarray of float64, shape (n,)
        The estimated crossings of each path's outlines; 0 where not estimated (strokes,
        or no `max_crossings`).
    """
    coords, line_offsets, line_path = flatten_paths(paths, tolerance, close=fill is not None)
    crossings = np.zeros(len(paths))
    if fill is not None and max_crossings is not None:
        edge_path = np.repeat(line_path, np.diff(line_offsets) - 1)
        ends = np.ones(coords.shape[0], dtype=bool)  # the last vertex of each polyline
        ends[line_offsets[1:] - 1] = False
        crossings = estimated_crossings(coords[ends], coords[np.roll(ends, 1)], edge_path,
                                        len(paths))
    lines = np.empty(line_path.shape[0], dtype=object)
    for j in range(line_path.shape[0]):
        lines[j] = coords[line_offsets[j]:line_offsets[j + 1]]
    out = np.empty(len(paths), dtype=object)
    for i in range(len(paths)):
        parts = [p for p in lines[line_path == i] if p.shape[0] >= 2]
        if fill is None:
            out[i] = shapely.multilinestrings([shapely.linestrings(p) for p in parts]) \
                if parts else shapely.MultiLineString()
        elif max_crossings is None or crossings[i] <= max_crossings:
            out[i] = filled_region(parts, fill)
    return out, crossings


def select_paths(paths: PathArrays, rows: np.ndarray) -> PathArrays:
    """Return paths `rows` (indices, in that order) of `paths` as a `PathArrays`."""
    return paths.take(rows)


def filled_region(rings: list[np.ndarray], fill: Fill) -> shapely.MultiPolygon:
    """Return the region that closed polylines `rings` paint under the fill rule.

    The outlines are noded and polygonized; each face is kept when the winding number
    of a point inside it is non-zero (nonzero) or odd (evenodd).
    """
    rings = [r for r in rings if r.shape[0] >= 4]
    if not rings:
        return shapely.MultiPolygon()
    outline = shapely.union_all([shapely.linestrings(r) for r in rings])
    faces = np.asarray(shapely.get_parts(shapely.polygonize([outline])))
    faces = faces[shapely.area(faces) > 0] if faces.size else faces
    if faces.size == 0:
        return shapely.MultiPolygon()
    inside = shapely.point_on_surface(faces)
    points = shapely.get_coordinates(inside)
    winding = winding_numbers(points, rings)
    keep = winding != 0 if fill is Fill.NONZERO else (winding % 2) == 1
    region = shapely.union_all(faces[keep])
    polygons = [g for g in shapely.get_parts(region)
                if g.geom_type == "Polygon" and not g.is_empty]
    return shapely.MultiPolygon(polygons)


def winding_numbers(points: np.ndarray, rings: list[np.ndarray]) -> np.ndarray:
    """Return the winding number of the closed polylines `rings` around each point."""
    a = np.concatenate([r[:-1] for r in rings])
    b = np.concatenate([r[1:] for r in rings])
    total = np.zeros(points.shape[0], dtype=np.int64)
    step = max(1, _WINDING_CHUNK // max(1, a.shape[0]))
    for lo in range(0, points.shape[0], step):
        p = points[lo:lo + step, None, :]
        cross = (b[:, 0] - a[:, 0]) * (p[..., 1] - a[:, 1]) - \
            (p[..., 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
        up = (a[:, 1] <= p[..., 1]) & (p[..., 1] < b[:, 1]) & (cross > 0)
        down = (b[:, 1] <= p[..., 1]) & (p[..., 1] < a[:, 1]) & (cross < 0)
        total[lo:lo + step] = up.sum(axis=1) - down.sum(axis=1)
    return total
