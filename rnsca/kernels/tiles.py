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

from rnsca.kernels.jit import borrowing, parallel

__all__ = ["cascade_counts", "cascade_write", "unwrap_rings", "unwrap_runs"]


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
