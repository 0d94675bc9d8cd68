"""Nicholl–Lee–Nicholl line clipping.

T. M. Nicholl, D. T. Lee and R. A. Nicholl, "An efficient new algorithm for 2-D line
clipping: its development and analysis", SIGGRAPH 1987. The region of P0 among the nine
outcode regions decides which edges can matter; comparing the direction P0->P1 with the
rays from P0 to the window's corners then names the edge of entry and of exit, so at
most two intersections are computed and none is thrown away.

By symmetry only three cases are written: P0 inside, P0 left of the window (edge
region), and P0 below-left (corner region). Reflections ``x -> -x``, ``y -> -y`` and
the swap of axes move every other region into these; all three are exact in floating
point and leave the segment's parameter t unchanged, so the parameters found in the
canonical frame are used directly, and each edge is mapped back for the output point.

Ray tests are signs of cross products; `_turn` rescales vectors whose products would
overflow or underflow, so coordinates from 1e-300 to 1e300 (and subnormal offsets) keep
their geometry.
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
    outcode,
    piece_of_interval,
)
from rnsca.kernels.records import Window

# Products of numbers within these magnitudes neither overflow nor lose to underflow.
_BIG = 2.0 ** 500
_SMALL = 2.0 ** -500


@scalar
def _extreme(x, y):
    """Return whether a product with a component of (x, y) may overflow or underflow."""
    ax = abs(x)
    ay = abs(y)
    return max(ax, ay) > _BIG or 0.0 < ax < _SMALL or 0.0 < ay < _SMALL


@scalar
def _normalized(x, y):
    """Return (x, y) divided by its larger magnitude (sign and direction kept)."""
    m = max(abs(x), abs(y))
    return (x / m, y / m) if m > 0.0 else (x, y)


@scalar
def _turn(ax, ay, bx, by):
    """Return the sign of cross(a, b): +1 if b is counter-clockwise of a, -1 if clockwise.

    When a product of components could overflow or underflow (a magnitude above 2**500
    or a non-zero component below 2**-500), both vectors are first divided by their
    larger magnitude: the sign is unchanged, and ``(5e-17, 0) x (5e-17, -5e-324)`` no
    longer underflows to "collinear".
    """
    if _extreme(ax, ay) or _extreme(bx, by):
        ax, ay = _normalized(ax, ay)
        bx, by = _normalized(bx, by)
    c = ax * by - ay * bx
    return 1 if c > 0.0 else (-1 if c < 0.0 else 0)


@scalar
def _single_edge(code):
    """Return the edge id of a one-bit outcode."""
    if code == LEFT:
        return EDGE_LEFT
    if code == RIGHT:
        return EDGE_RIGHT
    if code == BOTTOM:
        return EDGE_BOTTOM
    return EDGE_TOP


@scalar
def _parameter(edge, px, py, ex, ey, frame, st):
    """Return the parameter where P + t E meets the line of `edge` (one intersection).

    `frame` is the window in the canonical frame (a `Window`), as for every helper here.
    """
    st[C.INTERSECTIONS] += 1
    if edge == EDGE_LEFT:
        return (frame.xmin - px) / ex
    if edge == EDGE_RIGHT:
        return (frame.xmax - px) / ex
    if edge == EDGE_BOTTOM:
        return (frame.ymin - py) / ey
    return (frame.ymax - py) / ey


@scalar
def _exit_from_inside(c1, px, py, ex, ey, frame):
    """Return the exit edge of a segment from an inside P to an outside Q with code c1."""
    if c1 == LEFT or c1 == RIGHT or c1 == BOTTOM or c1 == TOP:
        return _single_edge(c1)
    # Q in a corner region: the ray to that corner splits the two candidate edges.
    cx = frame.xmax if c1 & RIGHT else frame.xmin
    cy = frame.ymax if c1 & TOP else frame.ymin
    ccw = _turn(cx - px, cy - py, ex, ey) > 0
    if c1 == RIGHT | TOP:
        return EDGE_TOP if ccw else EDGE_RIGHT
    if c1 == LEFT | TOP:
        return EDGE_LEFT if ccw else EDGE_TOP
    if c1 == LEFT | BOTTOM:
        return EDGE_BOTTOM if ccw else EDGE_LEFT
    return EDGE_RIGHT if ccw else EDGE_BOTTOM


@scalar
def _exit_from_left(px, py, ex, ey, frame):
    """Return the exit edge for a direction already known to cross the window from the left."""
    _, bottom, right, top = frame
    if _turn(right - px, top - py, ex, ey) > 0:
        return EDGE_TOP
    if _turn(right - px, bottom - py, ex, ey) < 0:
        return EDGE_BOTTOM
    return EDGE_RIGHT


@scalar
def _canonical_clip(px, py, qx, qy, frame, st):
    """Clip P->Q in the canonical frame, P inside, left, or below-left of the window.

    `frame` is the window in that frame (a `Window`). Returns (ok, u0, e0, u1, e1),
    edges in the canonical frame.
    """
    left, bottom, right, top = frame
    ex = qx - px
    ey = qy - py
    c0 = outcode(px, py, left, bottom, right, top)
    c1 = outcode(qx, qy, left, bottom, right, top)
    if c0 == 0:
        if c1 == 0:
            return True, 0.0, NO_EDGE, 1.0, NO_EDGE
        e1 = _exit_from_inside(c1, px, py, ex, ey, frame)
        # Q is outside, so the exit comes before it: a parameter past 1 is rounding.
        u1 = min(_parameter(e1, px, py, ex, ey, frame, st), 1.0)
        return True, 0.0, NO_EDGE, u1, e1
    if c1 & c0:
        return False, 0.0, NO_EDGE, 0.0, NO_EDGE
    if c0 == LEFT:
        # The window is visible from P between the rays to its bottom-left and top-left
        # corners; a direction outside that cone misses it.
        if _turn(left - px, bottom - py, ex, ey) < 0 or _turn(ex, ey, left - px, top - py) < 0:
            return False, 0.0, NO_EDGE, 0.0, NO_EDGE
        e0 = EDGE_LEFT
    else:  # LEFT | BOTTOM: visible between the rays to bottom-right and top-left
        if c1 & (LEFT | BOTTOM):
            return False, 0.0, NO_EDGE, 0.0, NO_EDGE
        if _turn(right - px, bottom - py, ex, ey) < 0 or _turn(ex, ey, left - px, top - py) < 0:
            return False, 0.0, NO_EDGE, 0.0, NO_EDGE
        # Steeper than the ray to the bottom-left corner: enters through the left edge.
        e0 = EDGE_LEFT if _turn(left - px, bottom - py, ex, ey) >= 0 else EDGE_BOTTOM
    u0 = _parameter(e0, px, py, ex, ey, frame, st)
    if c1 == 0:
        return True, max(u0, 0.0), e0, 1.0, NO_EDGE
    e1 = _exit_from_left(px, py, ex, ey, frame)
    u1 = min(_parameter(e1, px, py, ex, ey, frame, st), 1.0)
    return u0 <= u1, max(u0, 0.0), e0, u1, e1


@scalar
def _original_edge(edge, flip_x, flip_y, swap):
    """Map an edge of the canonical frame back to the window's own edge."""
    if edge == NO_EDGE:
        return NO_EDGE
    if swap:
        edge ^= 2  # LEFT <-> BOTTOM, RIGHT <-> TOP
    if flip_x and edge < EDGE_BOTTOM:
        edge ^= 1  # LEFT <-> RIGHT
    if flip_y and edge >= EDGE_BOTTOM:
        edge ^= 1  # BOTTOM <-> TOP
    return edge


@scalar
def nicholl_lee_nicholl_segment(x0, y0, x1, y1, window, st):
    """Clip one segment with Nicholl–Lee–Nicholl: P0's region names the edges that can cut.

    A zero-length segment is decided by its outcode. Otherwise the segment is moved into
    one of three canonical cases (module docstring), clipped there, and the edges that
    cut it mapped back; returns as every method does (`segments.clip_one`).
    """
    xmin, ymin, xmax, ymax = window
    st[C.EVALUATED] += 1
    st[C.LEVELS] += 1
    c0 = outcode(x0, y0, xmin, ymin, xmax, ymax)
    if x1 - x0 == 0.0 and y1 - y0 == 0.0:
        if c0 == 0:
            st[C.ACCEPTED] += 1
            return True, 0.0, 1.0, x0, y0, x1, y1
        st[C.REJECTED] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # Move P0 into a canonical region: reflect so it is not right of or above the
    # window, then swap axes if it is below only.
    flip_x = (c0 & RIGHT) != 0
    flip_y = (c0 & TOP) != 0
    px, qx, left, right = x0, x1, xmin, xmax
    py, qy, bottom, top = y0, y1, ymin, ymax
    if flip_x:
        px, qx, left, right = -x0, -x1, -xmax, -xmin
    if flip_y:
        py, qy, bottom, top = -y0, -y1, -ymax, -ymin
    swap = (c0 & (LEFT | RIGHT)) == 0 and (c0 & (BOTTOM | TOP)) != 0
    if swap:
        px, py, qx, qy = py, px, qy, qx
        left, bottom, right, top = bottom, left, top, right
    ok, u0, e0, u1, e1 = _canonical_clip(px, py, qx, qy, Window(left, bottom, right, top), st)
    if not ok:
        st[C.REJECTED] += 1
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    e0 = _original_edge(e0, flip_x, flip_y, swap)
    e1 = _original_edge(e1, flip_x, flip_y, swap)
    # Not degenerate: a zero-length segment was decided above.
    return piece_of_interval(x0, y0, x1, y1, False, u0, e0, u1, e1, window, st)
