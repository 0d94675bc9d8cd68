"""Polygons clipped pair by pair straight from their parent array: the common cases, fast.

The tile cascade (`rnsca.tiles.pyramid`) clips each geometry of a zoom against the padded
boxes of the children tiles it crosses: many (geometry, box) pairs, one rectangle each.
Most of them are simple: every ring is inside the box, outside it, or (the shell only)
crosses its boundary at isolated points. For those, the general clip
(`polygons.clip_polygon`: run pruning, chains in scratch, events sorted by position and
angle, the walk, loops split, pieces grouped) is far more machinery than the answer
needs. Here each pair is clipped in one pass over its rings, read from the parent's
arrays by the pair's geometry index (no gather), and written into a slot bounded by a
first, cheap pass; a pair that is not simple is handed back (`FALLBACK`) for the general
clip. What is clipped here is what `clip_polygon` gives, bit for bit:

- the same polygon classes (`polygons.polygon_class_of`: inside whole, outside whole,
  or cut), and the inside ones copied as `polygons._copy_decided` copies them;
- the same cut points: each segment with one end strictly inside and the other outside
  is clipped by the same segment core (`segments.rnsca_segment`, same options);
- the same rings, in the same order, from the same first vertex: the walk of
  `polygons._walk` from the chains in the order `polygons._cut_rings` makes them, the
  window's corners walked counter-clockwise between an exit and the next entry, repeated
  vertices dropped as `polygons._put` drops them, rings without area dropped, and the
  holes inside the window given to the first piece that holds them (`point_in_ring` on
  the same vertices).

A pair is simple when, for each of its polygons that is cut: no vertex lies on the line
of a window edge (so no chain breaks at a vertex or runs along an edge), every ring has
area and at least four positions, no hole crosses the boundary (no walk joins two
rings), no two boundary crossings share a point or lie on a corner, the crossings
alternate exits and entries along the boundary (valid input), no shell vertex repeats
(no walk passes a point twice: `polygons._split_loops` would split it), and every piece
comes out counter-clockwise and every hole clockwise. Anything else falls back. 2D only.

Outcodes (`outcode.outcode`)::

          1001 | 1000 | 1010
          -----+------+-----
          0001 | 0000 | 0010
          -----+------+-----
          0101 | 0100 | 0110
"""

from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels import counters as C
from rnsca.kernels.jit import borrowing, parallel, scalar
from rnsca.kernels.outcode import outcode
from rnsca.kernels.polygons import (
    AMBIGUOUS,
    boundary_key,
    point_in_ring,
    polygon_class_of,
    signed_area,
)
from rnsca.kernels.records import CoreOptions, Window
from rnsca.kernels.segments import SegmentStack, rnsca_segment, segment_stack

__all__ = ["FAST", "FALLBACK", "Parent", "PairRows", "Written", "plan_pairs", "write_pairs"]

#: A pair's status: clipped here, or left to the general clip.
FAST, FALLBACK = 0, 1
_INSIDE = 1  # `polygons.polygon_class_of`: the shell's box strictly inside the window

# Hash table slots per vertex for the repeated-vertex test (a power of two at least this).
_SLOTS_PER_VERTEX = 2


@scalar
def _on_edge_line(x, y, window):
    """Return whether (x, y) lies on the line of one of the window's edges."""
    xmin, ymin, xmax, ymax = window
    return (x == xmin) | (x == xmax) | (y == ymin) | (y == ymax)


@scalar
def _scan_ring(xy, first, last, window):
    """Return (inside, crossings, plain) for the closed ring ``xy[first..last]``.

    `inside` counts the vertices strictly inside (the closing one excluded),
    `crossings` bounds the boundary crossings: one per segment with one end inside and
    one outside, two per segment from outside to outside whose ends share no outcode
    bit (it may pass through the window). `plain` is False when a vertex lies on an
    edge line or the ring has fewer than four positions.
    """
    xmin, ymin, xmax, ymax = window
    if last - first < 3:
        return 0, 0, False
    inside = 0
    transitions = 0
    plain = True
    c1 = outcode(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax)
    for i in range(first, last):
        c0 = c1
        x = xy[i + 1, 0]
        y = xy[i + 1, 1]
        c1 = outcode(x, y, xmin, ymin, xmax, ymax)
        inside += c0 == 0
        transitions += (c0 == 0) != (c1 == 0)
        transitions += 2 * ((c0 != 0) & (c1 != 0) & ((c0 & c1) == 0))
        plain &= not _on_edge_line(x, y, window)
    return inside, transitions, plain


@scalar
def _pair_bound(xy, ring_offsets, polygon_offsets, geometry_offsets, g, window):
    """Return (simple, vertices, rings, polygons): pair bounds of geometry g in `window`.

    The bounds hold whatever this module writes for the pair; `simple` is False when a
    polygon that is cut is not simple by the ring scan alone (`_scan_ring`, a hole
    crossing the boundary).
    """
    n_v = 0
    n_r = 0
    n_p = 0
    for p in range(geometry_offsets[g], geometry_offsets[g + 1]):
        r_begin = polygon_offsets[p]
        r_end = polygon_offsets[p + 1]
        cls = polygon_class_of(xy, ring_offsets, r_begin, r_end, window)
        if cls == _INSIDE:
            n_v += ring_offsets[r_end] - ring_offsets[r_begin]
            n_r += r_end - r_begin
            n_p += 1
            continue
        if cls != AMBIGUOUS:
            continue
        for r in range(r_begin, r_end):
            inside, transitions, plain = _scan_ring(xy, ring_offsets[r],
                                                    ring_offsets[r + 1] - 1, window)
            if not plain or (r > r_begin and transitions > 0):
                return False, 0, 0, 0
            # Inside vertices, cut points, a closing vertex each; per chain (two cut
            # points) a closing vertex and the corners walked (four in all, at most, for
            # crossings that alternate); the window's square.
            n_v += inside + 2 * transitions + 1
            n_r += 1 + transitions // 2
        n_v += 4 + 5
        n_r += 1
        n_p += 1 + ring_offsets[r_begin + 1] - ring_offsets[r_begin]
    return True, n_v, n_r, n_p


@parallel
def plan_pairs(xy, ring_offsets, polygon_offsets, geometry_offsets, pair_geometry, windows,
               status, bound_vertices, bound_rings, bound_polygons):
    """Store each pair's status (`FAST` or `FALLBACK`) and its output bounds.

    Pair j is geometry ``pair_geometry[j]`` (of the MULTIPOLYGON levels ``ring_offsets``,
    ``polygon_offsets``, ``geometry_offsets`` over `xy`) against ``windows[j]``. The
    bounds of a fallback pair are 0.
    """
    for j in prange(pair_geometry.shape[0]):
        window = Window(windows[j, 0], windows[j, 1], windows[j, 2], windows[j, 3])
        simple, n_v, n_r, n_p = _pair_bound(xy, ring_offsets, polygon_offsets,
                                            geometry_offsets, pair_geometry[j], window)
        status[j] = FAST if simple else FALLBACK
        bound_vertices[j] = n_v if simple else 0
        bound_rings[j] = n_r if simple else 0
        bound_polygons[j] = n_p if simple else 0


@scalar
def _put(out, start, v, x, y):
    """Append (x, y) to the ring begun at `start` unless it repeats the last vertex."""
    if v > start and out[v - 1, 0] == x and out[v - 1, 1] == y:
        return v
    out[v, 0] = x
    out[v, 1] = y
    return v + 1


@scalar
def _close(out, start, v):
    """Close the ring ``out[start:v]`` with its first vertex unless it ends there."""
    if v > start and not (out[v - 1, 0] == out[start, 0] and out[v - 1, 1] == out[start, 1]):
        out[v, 0] = out[start, 0]
        out[v, 1] = out[start, 1]
        v += 1
    return v


@scalar
def _corner(edge, window):
    """Return the corner where `edge` (0 bottom, 1 right, 2 top, 3 left) starts."""
    xmin, ymin, xmax, ymax = window
    if edge == 0:
        return xmin, ymin
    if edge == 1:
        return xmax, ymin
    if edge == 2:
        return xmax, ymax
    return xmin, ymax


class Parent(NamedTuple):
    """The parent level's polygons (a 2D MULTIPOLYGON array), read by geometry index."""

    xy: np.ndarray
    ring_offsets: np.ndarray
    polygon_offsets: np.ndarray
    geometry_offsets: np.ndarray


class Written(NamedTuple):
    """Where the pairs are written: vertices, each ring's length, each polygon's rings."""

    out: np.ndarray
    ring_len: np.ndarray
    poly_rings: np.ndarray


class PairRows(NamedTuple):
    """Per pair: a first row (slot) or a count of vertices, rings and polygons."""

    vertices: np.ndarray
    rings: np.ndarray
    polygons: np.ndarray


class Core(NamedTuple):
    """The segment core's options (`CoreOptions`), its stack and its counters (not kept)."""

    options: CoreOptions
    stack: SegmentStack
    st: np.ndarray


class Scratch(NamedTuple):
    """One block's scratch, sized for its largest polygon (`_block_scratch`).

    `holes` holds the cut polygon's holes inside the window, oriented and deduplicated
    (hole j at rows ``hole_start[j]:hole_start[j + 1]``; `hole_state` 0 outside or
    dropped, 1 inside, 2 placed in a piece); per shell crossing: its segment `seg`,
    whether it `enters`, its `cut` point; per chain: its entering crossing `chain_a`,
    the chain its exit leads to (`following`), `visited`; per event: `edge`, `s` and
    the sorted `order`; `table` and `stamp` the repeated-vertex test's hash table, `bits`
    (2 floats) and `bits_int` (the same memory as int64) to read a float's bits.
    """

    holes: np.ndarray
    hole_start: np.ndarray
    hole_state: np.ndarray
    seg: np.ndarray
    enters: np.ndarray
    cut: np.ndarray
    chain_a: np.ndarray
    following: np.ndarray
    visited: np.ndarray
    edge: np.ndarray
    s: np.ndarray
    order: np.ndarray
    table: np.ndarray
    stamp: np.ndarray
    bits: np.ndarray
    bits_int: np.ndarray


@borrowing
def _has_repeat(xy, first, last, sc, generation):
    """Return whether a vertex of the ring ``first..last-1`` repeats a non-adjacent one.

    Consecutive equal vertices count as one; the last equal to the first counts as a
    repeat (conservative). Open addressing in ``sc.table`` (a power of two long), a
    slot valid where ``sc.stamp`` holds `generation`; vertices hashed by their bits
    (``+ 0.0`` makes -0.0 the 0.0 that ``==`` takes it for).
    """
    table = sc.table
    stamp = sc.stamp
    mask = table.shape[0] - 1
    for i in range(first, last):
        x = xy[i, 0]
        y = xy[i, 1]
        if i > first and x == xy[i - 1, 0] and y == xy[i - 1, 1]:
            continue
        sc.bits[0] = x + 0.0
        sc.bits[1] = y + 0.0
        # Shifts and xors only (no multiply that overflows, also in plain Python): the
        # high bits (sign, exponent, leading mantissa) folded onto the low ones, which
        # are zero for round numbers.
        bx = sc.bits_int[0]
        by = sc.bits_int[1]
        slot = (bx ^ (bx >> 23) ^ (bx >> 47) ^ (by << 11) ^ (by >> 13) ^ (by >> 37)) & mask
        while stamp[slot] == generation:
            k = table[slot]
            if xy[k, 0] == x and xy[k, 1] == y:
                return True
            slot = (slot + 1) & mask
        stamp[slot] = generation
        table[slot] = i
    return False


@borrowing
def _copy_inside(xy, ring_offsets, r_begin, r_end, out, v, ring_len, r):
    """Write an inside polygon as `polygons._copy_decided` does; return (v, r)."""
    for q in range(r_begin, r_end):
        first = ring_offsets[q]
        last = ring_offsets[q + 1] - 1
        area = signed_area(xy, first, last) if last > first else 0.0
        reverse = (area < 0.0) if q == r_begin else (area > 0.0)
        start = v
        for k in range(last - first + 1):
            i = last - k if reverse else first + k
            out[v, 0] = xy[i, 0]
            out[v, 1] = xy[i, 1]
            v += 1
        ring_len[r] = v - start
        r += 1
    return v, r


@borrowing
def _hole_copy(xy, first, last, reverse, out, v):
    """Write the ring oriented, repeated vertices dropped (`polygons._add_ring`); return end."""
    start = v
    for k in range(last - first + 1):
        i = last - k if reverse else first + k
        v = _put(out, start, v, xy[i, 0], xy[i, 1])
    return v


@borrowing
def _sort_holes(xy, ring_offsets, r_begin, r_end, window, sc):
    """Copy the holes inside the window into ``sc.holes``; return (ok, any hole outside).

    As `polygons._add_uncut_rings` stores them: oriented clockwise, repeated vertices
    dropped, dropped if fewer than four positions or no area remain (state 0). ``ok``
    is False for a ring without area in the input (the general clip then clips ring by
    ring) or a hole that turns counter-clockwise.
    """
    hs = 0
    sc.hole_start[0] = 0
    any_outside = False
    for j in range(1, r_end - r_begin):
        first = ring_offsets[r_begin + j]
        last = ring_offsets[r_begin + j + 1] - 1
        sc.hole_state[j] = 0
        sc.hole_start[j] = hs
        area = signed_area(xy, first, last)
        if area == 0.0:
            return False, any_outside
        inside, _, _ = _scan_ring(xy, first, last, window)
        if inside == 0:
            any_outside = True
        else:
            he = _hole_copy(xy, first, last, area > 0.0, sc.holes, hs)
            if he - hs >= 4:
                hole_area = signed_area(sc.holes, hs, he - 1)
                if hole_area > 0.0:
                    return False, any_outside  # a hole turned shell
                if hole_area < 0.0:
                    sc.hole_state[j] = 1
                    hs = he
        sc.hole_start[j + 1] = hs
    return True, any_outside


@borrowing
def _place_holes(out, start, v, ring_len, r, poly_rings, p, n_rings, sc):
    """Write the holes inside the piece ``out[start:v]`` after it (`polygons._write_pieces`).

    The piece and its holes are one output polygon. Returns ``(v, r, p)``.
    """
    ring_len[r] = v - start
    rings_before = r
    r += 1
    shell_last = v - 1
    holes = sc.holes
    for j in range(1, n_rings):
        if sc.hole_state[j] != 1:
            continue
        where = 0
        for i in range(sc.hole_start[j], sc.hole_start[j + 1] - 1):
            where = point_in_ring(holes[i, 0], holes[i, 1], out, start, shell_last)
            if where != 0:
                break
        if where < 0:
            continue
        sc.hole_state[j] = 2
        h0 = v
        for i in range(sc.hole_start[j], sc.hole_start[j + 1]):
            out[v, 0] = holes[i, 0]
            out[v, 1] = holes[i, 1]
            v += 1
        ring_len[r] = v - h0
        r += 1
    poly_rings[p] = r - rings_before
    return v, r, p + 1


@borrowing
def _window_if_covered(xy, ring_offsets, r_begin, r_end, window, any_outside, sc, w, v, r,
                       p):
    """Write the window if its centre lies in the shell and in no hole outside it.

    `polygons._add_window_if_covered`, for a polygon none of whose rings is cut; the
    holes inside the window go into it. Returns ``(ok, v, r, p)``.
    """
    xmin, ymin, xmax, ymax = window
    cx = 0.5 * xmin + 0.5 * xmax
    cy = 0.5 * ymin + 0.5 * ymax
    covered = point_in_ring(cx, cy, xy, ring_offsets[r_begin], ring_offsets[r_begin + 1] - 1) > 0
    if covered and any_outside:
        for j in range(1, r_end - r_begin):
            first = ring_offsets[r_begin + j]
            last = ring_offsets[r_begin + j + 1] - 1
            if (sc.hole_start[j + 1] == sc.hole_start[j]
                    and _scan_ring(xy, first, last, window)[0] == 0
                    and point_in_ring(cx, cy, xy, first, last) > 0):
                covered = False
    if not covered:
        return True, v, r, p
    start = v
    for corner in range(4):
        x, y = _corner(corner, window)
        v = _put(w.out, start, v, x, y)
    v = _close(w.out, start, v)
    if v - start < 4 or signed_area(w.out, start, v - 1) <= 0.0:
        return False, start, r, p
    v, r, p = _place_holes(w.out, start, v, w.ring_len, r, w.poly_rings, p, r_end - r_begin,
                           sc)
    return True, v, r, p


@borrowing
def _find_crossings(xy, first, last, window, options, stack, st, sc):
    """Store the shell's crossings in input order (``sc.seg``, ``sc.enters``, ``sc.cut``).

    Each segment that may cross the boundary (one end strictly inside, or both outside
    with no outcode bit in common) is clipped by `rnsca_segment`, as the general clip
    clips it: one crossing where it leaves or enters, two (entry, exit) where it passes
    through. Returns the number of crossings, or -1 if a chain would break there (a
    piece that does not keep its inside end) or a cut lands on a corner.
    """
    xmin, ymin, xmax, ymax = window
    t = 0
    c1 = outcode(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax)
    for i in range(first, last):
        c0 = c1
        c1 = outcode(xy[i + 1, 0], xy[i + 1, 1], xmin, ymin, xmax, ymax)
        if (c0 | c1) == 0 or (c0 & c1) != 0:
            continue
        x0 = xy[i, 0]
        y0 = xy[i, 1]
        x1 = xy[i + 1, 0]
        y1 = xy[i + 1, 1]
        keep, _, _, ax, ay, bx, by = rnsca_segment(x0, y0, x1, y1, window, options, st, stack)
        if c0 != 0 and c1 != 0:  # passes through (a chain of its own) or by
            if not keep:
                continue
            if _at_corner(ax, ay, window) or _at_corner(bx, by, window):
                return -1
            sc.seg[t] = i
            sc.enters[t] = True
            sc.cut[t, 0] = ax
            sc.cut[t, 1] = ay
            sc.seg[t + 1] = i
            sc.enters[t + 1] = False
            sc.cut[t + 1, 0] = bx
            sc.cut[t + 1, 1] = by
            t += 2
            continue
        if c0 == 0:  # leaves: the piece starts at vertex i (the chain goes on)
            ok = keep and ax == x0 and ay == y0
            px = bx
            py = by
        else:  # enters: the piece ends at vertex i + 1 (the chain goes on from it)
            ok = keep and bx == x1 and by == y1
            px = ax
            py = ay
        if not ok or _at_corner(px, py, window):
            return -1
        sc.seg[t] = i
        sc.enters[t] = c0 != 0
        sc.cut[t, 0] = px
        sc.cut[t, 1] = py
        t += 1
    return t


@scalar
def _at_corner(x, y, window):
    """Return whether (x, y) is a corner of the window."""
    xmin, ymin, xmax, ymax = window
    return (x == xmin or x == xmax) and (y == ymin or y == ymax)


@borrowing
def _link_chains(n_cross, reverse, window, sc):
    """Order the chains' ends along the boundary; return the chain count, or -1.

    Chains as `polygons._cut_rings` orders them: one per entering crossing, in input
    order; chain k runs from crossing ``chain_a[k]`` to the next (read backwards if the
    shell was `reverse`d to turn counter-clockwise). Event 2k is chain k's entry, 2k + 1
    its exit, placed by `boundary_key` and sorted (insertion sort: few per polygon).
    Each exit leads to the next event, which must be an entry at another point (-1
    otherwise: crossings at one point, or not alternating, which is invalid input).
    """
    n_chains = 0
    for q in range(n_cross):
        if sc.enters[q]:
            sc.chain_a[n_chains] = q
            n_chains += 1
    edge = sc.edge
    s = sc.s
    order = sc.order
    for k in range(n_chains):
        a = sc.chain_a[k]
        b = (a + 1) % n_cross
        entry = b if reverse else a
        leave = a if reverse else b
        edge[2 * k], s[2 * k] = boundary_key(sc.cut[entry, 0], sc.cut[entry, 1], window)
        edge[2 * k + 1], s[2 * k + 1] = boundary_key(sc.cut[leave, 0], sc.cut[leave, 1],
                                                     window)
    n_ev = 2 * n_chains
    for e in range(n_ev):
        item = e
        q = e - 1
        while q >= 0 and (edge[item] < edge[order[q]] or (
                edge[item] == edge[order[q]] and s[item] < s[order[q]])):
            order[q + 1] = order[q]
            q -= 1
        order[q + 1] = item
    for e in range(n_ev):
        here = order[e]
        after = order[(e + 1) % n_ev]
        if edge[here] == edge[after] and s[here] == s[after]:
            return -1
        if (here % 2 == 1) == (after % 2 == 1):
            return -1
        if here % 2 == 1:
            sc.following[here // 2] = after // 2
    return n_chains


@borrowing
def _put_chain(xy, first, last, k, n_cross, reverse, sc, out, start, v):
    """Append chain k (cut, input vertices, cut; oriented) to the ring at `start`."""
    a = sc.chain_a[k]
    b = (a + 1) % n_cross
    first_v = sc.seg[a] + 1  # the chain's input vertices: first_v .. seg[b]
    last_v = sc.seg[b]
    cut = sc.cut
    if last_v == first_v - 1:  # a segment passing through: its two cut points
        if reverse:
            v = _put(out, start, v, cut[b, 0], cut[b, 1])
            return _put(out, start, v, cut[a, 0], cut[a, 1])
        v = _put(out, start, v, cut[a, 0], cut[a, 1])
        return _put(out, start, v, cut[b, 0], cut[b, 1])
    if reverse:
        v = _put(out, start, v, cut[b, 0], cut[b, 1])
        if last_v >= first_v:
            for i in range(last_v, first_v - 1, -1):
                v = _put(out, start, v, xy[i, 0], xy[i, 1])
        else:  # across the closing vertex
            for i in range(last_v, first, -1):
                v = _put(out, start, v, xy[i, 0], xy[i, 1])
            for i in range(last, first_v - 1, -1):
                v = _put(out, start, v, xy[i, 0], xy[i, 1])
        return _put(out, start, v, cut[a, 0], cut[a, 1])
    v = _put(out, start, v, cut[a, 0], cut[a, 1])
    if last_v >= first_v:
        for i in range(first_v, last_v + 1):
            v = _put(out, start, v, xy[i, 0], xy[i, 1])
    else:
        for i in range(first_v, last + 1):
            v = _put(out, start, v, xy[i, 0], xy[i, 1])
        for i in range(first + 1, last_v + 1):
            v = _put(out, start, v, xy[i, 0], xy[i, 1])
    return _put(out, start, v, cut[b, 0], cut[b, 1])


@borrowing
def _clip_simple(xy, ring_offsets, r_begin, r_end, window, core, sc, w, v, r, p, generation):
    """Clip a cut polygon (class AMBIGUOUS) whose rings passed `_scan_ring`.

    Returns ``(ok, v, r, p)``; ``ok`` False if it is not simple after all (its pair
    falls back, and what was written does not count).
    """
    n_rings = r_end - r_begin
    first = ring_offsets[r_begin]
    last = ring_offsets[r_begin + 1] - 1
    area = signed_area(xy, first, last)
    if area == 0.0:
        return False, v, r, p
    reverse = area < 0.0
    ok, any_outside = _sort_holes(xy, ring_offsets, r_begin, r_end, window, sc)
    if not ok:
        return False, v, r, p
    n_cross = _find_crossings(xy, first, last, window, core.options, core.stack, core.st, sc)
    if n_cross < 0:
        return False, v, r, p
    if n_cross == 0:
        if _scan_ring(xy, first, last, window)[0] > 0:
            return False, v, r, p  # never: the shell would be inside, class INSIDE
        return _window_if_covered(xy, ring_offsets, r_begin, r_end, window, any_outside, sc,
                                  w, v, r, p)
    if _has_repeat(xy, first, last, sc, generation):
        return False, v, r, p
    n_chains = _link_chains(n_cross, reverse, window, sc)
    if n_chains < 0:
        return False, v, r, p
    # The walks (`polygons._walk_from`): each closes one piece.
    for k in range(n_chains):
        sc.visited[k] = False
    for k0 in range(n_chains):
        if sc.visited[k0]:
            continue
        start = v
        k = k0
        while True:
            sc.visited[k] = True
            v = _put_chain(xy, first, last, k, n_cross, reverse, sc, w.out, start, v)
            nxt = sc.following[k]
            # The corners from chain k's exit to chain nxt's entry (`_walk_corners`).
            exit_edge = sc.edge[2 * k + 1]
            entry_edge = sc.edge[2 * nxt]
            if not (entry_edge == exit_edge and sc.s[2 * nxt] > sc.s[2 * k + 1]):
                e = exit_edge
                while True:
                    x, y = _corner((e + 1) % 4, window)
                    v = _put(w.out, start, v, x, y)
                    e = (e + 1) % 4
                    if e == entry_edge:
                        break
            if nxt == k0:
                break
            if sc.visited[nxt]:
                return False, v, r, p
            k = nxt
        v = _close(w.out, start, v)
        if v - start < 4:
            v = start
            continue
        piece_area = signed_area(w.out, start, v - 1)
        if piece_area < 0.0:
            return False, v, r, p  # a piece turned hole
        if piece_area == 0.0:
            v = start
            continue
        v, r, p = _place_holes(w.out, start, v, w.ring_len, r, w.poly_rings, p, n_rings, sc)
    return True, v, r, p


@borrowing
def _write_pair(src, g, window, core, sc, w, v, r, p, generation):
    """Write geometry g of `src` clipped to `window` at rows v, r, p of `w`.

    From ``w.out[v]``, ``w.ring_len[r]`` and ``w.poly_rings[p]``. Returns
    ``(ok, v, r, p)``.
    """
    for q in range(src.geometry_offsets[g], src.geometry_offsets[g + 1]):
        r_begin = src.polygon_offsets[q]
        r_end = src.polygon_offsets[q + 1]
        cls = polygon_class_of(src.xy, src.ring_offsets, r_begin, r_end, window)
        if cls == _INSIDE:
            v, r = _copy_inside(src.xy, src.ring_offsets, r_begin, r_end, w.out, v,
                                w.ring_len, r)
            w.poly_rings[p] = r_end - r_begin
            p += 1
        elif cls == AMBIGUOUS:
            ok, v, r, p = _clip_simple(src.xy, src.ring_offsets, r_begin, r_end, window, core,
                                       sc, w, v, r, p, generation + q)
            if not ok:
                return False, v, r, p
    return True, v, r, p


@scalar
def _block_scratch(ring_offsets, polygon_offsets, geometry_offsets, pair_geometry, status, lo,
                   hi):
    """Return a `Scratch` for the largest polygon of the fast pairs lo..hi-1."""
    positions = 4
    rings = 2
    for j in range(lo, hi):
        if status[j] != FAST:
            continue
        g = pair_geometry[j]
        for q in range(geometry_offsets[g], geometry_offsets[g + 1]):
            r_begin = polygon_offsets[q]
            r_end = polygon_offsets[q + 1]
            positions = max(positions, ring_offsets[r_end] - ring_offsets[r_begin])
            rings = max(rings, r_end - r_begin + 1)
    slots = 8
    while slots < _SLOTS_PER_VERTEX * positions:
        slots *= 2
    bits = np.empty(2, dtype=np.float64)
    crossings = 2 * positions  # two per segment, at most (one passing through)
    return Scratch(np.empty((positions, 2), dtype=np.float64),
                   np.empty(rings + 1, dtype=np.int64), np.empty(rings, dtype=np.int8),
                   np.empty(crossings, dtype=np.int64), np.empty(crossings, dtype=np.bool_),
                   np.empty((crossings, 2), dtype=np.float64),
                   np.empty(positions, dtype=np.int64), np.empty(positions, dtype=np.int64),
                   np.empty(positions, dtype=np.bool_), np.empty(crossings, dtype=np.int64),
                   np.empty(crossings, dtype=np.float64), np.empty(crossings, dtype=np.int64),
                   np.empty(slots, dtype=np.int64), np.full(slots, -1, dtype=np.int64), bits,
                   bits.view(np.int64))


@scalar
def _write_block(blk, n_blocks, src, pair_geometry, windows, options, status, slot, w, count):
    """Clip the fast pairs of block `blk` (the body of `write_pairs`)."""
    n_pairs = pair_geometry.shape[0]
    lo = blk * n_pairs // n_blocks
    hi = (blk + 1) * n_pairs // n_blocks
    sc = _block_scratch(src.ring_offsets, src.polygon_offsets, src.geometry_offsets,
                        pair_geometry, status, lo, hi)
    # The segment core's counters are not kept.
    core = Core(options, segment_stack(), np.zeros(C.WIDTH, dtype=np.int64))
    for j in range(lo, hi):
        if status[j] != FAST:
            continue
        window = Window(windows[j, 0], windows[j, 1], windows[j, 2], windows[j, 3])
        # The hash table's generation: one per polygon (pairs of one geometry repeat
        # its polygons' indices, so the pair's position comes first).
        ok, v, r, p = _write_pair(src, pair_geometry[j], window, core, sc, w,
                                  slot.vertices[j], slot.rings[j], slot.polygons[j],
                                  (j - lo) * (src.polygon_offsets.shape[0]))
        if not ok:
            status[j] = FALLBACK
            v = slot.vertices[j]
            r = slot.rings[j]
            p = slot.polygons[j]
        count.vertices[j] = v - slot.vertices[j]
        count.rings[j] = r - slot.rings[j]
        count.polygons[j] = p - slot.polygons[j]


@parallel
def write_pairs(src, pair_geometry, windows, options, n_blocks, status, slot, w, count):
    """Clip the `FAST` pairs into their slots; a pair found not simple becomes `FALLBACK`.

    `src` is the parent's polygons (`Parent`). Pair j writes its vertices from
    ``w.out[slot.vertices[j]]``, its rings' lengths from ``w.ring_len[slot.rings[j]]``
    and its polygons' ring counts from ``w.poly_rings[slot.polygons[j]]`` (`Written`;
    slots, `PairRows`, from `plan_pairs`' bounds), and how many of each it wrote to
    ``count`` (`PairRows`; 0 for a fallback pair). `options` is the segment core's
    (`CoreOptions`, exact), as the general clip gets them. One prange iteration per block
    of pairs, each with its own scratch.
    """
    for blk in prange(n_blocks):
        _write_block(np.int64(blk), n_blocks, src, pair_geometry, windows, options, status,
                     slot, w, count)
