"""``rnsca tiles``: GeoJSON, GeoJSON text sequences, GeoParquet and FlatGeobuf into a
PMTiles archive or a z/x/y.mvt directory, with the summary per zoom."""

import gzip
import json

import mapbox_vector_tile
import numpy as np
import orjson
import pytest
import shapely
import shapely.geometry
from typer.testing import CliRunner

from rnsca.cli import app
from rnsca.tiles import tile_features
from tests.missing import missing

runner = CliRunner()


@pytest.fixture(scope="module")
def features():
    rng = np.random.default_rng(11)
    lines = [shapely.LineString(np.cumsum(rng.normal(0, 1, (40, 2)), axis=0)
                                + rng.uniform(-20, 20, 2)) for _ in range(20)]
    polygons = [shapely.Point(rng.uniform(-20, 20, 2)).buffer(3) for _ in range(10)]
    return [{"type": "Feature", "id": i, "properties": {"name": f"f{i}", "rank": i % 4},
             "geometry": shapely.geometry.mapping(g)}
            for i, g in enumerate(lines + polygons)]


def _needed(name):
    """Return module `name`: skipped here without it, a failure under CI=true."""
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError as exc:
        missing(f"{name} is not installed ({exc}); pip install -e '.[dev]'")


def _write(path, features):
    suffix = path.suffix
    if suffix == ".geojson":
        path.write_bytes(orjson.dumps({"type": "FeatureCollection", "features": features}))
    elif suffix == ".ndjson":
        path.write_bytes(b"\n".join(b"\x1e" + orjson.dumps(f) for f in features))
    else:
        geopandas = _needed("geopandas")
        frame = geopandas.GeoDataFrame.from_features(features, crs="EPSG:4326")
        frame["id"] = [f["id"] for f in features]
        if suffix == ".parquet":
            frame.to_parquet(path)
        else:
            _needed("pyogrio")
            frame.to_file(path, driver="FlatGeobuf")


def _tiles_of(archive):
    from pmtiles.reader import MmapSource, Reader, all_tiles

    with open(archive, "rb") as f:
        return {zxy: gzip.decompress(data) for zxy, data in
                all_tiles(Reader(MmapSource(f)).get_bytes)}


@pytest.mark.parametrize("suffix", [".geojson", ".ndjson", ".parquet", ".fgb"])
def test_each_input_format_gives_the_library_s_tiles(tmp_path, features, suffix):
    source = tmp_path / f"roads{suffix}"
    _write(source, features)
    out = tmp_path / "out.pmtiles"
    result = runner.invoke(app, ["tiles", str(source), "-o", str(out), "--minzoom", "1",
                                 "--maxzoom", "4", "--no-progress", "--summary-json",
                                 str(tmp_path / "s.json")])
    assert result.exit_code == 0, result.output
    read = _tiles_of(out)
    geometries = [shapely.geometry.shape(f["geometry"]) for f in features]
    properties = [f["properties"] for f in features]
    with_ids = suffix in (".geojson", ".ndjson")
    expected = {(z.zoom, int(x), int(y)): d
                for z in tile_features(geometries, properties if with_ids else None,
                                       ids=[f["id"] for f in features] if with_ids else None,
                                       minzoom=1, maxzoom=4, layer="roads")
                for x, y, d in zip(z.x, z.y, z.data, strict=True)}
    assert set(read) == set(expected)
    for key, data in read.items():
        decoded = mapbox_vector_tile.decode(data)["roads"]["features"]
        assert len(decoded) == len(mapbox_vector_tile.decode(expected[key])["roads"][
            "features"])
        for feature in decoded:
            assert feature["properties"]["name"].startswith("f")
        if with_ids:
            assert data == expected[key]
    summary = json.loads((tmp_path / "s.json").read_text())
    assert [z["zoom"] for z in summary["zooms"]] == [1, 2, 3, 4]
    assert sum(z["tiles"] for z in summary["zooms"]) == len(read)
    assert summary["features_in"] == len(features)


def test_a_directory_of_z_x_y_mvt_and_the_summary(tmp_path, features):
    source = tmp_path / "a.geojson"
    _write(source, features)
    result = runner.invoke(app, ["tiles", str(source), "-o", str(tmp_path / "out"),
                                 "--maxzoom", "2", "--layer", "things", "--buffer", "16"])
    assert result.exit_code == 0, result.output
    assert "zoom" in result.output and "tiles" in result.output and "features" in result.output
    files = sorted((tmp_path / "out").rglob("*.mvt"))
    assert files and all(len(p.relative_to(tmp_path / "out").parts) == 3 for p in files)
    assert "things" in mapbox_vector_tile.decode(files[0].read_bytes())


@pytest.mark.parametrize("arguments, message", [
    (["--maxzoom", "30"], "maxzoom"), (["--mode", "fast"], "mode"),
])
def test_bad_options_exit_2(tmp_path, features, arguments, message):
    source = tmp_path / "a.geojson"
    _write(source, features[:2])
    result = runner.invoke(app, ["tiles", str(source), "-o", str(tmp_path / "o.pmtiles"),
                                 *arguments])
    assert result.exit_code == 2 and message in result.output


def test_unreadable_input_exits_1(tmp_path):
    source = tmp_path / "a.geojson"
    source.write_text("{not json")
    result = runner.invoke(app, ["tiles", str(source), "-o", str(tmp_path / "o.pmtiles")])
    assert result.exit_code == 1 and "not JSON" in result.output
    result = runner.invoke(app, ["tiles", str(tmp_path / "a.txt"), "-o", "o.pmtiles"])
    assert result.exit_code != 0


def test_collections_and_null_geometries(tmp_path):
    source = tmp_path / "gc.ndjson"
    source.write_text("\n".join([
        '{"type":"Feature","id":1,"properties":{"a":1},"geometry":{"type":'
        '"GeometryCollection","geometries":[{"type":"Point","coordinates":[1,1]},'
        '{"type":"LineString","coordinates":[[0,0],[5,5]]}]}}',
        '{"type":"Feature","properties":{"a":2},"geometry":null}',
        '{"type":"Polygon","coordinates":[[[0,0],[3,0],[3,3],[0,0]]]}']))
    out = tmp_path / "gc.pmtiles"
    result = runner.invoke(app, ["tiles", str(source), "-o", str(out), "--maxzoom", "0",
                                 "--no-progress"])
    assert result.exit_code == 0, result.output
    features = mapbox_vector_tile.decode(_tiles_of(out)[(0, 0, 0)])["gc"]["features"]
    # A collection's members are features of their own, with its id and properties.
    assert sorted((f["geometry"]["type"], f["properties"].get("a")) for f in features) == [
        ("LineString", 1), ("Point", 1), ("Polygon", None)]
