"""Other projects' rectangle-clipping cases (``tests/data/peer/*.jsonl``), as whole geometries.

Every record (points, lines, polygons with holes, empties of every type, 2D and Z) is
clipped with ``rnsca.clip(shapely_geometry, window)`` and compared, geometrically
(`tests.geometry_checks.assert_equal_geometry`: normalize, Hausdorff distance, length,
symmetric-difference area, within ``1e-9`` of the window's size), with three references:

- ``intersection``: the record's ``shapely_intersection_wkt``, against
  ``boundary="closed"``;
- ``clip_by_rect``: the record's ``shapely_clip_by_rect_wkt``, against
  ``boundary="interior"``;
- ``expected``: the record's ``expected_wkt``, against the boundary rule of its source:
  ``"interior"`` for GEOS (``RectangleIntersection`` and ``GEOSClipByRect`` drop what only
  runs along or touches the edge), ``"closed"`` for lineclip and geojson-vt (their bbox is
  closed).

Each output must also lie in the closed window (no tolerance), have only parts of the
input's dimension, and, for polygons, pass ``shapely.is_valid``; records with Z must keep
it (`tests.geometry_checks.assert_z_on_input`) and match the reference's Z where the XY
match.

By default the whole reference must equal our output. Where we deliberately differ, the
record is listed in `DIFFERENCES` with the reason, and the test asserts what we do
instead; it also asserts that the plain comparison really fails there, so the table
cannot go stale.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import shapely

import rnsca
from rnsca import Window
from tests.geometry_checks import (
    TOLERANCE,
    assert_dimension,
    assert_equal_geometry,
    assert_inside_window,
    assert_valid_polygons,
    assert_z_on_input,
    dimension_of_type,
    flat_parts,
    parts_of_dimension,
)

PEER = Path(__file__).resolve().parents[1] / "data" / "peer"
REFERENCES = ("expected", "intersection", "clip_by_rect")


@dataclass(frozen=True)
class Difference:
    """Records where we deliberately differ from one reference, why, and the check instead."""

    ids: tuple[str, ...]
    reference: str
    reason: str
    instead: str


def _geos(*numbers: int, api: bool = False) -> tuple[str, ...]:
    name = "geos-GEOSClipByRectTest-" if api else "geos-RectangleIntersectionTest-"
    return tuple(f"{name}{n}" for n in numbers)


#: The deliberate differences. ``instead`` names the check in `INSTEAD`.
DIFFERENCES = (
    Difference(
        _geos(53, 54, 55, 56, 57, 114, 115, 116, 117, 118) + _geos(10, 11, api=True),
        "intersection",
        "Polygon that only touches the window (from outside at a point or along an edge, "
        "or whose hole is exactly the window): shapely.intersection returns the shared "
        "POINT or LINESTRING; results keep the input's dimension, so we return nothing.",
        "same_dimension"),
    Difference(
        _geos(14, api=True),
        "intersection",
        "Degenerate (zero-area, self-overlapping) ring: shapely.intersection returns a "
        "LINESTRING, a lower-dimensional leftover; we return no area.",
        "degenerate_ring"),
    Difference(
        _geos(14, api=True),
        "clip_by_rect",
        "Degenerate ring: GEOS clip_by_rect raises IllegalArgumentException; we clip "
        "invalid polygons ring by ring and flag them in stats.invalid_polygons, never raise "
        "for them (the issue: 'clipped ring by ring and flagged in the stats').",
        "degenerate_ring"),
    Difference(
        _geos(14, api=True),
        "expected",
        "Degenerate ring: upstream expects GEOSClipByRect to fail; we clip ring by ring "
        "and flag it in stats.invalid_polygons.",
        "degenerate_ring"),
    Difference(
        ("geojson-vt-clips-polygons-geom1",),
        "intersection",
        "Invalid (self-intersecting) input: shapely.intersection raises a "
        "TopologyException. We clip ring by ring and flag it in stats.invalid_polygons, "
        "not silently repaired.",
        "ring_by_ring"),
    Difference(
        ("geojson-vt-clips-polygons-geom1",),
        "clip_by_rect",
        "Invalid (self-intersecting) input: clip_by_rect returns an invalid polygon with "
        "parts reaching the window's y-limits. Ring by ring, flagged, as above.",
        "ring_by_ring"),
    Difference(
        _geos(15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 27, 28, 29, 30, 31, 32, 33, 34, 35,
              36, 37, 38, 39, 40, 41, 42, 43, 44, 58, 59, 60, 61, 62, 63, 64, 65, 66, 67, 68,
              69, 70, 71, 72, 73, 75),
        "expected",
        "GEOS RectangleIntersection::clipBoundary: the expected result is the polygon's "
        "boundary clipped as linework (rings wholly inside as polygons), not an area. We "
        "clip the polygon as an area.",
        "boundary_linework"),
)

_LISTED = {(i, d.reference): d for d in DIFFERENCES for i in d.ids}


def _records() -> list:
    files = sorted(PEER.glob("*.jsonl"))
    assert files, f"no peer cases in {PEER} (tests/data/peer, with its README)"
    records = []
    for path in files:
        records += [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return records


RECORDS = _records()


def _boundary_of_source(record) -> str:
    return "interior" if record["id"].startswith("geos-") else "closed"


def _boundary(record, reference: str) -> str:
    return {"intersection": "closed", "clip_by_rect": "interior"}.get(
        reference, _boundary_of_source(record))


def _reference_wkt(record, reference: str):
    return {"expected": record["expected_wkt"],
            "intersection": record["shapely_intersection_wkt"],
            "clip_by_rect": record["shapely_clip_by_rect_wkt"]}[reference]


def _allowed(record) -> float:
    return TOLERANCE * Window.of(record["window"]).size


# --- the comparison ----------------------------------------------------------------------

def _assert_well_formed(ours, geometry, window, where, *, valid=True):
    assert_inside_window(ours, window, where)
    dimension = dimension_of_type(geometry)
    if dimension >= 0:
        assert_dimension(ours, dimension, where)
    else:  # a collection: each member keeps its own dimension
        assert ours.is_empty or dimension_of_type(ours) == -1, (where, ours.wkt)
    if valid and any(dimension_of_type(p) == 2 for p in flat_parts(ours)):
        assert_valid_polygons(ours, where)


def _assert_z(ours, geometry, reference, window, where):
    if not shapely.has_z(geometry):
        return
    assert_z_on_input(ours, geometry, window, where)
    ours_xyz = shapely.get_coordinates(ours, include_z=True)
    reference_xyz = shapely.get_coordinates(reference, include_z=True)
    for x, y, z in ours_xyz:
        same = (reference_xyz[:, 0] == x) & (reference_xyz[:, 1] == y)
        if same.any():
            assert np.abs(reference_xyz[same, 2] - z).min() <= 1e-9 * max(1.0, abs(z)), (
                f"{where}: Z {z} at {(x, y)}, reference has {reference_xyz[same, 2]}")


def _assert_equals_whole_reference(ours, reference, record, where):
    """Check ours against all of the reference, every dimension of it."""
    geometry = shapely.from_wkt(record["input_wkt"])
    dimension = dimension_of_type(geometry)
    if dimension < 0:  # collections: compare per dimension
        for d in (0, 1, 2):
            assert_equal_geometry(parts_of_dimension(ours, d), parts_of_dimension(reference, d),
                                  _allowed(record), where)
        return
    extra = sorted({dimension_of_type(p) for p in flat_parts(reference)} - {dimension})
    assert not extra, (f"{where}: the reference has parts of dimension {extra}, ours has only "
                       f"{dimension}: {reference.wkt}")
    assert_equal_geometry(parts_of_dimension(ours, dimension),
                          parts_of_dimension(reference, dimension), _allowed(record), where)


def _differs_from_whole_reference(ours, record, reference_wkt, where) -> bool:
    if reference_wkt is None or reference_wkt.startswith("ERROR"):
        return True
    try:
        _assert_equals_whole_reference(ours, shapely.from_wkt(reference_wkt), record, where)
    except AssertionError:
        return True
    return False


# --- what we do instead, where we differ -------------------------------------------------

def _linework(geometry, box):
    """Return `geometry`'s boundary inside the box, without what runs along the box's edge."""
    rings = shapely.MultiLineString(
        [shapely.LineString(p.coords) for part in flat_parts(geometry)
         for p in (shapely.get_rings(part) if dimension_of_type(part) == 2 else [part])
         if dimension_of_type(p) >= 1])
    return shapely.difference(shapely.intersection(rings, box), shapely.boundary(box))


def _same_linework(a, b, record, where):
    assert_equal_geometry(parts_of_dimension(a, 1), parts_of_dimension(b, 1), _allowed(record),
                          where)


def _invalid_polygons(record, boundary) -> int:
    geometry = shapely.from_wkt(record["input_wkt"])
    result = rnsca.clip_ragged(*shapely.to_ragged_array([geometry]), record["window"],
                               boundary=boundary)
    return result.stats.invalid_polygons


def _instead_same_dimension(ours, record, reference_wkt, boundary, where):
    geometry = shapely.from_wkt(record["input_wkt"])
    dimension = dimension_of_type(geometry)
    reference = shapely.from_wkt(reference_wkt)
    assert {dimension_of_type(p) for p in flat_parts(reference)} - {dimension}, (
        f"{where}: listed for lower-dimensional leftovers, but the reference has none")
    assert_equal_geometry(parts_of_dimension(ours, dimension),
                          parts_of_dimension(reference, dimension), _allowed(record), where)


def _instead_boundary_linework(ours, record, reference_wkt, boundary, where):
    box = shapely.box(*record["window"])
    expected = shapely.from_wkt(reference_wkt)
    _same_linework(_linework(ours, box), _linework(expected, box), record, where)
    # And the area is Shapely's (clip_by_rect is checked in its own test; this is the link).
    _assert_equals_whole_reference(ours, shapely.from_wkt(record["shapely_clip_by_rect_wkt"]),
                                   record, where)


def _instead_ring_by_ring(ours, record, reference_wkt, boundary, where):
    box = shapely.box(*record["window"])
    geometry = shapely.from_wkt(record["input_wkt"])
    assert not geometry.is_valid
    assert _invalid_polygons(record, boundary) == 1, f"{where}: not flagged as invalid"
    _same_linework(_linework(ours, box), _linework(geometry, box), record, where)
    if reference_wkt is not None and not reference_wkt.startswith("ERROR"):
        _same_linework(_linework(ours, box), _linework(shapely.from_wkt(reference_wkt), box),
                       record, where)


def _instead_degenerate_ring(ours, record, reference_wkt, boundary, where):
    assert shapely.area(ours) == 0.0, f"{where}: area from a zero-area ring: {ours.wkt}"
    assert _invalid_polygons(record, boundary) == 1, f"{where}: not flagged as invalid"


INSTEAD = {
    "same_dimension": _instead_same_dimension,
    "boundary_linework": _instead_boundary_linework,
    "ring_by_ring": _instead_ring_by_ring,
    "degenerate_ring": _instead_degenerate_ring,
}


# --- the tests -----------------------------------------------------------------------------

CASES = [pytest.param(record, reference, id=f"{record['id']}-{reference}")
         for record in RECORDS for reference in REFERENCES]


@pytest.mark.parametrize(("record", "reference"), CASES)
def test_peer_case_equals_reference_or_documented_difference(record, reference):
    geometry = shapely.from_wkt(record["input_wkt"])
    window = Window.of(record["window"])
    boundary = _boundary(record, reference)
    where = f"{record['id']} ({reference}, boundary={boundary})"
    ours = rnsca.clip(geometry, window, boundary=boundary)
    assert isinstance(ours, shapely.Geometry), ours
    reference_wkt = _reference_wkt(record, reference)
    difference = _LISTED.get((record["id"], reference))
    _assert_well_formed(ours, geometry, window, where,
                        valid=geometry.is_valid or geometry.is_empty)
    if difference is None:
        assert reference_wkt is not None and not reference_wkt.startswith("ERROR"), (
            f"{where}: reference is {reference_wkt}: list it in DIFFERENCES")
        reference_geometry = shapely.from_wkt(reference_wkt)
        _assert_equals_whole_reference(ours, reference_geometry, record, where)
        _assert_z(ours, geometry, reference_geometry, window, where)
        return
    assert _differs_from_whole_reference(ours, record, reference_wkt, where), (
        f"{where}: listed in DIFFERENCES ({difference.instead}) but now equals the "
        f"reference: remove it from the table")
    INSTEAD[difference.instead](ours, record, reference_wkt, boundary, where)


def test_every_listed_difference_names_a_record_and_a_check():
    ids = {record["id"] for record in RECORDS}
    for difference in DIFFERENCES:
        assert difference.reference in REFERENCES, difference
        assert difference.instead in INSTEAD, difference
        missing = set(difference.ids) - ids
        assert not missing, f"{missing} are not peer records"


def test_all_peer_records_are_read():
    counts = {}
    for record in RECORDS:
        counts[record["source"]] = counts.get(record["source"], 0) + 1
    assert sum(counts.values()) == 200, counts
