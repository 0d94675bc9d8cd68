"""Numerical oracles for clipped Bézier paths, independent of the kernels.

Curves are evaluated in Bernstein form with NumPy; distances to a curve are found by
dense sampling refined by ternary search on the parameter; lengths by fine polylines.
"""

from __future__ import annotations

import numpy as np

from rnsca import PathArrays


def _lerp(a, b, t):
    # Exact at both ends and where a == b (a curve along an edge stays on it).
    return np.where(t < 0.5, a + t * (b - a), b - (1.0 - t) * (b - a))


def evaluate(controls: np.ndarray, degree: int, t: np.ndarray) -> np.ndarray:
    """Return the points at parameters `t` of one segment (controls (4, 2)), de Casteljau."""
    t = np.asarray(t, dtype=np.float64)[:, None]
    level = [np.broadcast_to(controls[i], (t.shape[0], 2)) for i in range(degree + 1)]
    while len(level) > 1:
        level = [_lerp(level[i], level[i + 1], t) for i in range(len(level) - 1)]
    return np.array(level[0])


def segments_of(paths: PathArrays, close: bool = False):
    """Yield (controls, degree) of every segment, with closing lines if asked."""
    for s in range(paths.closed.shape[0]):
        a, b = paths.subpath_offsets[s], paths.subpath_offsets[s + 1]
        for i in range(a, b):
            yield paths.controls[i], int(paths.degree[i])
        if b > a and (close or paths.closed[s]):
            end = paths.controls[b - 1, 3]
            if (end != paths.start[s]).any():
                yield np.array([end, paths.start[s], paths.start[s], paths.start[s]]), 1


def sample(paths: PathArrays, per_segment: int = 17, close: bool = False) -> np.ndarray:
    """Return points of every segment at `per_segment` equal parameter steps."""
    t = np.linspace(0.0, 1.0, per_segment)
    chunks = [evaluate(c, d, t) for c, d in segments_of(paths, close)]
    return np.concatenate(chunks) if chunks else np.zeros((0, 2))


def length(paths: PathArrays, per_segment: int = 4001, close: bool = False) -> float:
    """Return the total arc length (fine polylines)."""
    t = np.linspace(0.0, 1.0, per_segment)
    total = 0.0
    for c, d in segments_of(paths, close):
        p = evaluate(c, d, t)
        total += float(np.hypot(*np.diff(p, axis=0).T).sum())
    return total


def chord_inside_length(points: np.ndarray, window) -> float:
    """Return the length of the polyline `points` inside the closed window.

    Each chord is clipped on its own (Liang–Barsky in NumPy), so parts that double
    back over each other count every time, as a stroke draws them (a Shapely overlay
    would merge them).
    """
    xmin, ymin, xmax, ymax = window
    a, b = points[:-1], points[1:]
    d = b - a
    t0 = np.zeros(a.shape[0])
    t1 = np.ones(a.shape[0])
    keep = np.ones(a.shape[0], dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for p, q in ((-d[:, 0], a[:, 0] - xmin), (d[:, 0], xmax - a[:, 0]),
                     (-d[:, 1], a[:, 1] - ymin), (d[:, 1], ymax - a[:, 1])):
            parallel = p == 0
            keep &= ~(parallel & (q < 0))
            r = q / p
            t0 = np.where(~parallel & (p < 0), np.maximum(t0, r), t0)
            t1 = np.where(~parallel & (p > 0), np.minimum(t1, r), t1)
    keep &= t1 >= t0
    return float((np.hypot(d[:, 0], d[:, 1]) * np.where(keep, t1 - t0, 0.0)).sum())


def inside_length(paths: PathArrays, window, per_segment: int = 40001,
                  close: bool = False) -> float:
    """Return the arc length of the paths inside the closed window (fine polylines)."""
    t = np.linspace(0.0, 1.0, per_segment)
    return sum(chord_inside_length(evaluate(c, d, t), window)
               for c, d in segments_of(paths, close))


def distance_to_paths(points: np.ndarray, paths: PathArrays, close: bool = False) -> np.ndarray:
    """Return each point's distance to the nearest point of the paths' curves.

    Per segment, every local minimum of the distance to 2049 samples is refined by
    ternary search on the parameter (all at once): a curve passing near a point twice
    has two candidates, and the nearer sample need not be on the nearer branch.
    """
    best = np.full(points.shape[0], np.inf)
    grid = np.linspace(0.0, 1.0, 2049)
    for c, d in segments_of(paths, close):
        samples = evaluate(c, d, grid)
        dist = ((points[:, None, :] - samples[None]) ** 2).sum(axis=2)
        padded = np.pad(dist, ((0, 0), (1, 1)), constant_values=np.inf)
        minima = (dist <= padded[:, :-2]) & (dist <= padded[:, 2:])
        owner, k = np.nonzero(minima)
        lo = grid[np.maximum(k - 1, 0)]
        hi = grid[np.minimum(k + 1, grid.shape[0] - 1)]
        target = points[owner]
        for _ in range(100):  # ternary search: unimodal around a local minimum
            m1 = lo + (hi - lo) / 3
            m2 = hi - (hi - lo) / 3
            d1 = ((evaluate(c, d, m1) - target) ** 2).sum(axis=1)
            d2 = ((evaluate(c, d, m2) - target) ** 2).sum(axis=1)
            closer = d1 < d2
            hi = np.where(closer, m2, hi)
            lo = np.where(closer, lo, m1)
        found = np.hypot(*(evaluate(c, d, lo) - target).T)
        np.minimum.at(best, owner, found)
    return best


def outside_by(points: np.ndarray, window) -> np.ndarray:
    """Return how far each point lies outside the closed window (0 inside)."""
    xmin, ymin, xmax, ymax = window
    dx = np.maximum(np.maximum(xmin - points[:, 0], points[:, 0] - xmax), 0.0)
    dy = np.maximum(np.maximum(ymin - points[:, 1], points[:, 1] - ymax), 0.0)
    return np.hypot(dx, dy)


def signed_area(paths: PathArrays, per_segment: int = 2001) -> float:
    """Return the signed area enclosed by the closed subpaths (sum of winding x area)."""
    total = 0.0
    t = np.linspace(0.0, 1.0, per_segment)
    for s in range(paths.closed.shape[0]):
        a, b = paths.subpath_offsets[s], paths.subpath_offsets[s + 1]
        if b == a:
            continue
        pts = np.concatenate([evaluate(paths.controls[i], int(paths.degree[i]), t)
                              for i in range(a, b)] + [paths.start[s][None]])
        x, y = pts[:, 0], pts[:, 1]
        total += 0.5 * float(np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]))
    return total
