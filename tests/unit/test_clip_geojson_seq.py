"""rnsca.clip_records and rnsca.clip_geojson_seq: records clipped a chunk at a time."""

import orjson
import pytest
import shapely

import rnsca
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    LimitExceededError,
    ParseError,
)
from rnsca.io.geojson_seq import Framing, record_bytes, split_records

WINDOW = (0, 0, 10, 10)
ZIGZAG = {"type": "LineString",
          "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5], [15, 5]]}
SQUARE = {"type": "Polygon", "coordinates": [[[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]]}
AWAY = {"type": "Point", "coordinates": [50, 50]}


def feature(i, geometry, **members):
    return {"type": "Feature", "id": i, "properties": {"n": i}, "geometry": geometry,
            **members}


def test_each_record_keeps_its_kind_and_members():
    records = [ZIGZAG, feature(1, SQUARE, title="kept"),
               {"type": "FeatureCollection", "name": "fc",
                "features": [feature(2, AWAY), feature(3, ZIGZAG)]}]
    result = rnsca.clip_records(records, WINDOW)
    line, square, collection = result.records
    assert line["type"] == "MultiLineString"
    assert line["coordinates"] == [[[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]],
                                   [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]
    assert square["id"] == 1 and square["title"] == "kept" and square["properties"] == {"n": 1}
    assert shapely.equals(shapely.geometry.shape(square["geometry"]),
                          shapely.box(0, 0, 5, 5))
    assert collection["name"] == "fc" and [f["id"] for f in collection["features"]] == [3]
    assert result.source.tolist() == [0, 1, 2]


def test_records_left_empty_are_dropped_unless_kept():
    records = [AWAY, feature(1, AWAY), feature(2, None), SQUARE,
               {"type": "FeatureCollection", "features": [feature(3, AWAY)]}]
    dropped = rnsca.clip_records(records, WINDOW, first=10)
    assert dropped.source.tolist() == [13]
    kept = rnsca.clip_records(records, WINDOW, first=10, keep_empty=True)
    assert kept.source.tolist() == [10, 11, 12, 13, 14]
    assert kept.records[0] == {"type": "Point", "coordinates": []}
    assert kept.records[2]["geometry"] is None
    assert kept.records[4]["features"][0]["geometry"]["coordinates"] == []


def test_same_answer_as_one_feature_collection_and_as_shapely():
    features = [feature(i, {"type": "LineString",
                            "coordinates": [[-5 + i, -3], [4, 6 + i], [16, 2 * i - 3]]})
                for i in range(12)]
    whole, _ = rnsca.clip_geojson({"type": "FeatureCollection", "features": features},
                                  WINDOW)
    result = rnsca.clip_records([orjson.dumps(f) for f in features], WINDOW)
    assert result.records == whole["features"]
    box = shapely.box(*WINDOW)
    for clipped, i in zip(result.records, result.source, strict=True):
        expected = shapely.intersection(shapely.geometry.shape(features[i]["geometry"]), box)
        assert shapely.hausdorff_distance(shapely.geometry.shape(clipped["geometry"]),
                                          expected) < 1e-9


def test_the_stats_add_up_over_the_records():
    result = rnsca.clip_records([ZIGZAG, feature(0, SQUARE), AWAY], WINDOW)
    assert result.stats.geometries_in == 3 and result.stats.geometries_out == 2


def test_no_record_still_checks_the_window_and_options():
    assert rnsca.clip_records([], WINDOW).records == []
    with pytest.raises(InvalidWindowError):
        rnsca.clip_records([], (0, 0, -1, 1))
    with pytest.raises(InvalidOptionError):
        rnsca.clip_records([], WINDOW, method="nope")


@pytest.mark.parametrize("record, path, words", [
    (b'{"type": "Feature", "geometry": null,', None, "not valid JSON"),
    (b'[1, 2]', "", "got a JSON list"),
    (b'{"type": "Topology"}', "", "got type 'Topology'"),
    (b'{"coordinates": [1, 2]}', "", 'no "type" member'),
    (orjson.dumps(feature(7, {"type": "LineString", "coordinates": [[0, 0], [1, True]]})),
     "geometry.coordinates[1][1]", "expected a number"),
    (orjson.dumps({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 1]]]}),
     "coordinates[0]", "not closed"),
    (orjson.dumps({"type": "FeatureCollection", "features": [feature(0, ZIGZAG), 5]}),
     "features[1]", "expected a Feature"),
    (orjson.dumps({"type": "Feature", "properties": {}}), "<top level>", 'no "geometry"'),
])
def test_a_bad_record_is_named_with_the_path_inside_it(record, path, words):
    records = [orjson.dumps(feature(0, ZIGZAG)), orjson.dumps(AWAY), record,
               orjson.dumps(feature(3, SQUARE))]
    with pytest.raises((ParseError, InvalidGeometryError)) as caught:
        rnsca.clip_records(records, WINDOW, first=40)
    error = caught.value
    assert error.record == 42
    assert str(error).startswith("record 42")
    assert words in str(error)
    if path is not None:
        assert f"at {path}:" in str(error) or error.path == path
        assert error.path == ("" if path == "<top level>" else path)


def test_the_first_bad_record_is_named_when_a_later_one_is_not_json():
    bad_coordinates = orjson.dumps({"type": "Point", "coordinates": [1, None]})
    with pytest.raises(InvalidGeometryError) as caught:
        rnsca.clip_records([orjson.dumps(AWAY), bad_coordinates, b"{oops"], WINDOW)
    assert caught.value.record == 1


def test_the_vertex_limit_counts_the_whole_chunk():
    with pytest.raises(LimitExceededError):
        rnsca.clip_records([ZIGZAG, ZIGZAG], WINDOW, max_vertices=11)
    assert len(rnsca.clip_records([ZIGZAG, ZIGZAG], WINDOW, max_vertices=12).records) == 2


@pytest.mark.parametrize("chunk_records", [1, 2, 3, 1000])
def test_how_records_are_chunked_changes_nothing(chunk_records):
    records = [feature(i, ZIGZAG if i % 3 else AWAY) for i in range(10)]
    text = b"".join(record_bytes(r, Framing.RS) for r in records)
    whole, _ = rnsca.clip_geojson({"type": "FeatureCollection", "features": records}, WINDOW)
    clipped = rnsca.clip_geojson_seq(split_records([text]), WINDOW,
                                     chunk_records=chunk_records)
    assert list(clipped) == whole["features"]
    assert clipped.records_in == 10 and clipped.records_out == 6
    assert clipped.chunks == -(-10 // chunk_records)
    assert clipped.stats.geometries_in == 10


def test_chunks_are_cut_by_bytes_of_text():
    texts = [orjson.dumps(feature(i, ZIGZAG)) for i in range(6)]
    clipped = rnsca.clip_geojson_seq(texts, WINDOW, chunk_bytes=2 * len(texts[0]))
    assert len(list(clipped)) == 6 and clipped.chunks == 3


@pytest.mark.parametrize("chunk_records", [2, 3, 100])
def test_an_error_comes_after_every_record_before_it(chunk_records):
    texts = [orjson.dumps(feature(i, ZIGZAG)) for i in range(5)] + [b"{"] + [
        orjson.dumps(feature(6, ZIGZAG))]
    clipped = rnsca.clip_geojson_seq(texts, WINDOW, chunk_records=chunk_records)
    assert [next(clipped)["id"] for _ in range(5)] == [0, 1, 2, 3, 4]
    with pytest.raises(ParseError, match="record 5"):
        next(clipped)


def test_an_empty_sequence_gives_nothing_and_bad_chunk_sizes_are_refused():
    clipped = rnsca.clip_geojson_seq([], WINDOW)
    assert list(clipped) == [] and clipped.stats.geometries_in == 0
    with pytest.raises(InvalidOptionError):
        rnsca.clip_geojson_seq([], WINDOW, chunk_records=0)
