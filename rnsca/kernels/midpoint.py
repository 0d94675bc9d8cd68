"""Midpoint subdivision (Sproull and Sutherland, 1968).

Two binary searches, no intersection: the farthest visible point from P0 (the exit) and
the farthest visible point from P1 (the entry). Searching for the exit, the bracket
[a, b] is halved at m; if the half [m, b] is trivially invisible (its outcodes share a
bit) the exit lies in [a, m], otherwise in [m, b]. The second rule is sound because the
window is convex: past the exit, every point lies beyond the exit edge, so a half that
starts past the exit is always trivially invisible. The search stops when the bracket is
no longer than `tol` or `max_depth` halvings were made.

The final bracket is the leaf. In approx mode it is dropped and the visible end of the
bracket is the piece's end, so no point is outside and at most one bracket length is
lost per end; in exact mode the bracket is clipped with Liang–Barsky, as RNSCA does.
"""

import math

from rnsca.kernels import counters as C
from rnsca.kernels.jit import inlined, scalar
from rnsca.kernels.liang_barsky import liang_barsky_leaf
from rnsca.kernels.outcode import (
    SURE_SHIFT,
    UNSURE_BITS,
    direction,
    interpolated_point,
    is_piece,
    outcode,
    wide,
)
from rnsca.kernels.records import Fragment


@inlined  # into each `_piece_end`, itself inlined: `toward_end` folds (see `_piece_end`)
def _search(x0, y0, x1, y1, c0, c1, length, toward_end, window, options, st):
    """Return (bracket, level): the final bracket of one search, a `Fragment`, and its depth.

    ``toward_end=True`` brackets the exit (the farthest visible point from P0), else
    the entry (the farthest visible point from P1). `c0`, `c1` are the wide codes of
    P0 and P1, and the bracket's too (``rnsca.kernels.outcode``): bisection points are
    rounded. `window` is a `Window`, `options` the `CoreOptions` (max_depth, tol, exact).

    The bracket's far end is surely past the searched end. Its near end, in exact mode,
    is the last point the search found surely inside (or the search's start point), so
    the leaf clip finds the searched end exactly. In approx mode it is the classic near
    end if that is at worst within rounding of the boundary and the search did pass a
    surely inside point, else that last surely inside point: a segment lying an ulp
    outside an edge never yields a piece.
    """
    d = direction(x0, y0, x1, y1)
    a = 0.0
    xa, ya, ca = x0, y0, c0
    b = 1.0
    xb, yb, cb = x1, y1, c1
    # The last near end surely inside, initially the search's start point.
    if toward_end:
        st_t, st_x, st_y, st_c = a, xa, ya, ca
    else:
        st_t, st_x, st_y, st_c = b, xb, yb, cb
    found = False
    level = 0
    while level < options.max_depth and (b - a) * length > options.tol:
        m = a + (b - a) * 1 / 2
        xm, ym, cm = interpolated_point(x0, y0, d, m, window)
        level += 1
        st[C.EVALUATED] += 1
        # The half on the far side of the searched end: [m, b] for the exit, [a, m] for the entry.
        far = cb if toward_end else ca
        if (cm & far) >> SURE_SHIFT:
            st[C.REJECTED] += 1
            st[C.LEVELS + level] += 1
            if toward_end:
                b, xb, yb, cb = m, xm, ym, cm
            else:
                a, xa, ya, ca = m, xm, ym, cm
        else:
            st[C.SUBDIVIDED] += 1
            if toward_end:
                a, xa, ya, ca = m, xm, ym, cm
            else:
                b, xb, yb, cb = m, xm, ym, cm
            if (cm & UNSURE_BITS) == 0:
                st_t, st_x, st_y, st_c = m, xm, ym, cm
                found = True
    if level > st[C.DEEPEST]:
        st[C.DEEPEST] = level
    near_t, near_c = (a, ca) if toward_end else (b, cb)
    if not found and (near_c >> SURE_SHIFT) == 0 and near_t != st_t:
        # The search jumped from its start straight to the boundary: the point halfway
        # back tells a segment that runs inside (surely inside there) from one that lies
        # within rounding outside an edge all along.
        lo = min(near_t, st_t)
        hi = max(near_t, st_t)
        h = lo + (hi - lo) * 1 / 2
        found = (interpolated_point(x0, y0, d, h, window)[2] & UNSURE_BITS) == 0
    # In approx mode a near end within rounding of the boundary counts as visible (0).
    if toward_end:
        if options.exact or not (found and (ca >> SURE_SHIFT) == 0):
            a, xa, ya, ca = st_t, st_x, st_y, st_c
        else:
            ca = 0
        return Fragment(a, xa, ya, ca, b, xb, yb, cb), level
    if options.exact or not (found and (cb >> SURE_SHIFT) == 0):
        b, xb, yb, cb = st_t, st_x, st_y, st_c
    else:
        cb = 0
    return Fragment(a, xa, ya, ca, b, xb, yb, cb), level


@scalar
def _leaf(x0, y0, x1, y1, bracket, level, window, exact, st):
    """Decide a final bracket; return (ok, u0, ax, ay, u1, bx, by) of its visible part.

    `bracket` is a `Fragment` found at depth `level`. In approx mode the visible part is
    the bracket's visible end alone (u0 == u1).
    """
    a, xa, ya, ca, b, xb, yb, cb = bracket
    st[C.EVALUATED] += 1
    st[C.LEVELS + level] += 1
    if (ca & cb) >> SURE_SHIFT:
        st[C.REJECTED] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if (ca | cb) == 0:
        st[C.ACCEPTED] += 1
        return True, a, xa, ya, b, xb, yb
    if not exact:
        st[C.DROPPED] += 1
        if ca == 0:
            return True, a, xa, ya, a, xa, ya
        if cb == 0:
            return True, b, xb, yb, b, xb, yb
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    st[C.CLIPPED] += 1
    ok, u0, px, py, u1, qx, qy, divisions = liang_barsky_leaf(x0, y0, x1, y1, bracket, window)
    st[C.INTERSECTIONS] += divisions
    if not ok:
        # Rounding: when the window's corner or edge is ulp-close to a bracket end that
        # tested inside, Liang–Barsky can find [a, b] empty; that end is the piece's end.
        if ca == 0:
            return True, a, xa, ya, a, xa, ya
        if cb == 0:
            return True, b, xb, yb, b, xb, yb
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return True, u0, px, py, u1, qx, qy


@inlined
def _piece_end(x0, y0, x1, y1, c0, c1, length, toward_end, window, options, st):
    """Return (ok, t, x, y): the piece's exit (``toward_end``) or its entry.

    The end itself (P1, or P0) when its outcode (`c1`, or `c0`) is zero; else the end
    that `_search` brackets and `_leaf` decides. Not `ok` when that leaf holds nothing
    visible. The other parameters are those of `midpoint_segment` and `_search`.
    Inlined, and `_search` into it, so each call site searches with `toward_end` a
    constant, as written out (a compiled `_search` called with it as an argument: 13%
    slower on the approx benchmark, `benchmarks.compare`).
    """
    if toward_end and c1 == 0:
        return True, 1.0, x1, y1
    if not toward_end and c0 == 0:
        return True, 0.0, x0, y0
    bracket, level = _search(x0, y0, x1, y1, wide(c0), wide(c1), length, toward_end,
                             window, options, st)
    ok, u0, ax, ay, u1, bx, by = _leaf(x0, y0, x1, y1, bracket, level, window,
                                       options.exact, st)
    if toward_end:
        return ok, u1, bx, by
    return ok, u0, ax, ay


@scalar
def midpoint_segment(x0, y0, x1, y1, window, options, st):
    """Clip one segment by midpoint subdivision; return (keep, t0, t1, ax, ay, bx, by).

    `window` is a `rnsca.kernels.records.Window`, `options` the `CoreOptions` (max_depth,
    tol, exact are read); `st` the block's counter row.
    """
    exact = options.exact
    dx = x1 - x0
    dy = y1 - y0
    length = math.hypot(dx, dy)
    c0 = outcode(x0, y0, window.xmin, window.ymin, window.xmax, window.ymax)
    c1 = outcode(x1, y1, window.xmin, window.ymin, window.xmax, window.ymax)
    if (c0 | c1) == 0 or c0 & c1 or options.max_depth == 0 or length <= options.tol:
        # Decided at level 0 (accepted, rejected, or the whole segment is the leaf).
        whole = Fragment(0.0, x0, y0, wide(c0), 1.0, x1, y1, wide(c1))
        ok, t0, ax, ay, t1, bx, by = _leaf(x0, y0, x1, y1, whole, 0, window, exact, st)
        # A dropped approx leaf leaves one point. (In exact mode t0 == t1 can be a real piece:
        # a window far smaller than the segment lies within one rounding step of t.)
        if not ok or not exact and t0 == t1 and (c0 | c1) != 0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        return is_piece(dx == 0.0 and dy == 0.0, t0, t1, ax, ay, bx, by), t0, t1, ax, ay, bx, by
    st[C.EVALUATED] += 1
    st[C.SUBDIVIDED] += 1
    # The exit first: when nothing is visible, the entry is not searched for.
    ok, t1, bx, by = _piece_end(x0, y0, x1, y1, c0, c1, length, True, window, options, st)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ok, t0, ax, ay = _piece_end(x0, y0, x1, y1, c0, c1, length, False, window, options, st)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return is_piece(False, t0, t1, ax, ay, bx, by), t0, t1, ax, ay, bx, by
