"""The NumPy reference backend: every segment method, vectorized, written to be read.

This backend is the second opinion on the Numba kernels (``rnsca.kernels.segments`` and
``rnsca.baselines``). For every method, mode and option it gives the same pieces, the
same parameter intervals and the same `ClipStats`, because it evaluates the same
formulas in the same order (so the floating-point results agree bit for bit), only over
all segments at once:

- each branch of a scalar kernel becomes a boolean mask over the segments it applies to;
- a scalar loop (Cohen–Sutherland's moves, midpoint's bisection steps) becomes a bounded
  loop of masked iterations;
- RNSCA's depth-first stack becomes a breadth-first sweep over a frontier of fragments,
  one subdivision level at a time.

Work is counted in the kernels' own counter row (``rnsca.kernels.counters``): each
increment here stands for the same increment there, and `ClipStats.from_counters` reads
both. Nothing here is fast; it is meant to be read, stepped through, and trusted.

Every piece is described as in the kernels: a segment ``P(t) = P0 + t (P1 - P0)``, a
parameter interval ``[t0, t1]`` and its two end points. An end "cut" by a window edge
(``EDGE_*``) lies on that edge's line; an end not cut (``NO_EDGE``) is a point already
known. The outcode grid is drawn in ``rnsca.kernels.outcode``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from rnsca.baselines.cohen_sutherland import _MAX_MOVES
from rnsca.kernels import counters as C
from rnsca.kernels.outcode import (
    BOTTOM,
    EDGE_BOTTOM,
    EDGE_LEFT,
    EDGE_RIGHT,
    EDGE_TOP,
    LEFT,
    NO_EDGE,
    RIGHT,
    SURE_SHIFT,
    TOP,
    UNSURE_BITS,
    difference_dd,
    interpolate_dd,
    line_coordinate_dd,
)
from rnsca.kernels.segments import AUTO_N_MIN, N_MAX
from rnsca.options import Backend, Method, Mode, SegmentOptions
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["NumpyBackend"]


class NumpyBackend:
    """Run every segment method as vectorized NumPy; the reference for the other backends.

    Examples
    --------
    >>> from rnsca.options import SegmentOptions
    >>> w = Window(0.0, 0.0, 10.0, 10.0)
    >>> pieces, source, t, stats = NumpyBackend().clip_segments(
    ...     np.array([[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0]]), w,
    ...     SegmentOptions.resolve(w, method="liang_barsky"))
    >>> pieces.tolist(), source.tolist(), t.tolist()
    ([[0.0, 5.0, 10.0, 5.0]], [0], [[0.25, 0.75]])
    >>> stats.clipped, stats.rejected, stats.intersections
    (1, 1, 4)
    """

    kind = Backend.NUMPY

    def clip_segments(self, segments: np.ndarray, window: Window, options: SegmentOptions):
        """Return ``(pieces, source, t, stats)``; see `ClipBackend.clip_segments`.

        Parameters
        ----------
        segments : ndarray of float64, shape (n, 4)
            ``[x0, y0, x1, y1]`` per segment; finite, with finite differences.
        window : Window
        options : SegmentOptions

        Returns
        -------
        pieces : ndarray of float64, shape (m, 4)
            Each piece's end points, clamped into the window as the Numba driver does.
        source : ndarray of int64, shape (m,)
            Index of the segment each piece came from, increasing.
        t : ndarray of float64, shape (m, 2)
            Each piece's parameter interval on its segment.
        stats : ClipStats
        """
        s = _Segments.of(segments)
        st = np.zeros(C.WIDTH, dtype=np.int64)
        # Divisions by zero, overflows and inf - inf happen on rows a mask then ignores, or
        # exactly where the scalar kernels (compiled with NumPy's error model) meet them too.
        with np.errstate(all="ignore"):
            out = _CLIPPERS[options.method](s, window, options, st)
        keep = out.keep
        pieces = np.column_stack([
            _clamp(out.ax[keep], window.xmin, window.xmax),
            _clamp(out.ay[keep], window.ymin, window.ymax),
            _clamp(out.bx[keep], window.xmin, window.xmax),
            _clamp(out.by[keep], window.ymin, window.ymax),
        ]).reshape(-1, 4)
        source = np.flatnonzero(keep).astype(np.int64)
        t = np.column_stack([out.t0[keep], out.t1[keep]]).reshape(-1, 2)
        return pieces, source, t, ClipStats.from_counters(st, s.size, source.size)


# --------------------------------------------------------------------------------------
# Shared pieces: segments as columns, per-segment results, counters, outcodes, end points.


@dataclass(frozen=True)
class _Segments:
    """Segments as columns: the end points and the direction ``(dx, dy) = P1 - P0``."""

    x0: np.ndarray
    y0: np.ndarray
    x1: np.ndarray
    y1: np.ndarray
    dx: np.ndarray
    dy: np.ndarray

    @classmethod
    def of(cls, segments: np.ndarray) -> _Segments:
        """Return the columns of a float64 (n, 4) array."""
        x0, y0, x1, y1 = (np.array(segments[:, k], dtype=np.float64) for k in range(4))
        return cls(x0, y0, x1, y1, x1 - x0, y1 - y0)

    @property
    def size(self) -> int:
        """Return the number of segments."""
        return self.x0.size

    @property
    def degenerate(self) -> np.ndarray:
        """Return, per segment, whether it is a single point (P0 == P1)."""
        return (self.dx == 0.0) & (self.dy == 0.0)

    def take(self, index: np.ndarray) -> _Segments:
        """Return the segments at `index` (repeats allowed: one row per fragment)."""
        return _Segments(*(getattr(self, f.name)[index] for f in fields(self)))

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the points ``P0 + t (P1 - P0)``, rounded as the kernels round them."""
        return self.x0 + t * self.dx, self.y0 + t * self.dy


@dataclass(frozen=True)
class _Clipped:
    """What a method found per segment: whether a piece remains, its interval and ends."""

    keep: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    bx: np.ndarray
    by: np.ndarray

    @classmethod
    def nothing(cls, n: int) -> _Clipped:
        """Return a result for `n` segments with no piece yet."""
        return cls(np.zeros(n, dtype=bool), *(np.zeros(n) for _ in range(6)))

    def set(self, index, keep, t0, t1, ax, ay, bx, by) -> None:
        """Record the result of the segments at `index`."""
        for name, value in zip(("keep", "t0", "t1", "ax", "ay", "bx", "by"),
                               (keep, t0, t1, ax, ay, bx, by), strict=True):
            getattr(self, name)[index] = value


def _count(st: np.ndarray, counter: int, mask: np.ndarray) -> None:
    """Add the number of true entries of the boolean `mask` to counter `counter`."""
    st[counter] += np.count_nonzero(mask)


def _count_decided(st: np.ndarray, levels: np.ndarray) -> None:
    """Add one "decided" per entry of `levels` to the count of that subdivision level."""
    st[C.LEVELS:C.LEVELS + C.N_LEVELS] += np.bincount(levels, minlength=C.N_LEVELS)


def _reach(st: np.ndarray, level: int) -> None:
    """Record that subdivision reached `level` (the counter keeps the deepest)."""
    st[C.DEEPEST] = max(st[C.DEEPEST], level)


def _outcode(x, y, xmin, ymin, xmax, ymax) -> np.ndarray:
    """Return the 4-bit outcodes of points; 0 inside or on the boundary (``outcode``)."""
    across = np.where(x < xmin, LEFT, np.where(x > xmax, RIGHT, 0))
    along = np.where(y < ymin, BOTTOM, np.where(y > ymax, TOP, 0))
    return across | along


def _wide(code: np.ndarray) -> np.ndarray:
    """Return the wide codes of exactly known points (``wide``)."""
    return code | (code << SURE_SHIFT)


def _interpolated(s: _Segments, t):
    """Return (x, y, cx, mx, cy, my): rounded points at t, corrections, margins.

    ``interpolated_point``: the true coordinate is the rounded one plus the correction,
    to within the margin (the a-priori bound where the error terms overflowed).
    """
    with np.errstate(all="ignore"):
        dx, dx_err = difference_dd(s.x1, s.x0)
        dy, dy_err = difference_dd(s.y1, s.y0)
        x, x_err = interpolate_dd(s.x0, dx, dx_err, t)
        y, y_err = interpolate_dd(s.y0, dy, dy_err, t)
        out = [x, y]
        for err, a0, da in ((x_err, s.x0, dx), (y_err, s.y0, dy)):
            finite = np.isfinite(err)
            a_priori = 8.881784197001252e-16 * np.abs(a0) + 8.881784197001252e-16 * np.abs(da)
            floor = np.where((da != 0.0) & (np.abs(da) < 1e-290), 1e-322, 0.0)
            margin = np.abs(err) * 8.881784197001252e-16 + floor
            out += [np.where(finite, err, 0.0), np.where(finite, margin, a_priori + 1e-323)]
    x, y, cx, mx, cy, my = out
    return x, y, cx, mx, cy, my


def _wide_outcode_at(s: _Segments, t, w: Window):
    """Return (x, y, wide code) of the points at t on segments `s` (``wide_outcode``).

    The coordinates returned are the corrected ones.
    """
    x, y, cx, mx, cy, my = _interpolated(s, t)
    with np.errstate(all="ignore"):
        dl, dr = (x - w.xmin) + cx, (w.xmax - x) - cx
        db, dt = (y - w.ymin) + cy, (w.ymax - y) - cy
        unsure = ((dl < mx) * LEFT | (dr < mx) * RIGHT | (db < my) * BOTTOM
                  | (dt < my) * TOP)
        sure = ((-dl > mx) * LEFT | (-dr > mx) * RIGHT | (-db > my) * BOTTOM
                | (-dt > my) * TOP)
    # The corrected position, for output (as the kernels do).
    return x + cx, y + cy, unsure | (sure << SURE_SHIFT)


def _clamp(v: np.ndarray, low: float, high: float) -> np.ndarray:
    """Return v limited to [low, high], with the kernel's comparisons (``clamp``)."""
    return np.where(v < low, low, np.where(v > high, high, v))


def _line_coordinate_residual(e, a0, b0, a1, b1) -> tuple[np.ndarray, np.ndarray]:
    """Return (b, residual) as ``line_coordinate_residual`` does."""
    near1 = np.abs(e - a1) < np.abs(e - a0)
    a = np.where(near1, a1, a0)
    b = np.where(near1, b1, b0)
    da, da_err = difference_dd(a1, a0)
    db, db_err = difference_dd(b1, b0)
    with np.errstate(all="ignore"):
        precise, residual = line_coordinate_dd(e, a, b, da, da_err, db, db_err)
        plain = b + (e - a) / da * db
    ok = np.isfinite(precise) & np.isfinite(residual)
    return np.where(ok, precise, plain), np.where(ok, residual, 0.0)


def _edge_point_code(s: _Segments, edge, w: Window):
    """Return (x, y, code): `_edge_point` and the true point's outcode (``edge_point_code``)."""
    shape = np.shape(edge)
    x0, y0, x1, y1 = (np.broadcast_to(v, shape) for v in (s.x0, s.y0, s.x1, s.y1))
    vertical = (edge == EDGE_LEFT) | (edge == EDGE_RIGHT)
    xe = np.where(edge == EDGE_LEFT, w.xmin, w.xmax)
    ye = np.where(edge == EDGE_BOTTOM, w.ymin, w.ymax)
    yv, rv = _line_coordinate_residual(xe, x0, y0, x1, y1)
    xh, rh = _line_coordinate_residual(ye, y0, x0, y1, x1)
    x = np.where(vertical, xe, xh)
    y = np.where(vertical, yv, ye)
    cx = np.where(vertical, 0.0, rh)
    cy = np.where(vertical, rv, 0.0)
    with np.errstate(all="ignore"):
        dl, dr = (x - w.xmin) + cx, (w.xmax - x) - cx
        db, dt = (y - w.ymin) + cy, (w.ymax - y) - cy
    code = (dl < 0) * LEFT | (dr < 0) * RIGHT | (db < 0) * BOTTOM | (dt < 0) * TOP
    return x, y, code


def _line_coordinate(e, a0, b0, a1, b1) -> np.ndarray:
    """Return the b of the line through (a0, b0), (a1, b1) where its a is e (``line_coordinate``).

    Measured from the nearer end: plainly where that is within a few ulps, else in
    double-double (the kernels' own arithmetic).
    """
    near1 = np.abs(e - a1) < np.abs(e - a0)
    a = np.where(near1, a1, a0)
    b = np.where(near1, b1, b0)
    db = b1 - b0
    with np.errstate(all="ignore"):
        plain = b + (e - a) / (a1 - a0) * db
    well_conditioned = (np.abs(b) + np.abs(db) <= 16.0 * np.abs(plain)) | (np.abs(db) < 1e-290)
    return np.where(well_conditioned, plain, _line_coordinate_residual(e, a0, b0, a1, b1)[0])


def _edge_point(s: _Segments, t, edge, w: Window) -> tuple[np.ndarray, np.ndarray]:
    """Return the points where the segments' lines meet the lines of `edge` (``edge_point``).

    The coordinate across the edge is the edge's own value exactly; the other one is
    `_line_coordinate`. (`t` is not needed: the edge names the point.)
    """
    shape = np.broadcast_shapes(np.shape(t), s.x0.shape)
    x0, y0, x1, y1 = (np.broadcast_to(v, shape) for v in (s.x0, s.y0, s.x1, s.y1))
    with np.errstate(all="ignore"):
        y_left = _line_coordinate(w.xmin, x0, y0, x1, y1)
        y_right = _line_coordinate(w.xmax, x0, y0, x1, y1)
        x_bottom = _line_coordinate(w.ymin, y0, x0, y1, x1)
        x_top = _line_coordinate(w.ymax, y0, x0, y1, x1)
    x = np.select([edge == EDGE_LEFT, edge == EDGE_RIGHT, edge == EDGE_BOTTOM],
                  [w.xmin, w.xmax, x_bottom], x_top)
    y = np.select([edge == EDGE_LEFT, edge == EDGE_RIGHT, edge == EDGE_BOTTOM],
                  [y_left, y_right, w.ymin], w.ymax)
    return x, y


def _snap_into_window(x, y, s: _Segments, w: Window) -> tuple[np.ndarray, np.ndarray]:
    """Return ends on the segments' lines slid along them into the window (``snap_into_window``).

    An end outside in y moves to the horizontal edge it overshoots, then one outside in
    x to the vertical edge; every coordinate is then clamped.
    """
    with np.errstate(all="ignore"):
        over = (y > w.ymax) | (y < w.ymin)
        edge = np.where(y > w.ymax, w.ymax, w.ymin)
        x = np.where(over, _line_coordinate(edge, s.y0, s.x0, s.y1, s.x1), x)
        y = np.where(over, edge, y)
        over = (x > w.xmax) | (x < w.xmin)
        edge = np.where(x > w.xmax, w.xmax, w.xmin)
        y = np.where(over, _line_coordinate(edge, s.x0, s.y0, s.x1, s.y1), y)
        x = np.where(over, edge, x)
    return _clamp(x, w.xmin, w.xmax), _clamp(y, w.ymin, w.ymax)


def _end_point(s: _Segments, t, edge, px, py, w: Window) -> tuple[np.ndarray, np.ndarray]:
    """Return the piece ends: (px, py) where not cut, else the edge point snapped into the window.

    ``end_point``: the snap moves an end that parameter rounding put on the wrong
    edge's line back along the segment onto the window's boundary.
    """
    x, y = _edge_point(s, t, edge, w)
    cut = edge != NO_EDGE
    return _snap_into_window(np.where(cut, x, px), np.where(cut, y, py), s, w)


def _is_piece(degenerate, t0, t1, ax, ay, bx, by) -> np.ndarray:
    """Return whether each [t0, t1] with ends a, b is an output piece (``is_piece``).

    A zero-length input segment inside the window is kept; otherwise an empty interval
    or a single point (the segment only touches the window) is not a piece.
    """
    touches_only = (ax == bx) & (ay == by)
    return (t0 <= t1) & (degenerate | ~touches_only)


# --------------------------------------------------------------------------------------
# Liang–Barsky: the parametric clip; RNSCA and midpoint also use it for exact leaves.


def _clipt(p, q, edge, ok, u0, e0, u1, e1, st) -> np.ndarray:
    """Apply the half-plane ``p t <= q`` to the rows still `ok`; return the new `ok`.

    Updates `u0`, `e0`, `u1`, `e1` in place (``_clipt``). A row with ``p == 0`` runs
    parallel to the edge: wholly inside its half-plane or wholly outside. Otherwise
    ``r = q / p`` is where the line crosses the edge (one counted division): entering
    the half-plane (``p < 0``) it may raise u0, leaving it may lower u1, and an empty
    interval fails the row, which then skips the remaining edges.
    """
    parallel = ok & (p == 0.0)
    crossing = ok & (p != 0.0)
    _count(st, C.INTERSECTIONS, crossing)
    r = q / p
    entering = crossing & (p < 0.0)
    leaving = crossing & ~(p < 0.0)
    fails = (parallel & ~(q >= 0.0)) | (entering & (r > u1)) | (leaving & (r < u0))
    raise_u0 = entering & ~fails & (r > u0)
    lower_u1 = leaving & ~fails & (r < u1)
    u0[raise_u0] = r[raise_u0]
    e0[raise_u0] = edge
    u1[lower_u1] = r[lower_u1]
    e1[lower_u1] = edge
    return ok & ~fails


def _liang_barsky_interval(s: _Segments, ta, tb, w: Window, st):
    """Return (ok, u0, e0, u1, e1): the part of each [ta, tb] inside the window.

    ``liang_barsky_interval``: the four half-planes in the order left, right, bottom,
    top; `e0`, `e1` name the edge that cut each end (``NO_EDGE`` if none did).
    """
    shape = s.x0.shape
    u0 = np.array(np.broadcast_to(ta, shape), dtype=np.float64)
    u1 = np.array(np.broadcast_to(tb, shape), dtype=np.float64)
    e0 = np.full(shape, NO_EDGE)
    e1 = np.full(shape, NO_EDGE)
    ok = np.ones(shape, dtype=bool)
    for p, q, edge in ((-s.dx, s.x0 - w.xmin, EDGE_LEFT), (s.dx, w.xmax - s.x0, EDGE_RIGHT),
                       (-s.dy, s.y0 - w.ymin, EDGE_BOTTOM), (s.dy, w.ymax - s.y0, EDGE_TOP)):
        ok = _clipt(p, q, edge, ok, u0, e0, u1, e1, st)
    return ok & (u0 <= u1), u0, e0, u1, e1


def _liang_barsky_leaf(s: _Segments, ta, tb, xa, ya, xb, yb, flags, w: Window, st):
    """Return (ok, u0, ax, ay, u1, bx, by): the visible part of the leaves [ta, tb].

    ``liang_barsky_leaf``, for the leaves of subdivision methods, whose ends (xa, ya),
    (xb, yb) are known. Only the half-planes named in `flags` (the OR of the leaf's end
    outcodes) are applied, in the order left, right, bottom, top, each with one counted
    division and no early exit: a half-plane that holds at both ends of a leaf holds on
    all of it, and an ambiguous leaf never runs parallel to a flagged edge (both its
    ends would lie beyond it). A cut end takes the edge's coordinate exactly and the
    other one interpolated; at the end every coordinate is clamped into the window.
    """
    u0, ax, ay = (np.array(v, dtype=np.float64) for v in (ta, xa, ya))
    u1, bx, by = (np.array(v, dtype=np.float64) for v in (tb, xb, yb))
    for bit, p, q, vertical, value in ((LEFT, -s.dx, s.x0 - w.xmin, True, w.xmin),
                                       (RIGHT, s.dx, w.xmax - s.x0, True, w.xmax),
                                       (BOTTOM, -s.dy, s.y0 - w.ymin, False, w.ymin),
                                       (TOP, s.dy, w.ymax - s.y0, False, w.ymax)):
        on = (flags & bit) != 0
        _count(st, C.INTERSECTIONS, on)
        r = q / np.where(on, p, 1.0)  # rows not flagged divide by 1 (result unused)
        if vertical:
            x = np.full(r.shape, value)
            y = _line_coordinate(value, s.x0, s.y0, s.x1, s.y1)
        else:
            x = _line_coordinate(value, s.y0, s.x0, s.y1, s.x1)
            y = np.full(r.shape, value)
        enter = on & (p < 0.0) & (r > u0)
        leave = on & (p > 0.0) & (r < u1)
        u0, ax, ay = (np.where(enter, new, old) for new, old in ((r, u0), (x, ax), (y, ay)))
        u1, bx, by = (np.where(leave, new, old) for new, old in ((r, u1), (x, bx), (y, by)))
    ax, ay = _snap_into_window(ax, ay, s, w)
    bx, by = _snap_into_window(bx, by, s, w)
    return u0 <= u1, u0, ax, ay, u1, bx, by


def _liang_barsky(s: _Segments, w: Window, options: SegmentOptions, st) -> _Clipped:
    """Clip every segment with Liang–Barsky (``liang_barsky_segment``)."""
    st[C.EVALUATED] += s.size
    st[C.LEVELS] += s.size
    ok, u0, e0, u1, e1 = _liang_barsky_interval(s, 0.0, 1.0, w, st)
    whole = ok & (e0 == NO_EDGE) & (e1 == NO_EDGE)
    _count(st, C.REJECTED, ~ok)
    _count(st, C.ACCEPTED, whole)
    _count(st, C.CLIPPED, ok & ~whole)
    ax, ay = _end_point(s, u0, e0, s.x0, s.y0, w)
    bx, by = _end_point(s, u1, e1, s.x1, s.y1, w)
    keep = ok & _is_piece(s.degenerate, u0, u1, ax, ay, bx, by)
    return _Clipped(keep, u0, u1, ax, ay, bx, by)


# --------------------------------------------------------------------------------------
# Cohen–Sutherland: outcodes, then move one outside end to an edge, and test again.


def _edge_parameter(code, s: _Segments, w: Window):
    """Return (t, edge, bit) where each line crosses the edge named by `code`.

    One bit is chosen in the kernel's order of preference: TOP, BOTTOM, RIGHT, LEFT
    (``_edge_parameter``). The parameter comes from the original segment.
    """
    has = [(code & TOP) != 0, (code & BOTTOM) != 0, (code & RIGHT) != 0]
    t = np.select(has, [(w.ymax - s.y0) / s.dy, (w.ymin - s.y0) / s.dy,
                        (w.xmax - s.x0) / s.dx], (w.xmin - s.x0) / s.dx)
    edge = np.select(has, [EDGE_TOP, EDGE_BOTTOM, EDGE_RIGHT], EDGE_LEFT)
    bit = np.select(has, [TOP, BOTTOM, RIGHT], LEFT)
    return t, edge, bit


def _cohen_sutherland(s: _Segments, w: Window, options: SegmentOptions, st) -> _Clipped:
    """Clip every segment with Cohen–Sutherland (``cohen_sutherland_segment``).

    Each pass of the loop is one pass of the kernel's loop for every segment still
    undecided: classify (one evaluation), accept, reject, or cut one end.
    """
    n = s.size
    t0, t1 = np.zeros(n), np.ones(n)
    ax, ay, bx, by = s.x0.copy(), s.y0.copy(), s.x1.copy(), s.y1.copy()
    ca, cb = _outcode(ax, ay, *w.bounds), _outcode(bx, by, *w.bounds)
    accepted = np.zeros(n, dtype=bool)
    undecided = np.ones(n, dtype=bool)
    for _ in range(_MAX_MOVES):
        _count(st, C.EVALUATED, undecided)
        _count(st, C.LEVELS, undecided)
        accept = undecided & ((ca | cb) == 0)
        reject = undecided & ~accept & ((ca & cb) != 0)
        _count(st, C.ACCEPTED, accept)
        _count(st, C.REJECTED, reject)
        accepted |= accept
        undecided &= ~(accept | reject)
        _count(st, C.CLIPPED, undecided)
        _count(st, C.INTERSECTIONS, undecided)
        # Move P0's end if it is outside, else P1's, to the edge named by one of its bits;
        # an end only ever moves inwards. The moved end is not clamped: the next outcode
        # test must see where it really is. An end already past that edge's crossing
        # (rounding near a corner) stays, and the bit is cleared as noise.
        move_a = undecided & (ca != 0)
        move_b = undecided & (ca == 0)
        t, edge, bit = _edge_parameter(np.where(move_a, ca, cb), s, w)
        x, y, c = _edge_point_code(s, edge, w)
        raise_t0 = move_a & (t > t0)
        t0, ax, ay = (np.where(raise_t0, new, old) for new, old in ((t, t0), (x, ax), (y, ay)))
        ca = np.where(raise_t0, c, np.where(move_a, ca & ~bit, ca))
        lower_t1 = move_b & (t < t1)
        t1, bx, by = (np.where(lower_t1, new, old) for new, old in ((t, t1), (x, bx), (y, by)))
        cb = np.where(lower_t1, c, np.where(move_b, cb & ~bit, cb))
        undecided &= ~(t0 > t1)  # the moves crossed: nothing is left
    # Accepted segments keep a zero-length input. (The kernel proves that _MAX_MOVES
    # passes decide every segment; one still undecided would give no piece.)
    keep = accepted & _is_piece(s.degenerate, t0, t1, ax, ay, bx, by)
    return _Clipped(keep, t0, t1, ax, ay, bx, by)


# --------------------------------------------------------------------------------------
# Nicholl–Lee–Nicholl: reflect P0 into a canonical region, pick edges by ray tests.

# Products of numbers within these magnitudes neither overflow nor lose to underflow.
_BIG = 2.0 ** 500
_SMALL = 2.0 ** -500

# Leaving the window from inside towards a corner region (by its outcode), the exit
# edge when the direction is counter-clockwise of the ray to that corner, and when not
# (``_exit_from_inside``; any other code is treated as RIGHT | BOTTOM, as there).
_CORNER_EXITS = {RIGHT | TOP: (EDGE_TOP, EDGE_RIGHT), LEFT | TOP: (EDGE_LEFT, EDGE_TOP),
                 LEFT | BOTTOM: (EDGE_BOTTOM, EDGE_LEFT)}
_CORNER_EXIT_CCW = np.array([_CORNER_EXITS.get(c, (EDGE_RIGHT, EDGE_BOTTOM))[0] for c in range(16)])
_CORNER_EXIT_CW = np.array([_CORNER_EXITS.get(c, (EDGE_RIGHT, EDGE_BOTTOM))[1] for c in range(16)])
# The edge of a one-bit outcode (anything else maps to TOP, as in ``_single_edge``).
_SINGLE_EDGE = np.array([{LEFT: EDGE_LEFT, RIGHT: EDGE_RIGHT, BOTTOM: EDGE_BOTTOM}.get(c, EDGE_TOP)
                         for c in range(16)])


def _rescale(x, y):
    """Return vectors divided by their larger magnitude when that is extreme (``_rescale``)."""
    m = np.where(np.abs(y) > np.abs(x), np.abs(y), np.abs(x))  # max(), NaN as the kernel has it
    extreme = (m > _BIG) | ((0.0 < m) & (m < _SMALL))
    return np.where(extreme, x / m, x), np.where(extreme, y / m, y)


def _turn(ax, ay, bx, by) -> np.ndarray:
    """Return the sign of cross(a, b): +1 if b is counter-clockwise of a (``_turn``)."""
    ax, ay = _rescale(ax, ay)
    bx, by = _rescale(bx, by)
    c = ax * by - ay * bx
    return np.where(c > 0.0, 1, np.where(c < 0.0, -1, 0))


@dataclass(frozen=True)
class _Frame:
    """Segments reflected so that P0 is inside, left of, or below-left of the window.

    ``x -> -x`` (P0 right of the window), ``y -> -y`` (above), then the swap of axes (P0
    only below) map every region onto these three. All are exact in floating point and
    leave the parameter t unchanged; `edge_back` maps an edge back to the window's own.
    """

    px: np.ndarray
    py: np.ndarray
    qx: np.ndarray
    qy: np.ndarray
    left: np.ndarray
    bottom: np.ndarray
    right: np.ndarray
    top: np.ndarray
    flip_x: np.ndarray
    flip_y: np.ndarray
    swap: np.ndarray

    @classmethod
    def canonical(cls, s: _Segments, c0: np.ndarray, w: Window) -> _Frame:
        """Return the canonical frame of segments whose P0 has outcode `c0`."""
        flip_x = (c0 & RIGHT) != 0
        flip_y = (c0 & TOP) != 0
        px, qx = np.where(flip_x, -s.x0, s.x0), np.where(flip_x, -s.x1, s.x1)
        left, right = np.where(flip_x, -w.xmax, w.xmin), np.where(flip_x, -w.xmin, w.xmax)
        py, qy = np.where(flip_y, -s.y0, s.y0), np.where(flip_y, -s.y1, s.y1)
        bottom, top = np.where(flip_y, -w.ymax, w.ymin), np.where(flip_y, -w.ymin, w.ymax)
        swap = ((c0 & (LEFT | RIGHT)) == 0) & ((c0 & (BOTTOM | TOP)) != 0)

        def swapped(a, b):
            return np.where(swap, b, a), np.where(swap, a, b)

        px, py = swapped(px, py)
        qx, qy = swapped(qx, qy)
        left, bottom = swapped(left, bottom)
        right, top = swapped(right, top)
        return cls(px, py, qx, qy, left, bottom, right, top, flip_x, flip_y, swap)

    def parameter(self, edge, ex, ey, st, counted) -> np.ndarray:
        """Return where P + t E meets the line of `edge` (``_parameter``).

        One division per row; only the rows in `counted` are the kernel's.
        """
        _count(st, C.INTERSECTIONS, counted)
        return np.select(
            [edge == EDGE_LEFT, edge == EDGE_RIGHT, edge == EDGE_BOTTOM],
            [(self.left - self.px) / ex, (self.right - self.px) / ex,
             (self.bottom - self.py) / ey],
            (self.top - self.py) / ey)

    def edge_back(self, edge: np.ndarray) -> np.ndarray:
        """Return the window's own edge for an edge of this frame (``_original_edge``)."""
        cut = edge != NO_EDGE
        edge = np.where(cut & self.swap, edge ^ 2, edge)  # LEFT <-> BOTTOM, RIGHT <-> TOP
        edge = np.where(cut & self.flip_x & (edge < EDGE_BOTTOM), edge ^ 1, edge)
        return np.where(cut & self.flip_y & (edge >= EDGE_BOTTOM), edge ^ 1, edge)


def _canonical_clip(f: _Frame, st):
    """Return (ok, u0, e0, u1, e1) of segments in the canonical frame (``_canonical_clip``).

    P inside: the exit edge follows from Q's region (and, for a corner region, the ray
    to that corner). P left of the window: the window is seen between the rays to its
    bottom-left and top-left corners. P below-left: between the rays to bottom-right and
    top-left, entering through the left edge when steeper than the ray to bottom-left.
    """
    ex, ey = f.qx - f.px, f.qy - f.py
    c0 = _outcode(f.px, f.py, f.left, f.bottom, f.right, f.top)
    c1 = _outcode(f.qx, f.qy, f.left, f.bottom, f.right, f.top)
    n = c0.size
    ok = np.ones(n, dtype=bool)
    u0, u1 = np.zeros(n), np.ones(n)
    e0, e1 = np.full(n, NO_EDGE), np.full(n, NO_EDGE)

    # P inside, Q outside: one exit edge, one intersection.
    leaves = (c0 == 0) & (c1 != 0)
    corner_x = np.where((c1 & RIGHT) != 0, f.right, f.left)
    corner_y = np.where((c1 & TOP) != 0, f.top, f.bottom)
    ccw = _turn(corner_x - f.px, corner_y - f.py, ex, ey) > 0
    single = (c1 == LEFT) | (c1 == RIGHT) | (c1 == BOTTOM) | (c1 == TOP)
    exit_inside = np.where(single, _SINGLE_EDGE[c1],
                           np.where(ccw, _CORNER_EXIT_CCW[c1], _CORNER_EXIT_CW[c1]))
    e1 = np.where(leaves, exit_inside, e1)
    u1 = np.where(leaves, f.parameter(e1, ex, ey, st, leaves), u1)

    # P outside: rejected if Q shares its side, or if the direction misses the window.
    outside = c0 != 0
    ok &= ~(outside & ((c1 & c0) != 0))
    misses_top_left = _turn(ex, ey, f.left - f.px, f.top - f.py) < 0
    from_left = outside & ok & (c0 == LEFT)
    ok &= ~(from_left & ((_turn(f.left - f.px, f.bottom - f.py, ex, ey) < 0) | misses_top_left))
    from_corner = outside & ok & (c0 != LEFT)
    ok &= ~(from_corner & (((c1 & (LEFT | BOTTOM)) != 0)
                           | (_turn(f.right - f.px, f.bottom - f.py, ex, ey) < 0)
                           | misses_top_left))
    enters = outside & ok
    steep = _turn(f.left - f.px, f.bottom - f.py, ex, ey) >= 0
    e0 = np.where(enters, np.where((c0 == LEFT) | steep, EDGE_LEFT, EDGE_BOTTOM), e0)
    entry = f.parameter(e0, ex, ey, st, enters)
    # Q inside: the piece runs from the entry to Q. Q beyond: find the exit too.
    crosses = enters & (c1 != 0)
    exit_left = np.select(
        [_turn(f.right - f.px, f.top - f.py, ex, ey) > 0,
         _turn(f.right - f.px, f.bottom - f.py, ex, ey) < 0], [EDGE_TOP, EDGE_BOTTOM], EDGE_RIGHT)
    e1 = np.where(crosses, exit_left, e1)
    leave = f.parameter(e1, ex, ey, st, crosses)
    u1 = np.where(crosses, np.where(1.0 < leave, 1.0, leave), u1)  # min(leave, 1.0)
    ok &= ~(crosses & ~(entry <= u1))
    u0 = np.where(enters, np.where(0.0 > entry, 0.0, entry), u0)  # max(entry, 0.0)
    return ok, u0, e0, u1, e1


def _nicholl_lee_nicholl(s: _Segments, w: Window, options: SegmentOptions, st) -> _Clipped:
    """Clip every segment with Nicholl–Lee–Nicholl (``nicholl_lee_nicholl_segment``)."""
    st[C.EVALUATED] += s.size
    st[C.LEVELS] += s.size
    out = _Clipped.nothing(s.size)
    c0 = _outcode(s.x0, s.y0, *w.bounds)
    # A zero-length segment is its point: kept whole if inside.
    point = s.degenerate
    kept = np.flatnonzero(point & (c0 == 0))
    st[C.ACCEPTED] += kept.size
    _count(st, C.REJECTED, point & (c0 != 0))
    out.set(kept, True, 0.0, 1.0, s.x0[kept], s.y0[kept], s.x1[kept], s.y1[kept])

    rows = np.flatnonzero(~point)
    sr = s.take(rows)
    frame = _Frame.canonical(sr, c0[rows], w)
    ok, u0, e0, u1, e1 = _canonical_clip(frame, st)
    whole = ok & (e0 == NO_EDGE) & (e1 == NO_EDGE)
    _count(st, C.REJECTED, ~ok)
    _count(st, C.ACCEPTED, whole)
    _count(st, C.CLIPPED, ok & ~whole)
    e0, e1 = frame.edge_back(e0), frame.edge_back(e1)
    ax, ay = _end_point(sr, u0, e0, sr.x0, sr.y0, w)
    bx, by = _end_point(sr, u1, e1, sr.x1, sr.y1, w)
    out.set(rows, ok & _is_piece(False, u0, u1, ax, ay, bx, by), u0, u1, ax, ay, bx, by)
    return out


# --------------------------------------------------------------------------------------
# Midpoint subdivision: two bisection searches, for the exit and for the entry.


@dataclass(frozen=True)
class _Bracket:
    """Per segment, an interval [a, b] with its end points, their outcodes and its level."""

    a: np.ndarray
    xa: np.ndarray
    ya: np.ndarray
    ca: np.ndarray
    b: np.ndarray
    xb: np.ndarray
    yb: np.ndarray
    cb: np.ndarray
    level: np.ndarray

    @classmethod
    def whole(cls, s: _Segments, c0, c1) -> _Bracket:
        """Return the brackets [0, 1] of whole segments, at level 0."""
        n = s.size
        return cls(np.zeros(n), s.x0.copy(), s.y0.copy(), _wide(c0),
                   np.ones(n), s.x1.copy(), s.y1.copy(), _wide(c1), np.zeros(n, dtype=np.int64))

    def take(self, index) -> _Bracket:
        """Return the brackets at `index`."""
        return _Bracket(*(getattr(self, f.name)[index] for f in fields(self)))

    def moved(self, mask, end_b: bool, t, x, y, c, level) -> _Bracket:
        """Return the brackets with, where `mask`, end b (else end a) moved to (t, x, y, c)."""
        names = ("b", "xb", "yb", "cb", "level") if end_b else ("a", "xa", "ya", "ca", "level")
        return replace(self, **{name: np.where(mask, new, getattr(self, name))
                                for name, new in zip(names, (t, x, y, c, level), strict=True)})


def _bisect(s: _Segments, bracket: _Bracket, length, toward_end: bool,
            options: SegmentOptions, w: Window, st) -> _Bracket:
    """Return the final brackets of one search per segment (``_search``).

    ``toward_end=True`` brackets the exit (the farthest visible point from P0), else the
    entry (the farthest visible point from P1). Each step halves the bracket at m; if
    the half on the far side of the searched end ([m, b] for the exit, [a, m] for the
    entry) is surely invisible (its wide codes share a sure bit), the end lies in the
    near half, otherwise in the far one. Brackets still searching have all made the same
    number of steps, so a step is one level. The near end returned follows the kernel:
    the last surely inside one (exact mode, or when the classic one is not trusted), or
    the classic one marked visible (approx mode, within rounding of the boundary).
    """
    exact = options.mode is Mode.EXACT
    near = ("a", "xa", "ya", "ca") if toward_end else ("b", "xb", "yb", "cb")
    sure = [getattr(bracket, name).copy() for name in near]
    found = np.zeros(bracket.a.size, dtype=bool)
    for level in range(1, options.max_depth + 1):
        active = (bracket.b - bracket.a) * length > options.tolerance
        if not active.any():
            break
        m = bracket.a + (bracket.b - bracket.a) * 1 / 2
        xm, ym, cm = _wide_outcode_at(s, m, w)
        _count(st, C.EVALUATED, active)
        far = bracket.cb if toward_end else bracket.ca
        beyond = active & (((cm & far) >> SURE_SHIFT) != 0)
        _count(st, C.REJECTED, beyond)
        st[C.LEVELS + level] += np.count_nonzero(beyond)
        _count(st, C.SUBDIVIDED, active & ~beyond)
        # Far half invisible: the bracket shrinks to the near half, else to the far one.
        bracket = bracket.moved(beyond, toward_end, m, xm, ym, cm, level)
        bracket = bracket.moved(active & ~beyond, not toward_end, m, xm, ym, cm, level)
        surely_in = active & ~beyond & ((cm & UNSURE_BITS) == 0)
        sure = [np.where(surely_in, new, old) for new, old in zip((m, xm, ym, cm), sure,
                                                                   strict=True)]
        found |= surely_in
    if bracket.level.size:
        _reach(st, int(bracket.level.max()))
    near_t, near_c = getattr(bracket, near[0]), getattr(bracket, near[3])
    # A search that jumped from its start straight to the boundary: the point halfway
    # back tells a segment running inside from one lying within rounding outside.
    check = ~found & ((near_c >> SURE_SHIFT) == 0) & (near_t != sure[0])
    lo, hi = np.minimum(near_t, sure[0]), np.maximum(near_t, sure[0])
    h = lo + (hi - lo) * 1 / 2
    _, _, ch = _wide_outcode_at(s, h, w)
    found |= check & ((ch & UNSURE_BITS) == 0)
    trusted = ~np.asarray(exact) & found & ((near_c >> SURE_SHIFT) == 0)
    values = [np.where(trusted, getattr(bracket, name), old) for name, old in zip(near, sure,
                                                                                 strict=True)]
    values[3] = np.where(trusted, 0, values[3])
    return replace(bracket, **dict(zip(near, values, strict=True)))


def _midpoint_leaf(s: _Segments, br: _Bracket, exact: bool, w: Window, st):
    """Decide final brackets; return (ok, u0, ax, ay, u1, bx, by) of their visible parts.

    ``_leaf``: accepted or rejected by outcodes, else clipped with Liang–Barsky (exact
    mode) or dropped (approx mode). A dropped bracket leaves its visible end alone
    (``u0 == u1``), and so does a bracket that Liang–Barsky finds empty: rounding, when
    the window's corner or edge is ulp-close to an end that tested inside.
    """
    st[C.EVALUATED] += br.a.size
    _count_decided(st, br.level)
    apart = ((br.ca & br.cb) >> SURE_SHIFT) != 0
    inside = ~apart & ((br.ca | br.cb) == 0)
    straddles = ~apart & ~inside
    _count(st, C.REJECTED, apart)
    _count(st, C.ACCEPTED, inside)
    ok = inside.copy()
    u0, ax, ay = br.a.copy(), br.xa.copy(), br.ya.copy()
    u1, bx, by = br.b.copy(), br.xb.copy(), br.yb.copy()
    if exact:
        _count(st, C.CLIPPED, straddles)
        k = np.flatnonzero(straddles)
        ok[k], u0[k], ax[k], ay[k], u1[k], bx[k], by[k] = _liang_barsky_leaf(
            s.take(k), br.a[k], br.b[k], br.xa[k], br.ya[k], br.xb[k], br.yb[k],
            (br.ca[k] | br.cb[k]) & UNSURE_BITS, w, st)
        end_only = straddles & ~ok
    else:
        _count(st, C.DROPPED, straddles)
        end_only = straddles
    a_visible = end_only & (br.ca == 0)
    b_visible = end_only & ~a_visible & (br.cb == 0)
    ok |= a_visible | b_visible
    u0, ax, ay, u1, bx, by = (
        np.where(a_visible, at_a, np.where(b_visible, at_b, old)) for at_a, at_b, old in
        ((br.a, br.b, u0), (br.xa, br.xb, ax), (br.ya, br.yb, ay),
         (br.a, br.b, u1), (br.xa, br.xb, bx), (br.ya, br.yb, by)))
    return ok, u0, ax, ay, u1, bx, by


def _midpoint(s: _Segments, w: Window, options: SegmentOptions, st) -> _Clipped:
    """Clip every segment by midpoint subdivision (``midpoint_segment``)."""
    exact = options.mode is Mode.EXACT
    out = _Clipped.nothing(s.size)
    length = np.hypot(s.dx, s.dy)
    c0, c1 = _outcode(s.x0, s.y0, *w.bounds), _outcode(s.x1, s.y1, *w.bounds)

    # Decided at level 0: accepted, rejected, or the whole segment is the leaf.
    at_root = (((c0 | c1) == 0) | ((c0 & c1) != 0) | (options.max_depth == 0)
               | (length <= options.tolerance))
    rows = np.flatnonzero(at_root)
    sr = s.take(rows)
    ok, t0, ax, ay, t1, bx, by = _midpoint_leaf(
        sr, _Bracket.whole(sr, c0[rows], c1[rows]), exact, w, st)
    # A dropped approx leaf leaves one point. (In exact mode t0 == t1 can be a real piece:
    # a window far smaller than the segment lies within one rounding step of t.)
    ok &= exact | ~((t0 == t1) & ((c0[rows] | c1[rows]) != 0))
    out.set(rows, ok & _is_piece(sr.degenerate, t0, t1, ax, ay, bx, by), t0, t1, ax, ay, bx, by)

    # The others are searched: the exit first (unless P1 is visible), then the entry
    # (unless P0 is visible) of those whose exit was found.
    rows = np.flatnonzero(~at_root)
    st[C.EVALUATED] += rows.size
    st[C.SUBDIVIDED] += rows.size
    sr, c0, c1, length = s.take(rows), c0[rows], c1[rows], length[rows]
    whole = _Bracket.whole(sr, c0, c1)
    ok = np.ones(rows.size, dtype=bool)
    t0, ax, ay = np.zeros(rows.size), sr.x0.copy(), sr.y0.copy()
    t1, bx, by = np.ones(rows.size), sr.x1.copy(), sr.y1.copy()
    for toward_end in (True, False):
        k = np.flatnonzero(ok & ((c1 if toward_end else c0) != 0))
        sk = sr.take(k)
        final = _bisect(sk, whole.take(k), length[k], toward_end, options, w, st)
        found, u0, px, py, u1, qx, qy = _midpoint_leaf(sk, final, exact, w, st)
        ok[k] = found
        if toward_end:
            t1[k], bx[k], by[k] = u1, qx, qy
        else:
            t0[k], ax[k], ay[k] = u0, px, py
    out.set(rows, ok & _is_piece(False, t0, t1, ax, ay, bx, by), t0, t1, ax, ay, bx, by)
    return out


# --------------------------------------------------------------------------------------
# RNSCA, breadth first: every segment's ambiguous fragments, one level at a time.
#
# The kernel walks each segment's subdivision tree depth first with an explicit stack;
# here the whole frontier of one level is split at once. The counters are sums over
# fragments, so they do not depend on the order. The merged interval does, but only
# where two candidate ends share a parameter: the kernel keeps the first one it meets
# (its comparisons are strict). To keep the same one, each decision carries the key of
# its place in the kernel's walk (see `_Fragments.path`), and ties are broken by it.
#
# The kernel's stack is never full: a fragment is split only if its two wide codes
# differ, i.e. it crosses one of the eight band lines (edge +- rounding margin), each
# crossed once along a segment (nine children with the last-ulp difference between P1
# and P0 + 1 (P1 - P0)), so 31 levels of pushes hold at most 8 * 31 + 1 entries of its
# 272. Its "stack full" leaf rule has no counterpart here.


@dataclass(frozen=True)
class _Fragments:
    """Fragments of segments: the interval [ta, tb] of segment `seg`, its ends and codes.

    `path` (uint8, one column per level) records where the fragment sits in the kernel's
    depth-first walk: column ``L - 1`` of a fragment at level L holds ``n + 1 - j`` for
    its place j among its parent's n children, and later columns hold 0. The kernel
    pushes children left to right and pops the last pushed first, so it visits a
    fragment's children right to left (lower digit first), each fragment before its
    descendants (0 sorts first): the walk is the lexicographic order of paths.
    """

    seg: np.ndarray
    ta: np.ndarray
    tb: np.ndarray
    xa: np.ndarray
    ya: np.ndarray
    xb: np.ndarray
    yb: np.ndarray
    ca: np.ndarray
    cb: np.ndarray
    path: np.ndarray

    def __len__(self) -> int:
        return self.seg.size

    def take(self, index) -> _Fragments:
        """Return the fragments at `index` (a mask, or indices with repeats)."""
        return _Fragments(*(getattr(self, f.name)[index] for f in fields(self)))


class _Candidates:
    """Candidate ends of each segment's merged interval, collected in any order.

    The kernel merges accepted children and clipped leaves into one interval: the lowest
    start and the highest end, the first met among equals. Each candidate carries the
    `key` of the decision that produced it (its parent's path, then its own place j), so
    the first met can be found again.
    """

    def __init__(self) -> None:
        self._found = []

    def add(self, seg, key, t0, x0, y0, t1, x1, y1) -> None:
        """Add the interval [t0, t1] with end points found for fragments of segments `seg`."""
        self._found.append((seg, key, t0, x0, y0, t1, x1, y1))

    def merged(self, n_segments: int):
        """Return per segment (lo_t, lo_x, lo_y, hi_t, hi_x, hi_y); no candidate: lo > hi."""
        if not self._found:
            none = np.zeros(n_segments)
            return np.full(n_segments, np.inf), none, none, np.full(n_segments, -np.inf), none, none
        columns = zip(*self._found, strict=True)
        seg, key, t0, x0, y0, t1, x1, y1 = (np.concatenate(c) for c in columns)
        lo_t, lo_x, lo_y = _first_lowest(n_segments, seg, key, t0, x0, y0)
        minus_hi_t, hi_x, hi_y = _first_lowest(n_segments, seg, key, -t1, x1, y1)
        return lo_t, lo_x, lo_y, -minus_hi_t, hi_x, hi_y


def _first_lowest(n_segments, seg, key, t, x, y):
    """Return per segment the candidate of lowest `t`, the first in walk order among equals.

    A segment without candidates gets ``t = inf``.
    """
    order = np.lexsort([*key.T[::-1], t, seg])  # by segment, then t, then walk order
    seg_sorted = seg[order]
    head = order[np.diff(seg_sorted, prepend=-1) != 0]
    best_t = np.full(n_segments, np.inf)
    best_x, best_y = np.zeros(n_segments), np.zeros(n_segments)
    best_t[seg[head]], best_x[seg[head]], best_y[seg[head]] = t[head], x[head], y[head]
    return best_t, best_x, best_y


def _split_count(frontier: _Fragments, length, options: SegmentOptions) -> np.ndarray:
    """Return N for each fragment: fixed, or ``n="auto"`` (``auto_n``).

    Auto: ``ceil(piece length / window size)`` clamped to AUTO_N_MIN..N_MAX, so a piece
    much longer than the window is cut into window-sized pieces in one step.
    """
    if options.n > 0:
        return np.full(len(frontier), options.n, dtype=np.int64)
    piece = (frontier.tb - frontier.ta) * length[frontier.seg]
    k = np.ceil(piece / options.auto_piece)
    many = np.where(k > N_MAX, N_MAX, k)
    return np.where(~(piece > AUTO_N_MIN * options.auto_piece), AUTO_N_MIN, many).astype(np.int64)


def _split(frontier: _Fragments, level: int, s: _Segments, length, options, w: Window):
    """Return the children of every fragment, with the key of each one's decision.

    Child j of n spans ``[ta + step (j-1)/n, ta + step j/n]``, evaluated exactly as the
    kernel does (``t = ta + step * j / n``, ``P(t) = P0 + t (P1 - P0)``); each child
    starts where its left neighbour ends, the first at its parent's start, and the last
    ends at its parent's own end point (not a recomputed one).
    """
    n = _split_count(frontier, length, options)
    parent = np.repeat(np.arange(len(frontier)), n)
    j = np.arange(parent.size) - np.repeat(np.cumsum(n) - n, n) + 1
    n = n[parent]
    up = frontier.take(parent)
    t = up.ta + (up.tb - up.ta) * j / n
    x, y, c = _wide_outcode_at(s.take(up.seg), t, w)
    last = j == n
    tb, xb, yb, cb = (np.where(last, old, new) for new, old in
                      ((t, up.tb), (x, up.xb), (y, up.yb), (c, up.cb)))
    first = j == 1
    ta, xa, ya, ca = (np.where(first, old, np.roll(new, 1)) for new, old in
                      ((tb, up.ta), (xb, up.xa), (yb, up.ya), (cb, up.ca)))
    key = np.column_stack([up.path, j.astype(np.uint8)])
    path = up.path.copy()
    path[:, level - 1] = n + 1 - j
    return _Fragments(up.seg, ta, tb, xa, ya, xb, yb, ca, cb, path), key


def _clip_leaf(s: _Segments, ta, tb, xa, ya, xb, yb, flags, w: Window, st):
    """Return (ok, u0, ax, ay, u1, bx, by): RNSCA's exact clip of leaves (``_clip_leaf``).

    A leaf whose visible part is a single point is not `ok`.
    """
    ok, u0, ax, ay, u1, bx, by = _liang_barsky_leaf(s, ta, tb, xa, ya, xb, yb, flags, w, st)
    return ok & _is_piece(False, u0, u1, ax, ay, bx, by), u0, ax, ay, u1, bx, by


def _decide(kids: _Fragments, key, level: int, s: _Segments, length, options, w: Window,
            st, candidates: _Candidates) -> _Fragments:
    """Accept, reject, clip or drop the children of one level; return those to split.

    Both outcodes zero: accept whole. Codes sharing a bit: reject whole. Otherwise the
    child is ambiguous, and a leaf if at `max_depth` or no longer than `tolerance`:
    clipped with Liang–Barsky (exact mode) or dropped (approx mode).
    """
    st[C.EVALUATED] += len(kids)
    inside = (kids.ca | kids.cb) == 0
    outside = ~inside & (((kids.ca & kids.cb) >> SURE_SHIFT) != 0)
    ambiguous = ~inside & ~outside
    short = (kids.tb - kids.ta) * length[kids.seg] <= options.tolerance
    # ``ca == cb``: both ends within rounding of the same edges; splitting cannot help.
    leaf = ambiguous & ((level >= options.max_depth) | short | (kids.ca == kids.cb))
    _count(st, C.ACCEPTED, inside)
    _count(st, C.REJECTED, outside)
    _count(st, C.SUBDIVIDED, ambiguous & ~leaf)
    st[C.LEVELS + level] += np.count_nonzero(inside | outside | leaf)

    # A zero-width accepted child carries no length and gives no end (as in the kernel).
    wide = inside & (kids.ta < kids.tb)
    a = kids.take(wide)
    candidates.add(a.seg, key[wide], a.ta, a.xa, a.ya, a.tb, a.xb, a.yb)
    if options.mode is Mode.EXACT:
        _count(st, C.CLIPPED, leaf)
        lf = kids.take(leaf)
        ok, u0, ax, ay, u1, bx, by = _clip_leaf(s.take(lf.seg), lf.ta, lf.tb, lf.xa, lf.ya,
                                                lf.xb, lf.yb, (lf.ca | lf.cb) & UNSURE_BITS, w, st)
        candidates.add(lf.seg[ok], key[leaf][ok], u0[ok], ax[ok], ay[ok], u1[ok], bx[ok], by[ok])
    else:
        _count(st, C.DROPPED, leaf)
    return kids.take(ambiguous & ~leaf)


def _rnsca(s: _Segments, w: Window, options: SegmentOptions, st) -> _Clipped:
    """Clip every segment with RNSCA (``rnsca_segment``), breadth first."""
    exact = options.mode is Mode.EXACT
    n = s.size
    out = _Clipped.nothing(n)
    c0, c1 = _outcode(s.x0, s.y0, *w.bounds), _outcode(s.x1, s.y1, *w.bounds)
    length = np.hypot(s.dx, s.dy)

    # Level 0, the whole segment: accept, reject, or a leaf already.
    st[C.EVALUATED] += n
    inside = (c0 | c1) == 0
    outside = ~inside & ((c0 & c1) != 0)
    ambiguous = ~inside & ~outside
    # The driver first screens with |dx| + |dy| >= length, then the kernel tests length.
    short = ~(np.abs(s.dx) + np.abs(s.dy) > options.tolerance) | (length <= options.tolerance)
    leaf = ambiguous & ((options.max_depth == 0) | short)
    _count(st, C.ACCEPTED, inside)
    _count(st, C.REJECTED, outside)
    st[C.LEVELS] += np.count_nonzero(inside | outside | leaf)
    rows = np.flatnonzero(inside)
    out.set(rows, True, 0.0, 1.0, s.x0[rows], s.y0[rows], s.x1[rows], s.y1[rows])
    if exact:
        _count(st, C.CLIPPED, leaf)
        rows = np.flatnonzero(leaf)
        sr = s.take(rows)
        ok, u0, ax, ay, u1, bx, by = _clip_leaf(sr, np.zeros(rows.size), np.ones(rows.size),
                                                sr.x0, sr.y0, sr.x1, sr.y1,
                                                c0[rows] | c1[rows], w, st)
        out.set(rows, ok, u0, u1, ax, ay, bx, by)
    else:
        _count(st, C.DROPPED, leaf)

    # The rest are split, level by level, until no fragment is left undecided.
    rows = np.flatnonzero(ambiguous & ~leaf)
    st[C.SUBDIVIDED] += rows.size
    frontier = _Fragments(rows, np.zeros(rows.size), np.ones(rows.size),
                          s.x0[rows], s.y0[rows], s.x1[rows], s.y1[rows],
                          _wide(c0[rows]), _wide(c1[rows]),
                          np.zeros((rows.size, options.max_depth), dtype=np.uint8))
    candidates = _Candidates()
    level = 0
    while len(frontier):
        level += 1
        _reach(st, level)
        kids, key = _split(frontier, level, s, length, options, w)
        frontier = _decide(kids, key, level, s, length, options, w, st, candidates)

    # One interval per segment: the lowest start and the highest end found.
    lo_t, lo_x, lo_y, hi_t, hi_x, hi_y = candidates.merged(n)
    keep = (lo_t <= hi_t) & _is_piece(False, lo_t, hi_t, lo_x, lo_y, hi_x, hi_y)
    out.set(rows, keep[rows], lo_t[rows], hi_t[rows], lo_x[rows], lo_y[rows],
            hi_x[rows], hi_y[rows])
    return out


_CLIPPERS = {
    Method.RNSCA: _rnsca,
    Method.COHEN_SUTHERLAND: _cohen_sutherland,
    Method.LIANG_BARSKY: _liang_barsky,
    Method.NICHOLL_LEE_NICHOLL: _nicholl_lee_nicholl,
    Method.MIDPOINT: _midpoint,
}
