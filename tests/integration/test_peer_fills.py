"""Other projects' polygon cases (``tests/data/peer/*.jsonl``) clipped as SVG fills, clean.

Every record whose input has polygons (POLYGON, MULTIPOLYGON, or polygons in a
collection) becomes one path: each ring a subpath of lines, shells counter-clockwise and
holes clockwise (``shapely.orient_polygons``), so that both fill rules paint the polygon
(the rings of a valid polygon do not cross). It is clipped to the record's window with
``fill_output="clean"`` under both rules; then

- every subpath is a simple ring (`tests.ring_checks`), and no two lines of one run
  along a window edge over each other;
- the rings' polygonisation paints Shapely's ``intersection(polygon, box)`` within
  ``1e-9`` of its area (lines only: no flattening); for an invalid input polygon (a
  self-intersecting ring, a hole crossing its shell) rings cannot all be simple, and the
  region is compared with the one its rings paint by winding number, intersected with
  the box.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely

from rnsca import Fill, clip_paths, parse_paths
from tests.ring_checks import (
    flat_subpaths,
    polygonised,
    relative_difference,
    simple_ring_problems,
    winding_painted,
    window_edge_runs,
)

PEER = Path(__file__).resolve().parents[1] / "data" / "peer"
RULES = [Fill.NONZERO, Fill.EVENODD]


def _polygon_records() -> list:
    records = []
    for path in sorted(PEER.glob("*.jsonl")):
        for line in path.read_text().splitlines():
            if not line.strip():
                continue
            record = json.loads(line)
            geometry = shapely.force_2d(shapely.from_wkt(record["input_wkt"]))
            polygons = [p for p in shapely.get_parts(geometry)
                        if p.geom_type == "Polygon" and not p.is_empty]
            polygons += [q for p in shapely.get_parts(geometry)
                         if p.geom_type == "MultiPolygon" for q in shapely.get_parts(p)]
            if polygons:
                records.append(pytest.param(record, polygons, id=record["id"]))
    return records or [pytest.param(None, None, id="missing")]


def path_data(polygons) -> str:
    """Return one path of every ring of `polygons`, oriented (shells CCW, holes CW)."""
    subpaths = []
    for polygon in polygons:
        polygon = shapely.orient_polygons(polygon)
        for ring in [polygon.exterior, *polygon.interiors]:
            xy = np.asarray(ring.coords)[:-1]
            subpaths.append("M" + " L".join(f"{float(x)!r} {float(y)!r}" for x, y in xy) + " Z")
    return " ".join(subpaths)


@pytest.mark.parametrize("rule", RULES, ids=lambda r: r.value)
@pytest.mark.parametrize(("record", "polygons"), _polygon_records())
def test_peer_polygons_clip_to_simple_rings_painting_the_intersection(record, polygons, rule):
    if record is None:
        pytest.fail(f"no peer cases in {PEER}")
    window = tuple(float(v) for v in record["window"])
    d = path_data(polygons)
    source = parse_paths([d])
    clean = clip_paths(source, window, fill=rule).paths
    box = shapely.box(*window)
    # Valid polygons that do not overlap one another (a valid multipolygon's parts).
    valid = all(shapely.is_valid(p) for p in polygons) and (
        len(polygons) == 1
        or shapely.area(shapely.union_all(polygons)) == sum(p.area for p in polygons))
    got = polygonised(flat_subpaths(clean, 1), rule) if valid else \
        winding_painted(clean, rule, 1)
    if valid:
        assert simple_ring_problems(clean, 1) == []
        assert window_edge_runs(clean, window) == 0
        expected = shapely.intersection(shapely.union_all(polygons), box)
    else:
        expected = shapely.intersection(winding_painted(source, rule, 1), box)
    assert relative_difference(got, expected) <= 1e-9
