"""Cohen–Sutherland line clipping.

Classify both ends by outcode; accept if both are zero, reject if they share a bit,
otherwise move one outside end to the edge named by one of its bits (TOP, BOTTOM, RIGHT,
LEFT, in that order) and classify again. Each move computes one intersection. The
intersection is computed from the original segment (``t = (edge - x0) / dx``) rather
than from the already-moved ends, so errors do not accumulate and the parameter
interval of the piece is known.
"""

# The loop's bound: rnsca.constants says why 32 steps always decide a segment.
from rnsca.constants import CS_MAX_MOVES as _MAX_MOVES
from rnsca.kernels import counters as C
from rnsca.kernels.jit import scalar
from rnsca.kernels.outcode import (
    BOTTOM,
    EDGE_BOTTOM,
    EDGE_LEFT,
    EDGE_RIGHT,
    EDGE_TOP,
    LEFT,
    RIGHT,
    TOP,
    edge_point_code,
    is_piece,
    outcode,
)


@scalar
def _edge_parameter(code, x0, y0, dx, dy, window):
    """Return (t, edge, bit) where the segment's line crosses the edge named by `code`."""
    if code & TOP:
        return (window.ymax - y0) / dy, EDGE_TOP, TOP
    if code & BOTTOM:
        return (window.ymin - y0) / dy, EDGE_BOTTOM, BOTTOM
    if code & RIGHT:
        return (window.xmax - x0) / dx, EDGE_RIGHT, RIGHT
    return (window.xmin - x0) / dx, EDGE_LEFT, LEFT


@scalar
def cohen_sutherland_segment(x0, y0, x1, y1, window, st):
    """Clip one segment with Cohen–Sutherland: move an outside end to an edge, test again.

    At most `_MAX_MOVES` moves, one intersection each; the moved end is the true cut
    point's (`edge_point_code`). Returns as every method does (`segments.clip_one`).
    """
    xmin, ymin, xmax, ymax = window
    dx = x1 - x0
    dy = y1 - y0
    t0 = 0.0
    t1 = 1.0
    ax, ay, bx, by = x0, y0, x1, y1
    ca = outcode(ax, ay, xmin, ymin, xmax, ymax)
    cb = outcode(bx, by, xmin, ymin, xmax, ymax)
    for _ in range(_MAX_MOVES):
        st[C.EVALUATED] += 1
        st[C.LEVELS] += 1
        if (ca | cb) == 0:
            st[C.ACCEPTED] += 1
            return is_piece(dx == 0.0 and dy == 0.0, t0, t1, ax, ay, bx, by), t0, t1, ax, ay, bx, by
        if ca & cb:
            st[C.REJECTED] += 1
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        st[C.CLIPPED] += 1
        st[C.INTERSECTIONS] += 1
        if ca != 0:
            t, edge, bit = _edge_parameter(ca, x0, y0, dx, dy, window)
            if t > t0:
                t0 = t
                # The moved end is not clamped: the next outcode test must see it, and
                # sees the true point, not its rounding (see `edge_point_code`).
                ax, ay, ca = edge_point_code(x0, y0, x1, y1, edge, window)
            else:
                ca &= ~bit  # the end is already past this edge's crossing
        else:
            t, edge, bit = _edge_parameter(cb, x0, y0, dx, dy, window)
            if t < t1:
                t1 = t
                bx, by, cb = edge_point_code(x0, y0, x1, y1, edge, window)
            else:
                cb &= ~bit
        if t0 > t1:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # Unreachable (see _MAX_MOVES); an undecided segment never yields an unclipped end.
    return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
