"""Liang–Barsky parametric line clipping.

Y.-D. Liang and B. A. Barsky, "A new concept and method for line clipping", ACM TOG 3(1),
1984. The segment ``P(t) = P0 + t (P1 - P0)`` is inside the window where
``p_k t <= q_k`` for the four half-planes; each ``p_k != 0`` gives one boundary parameter
``q_k / p_k`` (one division, counted as one intersection). Entering parameters raise the
lower end of the interval, leaving ones lower the upper end. RNSCA clips its exact-mode
leaves with `liang_barsky_interval`, restricted to the leaf's interval.
"""

from rnsca.kernels import counters as C
from rnsca.kernels.jit import scalar
from rnsca.kernels.outcode import (
    EDGE_BOTTOM,
    EDGE_LEFT,
    EDGE_RIGHT,
    EDGE_TOP,
    NO_EDGE,
    end_point,
    is_piece,
)


@scalar
def _clipt(p, q, edge, u0, e0, u1, e1, st):
    """Apply one half-plane ``p t <= q`` to [u0, u1]; return (ok, u0, e0, u1, e1)."""
    if p == 0.0:
        # Parallel to this edge: wholly inside its half-plane or wholly outside.
        return q >= 0.0, u0, e0, u1, e1
    r = q / p
    st[C.INTERSECTIONS] += 1
    if p < 0.0:  # entering this half-plane
        if r > u1:
            return False, u0, e0, u1, e1
        if r > u0:
            u0 = r
            e0 = edge
    else:  # leaving it
        if r < u0:
            return False, u0, e0, u1, e1
        if r < u1:
            u1 = r
            e1 = edge
    return True, u0, e0, u1, e1


@scalar
def liang_barsky_interval(x0, y0, dx, dy, ta, tb, xmin, ymin, xmax, ymax, st):
    """Return (ok, u0, e0, u1, e1): the part of [ta, tb] inside the window.

    `e0`, `e1` name the edge that cut each end (``NO_EDGE`` if it was not cut).
    """
    u0 = ta
    u1 = tb
    e0 = NO_EDGE
    e1 = NO_EDGE
    ok, u0, e0, u1, e1 = _clipt(-dx, x0 - xmin, EDGE_LEFT, u0, e0, u1, e1, st)
    if not ok:
        return False, u0, e0, u1, e1
    ok, u0, e0, u1, e1 = _clipt(dx, xmax - x0, EDGE_RIGHT, u0, e0, u1, e1, st)
    if not ok:
        return False, u0, e0, u1, e1
    ok, u0, e0, u1, e1 = _clipt(-dy, y0 - ymin, EDGE_BOTTOM, u0, e0, u1, e1, st)
    if not ok:
        return False, u0, e0, u1, e1
    ok, u0, e0, u1, e1 = _clipt(dy, ymax - y0, EDGE_TOP, u0, e0, u1, e1, st)
    return ok and u0 <= u1, u0, e0, u1, e1


@scalar
def liang_barsky_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st):
    """Clip one segment with Liang–Barsky; return (keep, t0, t1, ax, ay, bx, by)."""
    dx = x1 - x0
    dy = y1 - y0
    st[C.EVALUATED] += 1
    st[C.LEVELS] += 1
    ok, u0, e0, u1, e1 = liang_barsky_interval(x0, y0, dx, dy, 0.0, 1.0,
                                               xmin, ymin, xmax, ymax, st)
    if not ok:
        st[C.REJECTED] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if e0 == NO_EDGE and e1 == NO_EDGE:
        st[C.ACCEPTED] += 1
    else:
        st[C.CLIPPED] += 1
    ax, ay = end_point(x0, y0, dx, dy, u0, e0, x0, y0, xmin, ymin, xmax, ymax)
    bx, by = end_point(x0, y0, dx, dy, u1, e1, x1, y1, xmin, ymin, xmax, ymax)
    keep = is_piece(dx == 0.0 and dy == 0.0, u0, u1, ax, ay, bx, by)
    return keep, u0, u1, ax, ay, bx, by
