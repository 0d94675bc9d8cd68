"""Hypothesis strategies: windows at any scale, and segments aimed at what breaks clipping.

A window is drawn at a scale ``10**e`` (e from -290 to 290), with any aspect ratio up to
1e4 and an offset from the origin of up to 1000 window sizes. Segments are drawn
relative to their window, each of one kind:

- ``random``: ends anywhere within two window sizes of the window;
- ``boundary``: ends on edge and corner values, one ulp either side of them, thirds;
- ``along_edge``: both ends on the same edge line, inside it or beyond its corners;
- ``through_corner``: symmetric about a corner, in any direction;
- ``touching_corner``: symmetric about a corner, with the window on one side only;
- ``axis``: horizontal or vertical, anywhere;
- ``zero_length``: both ends equal, inside, outside or on the boundary;
- ``lattice``: ends on a grid of 1/8 window steps, so split points land on edges;
- ``long``: through a point of the window, up to `LONG_SEGMENT_MAX_RATIO` windows long.

Long segments reach 1e6 windows. Cut points are computed in double-double from the
nearer end, so their coordinates stay within the exact-mode promise far beyond that
(the literal cases in `tests.cases` check 2e8 and 2e15 windows). What limits the
parametric methods (Liang–Barsky, RNSCA, midpoint) is the parameter t itself: its ulp is
eps times the segment's length, so a visible part shorter than that can be lost (or a
touching one kept), which breaks the 1e-9 promise past ~1e7 windows (see README, "Limits").

One documented limitation is left out: a segment whose direction has a non-zero
component that is subnormal or below 2**-500 (~3e-151) of the window's size (e.g. from
an edge at 0 to one ulp beside it). There the cut point itself is not representable to
the promise's precision and rounding flushes its residual, so the result may include or
miss a sub-ulp sliver (see README, "Limits").
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume
from hypothesis import strategies as st

from rnsca import Window

LONG_SEGMENT_MAX_RATIO = 1e6
#: Smallest normal float64: below it a direction component is subnormal.
TINY = 2.2250738585072014e-308
N_CHOICES = ["auto", 2, 3, 7, 64]
DEPTH_CHOICES = [None, 0, 1, 5, 32]
#: Tolerances as fractions of the window's size; None: the mode's default.
TOLERANCE_CHOICES = [None, 1e-12, 1e-6, 0.3]
KINDS = ("random", "boundary", "along_edge", "through_corner", "touching_corner", "axis",
         "zero_length", "lattice", "long")


@st.composite
def windows(draw, min_exponent: int = -290, max_exponent: int = 290) -> Window:
    """Return a window at scale 10**e, of aspect ratio up to 1e4, up to 1000 sizes away."""
    scale = 10.0 ** draw(st.integers(min_exponent, max_exponent), label="exponent")
    width = draw(st.floats(0.01, 100.0)) * scale
    height = draw(st.floats(0.01, 100.0)) * scale
    size = max(width, height)
    x = draw(st.one_of(st.just(0.0), st.floats(-1000.0, 1000.0))) * size
    y = draw(st.one_of(st.just(0.0), st.floats(-1000.0, 1000.0))) * size
    assume(x + width > x and y + height > y)
    return Window(x, y, x + width, y + height)


def _special(low: float, high: float) -> list[float]:
    """Values along one axis where clipping code goes wrong."""
    size = high - low
    return [low, high, float(np.nextafter(low, -math.inf)), float(np.nextafter(low, math.inf)),
            float(np.nextafter(high, -math.inf)), float(np.nextafter(high, math.inf)),
            low + size / 2, low + size / 3, high - size / 3, low - size, high + size,
            low - size / 7, high + size / 64]


def _coordinate(draw, low: float, high: float, reach: float = 2.0) -> float:
    """A coordinate within `reach` window sizes of [low, high], or a special value."""
    size = high - low
    return draw(st.one_of(st.floats(-reach, 1.0 + reach).map(lambda u: low + u * size),
                          st.sampled_from(_special(low, high))))


def _corner(draw, w: Window) -> tuple[float, float]:
    return (draw(st.sampled_from([w.xmin, w.xmax])), draw(st.sampled_from([w.ymin, w.ymax])))


@st.composite
def segment(draw, w: Window, kind: str | None = None) -> list[float]:
    """Return one segment ``[x0, y0, x1, y1]`` of the given kind (or a drawn one)."""
    seg = _segment(draw, w, kind)
    tiny = max(TINY, w.size * 2.0 ** -500)
    assume(not (0.0 < abs(seg[2] - seg[0]) < tiny or 0.0 < abs(seg[3] - seg[1]) < tiny))
    return seg


def _segment(draw, w: Window, kind: str | None = None) -> list[float]:
    kind = kind or draw(st.sampled_from(KINDS), label="kind")
    x = lambda: _coordinate(draw, w.xmin, w.xmax)  # noqa: E731
    y = lambda: _coordinate(draw, w.ymin, w.ymax)  # noqa: E731
    if kind == "random":
        u = [draw(st.floats(-2.0, 3.0)) for _ in range(4)]
        return [w.xmin + u[0] * w.width, w.ymin + u[1] * w.height,
                w.xmin + u[2] * w.width, w.ymin + u[3] * w.height]
    if kind == "boundary":
        xs, ys = _special(w.xmin, w.xmax), _special(w.ymin, w.ymax)
        return [draw(st.sampled_from(xs)), draw(st.sampled_from(ys)),
                draw(st.sampled_from(xs)), draw(st.sampled_from(ys))]
    if kind == "along_edge":
        if draw(st.booleans()):
            edge = draw(st.sampled_from([w.xmin, w.xmax]))
            return [edge, y(), edge, y()]
        edge = draw(st.sampled_from([w.ymin, w.ymax]))
        return [x(), edge, x(), edge]
    if kind in ("through_corner", "touching_corner"):
        cx, cy = _corner(draw, w)
        angle = draw(st.floats(0.0, 2 * math.pi))
        dx, dy = math.cos(angle), math.sin(angle)
        if kind == "touching_corner":
            # The line through the corner leaves the window on one side when the
            # direction's slope sign is opposite to the corner's diagonal.
            same_diagonal = (cx == w.xmin) == (cy == w.ymin)
            dx, dy = abs(dx), abs(dy) * (-1.0 if same_diagonal else 1.0)
        reach = draw(st.floats(1e-6, 3.0)) * w.size
        back = draw(st.sampled_from([1.0, 0.0, 0.5, 2.0]))  # 0: ends at the corner
        return [cx - back * reach * dx, cy - back * reach * dy, cx + reach * dx, cy + reach * dy]
    if kind == "axis":
        if draw(st.booleans()):
            at = y()
            return [x(), at, x(), at]
        at = x()
        return [at, y(), at, y()]
    if kind == "zero_length":
        px, py = x(), y()
        return [px, py, px, py]
    if kind == "lattice":
        k = st.integers(-16, 24)
        return [w.xmin + draw(k) * w.width / 8, w.ymin + draw(k) * w.height / 8,
                w.xmin + draw(k) * w.width / 8, w.ymin + draw(k) * w.height / 8]
    # long: through a point of the window, far out on both sides
    cx = w.xmin + draw(st.floats(0.0, 1.0)) * w.width
    cy = w.ymin + draw(st.floats(0.0, 1.0)) * w.height
    angle = draw(st.floats(0.0, 2 * math.pi))
    ratio = 10.0 ** draw(st.floats(0.0, math.log10(LONG_SEGMENT_MAX_RATIO)))
    a, b = draw(st.floats(0.0, 1.0)), draw(st.floats(0.0, 1.0))
    reach = ratio * w.size
    return [cx - a * reach * math.cos(angle), cy - a * reach * math.sin(angle),
            cx + b * reach * math.cos(angle), cy + b * reach * math.sin(angle)]


@st.composite
def segment_batches(draw, w: Window, kinds=KINDS, max_size: int = 12) -> np.ndarray:
    """Return a float64 (n, 4) batch of 1..max_size segments of mixed kinds."""
    n = draw(st.integers(1, max_size))
    rows = [draw(segment(w, draw(st.sampled_from(kinds)))) for _ in range(n)]
    batch = np.array(rows, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        assume(np.isfinite(batch).all() and np.isfinite(batch[:, 2:] - batch[:, :2]).all())
    return batch


@st.composite
def options(draw, w: Window) -> dict:
    """Return subdivision options for `w`: N, max_depth and a tolerance in window units."""
    tolerance = draw(st.sampled_from(TOLERANCE_CHOICES))
    return {"n": draw(st.sampled_from(N_CHOICES)),
            "max_depth": draw(st.sampled_from(DEPTH_CHOICES)),
            "tolerance": None if tolerance is None else tolerance * w.size}


@st.composite
def clip_inputs(draw, kinds=KINDS, min_exponent: int = -290, max_exponent: int = 290):
    """Return ``(window, segments, options)``."""
    w = draw(windows(min_exponent, max_exponent), label="window")
    return w, draw(segment_batches(w, kinds), label="segments"), draw(options(w), label="options")


@st.composite
def inside_batches(draw, w: Window) -> np.ndarray:
    """Return segments with both ends in the closed window (boundary included)."""
    n = draw(st.integers(1, 20))
    xs = st.one_of(st.floats(0.0, 1.0).map(lambda u: w.xmin + u * w.width),
                   st.sampled_from([w.xmin, w.xmax, float(np.nextafter(w.xmin, math.inf))]))
    ys = st.one_of(st.floats(0.0, 1.0).map(lambda u: w.ymin + u * w.height),
                   st.sampled_from([w.ymin, w.ymax, float(np.nextafter(w.ymax, -math.inf))]))
    rows = np.array([[draw(xs), draw(ys), draw(xs), draw(ys)] for _ in range(n)])
    rows[:, 0::2] = np.clip(rows[:, 0::2], w.xmin, w.xmax)
    rows[:, 1::2] = np.clip(rows[:, 1::2], w.ymin, w.ymax)
    return rows


@st.composite
def beyond_one_edge_batches(draw, w: Window) -> np.ndarray:
    """Return segments whose two ends lie strictly beyond the same edge."""
    n = draw(st.integers(1, 20))
    rows = []
    for _ in range(n):
        x0, y0, x1, y1 = draw(segment(w, "random"))
        gap0, gap1 = (draw(st.floats(1e-9, 3.0)) * w.size for _ in range(2))
        edge = draw(st.sampled_from(["left", "right", "bottom", "top"]))
        if edge == "left":
            x0, x1 = w.xmin - gap0, w.xmin - gap1
        elif edge == "right":
            x0, x1 = w.xmax + gap0, w.xmax + gap1
        elif edge == "bottom":
            y0, y1 = w.ymin - gap0, w.ymin - gap1
        else:
            y0, y1 = w.ymax + gap0, w.ymax + gap1
        rows.append([x0, y0, x1, y1])
    return np.array(rows, dtype=np.float64)
