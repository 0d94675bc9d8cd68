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

from rnsca.kernels.jit import scalar

LEFT = 1
RIGHT = 2
BOTTOM = 4
TOP = 8

# Edge identifiers for the end of a clipped piece; NO_EDGE: the end was not cut.
NO_EDGE = -1
EDGE_LEFT = 0
EDGE_RIGHT = 1
EDGE_BOTTOM = 2
EDGE_TOP = 3


@scalar
def outcode(x, y, xmin, ymin, xmax, ymax):
    """Return the 4-bit outcode of (x, y); 0 for a point inside or on the boundary."""
    # Bit arithmetic rather than if/elif: the comparisons are data-dependent, and a
    # mispredicted branch costs more than the whole computation.
    return ((x < xmin) * LEFT) | ((x > xmax) * RIGHT) | ((y < ymin) * BOTTOM) | ((y > ymax) * TOP)


@scalar
def clamp(v, low, high):
    """Return v limited to [low, high]."""
    return min(max(v, low), high)


@scalar
def edge_point(x0, y0, dx, dy, t, edge, xmin, ymin, xmax, ymax):
    """Return the point at parameter `t`, which lies on the line of `edge`.

    The coordinate across the edge is the edge's own value exactly (the intersection
    lies on the edge line by definition); the other is interpolated, not clamped.
    """
    if edge == EDGE_LEFT:
        return xmin, y0 + t * dy
    if edge == EDGE_RIGHT:
        return xmax, y0 + t * dy
    if edge == EDGE_BOTTOM:
        return x0 + t * dx, ymin
    return x0 + t * dx, ymax


@scalar
def end_point(x0, y0, dx, dy, t, edge, px, py, xmin, ymin, xmax, ymax):
    """Return the coordinates of a piece end at parameter `t` of the segment.

    An end not cut by an edge (``edge == NO_EDGE``) is the known point (px, py). An end
    cut by an edge takes that edge's coordinate exactly (the intersection lies on the
    edge line by definition), and the other coordinate is interpolated and clamped into
    the window: the last-ulp overshoot of ``y0 + t * dy`` must not put a point outside.
    Written with selects only, so it costs no mispredicted branch.
    """
    xi = clamp(x0 + t * dx, xmin, xmax)
    yi = clamp(y0 + t * dy, ymin, ymax)
    x = xmin if edge == EDGE_LEFT else (xmax if edge == EDGE_RIGHT else xi)
    y = ymin if edge == EDGE_BOTTOM else (ymax if edge == EDGE_TOP else yi)
    uncut = edge == NO_EDGE
    return (px if uncut else x), (py if uncut else y)


@scalar
def is_piece(degenerate, t0, t1, ax, ay, bx, by):
    """Return whether [t0, t1] with ends (ax, ay), (bx, by) is an output piece.

    A zero-length input segment inside the window is kept as it is; for any other
    segment, an empty interval or a single point (the segment only touches the window)
    is not a piece.
    """
    return (t0 <= t1) & (degenerate | (ax != bx) | (ay != by))
