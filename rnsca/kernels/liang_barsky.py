"""Liang–Barsky parametric line clipping.

Y.-D. Liang and B. A. Barsky, "A new concept and method for line clipping", ACM TOG 3(1),
1984. The segment ``P(t) = P0 + t (P1 - P0)`` is inside the window where
``p_k t <= q_k`` for the four half-planes; each ``p_k != 0`` gives one boundary parameter
``q_k / p_k`` (one division, counted as one intersection). Entering parameters raise the
lower end of the interval, leaving ones lower the upper end.

Subdivision methods (RNSCA, midpoint) clip their exact-mode leaves with
`liang_barsky_leaf`: the same test restricted to the leaf's interval and to the
half-planes its end codes flag. A half-plane that holds at both ends of a leaf holds
on all of it (it is convex), so skipping it changes nothing and saves the division.
"""

from rnsca.kernels import counters as C
from rnsca.kernels.jit import scalar
from rnsca.kernels.outcode import (
    BOTTOM,
    EDGE_BOTTOM,
    EDGE_LEFT,
    EDGE_RIGHT,
    EDGE_TOP,
    LEFT,
    NO_EDGE,
    RIGHT,
    TOP,
    UNSURE_BITS,
    end_point,
    piece_of_interval,
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
def liang_barsky_interval(x0, y0, dx, dy, ta, tb, window, st):
    """Return (ok, u0, e0, u1, e1): the part of [ta, tb] inside `window` (a `Window`).

    `e0`, `e1` name the edge that cut each end (``NO_EDGE`` if it was not cut).
    """
    xmin, ymin, xmax, ymax = window
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
def liang_barsky_segment(x0, y0, x1, y1, window, st):
    """Clip one segment with Liang–Barsky: its interval in [0, 1], then its two ends.

    Four half-plane tests (`liang_barsky_interval`), one division each unless parallel;
    returns as every method does (`segments.clip_one`).
    """
    dx = x1 - x0
    dy = y1 - y0
    st[C.EVALUATED] += 1
    st[C.LEVELS] += 1
    ok, u0, e0, u1, e1 = liang_barsky_interval(x0, y0, dx, dy, 0.0, 1.0, window, st)
    if not ok:
        st[C.REJECTED] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return piece_of_interval(x0, y0, x1, y1, dx == 0.0 and dy == 0.0, u0, e0, u1, e1,
                             window, st)


@scalar
def half_plane(bit, x0, y0, dx, dy, window):
    """Return (p, q, edge) of the half-plane ``p t <= q`` of the edge with outcode `bit`."""
    if bit == LEFT:
        return -dx, x0 - window.xmin, EDGE_LEFT
    if bit == RIGHT:
        return dx, window.xmax - x0, EDGE_RIGHT
    if bit == BOTTOM:
        return -dy, y0 - window.ymin, EDGE_BOTTOM
    return dy, window.ymax - y0, EDGE_TOP


@scalar
def leaf_cut(bit, flags, u0, e0, u1, e1, x0, y0, x1, y1, window):
    """Apply the half-plane of edge `bit` to a leaf's [u0, u1] when `flags` has that bit.

    Only parameters and the edge ids of the cut ends change, with selects instead of
    branches (the hot loops vectorize); `end_point` then computes each end once.
    """
    p, q, edge = half_plane(bit, x0, y0, x1 - x0, y1 - y0, window)
    on = (flags & bit) != 0
    # Off (or parallel, which an ambiguous leaf never is on a flagged edge): divide by 1
    # so no infinity or NaN is formed; the result is not used.
    r = q / (p if on else 1.0)
    enter = on & (p < 0.0) & (r > u0)  # & rather than `and`: no short-circuit branches
    leave = on & (p > 0.0) & (r < u1)
    u0 = r if enter else u0
    e0 = edge if enter else e0
    u1 = r if leave else u1
    e1 = edge if leave else e1
    return u0, e0, u1, e1


@scalar
def count_divisions(flags):
    """Return the number of edges flagged in an outcode: the divisions a leaf clip makes."""
    return (flags & 1) + ((flags >> 1) & 1) + ((flags >> 2) & 1) + ((flags >> 3) & 1)


@scalar
def liang_barsky_leaf(x0, y0, x1, y1, leaf, window):
    """Return (ok, u0, ax, ay, u1, bx, by, divisions) for a leaf of a segment.

    `leaf` is a `rnsca.kernels.records.Fragment`: its ends are kept where no edge cuts
    them. The half-planes that its ends' codes flag as unsure are tested, one division
    each (`divisions`). A cut end takes the edge's coordinate exactly and the other one
    interpolated and clamped into `window` (a `Window`). Branch-free, for the hot loop.
    """
    flags = (leaf.ca | leaf.cb) & UNSURE_BITS
    u0, e0, u1, e1 = leaf.ta, NO_EDGE, leaf.tb, NO_EDGE
    for bit in (LEFT, RIGHT, BOTTOM, TOP):
        u0, e0, u1, e1 = leaf_cut(bit, flags, u0, e0, u1, e1, x0, y0, x1, y1, window)
    ax, ay = end_point(x0, y0, x1, y1, e0, leaf.xa, leaf.ya, window)
    bx, by = end_point(x0, y0, x1, y1, e1, leaf.xb, leaf.yb, window)
    return u0 <= u1, u0, ax, ay, u1, bx, by, count_divisions(flags)
