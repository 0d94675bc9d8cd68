"""Polygon clipping with valid output: cut the rings into chains, close them along the window.

Sutherland–Hodgman clips a concave polygon into one ring with zero-width bridges along
the window's edge, which is not a valid polygon. Here each ring is cut into chains by
`polylines.clip_chains` (rings are oriented first: shells counter-clockwise, holes
clockwise, so the polygon's interior is on the left of every chain, and a ring is also
broken where it runs along an edge). Every chain then enters and leaves the window on
its boundary, and the pieces of polygon ∩ window are closed by the classic walk for
convex windows (Weiler–Atherton; GEOS's RectangleIntersection does the same): from
the point where a chain leaves, go counter-clockwise along the boundary, through the
corners passed, to the nearest point where a chain enters, and continue with that
chain until the ring closes. Each closed ring is a shell of one piece. Rings that lie
inside the window and are never cut stay as they are; holes among them go to the shell
that contains them. With no chain at all, the window is either inside the polygon (the
result is the window, with the holes inside it) or outside it.

Boundary positions are compared exactly, as (edge, coordinate along the edge): every
cut point has its edge coordinate exactly on the edge line (see `outcode.end_point`).

The kernels take records (named tuples): the rings and polygons with their windows
(`Polygons`), where the output goes (`PolygonsOut`) and how much of it there is
(`PolygonCounts`), what the count pass decided per polygon (`PolygonPlan`), and one
block's scratch (`PolygonScratch`: chains, logical chains, boundary events, ring states,
the walk, the closed rings). `clip_polygon` reads as its steps, each a function inlined
into it; it borrows the scratch (no reference counts per polygon), and only the helpers
that must allocate (`_split_loops`, the ring-by-ring fallback) are ``allocating``.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels import counters as C
from rnsca.kernels.jit import allocating, borrowing, inlined, parallel, scalar
from rnsca.kernels.outcode import line_coordinate
from rnsca.kernels.polylines import (
    RUN_STACK_CAPACITY,
    BlockState,
    ChainsOut,
    Cut,
    PartPlan,
    assemble_chains,
    bound_chains,
    clip_chains,
    run_box_codes,
)
from rnsca.kernels.records import window_of
from rnsca.kernels.segments import segment_stack

__all__ = [
    "AMBIGUOUS",
    "PolygonCounts",
    "PolygonPlan",
    "Polygons",
    "PolygonsOut",
    "boundary_key",
    "classify_polygons",
    "clip_polygon_blocks",
    "point_in_ring",
    "polygon_class_of",
    "signed_area",
    "sutherland_hodgman",
]

# Edges in counter-clockwise order, starting at (xmin, ymin).
_BOTTOM, _RIGHT, _TOP, _LEFT = 0, 1, 2, 3
# Ring states after cutting.
_UNTOUCHED, _FULL, _CUT = 0, 1, 2


class Polygons(NamedTuple):
    """The rings and polygons of a ragged polygon array, and their windows.

    Polygon p has rings ``polygon_offsets[p]`` to ``polygon_offsets[p+1] - 1`` (the
    shell first); ring r runs through vertices ``ring_offsets[r]`` to
    ``ring_offsets[r+1] - 1`` (of a `Vertices`), closed; polygon p is clipped against
    ``window_of(windows, polygon_window, p)``.
    """

    ring_offsets: np.ndarray
    polygon_offsets: np.ndarray
    windows: np.ndarray
    polygon_window: np.ndarray


class PolygonsOut(NamedTuple):
    """Where clipped polygons go: vertices, ring starts, rings per output polygon.

    Polygons are written from ``xy[v]`` (and ``z[v]``), their rings' starts from
    ``ring_starts[n_rings]`` and their ring counts from ``poly_rings[n_polys]``.
    Without `write` (the count pass) the arrays are one polygon's scratch, and a
    polygon clipped ring by ring (`sutherland_hodgman`) is only counted.
    """

    write: bool
    xy: np.ndarray
    z: np.ndarray
    ring_starts: np.ndarray
    poly_rings: np.ndarray


class PolygonCounts(NamedTuple):
    """Per polygon: output vertices, rings and polygons (the count pass), and their starts.

    The starts (exclusive sums of the counts) are empty in the count pass.
    """

    n_vertices: np.ndarray
    n_rings: np.ndarray
    n_polys: np.ndarray
    vertex_start: np.ndarray
    ring_start: np.ndarray
    poly_start: np.ndarray


class PolygonPlan(NamedTuple):
    """Per polygon, from the count pass: its class, and the chain scratch its clip needs.

    `polygon_class` is int8 (`polygon_class_of`), computed by the count pass unless
    `classified` (the OpenCL backend classifies every polygon before it chooses the
    rings to send to the device: the count pass reuses those classes); `scratch_vertices`
    and `scratch_chains` bound the vertices and chains of the ambiguous polygons' rings
    (`bound_chains`).
    """

    classified: bool
    polygon_class: np.ndarray
    scratch_vertices: np.ndarray
    scratch_chains: np.ndarray


class LogicalChains(NamedTuple):
    """The chains the walk joins, one row each (int64, or bool for the flags).

    A logical chain is range 1 (``start1..end1-1``) then range 2 (``start2..end2-1``)
    of the chain scratch (range 2 is the first chain of a ring, continued across its
    closing vertex), read backwards if the ring was `reversed` to orient it; `visited`
    by the walk; `ring` is the ring (of the polygon) it comes from.
    """

    start1: np.ndarray
    end1: np.ndarray
    start2: np.ndarray
    end2: np.ndarray
    reversed: np.ndarray
    visited: np.ndarray
    ring: np.ndarray


class Events(NamedTuple):
    """Boundary events: event ``2k`` is the start of logical chain k, ``2k + 1`` its end.

    Event e lies at ``(edge[e], s[e])`` (`boundary_key`) and enters or leaves at
    ``angle[e]`` (`_event_angle`); ``order`` lists the events counter-clockwise along
    the boundary, and ``rank[e]`` is e's position in it.
    """

    edge: np.ndarray
    s: np.ndarray
    angle: np.ndarray
    order: np.ndarray
    rank: np.ndarray


class RingStates(NamedTuple):
    """The rings of the polygon being clipped, by position in it (0: the shell).

    `state` (`_UNTOUCHED`, `_FULL`, `_CUT`), whether the ring was `reversed` to orient
    it, and its `first` and `last` vertex.
    """

    state: np.ndarray
    reversed: np.ndarray
    first: np.ndarray
    last: np.ndarray


class Walk(NamedTuple):
    """The ring a walk builds (``xy``, ``z``), and `index`, a stack of its vertex indices."""

    xy: np.ndarray
    z: np.ndarray
    index: np.ndarray


class ClosedRings(NamedTuple):
    """The closed rings found for a polygon, before they are grouped into pieces.

    Ring j is ``xy[start[j]:start[j+1]]`` (and `z`); `sign` 1 for a shell
    (counter-clockwise), -1 for a hole; `done` marks holes given to a shell.
    """

    xy: np.ndarray
    z: np.ndarray
    start: np.ndarray
    sign: np.ndarray
    done: np.ndarray


class Corners(NamedTuple):
    """The Z of each window corner lying on an input segment (`known`), by `_corner_after`."""

    z: np.ndarray
    known: np.ndarray


class PolygonScratch(NamedTuple):
    """One block's scratch for clipping its ambiguous polygons, sized by the largest."""

    block: BlockState
    chains: ChainsOut
    logical: LogicalChains
    events: Events
    rings: RingStates
    walk: Walk
    closed: ClosedRings
    corners: Corners
    no_plan: PartPlan


@borrowing
def signed_area(xy, first, last):
    """Return twice the signed area of the closed ring ``xy[first..last]`` (CCW > 0).

    Coordinates are taken relative to the first vertex (less cancellation); if the sum
    overflows, it is recomputed on coordinates scaled by 2**-600 (exact), keeping the sign.
    """
    x0 = xy[first, 0]
    y0 = xy[first, 1]
    total = 0.0
    for k in range(first, last):
        total += (xy[k, 0] - x0) * (xy[k + 1, 1] - y0) - (xy[k + 1, 0] - x0) * (xy[k, 1] - y0)
    if math.isfinite(total):
        return total
    s = 2.0 ** -600
    total = 0.0
    for k in range(first, last):
        ax = xy[k, 0] * s - x0 * s
        ay = xy[k, 1] * s - y0 * s
        bx = xy[k + 1, 0] * s - x0 * s
        by = xy[k + 1, 1] * s - y0 * s
        total += ax * by - bx * ay
    return total


@borrowing
def point_in_ring(px, py, xy, first, last):
    """Return 1 if (px, py) is inside the closed ring ``xy[first..last]``, 0 on it, -1 outside.

    Crossing-number test; a point on an edge (exactly collinear, within its extent) is on it.
    """
    inside = False
    for k in range(first, last):
        x1 = xy[k, 0]
        y1 = xy[k, 1]
        x2 = xy[k + 1, 0]
        y2 = xy[k + 1, 1]
        if (min(x1, x2) <= px <= max(x1, x2) and min(y1, y2) <= py <= max(y1, y2)
                and (x2 - x1) * (py - y1) == (y2 - y1) * (px - x1)):
            return 0
        if (y1 > py) != (y2 > py):
            x_cross = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
            if px < x_cross:
                inside = not inside
    return 1 if inside else -1


@scalar
def _along(edge, x, y):
    """Return the coordinate of (x, y) that increases counter-clockwise along `edge`."""
    if edge == _BOTTOM:
        return x
    if edge == _RIGHT:
        return y
    if edge == _TOP:
        return -x
    return -y


@scalar
def boundary_key(x, y, window):
    """Return (edge, s): the position of a boundary point, counter-clockwise from (xmin, ymin).

    `s` increases counter-clockwise along `edge` (`_along`). The edge is the first, in
    that order, whose line holds the point, so a corner belongs to the edge it ends. A
    point off the boundary (never produced by exact clipping) is put on the nearest edge.
    """
    xmin, ymin, xmax, ymax = window
    # How far inside the line of each edge the point lies, by edge.
    gaps = (y - ymin, xmax - x, ymax - y, x - xmin)
    target = 0.0 if 0.0 in gaps else min(min(gaps[0], gaps[1]), min(gaps[2], gaps[3]))
    edge = _BOTTOM
    while edge < _LEFT and gaps[edge] != target:
        edge += 1
    return edge, _along(edge, x, y)


@scalar
def _edge_start(edge, window):
    """Return (x, y, p): the corner where `edge` starts, and its distance along the boundary.

    Both counter-clockwise from (xmin, ymin). The corner where `edge` ends is the start
    of edge ``(edge + 1) % 4``.
    """
    xmin, ymin, xmax, ymax = window
    w = xmax - xmin
    h = ymax - ymin
    if edge == _BOTTOM:
        return xmin, ymin, 0.0
    if edge == _RIGHT:
        return xmax, ymin, w
    if edge == _TOP:
        return xmax, ymax, w + h
    return xmin, ymax, 2.0 * w + h


@scalar
def _perimeter_position(edge, s, window):
    """Return the distance along the boundary, counter-clockwise from (xmin, ymin).

    (edge, s) is a `boundary_key`.
    """
    x, y, start = _edge_start(edge, window)
    return start + (s - _along(edge, x, y))


@scalar
def _corner_after(edge, window):
    """Return the corner where `edge` ends (counter-clockwise)."""
    x, y, _ = _edge_start((edge + 1) % 4, window)
    return x, y


@scalar
def _key_less(e1, s1, t1, e2, s2, t2):
    """Return whether boundary event 1 comes before event 2: position, then angle."""
    return e1 < e2 or (e1 == e2 and (s1 < s2 or (s1 == s2 and t1 < t2)))


@inlined
def _chain_length(lc, k):
    return (lc.end1[k] - lc.start1[k]) + (lc.end2[k] - lc.start2[k])


@inlined
def _chain_vertex(lc, k, j):
    """Return the scratch index of vertex j of logical chain k, in its oriented order.

    See `LogicalChains`: range 1 then range 2, backwards if the ring was reversed.
    """
    if lc.reversed[k]:
        j = _chain_length(lc, k) - 1 - j
    n1 = lc.end1[k] - lc.start1[k]
    return lc.start1[k] + j if j < n1 else lc.start2[k] + (j - n1)


@inlined
def _event_angle(ch_xy, lc, k, at_start, edge, window):
    """Return the angle of chain k's direction into the window at its start or end.

    Measured from the boundary's counter-clockwise direction at the point (at a corner,
    that of the edge that starts there) towards the inward normal, in [0, pi]. Chains
    meeting at one boundary point are ordered by it.
    """
    length = _chain_length(lc, k)
    here = _chain_vertex(lc, k, 0 if at_start else length - 1)
    px = ch_xy[here, 0]
    py = ch_xy[here, 1]
    dx = 0.0
    dy = 0.0
    for step in range(1, length):
        other = _chain_vertex(lc, k, step if at_start else length - 1 - step)
        dx = ch_xy[other, 0] - px
        dy = ch_xy[other, 1] - py
        if dx != 0.0 or dy != 0.0:
            break
    cx, cy = _corner_after(edge, window)
    if px == cx and py == cy:
        edge = (edge + 1) % 4
    ux = 1.0 if edge == _BOTTOM else (-1.0 if edge == _TOP else 0.0)
    uy = 1.0 if edge == _RIGHT else (-1.0 if edge == _LEFT else 0.0)
    return math.atan2(dy * ux - dx * uy, dx * ux + dy * uy)


@borrowing
def _put(out_xy, out_z, has_z, v, ring_start, x, y, z):
    """Append a ring vertex unless it repeats the previous one; return the next position."""
    if v > ring_start and out_xy[v - 1, 0] == x and out_xy[v - 1, 1] == y:
        return v
    out_xy[v, 0] = x
    out_xy[v, 1] = y
    if has_z:
        out_z[v] = z
    return v + 1


@inlined
def _put_chain(chains, has_z, lc, k, walk, m):
    """Append the vertices of logical chain k to the walk's ring at `m`; return the end."""
    for j in range(_chain_length(lc, k)):
        i = _chain_vertex(lc, k, j)
        m = _put(walk.xy, walk.z, has_z, m, 0, chains.xy[i, 0], chains.xy[i, 1],
                 chains.z[i] if has_z else 0.0)
    return m


@borrowing
def _put_ring(xy, z, has_z, first, last, reverse, out_xy, out_z, v):
    """Copy the input ring ``xy[first..last]`` (backwards if `reverse`); return the end."""
    for k in range(last - first + 1):
        i = last - k if reverse else first + k
        out_xy[v, 0] = xy[i, 0]
        out_xy[v, 1] = xy[i, 1]
        if has_z:
            out_z[v] = z[i]
        v += 1
    return v


@borrowing
def _add_ring(closed, has_z, n_rg, src_xy, src_z, idx, count, close):
    """Store the ring of ``src[idx[0..count-1]]`` (closed with its first vertex if `close`).

    Returns the new ring count; a ring of fewer than three distinct vertices or no area
    is not stored. Its sign (1 shell, -1 hole) comes from its orientation.
    """
    v = closed.start[n_rg]
    start = v
    for j in range(count):
        i = idx[j]
        v = _put(closed.xy, closed.z, has_z, v, start, src_xy[i, 0], src_xy[i, 1],
                 src_z[i] if has_z else 0.0)
    if close:
        i = idx[0]
        v = _put(closed.xy, closed.z, has_z, v, start, src_xy[i, 0], src_xy[i, 1],
                 src_z[i] if has_z else 0.0)
    if v - start < 4:
        return n_rg
    area = signed_area(closed.xy, start, v - 1)
    if area == 0.0:
        return n_rg
    closed.sign[n_rg] = 1 if area > 0.0 else -1
    closed.start[n_rg + 1] = v
    return n_rg + 1


# Walk rings up to this many vertices are checked for a vertex lying inside another of
# their edges (a hole of the input touching its shell in the middle of a shell edge);
# the check is quadratic, so larger rings skip it (README, "Limits").
TOUCH_CHECK_LIMIT = 4096


@scalar
def _node_touches(ring_xy, ring_z, has_z, m):
    """Return ``(xy, z, m)``: the ring, noded where a vertex lies inside another edge.

    A vertex of the closed ring that lies inside one of its other edges (exactly
    collinear) is inserted into that edge; without any, the ring itself comes back.
    """
    n = m - 1
    hits_edge = np.empty(0, dtype=np.int64)
    hits_vertex = np.empty(0, dtype=np.int64)
    count = 0
    # Vertices sorted by x: each edge looks only at those within its x-extent.
    by_x = np.argsort(ring_xy[:n, 0], kind="mergesort")
    xs = ring_xy[by_x, 0]
    for j in range(n):
        ax = ring_xy[j, 0]
        ay = ring_xy[j, 1]
        bx = ring_xy[j + 1, 0]
        by = ring_xy[j + 1, 1]
        lo = np.searchsorted(xs, min(ax, bx), side="left")
        hi = np.searchsorted(xs, max(ax, bx), side="right")
        for k in range(lo, hi):
            i = by_x[k]
            if j == i or j + 1 == i or (i == 0 and j == n - 1):
                continue
            px = ring_xy[i, 0]
            py = ring_xy[i, 1]
            if py < min(ay, by) or py > max(ay, by):
                continue
            if (px == ax and py == ay) or (px == bx and py == by):
                continue
            if (bx - ax) * (py - ay) - (by - ay) * (px - ax) != 0.0:
                continue
            if count == hits_edge.shape[0]:
                grown_e = np.empty(2 * count + 4, dtype=np.int64)
                grown_v = np.empty(2 * count + 4, dtype=np.int64)
                grown_e[:count] = hits_edge[:count]
                grown_v[:count] = hits_vertex[:count]
                hits_edge = grown_e
                hits_vertex = grown_v
            hits_edge[count] = j
            hits_vertex[count] = i
            count += 1
    if count == 0:
        return ring_xy, ring_z, m
    out_xy = np.empty((m + count, 2), dtype=np.float64)
    out_z = np.empty(m + count if has_z else 0, dtype=np.float64)
    used = np.zeros(count, dtype=np.bool_)
    k = 0
    for j in range(n):
        out_xy[k, 0] = ring_xy[j, 0]
        out_xy[k, 1] = ring_xy[j, 1]
        if has_z:
            out_z[k] = ring_z[j]
        k += 1
        ax = ring_xy[j, 0]
        ay = ring_xy[j, 1]
        while True:  # the points on edge j, nearest to its start first
            best = -1
            best_d = 0.0
            for h in range(count):
                if used[h] or hits_edge[h] != j:
                    continue
                i = hits_vertex[h]
                d = abs(ring_xy[i, 0] - ax) + abs(ring_xy[i, 1] - ay)
                if best < 0 or d < best_d:
                    best = h
                    best_d = d
            if best < 0:
                break
            used[best] = True
            i = hits_vertex[best]
            out_xy[k, 0] = ring_xy[i, 0]
            out_xy[k, 1] = ring_xy[i, 1]
            if has_z:
                bz = ring_z[j + 1]
                az = ring_z[j]
                span = abs(ring_xy[j + 1, 0] - ax) + abs(ring_xy[j + 1, 1] - ay)
                out_z[k] = az + (bz - az) * (best_d / span if span > 0.0 else 0.0)
            k += 1
    out_xy[k, 0] = out_xy[0, 0]
    out_xy[k, 1] = out_xy[0, 1]
    if has_z:
        out_z[k] = out_z[0]
    return out_xy, out_z, k + 1


@allocating
def _split_loops(walk, has_z, m, node, closed, n_rg):
    """Store the closed walk ring ``walk.xy[0..m-1]`` as simple rings; return the ring count.

    The walk can pass a point twice (a hole or a part of the ring touching the window's
    edge, or a hole touching its shell at a vertex); a ring through one point twice is
    not valid, so it is cut into loops at every repeated point. Counter-clockwise loops
    are shells, clockwise ones holes (touching their shell at that point, as valid
    polygons may). With `node`, a vertex lying inside another edge of the ring (a hole
    touching its shell mid-edge) is first made a vertex of that edge too.
    """
    tmp_xy = walk.xy
    tmp_z = walk.z
    stk = walk.index
    if node and m - 1 <= TOUCH_CHECK_LIMIT:
        tmp_xy, tmp_z, noded = _node_touches(tmp_xy, tmp_z, has_z, m)
        if noded != m:
            m = noded
            stk = np.empty(m, dtype=np.int64)
    # Repeated vertices (sorted by x, then equal neighbours compared): a hole of the
    # input touching its shell at a vertex inside the window pinches the walk there too.
    repeated = np.zeros(m, dtype=np.bool_)
    by_x = np.argsort(tmp_xy[:m - 1, 0], kind="mergesort")
    g = 0
    while g < m - 1:
        h = g + 1
        while h < m - 1 and tmp_xy[by_x[h], 0] == tmp_xy[by_x[g], 0]:
            h += 1
        for a in range(g, h):
            for b in range(a + 1, h):
                if tmp_xy[by_x[a], 1] == tmp_xy[by_x[b], 1]:
                    repeated[by_x[a]] = True
                    repeated[by_x[b]] = True
        g = h
    top = 0
    for i in range(m - 1):
        x = tmp_xy[i, 0]
        y = tmp_xy[i, 1]
        if repeated[i]:
            q = -1
            for t in range(top - 1, -1, -1):
                if tmp_xy[stk[t], 0] == x and tmp_xy[stk[t], 1] == y:
                    q = t
                    break
            if q >= 0:
                n_rg = _add_ring(closed, has_z, n_rg, tmp_xy, tmp_z, stk[q:], top - q, True)
                top = q + 1
                continue
        stk[top] = i
        top += 1
    return _add_ring(closed, has_z, n_rg, tmp_xy, tmp_z, stk, top, True)


@borrowing
def _inside_edge(x, y, edge, window):
    xmin, ymin, xmax, ymax = window
    if edge == _LEFT:
        return x >= xmin
    if edge == _RIGHT:
        return x <= xmax
    if edge == _BOTTOM:
        return y >= ymin
    return y <= ymax


@borrowing
def _cross_edge(x0, y0, z0, x1, y1, z1, edge, window):
    """Return the point (x, y, z) where segment 0-1 crosses the line of `edge`."""
    xmin, ymin, xmax, ymax = window
    if edge == _LEFT or edge == _RIGHT:
        e = xmin if edge == _LEFT else xmax
        t = (e - x0) / (x1 - x0)
        return e, line_coordinate(e, x0, y0, x1, y1), z0 + t * (z1 - z0)
    e = ymin if edge == _BOTTOM else ymax
    t = (e - y0) / (y1 - y0)
    return line_coordinate(e, y0, x0, y1, x1), e, z0 + t * (z1 - z0)


@scalar
def sutherland_hodgman(line, first, last, reverse, window):
    """Return ``(ring (m, 3), m)``: the ring ``line.xy[first..last]`` clipped by Sutherland–Hodgman.

    The fallback for invalid polygons, clipped ring by ring (Sutherland & Hodgman 1974:
    one pass per window edge, keeping inside vertices and adding the crossings). The
    result is closed, may run along the window's edge and is not repaired. Each pass at
    most doubles the vertex count, hence the buffers.
    """
    xy = line.xy
    z = line.z
    has_z = line.has_z
    n = last - first  # without the closing vertex
    size = 16 * n + 16
    a = np.empty((size, 3), dtype=np.float64)
    b = np.empty((size, 3), dtype=np.float64)
    for k in range(n):
        i = last - k if reverse else first + k
        a[k, 0] = xy[i, 0]
        a[k, 1] = xy[i, 1]
        a[k, 2] = z[i] if has_z else 0.0
    for edge in range(4):
        m = 0
        for k in range(n):
            j = k - 1 if k > 0 else n - 1
            cur_in = _inside_edge(a[k, 0], a[k, 1], edge, window)
            prev_in = _inside_edge(a[j, 0], a[j, 1], edge, window)
            if cur_in != prev_in:
                b[m, 0], b[m, 1], b[m, 2] = _cross_edge(a[j, 0], a[j, 1], a[j, 2], a[k, 0],
                                                        a[k, 1], a[k, 2], edge, window)
                m += 1
            if cur_in:
                b[m, 0] = a[k, 0]
                b[m, 1] = a[k, 1]
                b[m, 2] = a[k, 2]
                m += 1
        a, b = b, a
        n = m
    if n < 3:
        return a, 0
    a[n, 0] = a[0, 0]
    a[n, 1] = a[0, 1]
    a[n, 2] = a[0, 2]
    return a, n + 1


@allocating
def _clip_rings_alone(line, ring_offsets, r_begin, r_end, ring_rev, window, out, v, n_rings,
                      n_polys):
    """Write an invalid polygon clipped ring by ring: one polygon, its shell then its holes.

    Without ``out.write`` only the counts advance. A shell clipped to nothing drops the
    polygon.
    """
    write = out.write
    has_z = line.has_z
    rings_before = n_rings
    for r in range(r_begin, r_end):
        first = ring_offsets[r]
        last = ring_offsets[r + 1] - 1
        if last - first < 3:
            continue
        ring, m = sutherland_hodgman(line, first, last, ring_rev[r - r_begin], window)
        if m == 0:
            if r == r_begin:
                return v, n_rings, n_polys
            continue
        if write:
            out_xy = out.xy
            out_z = out.z
            out.ring_starts[n_rings] = v
            for k in range(m):
                out_xy[v + k, 0] = ring[k, 0]
                out_xy[v + k, 1] = ring[k, 1]
                if has_z:
                    out_z[v + k] = ring[k, 2]
        v += m
        n_rings += 1
    if n_rings > rings_before:
        if write:
            out.poly_rings[n_polys] = n_rings - rings_before
        n_polys += 1
    return v, n_rings, n_polys


@borrowing
def clip_polygon(line, polygons, p, window, options, decisions, scratch, out, v, n_rings,
                 n_polys):
    """Clip polygon p of `polygons` (on the vertices `line`) against `window`.

    Output polygons are written from ``out.xy[v]``, their rings' starts from
    ``out.ring_starts[n_rings]`` and their ring counts from ``out.poly_rings[n_polys]``;
    shells counter-clockwise, holes clockwise. `scratch` is the caller's, sized by the
    bounds of `bound_chains`; the stats go to its block's counter row. Returns
    ``(v, n_rings, n_polys, ok)``; ``ok`` is False when the input is found invalid: a
    cut ring without area, or chains whose entries and exits do not alternate along the
    boundary (the rings cross); the polygon is then clipped ring by ring
    (`sutherland_hodgman`), not repaired. In the counting pass (``out.write`` False)
    that fallback only counts; the rest writes to `out`, the caller's scratch then.
    With ``decisions.decided`` the rings' runs were pruned and their segments clipped
    elsewhere (the OpenCL backend): ring r's chains are assembled from them
    (`polylines.assemble_chains`) instead of cut by `polylines.clip_chains`.

    The steps (each inlined here): cut the rings into chains (`_cut_rings`); sort the
    chains' ends along the boundary (`_sort_events`) and check that exits and entries
    alternate (`_events_alternate`); walk from each exit to the next entry, through the
    corners between, until the ring closes (`_walk`); keep the rings never cut
    (`_add_uncut_rings`), or the window itself if nothing is cut and the window lies
    inside the polygon (`_add_window_if_covered`); write each shell with its holes
    (`_write_pieces`). Only `_split_loops` and the fallback allocate (``allocating``):
    no other array is reference-counted per polygon.
    """
    r_begin = polygons.polygon_offsets[p]
    r_end = polygons.polygon_offsets[p + 1]
    n_r = r_end - r_begin
    if n_r == 0:
        return v, n_rings, n_polys, True
    has_z = line.has_z
    ring_offsets = polygons.ring_offsets
    # 1. Cut every ring into chains, oriented so the polygon's interior is on the left.
    n_lc, ok = _cut_rings(line, ring_offsets, r_begin, r_end, Cut(window, True), options,
                          decisions, scratch)
    if has_z:
        _find_corner_z(line, ring_offsets, r_begin, r_end, window, scratch.corners)
    # 2. The walk goes over boundary events (chain starts and ends), sorted
    # counter-clockwise: exits and entries must alternate.
    n_ev = _sort_events(scratch.chains.xy, scratch.logical, n_lc, window, scratch.events)
    if not (ok and _events_alternate(scratch.events, n_ev)):
        v, n_rings, n_polys = _clip_rings_alone(line, ring_offsets, r_begin, r_end,
                                                scratch.rings.reversed, window, out, v,
                                                n_rings, n_polys)
        return v, n_rings, n_polys, False
    # 3. The walk: chains closed into rings along the boundary.
    n_rg, walked = _walk(scratch, has_z, n_lc, n_ev, window)
    # 4. Rings never cut: inside the window whole.
    n_rg, uncut_ok = _add_uncut_rings(line, n_r, n_lc, scratch, n_rg)
    # 5. No chain and no uncut shell: the window lies inside the polygon or outside it.
    if n_lc == 0 and scratch.rings.state[0] == _UNTOUCHED:
        n_rg = _add_window_if_covered(line, n_r, window, scratch, n_rg)
    # 6. Output: each shell, then the holes inside it.
    v, n_rings, n_polys, placed = _write_pieces(has_z, scratch.closed, n_rg, out, v, n_rings,
                                                n_polys)
    return v, n_rings, n_polys, walked and uncut_ok and placed


@inlined
def _cut_rings(line, ring_offsets, r_begin, r_end, cut, options, decisions, scratch):
    """Cut rings r_begin..r_end-1 into ``scratch.chains``; return ``(n_logical, ok)``.

    Fills ``scratch.rings`` (each ring's state and orientation) and
    ``scratch.logical``, the chains of the cut rings, oriented so that the polygon's
    interior is on their left (shells counter-clockwise, holes clockwise); a ring's
    last and first chains join across its closing vertex. ``ok`` is False for a ring
    without area (self-intersecting or degenerate input).
    """
    chains = scratch.chains
    starts = chains.starts
    rings = scratch.rings
    lc = scratch.logical
    v_ch = 0
    c_ch = 0
    n_lc = 0
    ok = True
    for r in range(r_begin, r_end):
        first = ring_offsets[r]
        last = ring_offsets[r + 1] - 1
        j = r - r_begin
        rings.first[j] = first
        rings.last[j] = last
        area = signed_area(line.xy, first, last) if last > first else 0.0
        rings.reversed[j] = (area < 0.0) if j == 0 else (area > 0.0)
        c0 = c_ch
        if decisions.decided:
            v_ch, c_ch, at_first, at_last = assemble_chains(
                line, first, last, cut, True, decisions, decisions.chunk_start[r], chains, True,
                v_ch, c_ch)
        else:
            # Rings are short: their runs are coded from the vertices, and their chains
            # written as decided (no chunk codes, no plan).
            # The positions as int64, never literals: one copy of `clip_chains` for rings.
            v_ch, c_ch, at_first, at_last, _ = clip_chains(
                line, first, last, cut, True, options, chains, True, np.int64(v_ch),
                np.int64(c_ch), scratch.block, scratch.no_plan)
        starts[c_ch] = v_ch
        n_chains = c_ch - c0
        if last > first and area == 0.0:
            ok = False  # a ring without area: self-intersecting (or degenerate) input
        if n_chains == 0:
            rings.state[j] = _UNTOUCHED
            continue
        if n_chains == 1 and at_first and at_last:
            rings.state[j] = _FULL
            continue
        rings.state[j] = _CUT
        if area == 0.0:
            ok = False
        # Logical chains; the last and first chains join across the closing vertex.
        joined = at_first and at_last and n_chains >= 2
        for k in range(c0 + 1 if joined else c0, c_ch):
            lc.start1[n_lc] = starts[k]
            lc.end1[n_lc] = starts[k + 1]
            lc.start2[n_lc] = 0
            lc.end2[n_lc] = 0
            if joined and k == c_ch - 1:
                # The first chain's first vertex repeats the joint: skip it.
                lc.start2[n_lc] = starts[c0] + 1
                lc.end2[n_lc] = starts[c0 + 1]
            lc.reversed[n_lc] = rings.reversed[j]
            lc.ring[n_lc] = j
            n_lc += 1
    return n_lc, ok


@inlined
def _find_corner_z(line, ring_offsets, r_begin, r_end, window, corners):
    """Store the Z of the window's corners that lie on an input segment of the polygon.

    The walk passes corners; one on an input edge takes that edge's Z rather than one
    interpolated along the boundary.
    """
    xy = line.xy
    z = line.z
    xmin, ymin, xmax, ymax = window
    for e in range(4):
        corners.z[e] = 0.0
        corners.known[e] = False
    for r in range(r_begin, r_end):
        for i in range(ring_offsets[r], ring_offsets[r + 1] - 1):
            for e in range(4):
                if corners.known[e]:
                    continue
                cx, cy = _corner_after(e, window)
                x0 = xy[i, 0]
                y0 = xy[i, 1]
                x1 = xy[i + 1, 0]
                y1 = xy[i + 1, 1]
                # An input vertex at the corner, or a segment through it: within the
                # accuracy promise (1e-9 of the window's size) of the corner.
                dx = x1 - x0
                dy = y1 - y0
                dd = dx * dx + dy * dy
                t = 0.0
                if dd > 0.0:
                    t = min(1.0, max(0.0, ((cx - x0) * dx + (cy - y0) * dy) / dd))
                near = math.hypot(x0 + t * dx - cx, y0 + t * dy - cy) <= 1e-9 * max(
                    xmax - xmin, ymax - ymin)
                if not near:
                    continue
                corners.z[e] = z[i] + t * (z[i + 1] - z[i])
                corners.known[e] = True


@inlined
def _sort_events(ch_xy, lc, n_lc, window, events):
    """Place the start and end of every logical chain on the boundary, and sort them.

    Counter-clockwise from (xmin, ymin), then by angle (`_event_angle`); returns the
    number of events.
    """
    n_ev = 2 * n_lc
    order = events.order
    for k in range(n_lc):
        for end in range(2):
            i = _chain_vertex(lc, k, 0 if end == 0 else _chain_length(lc, k) - 1)
            e, s = boundary_key(ch_xy[i, 0], ch_xy[i, 1], window)
            ev = 2 * k + end
            events.edge[ev] = e
            events.s[ev] = s
            events.angle[ev] = _event_angle(ch_xy, lc, k, end == 0, e, window)
            order[ev] = ev
    for a in range(1, n_ev):  # insertion sort: few events per polygon
        item = order[a]
        b = a - 1
        while b >= 0 and _key_less(events.edge[item], events.s[item], events.angle[item],
                                   events.edge[order[b]], events.s[order[b]],
                                   events.angle[order[b]]):
            order[b + 1] = order[b]
            b -= 1
        order[b + 1] = item
    for a in range(n_ev):
        events.rank[order[a]] = a
    return n_ev


@inlined
def _event_key(events, e):
    """Return (edge, s): where event e lies on the boundary (a `boundary_key`)."""
    return events.edge[e], events.s[e]


@inlined
def _same_point(events, e1, e2):
    """Return whether events e1 and e2 lie at the same boundary point."""
    return _event_key(events, e1) == _event_key(events, e2)


@inlined
def _events_alternate(events, n_ev):
    """Return whether exits and entries alternate along the boundary.

    Two exits (or entries) in a row mean rings that cross, or a hole outside its shell.
    Events at one point (a ring touching the edge there) count as one, by their
    balance, which must be -1, 0 or 1. (Every chain has one exit and one entry, so
    alternating balances also close up cyclically.)
    """
    order = events.order
    previous = 0
    a = 0
    while a < n_ev:
        b = a
        net = 0
        while b < n_ev and _same_point(events, order[b], order[a]):
            net += 1 if order[b] % 2 == 1 else -1
            b += 1
        if net > 1 or net < -1 or (net != 0 and net == previous):
            return False
        if net != 0:
            previous = net
        a = b
    return True


@inlined
def _next_chain(events, n_ev, k):
    """Return ``(next, direct)``: the chain the walk continues with after chain k's end.

    The chain entering at the same point just clockwise of it (the polygon is pinched
    there: `direct`, no boundary between), else the first entry counter-clockwise along
    the boundary, the most clockwise one at its point; -1 if there is none.
    """
    order = events.order
    i = events.rank[2 * k + 1]
    if i > 0 and _same_point(events, order[i - 1], order[i]) and order[i - 1] % 2 == 0:
        return order[i - 1] // 2, True
    g = i + 1
    while g < n_ev and _same_point(events, order[g], order[i]):
        g += 1
    for _ in range(n_ev):
        if g >= n_ev:
            g = 0
        g_end = g + 1
        while g_end < n_ev and _same_point(events, order[g_end], order[g]):
            g_end += 1
        q = g_end - 1
        while q >= g and order[q] % 2 == 1:
            q -= 1
        if q >= g:
            return order[q] // 2, False
        g = g_end
    return -1, False


@inlined
def _walk_corners(scratch, has_z, k, nxt, window, m):
    """Append the corners passed from chain k's exit to chain nxt's entry; return the end.

    None if the entry lies further along the exit's edge. Their Z is the input's at a
    corner on an input segment (`_find_corner_z`), else interpolated along the boundary
    between the exit's and the entry's.
    """
    ee, es = _event_key(scratch.events, 2 * k + 1)  # chain k's exit
    se, ss = _event_key(scratch.events, 2 * nxt)  # chain nxt's entry
    if se == ee and ss > es:
        return m
    xmin, ymin, xmax, ymax = window
    lc = scratch.logical
    walk = scratch.walk
    corners = scratch.corners
    z_from = 0.0
    z_to = 0.0
    p_from = 0.0
    span = 1.0
    perimeter = 2.0 * ((xmax - xmin) + (ymax - ymin))
    if has_z:
        z_from = scratch.chains.z[_chain_vertex(lc, k, _chain_length(lc, k) - 1)]
        z_to = scratch.chains.z[_chain_vertex(lc, nxt, 0)]
        p_from = _perimeter_position(ee, es, window)
        span = _perimeter_position(se, ss, window) - p_from
        if span <= 0.0:
            span += perimeter
    e = ee
    while True:
        x, y, corner = _edge_start((e + 1) % 4, window)  # the corner where edge e ends
        zc = 0.0
        if has_z:
            d = corner - p_from
            if d < 0.0:
                d += perimeter
            zc = z_from + (z_to - z_from) * min(1.0, d / span)
            if corners.known[e]:
                zc = corners.z[e]
        m = _put(walk.xy, walk.z, has_z, m, 0, x, y, zc)
        e = (e + 1) % 4
        if e == se:
            break
    return m


@inlined
def _walk(scratch, has_z, n_lc, n_ev, window):
    """Close the logical chains into rings along the boundary; return ``(n_closed, ok)``.

    Each walk (`_walk_from`) starts at a chain not yet visited and is split into simple
    rings (`_split_loops`) stored in ``scratch.closed``. ``ok`` is False when the chains
    are inconsistent (invalid input): what was walked is closed anyway.
    """
    walk = scratch.walk
    closed = scratch.closed
    visited = scratch.logical.visited
    n_rg = 0
    closed.start[0] = 0
    ok = True
    for k in range(n_lc):
        visited[k] = False
    for k0 in range(n_lc):
        if visited[k0]:
            continue
        m, several_rings, consistent = _walk_from(scratch, has_z, k0, n_ev, window)
        ok = ok and consistent
        if m >= 4:
            n_rg = _split_loops(walk, has_z, m, several_rings, closed, n_rg)
    return n_rg, ok


@inlined
def _walk_from(scratch, has_z, k0, n_ev, window):
    """Walk from chain k0 back to it into ``scratch.walk``: ``(m, several_rings, ok)``.

    Appends each chain, goes to the chain the ring continues with (`_next_chain`)
    through the corners between (`_walk_corners`), until back at k0, and closes the
    ring (m vertices). `several_rings`: the walk joined chains of two or more rings.
    ``ok`` is False if the chains are inconsistent (a chain without a next one, or one
    visited before): the walk stops there.
    """
    lc = scratch.logical
    walk = scratch.walk
    ok = True
    m = 0
    k = k0
    # Only a walk joining chains of two or more rings (a cut hole and its shell) can
    # pass a vertex of one inside an edge of the other (a hole touching its shell
    # mid-edge), so only such a walk is noded (`_split_loops`): the chains of one
    # valid ring never touch each other. Noding every walk of a polygon with holes
    # took about a fifth of the polygon benchmark's time.
    several_rings = False
    while True:
        lc.visited[k] = True
        several_rings = several_rings or lc.ring[k] != lc.ring[k0]
        m = _put_chain(scratch.chains, has_z, lc, k, walk, m)
        nxt, direct = _next_chain(scratch.events, n_ev, k)
        if nxt < 0:
            ok = False
            break
        if not direct:
            m = _walk_corners(scratch, has_z, k, nxt, window, m)
        if nxt == k0:
            break
        if lc.visited[nxt]:
            ok = False  # inconsistent chains (invalid input): close what we have
            break
        k = nxt
    if m > 0 and not (walk.xy[m - 1, 0] == walk.xy[0, 0]
                      and walk.xy[m - 1, 1] == walk.xy[0, 1]):
        walk.xy[m, 0] = walk.xy[0, 0]
        walk.xy[m, 1] = walk.xy[0, 1]
        if has_z:
            walk.z[m] = walk.z[0]
        m += 1
    return m, several_rings, ok


@inlined
def _add_uncut_rings(line, n_r, n_lc, scratch, n_rg):
    """Store the rings inside the window whole; return ``(n_closed, ok)``.

    The shell of a cut polygon is never one of them unless the input is invalid (then
    ``ok`` is False).
    """
    rings = scratch.rings
    walk = scratch.walk
    ok = True
    for j in range(n_r):
        if rings.state[j] != _FULL:
            continue
        if j == 0 and n_lc > 0:
            ok = False
        count = _put_ring(line.xy, line.z, line.has_z, rings.first[j], rings.last[j],
                          rings.reversed[j], walk.xy, walk.z, 0)
        for i in range(count):
            walk.index[i] = i
        n_rg = _add_ring(scratch.closed, line.has_z, n_rg, walk.xy, walk.z, walk.index,
                         count, False)
    return n_rg, ok


@inlined
def _add_window_if_covered(line, n_r, window, scratch, n_rg):
    """Store the window as a ring if its centre lies inside the shell and outside the holes.

    For a polygon none of whose rings is cut or inside the window. Returns the ring count.
    """
    xmin, ymin, xmax, ymax = window
    rings = scratch.rings
    walk = scratch.walk
    corners = scratch.corners
    cx = 0.5 * xmin + 0.5 * xmax
    cy = 0.5 * ymin + 0.5 * ymax
    covered = point_in_ring(cx, cy, line.xy, rings.first[0], rings.last[0]) > 0
    for j in range(1, n_r):
        if covered and rings.state[j] == _UNTOUCHED and point_in_ring(
                cx, cy, line.xy, rings.first[j], rings.last[j]) > 0:
            covered = False
    if not covered:
        return n_rg
    zc = 0.0
    if line.has_z:
        for k in range(rings.first[0], rings.last[0]):
            zc += line.z[k]
        zc /= max(1, rings.last[0] - rings.first[0])
    for corner in range(4):
        x, y, _ = _edge_start(corner, window)
        walk.xy[corner, 0] = x
        walk.xy[corner, 1] = y
        if line.has_z:
            walk.z[corner] = corners.z[(corner + 3) % 4] if corners.known[
                (corner + 3) % 4] else zc
        walk.index[corner] = corner
    return _add_ring(scratch.closed, line.has_z, n_rg, walk.xy, walk.z, walk.index, 4, True)


@inlined
def _write_pieces(has_z, closed, n_rg, out, v, n_rings, n_polys):
    """Write each closed shell, then the holes inside it, as one polygon.

    Returns ``(v, n_rings, n_polys, placed)``; ``placed`` is False if a hole lies
    outside every shell (invalid input).
    """
    for a in range(n_rg):
        closed.done[a] = False
    for a in range(n_rg):
        if closed.sign[a] < 0:
            continue
        out.ring_starts[n_rings] = v
        n_rings += 1
        rings_before = n_rings - 1
        v = _put_ring(closed.xy, closed.z, has_z, closed.start[a], closed.start[a + 1] - 1,
                      False, out.xy, out.z, v)
        shell_start = out.ring_starts[n_rings - 1]
        shell_last = v - 1
        for b in range(n_rg):
            if closed.sign[b] > 0 or closed.done[b]:
                continue
            where = 0
            for i in range(closed.start[b], closed.start[b + 1] - 1):
                where = point_in_ring(closed.xy[i, 0], closed.xy[i, 1], out.xy, shell_start,
                                      shell_last)
                if where != 0:
                    break
            if where < 0:
                continue
            closed.done[b] = True
            out.ring_starts[n_rings] = v
            n_rings += 1
            v = _put_ring(closed.xy, closed.z, has_z, closed.start[b],
                          closed.start[b + 1] - 1, False, out.xy, out.z, v)
        out.poly_rings[n_polys] = n_rings - rings_before
        n_polys += 1
    placed = True
    for b in range(n_rg):
        if closed.sign[b] < 0 and not closed.done[b]:
            placed = False  # a hole outside every piece: invalid input
    return v, n_rings, n_polys, placed


_OUTSIDE, _INSIDE, _AMBIGUOUS = 0, 1, 2
#: Class of a polygon whose rings must be cut (`polygon_class_of`).
AMBIGUOUS = _AMBIGUOUS


@scalar
def _output_bound(scratch_vertices, scratch_chains, n_r):
    """Return the output vertex bound of a polygon from its chain bounds.

    Chain vertices (uncut rings included); up to four corners, a closing vertex and a
    loop split per chain; the window's five.
    """
    return scratch_vertices + 7 * scratch_chains + n_r + 6


@scalar
def polygon_class_of(xy, ring_offsets, r_begin, r_end, window):
    """Return what the shell's bounding box says of a polygon: outside, inside, ambiguous.

    The run test of `clip_chains` on the whole shell: beyond an edge, nothing is left;
    strictly inside the window, every ring stays as it is; otherwise it must be cut.
    """
    if r_end <= r_begin:
        return _OUTSIDE
    first = ring_offsets[r_begin]
    last = ring_offsets[r_begin + 1] - 1
    if last <= first:
        return _OUTSIDE
    lo, hi, strict = run_box_codes(xy, first, last, window)
    return _OUTSIDE if lo & hi else (_INSIDE if strict else _AMBIGUOUS)


@borrowing
def _class_of(line, polygons, p):
    """Return `polygon_class_of` polygon p against its window."""
    return polygon_class_of(line.xy, polygons.ring_offsets, polygons.polygon_offsets[p],
                            polygons.polygon_offsets[p + 1],
                            window_of(polygons.windows, polygons.polygon_window, p))


@parallel
def classify_polygons(line, polygons, polygon_class):
    """Store `polygon_class_of` of every polygon (as `clip_polygon_blocks` decides it)."""
    for p in prange(polygons.polygon_offsets.shape[0] - 1):
        polygon_class[p] = _class_of(line, polygons, p)


@parallel
def clip_polygon_blocks(line, polygons, options, block_size, plan, counts, out, counters,
                        decisions):
    """Count (``out.write`` False) or write every polygon of a ragged array.

    The shell's bounding box classifies each polygon (the run test of `clip_chains` on
    the whole shell): beyond an edge, nothing is left; strictly inside the window, every
    ring is copied as it is (holes lie inside their shell); only the others are cut.
    The count pass records the class in `plan` and the exact output counts in `counts`
    (``n_vertices``, ``n_rings``, ``n_polys``), cutting the ambiguous polygons into
    scratch space; the write pass writes polygon p at ``counts.vertex_start[p]``,
    ``ring_start[p]`` and ``poly_start[p]`` (exclusive sums of the counts), cutting the
    ambiguous ones again. Ambiguous polygons are few where it matters, so cutting them
    twice costs less than over-allocating every output and compacting it. Stats are
    counted in the write pass, one row of `counters` per block of `block_size`
    polygons. With ``decisions.decided``, the runs of the ambiguous polygons' rings were
    pruned and their segments clipped elsewhere (see `clip_polygon`; those counters are
    the caller's).
    """
    for blk in prange(counters.shape[0]):
        # int64, as the serial driver passes it: one specialisation of the block, not two
        _polygon_block(np.int64(blk), line, polygons, options, block_size, plan, counts, out,
                       counters, decisions)


@scalar
def _polygon_block(blk, line, polygons, options, block_size, plan, counts, out, counters,
                   decisions):
    """Count or write polygons ``blk * block_size`` on: the body of `clip_polygon_blocks`."""
    n_polygons = polygons.polygon_offsets.shape[0] - 1
    write = out.write
    lo_p = blk * block_size
    hi_p = min(n_polygons, (blk + 1) * block_size)
    st = counters[blk]
    if not write:
        st = np.zeros(C.WIDTH, dtype=np.int64)  # counted once, in the write pass
    max_v, max_c, max_r, max_out = _plan_block(line, polygons, lo_p, hi_p, not write, plan,
                                               counts)
    if write:
        _copy_decided(line, polygons, lo_p, hi_p, plan.polygon_class, counts, out, st)
    if max_out == 1:
        return  # no ambiguous polygon in this block
    has_z = line.has_z
    scratch = _polygon_scratch(st, max_v, max_c, max_r, max_out, has_z)
    dst = out
    if not write:
        dst = PolygonsOut(write, np.empty((max_out, 2), dtype=np.float64),
                          np.empty(max_out if has_z else 0, dtype=np.float64),
                          np.empty(max_out // 4 + 2, dtype=np.int64),
                          np.empty(max_out // 4 + 2, dtype=np.int64))
    _clip_ambiguous(line, polygons, lo_p, hi_p, options, decisions, plan.polygon_class, counts,
                    scratch, dst)


@borrowing
def _clip_ambiguous(line, polygons, lo_p, hi_p, options, decisions, polygon_class, counts,
                    scratch, out):
    """Clip (`clip_polygon`) the ambiguous polygons among lo_p..hi_p-1 into `out`.

    In the count pass (``out.write`` False, `out` one polygon's scratch) store their
    output counts in `counts`; in the write pass write them from their starts.
    """
    write = out.write
    for p in range(lo_p, hi_p):
        if polygon_class[p] != _AMBIGUOUS:
            continue
        v0 = counts.vertex_start[p] if write else 0
        r0 = counts.ring_start[p] if write else 0
        q0 = counts.poly_start[p] if write else 0
        window = window_of(polygons.windows, polygons.polygon_window, p)
        v, nr, npoly, ok = clip_polygon(line, polygons, p, window, options, decisions, scratch,
                                        out, v0, r0, q0)
        if not ok:
            scratch.block.st[C.INVALID_POLYGONS] += 1
        if not write:
            counts.n_vertices[p] = v - v0
            counts.n_rings[p] = nr - r0
            counts.n_polys[p] = npoly - q0


@borrowing
def _plan_block(line, polygons, lo_p, hi_p, classify, plan, counts):
    """Return the block's scratch sizes ``(vertices, chains, rings, output)``.

    With `classify` (the count pass), first classify each polygon into ``plan``, count
    the output of those not cut (all or nothing) into ``counts``, and bound the chain
    scratch of the ambiguous ones (`bound_chains`). The sizes are the largest over the
    block's ambiguous polygons (1 if there is none).
    """
    xy = line.xy
    ring_offsets = polygons.ring_offsets
    max_v = 1
    max_c = 1
    max_r = 1
    max_out = 1
    for p in range(lo_p, hi_p):
        r_begin = polygons.polygon_offsets[p]
        r_end = polygons.polygon_offsets[p + 1]
        n_r = r_end - r_begin
        if classify:
            window = window_of(polygons.windows, polygons.polygon_window, p)
            if plan.classified:
                cls = plan.polygon_class[p]
            else:
                cls = polygon_class_of(xy, ring_offsets, r_begin, r_end, window)
                plan.polygon_class[p] = cls
            counts.n_vertices[p] = 0
            counts.n_rings[p] = 0
            counts.n_polys[p] = 0
            if cls == _INSIDE:
                counts.n_vertices[p] = ring_offsets[r_end] - ring_offsets[r_begin]
                counts.n_rings[p] = n_r
                counts.n_polys[p] = 1
            elif cls == _AMBIGUOUS:
                sv = n_r
                sc = 0
                for r in range(r_begin, r_end):
                    first = ring_offsets[r]
                    last = ring_offsets[r + 1] - 1
                    if last > first:
                        nv, nc, _ = bound_chains(xy, first, last, window)
                        sv += nv
                        sc += nc
                    else:
                        sc += 1
                plan.scratch_vertices[p] = sv
                plan.scratch_chains[p] = sc
        if plan.polygon_class[p] == _AMBIGUOUS:
            max_v = max(max_v, plan.scratch_vertices[p])
            max_c = max(max_c, plan.scratch_chains[p])
            max_r = max(max_r, n_r)
            max_out = max(max_out, _output_bound(plan.scratch_vertices[p],
                                                 plan.scratch_chains[p], n_r))
    return max_v, max_c, max_r, max_out


@scalar
def _polygon_scratch(st, max_v, max_c, max_r, max_out, has_z):
    """Return the scratch to clip polygons of up to these sizes (see `_plan_block`).

    `st` is the block's counter row.
    """
    no_codes = np.empty(0, dtype=np.uint8)
    ch_xy = np.empty((max_v, 2), dtype=np.float64)
    return PolygonScratch(
        BlockState(st, np.empty((RUN_STACK_CAPACITY, 3), dtype=np.int64), segment_stack(),
                   no_codes),
        ChainsOut(ch_xy, ch_xy.reshape(-1), np.empty(max_v if has_z else 0),
                  np.empty(max_c + 1, dtype=np.int64)),
        LogicalChains(np.empty(max_c, dtype=np.int64), np.empty(max_c, dtype=np.int64),
                      np.empty(max_c, dtype=np.int64), np.empty(max_c, dtype=np.int64),
                      np.empty(max_c, dtype=np.bool_), np.empty(max_c, dtype=np.bool_),
                      np.empty(max_c, dtype=np.int64)),
        Events(np.empty(2 * max_c, dtype=np.int64), np.empty(2 * max_c, dtype=np.float64),
               np.empty(2 * max_c, dtype=np.float64), np.empty(2 * max_c, dtype=np.int64),
               np.empty(2 * max_c, dtype=np.int64)),
        RingStates(np.empty(max_r, dtype=np.int64), np.empty(max_r, dtype=np.bool_),
                   np.empty(max_r, dtype=np.int64), np.empty(max_r, dtype=np.int64)),
        Walk(np.empty((max_out, 2), dtype=np.float64),
             np.empty(max_out if has_z else 0, dtype=np.float64),
             np.empty(max_out, dtype=np.int64)),
        ClosedRings(np.empty((max_out, 2), dtype=np.float64),
                    np.empty(max_out if has_z else 0, dtype=np.float64),
                    np.empty(max_out // 4 + 2, dtype=np.int64),
                    np.empty(max_out // 4 + 2, dtype=np.int64),
                    np.empty(max_out // 4 + 2, dtype=np.bool_)),
        Corners(np.zeros(4), np.zeros(4, dtype=np.bool_)),
        PartPlan(no_codes, no_codes, np.empty((0, 2), dtype=np.int64)))


@borrowing
def _copy_decided(line, polygons, lo_p, hi_p, polygon_class, counts, out, st):
    """Write the polygons lo_p..hi_p-1 the window's box test decided whole.

    Outside: nothing; inside: all its rings, oriented on the way (shells
    counter-clockwise, holes clockwise). Ambiguous polygons are left to `clip_polygon`.
    """
    ring_offsets = polygons.ring_offsets
    for p in range(lo_p, hi_p):
        cls = polygon_class[p]
        if cls == _AMBIGUOUS:
            continue
        r_begin = polygons.polygon_offsets[p]
        r_end = polygons.polygon_offsets[p + 1]
        n_segments = ring_offsets[r_end] - ring_offsets[r_begin] - (r_end - r_begin)
        st[C.RUNS_EVALUATED] += 1
        st[C.RUN_LEVELS] += 1
        st[C.SEGMENT_LEVELS] += n_segments
        if cls == _OUTSIDE:
            st[C.RUNS_REJECTED] += 1
            continue
        st[C.RUNS_ACCEPTED] += 1
        v = counts.vertex_start[p]
        invalid = False
        for r in range(r_begin, r_end):
            first = ring_offsets[r]
            last = ring_offsets[r + 1] - 1
            area = signed_area(line.xy, first, last) if last > first else 0.0
            if area == 0.0:
                invalid = True
            out.ring_starts[counts.ring_start[p] + r - r_begin] = v
            v = _put_ring(line.xy, line.z, line.has_z, first, last,
                          (area < 0.0) if r == r_begin else (area > 0.0), out.xy, out.z, v)
        out.poly_rings[counts.poly_start[p]] = r_end - r_begin
        if invalid:
            st[C.INVALID_POLYGONS] += 1  # a ring without area (a symmetric bow tie)
