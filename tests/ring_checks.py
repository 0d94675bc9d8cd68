"""Oracles for clean fills: simple rings, and the region their polygonisation paints.

Independent of the kernels: curves are evaluated with NumPy (`tests.curve_checks`),
rings checked and polygonised with Shapely. A ring is flattened at a fixed number of
equal parameter steps per segment (the same segment gives the same points wherever it
appears, so two outputs built from the same pieces flatten alike), then:

- `simple_ring_problems`: every subpath, flattened and closed, must be a simple
  ``LinearRing`` (no self-intersection, no self-touching, no edge run twice) with at
  least three distinct vertices;
- `polygonised`: the region the rings paint under a fill rule, built from the rings as
  polygons: evenodd, the symmetric difference of the rings' polygons (correct for any
  simple rings); nonzero, the faces of the noded rings whose winding number is not 0
  (`rnsca.verify.paths.filled_region`).
"""

from __future__ import annotations

from functools import reduce

import numpy as np
import shapely

from rnsca import Fill, PathArrays
from rnsca.verify.paths import filled_region
from tests.curve_checks import evaluate

__all__ = ["flat_subpaths", "painted", "polygonised", "relative_difference",
           "simple_ring_problems", "window_edge_runs", "winding_painted"]


def flat_subpaths(paths: PathArrays, steps: int = 64) -> list[np.ndarray]:
    """Return every subpath closed and flattened: `steps` chords per curve, lines exact."""
    rings = []
    t = np.linspace(0.0, 1.0, steps + 1)[1:]
    for s in range(paths.closed.shape[0]):
        a, b = paths.subpath_offsets[s], paths.subpath_offsets[s + 1]
        if a == b:
            continue
        chunks = [paths.start[s][None]]
        for i in range(a, b):
            d = int(paths.degree[i])
            chunks.append(paths.controls[i, 3][None] if d == 1
                          else evaluate(paths.controls[i], d, t))
        ring = np.concatenate(chunks)
        if (ring[-1] != ring[0]).any():
            ring = np.concatenate([ring, ring[:1]])
        keep = np.ones(ring.shape[0], dtype=bool)  # no repeated consecutive point
        keep[1:] = (ring[1:] != ring[:-1]).any(axis=1)
        rings.append(ring[keep])
    return rings


def simple_ring_problems(paths: PathArrays, steps: int = 64) -> list[str]:
    """Return what is wrong with each subpath as a ring (empty: all simple rings)."""
    problems = []
    for j, ring in enumerate(flat_subpaths(paths, steps)):
        if ring.shape[0] < 4:
            problems.append(f"subpath {j}: fewer than 3 distinct vertices")
            continue
        linear = shapely.LinearRing(ring)
        if not linear.is_simple:
            reason = shapely.is_valid_reason(shapely.Polygon(ring))
            problems.append(f"subpath {j}: not simple ({reason})")
        elif shapely.Polygon(ring).area == 0.0:
            problems.append(f"subpath {j}: no area")
    return problems


def polygonised(rings: list[np.ndarray], rule: Fill | str):
    """Return the region the closed `rings` paint under `rule`, built from them as polygons."""
    rule = Fill(rule)
    if not rings:
        return shapely.MultiPolygon()
    if rule is Fill.EVENODD:
        return reduce(shapely.symmetric_difference, [shapely.Polygon(r) for r in rings])
    return filled_region(rings, rule)


def painted(paths: PathArrays, rule: Fill | str, steps: int = 64):
    """Return the region the clean rings of `paths` paint: `polygonised` `flat_subpaths`."""
    return polygonised(flat_subpaths(paths, steps), rule)


def winding_painted(paths: PathArrays, rule: Fill | str, steps: int = 64):
    """Return the region any closed subpaths paint (the raw fill output's too).

    Winding numbers of the faces of the noded outlines: needs no ring to be simple.
    """
    rings = flat_subpaths(paths, steps)
    return filled_region(rings, Fill(rule)) if rings else shapely.MultiPolygon()


def relative_difference(a, b) -> float:
    """Return the area of the symmetric difference over the larger area (0 if both empty)."""
    scale = max(float(shapely.area(a)), float(shapely.area(b)))
    if scale == 0.0:
        return 0.0
    return float(shapely.area(shapely.symmetric_difference(a, b))) / scale


def window_edge_runs(paths: PathArrays, window) -> int:
    """Return how many pairs of a subpath's lines on one window edge overlap (0: none).

    Lines lying on one edge line of the window, within one subpath, that share more than
    a point: what the raw fill output has where it runs along an edge more than once.
    """
    xmin, ymin, xmax, ymax = window
    overlaps = 0
    for s in range(paths.closed.shape[0]):
        a, b = paths.subpath_offsets[s], paths.subpath_offsets[s + 1]
        runs: dict[tuple[int, float], list[tuple[float, float]]] = {}
        for i in range(a, b):
            if paths.degree[i] != 1:
                continue
            (x0, y0), (x1, y1) = paths.controls[i, 0], paths.controls[i, 3]
            for axis, value in ((0, xmin), (0, xmax), (1, ymin), (1, ymax)):
                if (x0, y0)[axis] == value == (x1, y1)[axis]:
                    lo, hi = sorted(((x0, y0)[1 - axis], (x1, y1)[1 - axis]))
                    runs.setdefault((axis, value), []).append((lo, hi))
        for spans in runs.values():
            spans.sort()
            for k in range(1, len(spans)):
                if spans[k][0] < max(hi for _, hi in spans[:k]):
                    overlaps += 1
    return overlaps
