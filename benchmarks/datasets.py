"""Seeded segment workloads: the paper's Table 2 sets and three shaped variants.

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
]

EXTENT = (0.0, 0.0, 1000.0, 1000.0)
#: Segment counts of the paper's Table 2.
PAPER_SIZES = (100, 500, 1_000, 5_000, 10_000)
#: Added here: the NumPy backend's largest size, and the throughput sizes.
LARGE_SIZES = (100_000, 1_000_000, 10_000_000)

UNIFORM_WINDOW = (250.0, 250.0, 750.0, 750.0)
OUTSIDE_WINDOW = (450.0, 450.0, 550.0, 550.0)
INSIDE_WINDOW = (25.0, 25.0, 975.0, 975.0)
LONG_WINDOW = (495.0, 495.0, 505.0, 505.0)

# One seed per generator; the size is mixed in so that each size is its own draw.
_SEED_UNIFORM = 20_240_501
_SEED_LONG = 20_240_502


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
