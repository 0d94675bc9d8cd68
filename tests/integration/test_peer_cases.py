"""Other projects' rectangle-clipping cases (``tests/data/peer/*.jsonl``), as segments.

Which records are used, and against what:

- **Line records** (input LINESTRING, MULTILINESTRING or LINEARRING, empty ones
  included, Z dropped): the input is split into its segments, each segment is clipped,
  and the union of the pieces is compared with the line parts of the record's
  ``shapely_intersection_wkt``. That is ``shapely.intersection`` with the box, which
  treats the window as closed like rnsca does (lines along an edge are kept, a touching
  point is no piece). The records' ``expected_wkt`` is not the reference: GEOS
  ``clip_by_rect`` drops lines along the edge, and lineclip and geojson-vt split parts
  differently; the README's "Known semantic differences" lists where they disagree.
- **Polygon records**, and the (empty) GEOMETRYCOLLECTION records: their boundary rings
  are clipped as linework, segment by segment, and compared with
  ``shapely.intersection(boundary, box)`` computed here, since the recorded intersection
  is an area. The invalid (self-intersecting) geojson-vt ring and the degenerate ring of
  GEOSClipByRectTest-14 are fine as linework.
- **Point records** (kind "point": POINT and MULTIPOINT input, empty ones included) are
  left out: they have no segments. Every record, points and polygon areas included, is
  clipped as a whole geometry in ``tests/integration/test_peer_geometry.py``.

That makes 188 of the 200 records: 45 line, 141 polygon, 2 empty collections.

The comparison follows ``tests/data/peer/README.md``: both empty, or Hausdorff distance
(with ``densify=0.01``) within 1e-9 and total length equal within ``1e-9 * max(1, length)``,
except that the distance bound is rnsca's own promise, ``1e-9 * max(1, window size)``:
GEOS-RectangleIntersectionTest-208 has coordinates of 2e7, whose ulp (3.7e-9) is already
more than 1e-9.
Points of contact in Shapely's result (a line touching the edge) are not compared:
segments touching the window at one point yield no piece, by rnsca's rules. Pieces of
zero length (from repeated vertices) are left out of the union: they add no linework.
Every method runs in exact mode; RNSCA and midpoint also in approx mode, where the
pieces must lie on Shapely's lines and cover them to within two leaves.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely

from rnsca import Method, Mode, clip_segments
from rnsca.verify import approx_leaf_bound
from tests.checks import assert_inside_window, lengths

# A copy of the workplace's shared/peer-cases (with its README: sources and licences), kept
# in the repository so a clean checkout on any machine has it.
PEER_CASES = Path(__file__).resolve().parents[1] / "data" / "peer"
TOLERANCE = 1e-9


def _records() -> list:
    files = sorted(PEER_CASES.glob("*.jsonl"))
    if not files:
        return ["missing"]
    records = []
    for path in files:
        for line in path.read_text().splitlines():
            if line.strip():
                record = json.loads(line)
                geometry = shapely.force_2d(shapely.from_wkt(record["input_wkt"]))
                if record["kind"] != "point" and (_has_linework(geometry)
                                                  or geometry.is_empty):
                    records.append(pytest.param(record, id=record["id"]))
    return records


def _has_linework(geometry) -> bool:
    return any(shapely.get_type_id(part) in _LINE_OR_AREA
               for part in shapely.get_parts(geometry))


_LINE_OR_AREA = {shapely.GeometryType.LINESTRING, shapely.GeometryType.LINEARRING,
                 shapely.GeometryType.POLYGON}


def _lines(geometry) -> list:
    """Return the lines of `geometry`: line parts as they are, polygons by their rings."""
    lines = []
    for part in shapely.get_parts(shapely.force_2d(geometry)):
        kind = shapely.get_type_id(part)
        if kind == shapely.GeometryType.POLYGON:
            lines.extend(shapely.get_rings(part))
        elif kind in (shapely.GeometryType.LINESTRING, shapely.GeometryType.LINEARRING):
            lines.append(part)
        elif kind == shapely.GeometryType.GEOMETRYCOLLECTION:
            lines.extend(_lines(part))
    return [line for line in lines if not line.is_empty]


def _segments(geometry) -> np.ndarray:
    rows = [np.hstack([c[:-1], c[1:]]) for c in map(shapely.get_coordinates, _lines(geometry))]
    return np.concatenate(rows) if rows else np.empty((0, 4))


def _expected_lines(record, geometry, window):
    """Return Shapely's linework for the record (see the module docstring)."""
    if record["kind"] == "line":
        result = record["shapely_intersection_wkt"]
        assert not result.startswith("ERROR"), result
        reference = shapely.from_wkt(result)
    else:
        reference = shapely.intersection(shapely.MultiLineString(_lines(geometry)),
                                         shapely.box(*window))
    return shapely.MultiLineString([line for line in _lines(reference)
                                    if shapely.length(line) > 0])


def _clip(record, method, mode, backend):
    geometry = shapely.from_wkt(record["input_wkt"])
    window = tuple(record["window"])
    segments = _segments(geometry)
    result = clip_segments(segments, window, method=method, mode=mode, backend=backend)
    assert_inside_window(result, window)
    pieces = result.segments[lengths(result.segments) > 0]
    ours = shapely.MultiLineString(list(pieces.reshape(-1, 2, 2)))
    return segments, result, ours, _expected_lines(record, geometry, window)


def _allowed(record) -> float:
    xmin, ymin, xmax, ymax = record["window"]
    return TOLERANCE * max(1.0, xmax - xmin, ymax - ymin)


def _fail_if_missing(record):
    if record == "missing":
        pytest.fail(f"no peer cases found: expected *.jsonl files in {PEER_CASES} "
                    "(tests/data/peer, copied from the workplace's shared/peer-cases)")


@pytest.mark.parametrize("record", _records())
def test_clipped_segments_equal_shapely_linework(record, method, backend):
    _fail_if_missing(record)
    _, _, ours, expected = _clip(record, method, Mode.EXACT, backend)
    if ours.is_empty or expected.is_empty:
        assert ours.is_empty and expected.is_empty, (ours.wkt, expected.wkt)
        return
    distance = shapely.hausdorff_distance(shapely.normalize(ours), shapely.normalize(expected),
                                          densify=0.01)
    assert distance <= _allowed(record), (distance, ours.wkt, expected.wkt)
    ours_length = shapely.length(shapely.union_all(ours))
    expected_length = shapely.length(shapely.union_all(expected))
    assert abs(ours_length - expected_length) <= TOLERANCE * max(1.0, expected_length), (
        ours_length, expected_length)


@pytest.mark.parametrize("method", [Method.RNSCA, Method.MIDPOINT], ids=lambda m: m.value)
@pytest.mark.parametrize("record", _records())
def test_approx_pieces_lie_on_shapely_linework_within_two_leaves(record, method, backend):
    _fail_if_missing(record)
    segments, result, ours, expected = _clip(record, method, Mode.APPROX, backend)
    if expected.is_empty:
        assert ours.is_empty, ours.wkt
        return
    bound = float(approx_leaf_bound(lengths(segments), result).max(initial=0.0))
    if ours.is_empty:
        assert all(shapely.length(line) <= 2 * bound + _allowed(record)
                   for line in shapely.get_parts(expected))
        return
    # On Shapely's lines: 33 points along every piece are within tolerance of them.
    pieces = result.segments
    steps = np.linspace(0.0, 1.0, 33)[None, :, None]
    along = pieces[:, None, :2] + steps * (pieces[:, None, 2:] - pieces[:, None, :2])
    points = shapely.points(along.reshape(-1, 2))
    assert float(shapely.distance(points, expected).max()) <= _allowed(record)
    # Covering them: nothing of Shapely's is farther than two leaves from a piece.
    distance = shapely.hausdorff_distance(ours, expected, densify=0.01)
    assert distance <= 2 * bound + _allowed(record), (distance, bound)
