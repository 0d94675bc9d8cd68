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

State that travels together is one record (a named tuple, which Numba passes as its
fields: free once inlined): the window (`Window`), the options (`Options`), the input paths
(`PathInput`), decisions taken elsewhere (`Decisions`), the output's layout (`Layout`)
and arrays (`Output`), the state of the subpath being clipped (`State`), a block's
counters and scratch (`Work`), and a segment or piece (`Curve`). Helpers take them in
the order ``out, state, work, opts, window, curve``.
"""

from typing import NamedTuple

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
from rnsca.kernels.jit import borrowing, inlined, parallel, scalar
from rnsca.kernels.outcode import BOTTOM, LEFT, RIGHT, TOP, clamp, outcode
from rnsca.kernels.records import window_of
from rnsca.kernels.stacks import interval_at, put_interval

# Helpers that take arrays are `borrowing` (no reference counting of their arrays): a
# call then costs no more than passing the arrays' fields, and LLVM inlines the small
# ones. A helper LLVM does not inline is passed every field of every record it takes
# (7 to 11 per array), so the larger helpers called from one place (`_put_run`,
# `_emit_exact`, `_end_subpath`, ...) and the small ones on the hot path that call
# others (`_flush`, `_visible`) are `inlined` by Numba instead (measured on the glyph
# page, 1 thread: 1.12 ms with all of them `borrowing`, 0.88 ms inlined).

__all__ = [
    "BREAK_CAPACITY",
    "CURVE_N_AUTO",
    "RUN_SEGMENTS",
    "EXACT_LEAF_DEPTH",
    "SEGMENT_ACCEPTED",
    "SEGMENT_AMBIGUOUS",
    "SEGMENT_REJECTED",
    "Curve",
    "Decisions",
    "Layout",
    "Options",
    "Output",
    "PathInput",
    "State",
    "Work",
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
_START_X = 7      # the input subpath's start point (strokes end a closed one there;
_START_Y = 8      # fill returns to its clamp)
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
_V0 = 11          # the subpath's first output segment and first output subpath
_S0 = 12
_SOURCE = 13      # the input path its output subpaths come from
_INT_STATE_WIDTH = 14


class Options(NamedTuple):
    """How a clip treats its pieces: the same for every segment of a call."""

    fill: bool          # closed subpaths whose fill is kept (False: strokes)
    flatten: bool       # curves="flatten": curves become lines within `tolerance`
    exact: bool         # mode="exact": undecided leaves are cut at their crossings
    n_split: int        # N: pieces per split
    leaf_depth: int     # deepest split level
    tolerance: float    # flatness of lines (flatten); smallest piece (approx)
    clean: bool         # pieces for clean fills (`fill_rings`, which cuts rings at
                        # boundary vertices only): a visible piece ends where it touches
                        # an edge and turns back in, and its ends lie in the window


class Curve(NamedTuple):
    """A segment or piece: its degree (1..3) and 4 control values per axis.

    The slots a degree does not use repeat the end, so ``x[3], y[3]`` is always the end.
    """

    degree: int         # int64 (Numba types a record per field type: never int8)
    x: tuple            # (x0, x1, x2, x3)
    y: tuple            # (y0, y1, y2, y3)


class PathInput(NamedTuple):
    """The paths to clip, in the layout of `rnsca.io.svgpath.PathArrays`."""

    controls: np.ndarray         # float64 (m, 4, 2) control points per segment
    degree: np.ndarray           # int8 (m,)
    subpath_offsets: np.ndarray  # int64 (k + 1,) segments of each subpath
    closed: np.ndarray           # bool (k,)
    start: np.ndarray            # float64 (k, 2) each subpath's start point
    source: np.ndarray           # int64 (k,) the path each subpath belongs to


class Decisions(NamedTuple):
    """Decisions of runs and segments: the count pass's, or given (the OpenCL backend).

    Without `given`, `runs` is filled by the count pass (each run's ``_RUN_*`` at its
    first segment) and read by the write pass; the other arrays are empty and unused.
    With it, `runs` and, per input segment g, ``segment_class[g]`` (`SEGMENT_*`) and
    the points ending an accepted curve's lines in flatten mode,
    ``points[point_start[g]:point_start[g + 1]]`` (`flatten_into`'s), are given.
    """

    given: bool
    runs: np.ndarray             # int8 (m,)
    segment_class: np.ndarray    # uint8 (m,)
    point_start: np.ndarray      # int64 (m + 1,)
    points: np.ndarray           # float64 (p, 2)


class Layout(NamedTuple):
    """Each input subpath's output: its size (count pass) and its place (write pass)."""

    n_segments: np.ndarray       # int64 (k,) output segments
    n_subpaths: np.ndarray       # int64 (k,) output subpaths
    segment_start: np.ndarray    # int64 (k,) first output segment (write pass)
    subpath_start: np.ndarray    # int64 (k,) first output subpath (write pass)


class Output(NamedTuple):
    """The clipped paths; without `write` (the count pass), empty and untouched."""

    write: bool
    controls: np.ndarray         # float64 (M, 4, 2)
    degree: np.ndarray           # int8 (M,)
    first: np.ndarray            # int64 (K + 1,) each output subpath's first segment
    start: np.ndarray            # float64 (K, 2)
    closed: np.ndarray           # bool (K,)
    source: np.ndarray           # int64 (K,) input path; -1: an entry freed by a join


class State(NamedTuple):
    """The state of the subpath being clipped: output cursors, current point, pending.

    Small arrays indexed by the constants above: a helper updates them in place.
    """

    ints: np.ndarray             # int64 (_INT_STATE_WIDTH,), indexed by _V, _S, ...
    floats: np.ndarray           # float64 (_FLOAT_STATE_WIDTH,), by _CUR_X, ...


class Work(NamedTuple):
    """A block's counters and scratch arrays.

    Apart from `State`: most helpers need only that, and a helper that is not inlined
    is passed every field of every record it takes.
    """

    counters: np.ndarray         # int64 (counters.WIDTH,) the block's counter row
    break_t: np.ndarray          # float64 (BREAK_CAPACITY,) a leaf's break table
    break_edges: np.ndarray      # int64 (BREAK_CAPACITY,)
    stack: np.ndarray            # float64 (CURVE_STACK_CAPACITY, 3) pieces (a, b, level)


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
def _line(x0, y0, x1, y1):
    """Return the line from (x0, y0) to (x1, y1) as a `Curve`."""
    return Curve(1, (x0, x1, x1, x1), (y0, y1, y1, y1))


@borrowing
def _segment(controls, degree, g):
    """Return input segment g as a `Curve`."""
    return Curve(np.int64(degree[g]),
                 (controls[g, 0, 0], controls[g, 1, 0], controls[g, 2, 0], controls[g, 3, 0]),
                 (controls[g, 0, 1], controls[g, 1, 1], controls[g, 2, 1], controls[g, 3, 1]))


@scalar
def _piece(c, a, b):
    """Return the piece [a, b] of the curve (`piece_values` on each axis)."""
    return Curve(c.degree, piece_values(c.degree, *c.x, a, b),
                 piece_values(c.degree, *c.y, a, b))


@scalar
def _point(c, t):
    """Return the curve's point (x, y) at parameter t."""
    return point_value(c.degree, *c.x, t), point_value(c.degree, *c.y, t)


@scalar
def _code(x, y, window):
    """Return the outcode of (x, y) for the window."""
    return outcode(x, y, window.xmin, window.ymin, window.xmax, window.ymax)


@scalar
def _hull_codes(c, window):
    """Return (OR, AND) of the outcodes of the curve's control points."""
    c0 = _code(c.x[0], c.y[0], window)
    c1 = _code(c.x[1], c.y[1], window)
    c_or = c0 | c1
    c_and = c0 & c1
    if c.degree >= 2:
        c2 = _code(c.x[2], c.y[2], window)
        c_or |= c2
        c_and &= c2
    if c.degree == 3:
        c3 = _code(c.x[3], c.y[3], window)
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
def _solve_monotone(degree, a, level, u, v, gu, gv, counters):
    """Return the root of ``B(t) = level`` in [u, v], B monotone there.

    B is the 1-D Bézier of `degree` with control values ``a = (a0, a1, a2, a3)``;
    ``gu = B(u) - level`` and ``gv = B(v) - level`` have opposite signs.

    Illinois regula falsi, safeguarded by bisection, to adjacent floats. The side of a
    new point is read against the sign `gu` has on entry: the Illinois halving of `gu`
    can underflow it to -0.0 (from -5e-324, say), whose sign `< 0` no longer tells.
    """
    side = 0
    u_below = gu < 0.0
    counters[C.INTERSECTIONS] += 1
    for _ in range(200):
        t = (u * gv - v * gu) / (gv - gu)
        if not (u < t < v):
            t = 0.5 * (u + v)
            if not (u < t < v):
                break
        g = point_value(degree, *a, t) - level
        if g == 0.0:
            return t
        if (g < 0.0) == u_below:
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
    return u if abs(point_value(degree, *a, u) - level) <= \
        abs(point_value(degree, *a, v) - level) else v


@borrowing
def _add_break(brk_t, brk_e, n, t, edge_bit):
    if n < brk_t.shape[0]:
        brk_t[n] = t
        brk_e[n] = edge_bit
        n += 1
    return n


@borrowing
def _line_roots(degree, a, s, level, edge_bit, lo, hi, brk_t, brk_e, n, counters):
    """Add to the break table the parameters in [lo, hi] where B(t) crosses `level`.

    B is the 1-D Bézier of `degree` with control values ``a = (a0, a1, a2, a3)``;
    ``s = (s0, s1, s2, s3)`` are those of its piece [lo, hi] (shared by the two edge
    lines of an axis).
    """
    s0, s1, s2, s3 = s
    below = (s0 < level) | (s1 < level) | (s2 < level) | (s3 < level)
    above = (s0 > level) | (s1 > level) | (s2 > level) | (s3 > level)
    if not (below and above) and not (s0 == level or s3 == level):
        return n  # the piece stays on one side (or lies on the line): no crossing
    c0, c1 = _critical_points(degree, *a)
    u = lo
    gu = point_value(degree, *a, u) - level
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
        gv = point_value(degree, *a, v) - level
        if gv == 0.0:
            n = _add_break(brk_t, brk_e, n, v, edge_bit)
        elif (gu < 0.0) != (gv < 0.0) and gu != 0.0:
            n = _add_break(brk_t, brk_e, n,
                           _solve_monotone(degree, a, level, u, v, gu, gv, counters),
                           edge_bit)
        u = v
        gu = gv
        if u >= hi:
            break
    return n


@borrowing
def edge_breaks(curve, lo, hi, window, brk_t, brk_e, counters):
    """Fill the break table of the piece [lo, hi] of `curve`; return its length.

    ``brk_t[0] = lo < ... < brk_t[n-1] = hi`` with ``brk_e[k]`` the bits (LEFT, RIGHT,
    BOTTOM, TOP) of the edge lines of `window` the curve crosses or touches at
    ``brk_t[k]``. Between two breaks the piece lies in one of the nine regions the edge
    lines make. Each root solved counts in ``counters[INTERSECTIONS]``.
    """
    n = _add_break(brk_t, brk_e, 0, lo, 0)
    if lo == 0.0 and hi == 1.0:
        # The whole segment: its control values are the piece's (unused rows repeat
        # the end, as piece_values does), no blossoms needed.
        piece = curve
    else:
        piece = _piece(curve, lo, hi)
    d = curve.degree
    n = _line_roots(d, curve.x, piece.x, window.xmin, LEFT, lo, hi, brk_t, brk_e, n, counters)
    n = _line_roots(d, curve.x, piece.x, window.xmax, RIGHT, lo, hi, brk_t, brk_e, n, counters)
    n = _line_roots(d, curve.y, piece.y, window.ymin, BOTTOM, lo, hi, brk_t, brk_e, n, counters)
    n = _line_roots(d, curve.y, piece.y, window.ymax, TOP, lo, hi, brk_t, brk_e, n, counters)
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
def _snap(x, y, edges, window):
    """Return the point moved exactly onto the edge lines it was found on."""
    if edges & LEFT:
        x = window.xmin
    elif edges & RIGHT:
        x = window.xmax
    if edges & BOTTOM:
        y = window.ymin
    elif edges & TOP:
        y = window.ymax
    return x, y


@borrowing
def _advance(state, n, x, y):
    """Count `n` visible segments appended to the output, ending at (x, y)."""
    si = state.ints
    si[_V] += n
    si[_LAST_RUN] = 0
    si[_VISIBLE] = 1
    state.floats[_CUR_X] = x
    state.floats[_CUR_Y] = y


@borrowing
def _put_segment(out, state, c):
    """Append a visible segment (unused control slots repeat its end)."""
    v = state.ints[_V]
    if out.write and v < state.ints[_V_END]:
        out.controls[v, 0, 0] = c.x[0]
        out.controls[v, 1, 0] = c.x[1]
        out.controls[v, 2, 0] = c.x[2]
        out.controls[v, 3, 0] = c.x[3]
        out.controls[v, 0, 1] = c.y[0]
        out.controls[v, 1, 1] = c.y[1]
        out.controls[v, 2, 1] = c.y[2]
        out.controls[v, 3, 1] = c.y[3]
        out.degree[v] = c.degree
    _advance(state, 1, c.x[3], c.y[3])


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


@inlined
def _put_run(out, state, paths, a, b):
    """Append the input segments a..b-1, accepted whole (a continuous run)."""
    v = state.ints[_V]
    n = b - a
    if out.write:
        # One loop over the rows without a test per row: LLVM vectorizes the copy.
        n_copy = min(n, state.ints[_V_END] - v)
        for i in range(n_copy):
            for k in range(4):
                out.controls[v + i, k, 0] = paths.controls[a + i, k, 0]
                out.controls[v + i, k, 1] = paths.controls[a + i, k, 1]
        for i in range(n_copy):
            out.degree[v + i] = paths.degree[a + i]
    _advance(state, n, paths.controls[b - 1, 3, 0], paths.controls[b - 1, 3, 1])


@borrowing
def _put_line(out, state, x, y):
    """Append a line from the current point to (x, y)."""
    si = state.ints
    sf = state.floats
    v = si[_V]
    if out.write and v < si[_V_END]:
        out.controls[v, 0, 0] = sf[_CUR_X]
        out.controls[v, 0, 1] = sf[_CUR_Y]
        for k in range(1, 4):
            out.controls[v, k, 0] = x
            out.controls[v, k, 1] = y
        out.degree[v] = 1
    si[_V] = v + 1
    sf[_CUR_X] = x
    sf[_CUR_Y] = y


@borrowing
def _begin_subpath(out, state, x, y):
    """Start an output subpath at (x, y)."""
    si = state.ints
    s = si[_S]
    if out.write:
        out.first[s] = si[_V]
        out.start[s, 0] = x
        out.start[s, 1] = y
        out.source[s] = si[_SOURCE]
    si[_S] = s + 1
    si[_OPEN] = 1
    si[_LAST_RUN] = 0
    state.floats[_CUR_X] = x
    state.floats[_CUR_Y] = y


@borrowing
def _arrive_at(out, state, opts, x0, y0):
    """Make (x0, y0) the current point before visible output that starts there."""
    si = state.ints
    sf = state.floats
    if opts.fill:
        if x0 != sf[_CUR_X] or y0 != sf[_CUR_Y]:
            # Rounding left a gap between the clamped path and the piece: bridge it.
            _put_line(out, state, x0, y0)
    elif si[_OPEN] == 0 or x0 != sf[_CUR_X] or y0 != sf[_CUR_Y]:
        if si[_VISIBLE] == 0 and si[_BROKEN] == 0:
            si[_FIRST_AT_START] = 1  # nothing before it: it starts at t = 0
        _begin_subpath(out, state, x0, y0)


@borrowing
def _emit_piece(out, state, opts, c):
    """Add a visible piece `c` to the output."""
    _arrive_at(out, state, opts, c.x[0], c.y[0])
    _put_segment(out, state, c)


@borrowing
def _clamp_to(out, state, window, x, y):
    """Fill: continue the output along the boundary to the clamp of (x, y)."""
    si = state.ints
    sf = state.floats
    cx = clamp(x, window.xmin, window.xmax)
    cy = clamp(y, window.ymin, window.ymax)
    ux = sf[_CUR_X]
    uy = sf[_CUR_Y]
    if cx == ux and cy == uy:
        return
    rx = sf[_RUN_X]
    ry = sf[_RUN_Y]
    same_edge = ((rx == ux) & (ux == cx) & ((cx == window.xmin) | (cx == window.xmax))) | \
        ((ry == uy) & (uy == cy) & ((cy == window.ymin) | (cy == window.ymax)))
    if si[_LAST_RUN] == 1 and same_edge:
        # Extend the last boundary line instead of adding one along the same edge.
        sf[_AREA] += (rx * cy - cx * ry) - (rx * uy - ux * ry)
        if cx == rx and cy == ry:
            si[_V] -= 1  # back where the line began: drop it
            si[_LAST_RUN] = 0
        elif out.write and si[_V] - 1 < si[_V_END]:
            v = si[_V] - 1
            for k in range(1, 4):
                out.controls[v, k, 0] = cx
                out.controls[v, k, 1] = cy
        sf[_CUR_X] = cx
        sf[_CUR_Y] = cy
        return
    sf[_AREA] += ux * cy - cx * uy
    sf[_RUN_X] = ux
    sf[_RUN_Y] = uy
    _put_line(out, state, cx, cy)
    si[_LAST_RUN] = 1


@borrowing
def _outside(out, state, opts, window, x, y):
    """Mark the part ending at (x, y) not visible: clamp to it (fill), or end the chain."""
    state.ints[_BROKEN] = 1
    if opts.fill:
        _clamp_to(out, state, window, x, y)
    else:
        state.ints[_OPEN] = 0


@inlined
def _flush(out, state, opts, window, c):
    """Output the pending visible interval of the segment `c`, if any."""
    si = state.ints
    if si[_PEND] == 0:
        return
    si[_PEND] = 0
    a = state.floats[_PEND_A]
    b = state.floats[_PEND_B]
    if not opts.flatten or c.degree == 1:
        _emit_stretch(out, state, opts, window, c, a, b, si[_PEND_EA], si[_PEND_EB])
    else:
        _emit_flat_stretch(out, state, opts, window, c, a, b, si[_PEND_EA], si[_PEND_EB])


@borrowing
def _emit_flat_stretch(out, state, opts, window, c, a, b, edges_a, edges_b):
    """Output the visible stretch [a, b] of a curve as lines within the tolerance."""
    q = _piece(c, a, b)
    sx, sy = _inside(_snap(q.x[0], q.y[0], edges_a, window), opts, window)
    ex, ey = _inside(_snap(q.x[3], q.y[3], edges_b, window), opts, window)
    steps = flatten_count(q.degree, *q.x, *q.y, opts.tolerance)
    prev_x = sx
    prev_y = sy
    for k in range(1, steps + 1):
        if k == steps:
            nx = ex
            ny = ey
        else:
            nx, ny = _inside(_point(c, a + (b - a) * k / steps), opts, window)
        _emit_piece(out, state, opts, _line(prev_x, prev_y, nx, ny))
        prev_x = nx
        prev_y = ny


@scalar
def _inside(point, opts, window):
    """Return `point`, moved into the window for clean fills (``opts.clean``).

    A stretch between two breaks lies in one of the nine regions; one taken for visible
    (its middle in the window) is inside up to rounding, but its ends may round an ulp
    past an edge (an input vertex an ulp outside, or a root an ulp off): clean rings
    are built from points on the boundary or inside it, so such an end is clamped.
    """
    x, y = point
    if opts.clean:
        x = clamp(x, window.xmin, window.xmax)
        y = clamp(y, window.ymin, window.ymax)
    return x, y


@borrowing
def _emit_stretch(out, state, opts, window, c, a, b, edges_a, edges_b):
    """Output the visible stretch [a, b] of a segment as a piece of its degree."""
    q = _piece(c, a, b)
    sx, sy = _inside(_snap(q.x[0], q.y[0], edges_a, window), opts, window)
    # piece_values repeats the end in the unused slots: q.x[3], q.y[3] is the end.
    ex, ey = _inside(_snap(q.x[3], q.y[3], edges_b, window), opts, window)
    d = c.degree
    _emit_piece(out, state, opts,
                Curve(d, (sx, ex if d == 1 else q.x[1], q.x[2] if d == 3 else ex, ex),
                      (sy, ey if d == 1 else q.y[1], q.y[2] if d == 3 else ey, ey)))


@inlined
def _emit_exact(out, state, work, opts, window, c):
    """Clip a whole ambiguous segment at its edge crossings (exact mode, level 0).

    The lean form of `_leaf` for the default depth: no pending interval to merge with,
    so stretches are emitted straight from the break table, neighbours merged.
    """
    brk_t = work.break_t
    brk_e = work.break_edges
    work.counters[C.CLIPPED] += 1
    n = edge_breaks(c, 0.0, 1.0, window, brk_t, brk_e, work.counters)
    open_k = -1  # first break of the visible stretch being extended
    for k in range(n - 1):
        mx, my = _point(c, 0.5 * (brk_t[k] + brk_t[k + 1]))
        if _code(mx, my, window) == 0:
            if open_k < 0:
                open_k = k
            elif opts.clean and brk_e[k] != 0:
                # It touches an edge at break k and stays inside: two pieces, meeting
                # there exactly (both ends snapped onto the edge).
                _emit_stretch(out, state, opts, window, c, brk_t[open_k], brk_t[k],
                              brk_e[open_k], brk_e[k])
                open_k = k
            continue
        if open_k >= 0:
            _emit_stretch(out, state, opts, window, c, brk_t[open_k], brk_t[k], brk_e[open_k],
                          brk_e[k])
            open_k = -1
        px, py = _point(c, brk_t[k + 1])
        ex, ey = _snap(px, py, brk_e[k + 1], window)
        _outside(out, state, opts, window, ex, ey)
    if open_k >= 0:
        _emit_stretch(out, state, opts, window, c, brk_t[open_k], brk_t[n - 1], brk_e[open_k],
                      brk_e[n - 1])


@borrowing
def _pend(state, a, b, edges_a, edges_b, split_touches):
    """Mark [a, b] visible; return whether it continues the pending interval.

    With `split_touches` (``Options.clean``), an interval starting where the curve
    touches an edge (`edges_a` non-zero) does not continue it: the touch ends a piece.
    """
    if state.ints[_PEND] == 1 and state.floats[_PEND_B] == a and not (
            split_touches and edges_a != 0):
        state.floats[_PEND_B] = b
        state.ints[_PEND_EB] = edges_b
        return True
    return False


@inlined
def _visible(out, state, opts, window, c, a, b, edges_a, edges_b):
    """Make [a, b] (ends cut at edges `edges_a`, `edges_b`) of `c` the pending interval.

    It extends the pending one if it continues it; otherwise that one is output first.
    """
    if _pend(state, a, b, edges_a, edges_b, opts.clean):
        return
    _flush(out, state, opts, window, c)
    si = state.ints
    si[_PEND] = 1
    state.floats[_PEND_A] = a
    state.floats[_PEND_B] = b
    si[_PEND_EA] = edges_a
    si[_PEND_EB] = edges_b


@borrowing
def _leaf(out, state, work, opts, window, c, a, b):
    """Clip the piece [a, b] of `c` exactly at its crossings with the edge lines."""
    brk_t = work.break_t
    brk_e = work.break_edges
    work.counters[C.CLIPPED] += 1
    n = edge_breaks(c, a, b, window, brk_t, brk_e, work.counters)
    for k in range(n - 1):
        t0 = brk_t[k]
        t1 = brk_t[k + 1]
        mx, my = _point(c, 0.5 * (t0 + t1))
        if _code(mx, my, window) == 0:
            _visible(out, state, opts, window, c, t0, t1, brk_e[k], brk_e[k + 1])
        else:
            _flush(out, state, opts, window, c)
            px, py = _point(c, t1)
            ex, ey = _snap(px, py, brk_e[k + 1], window)
            _outside(out, state, opts, window, ex, ey)


@borrowing
def clip_segment(out, state, work, opts, window, c):
    """Clip one segment `c` into the output: RNSCA on its pieces, with a stack."""
    st = work.counters
    stack = work.stack
    st[C.EVALUATED] += 1
    c_or, c_and = _hull_codes(c, window)
    if c_or == 0:
        st[C.ACCEPTED] += 1
        st[C.LEVELS] += 1
        _visible(out, state, opts, window, c, 0.0, 1.0, 0, 0)
        _flush(out, state, opts, window, c)
        return
    if c_and != 0:
        st[C.REJECTED] += 1
        st[C.LEVELS] += 1
        end_x = c.x[3] if c.degree == 3 else (c.x[2] if c.degree == 2 else c.x[1])
        end_y = c.y[3] if c.degree == 3 else (c.y[2] if c.degree == 2 else c.y[1])
        _outside(out, state, opts, window, end_x, end_y)
        return
    st[C.EVALUATED] -= 1  # counted again when popped
    put_interval(stack, 0, 0.0, 1.0, 0)
    sp = 1
    while sp > 0:
        sp -= 1
        a, b, level = interval_at(stack, sp)
        slot = min(level, C.N_LEVELS - 1)
        if level > st[C.DEEPEST]:
            st[C.DEEPEST] = level
        st[C.EVALUATED] += 1
        q = _piece(c, a, b)
        c_or, c_and = _hull_codes(q, window)
        if c_or == 0:
            st[C.ACCEPTED] += 1
            st[C.LEVELS + slot] += 1
            _visible(out, state, opts, window, c, a, b, 0, 0)
            continue
        if c_and != 0:
            st[C.REJECTED] += 1
            st[C.LEVELS + slot] += 1
            _flush(out, state, opts, window, c)
            _outside(out, state, opts, window, q.x[3], q.y[3])
            continue
        # Ambiguous. A leaf when deep enough, or (flatten) flat enough, or (approx)
        # smaller than the tolerance.
        if opts.flatten:
            is_leaf = level >= opts.leaf_depth or flatten_count(
                q.degree, *q.x, *q.y, opts.tolerance) == 1
        elif opts.exact:
            # A line's crossings cost no more on the whole than on a piece of it.
            is_leaf = level >= opts.leaf_depth or c.degree == 1
        else:
            size = max(max(q.x[0], q.x[1], q.x[2], q.x[3]) - min(q.x[0], q.x[1], q.x[2], q.x[3]),
                       max(q.y[0], q.y[1], q.y[2], q.y[3]) - min(q.y[0], q.y[1], q.y[2], q.y[3]))
            is_leaf = level >= opts.leaf_depth or size <= opts.tolerance
        n_split = opts.n_split
        if not is_leaf and sp + n_split <= stack.shape[0]:
            st[C.SUBDIVIDED] += 1
            for j in range(n_split, 0, -1):
                put_interval(stack, sp, a + (b - a) * (j - 1) / n_split,
                             b if j == n_split else a + (b - a) * j / n_split, level + 1)
                sp += 1
            continue
        st[C.LEVELS + slot] += 1
        if opts.flatten:
            # The piece is flat: clip its chord as a line (a line is never flattened).
            chord = _line(q.x[0], q.y[0], q.x[3], q.y[3])
            _flush(out, state, opts, window, c)
            _leaf(out, state, work, opts, window, chord, 0.0, 1.0)
            _flush(out, state, opts, window, chord)
        elif opts.exact:
            _leaf(out, state, work, opts, window, c, a, b)
        else:
            st[C.DROPPED] += 1
            _flush(out, state, opts, window, c)
            _outside(out, state, opts, window, q.x[3], q.y[3])
    _flush(out, state, opts, window, c)


@borrowing
def _reverse_segments(out, a, b):
    """Reverse the order of the output segments a..b-1."""
    i = a
    j = b - 1
    while i < j:
        for r in range(4):
            for k in range(2):
                tmp = out.controls[i, r, k]
                out.controls[i, r, k] = out.controls[j, r, k]
                out.controls[j, r, k] = tmp
        d = out.degree[i]
        out.degree[i] = out.degree[j]
        out.degree[j] = d
        i += 1
        j -= 1


@borrowing
def _rotate_last_chain(out, s0, s_end, v0, v_end):
    """Move the last chain of a closed stroke in front of its first one, joining them.

    The chains of the subpath are ``out.first[s0:s_end]`` over segments v0..v_end-1;
    the last chain ends where the first begins (the subpath's start point).
    """
    last_first = out.first[s_end - 1]
    k = v_end - last_first
    # Rotate v0..v_end-1 right by k in place (three reversals: no scratch array).
    _reverse_segments(out, v0, v_end)
    _reverse_segments(out, v0, v0 + k)
    _reverse_segments(out, v0 + k, v_end)
    for s in range(s0 + 1, s_end - 1):
        out.first[s] += k
    out.start[s0, 0] = out.start[s_end - 1, 0]
    out.start[s0, 1] = out.start[s_end - 1, 1]


@inlined
def _end_subpath(out, state, opts, window, closed, end_x, end_y):
    """Finish the output of an input subpath whose segments have been clipped.

    `closed` is the input subpath's flag, (end_x, end_y) its last segment's end.
    Fill: return to the clamped start and keep the closed subpath, unless it is only
    boundary lines winding around no point. Strokes: a closed subpath visible whole
    stays closed; otherwise its last chain is joined to its first at the start point.
    """
    si = state.ints
    sf = state.floats
    sx = sf[_START_X]
    sy = sf[_START_Y]
    v0 = si[_V0]
    s0 = si[_S0]
    if opts.fill:
        cx = clamp(sx, window.xmin, window.xmax)
        cy = clamp(sy, window.ymin, window.ymax)
        if sf[_CUR_X] != cx or sf[_CUR_Y] != cy:
            _put_line(out, state, cx, cy)
        area = (window.xmax - window.xmin) * (window.ymax - window.ymin)
        if si[_VISIBLE] == 0 and abs(sf[_AREA]) < area:
            # Only boundary lines, winding around no point of the window: nothing.
            si[_V] = v0
            si[_S] = s0
        elif out.write:
            out.closed[s0] = True
        return
    if not closed or si[_S] == s0:
        return
    whole = si[_BROKEN] == 0 and si[_S] == s0 + 1
    if whole:
        if end_x != sx or end_y != sy:
            si[_V] -= 1  # the explicit closing line: Z draws it
        if out.write:
            out.closed[s0] = True
    elif (si[_FIRST_AT_START] == 1 and si[_OPEN] == 1 and si[_S] >= s0 + 2
          and sf[_CUR_X] == sx and sf[_CUR_Y] == sy):
        # The output keeps its counted size: the freed subpath entry is marked with
        # source -1 for the caller to drop (joins are rare; one pass over the table).
        if out.write:
            _rotate_last_chain(out, s0, si[_S], v0, si[_V])
            out.source[si[_S] - 1] = -1


@borrowing
def _emit_flattened(out, state, work, opts, x0, y0, points, a, b):
    """Output an accepted curve (flatten mode) as lines from (x0, y0) through points a..b-1.

    What `clip_segment` does with an accepted curve, from points computed elsewhere: the
    same counters, the same lines.
    """
    st = work.counters
    st[C.EVALUATED] += 1
    st[C.ACCEPTED] += 1
    st[C.LEVELS] += 1
    prev_x = x0
    prev_y = y0
    for p in range(a, b):
        nx = points[p, 0]
        ny = points[p, 1]
        _emit_piece(out, state, opts, _line(prev_x, prev_y, nx, ny))
        prev_x = nx
        prev_y = ny


@inlined
def _begin_input_subpath(state, k, paths, v0, v_end, s0):
    """Reset the working state for input subpath k, whose output starts at v0 and s0."""
    si = state.ints
    sf = state.floats
    for q in range(_INT_STATE_WIDTH):
        si[q] = 0
    for q in range(_FLOAT_STATE_WIDTH):
        sf[q] = 0.0
    si[_V] = v0
    si[_V_END] = v_end
    si[_S] = s0
    si[_V0] = v0
    si[_S0] = s0
    si[_SOURCE] = paths.source[k]
    sf[_START_X] = paths.start[k, 0]
    sf[_START_Y] = paths.start[k, 1]


@inlined
def _decide_run(paths, window, opts, i, j):
    """Return the decision (``_RUN_*``) of the run of segments i..j-1 by its box."""
    lo_x, lo_y, hi_x, hi_y = _run_box(paths.controls, i, j)
    c_lo = _code(lo_x, lo_y, window)
    c_hi = _code(hi_x, hi_y, window)
    if (c_lo | c_hi) == 0 and not opts.flatten:
        return _RUN_ACCEPTED
    return _RUN_REJECTED if (c_lo & c_hi) != 0 else _RUN_SEGMENTED


@borrowing
def _clip_subpaths(paths, windows, opts, decisions, layout, out, state, work, k0, k1):
    """Count or write the clipped output of subpaths k0..k1-1 (one block).

    Subpath k is clipped against its path's window (``paths.source[k]``'s row of
    `windows`, a `records.WindowRows`).

    Subpath k, segments ``first..last-1`` starting at (sx, sy), gives as strokes its
    visible parts as open subpaths (the subpath itself, closed, if it is visible whole;
    a closed subpath's last and first parts are joined at its start); with `fill`, one
    closed subpath, the visible parts joined by the boundary, or nothing if no part is
    visible and the boundary path winds around no point. One function for the whole
    block: a call per subpath passing these arrays cost more than a short subpath's clip.

    With ``decisions.given``, each run's decision, each segment's class and, in flatten
    mode, the points of the accepted curves' lines are given (computed elsewhere: the
    OpenCL backend); the closing lines and the ambiguous segments are done here.
    """
    si = state.ints
    st = work.counters
    fill = opts.fill
    controls = paths.controls
    for k in range(k0, k1):
        v0 = 0
        v_end = np.iinfo(np.int64).max
        s0 = 0
        if out.write:
            if layout.n_subpaths[k] == 0:
                continue
            v0 = layout.segment_start[k]
            v_end = v0 + layout.n_segments[k]
            s0 = layout.subpath_start[k]
        window = window_of(windows.bounds, windows.index, paths.source[k])
        first = paths.subpath_offsets[k]
        last = paths.subpath_offsets[k + 1]
        sx = paths.start[k, 0]
        sy = paths.start[k, 1]
        closed = paths.closed[k]
        _begin_input_subpath(state, k, paths, v0, v_end, s0)
        if first == last:
            # A lone moveto: nothing to fill; as a stroke, a dot (caps) if in the window.
            if not fill and _code(sx, sy, window) == 0:
                _begin_subpath(out, state, sx, sy)
                if out.write:
                    out.closed[s0] = closed
            if not out.write:
                layout.n_segments[k] = si[_V]
                layout.n_subpaths[k] = si[_S]
            continue
        if fill:
            _begin_subpath(out, state, clamp(sx, window.xmin, window.xmax),
                           clamp(sy, window.ymin, window.ymax))
        end = last + 1 if (fill or closed) else last  # index `last`: the closing line
        i = first
        while i < end:
            j = min(i + RUN_SEGMENTS, last)
            if j - i >= 2:
                # Run level: the box of the run's control points decides it whole, as a
                # piece's hull decides a piece (copy it, or skip it: no per-segment state).
                if out.write or decisions.given:
                    # The count pass's (or the device's): the same box, the same test.
                    decision = decisions.runs[i]
                else:
                    decision = _decide_run(paths, window, opts, i, j)
                    decisions.runs[i] = decision
                st[C.RUNS_EVALUATED] += 1
                if decision == _RUN_ACCEPTED:
                    st[C.RUNS_ACCEPTED] += 1
                    st[C.RUN_LEVELS] += 1
                    st[C.SEGMENT_LEVELS] += j - i
                    _arrive_at(out, state, opts, controls[i, 0, 0], controls[i, 0, 1])
                    _put_run(out, state, paths, i, j)
                    i = j
                    continue
                if decision == _RUN_REJECTED:
                    st[C.RUNS_REJECTED] += 1
                    st[C.RUN_LEVELS] += 1
                    st[C.SEGMENT_LEVELS] += j - i
                    si[_BROKEN] = 1
                    if fill:
                        _clamp_to(out, state, window, controls[j - 1, 3, 0], controls[j - 1, 3, 1])
                    else:
                        si[_OPEN] = 0
                    i = j
                    continue
                st[C.RUNS_SEGMENTED] += 1
            else:
                j = i + 1
            for g in range(i, j):
                if g < last:
                    c = _segment(controls, paths.degree, g)
                else:
                    # The closing line back to the start: filled subpaths are always closed.
                    c = _line(controls[last - 1, 3, 0], controls[last - 1, 3, 1], sx, sy)
                x0, x1, x2, x3 = c.x
                y0, y1, y2, y3 = c.y
                if x0 == x1 == x2 == x3 and y0 == y1 == y2 == y3:
                    continue  # a point: nothing to draw, nothing to clamp
                # Level 0 inline: most segments are decided here, and a call would pass every
                # array's fields (more than the test itself costs).
                if decisions.given and g < last:
                    accepted = decisions.segment_class[g] == SEGMENT_ACCEPTED
                    rejected = decisions.segment_class[g] == SEGMENT_REJECTED
                else:
                    c_or, c_and = _hull_codes(c, window)
                    accepted = c_or == 0
                    rejected = c_and != 0
                if accepted and not (opts.flatten and c.degree > 1):
                    st[C.EVALUATED] += 1
                    st[C.ACCEPTED] += 1
                    st[C.LEVELS] += 1
                    _emit_piece(out, state, opts, c)
                    continue
                if accepted and decisions.given and g < last:
                    _emit_flattened(out, state, work, opts, x0, y0, decisions.points,
                                    decisions.point_start[g], decisions.point_start[g + 1])
                    continue
                if rejected:
                    st[C.EVALUATED] += 1
                    st[C.REJECTED] += 1
                    st[C.LEVELS] += 1
                    si[_BROKEN] = 1
                    if fill:
                        _clamp_to(out, state, window, x3, y3)
                    else:
                        si[_OPEN] = 0
                    continue
                if opts.exact and opts.leaf_depth == 0 and not opts.flatten:
                    st[C.EVALUATED] += 1
                    st[C.LEVELS] += 1
                    _emit_exact(out, state, work, opts, window, c)
                    continue
                clip_segment(out, state, work, opts, window, c)
            i = j
        if out.write:
            for s in range(s0, si[_S]):
                out.closed[s] = False
        if fill or (closed and si[_S] != s0):
            _end_subpath(out, state, opts, window, closed, controls[last - 1, 3, 0],
                         controls[last - 1, 3, 1])
        if not out.write:
            layout.n_segments[k] = si[_V]
            layout.n_subpaths[k] = si[_S]


@parallel
def clip_path_blocks(paths, windows, opts, decisions, layout, out, counters, block_size):
    """Count (``out.write`` False) or write the clipped subpaths of a path array.

    Subpath k of `paths` (`PathInput`) is cut to its path's window (`windows`, a
    `records.WindowRows`: one window for all, or one per path) as `opts` says, block by block
    (`block_size` subpaths each). The count pass stores each subpath's output size in
    ``layout.n_segments``, ``layout.n_subpaths`` (and the stats, one row of `counters`
    per block) and each run's decision in ``decisions.runs``, unless given; the write
    pass writes subpath k's output from ``layout.segment_start[k]`` and
    ``layout.subpath_start[k]`` on: control points and degrees, and for each output
    subpath its first segment, start point, closed flag and source (``paths.source[k]``,
    or -1 for an entry freed by joining the ends of a closed stroke: drop those). The
    write pass reads the runs' decisions, it does not test runs again.
    """
    n = paths.subpath_offsets.shape[0] - 1
    n_blocks = counters.shape[0]
    for blk in prange(n_blocks):
        state = State(np.zeros(_INT_STATE_WIDTH, dtype=np.int64),
                      np.zeros(_FLOAT_STATE_WIDTH, dtype=np.float64))
        work = Work(np.zeros(C.WIDTH, dtype=np.int64) if out.write else counters[blk],
                    np.empty(BREAK_CAPACITY, dtype=np.float64),
                    np.empty(BREAK_CAPACITY, dtype=np.int64),
                    np.empty((CURVE_STACK_CAPACITY, 3), dtype=np.float64))
        _clip_subpaths(paths, windows, opts, decisions, layout, out, state, work,
                       blk * block_size, min(n, (blk + 1) * block_size))


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
