"""Clean fills: rebuild the clip of each filled path as closed subpaths whose rings are simple.

The fill clip (`bezier.clip_path_blocks` with ``fill``) replaces every part of a filled
subpath that lies outside the window by its clamp onto the window's boundary. Each input
subpath gives one closed output subpath; together they paint the right region under either
fill rule, but a subpath may run along an edge several times, back and forth, and touch
itself there (a polygoniser or a font editor would have to repair it). Here each path's
output is rebuilt from the same pieces, in four steps:

1. **Cut** (`_cut`). Every output subpath is cut at its vertices on the window's boundary.
   The pieces between two such vertices are *edge lines* (all control points on one edge
   line: the clamped outside parts, and visible parts lying on an edge) or *chains*
   (visible parts through the window, from one boundary point to another). A subpath
   with no vertex on the boundary is a *loop*, kept as it is. Segments of zero length
   are dropped, and so are chains that run out and back along one line to the point
   they started from (`_spike`: they enclose nothing).
2. **Count** (`_lane_counts`). The edge lines are replaced by their net count along the
   boundary: on each stretch between two boundary points, ``m`` = (times run
   counter-clockwise) - (times run clockwise), counter-clockwise meaning with the window's
   inside on the left (in y-up axes: along the bottom edge towards +x). A point just
   outside the window winds 0 times around the output, and stepping across a stretch run
   ``m`` times changes the winding number by ``m``: ``m`` is the winding number just
   inside the window. It steps by +1 where a chain ends on the boundary and by -1 where
   one starts (the fill clip's output is closed).
3. **Match** (`_match`). The chains are joined by *lanes* along the boundary. The
   chains' ends are ordered along the boundary, counter-clockwise from (xmin, ymin), and
   ends at one point by the angle at which their chains leave it (as if each lay a
   little further along the boundary, by its angle: the two ends of a chain that
   touches an edge and turns back are then taken in the order that keeps rings apart).
   *Nonzero* keeps the winding numbers: the lanes carry the count. Walking
   counter-clockwise from a stretch of least ``|m|``, a chain ending where the count is
   >= 0 starts a lane counter-clockwise, and the next chain starting where it is > 0
   takes the innermost open lane (a stack, as parentheses match); where the count is
   negative the lanes run clockwise, from a chain's end back to a start met earlier.
   The stretch of least ``|m|`` carries ``|m|`` lanes all around: that many copies of
   the window's outline. *Evenodd* keeps only the parity, and every chain separates an
   odd side from an even one: from a stretch where the count is even the ends are
   joined in pairs, each by one lane counter-clockwise over a stretch where it is odd,
   and a chain may be run backwards. No stretch carries two lanes, and the rings have
   the painted side on their left (for outlines that do not cross).
4. **Rings** (`_trace`, `_put_ring`). Chain, lane, chain, ... are followed into closed
   walks; a walk is cut into rings at every boundary point it passes twice (so no ring
   meets itself there), and each ring's lanes are written as one line per edge.

A walk joins chains of different subpaths (a counter open to the edge joins its shell's
ring). Where two outlines of a path cross each other inside the window, such a ring would
cross itself: when the control-point boxes of two such chains' pieces still overlap after
halving both many times (`_outlines_cross`, a test that errs only towards "may cross"),
the path is rebuilt subpath by subpath instead (each subpath's clip is closed on its
own). Every ring is then simple when its subpath's outline is (does not cross or touch
itself); overlapping outlines give overlapping rings.

The chains and loops are the clip's own pieces (curves stay curves, of their degree; a
piece that touches an edge and turns back in is cut there by the clip, and the ends of
its pieces lie in the closed window: ``clean`` of `bezier.Options`); only the lines
along the edges are new, and their ends are the pieces' boundary points or the window's
corners, exact: positions along the boundary are compared as (edge, coordinate along
the edge), never by a perimeter distance. Nonzero
output winds around every point off the boundary as often as the fill clip's does;
evenodd output as often modulo 2: each paints the same region under its rule. The closing
line of a ring is left to ``Z`` (not written).

Two passes over one body per path (`clean_fill_paths`, ``prange`` over blocks of paths):
the count pass sizes each path's output, the write pass writes it from its place. A path
with no vertex on the boundary is copied (its loops) without any scratch.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels.bezier import piece_values
from rnsca.kernels.jit import allocating, borrowing, parallel, scalar
from rnsca.kernels.records import window_of

__all__ = ["FillPaths", "RingLayout", "RingOutput", "clean_fill_paths"]

# Segment kinds (`_segment_kind`): an edge line's kind is _EDGE + its edge.
_PIECE = 0
_POINT = 1
_EDGE = 2
# Edges in counter-clockwise order from (xmin, ymin). A corner belongs to the edge that
# starts there, so a stretch from one boundary position to the next lies on the edge of
# the first.
_BOTTOM = 0
_RIGHT = 1
_TOP = 2
_LEFT = 3
# Steps of a walk (`_trace`): a chain, by the end it is entered at (2c: run from its
# start; 2c + 1: from its end, backwards), or one stretch of a lane.
_FORWARD = -1     # counter-clockwise, from vertex v to v + 1
_BACKWARD = -2    # clockwise, from vertex v to v - 1
# Chain ends (events).
_ARRIVE = 0       # a chain ends here
_DEPART = 1       # a chain starts here


class FillPaths(NamedTuple):
    """The fill clip's output (`rnsca.arrays.PathArrays` layout, every subpath closed)."""

    controls: np.ndarray         # float64 (m, 4, 2)
    degree: np.ndarray           # int8 (m,)
    subpath_offsets: np.ndarray  # int64 (k + 1,)
    path_offsets: np.ndarray     # int64 (n + 1,)


class RingLayout(NamedTuple):
    """Each path's output: its size (count pass) and its place (write pass)."""

    n_segments: np.ndarray       # int64 (n,)
    n_rings: np.ndarray          # int64 (n,)
    segment_start: np.ndarray    # int64 (n,) first output segment (write pass)
    ring_start: np.ndarray       # int64 (n,) first output subpath (write pass)


class RingOutput(NamedTuple):
    """The rings; without `write` (the count pass), empty and untouched."""

    write: bool
    controls: np.ndarray         # float64 (M, 4, 2)
    degree: np.ndarray           # int8 (M,)
    first: np.ndarray            # int64 (K + 1,) each ring's first segment
    start: np.ndarray            # float64 (K, 2)


class Cut(NamedTuple):
    """One path's pieces after cutting at the boundary (scratch; see step 1)."""

    kind: np.ndarray             # int64 (m,) per segment of the path (index - first one)
    chain_first: np.ndarray      # int64 (c,) each chain's first segment
    chain_count: np.ndarray      # int64 (c,) its segments, cyclic within its subpath
    chain_sub: np.ndarray        # int64 (c,) its subpath
    edge_segment: np.ndarray     # int64 (e,) each edge line
    edge_side: np.ndarray        # int64 (e,) the edge it lies on
    sub_chains: np.ndarray       # int64 (k + 1,) chain offsets of the path's subpaths
    sub_loop: np.ndarray         # bool (k,) a subpath with no vertex on the boundary


class Boundary(NamedTuple):
    """The boundary points of one path (scratch; see steps 2 and 3).

    Points (chain ends, edge line ends, the four corners) have positions (distinct
    boundary points, in counter-clockwise order); positions where a chain ends or that
    are corners are *vertices*, the only points the rings pass on the boundary.
    """

    point_edge: np.ndarray       # int64 (q,)
    point_along: np.ndarray      # float64 (q,)
    point_vertex: np.ndarray     # bool (q,)
    point_position: np.ndarray   # int64 (q,)
    position_vertex: np.ndarray  # int64 (q,) a position's vertex, or -1
    position_count: np.ndarray   # int64 (q + 1,) net count difference (then the count)
    vertex_edge: np.ndarray      # int64 (q,)
    vertex_along: np.ndarray     # float64 (q,)
    vertex_count: np.ndarray     # int64 (q,) m on the stretch from vertex v to v + 1


class Lanes(NamedTuple):
    """The lane from each chain end to another (scratch; see step 3).

    End ``2c`` is chain c's start, ``2c + 1`` its end.
    """

    partner: np.ndarray          # int64 (2c,) the end the lane leads to
    lane_steps: np.ndarray       # int64 (2c,) the stretches (vertex to vertex) it runs
    lane_step: np.ndarray        # int64 (2c,) _FORWARD or _BACKWARD, from this end
    vertex: np.ndarray           # int64 (2c,) the vertex where the end lies


class Walk(NamedTuple):
    """The walk being cut into rings (scratch; see step 4)."""

    step: np.ndarray             # int64 (w,) a chain's entry end, _FORWARD or _BACKWARD
    origin: np.ndarray           # int64 (w,) the vertex the step starts at
    seen: np.ndarray             # int64 (vertices,) the step that starts at a vertex, or -1
    visited: np.ndarray          # bool (c,) chains already in a walk


@scalar
def _on_boundary(x, y, window):
    return x == window.xmin or x == window.xmax or y == window.ymin or y == window.ymax


@borrowing
def _segment_kind(controls, g, window):
    """Return _POINT (no length), _EDGE + edge (on that edge's line) or _PIECE."""
    x0 = controls[g, 0, 0]
    y0 = controls[g, 0, 1]
    same_x = True
    same_y = True
    for k in range(1, 4):  # unused rows repeat the end: all four rows are on the curve's hull
        same_x = same_x and controls[g, k, 0] == x0
        same_y = same_y and controls[g, k, 1] == y0
    if same_x and same_y:
        return _POINT
    if same_x and x0 == window.xmin:
        return _EDGE + _LEFT
    if same_x and x0 == window.xmax:
        return _EDGE + _RIGHT
    if same_y and y0 == window.ymin:
        return _EDGE + _BOTTOM
    if same_y and y0 == window.ymax:
        return _EDGE + _TOP
    return _PIECE


@scalar
def _along(edge, x, y):
    """Return the coordinate of (x, y) that grows counter-clockwise along `edge`."""
    if edge == _BOTTOM:
        return x
    if edge == _RIGHT:
        return y
    if edge == _TOP:
        return -x
    return -y


@scalar
def _position(x, y, window):
    """Return (edge, along): where the boundary point (x, y) lies, counter-clockwise.

    A corner belongs to the edge that starts there; (xmin, ymin) is the first position.
    The points given are exactly on the boundary; one that were not (it cannot be: every
    point comes from an edge line or a vertex found on the boundary) is put on the edge
    nearest to it.
    """
    if y == window.ymin and x != window.xmax:
        return _BOTTOM, x
    if x == window.xmax and y != window.ymax:
        return _RIGHT, y
    if y == window.ymax and x != window.xmin:
        return _TOP, -x
    if x == window.xmin:
        return _LEFT, -y
    gaps = (y - window.ymin, window.xmax - x, window.ymax - y, x - window.xmin)
    edge = 0
    for e in range(1, 4):
        if gaps[e] < gaps[edge]:
            edge = e
    return edge, _along(edge, x, y)


@scalar
def _point_of(edge, along, window):
    """Return the boundary point at `along` on `edge` (the inverse of `_position`)."""
    if edge == _BOTTOM:
        return along, window.ymin
    if edge == _RIGHT:
        return window.xmax, along
    if edge == _TOP:
        return -along, window.ymax
    return window.xmin, -along


@scalar
def _angle(edge, dx, dy):
    """Return the angle of direction (dx, dy) into the window at a point of `edge`.

    From the edge's counter-clockwise direction towards the inward normal: 0 along the
    boundary ahead, pi/2 straight in (at a corner: back along the previous edge), pi
    along the boundary behind. Ends at one point are ordered by it, largest first.
    """
    ux = 1.0 if edge == _BOTTOM else (-1.0 if edge == _TOP else 0.0)
    uy = 1.0 if edge == _RIGHT else (-1.0 if edge == _LEFT else 0.0)
    inward = dy * ux - dx * uy
    if not inward > 0.0:
        # Along the boundary (or an ulp out): +0, so that straight back is pi, not -pi
        # (atan2(-0.0, -1) is -pi: a -0.0 here would put it ahead of everything).
        inward = 0.0
    return math.atan2(inward, dx * ux + dy * uy)


@borrowing
def _chain_segment(paths, cut, c, j):
    """Return the path-array index of segment j of chain c (cyclic within its subpath)."""
    a = paths.subpath_offsets[cut.chain_sub[c]]
    n = paths.subpath_offsets[cut.chain_sub[c] + 1] - a
    return a + (cut.chain_first[c] - a + j) % n


@borrowing
def _chain_direction(paths, cut, c, at_start):
    """Return the direction in which chain c leaves its start (or its end, backwards)."""
    count = cut.chain_count[c]
    controls = paths.controls
    for q in range(count):
        g = _chain_segment(paths, cut, c, q if at_start else count - 1 - q)
        if at_start:
            x0 = controls[g, 0, 0]
            y0 = controls[g, 0, 1]
            for k in range(1, 4):
                dx = controls[g, k, 0] - x0
                dy = controls[g, k, 1] - y0
                if dx != 0.0 or dy != 0.0:
                    return dx, dy
        else:
            x3 = controls[g, 3, 0]
            y3 = controls[g, 3, 1]
            for k in range(2, -1, -1):
                dx = controls[g, k, 0] - x3
                dy = controls[g, k, 1] - y3
                if dx != 0.0 or dy != 0.0:
                    return dx, dy
    return 0.0, 0.0


@borrowing
def _cut(paths, window, s_lo, s_hi, g_lo, cut):
    """Step 1: cut the subpaths s_lo..s_hi-1; return (chains, edge lines)."""
    controls = paths.controls
    n_chains = 0
    n_edges = 0
    for s in range(s_lo, s_hi):
        cut.sub_chains[s - s_lo] = n_chains
        a = paths.subpath_offsets[s]
        n = paths.subpath_offsets[s + 1] - a
        cut.sub_loop[s - s_lo] = False
        j0 = -1
        for t in range(n):
            if _on_boundary(controls[a + t, 0, 0], controls[a + t, 0, 1], window):
                j0 = t
                break
        if j0 < 0:
            cut.sub_loop[s - s_lo] = n > 0
            continue
        # From a vertex on the boundary, once around: a chain runs from the first piece
        # after a boundary vertex to the next boundary vertex.
        open_at = -1
        for t in range(n):
            g = a + (j0 + t) % n
            if open_at >= 0 and _on_boundary(controls[g, 0, 0], controls[g, 0, 1], window):
                cut.chain_count[n_chains] = t - open_at
                if not _spike(paths, cut, n_chains):
                    n_chains += 1
                open_at = -1
            kind = cut.kind[g - g_lo]
            if kind >= _EDGE:
                cut.edge_segment[n_edges] = g
                cut.edge_side[n_edges] = kind - _EDGE
                n_edges += 1
            elif kind == _PIECE and open_at < 0:
                open_at = t
                cut.chain_first[n_chains] = g
                cut.chain_sub[n_chains] = s
        if open_at >= 0:
            cut.chain_count[n_chains] = n - open_at
            if not _spike(paths, cut, n_chains):
                n_chains += 1
    cut.sub_chains[s_hi - s_lo] = n_chains
    return n_chains, n_edges


@borrowing
def _spike(paths, cut, c):
    """Return whether chain c goes out and back along one line to where it started.

    Such a chain encloses nothing (every point off the line winds around it 0 times):
    it is dropped. The fill clip leaves one where rounding takes a stretch an ulp
    outside an edge for visible (its middle rounds onto the edge): it runs from the
    edge an ulp out and back.
    """
    controls = paths.controls
    g0 = cut.chain_first[c]
    g1 = _chain_segment(paths, cut, c, cut.chain_count[c] - 1)
    x0 = controls[g0, 0, 0]
    y0 = controls[g0, 0, 1]
    if controls[g1, 3, 0] != x0 or controls[g1, 3, 1] != y0:
        return False
    dx = 0.0
    dy = 0.0
    for j in range(cut.chain_count[c]):
        g = _chain_segment(paths, cut, c, j)
        for k in range(1, 4):
            ex = controls[g, k, 0] - x0
            ey = controls[g, k, 1] - y0
            if dx == 0.0 and dy == 0.0:
                dx = ex
                dy = ey
            elif ex * dy - ey * dx != 0.0:
                return False
    return True


@borrowing
def _add_point(bd, q, x, y, vertex, window):
    edge, along = _position(x, y, window)
    bd.point_edge[q] = edge
    bd.point_along[q] = along
    bd.point_vertex[q] = vertex
    return q + 1


@borrowing
def _key_less(a, b, first, second, third):
    """Return whether item a comes before item b: by `first`, then `second`, then `third`."""
    if first[a] != first[b]:
        return first[a] < first[b]
    if second[a] != second[b]:
        return second[a] < second[b]
    return third[a] < third[b]


@borrowing
def _sort_by_keys(order, first, second, third, scratch):
    """Sort the items `order` by (`first`, `second`, `third`), in place: a merge sort.

    Bottom-up, stable; `scratch` is as long as `order`. One function for the boundary
    points (edge, along) and the chain ends (vertex, angle, kind): NumPy's argsort would
    compile once per key type and a lexsort is not in Numba.
    """
    n = order.shape[0]
    src = order
    dst = scratch
    in_scratch = False
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i = lo
            j = mid
            for k in range(lo, hi):
                if i < mid and (j >= hi or not _key_less(src[j], src[i], first, second, third)):
                    dst[k] = src[i]
                    i += 1
                else:
                    dst[k] = src[j]
                    j += 1
        src, dst = dst, src
        in_scratch = not in_scratch
        width *= 2
    if in_scratch:
        for k in range(n):
            order[k] = scratch[k]


@allocating
def _boundary_points(paths, window, cut, n_chains, n_edges, bd):
    """Step 2, first half: place the points; return (positions, vertices).

    Points 2c and 2c + 1 are chain c's start and end, then come the edge lines' ends
    (2 n_chains + 2e, + 1) and the corners. Sorted by (edge, along), exactly.
    """
    controls = paths.controls
    q = 0
    for c in range(n_chains):
        g0 = cut.chain_first[c]
        g1 = _chain_segment(paths, cut, c, cut.chain_count[c] - 1)
        q = _add_point(bd, q, controls[g0, 0, 0], controls[g0, 0, 1], True, window)
        q = _add_point(bd, q, controls[g1, 3, 0], controls[g1, 3, 1], True, window)
    for e in range(n_edges):
        g = cut.edge_segment[e]
        q = _add_point(bd, q, controls[g, 0, 0], controls[g, 0, 1], False, window)
        q = _add_point(bd, q, controls[g, 3, 0], controls[g, 3, 1], False, window)
    q = _add_point(bd, q, window.xmin, window.ymin, True, window)
    q = _add_point(bd, q, window.xmax, window.ymin, True, window)
    q = _add_point(bd, q, window.xmax, window.ymax, True, window)
    q = _add_point(bd, q, window.xmin, window.ymax, True, window)
    order = np.arange(q)
    _sort_by_keys(order, bd.point_edge, bd.point_along, bd.point_edge, np.empty(q, np.int64))
    n_positions = 0
    n_vertices = 0
    for i in range(q):
        p = order[i]
        if i == 0 or bd.point_edge[p] != bd.point_edge[order[i - 1]] or \
                bd.point_along[p] != bd.point_along[order[i - 1]]:
            bd.position_vertex[n_positions] = -1
            n_positions += 1
        bd.point_position[p] = n_positions - 1
        if bd.point_vertex[p] and bd.position_vertex[n_positions - 1] < 0:
            bd.position_vertex[n_positions - 1] = n_vertices
            bd.vertex_edge[n_vertices] = bd.point_edge[p]
            bd.vertex_along[n_vertices] = bd.point_along[p]
            n_vertices += 1
    return n_positions, n_vertices



@borrowing
def _lane_counts(paths, cut, n_chains, n_edges, n_positions, bd):
    """Step 2, second half: the count m on each stretch from a vertex to the next.

    Each edge line adds +1 (counter-clockwise) or -1 (clockwise) to the stretches it
    runs over, as a difference array over the positions; one that runs through the
    first position, (xmin, ymin), covers the stretches after its start and before its
    end: the base then counts it for all of them, and the differences take it off the
    ones in between.
    """
    controls = paths.controls
    diff = bd.position_count
    for i in range(n_positions + 1):
        diff[i] = 0
    base = 0
    for e in range(n_edges):
        g = cut.edge_segment[e]
        ia = bd.point_position[2 * n_chains + 2 * e]
        ib = bd.point_position[2 * n_chains + 2 * e + 1]
        if ia == ib:
            continue  # back where it began (a curve on the edge line turning back)
        edge = cut.edge_side[e]
        if _along(edge, controls[g, 3, 0], controls[g, 3, 1]) > \
                _along(edge, controls[g, 0, 0], controls[g, 0, 1]):
            diff[ia] += 1
            diff[ib] -= 1
            if ib < ia:
                base += 1
        else:
            diff[ib] -= 1
            diff[ia] += 1
            if ia < ib:
                base -= 1
    running = base
    for i in range(n_positions):
        running += diff[i]
        v = bd.position_vertex[i]
        if v >= 0:
            bd.vertex_count[v] = running


@borrowing
def _link(lanes, a, b, steps, step):
    """Join chain ends a and b by a lane of `steps` stretches, run `step`-wise from a."""
    lanes.partner[a] = b
    lanes.partner[b] = a
    lanes.lane_steps[a] = steps
    lanes.lane_steps[b] = steps
    lanes.lane_step[a] = step
    lanes.lane_step[b] = _BACKWARD if step == _FORWARD else _FORWARD


@allocating
def _match(paths, cut, n_chains, n_vertices, bd, lanes, evenodd):
    """Step 3: join every chain's end to another chain end by a lane.

    Returns ``(base, consistent)``: the number of lanes all around the window
    (counter-clockwise if positive), and whether the counts of the edge lines agree with
    the chains' ends (they do for any closed output: False would be a bug upstream).

    Nonzero keeps the winding numbers: a chain's end is joined to a chain's start (see
    the module's docstring). With `evenodd` only their parity matters, and every chain
    separates an odd side from an even one (crossing or not): from a stretch where the
    count is even, the ends are joined in pairs, counter-clockwise, each lane over a
    stretch where it is odd, and chains are run either way. No stretch then carries
    two lanes.
    """
    n_ends = 2 * n_chains
    if n_ends == 0:
        base = bd.vertex_count[0]
        consistent = True
        for v in range(n_vertices):
            consistent = consistent and bd.vertex_count[v] == base
        return (base % 2 if evenodd else base), consistent
    vertex = np.empty(n_ends, dtype=np.int64)
    angle = np.empty(n_ends, dtype=np.float64)  # negated: sorted ascending
    kind = np.empty(n_ends, dtype=np.int64)
    for c in range(n_chains):
        vs = bd.position_vertex[bd.point_position[2 * c]]
        ve = bd.position_vertex[bd.point_position[2 * c + 1]]
        lanes.vertex[2 * c] = vs
        lanes.vertex[2 * c + 1] = ve
        dx, dy = _chain_direction(paths, cut, c, True)
        vertex[2 * c] = vs
        angle[2 * c] = -_angle(bd.vertex_edge[vs], dx, dy)
        kind[2 * c] = _DEPART
        dx, dy = _chain_direction(paths, cut, c, False)
        vertex[2 * c + 1] = ve
        angle[2 * c + 1] = -_angle(bd.vertex_edge[ve], dx, dy)
        kind[2 * c + 1] = _ARRIVE
    # By vertex, then angle (largest first: `angle` is negated), then arrivals first.
    order = np.arange(n_ends)
    _sort_by_keys(order, vertex, angle, kind, np.empty(n_ends, np.int64))
    # The count after each end in that order, from the stretch before the first end.
    count = bd.vertex_count[(vertex[order[0]] - 1) % n_vertices]
    after = np.empty(n_ends, dtype=np.int64)
    best = 0
    consistent = True
    for i in range(n_ends):
        e = order[i]
        count += 1 if kind[e] == _ARRIVE else -1
        after[i] = count
        if abs(count) < abs(after[best]):
            best = i
        if i == n_ends - 1 or vertex[order[i + 1]] != vertex[e]:
            consistent = consistent and count == bd.vertex_count[vertex[e]]
    if evenodd:  # from a stretch of even count (half of them are)
        for i in range(n_ends):
            if after[i] % 2 == 0:
                best = i
                break
    base = after[best]
    # Once around from the stretch after end `best`. `unrolled` numbers the vertices
    # passed from there: the ends sorted up to `best` come after the wrap (+ n_vertices),
    # also those at the vertex where the walk starts, so a lane's length is a difference.
    unrolled = np.empty(n_ends, dtype=np.int64)
    for i in range(n_ends):
        e = order[i]
        unrolled[e] = vertex[e] + (n_vertices if i <= best else 0)
    if evenodd:
        for q in range(1, n_ends + 1, 2):
            a = order[(best + q) % n_ends]
            b = order[(best + q + 1) % n_ends]
            _link(lanes, a, b, unrolled[b] - unrolled[a], _FORWARD)
        return 0, consistent
    # Matching ends like parentheses.
    stack = np.empty(n_ends, dtype=np.int64)
    top = 0
    count = base
    for q in range(1, n_ends + 1):
        e = order[(best + q) % n_ends]
        if kind[e] == _ARRIVE:
            if count >= 0:  # a lane starts here, counter-clockwise
                stack[top] = e
                top += 1
            else:           # the innermost clockwise lane ends at a start met before
                top -= 1
                d = stack[top]
                _link(lanes, e, d, unrolled[e] - unrolled[d], _BACKWARD)
            count += 1
        else:
            if count > 0:   # the innermost counter-clockwise lane ends here
                top -= 1
                a = stack[top]
                _link(lanes, a, e, unrolled[e] - unrolled[a], _FORWARD)
            else:           # a clockwise lane will end here
                stack[top] = e
                top += 1
            count -= 1
    return base, consistent


@borrowing
def _put_segment(out, v, paths, g, backwards):
    """Write segment g (`backwards`: run from its end: its control points reversed)."""
    d = np.int64(paths.degree[g])
    for k in range(4):
        src = k
        if backwards:
            src = d - k if k <= d else 0  # unused rows repeat the end: here, g's start
        out.controls[v, k, 0] = paths.controls[g, src, 0]
        out.controls[v, k, 1] = paths.controls[g, src, 1]
    out.degree[v] = paths.degree[g]


@borrowing
def _put_line(out, v, x0, y0, x1, y1):
    out.controls[v, 0, 0] = x0
    out.controls[v, 0, 1] = y0
    for k in range(1, 4):
        out.controls[v, k, 0] = x1
        out.controls[v, k, 1] = y1
    out.degree[v] = 1


@borrowing
def _is_point(controls, g):
    x0 = controls[g, 0, 0]
    y0 = controls[g, 0, 1]
    for k in range(1, 4):
        if controls[g, k, 0] != x0 or controls[g, k, 1] != y0:
            return False
    return True


@scalar
def _kept(n_segments, last_is_line):
    """Return how many of a ring's segments are written: its closing line is left to Z."""
    return n_segments - 1 if (n_segments >= 2 and last_is_line) else n_segments


@borrowing
def _put_loop(paths, out, s, v, r):
    """Count or write subpath s as it is (no zero-length segment, no closing line)."""
    a = paths.subpath_offsets[s]
    b = paths.subpath_offsets[s + 1]
    n = 0
    first = -1
    last_is_line = False
    for g in range(a, b):
        if not _is_point(paths.controls, g):
            n += 1
            last_is_line = paths.degree[g] == 1
            if first < 0:
                first = g
    n = _kept(n, last_is_line)
    if n == 0:
        return v, r
    if out.write:
        out.first[r] = v
        out.start[r, 0] = paths.controls[first, 0, 0]
        out.start[r, 1] = paths.controls[first, 0, 1]
        w = v
        for g in range(a, b):
            if w < v + n and not _is_point(paths.controls, g):
                _put_segment(out, w, paths, g, False)
                w += 1
    return v + n, r + 1


@borrowing
def _put_window(out, window, counter_clockwise, v, r):
    """Count or write the window's outline from (xmin, ymin) (its closing line left to Z)."""
    if out.write:
        out.first[r] = v
        out.start[r, 0] = window.xmin
        out.start[r, 1] = window.ymin
        if counter_clockwise:
            _put_line(out, v, window.xmin, window.ymin, window.xmax, window.ymin)
            _put_line(out, v + 1, window.xmax, window.ymin, window.xmax, window.ymax)
            _put_line(out, v + 2, window.xmax, window.ymax, window.xmin, window.ymax)
        else:
            _put_line(out, v, window.xmin, window.ymin, window.xmin, window.ymax)
            _put_line(out, v + 1, window.xmin, window.ymax, window.xmax, window.ymax)
            _put_line(out, v + 2, window.xmax, window.ymax, window.xmax, window.ymin)
    return v + 3, r + 1


@borrowing
def _step_edge(walk, bd, t, n_vertices):
    """Return the edge a lane step lies on: that of its counter-clockwise-first vertex."""
    o = walk.origin[t]
    return bd.vertex_edge[o if walk.step[t] == _FORWARD else (o - 1) % n_vertices]


@borrowing
def _vertex_point(bd, window, v):
    return _point_of(bd.vertex_edge[v], bd.vertex_along[v], window)


@borrowing
def _emit(paths, window, cut, bd, walk, ring, out, v, limit):
    """Count a ring's segments, writing the first `limit` of them from v.

    `ring` is (first step, end step, the step it starts at). Each chain's segments are
    copied (zero-length ones dropped; a chain run backwards, reversed); each lane's
    steps along one edge, in one direction, become one line. Returns (segments, whether
    the last one is a line).
    """
    i, top, first = ring
    n_steps = top - i
    n = 0
    last_is_line = False
    if walk.step[first] >= 0:
        c = walk.step[first] >> 1
        if walk.step[first] & 1:
            g = _chain_segment(paths, cut, c, cut.chain_count[c] - 1)
            cx = paths.controls[g, 3, 0]
            cy = paths.controls[g, 3, 1]
        else:
            g = cut.chain_first[c]
            cx = paths.controls[g, 0, 0]
            cy = paths.controls[g, 0, 1]
    else:
        cx, cy = _vertex_point(bd, window, walk.origin[first])
    n_vertices = walk.seen.shape[0]
    run_to = -1   # the vertex the pending line along an edge goes to (-1: none)
    run_edge = -1
    run_step = 0
    for q in range(n_steps + 1):
        t = i + (first - i + q) % n_steps
        step = walk.step[t] if q < n_steps else 0
        edge = -1
        if q < n_steps and step < 0:
            edge = _step_edge(walk, bd, t, n_vertices)
        if run_to >= 0 and (q == n_steps or step >= 0 or edge != run_edge
                            or step != run_step):
            x, y = _vertex_point(bd, window, run_to)
            if n < limit:
                _put_line(out, v + n, cx, cy, x, y)
            n += 1
            last_is_line = True
            cx = x
            cy = y
            run_to = -1
        if q == n_steps:
            break
        if step >= 0:
            c = step >> 1
            backwards = (step & 1) == 1
            count = cut.chain_count[c]
            for j in range(count):
                g = _chain_segment(paths, cut, c, count - 1 - j if backwards else j)
                if _is_point(paths.controls, g):
                    continue
                if n < limit:
                    _put_segment(out, v + n, paths, g, backwards)
                n += 1
                last_is_line = paths.degree[g] == 1
                cx = paths.controls[g, 0 if backwards else 3, 0]
                cy = paths.controls[g, 0 if backwards else 3, 1]
        else:
            o = walk.origin[t]
            run_to = (o + 1) % n_vertices if step == _FORWARD else (o - 1) % n_vertices
            run_edge = edge
            run_step = step
    return n, last_is_line


@borrowing
def _put_ring(paths, window, cut, bd, walk, i, top, out, v, r):
    """Count or write the ring of walk steps i..top-1; return the next (v, r).

    It starts at its first chain; a ring of lanes only (the window's outline) at a
    corner.
    """
    n_vertices = walk.seen.shape[0]
    first = -1
    for t in range(i, top):
        if walk.step[t] >= 0:
            first = t
            break
    if first < 0:
        for t in range(i, top):
            p = t - 1 if t > i else top - 1
            if _step_edge(walk, bd, t, n_vertices) != _step_edge(walk, bd, p, n_vertices):
                first = t
                break
        if first < 0:
            first = i
    ring = (i, top, first)
    n, last_is_line = _emit(paths, window, cut, bd, walk, ring, out, v, 0)
    n = _kept(n, last_is_line)
    if n == 0:
        return v, r
    if out.write:
        _emit(paths, window, cut, bd, walk, ring, out, v, n)
        out.first[r] = v
        out.start[r, 0] = out.controls[v, 0, 0]
        out.start[r, 1] = out.controls[v, 0, 1]
    return v + n, r + 1


@borrowing
def _arrive(paths, window, cut, bd, walk, here, top, out, v, r):
    """Step 4: the walk reaches vertex `here`; cut off the ring it closes, if any.

    Returns (top, v, r).
    """
    i = walk.seen[here]
    if i < 0:
        walk.seen[here] = top
        return top, v, r
    v, r = _put_ring(paths, window, cut, bd, walk, i, top, out, v, r)
    for t in range(i, top):
        walk.seen[walk.origin[t]] = -1
    walk.seen[here] = i
    return i, v, r


@borrowing
def _trace(paths, window, cut, bd, lanes, walk, c0, out, v, r, evenodd):
    """Step 4: follow chains and lanes from chain c0 round to it, writing rings on the way.

    A chain entered at its end runs backwards (evenodd only: nonzero's lanes join a
    chain's end to a chain's start). With `evenodd`, chain c0 is entered so that the
    lane after it runs counter-clockwise: the rings then have the painted side on their
    left (a pairing by parity runs every lane counter-clockwise from its first end).
    """
    n_vertices = walk.seen.shape[0]
    entry = 2 * c0
    if evenodd and lanes.lane_step[entry + 1] != _FORWARD:
        entry += 1
    here = lanes.vertex[entry]
    walk.seen[here] = 0
    top = 0
    e = entry
    while True:
        walk.visited[e >> 1] = True
        walk.step[top] = e  # 2c + 1: chain c entered at its end, run backwards
        walk.origin[top] = here
        top += 1
        out_end = e ^ 1
        here = lanes.vertex[out_end]
        top, v, r = _arrive(paths, window, cut, bd, walk, here, top, out, v, r)
        step = lanes.lane_step[out_end]
        for _ in range(lanes.lane_steps[out_end]):
            walk.step[top] = step
            walk.origin[top] = here
            top += 1
            here = (here + 1) % n_vertices if step == _FORWARD else (here - 1) % n_vertices
            top, v, r = _arrive(paths, window, cut, bd, walk, here, top, out, v, r)
        e = lanes.partner[out_end]
        if e == entry:
            break
    walk.seen[here] = -1
    return v, r


# Two curves are taken to cross once the boxes of their pieces still overlap after this
# many halvings of both (pieces 1/65536 of the segment), or after the test's budget of
# piece pairs is spent: a test that only errs towards "crossing", whose cost is a
# rebuild subpath by subpath. Measured on the glyph page (3000 glyph-like paths whose
# contours overlap, evenodd, 1 thread): depth 24 and 4096 pairs took the clean pass
# from 0.9 ms without the test to 5.6 ms; depth 16 and 1024 pairs, to 1.5 ms.
_CROSS_DEPTH = 16
_CROSS_BUDGET = 1024
_CROSS_STACK = 4 * _CROSS_DEPTH + 4


@borrowing
def _may_cross(paths, g1, g2, stack):
    """Return whether segments g1 and g2 may meet: their pieces' boxes never part.

    Both are halved in turn (depth-first, with `stack`) while the control-point boxes of
    their pieces overlap (touching counts); pieces whose boxes part cannot meet (a curve
    lies in the hull of its control points).
    """
    controls = paths.controls
    d1 = np.int64(paths.degree[g1])
    d2 = np.int64(paths.degree[g2])
    stack[0, 0] = 0.0
    stack[0, 1] = 1.0
    stack[0, 2] = 0.0
    stack[0, 3] = 1.0
    stack[0, 4] = 0.0
    top = 1
    budget = _CROSS_BUDGET
    while top > 0:
        top -= 1
        a0 = stack[top, 0]
        a1 = stack[top, 1]
        b0 = stack[top, 2]
        b1 = stack[top, 3]
        depth = stack[top, 4]
        p = _box(d1, controls, g1, a0, a1)
        q = _box(d2, controls, g2, b0, b1)
        if p[2] < q[0] or q[2] < p[0] or p[3] < q[1] or q[3] < p[1]:
            continue
        budget -= 1
        if depth >= _CROSS_DEPTH or budget <= 0 or top + 4 > stack.shape[0]:
            return True
        am = 0.5 * (a0 + a1)
        bm = 0.5 * (b0 + b1)
        for k in range(4):
            stack[top, 0] = a0 if k < 2 else am
            stack[top, 1] = am if k < 2 else a1
            stack[top, 2] = b0 if k % 2 == 0 else bm
            stack[top, 3] = bm if k % 2 == 0 else b1
            stack[top, 4] = depth + 1.0
            top += 1
    return False


@borrowing
def _box(degree, controls, g, a, b):
    """Return the box (lo_x, lo_y, hi_x, hi_y) of the control points of piece [a, b] of g."""
    x0, x1, x2, x3 = piece_values(degree, controls[g, 0, 0], controls[g, 1, 0],
                                  controls[g, 2, 0], controls[g, 3, 0], a, b)
    y0, y1, y2, y3 = piece_values(degree, controls[g, 0, 1], controls[g, 1, 1],
                                  controls[g, 2, 1], controls[g, 3, 1], a, b)
    return (min(min(x0, x1), min(x2, x3)), min(min(y0, y1), min(y2, y3)),
            max(max(x0, x1), max(x2, x3)), max(max(y0, y1), max(y2, y3)))


@allocating
def _outlines_cross(paths, cut, n_chains, lanes):
    """Return whether two chains of different subpaths, in one walk, may cross.

    A walk joins chains by the lanes whatever subpath they come from; where two input
    outlines cross each other inside the window, a ring through both would cross
    itself. Chains of one outline never cross (the outline is taken to be simple).
    """
    if n_chains < 2:
        return False
    walk_of = np.full(n_chains, -1, dtype=np.int64)
    n_walks = 0
    mixed = False
    for c0 in range(n_chains):
        if walk_of[c0] >= 0:
            continue
        e = 2 * c0
        while walk_of[e >> 1] < 0:
            walk_of[e >> 1] = n_walks
            mixed = mixed or cut.chain_sub[e >> 1] != cut.chain_sub[c0]
            e = lanes.partner[e ^ 1]
        n_walks += 1
    if not mixed:
        return False
    box = np.empty((n_chains, 4), dtype=np.float64)
    for c in range(n_chains):
        box[c, 0] = np.inf
        box[c, 1] = np.inf
        box[c, 2] = -np.inf
        box[c, 3] = -np.inf
        for j in range(cut.chain_count[c]):
            g = _chain_segment(paths, cut, c, j)
            for k in range(4):
                box[c, 0] = min(box[c, 0], paths.controls[g, k, 0])
                box[c, 1] = min(box[c, 1], paths.controls[g, k, 1])
                box[c, 2] = max(box[c, 2], paths.controls[g, k, 0])
                box[c, 3] = max(box[c, 3], paths.controls[g, k, 1])
    stack = np.empty((_CROSS_STACK, 5), dtype=np.float64)
    for c1 in range(n_chains):
        for c2 in range(c1 + 1, n_chains):
            if walk_of[c1] != walk_of[c2] or cut.chain_sub[c1] == cut.chain_sub[c2]:
                continue
            if box[c1, 2] < box[c2, 0] or box[c2, 2] < box[c1, 0] or \
                    box[c1, 3] < box[c2, 1] or box[c2, 3] < box[c1, 1]:
                continue
            for j1 in range(cut.chain_count[c1]):
                g1 = _chain_segment(paths, cut, c1, j1)
                for j2 in range(cut.chain_count[c2]):
                    g2 = _chain_segment(paths, cut, c2, j2)
                    if _may_cross(paths, g1, g2, stack):
                        return True
    return False


# What `_clean_subpaths` found.
_DONE = 0
_CROSSED = 1         # outlines of different subpaths may cross: nothing written
_INCONSISTENT = 2    # the edge lines do not add up (a bug upstream): nothing written


@allocating
def _clean_subpaths(paths, window, out, s_lo, s_hi, whole, v, r, evenodd):
    """Count or write the rings of subpaths s_lo..s_hi-1 from segment v and ring r.

    Returns (status, v, r). With `whole` (the path's subpaths together), nothing is
    written when two outlines may cross (`_CROSSED`): the caller then takes them one
    by one.
    """
    controls = paths.controls
    g_lo = paths.subpath_offsets[s_lo]
    g_hi = paths.subpath_offsets[s_hi]
    m = g_hi - g_lo
    k = s_hi - s_lo
    cut = Cut(np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64),
              np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64),
              np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64),
              np.empty(k + 1, dtype=np.int64), np.empty(k, dtype=np.bool_))
    for g in range(g_lo, g_hi):
        cut.kind[g - g_lo] = _segment_kind(controls, g, window)
    n_chains, n_edges = _cut(paths, window, s_lo, s_hi, g_lo, cut)
    q = 2 * (n_chains + n_edges) + 4
    bd = Boundary(np.empty(q, dtype=np.int64), np.empty(q, dtype=np.float64),
                  np.empty(q, dtype=np.bool_), np.empty(q, dtype=np.int64),
                  np.empty(q, dtype=np.int64), np.empty(q + 1, dtype=np.int64),
                  np.empty(q, dtype=np.int64), np.empty(q, dtype=np.float64),
                  np.empty(q, dtype=np.int64))
    n_positions, n_vertices = _boundary_points(paths, window, cut, n_chains, n_edges, bd)
    _lane_counts(paths, cut, n_chains, n_edges, n_positions, bd)
    lanes = Lanes(np.empty(2 * n_chains, dtype=np.int64),
                  np.empty(2 * n_chains, dtype=np.int64),
                  np.empty(2 * n_chains, dtype=np.int64),
                  np.empty(2 * n_chains, dtype=np.int64))
    base, consistent = _match(paths, cut, n_chains, n_vertices, bd, lanes, evenodd)
    if not consistent:
        return _INCONSISTENT, v, r
    if whole and k > 1 and _outlines_cross(paths, cut, n_chains, lanes):
        return _CROSSED, v, r
    for _ in range(abs(base)):
        v, r = _put_window(out, window, base > 0, v, r)
    steps = n_chains
    for c in range(n_chains):
        steps += max(lanes.lane_steps[2 * c], lanes.lane_steps[2 * c + 1])
    walk = Walk(np.empty(steps, dtype=np.int64), np.empty(steps, dtype=np.int64),
                np.full(n_vertices, -1, dtype=np.int64), np.zeros(n_chains, dtype=np.bool_))
    for s in range(s_lo, s_hi):
        if cut.sub_loop[s - s_lo]:
            v, r = _put_loop(paths, out, s, v, r)
            continue
        for c in range(cut.sub_chains[s - s_lo], cut.sub_chains[s - s_lo + 1]):
            if not walk.visited[c]:
                v, r = _trace(paths, window, cut, bd, lanes, walk, c, out, v, r, evenodd)
    return _DONE, v, r


@borrowing
def _clean_path(paths, window, out, p, v, r, evenodd):
    """Count or write path p's rings from segment v and ring r; return their counts.

    The path's subpaths together (their boundary runs add up: a hole open to the edge
    joins its shell's ring), or one by one where two of their outlines may cross.
    (-1, -1): the edge lines' counts disagree with the chains' ends (never, for the
    output of the fill clip).
    """
    controls = paths.controls
    s_lo = paths.path_offsets[p]
    s_hi = paths.path_offsets[p + 1]
    g_lo = paths.subpath_offsets[s_lo]
    g_hi = paths.subpath_offsets[s_hi]
    v0 = v
    r0 = r
    touches = False
    for g in range(g_lo, g_hi):
        if _on_boundary(controls[g, 0, 0], controls[g, 0, 1], window):
            touches = True
            break
    if not touches:  # no vertex on the boundary: every subpath is a loop
        for s in range(s_lo, s_hi):
            v, r = _put_loop(paths, out, s, v, r)
        return v - v0, r - r0
    status, v, r = _clean_subpaths(paths, window, out, s_lo, s_hi, True, v, r, evenodd)
    if status == _CROSSED:
        for s in range(s_lo, s_hi):
            status, v, r = _clean_subpaths(paths, window, out, s, s + 1, False, v, r, evenodd)
            if status != _DONE:
                break
    if status == _INCONSISTENT:
        return -1, -1
    return v - v0, r - r0


@borrowing
def _clean_paths(paths, windows, layout, out, p0, p1, evenodd):
    """Count or write the rings of paths p0..p1-1 (one block), each in its window."""
    for p in range(p0, p1):
        window = window_of(windows.bounds, windows.index, p)
        v = 0
        r = 0
        if out.write:
            v = layout.segment_start[p]
            r = layout.ring_start[p]
        n_segments, n_rings = _clean_path(paths, window, out, p, v, r, evenodd)
        if not out.write:
            layout.n_segments[p] = n_segments
            layout.n_rings[p] = n_rings


@parallel
def clean_fill_paths(paths, windows, layout, out, block_size, evenodd):
    """Count (``out.write`` False) or write the clean rings of each filled path.

    `paths` (`FillPaths`) is the fill clip's output for `windows` (`records.WindowRows`:
    path p's window is ``window_of(windows.bounds, windows.index, p)``): closed
    subpaths inside their closed window, each segment starting where the one
    before it ends and the last ending at its subpath's start. The count pass stores
    each path's output size in ``layout.n_segments`` and ``layout.n_rings`` (-1 for a
    path whose edge lines do not add up: a bug upstream); the write pass writes path
    p's rings from ``layout.segment_start[p]`` and ``layout.ring_start[p]`` on: control
    points, degrees, and each ring's first segment and start point (every ring is
    closed; its closing line is implicit). `evenodd`: the paths are filled by the
    even-odd rule (the rings need keep only the parity of winding numbers), else by the
    nonzero rule (they keep the winding numbers). Paths go `block_size` to a block,
    blocks in parallel.
    """
    n = paths.path_offsets.shape[0] - 1
    n_blocks = (n + block_size - 1) // block_size
    for blk in prange(n_blocks):
        _clean_paths(paths, windows, layout, out, blk * block_size,
                     min(n, (blk + 1) * block_size), evenodd)
