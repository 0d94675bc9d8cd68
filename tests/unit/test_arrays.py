"""rnsca.arrays.to_shapely: ragged arrays Shapely 2.2 cannot read (some crash it) read safely.

Each layout here is valid GeoArrow and accepted by `Ragged`; ``shapely.from_ragged_array``
kills the process on the polygon cases (a segfault in GEOS), so a regression ends the test
run instead of failing one test: `tests/e2e/test_degenerate_geoarrow.py` sends the same
through a server in a subprocess.
"""

import numpy as np
import pytest
import shapely

import rnsca
from rnsca.arrays import GeometryKind, Ragged, to_shapely

SQUARE = [[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]]
HOLE = [[1, 1], [1, 2], [2, 2], [2, 1], [1, 1]]


def _offsets(*levels):
    return tuple(np.array(level, dtype=np.int64) for level in levels)


def _wkt(geometries) -> list[str]:
    return [g.wkt for g in geometries]


def test_a_ringless_polygon_of_a_multipolygon_is_dropped():
    coords = np.array(SQUARE, dtype=float)
    got = to_shapely(GeometryKind.MULTIPOLYGON, coords, _offsets([0, 5], [0, 0, 1], [0, 2]))
    assert _wkt(got) == ["MULTIPOLYGON (((0 0, 4 0, 4 4, 0 4, 0 0)))"]


def test_multipolygons_of_only_ringless_polygons_are_empty():
    got = to_shapely(GeometryKind.MULTIPOLYGON, np.empty((0, 2)),
                     _offsets([0], [0, 0, 0], [0, 2, 2]))
    assert _wkt(got) == ["MULTIPOLYGON EMPTY", "MULTIPOLYGON EMPTY"]


def test_a_polygon_whose_exterior_is_empty_is_empty_with_its_holes_dropped():
    # Rings: an empty exterior, then a hole; then a second polygon that is kept.
    coords = np.array(HOLE + SQUARE, dtype=float)
    polygons = to_shapely(GeometryKind.POLYGON, coords, _offsets([0, 0, 5, 10], [0, 2, 3]))
    assert _wkt(polygons) == ["POLYGON EMPTY", "POLYGON ((0 0, 4 0, 4 4, 0 4, 0 0))"]
    multi = to_shapely(GeometryKind.MULTIPOLYGON, coords,
                       _offsets([0, 0, 5, 10], [0, 2, 3], [0, 2]))
    assert _wkt(multi) == ["MULTIPOLYGON (((0 0, 4 0, 4 4, 0 4, 0 0)))"]


def test_offsets_of_the_geometries_around_a_dropped_polygon_are_rebuilt():
    # Geometry 0: [ringless, square with a hole]; 1: [empty exterior + hole];
    # 2: [ringless]; 3: [square].
    coords = np.array(SQUARE + HOLE + HOLE + SQUARE, dtype=float)
    rings = [0, 5, 10, 10, 15, 20]
    polygons = [0, 0, 2, 4, 4, 5]
    got = to_shapely(GeometryKind.MULTIPOLYGON, coords, _offsets(rings, polygons,
                                                                 [0, 2, 3, 4, 5]))
    square = "((0 0, 4 0, 4 4, 0 4, 0 0))"
    assert _wkt(got) == [
        "MULTIPOLYGON (((0 0, 4 0, 4 4, 0 4, 0 0), (1 1, 1 2, 2 2, 2 1, 1 1)))",
        "MULTIPOLYGON EMPTY", "MULTIPOLYGON EMPTY", f"MULTIPOLYGON ({square})"]


def test_z_is_kept_through_the_rebuild():
    coords = np.array([[*xy, 7.0] for xy in SQUARE])
    [got] = to_shapely(GeometryKind.MULTIPOLYGON, coords, _offsets([0, 5], [0, 0, 1], [0, 2]))
    assert shapely.has_z(got) and set(shapely.get_coordinates(got, include_z=True)[:, 2]) == {7}


@pytest.mark.parametrize(("kind", "offsets", "empty"), [
    (GeometryKind.LINESTRING, ([0, 0],), "LINESTRING EMPTY"),
    (GeometryKind.MULTILINESTRING, ([0, 0], [0, 1]), "MULTILINESTRING EMPTY"),
    (GeometryKind.MULTIPOINT, ([0, 0, 0],), "MULTIPOINT EMPTY"),
    (GeometryKind.POLYGON, ([0], [0, 0]), "POLYGON EMPTY"),
])
def test_arrays_without_coordinates_are_empty_geometries(kind, offsets, empty):
    got = to_shapely(kind, np.empty((0, 2)), _offsets(*offsets))
    assert len(got) == len(offsets[-1]) - 1 and all(g.wkt == empty for g in got)


def test_parts_shapely_reads_are_passed_as_they_are():
    # Lines of no positions, multipoints of no points, polygons of no rings (single kind).
    coords = np.array(SQUARE, dtype=float)
    assert _wkt(to_shapely(GeometryKind.MULTILINESTRING, coords,
                           _offsets([0, 0, 5], [0, 2]))) == [
        "MULTILINESTRING (EMPTY, (0 0, 4 0, 4 4, 0 4, 0 0))"]
    assert _wkt(to_shapely(GeometryKind.MULTIPOINT, coords, _offsets([0, 0, 5])))[0] == \
        "MULTIPOINT EMPTY"
    assert _wkt(to_shapely(GeometryKind.POLYGON, coords, _offsets([0, 5], [0, 0, 1])))[0] == \
        "POLYGON EMPTY"


# --- the library's entry points --------------------------------------------------------

DEGENERATE = {
    "ringless polygon": (GeometryKind.MULTIPOLYGON, SQUARE, ([0, 5], [0, 0, 1], [0, 2])),
    "only ringless polygons": (GeometryKind.MULTIPOLYGON, [], ([0], [0, 0], [0, 1])),
    "empty exterior with a hole": (GeometryKind.POLYGON, SQUARE, ([0, 0, 5], [0, 2])),
    "empty exterior with a hole, multi": (GeometryKind.MULTIPOLYGON, SQUARE,
                                          ([0, 0, 5], [0, 2], [0, 1])),
    "no coordinates, lines": (GeometryKind.LINESTRING, [], ([0, 0],)),
    "no coordinates, multipoints": (GeometryKind.MULTIPOINT, [], ([0, 0, 0],)),
}


@pytest.mark.parametrize("name", DEGENERATE)
def test_degenerate_arrays_are_clipped_verified_and_read_back(name):
    kind, coords, offsets = DEGENERATE[name]
    coords = np.array(coords, dtype=float).reshape(-1, 2)
    offsets = _offsets(*offsets)
    window = (1, 1, 3, 3)
    ragged = Ragged.of(kind, coords, offsets)
    assert len(ragged.to_shapely()) == ragged.count
    result = rnsca.clip_ragged(kind, coords, offsets, window, keep_empty=True,
                               check_validity=kind.dimension == 2)
    expected = shapely.clip_by_rect(ragged.to_shapely(), *window)
    assert shapely.equals(result.to_shapely(), expected).all()
    assert rnsca.verify((kind.shapely_type, coords, offsets), result, window).passed
    assert rnsca.verify(ragged, result, window).passed


def test_a_polygon_whose_exterior_is_empty_clips_to_nothing_wherever_its_hole_is():
    # Window inside the hole, around it, and across it: the polygon has no area anywhere.
    coords = np.array(HOLE, dtype=float)
    for window in ((1.2, 1.2, 1.8, 1.8), (0, 0, 4, 4), (1.5, 0, 4, 4)):
        result = rnsca.clip_ragged(GeometryKind.POLYGON, coords, _offsets([0, 0, 5], [0, 2]),
                                   window)
        assert len(result) == 0 and result.coords.shape == (0, 2)


def test_a_call_on_chunks_in_threads_gives_one_call_s_values():
    from rnsca.arrays import in_threads
    from rnsca.tiles.mercator import _lonlat_rows_to_world, lonlat_to_world

    rng = np.random.default_rng(3)
    xy = np.column_stack([rng.uniform(-180, 180, 70_000), rng.uniform(-89, 89, 70_000)])
    whole = in_threads(_lonlat_rows_to_world, xy, min_rows=10**9)
    chunked = in_threads(_lonlat_rows_to_world, xy, min_rows=1)
    assert whole.tobytes() == chunked.tobytes() == lonlat_to_world(xy).tobytes()
    polygons = shapely.buffer(shapely.points(xy[:3000]), 1.0, quad_segs=2)
    assert np.array_equal(in_threads(shapely.is_valid, polygons, min_rows=1),
                          shapely.is_valid(polygons))
    assert in_threads(np.negative, np.zeros((0, 2)), min_rows=0).shape == (0, 2)
