"""Cohen–Sutherland outcodes and the scalar pieces every segment method shares.

The plane around the closed window is cut into nine regions; a point's outcode has one
bit per window edge it lies beyond (strict comparisons, so the boundary is inside)::

          1001 | 1000 | 1010          TOP    = 8
          -----+------+-----          BOTTOM = 4
          0001 | 0000 | 0010          RIGHT  = 2
          -----+------+-----          LEFT   = 1
          0101 | 0100 | 0110

A piece whose two outcodes are both zero is inside (the window is convex); a piece whose
outcodes share a bit lies wholly beyond that edge; anything else is ambiguous.
"""

import math

# The bits, the edge ids (NO_EDGE: the end was not cut) and the wide-code layout are
# defined in rnsca.constants, shared with clip.cl; importable from here as before.
from rnsca.constants import (
    BOTTOM,
    EDGE_BOTTOM,
    EDGE_LEFT,
    EDGE_RIGHT,
    LEFT,
    NO_EDGE,
    RIGHT,
    SURE_SHIFT,
    TOP,
    UNSURE_BITS,
)
from rnsca.constants import EDGE_TOP as EDGE_TOP  # re-exported (not used here)
from rnsca.kernels import counters as C
from rnsca.kernels.jit import inlined, scalar
from rnsca.kernels.records import Direction


@scalar
def outcode(x, y, xmin, ymin, xmax, ymax):
    """Return the 4-bit outcode of (x, y); 0 for a point inside or on the boundary."""
    # Bit arithmetic rather than if/elif: the comparisons are data-dependent, and a
    # mispredicted branch costs more than the whole computation.
    return ((x < xmin) * LEFT) | ((x > xmax) * RIGHT) | ((y < ymin) * BOTTOM) | ((y > ymax) * TOP)


# Points interpolated inside a segment, ``x0 + t * (x1 - x0)``, are rounded: their
# outcodes alone could accept a piece lying an ulp outside an edge. Subdivision methods
# therefore classify such points with a "wide" code: bits 0-3 name the edges the point
# is not surely inside of, bits 4-7 the edges it is surely beyond, given the rounding
# bound of `interpolation_margin`. A piece is accepted only if both its ends are surely
# inside (wide codes OR to 0), rejected only if both are surely beyond one edge (AND of
# the high bits), and otherwise stays ambiguous, so it is refined, clipped exactly, or
# (approx mode) dropped. An exact point (an input end point) has ``wide(c)``.


@scalar
def wide(code):
    """Return the wide code of an exactly known point with outcode `code`."""
    return code | (code << SURE_SHIFT)


# Veltkamp's splitter for Dekker's exact product (2**27 + 1): no fused multiply-add is
# needed, so the compiled kernels, plain Python and OpenCL round identically.
_SPLITTER = 134217729.0


@inlined
def two_product(a, b):
    """Return (p, e): ``p = a * b`` rounded and ``p + e == a * b`` exactly (Dekker's TwoProduct).

    Each factor is split into halves of 26 bits (Veltkamp), whose products are exact.
    Exact while no partial product overflows or underflows: |a|, |b| below about 1e300,
    a * b not subnormal. Shared by the segment kernels and `rnsca.io.svgwrite`; inlined,
    so the split of a factor used twice is computed once (`line_coordinate_dd`).
    """
    p = a * b
    c = _SPLITTER * a
    ah = c - (c - a)
    al = a - ah
    c = _SPLITTER * b
    bh = c - (c - b)
    bl = b - bh
    return p, (((ah * bh - p) + ah * bl) + al * bh) + al * bl


def interpolate_dd(a0, da, da_err, t):
    """Return (a, err): ``a = a0 + t * da`` as the kernels round it, and its error.

    ``a + err`` is ``a0 + t * (da + da_err)`` (the point of the exact segment at t) up
    to a rounding of `err` itself: Dekker's TwoProduct and Knuth's TwoSum recover the
    two roundings, and `da_err` is that of the direction. Plain arithmetic and
    `two_product`, shared by Numba (jitted below) and NumPy.
    """
    p, p_err = two_product(t, da)
    a = a0 + p  # TwoSum(a0, p)
    v = a - a0
    a_err = (a0 - (a - v)) + (p - v)
    return a, a_err + p_err + t * da_err


_interpolate_dd = scalar(interpolate_dd)


@scalar
def interpolation_margin(err, a0, da):
    """Return (correction, margin) for a rounded interpolated coordinate.

    The true coordinate is the rounded one plus `correction`, to within `margin`.
    `err`, from `interpolate_dd`, is itself rounded (to an ulp of a tiny number). Where
    its splitting overflowed (|coordinates| beyond ~1e300) it is not finite: then no
    correction, and the a-priori bound of three roundings, 4 eps (|a0| + |da|).
    """
    if not math.isfinite(err):
        return 0.0, 8.881784197001252e-16 * abs(a0) + 8.881784197001252e-16 * abs(da) + 1e-323
    # Error terms of a direction below ~1e-290 can underflow into the subnormals, where
    # they are no longer exact: allow a few subnormal steps there.
    floor = 1e-322 if da != 0.0 and abs(da) < 1e-290 else 0.0
    return err, abs(err) * 8.881784197001252e-16 + floor




@scalar
def wide_outcode(x, y, cx, mx, cy, my, window):
    """Return the wide code of the true point (x + cx, y + cy), known to within mx, my.

    Distances to the edges of `window` (a `rnsca.kernels.records.Window`) are formed
    from the rounded point (exact near an edge, where it matters) plus the correction,
    and compared with the margins: so a point is unsure only when it lies within its
    own tiny residual error of an edge.
    """
    dl = (x - window.xmin) + cx
    dr = (window.xmax - x) - cx
    db = (y - window.ymin) + cy
    dt = (window.ymax - y) - cy
    unsure = (dl < mx) * LEFT | (dr < mx) * RIGHT | (db < my) * BOTTOM | (dt < my) * TOP
    sure = (-dl > mx) * LEFT | (-dr > mx) * RIGHT | (-db > my) * BOTTOM | (-dt > my) * TOP
    return unsure | (sure << SURE_SHIFT)


@inlined
def interpolated_point(x0, y0, d, t, window):
    """Return (x, y, code): the point at t of the segment from (x0, y0) along `d`.

    `d` is the segment's `Direction`. The point is rounded, then moved by the correction
    `interpolation_margin` finds (so an output end lies as near the true point as it
    can), and `code` is the `wide_outcode` of the true point within the margins.
    Inlined: the subdivision loops run it per point (as a call, RNSCA and midpoint in
    approx mode ran about 30% more instructions).
    """
    x, x_err = _interpolate_dd(x0, d.dx, d.dx_err, t)
    y, y_err = _interpolate_dd(y0, d.dy, d.dy_err, t)
    cx, mx = interpolation_margin(x_err, x0, d.dx)
    cy, my = interpolation_margin(y_err, y0, d.dy)
    return x + cx, y + cy, wide_outcode(x, y, cx, mx, cy, my, window)


@scalar
def clamp(v, low, high):
    """Return v limited to [low, high]."""
    return min(max(v, low), high)


def difference_dd(x1, x0):
    """Return (d, d_err) with ``d + d_err == x1 - x0`` exactly (Knuth's TwoSum)."""
    d = x1 - x0
    v = d - x1
    return d, (x1 - (d - v)) + (-x0 - v)


def line_coordinate_dd(e, a, b, da, da_err, db, db_err):
    """Return ``b + ((e - a) / da) * db`` carried in double-double, to about one ulp.

    (da + da_err, db + db_err) is the segment's direction, exactly. The cut point of a
    long segment lies far from both its ends: computed plainly, the rounding of the
    direction and of the parameter, times the segment's length, can exceed the window's
    own size (a segment 1e8 windows long misses by ~1e-8 of the window). Every rounding
    step here keeps its error term (Knuth's TwoSum, Dekker's TwoProduct). The parameter
    is formed first, so with the nearer end as base |t| <= 1/2 and no product underflows
    or overflows that the result would not. Plain arithmetic and `two_product` only, so
    this one function serves Numba (jitted below) and NumPy arrays alike. Returns the
    rounded value and its residual (true minus rounded); NaN when a split overflows
    (magnitudes beyond ~1e300), and callers then fall back to the plain formula.
    """
    s = e - a  # TwoSum(e, -a), written out: the jitted copy may call no plain function
    v = s - e
    s_err = (e - (s - v)) + (-a - v)
    t = s / da
    r, r_err = two_product(t, da)
    # t + t_lo == (e - a) / (da + da_err) to ~eps**2
    t_lo = ((((s - r) - r_err) + s_err) - t * da_err) / da
    p, p_err = two_product(t, db)
    p_err += t_lo * db + t * db_err
    y = b + p  # TwoSum(b, p)
    v = y - b
    y_err = (b - (y - v)) + (p - v)
    e = y_err + p_err
    z = y + e  # TwoSum(y, e): the rounded result and what rounding left out
    v = z - y
    return z, (y - (z - v)) + (e - v)


_difference_dd = scalar(difference_dd)
_line_coordinate_dd = scalar(line_coordinate_dd)


@scalar
def direction(x0, y0, x1, y1):
    """Return the `Direction` of the segment from (x0, y0) to (x1, y1), errors included."""
    dx, dx_err = _difference_dd(x1, x0)
    dy, dy_err = _difference_dd(y1, y0)
    return Direction(dx, dx_err, dy, dy_err)


@scalar
def line_coordinate_residual(e, a0, b0, a1, b1):
    """Return (b, residual): the line's b-coordinate where its a equals e, and the rest.

    The line runs through (a0, b0), (a1, b1); `b` is rounded and `residual` is the true
    value minus `b`. Measured from the nearer end (so a cut at an end point returns that
    end exactly), in double-double (`line_coordinate_dd`), falling back to plain
    arithmetic (and a zero residual) where that overflows (coordinates beyond ~1e300).
    """
    near1 = abs(e - a1) < abs(e - a0)
    a = a1 if near1 else a0
    b = b1 if near1 else b0
    da, da_err = _difference_dd(a1, a0)
    db, db_err = _difference_dd(b1, b0)
    precise, residual = _line_coordinate_dd(e, a, b, da, da_err, db, db_err)
    if math.isfinite(precise) and math.isfinite(residual):
        return precise, residual
    return b + (e - a) / da * db, 0.0


@scalar
def line_coordinate(e, a0, b0, a1, b1):
    """Return the b-coordinate of the line through (a0, b0), (a1, b1) where its a equals e.

    From the nearer end, ``b + (e - a) / da * db`` is within a few ulps of the result
    unless the segment is long compared with the result's magnitude (its error is about
    eps (|b| + |db|)); only then is the double-double `line_coordinate_residual` needed.
    Either way a cut at an end point returns that end exactly.
    """
    near1 = abs(e - a1) < abs(e - a0)
    a = a1 if near1 else a0
    b = b1 if near1 else b0
    db = b1 - b0
    plain = b + (e - a) / (a1 - a0) * db
    # Below ~1e-290 the double-double error terms underflow and stop being exact.
    if abs(b) + abs(db) <= 16.0 * abs(plain) or abs(db) < 1e-290:
        return plain
    return line_coordinate_residual(e, a0, b0, a1, b1)[0]


@scalar
def edge_point_code(x0, y0, x1, y1, edge, window):
    """Return (x, y, code): `edge_point` and the outcode of the true point it rounds.

    A rounded cut point can land inside the window while the true one lies a fraction
    of an ulp outside (a segment nearly parallel to an edge); its residual decides.
    """
    if edge == EDGE_LEFT or edge == EDGE_RIGHT:
        x = window.xmin if edge == EDGE_LEFT else window.xmax
        y, r = line_coordinate_residual(x, x0, y0, x1, y1)
        return x, y, wide_outcode(x, y, 0.0, 0.0, r, 0.0, window) & UNSURE_BITS
    y = window.ymin if edge == EDGE_BOTTOM else window.ymax
    x, r = line_coordinate_residual(y, y0, x0, y1, x1)
    return x, y, wide_outcode(x, y, r, 0.0, 0.0, 0.0, window) & UNSURE_BITS


@scalar
def edge_point(x0, y0, x1, y1, edge, window):
    """Return the point where the segment's line meets the line of `edge`.

    The coordinate across the edge is the edge's own value exactly (the intersection
    lies on the edge line by definition); the other is `line_coordinate`, not clamped.
    """
    if edge == EDGE_LEFT:
        return window.xmin, line_coordinate(window.xmin, x0, y0, x1, y1)
    if edge == EDGE_RIGHT:
        return window.xmax, line_coordinate(window.xmax, x0, y0, x1, y1)
    if edge == EDGE_BOTTOM:
        return line_coordinate(window.ymin, y0, x0, y1, x1), window.ymin
    return line_coordinate(window.ymax, y0, x0, y1, x1), window.ymax


@scalar
def snap_into_window(x, y, x0, y0, x1, y1, window):
    """Return a piece end on the segment's line, moved along the line into the window.

    A cut end is chosen by comparing parameters t, which cannot tell two edges apart
    when the segment is so long (~1e15 windows) that the window spans less than an ulp
    of t; the end then lands on the line of the wrong edge, outside the window in its
    other coordinate. Sliding it along the line to the edge it overshoots puts it back
    on the true boundary. Every coordinate is then clamped (the last-ulp overshoot).
    Rarely taken branches, outside the vectorized loops.
    """
    xmin, ymin, xmax, ymax = window
    if y > ymax or y < ymin:
        edge = ymax if y > ymax else ymin
        x = line_coordinate(edge, y0, x0, y1, x1)
        y = edge
    if x > xmax or x < xmin:
        edge = xmax if x > xmax else xmin
        y = line_coordinate(edge, x0, y0, x1, y1)
        x = edge
    return clamp(x, xmin, xmax), clamp(y, ymin, ymax)


@scalar
def end_point(x0, y0, x1, y1, edge, px, py, window):
    """Return the coordinates of a piece end, inside the window.

    An end not cut by an edge (``edge == NO_EDGE``) is the known point (px, py); an end
    cut by an edge is `edge_point`. Either is then moved into the window by
    `snap_into_window` (a no-op for a known point inside it).
    """
    x, y = px, py
    if edge != NO_EDGE:
        x, y = edge_point(x0, y0, x1, y1, edge, window)
    return snap_into_window(x, y, x0, y0, x1, y1, window)


@scalar
def common_end_point(x0, y0, x1, y1, edge, px, py, window):
    """Return (x, y, sure): a piece end by `end_point`'s common path, without branches.

    Where `sure`, (x, y) is what `end_point` returns, bit for bit: the end is not cut
    (the known point (px, py)) or cut with `line_coordinate`'s plain formula, and lies
    in the window, so `snap_into_window` would not move it. Otherwise the caller calls
    `end_point` (double-double cut, snapping: rare). Selects only, so the loop over a
    block's ends vectorizes; a branch on the edge id (random on real data) cost most of
    the exact clip (177 of 221 ms of compute on 10M uniform segments, 2 threads).
    """
    xmin, ymin, xmax, ymax = window
    cut = edge != NO_EDGE
    across_x = (edge == EDGE_LEFT) | (edge == EDGE_RIGHT)
    # The edge's value, and the segment in (a, b) coordinates: a across the edge.
    value = xmin if edge == EDGE_LEFT else (
        xmax if edge == EDGE_RIGHT else (ymin if edge == EDGE_BOTTOM else ymax))
    a0 = x0 if across_x else y0
    b0 = y0 if across_x else x0
    a1 = x1 if across_x else y1
    b1 = y1 if across_x else x1
    # line_coordinate(value, a0, b0, a1, b1), its plain formula and its test.
    near1 = abs(value - a1) < abs(value - a0)
    a = a1 if near1 else a0
    b = b1 if near1 else b0
    db = b1 - b0
    da = a1 - a0
    plain = b + (value - a) / (da if cut else 1.0) * db
    plain_enough = (abs(b) + abs(db) <= 16.0 * abs(plain)) | (abs(db) < 1e-290)
    x = (value if across_x else plain) if cut else px
    y = (plain if across_x else value) if cut else py
    inside = (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)
    return x, y, inside & (plain_enough | (not cut))


@scalar
def is_piece(degenerate, t0, t1, ax, ay, bx, by):
    """Return whether [t0, t1] with ends (ax, ay), (bx, by) is an output piece.

    A zero-length input segment inside the window is kept as it is; for any other
    segment, an empty interval or a single point (the segment only touches the window)
    is not a piece.
    """
    return (t0 <= t1) & (degenerate | (ax != bx) | (ay != by))


@inlined
def piece_of_interval(x0, y0, x1, y1, degenerate, u0, e0, u1, e1, window, st):
    """Return (keep, t0, t1, ax, ay, bx, by) for the visible interval [u0, u1] of a segment.

    For the methods that find the interval before any end point (Liang–Barsky,
    Nicholl–Lee–Nicholl), once they know it is not empty: `e0`, `e1` name the edge that
    cut each end, ``NO_EDGE`` for an end of the segment itself; `degenerate`, the
    segment has zero length (`is_piece`). Counts the segment in `st` as accepted or
    clipped, and computes each end once (`end_point`). Inlined: as a call, Liang–Barsky
    and NLL ran 11% more instructions.
    """
    if e0 == NO_EDGE and e1 == NO_EDGE:
        st[C.ACCEPTED] += 1
    else:
        st[C.CLIPPED] += 1
    ax, ay = end_point(x0, y0, x1, y1, e0, x0, y0, window)
    bx, by = end_point(x0, y0, x1, y1, e1, x1, y1, window)
    keep = is_piece(degenerate, u0, u1, ax, ay, bx, by)
    return keep, u0, u1, ax, ay, bx, by
