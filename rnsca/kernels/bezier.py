"""RNSCA for Bézier paths: clip lines, quadratics and cubics, keeping curves as curves.

A segment of degree d (1, 2 or 3) is given by its control points; a *piece* is the
segment restricted to a parameter interval [a, b], whose control points come from the
blossom (`piece_values`). RNSCA's test for a piece uses the outcodes of its control
points (the curve lies in their convex hull): all zero, accept the piece whole; AND
non-zero, reject it whole; otherwise split it into N pieces of equal parameter length
and recurse, with an explicit stack. What happens at an undecided leaf:

- exact (``curves="preserve"``): find where the piece crosses the four edge lines,
  root by root on monotone stretches (`edge_breaks`), and keep the stretches between
  crossings whose middle is in the window. Visible stretches are output as pieces of
  the same degree, their cut ends snapped onto the edge they cross;
- approx: drop the leaf (no root is ever computed; the output stays in the window);
- flatten (``curves="flatten"``): subdivide until a piece is flat within `tolerance`,
  then clip its chord as a line; accepted pieces are flattened into lines.

Open paths (strokes) give their visible parts as separate subpaths. Filled paths
(``fill``) give closed subpaths whose fill inside the window is the input's: each part
outside is replaced by its projection onto the window's boundary (the clamped curve).
Moving a point outside the window to its clamp never passes through the window's
interior, so the winding number of every interior point is unchanged; both fill rules
see the same shape. A part outside that stays beyond one edge projects onto that edge,
a contractible segment, so it is replaced by the straight line between its clamped
ends, and consecutive such lines along one edge are merged.

Two passes (count, write) over one body per block of subpaths, `prange` over the blocks;
the write pass takes each run's decision from the count pass instead of testing it again.
"""

import numpy as np
from numba import prange

# The device's segment classes, the run decisions (kept by the count pass for the write
# pass) and the stack's size are defined in rnsca.constants (shared with clip.cl);
# importable from here as before.
from rnsca.constants import CURVE_RUN_ACCEPTED as _RUN_ACCEPTED
from rnsca.constants import CURVE_RUN_REJECTED as _RUN_REJECTED
from rnsca.constants import CURVE_RUN_SEGMENTED as _RUN_SEGMENTED
from rnsca.constants import (
    CURVE_STACK_CAPACITY,
    SEGMENT_ACCEPTED,
    SEGMENT_AMBIGUOUS,
    SEGMENT_REJECTED,
)
from rnsca.kernels import counters as C
from rnsca.kernels.jit import borrowing, parallel, scalar
from rnsca.kernels.outcode import BOTTOM, LEFT, RIGHT, TOP, clamp, outcode

# Helpers that take arrays are `borrowing` (no reference counting of their arrays): a
# call then costs no more than passing the arrays' fields, and LLVM inlines the small
# ones (measured: Numba's own inlining of them, which this module used, gains nothing).

__all__ = [
    "BREAK_CAPACITY",
    "CURVE_N_AUTO",
    "RUN_SEGMENTS",
    "EXACT_LEAF_DEPTH",
    "SEGMENT_ACCEPTED",
    "SEGMENT_AMBIGUOUS",
    "SEGMENT_REJECTED",
    "clip_path_blocks",
    "closing_edges",
    "edge_breaks",
    "flatten_count",
    "flatten_into",
    "flatten_segments",
    "flatten_steps",
    "piece_values",
    "point_value",
]

# n="auto" for curves: a piece's test costs a blossom of its control points, the same
# for any N; 4 halves the ambiguous parameter range twice per level.
CURVE_N_AUTO = 4
# Exact mode: ambiguous pieces are split this deep (at most) before their edge
# crossings are solved. Measured on the benchmark curves (1 thread, 100,000 cubics):
# depth 0 / 1 / 2 / 3 took 8.0 / 9.3 / 10.9 / 12.2 ms: a piece's test costs a blossom of
# its control points, a crossing about a dozen evaluations, so deeper splits do not pay
# in exact mode (they do in approx mode, which has no other way to decide a piece).
EXACT_LEAF_DEPTH = 0
# Break points of one leaf: its two ends and at most 3 crossings with each edge line.
BREAK_CAPACITY = 16
# Runs of this many segments are tested whole by the box of their control points
# before any segment is (run-level RNSCA, as for polylines): a path that lies mostly
# inside or outside is copied or skipped a run at a time.
RUN_SEGMENTS = 16

# Float state of the subpath being clipped (see `_emit_piece`, `_clamp_to`).
_CUR_X = 0        # current point: the end of the output so far
_CUR_Y = 1
_RUN_X = 2        # start of the last boundary line (fill), which may be extended
_RUN_Y = 3
_AREA = 4         # twice the signed area swept by the boundary lines (fill)
_PEND_A = 5       # pending visible parameter interval of the current segment
_PEND_B = 6
_START_X = 7      # the input subpath's start point
_START_Y = 8
_FLOAT_STATE_WIDTH = 9
# Integer state.
_V = 0            # next output segment
_S = 1            # next output subpath
_OPEN = 2         # a chain is open: the next piece may continue it
_LAST_RUN = 3     # the last output segment is a boundary line (fill)
_VISIBLE = 4      # some part of the input subpath is visible
_BROKEN = 5       # some part of the input subpath is not visible (strokes)
_PEND = 6         # a visible interval is pending
_PEND_EA = 7      # edges the pending interval's ends were cut at (bit masks)
_PEND_EB = 8
_FIRST_AT_START = 9  # the subpath's first chain starts at its start point (strokes)
_V_END = 10       # end of the subpath's counted output: a closing line dropped later
                  # (a whole closed stroke: Z draws it) is not written past it
_INT_STATE_WIDTH = 11


@scalar
def _lerp(a, b, t):
    # Exact at both ends (t = 0 gives a, t = 1 gives b) and where a == b, so a curve
    # along an edge line stays exactly on it: measured from the nearer end.
    return a + t * (b - a) if t < 0.5 else b - (1.0 - t) * (b - a)


@scalar
def _blossom(degree, a0, a1, a2, a3, u1, u2, u3):
    """Return the blossom of the 1-D Bézier (a0..a_degree) at (u1, .., u_degree)."""
    if degree == 1:
        return _lerp(a0, a1, u1)
    if degree == 2:
        return _lerp(_lerp(a0, a1, u1), _lerp(a1, a2, u1), u2)
    b0 = _lerp(a0, a1, u1)
    b1 = _lerp(a1, a2, u1)
    b2 = _lerp(a2, a3, u1)
    return _lerp(_lerp(b0, b1, u2), _lerp(b1, b2, u2), u3)


@scalar
def point_value(degree, a0, a1, a2, a3, t):
    """Return the 1-D Bézier (a0..a_degree) at parameter t (de Casteljau)."""
    return _blossom(degree, a0, a1, a2, a3, t, t, t)


@scalar
def piece_values(degree, a0, a1, a2, a3, s, t):
    """Return the 1-D control values of the piece [s, t]; unused slots repeat the end.

    Control value i is the blossom at (s, .., s, t, .., t) with i times t, so the ends
    are the curve's points at s and t, exactly as `point_value` gives them.
    """
    if degree == 1:
        q1 = _blossom(1, a0, a1, a2, a3, t, t, t)
        return _blossom(1, a0, a1, a2, a3, s, s, s), q1, q1, q1
    if degree == 2:
        q2 = _blossom(2, a0, a1, a2, a3, t, t, t)
        return (_blossom(2, a0, a1, a2, a3, s, s, s), _blossom(2, a0, a1, a2, a3, s, t, t),
                q2, q2)
    return (_blossom(3, a0, a1, a2, a3, s, s, s), _blossom(3, a0, a1, a2, a3, s, s, t),
            _blossom(3, a0, a1, a2, a3, s, t, t), _blossom(3, a0, a1, a2, a3, t, t, t))


@scalar
def _hull_codes(degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax, ymax):
    """Return (OR, AND) of the outcodes of the control points."""
    c0 = outcode(x0, y0, xmin, ymin, xmax, ymax)
    c1 = outcode(x1, y1, xmin, ymin, xmax, ymax)
    c_or = c0 | c1
    c_and = c0 & c1
    if degree >= 2:
        c2 = outcode(x2, y2, xmin, ymin, xmax, ymax)
        c_or |= c2
        c_and &= c2
    if degree == 3:
        c3 = outcode(x3, y3, xmin, ymin, xmax, ymax)
        c_or |= c3
        c_and &= c3
    return c_or, c_and


@scalar
def flatten_count(degree, x0, x1, x2, x3, y0, y1, y2, y3, tol):
    """Return how many equal parameter steps flatten the curve within `tol`.

    Uniform subdivision into n chords deviates from the curve by at most
    ``d (d - 1) / 8 * max |second difference of the control points| / n**2``.
    """
    if degree == 1:
        return 1
    if degree == 2:
        m = np.hypot(x0 - 2.0 * x1 + x2, y0 - 2.0 * y1 + y2) * 0.25
    else:
        m = 0.75 * max(np.hypot(x0 - 2.0 * x1 + x2, y0 - 2.0 * y1 + y2),
                       np.hypot(x1 - 2.0 * x2 + x3, y1 - 2.0 * y2 + y3))
    if not (m > tol):
        return 1
    n = np.ceil(np.sqrt(m / tol))
    return int(min(n, 1.0e6))


@scalar
def _critical_points(degree, a0, a1, a2, a3):
    """Return up to two parameters in (0, 1) where the 1-D Bézier's derivative is 0.

    Missing ones are -1; the two are in increasing order.
    """
    if degree == 1:
        return -1.0, -1.0
    if degree == 2:
        den = (a1 - a0) - (a2 - a1)
        if den == 0.0:
            return -1.0, -1.0
        t = (a1 - a0) / den
        return (t if 0.0 < t < 1.0 else -1.0), -1.0
    # Derivative / 3 = d0 (1-t)^2 + 2 d1 t (1-t) + d2 t^2 = A t^2 + B t + C.
    d0 = a1 - a0
    d1 = a2 - a1
    d2 = a3 - a2
    qa = d0 - 2.0 * d1 + d2
    qb = 2.0 * (d1 - d0)
    qc = d0
    r0 = -1.0
    r1 = -1.0
    if qa == 0.0:
        if qb != 0.0:
            r0 = -qc / qb
    else:
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            # The stable pair: no cancellation between -b and the root.
            q = -0.5 * (qb + np.copysign(np.sqrt(disc), qb))
            r0 = q / qa
            r1 = qc / q if q != 0.0 else -1.0
    if not (0.0 < r0 < 1.0):
        r0 = -1.0
    if not (0.0 < r1 < 1.0):
        r1 = -1.0
    if r0 < 0.0 or (r1 >= 0.0 and r1 < r0):
        r0, r1 = r1, r0
    return r0, r1


@borrowing
def _solve_monotone(degree, a0, a1, a2, a3, level, u, v, gu, gv, st):
    """Return the root of ``B(t) = level`` in [u, v], B monotone there.

    ``gu = B(u) - level`` and ``gv = B(v) - level`` have opposite signs.

    Illinois regula falsi, safeguarded by bisection, to adjacent floats.
    """
    side = 0
    st[C.INTERSECTIONS] += 1
    for _ in range(200):
        t = (u * gv - v * gu) / (gv - gu)
        if not (u < t < v):
            t = 0.5 * (u + v)
            if not (u < t < v):
                break
        g = point_value(degree, a0, a1, a2, a3, t) - level
        if g == 0.0:
            return t
        if (g < 0.0) == (gu < 0.0):
            u = t
            gu = g
            if side == -1:
                gv *= 0.5
            side = -1
        else:
            v = t
            gv = g
            if side == 1:
                gu *= 0.5
            side = 1
    return u if abs(point_value(degree, a0, a1, a2, a3, u) - level) <= \
        abs(point_value(degree, a0, a1, a2, a3, v) - level) else v


@borrowing
def _add_break(brk_t, brk_e, n, t, edge_bit):
    if n < brk_t.shape[0]:
        brk_t[n] = t
        brk_e[n] = edge_bit
        n += 1
    return n


@borrowing
def _line_roots(degree, a0, a1, a2, a3, s0, s1, s2, s3, level, edge_bit, lo, hi, brk_t,
                brk_e, n, st):
    """Add to the break table the parameters in [lo, hi] where B(t) crosses `level`.

    s0..s3 are the control values of the piece [lo, hi] (shared by the two edge lines
    of an axis).
    """
    below = (s0 < level) | (s1 < level) | (s2 < level) | (s3 < level)
    above = (s0 > level) | (s1 > level) | (s2 > level) | (s3 > level)
    if not (below and above) and not (s0 == level or s3 == level):
        return n  # the piece stays on one side (or lies on the line): no crossing
    c0, c1 = _critical_points(degree, a0, a1, a2, a3)
    u = lo
    gu = point_value(degree, a0, a1, a2, a3, u) - level
    if gu == 0.0:
        n = _add_break(brk_t, brk_e, n, u, edge_bit)
    for k in range(3):
        v = hi
        if k == 0 and lo < c0 < hi:
            v = c0
        elif k <= 1 and lo < c1 < hi and c1 > u:
            v = c1
        if v <= u:
            continue
        gv = point_value(degree, a0, a1, a2, a3, v) - level
        if gv == 0.0:
            n = _add_break(brk_t, brk_e, n, v, edge_bit)
        elif (gu < 0.0) != (gv < 0.0) and gu != 0.0:
            n = _add_break(brk_t, brk_e, n,
                           _solve_monotone(degree, a0, a1, a2, a3, level, u, v, gu, gv, st),
                           edge_bit)
        u = v
        gu = gv
        if u >= hi:
            break
    return n


@borrowing
def edge_breaks(degree, x0, x1, x2, x3, y0, y1, y2, y3, lo, hi, xmin, ymin, xmax, ymax,
                brk_t, brk_e, st):
    """Fill the break table of the piece [lo, hi]; return its length.

    ``brk_t[0] = lo < ... < brk_t[n-1] = hi`` with ``brk_e[k]`` the bits (LEFT, RIGHT,
    BOTTOM, TOP) of the edge lines the curve crosses or touches at ``brk_t[k]``. Between
    two breaks the piece lies in one of the nine regions the edge lines make.
    """
    n = _add_break(brk_t, brk_e, 0, lo, 0)
    if lo == 0.0 and hi == 1.0:
        # The whole segment: its control values are the piece's (unused rows repeat
        # the end, as piece_values does), no blossoms needed.
        sx0, sx1, sx2, sx3 = x0, x1, x2, x3
        sy0, sy1, sy2, sy3 = y0, y1, y2, y3
    else:
        sx0, sx1, sx2, sx3 = piece_values(degree, x0, x1, x2, x3, lo, hi)
        sy0, sy1, sy2, sy3 = piece_values(degree, y0, y1, y2, y3, lo, hi)
    n = _line_roots(degree, x0, x1, x2, x3, sx0, sx1, sx2, sx3, xmin, LEFT, lo, hi, brk_t,
                    brk_e, n, st)
    n = _line_roots(degree, x0, x1, x2, x3, sx0, sx1, sx2, sx3, xmax, RIGHT, lo, hi, brk_t,
                    brk_e, n, st)
    n = _line_roots(degree, y0, y1, y2, y3, sy0, sy1, sy2, sy3, ymin, BOTTOM, lo, hi, brk_t,
                    brk_e, n, st)
    n = _line_roots(degree, y0, y1, y2, y3, sy0, sy1, sy2, sy3, ymax, TOP, lo, hi, brk_t,
                    brk_e, n, st)
    n = _add_break(brk_t, brk_e, n, hi, 0)
    # Insertion sort (at most BREAK_CAPACITY entries), then merge equal parameters.
    for i in range(1, n):
        t = brk_t[i]
        e = brk_e[i]
        j = i - 1
        while j >= 0 and brk_t[j] > t:
            brk_t[j + 1] = brk_t[j]
            brk_e[j + 1] = brk_e[j]
            j -= 1
        brk_t[j + 1] = t
        brk_e[j + 1] = e
    m = 0
    for i in range(n):
        t = min(max(brk_t[i], lo), hi)
        if m > 0 and brk_t[m - 1] == t:
            brk_e[m - 1] |= brk_e[i]
        else:
            brk_t[m] = t
            brk_e[m] = brk_e[i]
            m += 1
    return m


@scalar
def _snap(x, y, edges, xmin, ymin, xmax, ymax):
    """Return the point moved exactly onto the edge lines it was found on."""
    if edges & LEFT:
        x = xmin
    elif edges & RIGHT:
        x = xmax
    if edges & BOTTOM:
        y = ymin
    elif edges & TOP:
        y = ymax
    return x, y


@borrowing
def _advance(n, x, y, si, sf):
    """Count `n` visible segments appended to the output, ending at (x, y)."""
    si[_V] += n
    si[_LAST_RUN] = 0
    si[_VISIBLE] = 1
    sf[_CUR_X] = x
    sf[_CUR_Y] = y


@borrowing
def _put_segment(write, degree, x0, x1, x2, x3, y0, y1, y2, y3, out_ctrl, out_deg, si, sf):
    """Append a visible segment (unused control slots repeat its end)."""
    v = si[_V]
    if write and v < si[_V_END]:
        out_ctrl[v, 0, 0] = x0
        out_ctrl[v, 1, 0] = x1
        out_ctrl[v, 2, 0] = x2
        out_ctrl[v, 3, 0] = x3
        out_ctrl[v, 0, 1] = y0
        out_ctrl[v, 1, 1] = y1
        out_ctrl[v, 2, 1] = y2
        out_ctrl[v, 3, 1] = y3
        out_deg[v] = degree
    _advance(1, x3, y3, si, sf)


@borrowing
def _run_box(controls, a, b):
    """Return the bounding box (lo_x, lo_y, hi_x, hi_y) of the control points of a..b-1."""
    lo_x = controls[a, 0, 0]
    hi_x = lo_x
    lo_y = controls[a, 0, 1]
    hi_y = lo_y
    for i in range(a, b):
        for k in range(1, 4):  # slot 0 is the previous segment's end (slot 3)
            x = controls[i, k, 0]
            y = controls[i, k, 1]
            lo_x = min(lo_x, x)
            hi_x = max(hi_x, x)
            lo_y = min(lo_y, y)
            hi_y = max(hi_y, y)
    return lo_x, lo_y, hi_x, hi_y


@borrowing
def _put_run(write, controls, degree, a, b, out_ctrl, out_deg, si, sf):
    """Append the input segments a..b-1, accepted whole (a continuous run)."""
    v = si[_V]
    n = b - a
    if write:
        # One loop over the rows without a test per row: LLVM vectorizes the copy.
        n_copy = min(n, si[_V_END] - v)
        for i in range(n_copy):
            for k in range(4):
                out_ctrl[v + i, k, 0] = controls[a + i, k, 0]
                out_ctrl[v + i, k, 1] = controls[a + i, k, 1]
        for i in range(n_copy):
            out_deg[v + i] = degree[a + i]
    _advance(n, controls[b - 1, 3, 0], controls[b - 1, 3, 1], si, sf)


@borrowing
def _put_line(write, x, y, out_ctrl, out_deg, si, sf):
    """Append a line from the current point to (x, y)."""
    v = si[_V]
    if write and v < si[_V_END]:
        out_ctrl[v, 0, 0] = sf[_CUR_X]
        out_ctrl[v, 0, 1] = sf[_CUR_Y]
        for k in range(1, 4):
            out_ctrl[v, k, 0] = x
            out_ctrl[v, k, 1] = y
        out_deg[v] = 1
    si[_V] = v + 1
    sf[_CUR_X] = x
    sf[_CUR_Y] = y


@borrowing
def _begin_subpath(write, x, y, source, out_first, out_start, out_from, si, sf):
    s = si[_S]
    if write:
        out_first[s] = si[_V]
        out_start[s, 0] = x
        out_start[s, 1] = y
        out_from[s] = source
    si[_S] = s + 1
    si[_OPEN] = 1
    si[_LAST_RUN] = 0
    sf[_CUR_X] = x
    sf[_CUR_Y] = y


@borrowing
def _arrive_at(write, fill, x0, y0, source, out_ctrl, out_deg, out_first, out_start, out_from,
               si, sf):
    """Make (x0, y0) the current point before visible output that starts there."""
    if fill:
        if x0 != sf[_CUR_X] or y0 != sf[_CUR_Y]:
            # Rounding left a gap between the clamped path and the piece: bridge it.
            _put_line(write, x0, y0, out_ctrl, out_deg, si, sf)
    elif si[_OPEN] == 0 or x0 != sf[_CUR_X] or y0 != sf[_CUR_Y]:
        if si[_VISIBLE] == 0 and si[_BROKEN] == 0:
            si[_FIRST_AT_START] = 1  # nothing before it: it starts at t = 0
        _begin_subpath(write, x0, y0, source, out_first, out_start, out_from, si, sf)


@borrowing
def _emit_piece(write, fill, degree, x0, x1, x2, x3, y0, y1, y2, y3, source, out_ctrl,
                out_deg, out_first, out_start, out_from, si, sf):
    """Add a visible piece (control points x0..x3, y0..y3) to the output."""
    _arrive_at(write, fill, x0, y0, source, out_ctrl, out_deg, out_first, out_start, out_from,
               si, sf)
    _put_segment(write, degree, x0, x1, x2, x3, y0, y1, y2, y3, out_ctrl, out_deg, si, sf)


@borrowing
def _clamp_to(write, x, y, xmin, ymin, xmax, ymax, out_ctrl, out_deg, si, sf):
    """Fill: continue the output along the boundary to the clamp of (x, y)."""
    cx = clamp(x, xmin, xmax)
    cy = clamp(y, ymin, ymax)
    ux = sf[_CUR_X]
    uy = sf[_CUR_Y]
    if cx == ux and cy == uy:
        return
    rx = sf[_RUN_X]
    ry = sf[_RUN_Y]
    same_edge = ((rx == ux) & (ux == cx) & ((cx == xmin) | (cx == xmax))) | \
        ((ry == uy) & (uy == cy) & ((cy == ymin) | (cy == ymax)))
    if si[_LAST_RUN] == 1 and same_edge:
        # Extend the last boundary line instead of adding one along the same edge.
        sf[_AREA] += (rx * cy - cx * ry) - (rx * uy - ux * ry)
        if cx == rx and cy == ry:
            si[_V] -= 1  # back where the line began: drop it
            si[_LAST_RUN] = 0
        elif write and si[_V] - 1 < si[_V_END]:
            v = si[_V] - 1
            for k in range(1, 4):
                out_ctrl[v, k, 0] = cx
                out_ctrl[v, k, 1] = cy
        sf[_CUR_X] = cx
        sf[_CUR_Y] = cy
        return
    sf[_AREA] += ux * cy - cx * uy
    sf[_RUN_X] = ux
    sf[_RUN_Y] = uy
    _put_line(write, cx, cy, out_ctrl, out_deg, si, sf)
    si[_LAST_RUN] = 1


@borrowing
def _outside(write, fill, x, y, xmin, ymin, xmax, ymax, out_ctrl, out_deg, si, sf):
    """Mark the part ending at (x, y) not visible: clamp to it (fill), or end the chain."""
    si[_BROKEN] = 1
    if fill:
        _clamp_to(write, x, y, xmin, ymin, xmax, ymax, out_ctrl, out_deg, si, sf)
    else:
        si[_OPEN] = 0


@borrowing
def _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax,
           ymax, tol, source, out_ctrl, out_deg, out_first, out_start, out_from, si, sf):
    """Output the pending visible interval of the segment, if any."""
    if si[_PEND] == 0:
        return
    si[_PEND] = 0
    a = sf[_PEND_A]
    b = sf[_PEND_B]
    if not flatten or degree == 1:
        _emit_stretch(write, fill, degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, si[_PEND_EA],
                      si[_PEND_EB], xmin, ymin, xmax, ymax, source, out_ctrl, out_deg,
                      out_first, out_start, out_from, si, sf)
        return
    qx0, qx1, qx2, qx3 = piece_values(degree, x0, x1, x2, x3, a, b)
    qy0, qy1, qy2, qy3 = piece_values(degree, y0, y1, y2, y3, a, b)
    sx, sy = _snap(qx0, qy0, si[_PEND_EA], xmin, ymin, xmax, ymax)
    ex, ey = _snap(qx3, qy3, si[_PEND_EB], xmin, ymin, xmax, ymax)
    steps = flatten_count(degree, qx0, qx1, qx2, qx3, qy0, qy1, qy2, qy3, tol)
    prev_x = sx
    prev_y = sy
    for k in range(1, steps + 1):
        if k == steps:
            nx = ex
            ny = ey
        else:
            t = a + (b - a) * k / steps
            nx = point_value(degree, x0, x1, x2, x3, t)
            ny = point_value(degree, y0, y1, y2, y3, t)
        _emit_piece(write, fill, 1, prev_x, nx, nx, nx, prev_y, ny, ny, ny, source, out_ctrl,
                    out_deg, out_first, out_start, out_from, si, sf)
        prev_x = nx
        prev_y = ny


@borrowing
def _emit_stretch(write, fill, degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, edges_a, edges_b,
                  xmin, ymin, xmax, ymax, source, out_ctrl, out_deg, out_first,
                  out_start, out_from, si, sf):
    """Output the visible stretch [a, b] of a segment as a piece of its degree."""
    qx0, qx1, qx2, qx3 = piece_values(degree, x0, x1, x2, x3, a, b)
    qy0, qy1, qy2, qy3 = piece_values(degree, y0, y1, y2, y3, a, b)
    sx, sy = _snap(qx0, qy0, edges_a, xmin, ymin, xmax, ymax)
    # piece_values repeats the end in the unused slots: qx3, qy3 is the end.
    ex, ey = _snap(qx3, qy3, edges_b, xmin, ymin, xmax, ymax)
    _emit_piece(write, fill, degree, sx, ex if degree == 1 else qx1,
                qx2 if degree == 3 else ex, ex, sy, ey if degree == 1 else qy1,
                qy2 if degree == 3 else ey, ey, source, out_ctrl, out_deg, out_first, out_start,
                out_from, si, sf)


@borrowing
def _emit_exact(write, fill, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax, ymax,
                source, brk_t, brk_e, out_ctrl, out_deg, out_first, out_start,
                out_from, si, sf, st):
    """Clip a whole ambiguous segment at its edge crossings (exact mode, level 0).

    The lean form of `_leaf` for the default depth: no pending interval to merge with,
    so stretches are emitted straight from the break table, neighbours merged.
    """
    st[C.CLIPPED] += 1
    n = edge_breaks(degree, x0, x1, x2, x3, y0, y1, y2, y3, 0.0, 1.0, xmin, ymin, xmax, ymax,
                    brk_t, brk_e, st)
    open_k = -1  # first break of the visible stretch being extended
    for k in range(n - 1):
        tm = 0.5 * (brk_t[k] + brk_t[k + 1])
        inside = outcode(point_value(degree, x0, x1, x2, x3, tm),
                         point_value(degree, y0, y1, y2, y3, tm), xmin, ymin, xmax, ymax) == 0
        if inside:
            if open_k < 0:
                open_k = k
            continue
        if open_k >= 0:
            _emit_stretch(write, fill, degree, x0, x1, x2, x3, y0, y1, y2, y3, brk_t[open_k],
                          brk_t[k], brk_e[open_k], brk_e[k], xmin, ymin, xmax, ymax, source,
                          out_ctrl, out_deg, out_first, out_start, out_from, si, sf)
            open_k = -1
        ex, ey = _snap(point_value(degree, x0, x1, x2, x3, brk_t[k + 1]),
                       point_value(degree, y0, y1, y2, y3, brk_t[k + 1]), brk_e[k + 1], xmin,
                       ymin, xmax, ymax)
        _outside(write, fill, ex, ey, xmin, ymin, xmax, ymax, out_ctrl, out_deg, si, sf)
    if open_k >= 0:
        _emit_stretch(write, fill, degree, x0, x1, x2, x3, y0, y1, y2, y3, brk_t[open_k],
                      brk_t[n - 1], brk_e[open_k], brk_e[n - 1], xmin, ymin, xmax, ymax,
                      source, out_ctrl, out_deg, out_first, out_start, out_from, si,
                      sf)


@borrowing
def _pend(a, b, edges_a, edges_b, si, sf):
    """Mark [a, b] visible; return whether it continues the pending interval."""
    if si[_PEND] == 1 and sf[_PEND_B] == a:
        sf[_PEND_B] = b
        si[_PEND_EB] = edges_b
        return True
    return False


@borrowing
def _visible(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, edges_a,
             edges_b, xmin, ymin, xmax, ymax, tol, source, out_ctrl, out_deg,
             out_first, out_start, out_from, si, sf):
    if _pend(a, b, edges_a, edges_b, si, sf):
        return
    _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax,
           ymax, tol, source, out_ctrl, out_deg, out_first, out_start, out_from, si, sf)
    si[_PEND] = 1
    sf[_PEND_A] = a
    sf[_PEND_B] = b
    si[_PEND_EA] = edges_a
    si[_PEND_EB] = edges_b


@borrowing
def _leaf(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, xmin, ymin,
          xmax, ymax, tol, source, brk_t, brk_e, out_ctrl, out_deg, out_first,
          out_start, out_from, si, sf, st):
    """Clip the piece [a, b] exactly at its crossings with the edge lines."""
    st[C.CLIPPED] += 1
    n = edge_breaks(degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, xmin, ymin, xmax, ymax,
                    brk_t, brk_e, st)
    for k in range(n - 1):
        t0 = brk_t[k]
        t1 = brk_t[k + 1]
        tm = 0.5 * (t0 + t1)
        code = outcode(point_value(degree, x0, x1, x2, x3, tm),
                       point_value(degree, y0, y1, y2, y3, tm), xmin, ymin, xmax, ymax)
        if code == 0:
            _visible(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, t0, t1,
                     brk_e[k], brk_e[k + 1], xmin, ymin, xmax, ymax, tol, source,
                     out_ctrl, out_deg, out_first, out_start, out_from, si, sf)
        else:
            _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin,
                   xmax, ymax, tol, source, out_ctrl, out_deg, out_first, out_start,
                   out_from, si, sf)
            ex, ey = _snap(point_value(degree, x0, x1, x2, x3, t1),
                           point_value(degree, y0, y1, y2, y3, t1), brk_e[k + 1], xmin, ymin,
                           xmax, ymax)
            _outside(write, fill, ex, ey, xmin, ymin, xmax, ymax, out_ctrl, out_deg,
                     si, sf)


@borrowing
def clip_segment(write, fill, flatten, exact, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin,
                 ymin, xmax, ymax, n_split, leaf_depth, tol, source, brk_t, brk_e,
                 stack, out_ctrl, out_deg, out_first, out_start, out_from, si, sf, st):
    """Clip one segment (degree 1..3, control points x0..x3, y0..y3) into the output."""
    st[C.EVALUATED] += 1
    c_or, c_and = _hull_codes(degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax, ymax)
    if c_or == 0:
        st[C.ACCEPTED] += 1
        st[C.LEVELS] += 1
        _visible(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, 0.0, 1.0, 0, 0,
                 xmin, ymin, xmax, ymax, tol, source, out_ctrl, out_deg, out_first,
                 out_start, out_from, si, sf)
        _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax,
               ymax, tol, source, out_ctrl, out_deg, out_first, out_start, out_from,
               si, sf)
        return
    if c_and != 0:
        st[C.REJECTED] += 1
        st[C.LEVELS] += 1
        end_x = x3 if degree == 3 else (x2 if degree == 2 else x1)
        end_y = y3 if degree == 3 else (y2 if degree == 2 else y1)
        _outside(write, fill, end_x, end_y, xmin, ymin, xmax, ymax, out_ctrl, out_deg,
                 si, sf)
        return
    st[C.EVALUATED] -= 1  # counted again when popped
    stack[0, 0] = 0.0
    stack[0, 1] = 1.0
    stack[0, 2] = 0.0
    sp = 1
    while sp > 0:
        sp -= 1
        a = stack[sp, 0]
        b = stack[sp, 1]
        level = int(stack[sp, 2])
        slot = min(level, C.N_LEVELS - 1)
        if level > st[C.DEEPEST]:
            st[C.DEEPEST] = level
        st[C.EVALUATED] += 1
        qx0, qx1, qx2, qx3 = piece_values(degree, x0, x1, x2, x3, a, b)
        qy0, qy1, qy2, qy3 = piece_values(degree, y0, y1, y2, y3, a, b)
        c_or, c_and = _hull_codes(degree, qx0, qx1, qx2, qx3, qy0, qy1, qy2, qy3, xmin, ymin,
                                  xmax, ymax)
        if c_or == 0:
            st[C.ACCEPTED] += 1
            st[C.LEVELS + slot] += 1
            _visible(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, 0, 0,
                     xmin, ymin, xmax, ymax, tol, source, out_ctrl, out_deg,
                     out_first, out_start, out_from, si, sf)
            continue
        if c_and != 0:
            st[C.REJECTED] += 1
            st[C.LEVELS + slot] += 1
            _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin,
                   xmax, ymax, tol, source, out_ctrl, out_deg, out_first, out_start,
                   out_from, si, sf)
            _outside(write, fill, qx3, qy3, xmin, ymin, xmax, ymax, out_ctrl,
                     out_deg, si, sf)
            continue
        # Ambiguous. A leaf when deep enough, or (flatten) flat enough, or (approx)
        # smaller than the tolerance.
        if flatten:
            is_leaf = level >= leaf_depth or flatten_count(
                degree, qx0, qx1, qx2, qx3, qy0, qy1, qy2, qy3, tol) == 1
        elif exact:
            # A line's crossings cost no more on the whole than on a piece of it.
            is_leaf = level >= leaf_depth or degree == 1
        else:
            size = max(max(qx0, qx1, qx2, qx3) - min(qx0, qx1, qx2, qx3),
                       max(qy0, qy1, qy2, qy3) - min(qy0, qy1, qy2, qy3))
            is_leaf = level >= leaf_depth or size <= tol
        if not is_leaf and sp + n_split <= stack.shape[0]:
            st[C.SUBDIVIDED] += 1
            for j in range(n_split, 0, -1):
                stack[sp, 0] = a + (b - a) * (j - 1) / n_split
                stack[sp, 1] = b if j == n_split else a + (b - a) * j / n_split
                stack[sp, 2] = level + 1
                sp += 1
            continue
        st[C.LEVELS + slot] += 1
        if flatten:
            # The piece is flat: clip its chord as a line.
            _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin,
                   xmax, ymax, tol, source, out_ctrl, out_deg, out_first, out_start,
                   out_from, si, sf)
            _leaf(write, fill, False, 1, qx0, qx3, qx3, qx3, qy0, qy3, qy3, qy3, 0.0, 1.0,
                  xmin, ymin, xmax, ymax, tol, source, brk_t, brk_e, out_ctrl, out_deg,
                  out_first, out_start, out_from, si, sf, st)
            _flush(write, fill, False, 1, qx0, qx3, qx3, qx3, qy0, qy3, qy3, qy3, xmin, ymin,
                   xmax, ymax, tol, source, out_ctrl, out_deg, out_first, out_start,
                   out_from, si, sf)
        elif exact:
            _leaf(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, a, b, xmin,
                  ymin, xmax, ymax, tol, source, brk_t, brk_e, out_ctrl, out_deg,
                  out_first, out_start, out_from, si, sf, st)
        else:
            st[C.DROPPED] += 1
            _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin,
                   xmax, ymax, tol, source, out_ctrl, out_deg, out_first, out_start,
                   out_from, si, sf)
            _outside(write, fill, qx3, qy3, xmin, ymin, xmax, ymax, out_ctrl,
                     out_deg, si, sf)
    _flush(write, fill, flatten, degree, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax,
           ymax, tol, source, out_ctrl, out_deg, out_first, out_start, out_from, si, sf)


@borrowing
def _reverse_segments(out_ctrl, out_deg, a, b):
    """Reverse the order of the output segments a..b-1."""
    i = a
    j = b - 1
    while i < j:
        for r in range(4):
            for c in range(2):
                tmp = out_ctrl[i, r, c]
                out_ctrl[i, r, c] = out_ctrl[j, r, c]
                out_ctrl[j, r, c] = tmp
        d = out_deg[i]
        out_deg[i] = out_deg[j]
        out_deg[j] = d
        i += 1
        j -= 1


@borrowing
def _rotate_last_chain(s0, s_end, v0, v_end, out_ctrl, out_deg, out_first, out_start):
    """Move the last chain of a closed stroke in front of its first one, joining them.

    The chains of the subpath are ``out_first[s0:s_end]`` over segments v0..v_end-1;
    the last chain ends where the first begins (the subpath's start point).
    """
    last_first = out_first[s_end - 1]
    k = v_end - last_first
    # Rotate v0..v_end-1 right by k in place (three reversals: no scratch array).
    _reverse_segments(out_ctrl, out_deg, v0, v_end)
    _reverse_segments(out_ctrl, out_deg, v0, v0 + k)
    _reverse_segments(out_ctrl, out_deg, v0 + k, v_end)
    for s in range(s0 + 1, s_end - 1):
        out_first[s] += k
    out_start[s0, 0] = out_start[s_end - 1, 0]
    out_start[s0, 1] = out_start[s_end - 1, 1]


@borrowing
def _end_subpath(write, fill, closed, controls, last, sx, sy, xmin, ymin, xmax, ymax, v0, s0,
                 out_ctrl, out_deg, out_first, out_start, out_closed, out_from, si, sf):
    """Finish the output of a subpath whose segments first..last-1 have been clipped.

    Fill: return to the clamped start and keep the closed subpath, unless it is only
    boundary lines winding around no point. Strokes: a closed subpath visible whole
    stays closed; otherwise its last chain is joined to its first at the start point.
    """
    if fill:
        cx = clamp(sx, xmin, xmax)
        cy = clamp(sy, ymin, ymax)
        if sf[_CUR_X] != cx or sf[_CUR_Y] != cy:
            _put_line(write, cx, cy, out_ctrl, out_deg, si, sf)
        if si[_VISIBLE] == 0 and abs(sf[_AREA]) < (xmax - xmin) * (ymax - ymin):
            # Only boundary lines, winding around no point of the window: nothing.
            si[_V] = v0
            si[_S] = s0
        elif write:
            out_closed[s0] = True
        return
    if not closed or si[_S] == s0:
        return
    end_x = controls[last - 1, 3, 0]
    end_y = controls[last - 1, 3, 1]
    whole = si[_BROKEN] == 0 and si[_S] == s0 + 1
    if whole:
        if end_x != sx or end_y != sy:
            si[_V] -= 1  # the explicit closing line: Z draws it
        if write:
            out_closed[s0] = True
    elif (si[_FIRST_AT_START] == 1 and si[_OPEN] == 1 and si[_S] >= s0 + 2
          and sf[_CUR_X] == sx and sf[_CUR_Y] == sy):
        # The output keeps its counted size: the freed subpath entry is marked with
        # source -1 for the caller to drop (joins are rare; one pass over the table).
        if write:
            _rotate_last_chain(s0, si[_S], v0, si[_V], out_ctrl, out_deg, out_first,
                               out_start)
            out_from[si[_S] - 1] = -1



@borrowing
def _emit_flattened(write, fill, x0, y0, a, b, points, source, out_ctrl, out_deg, out_first,
                    out_start, out_from, si, sf, st):
    """Output an accepted curve (flatten mode) as lines from (x0, y0) through points a..b-1.

    What `clip_segment` does with an accepted curve, from points computed elsewhere: the
    same counters, the same lines.
    """
    st[C.EVALUATED] += 1
    st[C.ACCEPTED] += 1
    st[C.LEVELS] += 1
    prev_x = x0
    prev_y = y0
    for p in range(a, b):
        nx = points[p, 0]
        ny = points[p, 1]
        _emit_piece(write, fill, 1, prev_x, nx, nx, nx, prev_y, ny, ny, ny, source, out_ctrl,
                    out_deg, out_first, out_start, out_from, si, sf)
        prev_x = nx
        prev_y = ny


@borrowing
def _clip_subpaths(write, fill, flatten, exact, controls, degree, subpath_offsets, closed,
                   start, subpath_source, xmin, ymin, xmax, ymax, n_split, leaf_depth, tol, k0,
                   k1, segment_start, subpath_start, n_segments, n_subpaths, run_decisions,
                   brk_t, brk_e, stack, out_ctrl, out_deg, out_first, out_start, out_closed,
                   out_from, si, sf, st, decided, segment_class, point_start, points):
    """Count or write the clipped output of subpaths k0..k1-1 (one block).

    Subpath k, segments ``first..last-1`` starting at (sx, sy), gives as strokes its
    visible parts as open subpaths (the subpath itself, closed, if it is visible whole;
    a closed subpath's last and first parts are joined at its start); with `fill`, one
    closed subpath, the visible parts joined by the boundary, or nothing if no part is
    visible and the boundary path winds around no point. One function for the whole
    block: a call per subpath passing these arrays cost more than a short subpath's clip.

    With `decided`, each run's decision is already in `run_decisions`, each input
    segment's class is ``segment_class[g]`` (`SEGMENT_*`) and, in flatten mode, an
    accepted curve's lines end at ``points[point_start[g]:point_start[g + 1]]``
    (`flatten_into`'s points), all computed elsewhere (the OpenCL
    backend); the closing lines and the ambiguous segments are done here.
    """
    for k in range(k0, k1):
        v0 = 0
        v_end = np.iinfo(np.int64).max
        s0 = 0
        if write:
            if n_subpaths[k] == 0:
                continue
            v0 = segment_start[k]
            v_end = v0 + n_segments[k]
            s0 = subpath_start[k]
        first = subpath_offsets[k]
        last = subpath_offsets[k + 1]
        sx = start[k, 0]
        sy = start[k, 1]
        source = subpath_source[k]
        for q in range(_INT_STATE_WIDTH):
            si[q] = 0
        for q in range(_FLOAT_STATE_WIDTH):
            sf[q] = 0.0
        si[_V] = v0
        si[_V_END] = v_end
        si[_S] = s0
        sf[_START_X] = sx
        sf[_START_Y] = sy
        if first == last:
            # A lone moveto: nothing to fill; as a stroke, a dot (caps) if in the window.
            if not fill and outcode(sx, sy, xmin, ymin, xmax, ymax) == 0:
                _begin_subpath(write, sx, sy, source, out_first, out_start, out_from, si, sf)
                if write:
                    out_closed[s0] = closed[k]
            if not write:
                n_segments[k] = si[_V]
                n_subpaths[k] = si[_S]
            continue
        if fill:
            _begin_subpath(write, clamp(sx, xmin, xmax), clamp(sy, ymin, ymax), source,
                           out_first, out_start, out_from, si, sf)
        end = last + 1 if (fill or closed[k]) else last  # index `last`: the closing line
        i = first
        while i < end:
            j = min(i + RUN_SEGMENTS, last)
            if j - i >= 2:
                # Run level: the box of the run's control points decides it whole, as a
                # piece's hull decides a piece (copy it, or skip it: no per-segment work).
                if write or decided:
                    # The count pass's (or the device's): the same box, the same test.
                    decision = run_decisions[i]
                else:
                    lo_x, lo_y, hi_x, hi_y = _run_box(controls, i, j)
                    c_lo = outcode(lo_x, lo_y, xmin, ymin, xmax, ymax)
                    c_hi = outcode(hi_x, hi_y, xmin, ymin, xmax, ymax)
                    decision = _RUN_ACCEPTED if (c_lo | c_hi) == 0 and not flatten else (
                        _RUN_REJECTED if (c_lo & c_hi) != 0 else _RUN_SEGMENTED)
                    run_decisions[i] = decision
                st[C.RUNS_EVALUATED] += 1
                if decision == _RUN_ACCEPTED:
                    st[C.RUNS_ACCEPTED] += 1
                    st[C.RUN_LEVELS] += 1
                    st[C.SEGMENT_LEVELS] += j - i
                    _arrive_at(write, fill, controls[i, 0, 0], controls[i, 0, 1], source,
                               out_ctrl, out_deg, out_first, out_start, out_from, si, sf)
                    _put_run(write, controls, degree, i, j, out_ctrl, out_deg, si, sf)
                    i = j
                    continue
                if decision == _RUN_REJECTED:
                    st[C.RUNS_REJECTED] += 1
                    st[C.RUN_LEVELS] += 1
                    st[C.SEGMENT_LEVELS] += j - i
                    si[_BROKEN] = 1
                    if fill:
                        _clamp_to(write, controls[j - 1, 3, 0], controls[j - 1, 3, 1], xmin, ymin,
                                  xmax, ymax, out_ctrl, out_deg, si, sf)
                    else:
                        si[_OPEN] = 0
                    i = j
                    continue
                st[C.RUNS_SEGMENTED] += 1
            else:
                j = i + 1
            for g in range(i, j):
                if g < last:
                    d = degree[g]
                    x0 = controls[g, 0, 0]
                    x1 = controls[g, 1, 0]
                    x2 = controls[g, 2, 0]
                    x3 = controls[g, 3, 0]
                    y0 = controls[g, 0, 1]
                    y1 = controls[g, 1, 1]
                    y2 = controls[g, 2, 1]
                    y3 = controls[g, 3, 1]
                else:
                    # The closing line back to the start: filled subpaths are always closed.
                    d = 1
                    x0 = controls[last - 1, 3, 0]
                    y0 = controls[last - 1, 3, 1]
                    x1 = sx
                    y1 = sy
                    x2 = sx
                    y2 = sy
                    x3 = sx
                    y3 = sy
                if x0 == x1 == x2 == x3 and y0 == y1 == y2 == y3:
                    continue  # a point: nothing to draw, nothing to clamp
                # Level 0 inline: most segments are decided here, and a call would pass every
                # array's fields (more than the test itself costs).
                if decided and g < last:
                    accepted = segment_class[g] == SEGMENT_ACCEPTED
                    rejected = segment_class[g] == SEGMENT_REJECTED
                else:
                    c_or, c_and = _hull_codes(d, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin,
                                              xmax, ymax)
                    accepted = c_or == 0
                    rejected = c_and != 0
                if accepted and not (flatten and d > 1):
                    st[C.EVALUATED] += 1
                    st[C.ACCEPTED] += 1
                    st[C.LEVELS] += 1
                    _emit_piece(write, fill, d, x0, x1, x2, x3, y0, y1, y2, y3, source,
                                out_ctrl, out_deg, out_first, out_start, out_from, si, sf)
                    continue
                if accepted and decided and g < last:
                    _emit_flattened(write, fill, x0, y0, point_start[g], point_start[g + 1],
                                    points, source, out_ctrl, out_deg, out_first, out_start,
                                    out_from, si, sf, st)
                    continue
                if rejected:
                    st[C.EVALUATED] += 1
                    st[C.REJECTED] += 1
                    st[C.LEVELS] += 1
                    si[_BROKEN] = 1
                    if fill:
                        _clamp_to(write, x3, y3, xmin, ymin, xmax, ymax, out_ctrl, out_deg, si,
                                  sf)
                    else:
                        si[_OPEN] = 0
                    continue
                if exact and leaf_depth == 0 and not flatten:
                    st[C.EVALUATED] += 1
                    st[C.LEVELS] += 1
                    _emit_exact(write, fill, d, x0, x1, x2, x3, y0, y1, y2, y3, xmin, ymin, xmax,
                                ymax, source, brk_t, brk_e, out_ctrl, out_deg, out_first,
                                out_start, out_from, si, sf, st)
                    continue
                clip_segment(write, fill, flatten, exact, d, x0, x1, x2, x3, y0, y1, y2, y3, xmin,
                             ymin, xmax, ymax, n_split, leaf_depth, tol, source, brk_t,
                             brk_e, stack, out_ctrl, out_deg, out_first, out_start, out_from, si,
                             sf, st)
            i = j
        if write:
            for s in range(s0, si[_S]):
                out_closed[s] = False
        if fill or (closed[k] and si[_S] != s0):
            _end_subpath(write, fill, closed[k], controls, last, sx, sy, xmin, ymin, xmax,
                         ymax, v0, s0, out_ctrl, out_deg, out_first, out_start,
                         out_closed, out_from, si, sf)
        if not write:
            n_segments[k] = si[_V]
            n_subpaths[k] = si[_S]


@parallel
def clip_path_blocks(controls, degree, subpath_offsets, closed, start, subpath_source, xmin,
                     ymin, xmax, ymax, fill, flatten, exact, n_split, leaf_depth, tol,
                     block_size, write, segment_start, subpath_start, out_ctrl, out_deg,
                     out_first, out_start, out_closed, out_from, n_segments, n_subpaths,
                     run_decisions, counters, decided, segment_class, point_start, points):
    """Count (``write=False``) or write the clipped subpaths of a path array.

    Subpath k is the segments ``subpath_offsets[k]:subpath_offsets[k+1]`` of `controls`
    (m, 4, 2) and `degree` (m,), starting at ``start[k]``. The count pass stores each
    subpath's output size in `n_segments`, `n_subpaths` (and the stats, one counter row
    per block); the write pass writes subpath k's output from ``segment_start[k]`` and
    ``subpath_start[k]`` on: control points and degrees, and for each output subpath
    its first segment, start point, closed flag and source (``subpath_source[k]``, or
    -1 for an entry freed by joining the ends of a closed stroke: drop those).
    `run_decisions` (int8, one per input segment) keeps the count pass's decision of
    each run (at its first segment) for the write pass, which does not test runs again.
    With `decided`, the runs' decisions, the segments' classes and the accepted curves'
    flattened points are given (`run_decisions`, `segment_class`, `point_start`,
    `points`; see `_clip_subpaths`); otherwise those are empty and unused.
    """
    n = subpath_offsets.shape[0] - 1
    n_blocks = counters.shape[0]
    for blk in prange(n_blocks):
        st = np.zeros(C.WIDTH, dtype=np.int64) if write else counters[blk]
        si = np.zeros(_INT_STATE_WIDTH, dtype=np.int64)
        sf = np.zeros(_FLOAT_STATE_WIDTH, dtype=np.float64)
        brk_t = np.empty(BREAK_CAPACITY, dtype=np.float64)
        brk_e = np.empty(BREAK_CAPACITY, dtype=np.int64)
        stack = np.empty((CURVE_STACK_CAPACITY, 3), dtype=np.float64)
        _clip_subpaths(write, fill, flatten, exact, controls, degree, subpath_offsets, closed,
                       start, subpath_source, xmin, ymin, xmax, ymax, n_split, leaf_depth, tol,
                       blk * block_size, min(n, (blk + 1) * block_size), segment_start,
                       subpath_start, n_segments, n_subpaths, run_decisions, brk_t,
                       brk_e, stack, out_ctrl, out_deg, out_first, out_start, out_closed,
                       out_from, si, sf, st, decided, segment_class, point_start, points)


@scalar
def closing_edges(controls, subpath_offsets, closed, start, fill):
    """Return how many subpaths have a closing line that is clipped as a segment.

    A subpath with segments has one when it is closed (or `fill` closes every subpath)
    and its last segment does not end at its start point.
    """
    count = 0
    for s in range(closed.shape[0]):
        last = subpath_offsets[s + 1]
        if last == subpath_offsets[s] or not (fill or closed[s]):
            continue
        if controls[last - 1, 3, 0] != start[s, 0] or controls[last - 1, 3, 1] != start[s, 1]:
            count += 1
    return count


@borrowing
def _segment_points(controls, degree, i, n, coords, pos):
    """Write segment i's `n` points, at equal parameter steps, to ``coords[pos:pos + n]``.

    Its end point exactly last.
    """
    d = degree[i]
    for k in range(1, n + 1):
        if k == n:
            coords[pos, 0] = controls[i, 3, 0]
            coords[pos, 1] = controls[i, 3, 1]
        else:
            t = k / n
            coords[pos, 0] = point_value(d, controls[i, 0, 0], controls[i, 1, 0],
                                         controls[i, 2, 0], controls[i, 3, 0], t)
            coords[pos, 1] = point_value(d, controls[i, 0, 1], controls[i, 1, 1],
                                         controls[i, 2, 1], controls[i, 3, 1], t)
        pos += 1


@parallel
def flatten_segments(controls, degree, point_start, points):
    """Write each segment's points (`_segment_points`) to ``points[point_start[i]:]``.

    Segment i has ``point_start[i + 1] - point_start[i]`` of them: the layout of
    `OpenCLBackend.classify_curves`.
    """
    for i in prange(degree.shape[0]):
        _segment_points(controls, degree, i, point_start[i + 1] - point_start[i], points,
                        point_start[i])


@parallel
def flatten_steps(controls, degree, tol):
    """Return how many lines flatten each segment within `tol` (`flatten_count`)."""
    m = controls.shape[0]
    steps = np.empty(m, dtype=np.int64)
    for i in prange(m):
        steps[i] = flatten_count(degree[i], controls[i, 0, 0], controls[i, 1, 0],
                                 controls[i, 2, 0], controls[i, 3, 0], controls[i, 0, 1],
                                 controls[i, 1, 1], controls[i, 2, 1], controls[i, 3, 1], tol)
    return steps


@parallel
def flatten_into(controls, degree, tol, subpath_offsets, start, lines, closes, steps,
                 segment_points, line_offsets, coords):
    """Write subpath ``lines[j]`` as the polyline ``coords[line_offsets[j]:]``.

    Segment i contributes ``steps[i]`` points at equal parameter steps (its end point
    exactly last); a subpath with ``closes`` set returns to its start point.
    """
    for j in prange(lines.shape[0]):
        s = lines[j]
        pos = line_offsets[j]
        coords[pos, 0] = start[s, 0]
        coords[pos, 1] = start[s, 1]
        pos += 1
        for i in range(subpath_offsets[s], subpath_offsets[s + 1]):
            _segment_points(controls, degree, i, steps[i], coords, pos)
            pos += steps[i]
        if closes[s]:
            coords[pos, 0] = start[s, 0]
            coords[pos, 1] = start[s, 1]
