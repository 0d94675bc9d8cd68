"""Rounded rings cleaned before the validity check (`rnsca.tiles.encode.clean_polygons`).

Independent oracles: the winding number of each ring at points off the integer lattice
(the region a ring encloses, with its multiplicity) and the exact surveyor's area, both
computed here in Python on the input; Shapely for validity. Rings are drawn on a small
lattice so that repeated positions, collinear runs, spikes and collapsed rings are
common, as rounding makes them at low zooms.
"""

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rnsca.arrays import GeometryKind, Ragged
from rnsca.kernels.tiles import polygons_at_risk
from rnsca.tiles.encode import clean_polygons

# Sample points off every line through two lattice points of the 0..6 grid: x halfway,
# y at an offset no multiple of 1 / (2 q) for q <= 12.
_SAMPLES = np.array([(i + 0.5, j + 0.3183) for i in range(-1, 7) for j in range(-1, 7)])

_position = st.tuples(st.integers(0, 6), st.integers(0, 6))
_ring = st.lists(_position, min_size=3, max_size=12)


def _winding(ring: list, points: np.ndarray) -> np.ndarray:
    """Return the winding number of the closed ring about each point (none on it)."""
    out = np.zeros(len(points), dtype=int)
    for (x0, y0), (x1, y1) in zip(ring, ring[1:] + ring[:1], strict=True):
        for k, (px, py) in enumerate(points):
            left = (x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)
            if y0 <= py < y1 and left > 0:
                out[k] += 1
            elif y1 <= py < y0 and left < 0:
                out[k] -= 1
    return out


def _area2(ring: list) -> int:
    return sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1)
               in zip(ring, ring[1:] + ring[:1], strict=True))


def _multipolygons(polygons: list) -> tuple[np.ndarray, tuple]:
    """Return int64 positions and MULTIPOLYGON offsets of one geometry per polygon."""
    coords, ring_offsets, polygon_rings = [], [0], [0]
    for rings in polygons:
        for ring in rings:
            coords += ring + ring[:1]
            ring_offsets.append(len(coords))
        polygon_rings.append(len(ring_offsets) - 1)
    offsets = (np.array(ring_offsets), np.array(polygon_rings),
               np.arange(len(polygons) + 1))
    return np.array(coords, dtype=np.int64).reshape(-1, 2), offsets


def _rings_of(q: np.ndarray, offsets: tuple) -> list:
    return [[tuple(p) for p in q[a:b - 1].tolist()]
            for a, b in zip(offsets[0][:-1], offsets[0][1:], strict=True)]


@settings(max_examples=300, deadline=None)
@given(st.lists(_ring, min_size=1, max_size=6))
def test_a_cleaned_ring_encloses_what_the_ring_enclosed(rings):
    q, offsets = _multipolygons([[ring] for ring in rings])
    out, (ring_offsets, polygon_rings, geometry_polygons) = clean_polygons(q, offsets)
    assert geometry_polygons.shape[0] == len(rings) + 1  # the same geometries
    kept = np.diff(geometry_polygons)
    cleaned = iter(_rings_of(out, (ring_offsets,)))
    for ring, k in zip(rings, kept, strict=True):
        if k == 0:  # dropped: it enclosed nothing
            assert not _winding(ring, _SAMPLES).any() and _area2(ring) == 0
            continue
        clean = next(cleaned)
        np.testing.assert_array_equal(_winding(clean, _SAMPLES), _winding(ring, _SAMPLES))
        assert _area2(clean) == _area2(ring)
        # At least three positions, none repeated, no three in a row on one line.
        n = len(clean)
        assert n >= 3
        for i in range(n):
            (ax, ay), (bx, by), (cx, cy) = clean[i - 2], clean[i - 1], clean[i]
            assert (bx, by) != (cx, cy)
            assert (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) != 0
    # Closed rings.
    for a, b in zip(ring_offsets[:-1], ring_offsets[1:], strict=True):
        assert (out[a] == out[b - 1]).all()


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(_ring, st.lists(_ring, max_size=2)), min_size=1, max_size=4))
def test_holes_go_with_a_collapsed_shell_and_kept_polygons_are_proved_or_checked(polygons):
    q, offsets = _multipolygons([[shell, *holes] for shell, holes in polygons])
    out, cleaned = clean_polygons(q, offsets)
    ring_offsets, polygon_rings, geometry_polygons = cleaned
    for g, (shell, holes) in enumerate(polygons):
        n_polygons = geometry_polygons[g + 1] - geometry_polygons[g]
        if n_polygons == 0:  # a shell dropped enclosed nothing; its holes went with it
            assert not _winding(shell, _SAMPLES).any()
            continue
        p = geometry_polygons[g]
        written = polygon_rings[p + 1] - polygon_rings[p] - 1
        assert sum(_winding(h, _SAMPLES).any() for h in holes) <= written <= len(holes)
    # What the kernel proves valid, GEOS finds valid, as the encoder writes it: rings of
    # no area left out (a shell with its holes), each wound as the specification asks.
    at_risk = np.empty(len(polygons), dtype=bool)
    polygons_at_risk(out, *cleaned, at_risk)
    for g in np.flatnonzero(~at_risk):
        parts = []
        for p in range(geometry_polygons[g], geometry_polygons[g + 1]):
            rings = _rings_of(out, (ring_offsets[polygon_rings[p]:polygon_rings[p + 1] + 1],))
            if _area2(rings[0]) == 0:
                continue
            parts.append(shapely.Polygon(rings[0], [h for h in rings[1:] if _area2(h)]))
        geometry = shapely.MultiPolygon(parts)
        assert geometry.is_valid, geometry.wkt


@settings(max_examples=100, deadline=None)
@given(st.lists(_ring, min_size=1, max_size=5), st.lists(_ring, min_size=1, max_size=5),
       st.data())
def test_concat_take_is_concat_then_take(a, b, data):
    def ragged(rings):
        q, offsets = _multipolygons([[r] for r in rings])
        return Ragged(GeometryKind.MULTIPOLYGON, q.astype(np.float64), offsets)
    ra, rb = ragged(a), ragged(b)
    index = data.draw(st.lists(st.integers(0, len(a) + len(b) - 1), max_size=12))
    got, expected = ra.concat_take(rb, index), ra.concat(rb).take(index)
    np.testing.assert_array_equal(got.coords, expected.coords)
    for x, y in zip(got.offsets, expected.offsets, strict=True):
        np.testing.assert_array_equal(x, y)
