"""The Hausdorff distance between aligned lines, points or polygon boundaries.

GEOS's discrete Hausdorff distance measures from vertices only; `hausdorff` also samples
lines where a gap inside a straight stretch would hide (see its docstring), and finds
nearest segments in NumPy from a spatial index.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property

import numpy as np
import shapely

__all__ = ["hausdorff"]

#: Candidate (point, segment) pairs one query of the index should return: about 100 bytes
#: each on their way through, so ~50 MB however many long segments pass by each point.
_PAIRS_PER_QUERY = 1 << 19
#: Points in the first query, before the pairs per point are known; and at most.
_FIRST_QUERY = 1 << 10
_LARGEST_QUERY = 1 << 16


def hausdorff(a: np.ndarray, b: np.ndarray, lineal: bool, radius: np.ndarray,
              check_time: Callable[[], None] | None = None) -> np.ndarray:
    """Return the Hausdorff distance between aligned point sets or (multi)line strings.

    GEOS's discrete Hausdorff distance measures only from vertices, so it misses a gap
    inside a straight stretch (two pieces with a hole between them against one piece:
    every vertex of each lies on the other). Lines are therefore also sampled midway
    between consecutive positions along them of their own vertices and of the points
    where the other side's vertices project, which finds such a gap's middle exactly.
    A stretch between the projections of the two ends of one segment of the other side
    needs no sample: each of its points is within the larger of the two ends' distances
    of that segment. Nearest segments come from exact vertex matches first (a clip
    copies most vertices), then from a spatial index searched within `radius` of each
    point (where a correct clip puts every vertex), then in growing circles.
    `check_time`, if given, is called before each search of the index: what it raises
    ends the measurement (a time limit).
    """
    deviation = np.zeros(a.shape[0])
    with np.errstate(invalid="ignore"):  # a NaN output vertex gives a NaN deviation
        sides = _Linework(a), _Linework(b)
        for source, target in (sides, sides[::-1]):
            _directed_hausdorff(source, target, lineal, radius, deviation, check_time)
    return deviation


def _directed_hausdorff(source: _Linework, target: _Linework, lineal: bool,
                        radius: np.ndarray, deviation: np.ndarray,
                        check_time: Callable[[], None] | None) -> None:
    """Raise `deviation` to the distances from points of `source` to `target`, per owner."""
    owner = source.vertex_owner
    distance, segment, position = target.nearest(source.vertices, owner, radius[owner],
                                                 check_time)
    np.maximum.at(deviation, owner, distance)
    if not lineal or not owner.size:
        return
    # Stretches of the target between the projections of a source segment's ends
    # (on one part of the target: positions at a part's end and at the next one's
    # start are equal, the points are not).
    joined = np.flatnonzero(source.joined)
    part = target.part[segment[joined]]
    same = part == target.part[segment[joined + 1]]
    spanned = _interval_keys(part[same], position[joined[same]],
                             position[joined[same] + 1])
    # Positions along the target: its vertices, and where the source's project.
    along = np.concatenate([target.vertex_along, position])
    segment = np.concatenate([target.vertex_segment, segment])
    owner = np.concatenate([target.vertex_owner, owner])
    # Ties sorted by segment: a stretch then starts in the segment of its lower end.
    order = np.lexsort((segment, along, owner))
    along, segment, owner = along[order], segment[order], owner[order]
    gap = (owner[1:] == owner[:-1]) & (along[1:] > along[:-1])
    middle = 0.5 * (along[1:] + along[:-1])[gap]
    holder = target.segment_at(segment[:-1][gap], middle)
    sampled = ~np.isin(_interval_keys(target.part[holder], along[:-1][gap],
                                      along[1:][gap]), spanned)
    if sampled.any():
        owner = owner[1:][gap][sampled]
        samples = target.point_at(holder[sampled], middle[sampled])
        distance, _, _ = source.nearest(samples, owner, radius[owner], check_time)
        np.maximum.at(deviation, owner, distance)


def _keys(group: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Return (group, first, second) rows as opaque values that compare by their bytes."""
    rows = np.empty(group.shape[0], dtype=[("group", "<i8"), ("first", "<f8"),
                                           ("second", "<f8")])
    rows["group"] = group
    rows["first"] = first + 0.0  # -0.0 becomes 0.0: equal values, equal bytes
    rows["second"] = second + 0.0
    return rows.view("V24")


def _interval_keys(group: np.ndarray, one: np.ndarray, other: np.ndarray) -> np.ndarray:
    return _keys(group, np.minimum(one, other), np.maximum(one, other))


class _Linework:
    """The segments of an array of point sets or (multi)line strings, spatially indexed.

    Consecutive vertices of a part make a segment; a part of one vertex (a point) is a
    segment of zero length. ``along`` positions run along each geometry's parts in
    order, restarting at 0 for each geometry.
    """

    def __init__(self, geometries: np.ndarray) -> None:
        parts, part_owner = shapely.get_parts(geometries, return_index=True)
        coords, part = shapely.get_coordinates(parts, return_index=True)
        count = coords.shape[0]
        owner = part_owner[part]
        joined = np.zeros(count, dtype=bool)  # vertex k and k + 1 are in the same part
        joined[:-1] = part[1:] == part[:-1]
        single = ~joined & np.r_[True, ~joined[:-1]]  # a part of one vertex
        step = np.zeros(count)
        step[1:] = np.where(joined[:-1], np.hypot(*(coords[1:] - coords[:-1]).T), 0.0)
        along = np.cumsum(step)
        first = np.r_[True, owner[1:] != owner[:-1]] if count else np.zeros(0, dtype=bool)
        along -= np.maximum.accumulate(np.where(first, along, 0.0))

        starts = np.flatnonzero(joined | single)
        ends = np.where(joined[starts], starts + 1, starts)
        self.vertices, self.vertex_owner, self.vertex_along = coords, owner, along
        self.joined = joined
        self.starts = starts
        self.start, self.end = coords[starts], coords[ends]
        self.owner = owner[starts]
        self.part = part[starts]
        self.along = along[starts]
        self.length = along[ends] - along[starts]
        # The segment a vertex starts, or for a part's last vertex the one it ends.
        self.vertex_segment = np.searchsorted(starts, np.arange(count), side="right") - 1
        self.box = shapely.bounds(geometries)

    @cached_property
    def index(self) -> shapely.STRtree:
        """Return a spatial index of the segments' boxes, each geometry in its own lane.

        Built when a point is not a vertex. In one index of every geometry's segments, a
        point would also meet the other geometries' segments around it, only to be
        thrown away: quadratic where many long lines lie over one another (a chunk of
        self-crossing lines across the window). So for the index only, each geometry is
        mapped to the unit square of its bounding box and shifted along x into lane
        ``2 * i`` (`_lane_boxes`).
        """
        with np.errstate(invalid="ignore"):  # a NaN vertex makes a box of nothing
            boxes = self._lane_boxes(np.minimum(self.start, self.end),
                                     np.maximum(self.start, self.end), self.owner)
        return shapely.STRtree(boxes)

    def _lane_boxes(self, lo: np.ndarray, hi: np.ndarray, owner: np.ndarray) -> np.ndarray:
        """Return the boxes from corners `lo` to `hi` mapped into their owners' lanes.

        Each step of the map (subtract, multiply by a positive number, add, clamp to the
        lane) is monotonic in floating point, so boxes that meet still meet once mapped:
        the index loses no candidate, and rounding can only add some. A box with a NaN
        corner is None (indexed as nothing).
        """
        box = self.box[owner]
        origin = np.nan_to_num(box[:, :2], nan=0.0, posinf=0.0, neginf=0.0)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            extent = np.maximum(box[:, 2] - box[:, 0], box[:, 3] - box[:, 1])
            unit = 1.0 / extent
            unit = np.where((extent > 0) & np.isfinite(unit), unit, 1.0)
            lane = 2.0 * owner
            x0, x1 = ((c[:, 0] - origin[:, 0]) * unit + lane for c in (lo, hi))
            y0, y1 = ((c[:, 1] - origin[:, 1]) * unit for c in (lo, hi))
        # The lane holds its geometry in [lane, lane + 1] x [0, 1] (up to rounding).
        x0, x1 = np.clip(x0, lane - 0.5, lane + 1.5), np.clip(x1, lane - 0.5, lane + 1.5)
        y0, y1 = np.clip(y0, -0.5, 1.5), np.clip(y1, -0.5, 1.5)
        boxes = shapely.box(x0, y0, x1, y1)
        boxes[~np.isfinite(np.column_stack([lo, hi])).all(axis=1)] = None
        return boxes

    def nearest(self, points: np.ndarray, owner: np.ndarray, radius: np.ndarray,
                check_time: Callable[[], None] | None = None,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return, per point, the distance to its owner's segments, the nearest and where.

        Returns ``(distance, segment, along)``: the nearest point to ``points[i]`` lies on
        ``segment[i]`` at position ``along[i]``. A non-finite point gets a NaN distance.
        Points are looked up a batch at a time, sized so that a query returns about
        `_PAIRS_PER_QUERY` candidate segments.
        """
        count = points.shape[0]
        distance = np.full(count, np.nan)
        segment = np.zeros(count, dtype=np.int64)
        along = np.zeros(count)
        # A point equal to one of its owner's vertices is on it.
        keys = _keys(owner, points[:, 0], points[:, 1])
        mine = _keys(self.vertex_owner, self.vertices[:, 0], self.vertices[:, 1])
        unique, inverse = np.unique(np.concatenate([mine, keys]), return_inverse=True)
        vertex_of = np.full(unique.shape[0], -1)
        vertex_of[inverse[:mine.shape[0]]] = np.arange(mine.shape[0])
        vertex = vertex_of[inverse[mine.shape[0]:]]
        on_vertex = vertex >= 0
        distance[on_vertex] = 0.0
        segment[on_vertex] = self.vertex_segment[vertex[on_vertex]]
        along[on_vertex] = self.vertex_along[vertex[on_vertex]]

        # The farthest corner of the owner's bounding box: every segment lies within it.
        box = self.box[owner]
        reach = np.hypot(np.maximum(np.abs(points[:, 0] - box[:, 0]),
                                    np.abs(points[:, 0] - box[:, 2])),
                         np.maximum(np.abs(points[:, 1] - box[:, 1]),
                                    np.abs(points[:, 1] - box[:, 3])))
        reach = reach * (1 + 1e-9) + np.finfo(float).tiny
        todo = np.flatnonzero(~on_vertex & np.isfinite(points).all(axis=1))
        radius = np.minimum(np.maximum(radius, np.finfo(float).tiny), reach)
        size = _FIRST_QUERY
        while todo.size:
            if check_time is not None:
                check_time()
            batch, todo = todo[:size], todo[size:]
            # Every segment within the radius has its box in the point's (widened by the
            # rounding of its corners): if one is found there, the nearest is among them.
            radii = radius[batch, None]
            hit, seg = self.index.query(self._lane_boxes(
                np.nextafter(points[batch] - radii, -np.inf),
                np.nextafter(points[batch] + radii, np.inf), owner[batch]))
            size = int(np.clip(_PAIRS_PER_QUERY * batch.size // max(hit.size, 1), 1,
                               _LARGEST_QUERY))
            point = batch[hit]
            keep = self.owner[seg] == owner[point]
            point, seg = point[keep], seg[keep]
            d, t = _point_segment(points[point], self.start[seg], self.end[seg])
            order = np.lexsort((d, point))
            best = order[np.r_[True, point[order][1:] != point[order][:-1]]] if order.size \
                else order
            last = radius[point[best]] >= reach[point[best]]
            best = best[(d[best] <= radius[point[best]]) | last]
            point, seg = point[best], seg[best]
            distance[point], segment[point] = d[best], seg
            along[point] = self.along[seg] + t[best] * self.length[seg]
            # A point not found within its owner's reach has no segment to be near.
            again = batch[np.isnan(distance[batch]) & (radius[batch] < reach[batch])]
            radius[again] = np.minimum(radius[again] * 16.0, reach[again])
            todo = np.concatenate([todo, again])
        return distance, segment, along

    def segment_at(self, segment: np.ndarray, along: np.ndarray) -> np.ndarray:
        """Return the segment holding each position `along`, searching on from `segment`."""
        segment = segment.copy()
        last = self.start.shape[0] - 1
        while True:
            nxt = np.minimum(segment + 1, last)
            beyond = ((along > self.along[segment] + self.length[segment]) & (segment < last)
                      & (self.owner[nxt] == self.owner[segment]))
            if not beyond.any():
                return segment
            segment[beyond] += 1

    def point_at(self, segment: np.ndarray, along: np.ndarray) -> np.ndarray:
        """Return the points at positions `along`, each on the given segment."""
        length = self.length[segment]
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(length > 0, (along - self.along[segment]) / length, 0.0)
        t = np.clip(t, 0.0, 1.0)[:, None]
        return self.start[segment] + t * (self.end[segment] - self.start[segment])


def _point_segment(points: np.ndarray, start: np.ndarray,
                   end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the distance from each point to its segment, and the nearest point's t."""
    direction = end - start
    squared = (direction ** 2).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(squared > 0, ((points - start) * direction).sum(axis=1) / squared, 0.0)
    t = np.clip(t, 0.0, 1.0)
    nearest = start + t[:, None] * direction
    return np.hypot(*(points - nearest).T), t
