"""Seeded workloads: segment sets, curves, polygons with holes, a GeoJSON FeatureCollection.

The segment sets are the paper's Table 2 and three shaped variants; the geometry sets
(issue 3) follow them below.

Every generator is a pure function of its size and a fixed seed, so a workload is the
same array on every machine and in every run. A `Workload` describes a set without
holding it; call `Workload.segments()` to build the (n, 4) float64 array when needed
(10M segments are 320 MB, so the runner builds one set at a time).

The sets
--------
``uniform``
    The paper's Table 2: both end points uniform in the extent [0, 1000]^2, window
    [250, 750]^2 (a quarter of the extent's area). Segments are long (mean length about
    520, about the window's side): 6% have both ends inside, 23% are rejected by their
    end points' outcodes, 70% are ambiguous at level 0, and 73% leave a piece.
``mostly_outside``
    The same segments, window [450, 550]^2: 1% of the extent's area. 84% of the segments
    miss the window; 65% are rejected at level 0 by their outcodes.
``mostly_inside``
    The same segments, window [25, 975]^2 (90% of the extent's area): 81% of the
    segments have both ends inside and are accepted whole; 99.7% leave a piece.
``long_segments``
    A small window [495, 505]^2 (side 10, 0.01% of the extent's area) and segments 40 to
    120 times its side: midpoints uniform in [450, 550]^2, directions uniform, lengths
    uniform in [400, 1200]. Almost every segment straddles the window's row or column
    band, so 93% are ambiguous at level 0 and subdivision has to localise the window,
    while only 14% leave a piece. A large N (or ``n="auto"``) rejects the far pieces in
    one step where N = 2 needs about seven bisections.

Geometry sets (issue 3; see `benchmarks.bench_geometry`)
-------------------------------------------------------
``smooth_polylines``
    The paper's curve workload: smooth lines of 2,000 to 5,000 vertices that wander
    across [0, 1000]^2. Each coordinate is a sum of four sinusoids (0.3 to 2.5 cycles
    over the line, random phases and weights, total amplitude 500 to 900) around a
    random centre, folded back into the extent at its edges (a line bounces off the
    extent's border). Vertices cover the extent almost uniformly, so a centred window
    holds about its share of the area in vertices. Vertices are about 1.0 apart.
``star_polygons``
    Polygons with one hole: a star-shaped shell of 40 vertices (radii 0.5 to 1 times
    R, R uniform in [5, 40], angles jittered) around a centre uniform in the extent,
    counter-clockwise, and a star-shaped hole of 10 vertices (radii 0.2 to 0.3 R,
    centre within 0.1 R of the shell's), clockwise. Every polygon is valid; with the
    window [250, 750]^2 about 21% of them lie inside, 71% outside and 8% cross an edge.
``geojson_collection``
    A FeatureCollection of lines (a fifth of them MultiLineStrings) and polygons with
    holes (a tenth MultiPolygons of two), each feature with an id and properties,
    drawn from the two generators above.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "EXTENT",
    "PAPER_SIZES",
    "LARGE_SIZES",
    "Workload",
    "uniform_segments",
    "long_segments",
    "table2",
    "shaped",
    "classify",
    "CURVE_VERTICES",
    "CURVE_WINDOWS",
    "POLYGON_WINDOW",
    "centred_window",
    "smooth_polylines",
    "star_polygons",
    "explode_lines",
    "geojson_collection",
]

EXTENT = (0.0, 0.0, 1000.0, 1000.0)
#: Segment counts of the paper's Table 2.
PAPER_SIZES = (100, 500, 1_000, 5_000, 10_000)
#: Added here: the throughput sizes.
LARGE_SIZES = (100_000, 1_000_000, 10_000_000)

UNIFORM_WINDOW = (250.0, 250.0, 750.0, 750.0)
OUTSIDE_WINDOW = (450.0, 450.0, 550.0, 550.0)
INSIDE_WINDOW = (25.0, 25.0, 975.0, 975.0)
LONG_WINDOW = (495.0, 495.0, 505.0, 505.0)

# One seed per generator; the size is mixed in so that each size is its own draw.
_SEED_UNIFORM = 20_240_501
_SEED_LONG = 20_240_502
_SEED_CURVES = 20_240_503
_SEED_POLYGONS = 20_240_504
_SEED_GEOJSON = 20_240_505

#: Vertices per curve of the paper's curve workload (inclusive bounds).
CURVE_VERTICES = (2_000, 5_000)
#: The curve workload's windows, keyed by the share of the extent's area they cover.
#: Filled in below by `centred_window`.
CURVE_WINDOWS: dict[str, tuple[float, float, float, float]] = {}
#: The polygon and GeoJSON window: the paper's [250, 750]^2.
POLYGON_WINDOW = UNIFORM_WINDOW


def uniform_segments(n: int, extent=EXTENT, seed: int = _SEED_UNIFORM) -> np.ndarray:
    """Return (n, 4) float64 segments with both end points uniform in `extent`."""
    rng = np.random.default_rng([seed, n])
    xmin, ymin, xmax, ymax = extent
    out = rng.random((n, 4))
    out[:, 0::2] *= xmax - xmin
    out[:, 0::2] += xmin
    out[:, 1::2] *= ymax - ymin
    out[:, 1::2] += ymin
    return out


def long_segments(n: int, centre_box=(450.0, 450.0, 550.0, 550.0), length=(400.0, 1200.0),
                  seed: int = _SEED_LONG) -> np.ndarray:
    """Return (n, 4) float64 segments with midpoints in `centre_box`, random direction and length.

    Midpoints are uniform in `centre_box`, directions uniform on the circle, lengths
    uniform in `length`.
    """
    rng = np.random.default_rng([seed, n])
    cx0, cy0, cx1, cy1 = centre_box
    cx = rng.uniform(cx0, cx1, n)
    cy = rng.uniform(cy0, cy1, n)
    angle = rng.uniform(0.0, 2.0 * np.pi, n)
    half = 0.5 * rng.uniform(length[0], length[1], n)
    hx = half * np.cos(angle)
    hy = half * np.sin(angle)
    return np.stack([cx - hx, cy - hy, cx + hx, cy + hy], axis=1)


@dataclass(frozen=True)
class Workload:
    """A named, seeded set of segments and the window to clip them to.

    Attributes
    ----------
    name : str
        Unique, e.g. ``"uniform-1000000"``.
    family : str
        ``uniform``, ``mostly_outside``, ``mostly_inside`` or ``long_segments``.
    n : int
        Number of segments.
    window : tuple of 4 floats
        ``(xmin, ymin, xmax, ymax)``.
    description : str
        One line for the README and the JSON.
    make : callable
        ``make(n) -> (n, 4) float64``; called by `segments`.
    """

    name: str
    family: str
    n: int
    window: tuple[float, float, float, float]
    description: str
    make: Callable[[int], np.ndarray] = field(repr=False, compare=False)

    def segments(self) -> np.ndarray:
        """Return the workload's (n, 4) float64 C-contiguous segments (built on each call)."""
        return np.ascontiguousarray(self.make(self.n), dtype=np.float64)

    def describe(self) -> dict:
        """Return the workload's JSON description (without the data)."""
        return {"name": self.name, "family": self.family, "n": self.n,
                "window": list(self.window), "description": self.description,
                "input_nbytes": self.n * 4 * 8}


def table2(sizes) -> list[Workload]:
    """Return the paper's Table 2 workloads (uniform segments, window [250, 750]^2) at `sizes`."""
    return [Workload(f"uniform-{n}", "uniform", n, UNIFORM_WINDOW,
                     "end points uniform in [0,1000]^2, window [250,750]^2 (paper, Table 2)",
                     uniform_segments)
            for n in sizes]


def shaped(n: int) -> list[Workload]:
    """Return the mostly-outside, mostly-inside and long-segment workloads of `n` segments."""
    return [
        Workload(f"mostly_outside-{n}", "mostly_outside", n, OUTSIDE_WINDOW,
                 "end points uniform in [0,1000]^2, window [450,550]^2 (1% of the area)",
                 uniform_segments),
        Workload(f"mostly_inside-{n}", "mostly_inside", n, INSIDE_WINDOW,
                 "end points uniform in [0,1000]^2, window [25,975]^2 (90% of the area)",
                 uniform_segments),
        Workload(f"long_segments-{n}", "long_segments", n, LONG_WINDOW,
                 "midpoints uniform in [450,550]^2, random direction, length 400..1200; "
                 "window [495,505]^2 (side 10)",
                 long_segments),
    ]


def classify(segments: np.ndarray, window) -> dict:
    """Return the fractions of segments inside, rejected by outcodes, and ambiguous at level 0.

    Uses the same outcodes as the kernels (strict comparisons; the boundary is inside).
    ``ambiguous`` segments are neither accepted nor rejected by their end points' codes;
    they are the ones any method must work on.
    """
    n = segments.shape[0]
    if n == 0:
        return {"inside": 0.0, "rejected": 0.0, "ambiguous": 0.0}
    xmin, ymin, xmax, ymax = window
    codes = []
    for x, y in ((segments[:, 0], segments[:, 1]), (segments[:, 2], segments[:, 3])):
        code = ((x < xmin).astype(np.uint8) | ((x > xmax).astype(np.uint8) << 1)
                | ((y < ymin).astype(np.uint8) << 2) | ((y > ymax).astype(np.uint8) << 3))
        codes.append(code)
    c0, c1 = codes
    inside = np.count_nonzero((c0 | c1) == 0)
    rejected = np.count_nonzero(c0 & c1)
    return {"inside": float(inside / n), "rejected": float(rejected / n),
            "ambiguous": float((n - inside - rejected) / n)}


# --------------------------------------------------------------------------- geometry sets


def centred_window(fraction: float, extent=EXTENT) -> tuple[float, float, float, float]:
    """Return the square window centred in `extent` that covers `fraction` of its area.

    The extent must be square, e.g. ``centred_window(0.01) == (450.0, 450.0, 550.0, 550.0)``.
    """
    xmin, ymin, xmax, ymax = extent
    half = 0.5 * np.sqrt(fraction) * (xmax - xmin)
    cx, cy = 0.5 * (xmin + xmax), 0.5 * (ymin + ymax)
    return (float(cx - half), float(cy - half), float(cx + half), float(cy + half))


CURVE_WINDOWS.update({"25%": UNIFORM_WINDOW, "10%": centred_window(0.10),
                      "1%": centred_window(0.01)})


def _fold(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Reflect `values` into [lo, hi] (a triangle wave: continuous, a kink at each bounce)."""
    span = hi - lo
    u = np.mod(values - lo, 2.0 * span)
    return lo + np.where(u > span, 2.0 * span - u, u)


def smooth_polylines(n_lines: int, vertices=CURVE_VERTICES, extent=EXTENT,
                     seed: int = _SEED_CURVES) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(coords, offsets)`` of `n_lines` smooth polylines in `extent`.

    The layout is ``shapely.to_ragged_array``'s for LineStrings: ``coords`` float64
    (V, 2) and ``offsets`` int64 (n_lines + 1,), line k being
    ``coords[offsets[k]:offsets[k + 1]]``. Vertex counts are uniform in `vertices`
    (inclusive); see the module docstring for the shape of the lines.
    """
    rng = np.random.default_rng([seed, n_lines])
    counts = rng.integers(vertices[0], vertices[1] + 1, n_lines)
    offsets = np.zeros(n_lines + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    coords = np.empty((int(offsets[-1]), 2), dtype=np.float64)
    bounds = ((extent[0], extent[2]), (extent[1], extent[3]))
    for k, count in enumerate(counts):
        t = np.linspace(0.0, 1.0, int(count))
        for axis, (lo, hi) in enumerate(bounds):
            scale = (hi - lo) / 1000.0
            freq = rng.uniform(0.3, 2.5, 4)
            phase = rng.uniform(0.0, 2.0 * np.pi, 4)
            weight = rng.uniform(0.2, 1.0, 4)
            amplitude = weight / weight.sum() * rng.uniform(500.0, 900.0) * scale
            centre = rng.uniform(lo, hi)
            wave = amplitude[:, None] * np.sin(2.0 * np.pi * freq[:, None] * t + phase[:, None])
            coords[offsets[k]:offsets[k + 1], axis] = _fold(centre + wave.sum(axis=0), lo, hi)
    return coords, offsets


_SHELL = 40
_HOLE = 10


def star_polygons(n: int, radius=(5.0, 40.0), extent=EXTENT,
                  seed: int = _SEED_POLYGONS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ``(coords, ring_offsets, geom_offsets)`` of `n` valid polygons with one hole.

    The layout is ``shapely.to_ragged_array``'s for Polygons: polygon k has rings
    ``ring_offsets[geom_offsets[k]:geom_offsets[k + 1] + 1]``, each ring closed (first
    position repeated). Shell: 40 vertices, counter-clockwise; hole: 10 vertices,
    clockwise (RFC 7946 orientation); see the module docstring.
    """
    rng = np.random.default_rng([seed, n])
    xmin, ymin, xmax, ymax = extent
    cx = rng.uniform(xmin, xmax, n)
    cy = rng.uniform(ymin, ymax, n)
    r = rng.uniform(radius[0], radius[1], n)

    def ring(centre_x, centre_y, count, radii, direction):
        # Angles jittered by at most 0.4 of their spacing stay in order, so the ring is
        # star-shaped about its centre and simple.
        steps = np.arange(count) + rng.uniform(-0.4, 0.4, (n, count))
        angle = direction * 2.0 * np.pi * steps / count
        pts = np.empty((n, count + 1, 2))
        pts[:, :-1, 0] = centre_x[:, None] + radii * np.cos(angle)
        pts[:, :-1, 1] = centre_y[:, None] + radii * np.sin(angle)
        pts[:, -1] = pts[:, 0]
        return pts

    shell = ring(cx, cy, _SHELL, r[:, None] * rng.uniform(0.5, 1.0, (n, _SHELL)), 1.0)
    # The shell is at least 0.5 R * cos(0.9 pi / 40) > 0.49 R from the centre; the hole
    # reaches at most 0.1 R + 0.3 R from it, so it lies strictly inside.
    shift = 0.1 * r * np.sqrt(rng.random(n))
    turn = rng.uniform(0.0, 2.0 * np.pi, n)
    hole = ring(cx + shift * np.cos(turn), cy + shift * np.sin(turn), _HOLE,
                r[:, None] * rng.uniform(0.2, 0.3, (n, _HOLE)), -1.0)
    coords = np.concatenate([shell, hole], axis=1).reshape(-1, 2)
    sizes = np.tile([_SHELL + 1, _HOLE + 1], n)
    ring_offsets = np.zeros(2 * n + 1, dtype=np.int64)
    np.cumsum(sizes, out=ring_offsets[1:])
    geom_offsets = np.arange(0, 2 * n + 1, 2, dtype=np.int64)
    return coords, ring_offsets, geom_offsets


def explode_lines(coords: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Return the (m, 4) segments ``[x0, y0, x1, y1]`` of LineStrings in ragged layout.

    Consecutive vertices of one line give one segment; no segment joins two lines.
    """
    coords = np.asarray(coords, dtype=np.float64)
    keep = np.ones(max(coords.shape[0] - 1, 0), dtype=bool)
    inner_ends = np.asarray(offsets[1:-1], dtype=np.int64) - 1
    keep[inner_ends[(inner_ends >= 0) & (inner_ends < keep.size)]] = False
    return np.ascontiguousarray(np.concatenate([coords[:-1, :2][keep], coords[1:, :2][keep]],
                                               axis=1))


def geojson_collection(n_lines: int, n_polygons: int, seed: int = _SEED_GEOJSON) -> dict:
    """Return a GeoJSON FeatureCollection of lines and polygons with holes, with properties.

    `n_lines` curves from `smooth_polylines` (every fifth a MultiLineString of its two
    halves) and `n_polygons` polygons from `star_polygons` (every tenth feature a
    MultiPolygon of two of them), in [0, 1000]^2, each feature with an ``id`` and
    ``properties`` (name, kind, an integer, a float, a list of tags). About 37 bytes per
    vertex once serialized by orjson: ``geojson_collection(136, 14_500)`` is about 50 MB.
    """
    rng = np.random.default_rng([seed, n_lines, n_polygons])
    features = []
    line_coords, line_offsets = smooth_polylines(n_lines, seed=seed)
    for k in range(n_lines):
        pts = line_coords[line_offsets[k]:line_offsets[k + 1]]
        if k % 5 == 4:
            mid = pts.shape[0] // 2
            geometry = {"type": "MultiLineString",
                        "coordinates": [pts[:mid + 1].tolist(), pts[mid:].tolist()]}
        else:
            geometry = {"type": "LineString", "coordinates": pts.tolist()}
        features.append({"type": "Feature", "id": len(features), "geometry": geometry,
                         "properties": {"name": f"road {k}", "kind": "road",
                                        "lanes": int(rng.integers(1, 5)),
                                        "speed": float(np.round(rng.uniform(20, 130), 1)),
                                        "tags": ["curve", "seeded"]}})
    coords, ring_offsets, geom_offsets = star_polygons(n_polygons, seed=seed)

    def rings(p):
        return [coords[ring_offsets[j]:ring_offsets[j + 1]].tolist()
                for j in range(geom_offsets[p], geom_offsets[p + 1])]

    p = 0
    while p < n_polygons:
        if len(features) % 10 == 9 and p + 1 < n_polygons:
            geometry = {"type": "MultiPolygon", "coordinates": [rings(p), rings(p + 1)]}
            p += 2
        else:
            geometry = {"type": "Polygon", "coordinates": rings(p)}
            p += 1
        features.append({"type": "Feature", "id": len(features), "geometry": geometry,
                         "properties": {"name": f"parcel {p}", "kind": "parcel",
                                        "floors": int(rng.integers(1, 30)),
                                        "value": float(np.round(rng.uniform(1e4, 1e6), 2)),
                                        "tags": ["star", "with hole"]}})
    return {"type": "FeatureCollection", "features": features}
