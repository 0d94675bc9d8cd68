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
"""

import math

import numpy as np
from numba import prange

from rnsca.kernels import counters as C
from rnsca.kernels.jit import borrowing, parallel, scalar
from rnsca.kernels.outcode import line_coordinate
from rnsca.kernels.polylines import (
    RUN_STACK_CAPACITY,
    assemble_chains,
    bound_chains,
    clip_chains,
    run_box_codes,
)
from rnsca.kernels.segments import STACK_CAPACITY

__all__ = [
    "AMBIGUOUS",
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
def boundary_key(x, y, xmin, ymin, xmax, ymax):
    """Return (edge, s): the position of a boundary point, counter-clockwise from (xmin, ymin).

    `s` increases counter-clockwise along `edge`; a corner belongs to the edge it ends.
    A point off the boundary (never produced by exact clipping) is put on the nearest edge.
    """
    if y == ymin:
        return _BOTTOM, x
    if x == xmax:
        return _RIGHT, y
    if y == ymax:
        return _TOP, -x
    if x == xmin:
        return _LEFT, -y
    d_bottom = y - ymin
    d_right = xmax - x
    d_top = ymax - y
    d_left = x - xmin
    d = min(min(d_bottom, d_right), min(d_top, d_left))
    if d == d_bottom:
        return _BOTTOM, x
    if d == d_right:
        return _RIGHT, y
    if d == d_top:
        return _TOP, -x
    return _LEFT, -y


@scalar
def _perimeter_position(edge, s, xmin, ymin, xmax, ymax):
    """Return the distance along the boundary, counter-clockwise from (xmin, ymin)."""
    w = xmax - xmin
    h = ymax - ymin
    if edge == _BOTTOM:
        return s - xmin
    if edge == _RIGHT:
        return w + (s - ymin)
    if edge == _TOP:
        return w + h + (xmax + s)
    return 2.0 * w + h + (ymax + s)


@scalar
def _corner_after(edge, xmin, ymin, xmax, ymax):
    """Return the corner where `edge` ends (counter-clockwise)."""
    if edge == _BOTTOM:
        return xmax, ymin
    if edge == _RIGHT:
        return xmax, ymax
    if edge == _TOP:
        return xmin, ymax
    return xmin, ymin


@scalar
def _corner_position(edge, xmin, ymin, xmax, ymax):
    """Return the boundary distance of the corner where `edge` ends (see `_corner_after`)."""
    w = xmax - xmin
    h = ymax - ymin
    if edge == _BOTTOM:
        return w
    if edge == _RIGHT:
        return w + h
    if edge == _TOP:
        return 2.0 * w + h
    return 0.0


@scalar
def _key_less(e1, s1, t1, e2, s2, t2):
    """Return whether boundary event 1 comes before event 2: position, then angle."""
    return e1 < e2 or (e1 == e2 and (s1 < s2 or (s1 == s2 and t1 < t2)))


@borrowing
def _chain_length(lc, k):
    return (lc[k, 1] - lc[k, 0]) + (lc[k, 3] - lc[k, 2])


@borrowing
def _chain_vertex(lc, k, j):
    """Return the scratch index of vertex j of logical chain k, in its oriented order.

    A logical chain is range 1 then range 2 of the chain scratch (range 2 is the first
    chain of a ring, continued across its closing vertex), read backwards if the ring
    was reversed to orient it. Row k of `lc`: range 1 (columns 0, 1), range 2 (2, 3),
    reversed (4), visited by the walk (5), and the ring it comes from (6).
    """
    if lc[k, 4] != 0:
        j = _chain_length(lc, k) - 1 - j
    n1 = lc[k, 1] - lc[k, 0]
    return lc[k, 0] + j if j < n1 else lc[k, 2] + (j - n1)


@borrowing
def _event_angle(ch_xy, lc, k, at_start, edge, xmin, ymin, xmax, ymax):
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
    cx, cy = _corner_after(edge, xmin, ymin, xmax, ymax)
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


@borrowing
def _put_chain(ch_xy, ch_z, has_z, lc, k, out_xy, out_z, v, ring_start):
    """Append the vertices of logical chain k; return the next position."""
    for j in range(_chain_length(lc, k)):
        i = _chain_vertex(lc, k, j)
        v = _put(out_xy, out_z, has_z, v, ring_start, ch_xy[i, 0], ch_xy[i, 1],
                 ch_z[i] if has_z else 0.0)
    return v


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
def _add_ring(rg_xy, rg_z, has_z, rg_start, rg_sign, n_rg, src_xy, src_z, idx, count, close):
    """Store the ring of ``src[idx[0..count-1]]`` (closed with its first vertex if `close`).

    Returns the new ring count; a ring of fewer than three distinct vertices or no area
    is not stored. Its sign (1 shell, -1 hole) comes from its orientation.
    """
    v = rg_start[n_rg]
    start = v
    for j in range(count):
        i = idx[j]
        v = _put(rg_xy, rg_z, has_z, v, start, src_xy[i, 0], src_xy[i, 1],
                 src_z[i] if has_z else 0.0)
    if close:
        i = idx[0]
        v = _put(rg_xy, rg_z, has_z, v, start, src_xy[i, 0], src_xy[i, 1],
                 src_z[i] if has_z else 0.0)
    if v - start < 4:
        return n_rg
    area = signed_area(rg_xy, start, v - 1)
    if area == 0.0:
        return n_rg
    rg_sign[n_rg] = 1 if area > 0.0 else -1
    rg_start[n_rg + 1] = v
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


@scalar
def _split_loops(tmp_xy, tmp_z, has_z, m, node, stk, rg_xy, rg_z, rg_start, rg_sign, n_rg):
    """Store the closed walk ring ``tmp[0..m-1]`` as simple rings; return the ring count.

    The walk can pass a point twice (a hole or a part of the ring touching the window's
    edge, or a hole touching its shell at a vertex); a ring through one point twice is
    not valid, so it is cut into loops at every repeated point. Counter-clockwise loops
    are shells, clockwise ones holes (touching their shell at that point, as valid
    polygons may). With `node`, a vertex lying inside another edge of the ring (a hole
    touching its shell mid-edge) is first made a vertex of that edge too.
    """
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
                n_rg = _add_ring(rg_xy, rg_z, has_z, rg_start, rg_sign, n_rg, tmp_xy, tmp_z,
                                 stk[q:], top - q, True)
                top = q + 1
                continue
        stk[top] = i
        top += 1
    return _add_ring(rg_xy, rg_z, has_z, rg_start, rg_sign, n_rg, tmp_xy, tmp_z, stk, top, True)


@borrowing
def _inside_edge(x, y, edge, xmin, ymin, xmax, ymax):
    if edge == _LEFT:
        return x >= xmin
    if edge == _RIGHT:
        return x <= xmax
    if edge == _BOTTOM:
        return y >= ymin
    return y <= ymax


@borrowing
def _cross_edge(x0, y0, z0, x1, y1, z1, edge, xmin, ymin, xmax, ymax):
    """Return the point (x, y, z) where segment 0-1 crosses the line of `edge`."""
    if edge == _LEFT or edge == _RIGHT:
        e = xmin if edge == _LEFT else xmax
        t = (e - x0) / (x1 - x0)
        return e, line_coordinate(e, x0, y0, x1, y1), z0 + t * (z1 - z0)
    e = ymin if edge == _BOTTOM else ymax
    t = (e - y0) / (y1 - y0)
    return line_coordinate(e, y0, x0, y1, x1), e, z0 + t * (z1 - z0)


@scalar
def sutherland_hodgman(xy, z, has_z, first, last, reverse, xmin, ymin, xmax, ymax):
    """Return ``(ring (m, 3), m)``: the ring ``xy[first..last]`` clipped by Sutherland–Hodgman.

    The fallback for invalid polygons, clipped ring by ring (Sutherland & Hodgman 1974:
    one pass per window edge, keeping inside vertices and adding the crossings). The
    result is closed, may run along the window's edge and is not repaired. Each pass at
    most doubles the vertex count, hence the buffers.
    """
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
            cur_in = _inside_edge(a[k, 0], a[k, 1], edge, xmin, ymin, xmax, ymax)
            prev_in = _inside_edge(a[j, 0], a[j, 1], edge, xmin, ymin, xmax, ymax)
            if cur_in != prev_in:
                b[m, 0], b[m, 1], b[m, 2] = _cross_edge(a[j, 0], a[j, 1], a[j, 2], a[k, 0],
                                                        a[k, 1], a[k, 2], edge, xmin, ymin,
                                                        xmax, ymax)
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


@scalar
def _clip_rings_alone(xy, z, has_z, ring_offsets, r_begin, r_end, ring_rev, xmin, ymin, xmax,
                      ymax, write, out_xy, out_z, out_ring_starts, out_poly_rings, v, n_rings,
                      n_polys):
    """Write an invalid polygon clipped ring by ring: one polygon, its shell then its holes.

    Without `write` only the counts advance. A shell clipped to nothing drops the polygon.
    """
    rings_before = n_rings
    for r in range(r_begin, r_end):
        first = ring_offsets[r]
        last = ring_offsets[r + 1] - 1
        if last - first < 3:
            continue
        ring, m = sutherland_hodgman(xy, z, has_z, first, last, ring_rev[r - r_begin],
                                     xmin, ymin, xmax, ymax)
        if m == 0:
            if r == r_begin:
                return v, n_rings, n_polys
            continue
        if write:
            out_ring_starts[n_rings] = v
            for k in range(m):
                out_xy[v + k, 0] = ring[k, 0]
                out_xy[v + k, 1] = ring[k, 1]
                if has_z:
                    out_z[v + k] = ring[k, 2]
        v += m
        n_rings += 1
    if n_rings > rings_before:
        if write:
            out_poly_rings[n_polys] = n_rings - rings_before
        n_polys += 1
    return v, n_rings, n_polys


@scalar
def clip_polygon(xy, z, has_z, ring_offsets, r_begin, r_end, xmin, ymin, xmax, ymax, method,
                 n_fixed, max_depth, tol, auto_piece, exact, out_xy, out_z, out_ring_starts,
                 out_poly_rings, v, n_rings, n_polys, st, run_stack, stack_f, stack_i,
                 ch_xy, ch_z, ch_starts, lc, ev_key, ev_chain, order, ring_state, ring_rev,
                 ring_first, ring_last, tmp_xy, tmp_z, stk, rg_xy, rg_z, rg_start, rg_sign,
                 rg_done, write, decided, chunk_start, decision, piece_start, keep, pieces):
    """Clip the polygon of rings ``r_begin..r_end-1`` (shell first); write valid pieces.

    Output polygons are written from ``out_xy[v]``, their rings' starts from
    ``out_ring_starts[n_rings]`` and their ring counts from ``out_poly_rings[n_polys]``;
    shells counter-clockwise, holes clockwise. The remaining arguments are the caller's
    scratch, sized by the bounds of `bound_chains`. Returns ``(v, n_rings, n_polys, ok)``;
    ``ok`` is False when the input is found invalid: a cut ring without area, or chains
    whose entries and exits do not alternate along the boundary (the rings cross); the
    polygon is then clipped ring by ring (`sutherland_hodgman`), not repaired. `write`
    is False in the counting pass (the fallback then only counts; the rest writes to
    the caller's scratch). With `decided` the rings' runs were pruned and their segments
    clipped elsewhere (the OpenCL backend): ring r's chains are assembled from
    ``decision[chunk_start[r]:]``, ``piece_start``, ``keep`` and ``pieces``
    (`polylines.assemble_chains`) instead of cut by `polylines.clip_chains`.
    """
    n_r = r_end - r_begin
    if n_r == 0:
        return v, n_rings, n_polys, True
    no_codes = np.empty(0, dtype=np.uint8)  # rings are short: runs coded from vertices
    no_plan = np.empty((0, 2), dtype=np.int64)  # and their chains written as decided
    v_ch = 0
    c_ch = 0
    n_lc = 0
    ok = True
    # 1. Cut every ring into chains, oriented so the polygon's interior is on the left.
    for r in range(r_begin, r_end):
        first = ring_offsets[r]
        last = ring_offsets[r + 1] - 1
        j = r - r_begin
        ring_first[j] = first
        ring_last[j] = last
        area = signed_area(xy, first, last) if last > first else 0.0
        ring_rev[j] = (area < 0.0) if j == 0 else (area > 0.0)
        c0 = c_ch
        if decided:
            v_ch, c_ch, at_first, at_last = assemble_chains(
                xy, z, has_z, True, first, last, True, True, xmin, ymin, xmax, ymax, decision,
                chunk_start[r], piece_start, keep, pieces, ch_xy, ch_z, ch_starts, v_ch, c_ch)
        else:
            v_ch, c_ch, at_first, at_last, _ = clip_chains(
                xy, z, has_z, True, first, last, xmin, ymin, xmax, ymax, method, n_fixed,
                max_depth, tol, auto_piece, exact, True, True, ch_xy, ch_z, ch_starts, v_ch,
                c_ch, st, run_stack, stack_f, stack_i, no_codes, no_codes, 0, no_plan, 0)
        ch_starts[c_ch] = v_ch
        n_chains = c_ch - c0
        if last > first and area == 0.0:
            ok = False  # a ring without area: self-intersecting (or degenerate) input
        if n_chains == 0:
            ring_state[j] = _UNTOUCHED
            continue
        if n_chains == 1 and at_first and at_last:
            ring_state[j] = _FULL
            continue
        ring_state[j] = _CUT
        if area == 0.0:
            ok = False
        # Logical chains; the last and first chains join across the closing vertex.
        joined = at_first and at_last and n_chains >= 2
        for k in range(c0 + 1 if joined else c0, c_ch):
            lc[n_lc, 0] = ch_starts[k]
            lc[n_lc, 1] = ch_starts[k + 1]
            lc[n_lc, 2] = 0
            lc[n_lc, 3] = 0
            if joined and k == c_ch - 1:
                # The first chain's first vertex repeats the joint: skip it.
                lc[n_lc, 2] = ch_starts[c0] + 1
                lc[n_lc, 3] = ch_starts[c0 + 1]
            lc[n_lc, 4] = 1 if ring_rev[j] else 0
            lc[n_lc, 6] = j
            n_lc += 1
    # Z of the window's corners that lie on an input segment (the walk passes corners;
    # one on an input edge takes that edge's Z rather than one interpolated along the
    # boundary).
    corner_z = np.zeros(4)
    corner_z_known = np.zeros(4, dtype=np.bool_)
    if has_z:
        for r in range(r_begin, r_end):
            for i in range(ring_offsets[r], ring_offsets[r + 1] - 1):
                for e in range(4):
                    if corner_z_known[e]:
                        continue
                    cx, cy = _corner_after(e, xmin, ymin, xmax, ymax)
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
                    corner_z[e] = z[i] + t * (z[i + 1] - z[i])
                    corner_z_known[e] = True
    n_rg = 0
    rg_start[0] = 0
    # 2. The walk over boundary events (chain starts and ends), sorted counter-clockwise.
    n_ev = 2 * n_lc
    for k in range(n_lc):
        for end in range(2):
            i = _chain_vertex(lc, k, 0 if end == 0 else _chain_length(lc, k) - 1)
            e, s = boundary_key(ch_xy[i, 0], ch_xy[i, 1], xmin, ymin, xmax, ymax)
            ev = 2 * k + end
            ev_key[ev, 0] = e
            ev_key[ev, 1] = s
            ev_key[ev, 2] = _event_angle(ch_xy, lc, k, end == 0, e, xmin, ymin, xmax, ymax)
            order[ev] = ev
    for a in range(1, n_ev):  # insertion sort: few events per polygon
        item = order[a]
        b = a - 1
        while b >= 0 and _key_less(ev_key[item, 0], ev_key[item, 1], ev_key[item, 2],
                                   ev_key[order[b], 0], ev_key[order[b], 1],
                                   ev_key[order[b], 2]):
            order[b + 1] = order[b]
            b -= 1
        order[b + 1] = item
    for a in range(n_ev):
        ev_chain[order[a]] = a  # position of each event in the sorted order
    # Along the boundary, exits and entries alternate: two exits (or entries) in a row
    # mean rings that cross, or a hole outside its shell. Events at one point (a ring
    # touching the edge there) count as one, by their balance, which must be -1, 0 or 1.
    # (Every chain has one exit and one entry, so alternating balances also close up
    # cyclically.)
    previous = 0
    a = 0
    while a < n_ev:
        b = a
        net = 0
        while b < n_ev and ev_key[order[b], 0] == ev_key[order[a], 0] \
                and ev_key[order[b], 1] == ev_key[order[a], 1]:
            net += 1 if order[b] % 2 == 1 else -1
            b += 1
        if net > 1 or net < -1 or (net != 0 and net == previous):
            ok = False
        if net != 0:
            previous = net
        a = b
    if not ok:
        v, n_rings, n_polys = _clip_rings_alone(
            xy, z, has_z, ring_offsets, r_begin, r_end, ring_rev, xmin, ymin, xmax, ymax,
            write, out_xy, out_z, out_ring_starts, out_poly_rings, v, n_rings, n_polys)
        return v, n_rings, n_polys, False
    visited = lc[:, 5]
    for k in range(n_lc):
        visited[k] = 0
    for k0 in range(n_lc):
        if visited[k0]:
            continue
        m = 0
        k = k0
        # Only a walk joining chains of two or more rings (a cut hole and its shell) can
        # pass a vertex of one inside an edge of the other (a hole touching its shell
        # mid-edge), so only such a walk is noded (`_split_loops`): the chains of one
        # valid ring never touch each other. Noding every walk of a polygon with holes
        # took about a fifth of the polygon benchmark's time.
        several_rings = False
        while True:
            visited[k] = 1
            several_rings = several_rings or lc[k, 6] != lc[k0, 6]
            m = _put_chain(ch_xy, ch_z, has_z, lc, k, tmp_xy, tmp_z, m, 0)
            # Where the ring goes from chain k's end: the chain entering at the same point
            # just clockwise of it (the polygon is pinched there), else the first entry
            # counter-clockwise along the boundary, the most clockwise one at its point.
            i = ev_chain[2 * k + 1]
            ee = ev_key[order[i], 0]
            es = ev_key[order[i], 1]
            nxt = -1
            direct = False
            if i > 0 and ev_key[order[i - 1], 0] == ee and ev_key[order[i - 1], 1] == es \
                    and order[i - 1] % 2 == 0:
                nxt = order[i - 1] // 2
                direct = True
            else:
                g = i + 1
                while g < n_ev and ev_key[order[g], 0] == ee and ev_key[order[g], 1] == es:
                    g += 1
                for _ in range(n_ev):
                    if g >= n_ev:
                        g = 0
                    g_end = g + 1
                    while g_end < n_ev and ev_key[order[g_end], 0] == ev_key[order[g], 0] \
                            and ev_key[order[g_end], 1] == ev_key[order[g], 1]:
                        g_end += 1
                    q = g_end - 1
                    while q >= g and order[q] % 2 == 1:
                        q -= 1
                    if q >= g:
                        nxt = order[q] // 2
                        break
                    g = g_end
            if nxt < 0:
                ok = False
                break
            if not direct:
                se = ev_key[2 * nxt, 0]
                ss = ev_key[2 * nxt, 1]
                if not (se == ee and ss > es):
                    z_from = 0.0
                    z_to = 0.0
                    p_from = 0.0
                    span = 1.0
                    perimeter = 2.0 * ((xmax - xmin) + (ymax - ymin))
                    if has_z:
                        z_from = ch_z[_chain_vertex(lc, k, _chain_length(lc, k) - 1)]
                        z_to = ch_z[_chain_vertex(lc, nxt, 0)]
                        p_from = _perimeter_position(ee, es, xmin, ymin, xmax, ymax)
                        span = _perimeter_position(se, ss, xmin, ymin, xmax, ymax) - p_from
                        if span <= 0.0:
                            span += perimeter
                    e = int(ee)
                    while True:
                        x, y = _corner_after(e, xmin, ymin, xmax, ymax)
                        zc = 0.0
                        if has_z:
                            d = _corner_position(e, xmin, ymin, xmax, ymax) - p_from
                            if d < 0.0:
                                d += perimeter
                            zc = z_from + (z_to - z_from) * min(1.0, d / span)
                            if corner_z_known[e]:
                                zc = corner_z[e]
                        m = _put(tmp_xy, tmp_z, has_z, m, 0, x, y, zc)
                        e = (e + 1) % 4
                        if e == se:
                            break
            if nxt == k0:
                break
            if visited[nxt]:
                ok = False  # inconsistent chains (invalid input): close what we have
                break
            k = nxt
        if m > 0 and not (tmp_xy[m - 1, 0] == tmp_xy[0, 0] and tmp_xy[m - 1, 1] == tmp_xy[0, 1]):
            tmp_xy[m, 0] = tmp_xy[0, 0]
            tmp_xy[m, 1] = tmp_xy[0, 1]
            if has_z:
                tmp_z[m] = tmp_z[0]
            m += 1
        if m >= 4:
            n_rg = _split_loops(tmp_xy, tmp_z, has_z, m, several_rings, stk, rg_xy, rg_z,
                                rg_start, rg_sign, n_rg)
    # 3. Rings never cut: inside the window whole. The shell of a cut polygon is never
    # one of them unless the input is invalid.
    for j in range(n_r):
        if ring_state[j] != _FULL:
            continue
        if j == 0 and n_lc > 0:
            ok = False
        first = ring_first[j]
        count = _put_ring(xy, z, has_z, first, ring_last[j], ring_rev[j], tmp_xy, tmp_z, 0)
        for i in range(count):
            stk[i] = i
        n_rg = _add_ring(rg_xy, rg_z, has_z, rg_start, rg_sign, n_rg, tmp_xy, tmp_z, stk,
                         count, False)
    # 4. No chain and no uncut shell: the window lies inside the polygon or outside it.
    if n_lc == 0 and ring_state[0] == _UNTOUCHED:
        cx = 0.5 * xmin + 0.5 * xmax
        cy = 0.5 * ymin + 0.5 * ymax
        covered = point_in_ring(cx, cy, xy, ring_first[0], ring_last[0]) > 0
        for j in range(1, n_r):
            if covered and ring_state[j] == _UNTOUCHED and point_in_ring(
                    cx, cy, xy, ring_first[j], ring_last[j]) > 0:
                covered = False
        if covered:
            zc = 0.0
            if has_z:
                for k in range(ring_first[0], ring_last[0]):
                    zc += z[k]
                zc /= max(1, ring_last[0] - ring_first[0])
            for corner in range(4):
                x, y = _corner_after((corner + 3) % 4, xmin, ymin, xmax, ymax)
                tmp_xy[corner, 0] = x
                tmp_xy[corner, 1] = y
                if has_z:
                    tmp_z[corner] = corner_z[(corner + 3) % 4] if corner_z_known[
                        (corner + 3) % 4] else zc
                stk[corner] = corner
            n_rg = _add_ring(rg_xy, rg_z, has_z, rg_start, rg_sign, n_rg, tmp_xy, tmp_z, stk,
                             4, True)
    # 5. Output: each shell, then the holes inside it.
    for a in range(n_rg):
        rg_done[a] = False
    for a in range(n_rg):
        if rg_sign[a] < 0:
            continue
        out_ring_starts[n_rings] = v
        n_rings += 1
        rings_before = n_rings - 1
        v = _put_ring(rg_xy, rg_z, has_z, rg_start[a], rg_start[a + 1] - 1, False, out_xy,
                      out_z, v)
        shell_start = out_ring_starts[n_rings - 1]
        shell_last = v - 1
        for b in range(n_rg):
            if rg_sign[b] > 0 or rg_done[b]:
                continue
            where = 0
            for i in range(rg_start[b], rg_start[b + 1] - 1):
                where = point_in_ring(rg_xy[i, 0], rg_xy[i, 1], out_xy, shell_start,
                                      shell_last)
                if where != 0:
                    break
            if where < 0:
                continue
            rg_done[b] = True
            out_ring_starts[n_rings] = v
            n_rings += 1
            v = _put_ring(rg_xy, rg_z, has_z, rg_start[b], rg_start[b + 1] - 1, False,
                          out_xy, out_z, v)
        out_poly_rings[n_polys] = n_rings - rings_before
        n_polys += 1
    for b in range(n_rg):
        if rg_sign[b] < 0 and not rg_done[b]:
            ok = False  # a hole outside every piece: invalid input
    return v, n_rings, n_polys, ok


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
def polygon_class_of(xy, ring_offsets, r_begin, r_end, xmin, ymin, xmax, ymax):
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
    lo, hi, strict = run_box_codes(xy, first, last, xmin, ymin, xmax, ymax)
    return _OUTSIDE if lo & hi else (_INSIDE if strict else _AMBIGUOUS)


@parallel
def classify_polygons(xy, ring_offsets, polygon_offsets, polygon_window, windows,
                      polygon_class):
    """Store `polygon_class_of` of every polygon (as `clip_polygon_blocks` decides it)."""
    for p in prange(polygon_offsets.shape[0] - 1):
        w = polygon_window[p]
        polygon_class[p] = polygon_class_of(xy, ring_offsets, polygon_offsets[p],
                                            polygon_offsets[p + 1], windows[w, 0],
                                            windows[w, 1], windows[w, 2], windows[w, 3])


@parallel
def clip_polygon_blocks(xy, z, has_z, ring_offsets, polygon_offsets, polygon_window, windows,
                        method, n_fixed, max_depth, tol, auto_piece, exact, block_size, write,
                        polygon_class, scratch_vertices, scratch_chains, vertex_start,
                        ring_start, poly_start, out_xy, out_z, out_ring_starts, out_poly_rings,
                        n_vertices, n_rings, n_polys, counters, decided, chunk_start, decision,
                        piece_start, keep, pieces):
    """Count (``write=False``) or write (``write=True``) every polygon of a ragged array.

    Polygon ``p`` has rings ``polygon_offsets[p]..polygon_offsets[p+1]-1`` (the shell
    first) of ``ring_offsets``, clipped against ``windows[polygon_window[p]]``.

    The shell's bounding box classifies each polygon (the run test of `clip_chains` on
    the whole shell): beyond an edge, nothing is left; strictly inside the window, every
    ring is copied as it is (holes lie inside their shell); only the others are cut.
    The count pass records the class and the exact output counts (`n_vertices`,
    `n_rings`, `n_polys`), cutting the ambiguous polygons into scratch space; the write
    pass writes polygon p at ``vertex_start[p]``, ``ring_start[p]`` and
    ``poly_start[p]`` (exclusive sums of the counts), cutting the ambiguous ones again.
    Ambiguous polygons are few where it matters, so cutting them twice costs less than
    over-allocating every output and compacting it. Stats are counted in the write pass.
    With `decided`, the runs of the ambiguous polygons' rings were pruned and their
    segments clipped elsewhere (see `clip_polygon`; those counters are the caller's).
    """
    n_polygons = polygon_offsets.shape[0] - 1
    n_blocks = counters.shape[0]
    for blk in prange(n_blocks):
        st = counters[blk]
        if not write:
            st = np.zeros(C.WIDTH, dtype=np.int64)  # counted once, in the write pass
        lo_p = blk * block_size
        hi_p = min(n_polygons, (blk + 1) * block_size)
        max_v = 1
        max_c = 1
        max_r = 1
        max_out = 1
        for p in range(lo_p, hi_p):
            r_begin = polygon_offsets[p]
            r_end = polygon_offsets[p + 1]
            n_r = r_end - r_begin
            if not write:
                w = polygon_window[p]
                cls = polygon_class_of(xy, ring_offsets, r_begin, r_end, windows[w, 0],
                                       windows[w, 1], windows[w, 2], windows[w, 3])
                polygon_class[p] = cls
                n_vertices[p] = 0
                n_rings[p] = 0
                n_polys[p] = 0
                if cls == _INSIDE:
                    n_vertices[p] = ring_offsets[r_end] - ring_offsets[r_begin]
                    n_rings[p] = n_r
                    n_polys[p] = 1
                elif cls == _AMBIGUOUS:
                    sv = n_r
                    sc = 0
                    for r in range(r_begin, r_end):
                        first = ring_offsets[r]
                        last = ring_offsets[r + 1] - 1
                        if last > first:
                            nv, nc, _ = bound_chains(xy, first, last, windows[w, 0],
                                                     windows[w, 1], windows[w, 2],
                                                     windows[w, 3])
                            sv += nv
                            sc += nc
                        else:
                            sc += 1
                    scratch_vertices[p] = sv
                    scratch_chains[p] = sc
            if polygon_class[p] == _AMBIGUOUS:
                max_v = max(max_v, scratch_vertices[p])
                max_c = max(max_c, scratch_chains[p])
                max_r = max(max_r, n_r)
                max_out = max(max_out, _output_bound(scratch_vertices[p], scratch_chains[p],
                                                     n_r))
        if max_out == 1 and not write:
            continue  # no ambiguous polygon in this block
        run_stack = np.empty((RUN_STACK_CAPACITY, 3), dtype=np.int64)
        stack_f = np.empty((STACK_CAPACITY, 6), dtype=np.float64)
        stack_i = np.empty((STACK_CAPACITY, 3), dtype=np.int64)
        ch_xy = np.empty((max_v, 2), dtype=np.float64)
        ch_z = np.empty(max_v if has_z else 0, dtype=np.float64)
        ch_starts = np.empty(max_c + 1, dtype=np.int64)
        lc = np.empty((max_c, 7), dtype=np.int64)
        ev_key = np.empty((2 * max_c, 3), dtype=np.float64)
        ev_chain = np.empty(2 * max_c, dtype=np.int64)
        order = np.empty(2 * max_c, dtype=np.int64)
        ring_state = np.empty(max_r, dtype=np.int64)
        ring_rev = np.empty(max_r, dtype=np.bool_)
        ring_first = np.empty(max_r, dtype=np.int64)
        ring_last = np.empty(max_r, dtype=np.int64)
        tmp_xy = np.empty((max_out, 2), dtype=np.float64)
        tmp_z = np.empty(max_out if has_z else 0, dtype=np.float64)
        stk = np.empty(max_out, dtype=np.int64)
        rg_xy = np.empty((max_out, 2), dtype=np.float64)
        rg_z = np.empty(max_out if has_z else 0, dtype=np.float64)
        rg_start = np.empty(max_out // 4 + 2, dtype=np.int64)
        rg_sign = np.empty(max_out // 4 + 2, dtype=np.int64)
        rg_done = np.empty(max_out // 4 + 2, dtype=np.bool_)
        if write:
            dst_xy = out_xy
            dst_z = out_z
            dst_rings = out_ring_starts
            dst_polys = out_poly_rings
        else:
            dst_xy = np.empty((max_out, 2), dtype=np.float64)
            dst_z = np.empty(max_out if has_z else 0, dtype=np.float64)
            dst_rings = np.empty(max_out // 4 + 2, dtype=np.int64)
            dst_polys = np.empty(max_out // 4 + 2, dtype=np.int64)
        for p in range(lo_p, hi_p):
            cls = polygon_class[p]
            r_begin = polygon_offsets[p]
            r_end = polygon_offsets[p + 1]
            n_segments = ring_offsets[r_end] - ring_offsets[r_begin] - (r_end - r_begin)
            if cls != _AMBIGUOUS:
                if not write:
                    continue
                st[C.RUNS_EVALUATED] += 1
                st[C.RUN_LEVELS] += 1
                st[C.SEGMENT_LEVELS] += n_segments
                if cls == _OUTSIDE:
                    st[C.RUNS_REJECTED] += 1
                    continue
                st[C.RUNS_ACCEPTED] += 1
                v = vertex_start[p]
                invalid = False
                for r in range(r_begin, r_end):
                    first = ring_offsets[r]
                    last = ring_offsets[r + 1] - 1
                    area = signed_area(xy, first, last) if last > first else 0.0
                    if area == 0.0:
                        invalid = True
                    out_ring_starts[ring_start[p] + r - r_begin] = v
                    v = _put_ring(xy, z, has_z, first, last,
                                  (area < 0.0) if r == r_begin else (area > 0.0),
                                  out_xy, out_z, v)
                out_poly_rings[poly_start[p]] = r_end - r_begin
                if invalid:
                    st[C.INVALID_POLYGONS] += 1  # a ring without area (a symmetric bow tie)
                continue
            w = polygon_window[p]
            v0 = vertex_start[p] if write else 0
            r0 = ring_start[p] if write else 0
            q0 = poly_start[p] if write else 0
            v, nr, npoly, ok = clip_polygon(
                xy, z, has_z, ring_offsets, r_begin, r_end, windows[w, 0], windows[w, 1],
                windows[w, 2], windows[w, 3], method, n_fixed, max_depth, tol, auto_piece,
                exact, dst_xy, dst_z, dst_rings, dst_polys, v0, r0, q0, st, run_stack,
                stack_f, stack_i, ch_xy, ch_z, ch_starts, lc, ev_key, ev_chain, order,
                ring_state, ring_rev, ring_first, ring_last, tmp_xy, tmp_z, stk, rg_xy, rg_z,
                rg_start, rg_sign, rg_done, write, decided, chunk_start, decision, piece_start,
                keep, pieces)
            if not ok:
                st[C.INVALID_POLYGONS] += 1
            if not write:
                n_vertices[p] = v - v0
                n_rings[p] = nr - r0
                n_polys[p] = npoly - q0
