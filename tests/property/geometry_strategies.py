"""Hypothesis strategies for whole geometries and the windows they are clipped to.

Everything is drawn in *relative* coordinates ``(u, v)`` of a frame window (the frame is
``[0, 1]^2``) and mapped to absolute ones by `Frame.absolute`, which sends 0 and 1 to the
frame's bounds exactly. A frame is one of:

- a **grid** frame: integer bounds whose width and height are multiples of G (G in 4, 8,
  16, 32), with every relative coordinate snapped to a multiple of 1/G, so every
  coordinate (geometry and window) is an integer: vertices fall exactly on window edges,
  edges run exactly along them, and cut points are often exact;
- a **float** frame at scales 1e-6 to 1e6 (any aspect ratio up to 1e4, up to 1000
  window sizes from the origin), where Shapely's GEOS is accurate to far better than
  the 1e-9 the comparison allows.

Geometries (relative coordinates, then mapped):

- **lines**: 2 to 12 vertices, each of one kind: random, on the frame's grid of quarters,
  on an edge line, on a corner, repeating the previous vertex, running along the edge the
  previous vertex is on, axis-parallel to the previous one, or a pair through a corner;
- **stars**: a simple polygon by construction: vertices sorted by angle around a center,
  at radii from a radial function, no angular gap reaching pi; up to 3 holes, each a
  smaller star around a point of the shell's inner disc (the disc of the smallest
  distance from the center to an edge), small enough that the holes are disjoint and
  inside that disc: valid by construction;
- **combs**: a base bar with 2 to 5 teeth of integer widths, gaps and heights (in units
  of 1/G), turned by a multiple of 90 degrees; concave, so a window across the teeth
  splits it into one piece per tooth;
- **multipolygons**: 2 to 4 stars (holes allowed) on distinct cells of a 3 x 3 grid, each
  within 0.45 of a cell of its center: disjoint by construction;
- **points** and **multipoints**: vertices of the kinds lines use.

Snapping to a grid can make a star invalid (two vertices rounding together); the star
is then used unsnapped, never dropped. Rings come in either orientation.

Relative offsets below 1e-100 are flushed to 0 (`TINY`), as are the frame's offsets
from the origin: GEOS underflows on such numbers (`tests.checks.shapely_can_judge`).

Windows are placed against the geometry's coordinates (`window_for`): the frame itself,
inside the geometry's bounding box, outside it (touching its side with gap 0 sometimes),
enclosing it (touching with margin 0 sometimes), crossing it, with every bound snapped
to one of the geometry's own coordinates (so edges pass through vertices and along
edges), and, for combs, a band across the teeth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from hypothesis import assume
from hypothesis import strategies as st

from rnsca import Window

__all__ = [
    "Frame",
    "PLACEMENTS",
    "frames",
    "line_coords",
    "lines",
    "multilines",
    "points",
    "multipoints",
    "stars",
    "combs",
    "polygons",
    "multipolygons",
    "monotone_lines",
    "window_for",
    "with_z",
    "cases",
]

PLACEMENTS = ("frame", "inside", "outside", "enclosing", "crossing", "snapped")
VERTEX_KINDS = ("random", "grid", "edge", "corner", "repeat", "along_edge", "axis",
                "through_corner")
GRIDS = (4, 8, 16, 32)


@dataclass(frozen=True)
class Frame:
    """The window that relative coordinates are measured in, and its grid (None: floats)."""

    window: Window
    grid: int | None

    def snap(self, uv: np.ndarray) -> np.ndarray:
        """Return relative coordinates rounded to the grid (unchanged in a float frame)."""
        uv = np.asarray(uv, dtype=np.float64)
        return uv if self.grid is None else np.round(uv * self.grid) / self.grid

    def absolute(self, uv: np.ndarray) -> np.ndarray:
        """Return absolute coordinates of relative ones; 0 and 1 land on the bounds exactly."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        w = self.window
        out = np.empty_like(uv)
        for k, (lo, hi) in enumerate(((w.xmin, w.xmax), (w.ymin, w.ymax))):
            out[:, k] = np.where(uv[:, k] == 0.0, lo,
                                 np.where(uv[:, k] == 1.0, hi, lo + uv[:, k] * (hi - lo)))
        return out

    def geometry(self, relative):
        """Return a shapely geometry in relative coordinates mapped to absolute ones."""
        return shapely.transform(relative, self.absolute)


@st.composite
def frames(draw) -> Frame:
    """Return a grid frame (integer coordinates) or a float frame at scale 1e-6..1e6."""
    if draw(st.booleans(), label="grid frame"):
        g = draw(st.sampled_from(GRIDS))
        x0, y0 = draw(st.integers(-50, 50)), draw(st.integers(-50, 50))
        width, height = g * draw(st.integers(1, 3)), g * draw(st.integers(1, 3))
        return Frame(Window(x0, y0, x0 + width, y0 + height), g)
    scale = 10.0 ** draw(st.integers(-6, 6), label="exponent")
    width, height = (draw(st.floats(0.01, 100.0)) * scale for _ in range(2))
    size = max(width, height)
    x, y = (draw(st.one_of(st.just(0.0), _floats(-1000.0, 1000.0))) * size for _ in range(2))
    assume(x + width > x and y + height > y)
    return Frame(Window(x, y, x + width, y + height), None)


#: Relative offsets below this are flushed to 0: under 2**-500 of the window's size a cut
#: point is not representable to the 1e-9 promise (README, "Limits") and GEOS underflows
#: (`tests.checks.shapely_can_judge`); `tests/property/test_vs_exact.py` covers them.
TINY = 1e-100


def _flush(u: float) -> float:
    return 0.0 if abs(u) < TINY else u


def _floats(low: float, high: float):
    return st.floats(low, high).map(_flush)


def _unit(draw, low: float = -0.75, high: float = 1.75) -> float:
    return draw(st.one_of(_floats(low, high), st.sampled_from([0.0, 1.0, 0.5, 0.25, 0.75])))


# --- lines and points ----------------------------------------------------------------------

def _vertex(draw, kind: str, previous: list[float] | None) -> list[list[float]]:
    """Return the relative vertices one draw of `kind` adds (a pair for through_corner)."""
    if kind == "repeat" and previous is not None:
        return [list(previous)]
    if kind == "along_edge" and previous is not None:
        if previous[0] in (0.0, 1.0):
            return [[previous[0], _unit(draw)]]
        if previous[1] in (0.0, 1.0):
            return [[_unit(draw), previous[1]]]
        kind = "edge"
    if kind == "axis" and previous is not None:
        return [[previous[0], _unit(draw)]] if draw(st.booleans()) else [[_unit(draw),
                                                                          previous[1]]]
    if kind == "grid":
        k = st.integers(-4, 8)
        return [[draw(k) / 4, draw(k) / 4]]
    if kind == "edge":
        edge = draw(st.sampled_from([0.0, 1.0]))
        return [[edge, _unit(draw)]] if draw(st.booleans()) else [[_unit(draw), edge]]
    if kind == "corner":
        return [[draw(st.sampled_from([0.0, 1.0])), draw(st.sampled_from([0.0, 1.0]))]]
    if kind == "through_corner":
        cu, cv = draw(st.sampled_from([0.0, 1.0])), draw(st.sampled_from([0.0, 1.0]))
        du, dv = draw(_floats(-0.8, 0.8)), draw(_floats(-0.8, 0.8))
        return [[cu - du, cv - dv], [cu + du, cv + dv]]
    return [[_unit(draw), _unit(draw)]]


@st.composite
def line_coords(draw, frame: Frame, min_vertices: int = 2, max_vertices: int = 12):
    """Return relative vertices (n, 2) of one line, each vertex of a drawn kind."""
    n = draw(st.integers(min_vertices, max_vertices))
    out: list[list[float]] = []
    while len(out) < n:
        kind = draw(st.sampled_from(VERTEX_KINDS))
        out.extend(_vertex(draw, kind, out[-1] if out else None))
    return frame.snap(np.array(out[:max(n, 2)]))


@st.composite
def lines(draw, frame: Frame):
    """Return a LINESTRING (relative coordinates)."""
    return shapely.LineString(draw(line_coords(frame)))


@st.composite
def multilines(draw, frame: Frame):
    """Return a MULTILINESTRING of 1 to 3 lines (relative coordinates)."""
    return shapely.MultiLineString([draw(line_coords(frame))
                                    for _ in range(draw(st.integers(1, 3)))])


@st.composite
def monotone_lines(draw, frame: Frame):
    """Return a LINESTRING whose x strictly increases (so it never meets itself)."""
    n = draw(st.integers(2, 16))
    xs = np.sort(np.array(draw(st.lists(_floats(-0.75, 1.75), min_size=n, max_size=n,
                                        unique=True))))
    ys = np.array([_unit(draw) for _ in range(n)])
    uv = frame.snap(np.column_stack([xs, ys]))
    assume(np.all(np.diff(uv[:, 0]) > 0))
    return shapely.LineString(uv)


@st.composite
def points(draw, frame: Frame):
    """Return a POINT (relative coordinates): random, on the grid, an edge or a corner."""
    kind = draw(st.sampled_from(("random", "grid", "edge", "corner")))
    return shapely.Point(frame.snap(np.array(_vertex(draw, kind, None)[0])))


@st.composite
def multipoints(draw, frame: Frame):
    """Return a MULTIPOINT of 1 to 10 points (repeats possible)."""
    uv = draw(line_coords(frame, 1, 10))
    return shapely.MultiPoint(uv)


# --- polygons ------------------------------------------------------------------------------

def _star_ring(draw, center, radius: float, min_fraction: float, n_min: int = 3,
               n_max: int = 14) -> np.ndarray:
    """Return a closed star ring (CCW) around `center` with radii in [f r, r]."""
    n = draw(st.integers(n_min, n_max))
    jitter = np.array(draw(st.lists(st.floats(0.0, 0.45), min_size=n, max_size=n)))
    angles = (np.arange(n) + jitter) * 2 * math.pi / n + draw(st.floats(0.0, 2 * math.pi))
    radii = radius * np.array(draw(st.lists(st.floats(min_fraction, 1.0), min_size=n,
                                            max_size=n)))
    ring = np.column_stack([center[0] + radii * np.cos(angles),
                            center[1] + radii * np.sin(angles)])
    return np.vstack([ring, ring[:1]])


def _inner_radius(ring: np.ndarray, center) -> float:
    """Return the smallest distance from `center` to an edge of the closed `ring`."""
    a, b = ring[:-1], ring[1:]
    d = b - a
    t = np.clip(((np.asarray(center) - a) * d).sum(axis=1) / (d * d).sum(axis=1), 0.0, 1.0)
    return float(np.hypot(*(a + t[:, None] * d - center).T).min())


def _oriented(draw, ring: np.ndarray) -> np.ndarray:
    return ring[::-1].copy() if draw(st.booleans(), label="reverse ring") else ring


def _star_polygon(draw, frame: Frame, center, radius: float, max_holes: int = 3):
    """Return a star polygon (relative coordinates) with 0..max_holes holes inside."""
    shell = _star_ring(draw, center, radius, draw(st.floats(0.3, 1.0)))
    holes = []
    n_holes = draw(st.integers(0, max_holes))
    if n_holes:
        inner = _inner_radius(shell, center)
        if n_holes == 1:
            spots, reach = [np.asarray(center)], 0.8 * inner
        else:
            # Hole centres on a circle of radius inner/2, each hole within a disc that
            # touches neither its neighbours' discs nor the inner disc's rim.
            turn = draw(st.floats(0.0, 2 * math.pi))
            spots = [np.asarray(center) + inner / 2 * np.array([math.cos(turn + 2 * math.pi
                                                                         * j / n_holes),
                                                                math.sin(turn + 2 * math.pi
                                                                         * j / n_holes)])
                     for j in range(n_holes)]
            reach = 0.8 * min(inner / 2, inner / 2 * math.sin(math.pi / n_holes))
        for spot in spots:
            holes.append(_oriented(draw, _star_ring(draw, spot, reach * draw(
                st.floats(0.2, 1.0)), draw(st.floats(0.3, 1.0)), 3, 8)))
    shell = _oriented(draw, shell)
    exact = shapely.Polygon(shell, holes)
    snapped = shapely.Polygon(frame.snap(shell), [frame.snap(h) for h in holes])
    if frame.grid is not None and snapped.is_valid and frame.geometry(snapped).is_valid:
        return snapped
    return exact


@st.composite
def stars(draw, frame: Frame):
    """Return a star-shaped POLYGON with up to 3 holes (relative coordinates)."""
    center = [_unit(draw, -0.5, 1.5), _unit(draw, -0.5, 1.5)]
    return _star_polygon(draw, frame, center, draw(st.floats(0.05, 1.5)))


@st.composite
def combs(draw, frame: Frame):
    """Return ``(comb, band)``: a comb POLYGON and a window (relative) across its teeth."""
    k = draw(st.integers(2, 5))
    widths = [draw(st.integers(1, 3)) for _ in range(k)]
    gaps = [draw(st.integers(1, 3)) for _ in range(k - 1)]
    base = draw(st.integers(1, 3))
    heights = [draw(st.integers(2, 6)) for _ in range(k)]
    lefts = [sum(widths[:i]) + sum(gaps[:i]) for i in range(k)]
    rights = [left + w for left, w in zip(lefts, widths, strict=True)]
    ring = [(0, 0), (rights[-1], 0)]
    for i in range(k - 1, -1, -1):
        ring += [(rights[i], base + heights[i]), (lefts[i], base + heights[i])]
        if i > 0:
            ring += [(lefts[i], base), (rights[i - 1], base)]
    ring.append((0, 0))
    local = np.array(ring, dtype=np.float64)
    # The band: all x, from the base's top (exactly on it) to below the lowest tooth top.
    band = np.array([[-1.0, base], [rights[-1] + 1.0, base + min(heights) - 1]])
    turns = draw(st.integers(0, 3))
    for _ in range(turns):
        local, band = local @ [[0, 1], [-1, 0]], band @ [[0, 1], [-1, 0]]
    unit = 1.0 / frame.grid if frame.grid else draw(st.floats(0.01, 0.1))
    origin = frame.snap(np.array([_unit(draw, -0.5, 0.5), _unit(draw, -0.5, 0.5)]))
    uv = origin + local * unit
    band = origin + band * unit
    comb = shapely.Polygon(_oriented(draw, uv))
    return comb, (*band.min(axis=0), *band.max(axis=0))


@st.composite
def polygons(draw, frame: Frame):
    """Return a star with holes or a comb (relative coordinates), and a suggested window."""
    if draw(st.booleans(), label="comb"):
        return draw(combs(frame))
    return draw(stars(frame)), None


@st.composite
def multipolygons(draw, frame: Frame):
    """Return a MULTIPOLYGON of 2 to 4 disjoint stars (relative coordinates)."""
    cell = draw(st.floats(0.2, 0.8))
    origin = [_unit(draw, -0.5, 0.5), _unit(draw, -0.5, 0.5)]
    spots = draw(st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2)), min_size=2,
                          max_size=4, unique=True))
    parts = []
    for i, j in spots:
        center = [origin[0] + (i + 0.5) * cell, origin[1] + (j + 0.5) * cell]
        parts.append(_star_polygon(draw, frame, center, 0.45 * cell * draw(st.floats(0.3, 1.0)),
                                   max_holes=2))
    return shapely.MultiPolygon(parts)


# --- windows -------------------------------------------------------------------------------

@st.composite
def window_for(draw, frame: Frame, relative_geometries, suggested=None,
               placements=PLACEMENTS) -> Window:
    """Return a window placed against the geometries (relative), mapped like them."""
    uv = np.concatenate([shapely.get_coordinates(g) for g in relative_geometries])
    choices = list(placements) + (["suggested"] * 2 if suggested is not None else [])
    placement = draw(st.sampled_from(choices), label="placement")
    if uv.shape[0] == 0:
        placement = "frame"
    if placement == "frame":
        return frame.window
    a0, b0 = uv.min(axis=0)
    a1, b1 = uv.max(axis=0)
    s = max(a1 - a0, b1 - b0, 0.25)
    fraction = _floats(0.0, 1.0)
    if placement == "suggested":
        box = list(suggested)
    elif placement == "inside":
        u = sorted([draw(fraction), draw(fraction)])
        v = sorted([draw(fraction), draw(fraction)])
        box = [a0 + u[0] * (a1 - a0), b0 + v[0] * (b1 - b0),
               a0 + u[1] * (a1 - a0), b0 + v[1] * (b1 - b0)]
    elif placement == "outside":
        gap = draw(st.sampled_from([0.0, 0.1, 0.5])) * s
        depth = draw(_floats(0.1, 2.0)) * s
        side = draw(st.sampled_from(["left", "right", "below", "above"]))
        lo, hi = sorted([draw(_floats(-1.0, 2.0)), draw(_floats(-1.0, 2.0))])
        if side in ("left", "right"):
            x = [a0 - gap - depth, a0 - gap] if side == "left" else [a1 + gap, a1 + gap + depth]
            box = [x[0], b0 + lo * (b1 - b0 + s), x[1], b0 + hi * (b1 - b0 + s)]
        else:
            y = [b0 - gap - depth, b0 - gap] if side == "below" else [b1 + gap, b1 + gap + depth]
            box = [a0 + lo * (a1 - a0 + s), y[0], a0 + hi * (a1 - a0 + s), y[1]]
    elif placement == "enclosing":
        margin = st.sampled_from([0.0, 0.0, 0.01, 0.3])
        box = [a0 - draw(margin) * s, b0 - draw(margin) * s,
               a1 + draw(margin) * s, b1 + draw(margin) * s]
    elif placement == "crossing":
        x0, y0 = a0 + draw(_floats(-0.5, 1.0)) * s, b0 + draw(_floats(-0.5, 1.0)) * s
        box = [x0, y0, x0 + draw(_floats(0.05, 1.5)) * s, y0 + draw(_floats(0.05, 1.5)) * s]
    else:  # snapped: every bound is one of the geometry's own coordinates
        xs, ys = np.unique(uv[:, 0]), np.unique(uv[:, 1])
        if xs.size < 2 or ys.size < 2:
            return frame.window
        i = sorted(draw(st.lists(st.integers(0, xs.size - 1), min_size=2, max_size=2,
                                 unique=True)))
        j = sorted(draw(st.lists(st.integers(0, ys.size - 1), min_size=2, max_size=2,
                                 unique=True)))
        box = [xs[i[0]], ys[j[0]], xs[i[1]], ys[j[1]]]
    box = frame.snap(np.array(box, dtype=np.float64))
    if frame.grid is not None:
        step = 1.0 / frame.grid
        box[2], box[3] = max(box[2], box[0] + step), max(box[3], box[1] + step)
    corners = frame.absolute(np.array([box[:2], box[2:]]))
    xmin, ymin = corners[0]
    xmax, ymax = corners[1]
    assume(xmin < xmax and ymin < ymax)
    # Up to 1e4 to 1, like the frames: in a thinner window, a crossing of its long edge
    # by a segment nearly parallel to it is so ill-conditioned that GEOS's double-precision
    # cut point misses by more than 1e-9 of the window (rnsca's is exact; the segment
    # tests check it against rational arithmetic at any aspect).
    assume(max(xmax - xmin, ymax - ymin) <= 1e4 * min(xmax - xmin, ymax - ymin))
    return Window(xmin, ymin, xmax, ymax)


def with_z(draw, geometry):
    """Return `geometry` with a Z on every vertex, drawn from [-100, 100] (seeded).

    Z is a function of the position: vertices at the same XY (a ring's closing vertex,
    repeated vertices, a line crossing its own vertex) get the same Z, as a closed ring
    needs and as makes "the Z of the input vertex at this XY" well defined.
    """
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1), label="z seed"))
    xy = shapely.get_coordinates(geometry)
    unique, position = np.unique(xy, axis=0, return_inverse=True)
    z = rng.uniform(-100.0, 100.0, unique.shape[0])[position.reshape(-1)]
    return shapely.set_coordinates(shapely.force_3d(geometry), np.column_stack([xy, z]))


KINDS = {
    "point": points,
    "multipoint": multipoints,
    "linestring": lines,
    "multilinestring": multilines,
    "polygon": polygons,
    "multipolygon": multipolygons,
}


@st.composite
def cases(draw, kind: str, max_geometries: int = 3, z: bool | None = False):
    """Return ``(geometries, window)``: 1..max_geometries of one kind, and one window.

    `kind` is a key of `KINDS`; polygons may be combs (then the window may be the band
    across the teeth). `z`: True adds Z, None draws whether to.
    """
    frame = draw(frames(), label="frame")
    n = draw(st.integers(1, max_geometries))
    relative, suggested = [], None
    for _ in range(n):
        drawn = draw(KINDS[kind](frame))
        if kind == "polygon":
            drawn, band = drawn
            suggested = band if band is not None else suggested
        relative.append(drawn)
    window = draw(window_for(frame, relative, suggested), label="window")
    geometries = [frame.geometry(g) for g in relative]
    # Valid in relative coordinates by construction; rounding in the map to a float frame
    # (aspect ratios up to 1e4) could in principle spoil that, so check.
    if kind in ("polygon", "multipolygon"):
        assume(all(shapely.is_valid(g) for g in geometries))
    if z is None:
        z = draw(st.booleans(), label="z")
    if z:
        geometries = [with_z(draw, g) for g in geometries]
    return geometries, window
