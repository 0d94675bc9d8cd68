"""rnsca.tiles.split: a pyramid built in parts (subtrees below a split zoom, the zooms
above whole) and merged gives `tile_table`'s tiles, byte for byte, whatever the split."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
import shapely

from rnsca.errors import InvalidOptionError
from rnsca.tiles import FeatureTable, tile_table
from rnsca.tiles.split import MAX_SPLIT_ZOOM, build_part, build_top, merge, split


@pytest.fixture(scope="module")
def table():
    rng = np.random.default_rng(7)
    lines = [shapely.LineString(np.cumsum(rng.normal(0, 1.5, (50, 2)), axis=0)
                                + rng.uniform(-40, 40, 2)) for _ in range(60)]
    polygons = [shapely.Point(rng.uniform(-40, 40, 2)).buffer(rng.uniform(0.5, 8))
                .difference(shapely.Point(0, 0).buffer(0.2)) for _ in range(40)]
    points = [shapely.MultiPoint(rng.uniform(-40, 40, (3, 2))) for _ in range(20)]
    # A polygon covering a whole zoom-2 tile and more, and one across the antimeridian.
    wide = [shapely.box(-100, -60, 100, 60), shapely.LineString([(170, 5), (190, 6)])]
    geometries = lines + polygons + points + wide
    properties = [{"i": i, "kind": f"k{i % 5}"} for i in range(len(geometries))]
    return FeatureTable.of(geometries, properties, list(range(len(geometries))))


def _built(table, split_zoom, parts, **options):
    mode = options.get("mode", "exact")
    zoom, pieces = split(table, parts=parts, split_zoom=split_zoom, mode=mode,
                         maxzoom=options["maxzoom"])
    assert zoom == split_zoom
    return [build_top(table, split_zoom=split_zoom, **options)] + [
        build_part(table, part, **options) for part in pieces]


def _same(got, expected):
    assert [z.zoom for z in got] == [z.zoom for z in expected]
    for a, b in zip(got, expected, strict=True):
        assert a.x.tolist() == b.x.tolist() and a.y.tolist() == b.y.tolist(), a.zoom
        assert a.data == b.data, a.zoom
        assert a.features.tolist() == b.features.tolist()


@pytest.mark.parametrize(("mode", "split_zoom", "parts"), [
    ("exact", 0, 1), ("exact", 2, 5), ("exact", 3, 16), ("approx", 1, 3), ("approx", 5, 7)])
def test_parts_merged_equal_the_single_pass_pyramid(table, mode, split_zoom, parts):
    options = dict(minzoom=1, maxzoom=5, mode=mode)
    _same(list(merge(_built(table, split_zoom, parts, **options))),
          list(tile_table(table, **options)))


def test_a_split_below_minzoom_builds_no_top_and_tiles_are_compressed(table):
    options = dict(minzoom=4, maxzoom=5)
    built = _built(table, 2, 4, compression="gzip", **options)
    assert built[0] == []
    merged = list(merge(built))
    expected = list(tile_table(table, **options))
    assert [gzip.decompress(d) for z in merged for d in z.data] == [
        d for z in expected for d in z.data]


def test_parts_own_disjoint_runs_of_the_split_zoom_s_tiles(table):
    zoom, parts = split(table, parts=6, split_zoom=3)
    assert zoom == 3 and 1 < len(parts) <= 6
    owned = [(x, y) for p in parts for x, y in zip(p.x.tolist(), p.y.tolist(), strict=True)]
    assert len(owned) == len(set(owned))
    assert all(p.weight > 0 for p in parts)
    for part in parts:  # each part holds its tiles' geometry, and no other tile's
        held = {(x, y) for level in part.levels
                for x, y in zip(level.tile_x.tolist(), level.tile_y.tolist(), strict=True)}
        assert held == set(zip(part.x.tolist(), part.y.tolist(), strict=True))


def test_merge_refuses_a_tile_built_twice(table):
    _, (part,) = split(table, parts=1, split_zoom=1)
    built = build_part(table, part, maxzoom=2)
    with pytest.raises(ValueError, match="same tile"):
        list(merge([built, built]))


def test_the_split_zoom_is_the_first_with_enough_tiles(table):
    assert split(table, parts=1, maxzoom=8)[0] == 0
    zoom, parts = split(table, parts=8, maxzoom=8)
    assert zoom == 2 and 1 < len(parts) <= 8  # heavy tiles make fewer parts
    assert split(table, parts=10**9, maxzoom=3)[0] == 3
    with pytest.raises(InvalidOptionError, match="split_zoom"):
        split(table, parts=2, split_zoom=MAX_SPLIT_ZOOM + 1, maxzoom=24)
    with pytest.raises(InvalidOptionError, match="split_zoom"):
        split(table, parts=2, split_zoom=4, maxzoom=3)
    with pytest.raises(InvalidOptionError, match="parts"):
        split(table, parts=0)
