"""rnsca.dask.tiles and ``rnsca tiles --scheduler/--workers`` on real LocalClusters of
worker processes: the archive equals the single-process one, tile for tile (decoded with
mapbox-vector-tile) and byte for byte."""

from __future__ import annotations

import gzip
import subprocess
import sys

import numpy as np
import orjson
import pytest
import shapely
import shapely.geometry

from tests.dask_data import local_client, require_dask
from tests.missing import missing

pytestmark = pytest.mark.slow

MAXZOOM = 7


@pytest.fixture(scope="module")
def client():
    require_dask()
    with local_client(2) as client:
        yield client


@pytest.fixture(scope="module")
def features():
    """Lines, polygons with holes and points over a few degrees, with properties and ids."""
    rng = np.random.default_rng(20)
    lines = [shapely.LineString(np.cumsum(rng.normal(0, 0.4, (80, 2)), axis=0)
                                + rng.uniform(-8, 8, 2)) for _ in range(120)]
    polygons = [shapely.Point(rng.uniform(-8, 8, 2)).buffer(rng.uniform(0.2, 2.5))
                .difference(shapely.Point(rng.uniform(-8, 8, 2)).buffer(0.5))
                for _ in range(60)]
    points = [shapely.Point(rng.uniform(-8, 8, 2)) for _ in range(40)]
    geometries = lines + polygons + points
    return [{"type": "Feature", "id": i, "properties": {"name": f"f{i}", "rank": i % 4},
             "geometry": shapely.geometry.mapping(g)} for i, g in enumerate(geometries)]


@pytest.fixture(scope="module")
def table(features):
    from rnsca.tiles import FeatureTable

    return FeatureTable.of([shapely.geometry.shape(f["geometry"]) for f in features],
                           [f["properties"] for f in features], [f["id"] for f in features])


def _tiles(archive):
    """Return {(z, x, y): decoded tile} and the header and metadata of a PMTiles archive."""
    import mapbox_vector_tile
    from pmtiles.reader import MmapSource, Reader, all_tiles

    with open(archive, "rb") as f:
        reader = Reader(MmapSource(f))
        tiles = {zxy: mapbox_vector_tile.decode(gzip.decompress(data))
                 for zxy, data in all_tiles(reader.get_bytes)}
        return tiles, reader.header(), reader.metadata()


def _single_process(table, path, **options):
    from rnsca.tiles import tile_table, write_pmtiles

    layer = options.pop("layer", "features")
    write_pmtiles(path, tile_table(table, layer=layer, **options), layer=layer)


@pytest.mark.parametrize(("split_zoom", "parts"), [(None, None), (3, 5)])
def test_parallel_tiles_equal_the_single_process_tiles(client, table, tmp_path, split_zoom,
                                                       parts):
    import rnsca.dask

    _single_process(table, tmp_path / "one.pmtiles", minzoom=1, maxzoom=MAXZOOM)
    done = []
    summary = rnsca.dask.tiles(table, tmp_path / "many.pmtiles", client=client, minzoom=1,
                               maxzoom=MAXZOOM, split_zoom=split_zoom, parts=parts,
                               on_part=lambda k, n: done.append((k, n)))
    expected, header, metadata = _tiles(tmp_path / "one.pmtiles")
    got, got_header, got_metadata = _tiles(tmp_path / "many.pmtiles")
    assert got.keys() == expected.keys() and len(got) == summary.tiles > 100
    assert all(got[key] == expected[key] for key in expected)
    assert (got_header, got_metadata) == (header, metadata)
    assert (tmp_path / "many.pmtiles").read_bytes() == (tmp_path / "one.pmtiles").read_bytes()
    assert done[-1][0] == done[-1][1] > 2 and [k for k, _ in done] == list(
        range(1, len(done) + 1))


def test_a_directory_of_tiles_and_approx_mode_equal_the_single_process_ones(client, table,
                                                                            tmp_path):
    import rnsca.dask
    from rnsca.tiles import tile_table, write_directory

    write_directory(tmp_path / "one", tile_table(table, maxzoom=5, mode="approx"))
    rnsca.dask.tiles(table, tmp_path / "many", client=client, maxzoom=5, mode="approx",
                     split_zoom=2)
    one = {p.relative_to(tmp_path / "one"): p.read_bytes()
           for p in (tmp_path / "one").rglob("*.mvt")}
    many = {p.relative_to(tmp_path / "many"): p.read_bytes()
            for p in (tmp_path / "many").rglob("*.mvt")}
    assert len(one) > 20 and one.keys() == many.keys()
    assert all(one[k] == many[k] for k in one)


def test_bad_options_fail_before_any_task(client, table, tmp_path):
    import rnsca.dask
    from rnsca.errors import InvalidOptionError

    with pytest.raises(InvalidOptionError, match="split_zoom"):
        rnsca.dask.tiles(table, tmp_path / "a.pmtiles", client=client, maxzoom=3,
                         split_zoom=4)
    with pytest.raises(InvalidOptionError, match="zooms"):
        rnsca.dask.tiles(table, tmp_path / "a.pmtiles", client=client, minzoom=5, maxzoom=3)
    assert not (tmp_path / "a.pmtiles").exists()


def _cli(*arguments, timeout=300):
    return subprocess.run([sys.executable, "-m", "rnsca.cli", "tiles", *map(str, arguments)],
                          capture_output=True, text=True, timeout=timeout)


def test_cli_on_a_scheduler_equals_the_cli_in_one_process(client, features, tmp_path):
    source = tmp_path / "roads.geojson"
    source.write_bytes(orjson.dumps({"type": "FeatureCollection", "features": features}))
    one = _cli(source, "-o", tmp_path / "one.pmtiles", "--maxzoom", MAXZOOM, "--no-progress")
    assert one.returncode == 0, one.stderr
    many = _cli(source, "-o", tmp_path / "many.pmtiles", "--maxzoom", MAXZOOM,
                "--no-progress", "--scheduler", client.scheduler.address,
                "--summary-json", tmp_path / "s.json")
    assert many.returncode == 0, many.stderr
    assert "dashboard: http" in many.stderr
    expected, _, _ = _tiles(tmp_path / "one.pmtiles")
    got, _, _ = _tiles(tmp_path / "many.pmtiles")
    assert got == expected and "roads" in next(iter(got.values()))
    summary = orjson.loads((tmp_path / "s.json").read_bytes())
    assert sum(z["tiles"] for z in summary["zooms"]) == len(got)
    assert summary["features_in"] == len(features)


def test_cli_on_its_own_local_cluster_of_two_workers(features, tmp_path):
    require_dask()
    source = tmp_path / "roads.ndjson"
    source.write_bytes(b"\n".join(orjson.dumps(f) for f in features))
    one = _cli(source, "-o", tmp_path / "one.pmtiles", "--maxzoom", 5, "--no-progress")
    many = _cli(source, "-o", tmp_path / "many.pmtiles", "--maxzoom", 5, "--no-progress",
                "--workers", 2, "--parts", 3)
    assert one.returncode == 0 and many.returncode == 0, many.stderr
    assert "dashboard: http" in many.stderr
    assert (tmp_path / "many.pmtiles").read_bytes() == (tmp_path / "one.pmtiles").read_bytes()


def test_cli_refuses_dask_options_without_a_cluster_and_bad_workers(tmp_path):
    try:
        import pmtiles  # noqa: F401
    except ImportError as exc:
        missing(f"the tiles extra is not installed: {exc}")
    source = tmp_path / "a.geojson"
    source.write_text('{"type": "Point", "coordinates": [1, 2]}')
    result = _cli(source, "-o", tmp_path / "a.pmtiles", "--split-zoom", "2", timeout=120)
    assert result.returncode == 2 and "--scheduler or --workers" in result.stderr
    result = _cli(source, "-o", tmp_path / "a.pmtiles", "--workers", "0", timeout=120)
    assert result.returncode == 2 and "--workers must be at least 1" in result.stderr
