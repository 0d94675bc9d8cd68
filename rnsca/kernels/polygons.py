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
from rnsca.kernels.jit import parallel, scalar
from rnsca.kernels.polylines import (
    RUN_STACK_CAPACITY,
    bound_chains,
    clip_chains,
)
from rnsca.kernels.segments import STACK_CAPACITY

__all__ = [
    "boundary_key",
    "clip_polygon_blocks",
    "compact_polygons",
    "point_in_ring",
    "signed_area",
]

# Edges in counter-clockwise order, starting at (xmin, ymin).
_BOTTOM, _RIGHT, _TOP, _LEFT = 0, 1, 2, 3
# Ring states after cutting.
_UNTOUCHED, _FULL, _CUT = 0, 1, 2


@scalar
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


@scalar
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
def _key_less(e1, s1, e2, s2):
    return e1 < e2 or (e1 == e2 and s1 < s2)


@scalar
def _put(out_xy, out_z, has_z, v, ring_start, x, y, z):
    """Append a ring vertex unless it repeats the previous one; return the next position."""
    if v > ring_start and out_xy[v - 1, 0] == x and out_xy[v - 1, 1] == y:
        return v
    out_xy[v, 0] = x
    out_xy[v, 1] = y
    if has_z:
        out_z[v] = z
    return v + 1


@scalar
def _put_range(src_xy, src_z, has_z, a, b, reverse, out_xy, out_z, v, ring_start):
    """Append vertices src[a:b] (backwards if `reverse`); return the next position."""
    for k in range(b - a):
        i = b - 1 - k if reverse else a + k
        v = _put(out_xy, out_z, has_z, v, ring_start, src_xy[i, 0], src_xy[i, 1], src_z[i]
                 if has_z else 0.0)
    return v


@scalar
def _put_chain(ch_xy, ch_z, has_z, lc, k, out_xy, out_z, v, ring_start):
    """Append logical chain k: range 1 then range 2 (forwards), or both reversed."""
    a1 = lc[k, 0]
    b1 = lc[k, 1]
    a2 = lc[k, 2]
    b2 = lc[k, 3]
    if lc[k, 4] == 0:
        v = _put_range(ch_xy, ch_z, has_z, a1, b1, False, out_xy, out_z, v, ring_start)
        v = _put_range(ch_xy, ch_z, has_z, a2, b2, False, out_xy, out_z, v, ring_start)
    else:
        v = _put_range(ch_xy, ch_z, has_z, a2, b2, True, out_xy, out_z, v, ring_start)
        v = _put_range(ch_xy, ch_z, has_z, a1, b1, True, out_xy, out_z, v, ring_start)
    return v


@scalar
def _chain_end_index(lc, k, at_start):
    """Return the scratch index of the first (`at_start`) or last vertex of logical chain k."""
    head = lc[k, 0]
    tail = lc[k, 3] - 1 if lc[k, 3] > lc[k, 2] else lc[k, 1] - 1
    if lc[k, 4] == 0:
        return head if at_start else tail
    return tail if at_start else head


@scalar
def _close_ring(out_xy, out_z, has_z, v, ring_start):
    """Close the ring (repeat its first vertex); return (v, twice its signed area)."""
    if v - ring_start >= 1 and not (out_xy[v - 1, 0] == out_xy[ring_start, 0]
                                    and out_xy[v - 1, 1] == out_xy[ring_start, 1]):
        out_xy[v, 0] = out_xy[ring_start, 0]
        out_xy[v, 1] = out_xy[ring_start, 1]
        if has_z:
            out_z[v] = out_z[ring_start]
        v += 1
    if v - ring_start < 4:
        return v, 0.0
    return v, signed_area(out_xy, ring_start, v - 1)


@scalar
def _put_holes(xy, z, has_z, ring_state, ring_rev, ring_first, ring_last, r_begin, r_end,
               hole_done, out_xy, out_z, out_ring_starts, v, n_rings, shell_start, shell_end,
               only_shell):
    """Append the uncut holes that lie in the shell out_xy[shell_start..shell_end]."""
    for r in range(r_begin + 1, r_end):
        if ring_state[r - r_begin] != _FULL or hole_done[r - r_begin]:
            continue
        first = ring_first[r - r_begin]
        last = ring_last[r - r_begin]
        inside = only_shell
        if not inside:
            where = 0
            for k in range(first, last):
                where = point_in_ring(xy[k, 0], xy[k, 1], out_xy, shell_start, shell_end)
                if where != 0:
                    break
            inside = where >= 0
        if not inside:
            continue
        hole_done[r - r_begin] = True
        out_ring_starts[n_rings] = v
        n_rings += 1
        reverse = ring_rev[r - r_begin]
        for k in range(last - first + 1):
            i = last - k if reverse else first + k
            out_xy[v, 0] = xy[i, 0]
            out_xy[v, 1] = xy[i, 1]
            if has_z:
                out_z[v] = z[i]
            v += 1
    return v, n_rings


@scalar
def clip_polygon(xy, z, has_z, ring_offsets, r_begin, r_end, xmin, ymin, xmax, ymax, method,
                 n_fixed, max_depth, tol, auto_piece, exact, out_xy, out_z, out_ring_starts,
                 out_poly_rings, v, n_rings, n_polys, st, run_stack, stack_f, stack_i,
                 ch_xy, ch_z, ch_starts, lc, keys, order, ring_state, ring_rev, ring_first,
                 ring_last, hole_done):
    """Clip the polygon of rings ``r_begin..r_end-1`` (shell first); write valid pieces.

    Output polygons are written from ``out_xy[v]``, their rings' starts from
    ``out_ring_starts[n_rings]`` and their ring counts from ``out_poly_rings[n_polys]``;
    shells counter-clockwise, holes clockwise. The remaining arguments are the caller's
    scratch, sized by the bounds of `bound_chains`. Returns ``(v, n_rings, n_polys, ok)``;
    ``ok`` is False when the chains could not be closed consistently (invalid input).
    """
    n_r = r_end - r_begin
    if n_r == 0:
        return v, n_rings, n_polys, True
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
        hole_done[j] = False
        area = signed_area(xy, first, last) if last > first else 0.0
        want_ccw = r == r_begin
        ring_rev[j] = (area < 0.0) if want_ccw else (area > 0.0)
        c0 = c_ch
        v_ch, c_ch, at_first, at_last = clip_chains(
            xy, z, has_z, first, last, xmin, ymin, xmax, ymax, method, n_fixed, max_depth, tol,
            auto_piece, exact, True, ch_xy, ch_z, ch_starts, v_ch, c_ch, st, run_stack,
            stack_f, stack_i)
        ch_starts[c_ch] = v_ch
        n_chains = c_ch - c0
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
            n_lc += 1
    # 2. No chain: the window is inside the polygon or outside it.
    if n_lc == 0:
        shell_full = ring_state[0] == _FULL
        ring_start = v
        if shell_full:
            reverse = ring_rev[0]
            first = ring_first[0]
            last = ring_last[0]
            for k in range(last - first + 1):
                i = last - k if reverse else first + k
                out_xy[v, 0] = xy[i, 0]
                out_xy[v, 1] = xy[i, 1]
                if has_z:
                    out_z[v] = z[i]
                v += 1
        else:
            cx = 0.5 * xmin + 0.5 * xmax
            cy = 0.5 * ymin + 0.5 * ymax
            if ring_state[0] != _UNTOUCHED or n_r == 0 or point_in_ring(
                    cx, cy, xy, ring_first[0], ring_last[0]) <= 0:
                return v, n_rings, n_polys, ok
            for j in range(1, n_r):
                if ring_state[j] == _UNTOUCHED and point_in_ring(
                        cx, cy, xy, ring_first[j], ring_last[j]) > 0:
                    return v, n_rings, n_polys, ok
            zc = 0.0
            if has_z:
                for k in range(ring_first[0], ring_last[0]):
                    zc += z[k]
                zc /= max(1, ring_last[0] - ring_first[0])
            for corner in range(5):
                x, y = _corner_after((corner + 3) % 4, xmin, ymin, xmax, ymax)
                out_xy[v, 0] = x
                out_xy[v, 1] = y
                if has_z:
                    out_z[v] = zc
                v += 1
        out_ring_starts[n_rings] = ring_start
        rings_before = n_rings
        n_rings += 1
        v, n_rings = _put_holes(xy, z, has_z, ring_state, ring_rev, ring_first, ring_last,
                                r_begin, r_end, hole_done, out_xy, out_z, out_ring_starts, v,
                                n_rings, ring_start, v - 1, True)
        out_poly_rings[n_polys] = n_rings - rings_before
        n_polys += 1
        return v, n_rings, n_polys, ok
    # 3. The walk. keys: (start edge, start s, end edge, end s) per logical chain.
    for k in range(n_lc):
        i = _chain_end_index(lc, k, True)
        e, s = boundary_key(ch_xy[i, 0], ch_xy[i, 1], xmin, ymin, xmax, ymax)
        keys[k, 0] = e
        keys[k, 1] = s
        i = _chain_end_index(lc, k, False)
        e, s = boundary_key(ch_xy[i, 0], ch_xy[i, 1], xmin, ymin, xmax, ymax)
        keys[k, 2] = e
        keys[k, 3] = s
        order[k] = k
    # Insertion sort of the chains by start position (few chains per polygon).
    for a in range(1, n_lc):
        item = order[a]
        b = a - 1
        while b >= 0 and _key_less(keys[item, 0], keys[item, 1],
                                   keys[order[b], 0], keys[order[b], 1]):
            order[b + 1] = order[b]
            b -= 1
        order[b + 1] = item
    visited = lc[:, 5]
    for k in range(n_lc):
        visited[k] = 0
    for k0 in range(n_lc):
        if visited[k0]:
            continue
        ring_start = v
        k = k0
        while True:
            visited[k] = 1
            v = _put_chain(ch_xy, ch_z, has_z, lc, k, out_xy, out_z, v, ring_start)
            # The next entry counter-clockwise from this exit (binary search, cyclic).
            ee = keys[k, 2]
            es = keys[k, 3]
            lo = 0
            hi = n_lc
            while lo < hi:
                mid = (lo + hi) // 2
                if _key_less(keys[order[mid], 0], keys[order[mid], 1], ee, es):
                    lo = mid + 1
                else:
                    hi = mid
            nxt = order[lo % n_lc]
            # Corners passed on the way from (ee, es) to the next entry.
            se = keys[nxt, 0]
            ss = keys[nxt, 1]
            if not (se == ee and ss >= es):
                z_from = 0.0
                z_to = 0.0
                p_from = 0.0
                span = 1.0
                if has_z:
                    z_from = ch_z[_chain_end_index(lc, k, False)]
                    z_to = ch_z[_chain_end_index(lc, nxt, True)]
                    p_from = _perimeter_position(ee, es, xmin, ymin, xmax, ymax)
                    perimeter = 2.0 * ((xmax - xmin) + (ymax - ymin))
                    span = _perimeter_position(se, ss, xmin, ymin, xmax, ymax) - p_from
                    if span <= 0.0:
                        span += perimeter
                e = ee
                while True:
                    x, y = _corner_after(e, xmin, ymin, xmax, ymax)
                    zc = 0.0
                    if has_z:
                        d = _corner_position(e, xmin, ymin, xmax, ymax) - p_from
                        if d < 0.0:
                            d += 2.0 * ((xmax - xmin) + (ymax - ymin))
                        zc = z_from + (z_to - z_from) * min(1.0, d / span)
                    v = _put(out_xy, out_z, has_z, v, ring_start, x, y, zc)
                    e = (e + 1) % 4
                    if e == se:
                        break
            if nxt == k0:
                break
            if visited[nxt]:
                ok = False  # inconsistent chains (invalid input): close what we have
                break
            k = nxt
        v, area = _close_ring(out_xy, out_z, has_z, v, ring_start)
        if not area > 0.0:
            if area < 0.0:
                ok = False
            v = ring_start  # a degenerate piece: no area inside the window
            continue
        out_ring_starts[n_rings] = ring_start
        rings_before = n_rings
        n_rings += 1
        v, n_rings = _put_holes(xy, z, has_z, ring_state, ring_rev, ring_first, ring_last,
                                r_begin, r_end, hole_done, out_xy, out_z, out_ring_starts, v,
                                n_rings, ring_start, v - 1, False)
        out_poly_rings[n_polys] = n_rings - rings_before
        n_polys += 1
    # An uncut ring left over means invalid input (a valid polygon's uncut holes all lie
    # in some piece, and its shell is cut whenever any ring is): clipped ring by ring,
    # an uncut shell is its own polygon; a stray hole has nothing to be a hole of.
    for j in range(n_r):
        if ring_state[j] != _FULL or hole_done[j]:
            continue
        ok = False
        if j > 0:
            continue
        ring_start = v
        first = ring_first[0]
        last = ring_last[0]
        for k in range(last - first + 1):
            i = last - k if ring_rev[0] else first + k
            out_xy[v, 0] = xy[i, 0]
            out_xy[v, 1] = xy[i, 1]
            if has_z:
                out_z[v] = z[i]
            v += 1
        out_ring_starts[n_rings] = ring_start
        n_rings += 1
        out_poly_rings[n_polys] = 1
        n_polys += 1
    return v, n_rings, n_polys, ok


@parallel
def clip_polygon_blocks(xy, z, has_z, ring_offsets, polygon_offsets, polygon_window, windows,
                        method, n_fixed, max_depth, tol, auto_piece, exact, block_size, write,
                        vertex_slot, ring_slot, out_xy, out_z, out_ring_starts, out_poly_rings,
                        n_vertices, n_rings, n_polys, scratch_vertices, scratch_chains,
                        counters):
    """Bound (``write=False``) or clip (``write=True``) every polygon of a ragged array.

    Polygon ``p`` has rings ``polygon_offsets[p]..polygon_offsets[p+1]-1`` (the shell
    first) of ``ring_offsets``, clipped against ``windows[polygon_window[p]]``. The bound
    pass fills `n_vertices` and `n_rings` with output bounds (`n_polys` gets the ring
    bound too) and the scratch sizes; the write pass writes polygon p from
    ``vertex_slot[p]`` / ``ring_slot[p]`` (output polygons use the same ring slot) and
    replaces the bounds with the actual counts.
    """
    n_polygons = polygon_offsets.shape[0] - 1
    n_blocks = counters.shape[0]
    for blk in prange(n_blocks):
        st = counters[blk]
        lo_p = blk * block_size
        hi_p = min(n_polygons, (blk + 1) * block_size)
        if not write:
            for p in range(lo_p, hi_p):
                w = polygon_window[p]
                sv = 0
                sc = 0
                for r in range(polygon_offsets[p], polygon_offsets[p + 1]):
                    first = ring_offsets[r]
                    last = ring_offsets[r + 1] - 1
                    if last > first:
                        nv, nc, _ = bound_chains(xy, first, last, windows[w, 0], windows[w, 1],
                                                 windows[w, 2], windows[w, 3])
                        sv += nv
                        sc += nc
                    else:
                        sc += 1
                n_r = polygon_offsets[p + 1] - polygon_offsets[p]
                scratch_vertices[p] = sv
                scratch_chains[p] = sc
                # Chain vertices; up to four corners and a closing vertex per chain; the
                # window's five; the uncut rings are counted in `sv` already.
                n_vertices[p] = sv + 5 * sc + 6
                n_rings[p] = sc + n_r + 1
                n_polys[p] = sc + n_r + 1
            continue
        max_v = 1
        max_c = 1
        max_r = 1
        for p in range(lo_p, hi_p):
            max_v = max(max_v, scratch_vertices[p])
            max_c = max(max_c, scratch_chains[p])
            max_r = max(max_r, polygon_offsets[p + 1] - polygon_offsets[p])
        run_stack = np.empty((RUN_STACK_CAPACITY, 3), dtype=np.int64)
        stack_f = np.empty((STACK_CAPACITY, 6), dtype=np.float64)
        stack_i = np.empty((STACK_CAPACITY, 3), dtype=np.int64)
        ch_xy = np.empty((max_v, 2), dtype=np.float64)
        ch_z = np.empty(max_v if has_z else 0, dtype=np.float64)
        ch_starts = np.empty(max_c + 1, dtype=np.int64)
        lc = np.empty((max_c, 6), dtype=np.int64)
        keys = np.empty((max_c, 4), dtype=np.float64)
        order = np.empty(max_c, dtype=np.int64)
        ring_state = np.empty(max_r, dtype=np.int64)
        ring_rev = np.empty(max_r, dtype=np.bool_)
        ring_first = np.empty(max_r, dtype=np.int64)
        ring_last = np.empty(max_r, dtype=np.int64)
        hole_done = np.empty(max_r, dtype=np.bool_)
        for p in range(lo_p, hi_p):
            w = polygon_window[p]
            v0 = vertex_slot[p]
            r0 = ring_slot[p]
            v, nr, npoly, ok = clip_polygon(
                xy, z, has_z, ring_offsets, polygon_offsets[p], polygon_offsets[p + 1],
                windows[w, 0], windows[w, 1], windows[w, 2], windows[w, 3], method, n_fixed,
                max_depth, tol, auto_piece, exact, out_xy, out_z, out_ring_starts,
                out_poly_rings, v0, r0, r0, st, run_stack, stack_f, stack_i, ch_xy, ch_z,
                ch_starts, lc, keys, order, ring_state, ring_rev, ring_first, ring_last,
                hole_done)
            if not ok:
                st[C.INVALID_POLYGONS] += 1
            n_vertices[p] = v - v0
            n_rings[p] = nr - r0
            n_polys[p] = npoly - r0


@parallel
def compact_polygons(vertex_slot, ring_slot, n_vertices, n_rings, n_polys, slot_xy, slot_z,
                     has_z, slot_ring_starts, slot_poly_rings, vertex_start, ring_start,
                     poly_start, out_xy, out_z, out_ring_offsets, out_poly_rings):
    """Copy each polygon's output from its slot to its final place, closing the gaps.

    Ring starts are rebased from slot positions to final positions; `out_poly_rings`
    receives the ring count of each output polygon.
    """
    for p in prange(n_vertices.shape[0]):
        src = vertex_slot[p]
        dst = vertex_start[p]
        for k in range(n_vertices[p]):
            out_xy[dst + k, 0] = slot_xy[src + k, 0]
            out_xy[dst + k, 1] = slot_xy[src + k, 1]
            if has_z:
                out_z[dst + k] = slot_z[src + k]
        for k in range(n_rings[p]):
            out_ring_offsets[ring_start[p] + k] = slot_ring_starts[ring_slot[p] + k] - src + dst
        for k in range(n_polys[p]):
            out_poly_rings[poly_start[p] + k] = slot_poly_rings[ring_slot[p] + k]
