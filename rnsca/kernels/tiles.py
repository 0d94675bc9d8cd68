"""Tile pyramids: which child tiles each clipped geometry goes to, and longitudes unwrapped.

World coordinates: Web Mercator scaled to the unit square, ``X`` east from the
antimeridian, ``Y`` south from the top (85.0511 N), as XYZ tiles count them. Tile
``(x, y)`` of zoom ``z`` covers ``[x, x + 1] * cell`` by ``[y, y + 1] * cell`` with
``cell = 2**-z``, and is clipped with ``pad = buffer / extent * cell`` around it.

The cascade (`cascade_counts` then `cascade_write`): the geometries of zoom ``z`` come
grouped by their tile, groups in quadkey order (children of one parent in the order
top-left, top-right, bottom-left, bottom-right), geometries in source order within a
group. Each geometry goes to those of its tile's four children whose padded box its
bounding box touches (closed: touching counts; the clip decides). Every child's
padded box lies inside its parent's (half the pad, in world units), so a child needs
nothing its parent did not keep. Counting per (group, quadrant), then writing at each
(group, quadrant)'s cursor, puts the pairs in quadkey order of the children and in
source order within each: sorted by window then source with no sort call.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from rnsca.kernels.jit import borrowing, parallel, scalar

__all__ = ["MAX_EDGES", "cascade_counts", "cascade_write", "clean_rings", "polygons_at_risk",
           "quantise", "unwrap_rings", "unwrap_runs", "write_clean_rings"]


@borrowing
def _touches(boxes, i, cx, cy, cell, pad):
    """Return whether box ``i`` touches child tile ``(cx, cy)`` padded by `pad` (closed).

    A NaN box (an empty geometry) touches nothing: every comparison with NaN is False.
    """
    return (boxes[i, 0] <= (cx + 1) * cell + pad and boxes[i, 2] >= cx * cell - pad
            and boxes[i, 1] <= (cy + 1) * cell + pad and boxes[i, 3] >= cy * cell - pad)


@parallel
def cascade_counts(boxes, group_offsets, group_x, group_y, cell, pad, counts):
    """Count the geometries of each group that go to each of its four children.

    `boxes` float64 (n, 4) ``[xmin, ymin, xmax, ymax]`` in world units; group ``g`` is
    geometries ``group_offsets[g]:group_offsets[g + 1]`` of parent tile ``(group_x[g],
    group_y[g])``; `cell` and `pad` are those of the children's zoom. ``counts[g, q]``
    (zeroed by the caller) gets the count of quadrant ``q = 2 * dy + dx``.
    """
    for g in prange(group_offsets.shape[0] - 1):
        for i in range(group_offsets[g], group_offsets[g + 1]):
            for q in range(4):
                if _touches(boxes, i, 2 * group_x[g] + (q & 1), 2 * group_y[g] + (q >> 1),
                            cell, pad):
                    counts[g, q] += 1


@parallel
def cascade_write(boxes, group_offsets, group_x, group_y, cell, pad, cursor, pairs):
    """Write each (geometry, child) pair's geometry at its child's cursor.

    ``cursor[g, q]`` is the first slot of child ``q`` of group ``g`` (an exclusive prefix
    sum of `cascade_counts`, groups then quadrants) and is advanced.
    """
    for g in prange(group_offsets.shape[0] - 1):
        for i in range(group_offsets[g], group_offsets[g + 1]):
            for q in range(4):
                if _touches(boxes, i, 2 * group_x[g] + (q & 1), 2 * group_y[g] + (q >> 1),
                            cell, pad):
                    pairs[cursor[g, q]] = i
                    cursor[g, q] += 1


@borrowing
def _unwrap_run(lon, first, last):
    """Shift longitudes of one run by multiples of 360 so no step is longer than 180.

    A step from 179 to -179 is taken to cross the antimeridian (2 degrees east), not the
    whole map (358 west): RFC 7946 asks for such geometries to be cut, and uncut ones
    mean the short way. A step between two positions on the antimeridian (both at
    +-180: the edge of a map drawn flat, such as a world box) is left as it is.
    """
    prev_raw = lon[first]
    for v in range(first + 1, last):
        raw = lon[v]
        step = lon[v] - lon[v - 1]
        if abs(raw) == 180.0 and abs(prev_raw) == 180.0:
            step = 0.0
            lon[v] = lon[v - 1] + (raw - prev_raw)
        if step > 180.0:
            lon[v] -= 360.0 * np.ceil((step - 180.0) / 360.0)
        elif step < -180.0:
            lon[v] += 360.0 * np.ceil((-step - 180.0) / 360.0)
        prev_raw = raw


@parallel
def unwrap_runs(lon, run_offsets):
    """Unwrap the longitudes of each line part in place (`_unwrap_run`)."""
    for r in prange(run_offsets.shape[0] - 1):
        _unwrap_run(lon, run_offsets[r], run_offsets[r + 1])


@parallel
def unwrap_rings(lon, original, ring_offsets, polygon_rings):
    """Unwrap the rings of each polygon in place, its holes beside its shell.

    `original` is a copy of `lon` before. A ring that does not close once unwrapped goes
    round a pole: it is put back as it was (its crossing is the map's edge, not a step).
    Each hole is shifted by whole turns so its first vertex lies within 180 of the
    shell's.
    """
    for p in prange(polygon_rings.shape[0] - 1):
        first_ring = polygon_rings[p]
        reference = 0.0
        for r in range(first_ring, polygon_rings[p + 1]):
            first = ring_offsets[r]
            last = ring_offsets[r + 1]
            if last - first < 2:
                continue
            _unwrap_run(lon, first, last)
            if lon[last - 1] != lon[first]:  # round a pole: put back
                for v in range(first, last):
                    lon[v] = original[v]
            if r == first_ring:
                reference = lon[first]
            else:
                shift = 360.0 * np.round((reference - lon[first]) / 360.0)
                if shift != 0.0:
                    for v in range(first, last):
                        lon[v] += shift


@parallel
def quantise(coords, vertex_offsets, tile_offsets, tile_x, tile_y, scale, extent, q):
    """Write each vertex in integer units of its tile: ``q`` int64 (v, 2).

    ``round((X * scale - x) * extent)`` (half up, as ``floor(u + 1/2)``) with the tile
    ``(x, y)`` of the vertex's geometry: tile ``t``'s geometries are
    ``tile_offsets[t]:tile_offsets[t + 1]``, geometry ``g``'s vertices
    ``vertex_offsets[g]:vertex_offsets[g + 1]``; `scale` is ``2**zoom``.
    """
    for t in prange(tile_x.shape[0]):
        ox = np.float64(tile_x[t])
        oy = np.float64(tile_y[t])
        for v in range(vertex_offsets[tile_offsets[t]], vertex_offsets[tile_offsets[t + 1]]):
            q[v, 0] = np.int64(np.floor((coords[v, 0] * scale - ox) * extent + 0.5))
            q[v, 1] = np.int64(np.floor((coords[v, 1] * scale - oy) * extent + 0.5))


@borrowing
def _orient(q, a, b, c):
    """Return the sign of the turn a -> b -> c (exact: int64 tile units, |q| < 2**30)."""
    d = (q[b, 0] - q[a, 0]) * (q[c, 1] - q[a, 1]) - (q[b, 1] - q[a, 1]) * (q[c, 0] - q[a, 0])
    return 1 if d > 0 else (-1 if d < 0 else 0)


@borrowing
def _within(q, a, b, c):
    """Whether c, collinear with a and b, lies in their bounding box (on the segment)."""
    return (min(q[a, 0], q[b, 0]) <= q[c, 0] <= max(q[a, 0], q[b, 0])
            and min(q[a, 1], q[b, 1]) <= q[c, 1] <= max(q[a, 1], q[b, 1]))


@borrowing
def _touch(q, a, b, c, d):
    """Whether segments ab and cd share a point (crossing, touching or overlapping)."""
    o1 = _orient(q, a, b, c)
    o2 = _orient(q, a, b, d)
    o3 = _orient(q, c, d, a)
    o4 = _orient(q, c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return ((o1 == 0 and _within(q, a, b, c)) or (o2 == 0 and _within(q, a, b, d))
            or (o3 == 0 and _within(q, c, d, a)) or (o4 == 0 and _within(q, c, d, b)))


@borrowing
def _next_edge(q, first, last, i):
    """Return the next edge of positive length after edge i of the ring, cyclically."""
    n = last - 1  # edges first..last-2: (v, v + 1); the ring is closed
    j = i
    for _ in range(n - first):
        j = j + 1 if j + 1 < n else first
        if q[j, 0] != q[j + 1, 0] or q[j, 1] != q[j + 1, 1]:
            return j
    return i


@borrowing
def _inside(q, first, last, p):
    """Return 1 if position p is strictly inside the ring, 0 outside, -1 on it."""
    inside = False
    for v in range(first, last - 1):
        w = v + 1
        if _orient(q, v, w, p) == 0 and _within(q, v, w, p):
            return -1
        if (q[v, 1] > q[p, 1]) != (q[w, 1] > q[p, 1]):
            # The edge crosses the horizontal line through p: left or right of p?
            side = _orient(q, v, w, p) if q[w, 1] > q[v, 1] else -_orient(q, v, w, p)
            if side > 0:
                inside = not inside
    return 1 if inside else 0


#: Most edges `polygons_at_risk` compares pairwise in one geometry; past it the
#: geometry is marked (GEOS checks it).
MAX_EDGES = 512


@borrowing
def _area2(q, first, last):
    area = 0
    for v in range(first, last - 1):
        area += q[v, 0] * q[v + 1, 1] - q[v + 1, 0] * q[v, 1]
    return area


@borrowing
def _boxes_meet(q, a, b, c, d):
    return (max(q[a, 0], q[b, 0]) >= min(q[c, 0], q[d, 0])
            and max(q[c, 0], q[d, 0]) >= min(q[a, 0], q[b, 0])
            and max(q[a, 1], q[b, 1]) >= min(q[c, 1], q[d, 1])
            and max(q[c, 1], q[d, 1]) >= min(q[a, 1], q[b, 1]))


#: Edges per run in `_suspect`'s pruning by boxes (4 measured fastest of 2, 4 and 8 on
#: the polygons benchmark's stars).
_RUN = 4


@scalar
def _suspect(q, ring_offsets, polygon_rings, first_polygon, last_polygon, kept):
    """Whether one geometry's rounded polygons may be invalid (see `polygons_at_risk`).

    `kept` is scratch, one flag per ring of the whole array.
    """
    first_ring = polygon_rings[first_polygon]
    last_ring = polygon_rings[last_polygon]
    if ring_offsets[last_ring] - ring_offsets[first_ring] > MAX_EDGES:
        return True
    # The rings the encoder writes: non-zero area, and a shell written (the others are
    # dropped whole, so they cannot make the output invalid).
    for p in range(first_polygon, last_polygon):
        shell_kept = False
        for r in range(polygon_rings[p], polygon_rings[p + 1]):
            kept[r] = (_area2(q, ring_offsets[r], ring_offsets[r + 1]) != 0
                       and (r == polygon_rings[p] or shell_kept))
            if r == polygon_rings[p]:
                shell_kept = kept[r]
    # Adjacent edges of positive length may not fold back onto each other.
    for r in range(first_ring, last_ring):
        if not kept[r]:
            continue
        first = ring_offsets[r]
        last = ring_offsets[r + 1]
        for i in range(first, last - 1):
            if q[i, 0] == q[i + 1, 0] and q[i, 1] == q[i + 1, 1]:
                continue
            nxt = _next_edge(q, first, last, i)
            # The shared position is i + 1 = nxt: a spike if the two edges go back along
            # one line.
            if _orient(q, i, i + 1, nxt + 1) == 0 and (
                    (q[i, 0] - q[i + 1, 0]) * (q[nxt + 1, 0] - q[nxt, 0])
                    + (q[i, 1] - q[i + 1, 1]) * (q[nxt + 1, 1] - q[nxt, 1])) > 0:
                return True
    # Other edges may not meet at all. The edges in runs of `_RUN` consecutive ones of
    # a ring, each run's box first: only the pairs of runs whose boxes meet compare
    # their edges (a star's runs mostly lie apart: about half the comparisons).
    n_runs = 0
    for r in range(first_ring, last_ring):
        if kept[r]:
            n_runs += (ring_offsets[r + 1] - ring_offsets[r] - 1 + _RUN - 1) // _RUN
    runs = np.empty((n_runs, 7), dtype=np.int64)  # first edge, end, ring, box
    k = 0
    for r in range(first_ring, last_ring):
        if not kept[r]:
            continue
        for start in range(ring_offsets[r], ring_offsets[r + 1] - 1, _RUN):
            stop = min(start + _RUN, ring_offsets[r + 1] - 1)
            runs[k, 0] = start
            runs[k, 1] = stop
            runs[k, 2] = r
            runs[k, 3] = q[start, 0]
            runs[k, 4] = q[start, 1]
            runs[k, 5] = q[start, 0]
            runs[k, 6] = q[start, 1]
            for v in range(start + 1, stop + 1):
                runs[k, 3] = min(runs[k, 3], q[v, 0])
                runs[k, 4] = min(runs[k, 4], q[v, 1])
                runs[k, 5] = max(runs[k, 5], q[v, 0])
                runs[k, 6] = max(runs[k, 6], q[v, 1])
            k += 1
    for a in range(n_runs):
        r = runs[a, 2]
        first = ring_offsets[r]
        last = ring_offsets[r + 1]
        for b in range(a, n_runs):
            if (runs[a, 5] < runs[b, 3] or runs[b, 5] < runs[a, 3] or runs[a, 6] < runs[b, 4]
                    or runs[b, 6] < runs[a, 4]):
                continue
            same = runs[b, 2] == r
            for i in range(runs[a, 0], runs[a, 1]):
                if q[i, 0] == q[i + 1, 0] and q[i, 1] == q[i + 1, 1]:
                    continue
                nxt = _next_edge(q, first, last, i)
                for j in range(i + 1 if a == b else runs[b, 0], runs[b, 1]):
                    if not _boxes_meet(q, i, i + 1, j, j + 1):
                        continue
                    if q[j, 0] == q[j + 1, 0] and q[j, 1] == q[j + 1, 1]:
                        continue
                    if same and (j == nxt or i == _next_edge(q, first, last, j)):
                        continue
                    if _touch(q, i, i + 1, j, j + 1):
                        return True
    # No edges meet: each hole is wholly inside its shell or wholly outside, and each
    # polygon wholly inside another's shell or wholly outside it.
    for p in range(first_polygon, last_polygon):
        shell = polygon_rings[p]
        if not kept[shell]:
            continue
        for h in range(shell + 1, polygon_rings[p + 1]):
            if kept[h] and _inside(q, ring_offsets[shell], ring_offsets[shell + 1],
                                   ring_offsets[h]) != 1:
                return True
        for o in range(first_polygon, last_polygon):
            other = polygon_rings[o]
            if o != p and kept[other] and _inside(
                    q, ring_offsets[other], ring_offsets[other + 1],
                    ring_offsets[shell]) != 0:
                return True
    return False


@parallel
def polygons_at_risk(q, ring_offsets, polygon_rings, geometry_polygons, at_risk):
    """Mark the geometries whose rounded polygons may be invalid (``at_risk[g]``).

    Only the rings the encoder writes count (`rnsca.kernels.mvt`: a ring of zero area
    is dropped, a shell with its holes): rounding collapses most small polygons of low
    zooms, which then need no check. A geometry is not marked only when those rings are
    proved fine here, exactly in integer arithmetic: no two
    edges of positive length meet (crossing, touching or overlapping) except adjacent
    ones at their shared position, and no two adjacent ones fold back along one line;
    every hole lies inside its shell and no polygon's shell inside another's. Then the
    rings are simple and properly nested: the polygons are valid. Anything else (or more
    than `MAX_EDGES` edges, where the O(E^2) test would cost more than GEOS) is marked,
    and the caller checks it with GEOS. Repeated positions are allowed, as in GEOS.
    """
    kept = np.empty(ring_offsets.shape[0] - 1, dtype=np.bool_)
    for g in prange(geometry_polygons.shape[0] - 1):
        at_risk[g] = _suspect(q, ring_offsets, polygon_rings, geometry_polygons[g],
                              geometry_polygons[g + 1], kept)


# --- Rounded rings cleaned before any validity check ---------------------------------


@borrowing
def _turn(w, a, b, c):
    """Return the sign of the turn a -> b -> c of rows of `w` (exact, as `_orient`)."""
    d = (w[b, 0] - w[a, 0]) * (w[c, 1] - w[a, 1]) - (w[b, 1] - w[a, 1]) * (w[c, 0] - w[a, 0])
    return 1 if d > 0 else (-1 if d < 0 else 0)


@borrowing
def _unit(value, origin, scale, extent):
    """Return a world coordinate in integer tile units, as `quantise` rounds it."""
    return np.int64(np.floor((value * scale - origin) * extent + 0.5))


@borrowing
def _clean_ring(coords, first, last, ox, oy, scale, extent, w):
    """Round one closed ring ``coords[first:last]`` and clean it into ``w[first:]``.

    Return ``(begin, end)``: the kept positions are ``w[begin:end]`` (not closed).
    Each position is rounded to tile units (tile origin ``(ox, oy)``, as `quantise`)
    and pushed on a stack held in ``w[first:]``: a position equal to the top is not
    pushed, and while the top two and the new position lie on one line (integer
    orientation zero: exact for tile units below 2**30) the top is popped: a collinear
    vertex (the same point set) or the tip of a spike (an edge that goes back along
    itself, of no area: GEOS's ``make_valid`` drops it too). Then the same across the
    ring's ends, from either side, until no three cyclically consecutive positions are
    collinear or repeated. Fewer than three left: nothing is kept (a ring of no area,
    dropped as the specification asks).
    """
    top = first  # next free row of the stack
    for v in range(first, last - 1):
        x = _unit(coords[v, 0], ox, scale, extent)
        y = _unit(coords[v, 1], oy, scale, extent)
        if top > first and x == w[top - 1, 0] and y == w[top - 1, 1]:
            continue
        w[top, 0] = x
        w[top, 1] = y
        while top - first >= 2 and _turn(w, top - 2, top - 1, top) == 0:
            # Pop the middle one (the new position moves down one row).
            w[top - 1, 0] = w[top, 0]
            w[top - 1, 1] = w[top, 1]
            top -= 1
        if top - first >= 1 and w[top, 0] == w[top - 1, 0] and w[top, 1] == w[top - 1, 1]:
            continue  # a spike back onto the position below: already there
        top += 1
    begin = first
    end = top
    while end - begin >= 3:
        if w[end - 1, 0] == w[begin, 0] and w[end - 1, 1] == w[begin, 1]:
            end -= 1
        elif _turn(w, end - 2, end - 1, begin) == 0:
            end -= 1
        elif _turn(w, end - 1, begin, begin + 1) == 0:
            begin += 1
        else:
            break
    if end - begin < 3:
        return begin, begin
    return begin, end


@parallel
def clean_rings(coords, ring_offsets, polygon_rings, geometry_polygons, origin, scale, extent,
                w, ring_begin, ring_end):
    """Round and clean every ring (`_clean_ring`); drop degenerate rings and their holes.

    `coords` float64 (v, 2) world positions, rings closed; geometry ``g``'s tile origin
    is ``origin[g]`` (tile x, y), `scale` is ``2**zoom`` (with ``scale = extent = 1``
    and origins 0, integer positions are cleaned as they are). `w` int64 (v, 2) gets
    each ring's kept positions at ``w[ring_begin[r]:ring_end[r]]`` (within the ring's
    own rows, not closed); a ring left with fewer than three positions, and every ring
    of a polygon whose shell is such, gets ``ring_begin[r] == ring_end[r]``. The
    geometry each ring belongs to is unchanged (`write_clean_rings` compacts).
    """
    for g in prange(geometry_polygons.shape[0] - 1):
        ox = np.float64(origin[g, 0])
        oy = np.float64(origin[g, 1])
        for p in range(geometry_polygons[g], geometry_polygons[g + 1]):
            shell = polygon_rings[p]
            for r in range(shell, polygon_rings[p + 1]):
                first = ring_offsets[r]
                last = ring_offsets[r + 1]
                if last - first < 4 or (r > shell and ring_begin[shell] == ring_end[shell]):
                    ring_begin[r] = first
                    ring_end[r] = first
                    continue
                begin, end = _clean_ring(coords, first, last, ox, oy, scale, extent, w)
                ring_begin[r] = begin
                ring_end[r] = end


@parallel
def write_clean_rings(w, ring_begin, ring_end, out_start, out):
    """Write each kept ring ``w[ring_begin[r]:ring_end[r]]``, closed, at ``out[out_start[r]:]``.

    `out_start` holds each ring's first row in `out` (rings of no positions write
    nothing).
    """
    for r in prange(ring_begin.shape[0]):
        n = ring_end[r] - ring_begin[r]
        if n == 0:
            continue
        o = out_start[r]
        for k in range(n):
            out[o + k, 0] = w[ring_begin[r] + k, 0]
            out[o + k, 1] = w[ring_begin[r] + k, 1]
        out[o + n, 0] = w[ring_begin[r], 0]
        out[o + n, 1] = w[ring_begin[r], 1]
