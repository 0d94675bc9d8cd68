"""The compiled GeoJSON file reader (`rnsca.io.geojson_file`) against the exact reader.

`read_features` reads a GeoJSON file with the compiled reader where it takes the
document and with orjson and ``from_geojson`` (the *exact* reader, forced here by
making the compiled one decline) otherwise. Every test compares the two: the same
arrays bit for bit, the same properties and ids, or the same exception and message.
"""

from __future__ import annotations

from pathlib import Path
from unittest import mock

import numpy as np
import orjson
import pytest
import shapely

from rnsca.errors import RnscaError
from rnsca.io.geojson_file import padded_bytes, read_file_features
from rnsca.kernels.geojson_scan import NOT_TAKEN, PADDING, SCANNED, scan
from rnsca.tiles import sources

SQUARE = "[[0,0],[10,0],[10,10],[0,10],[0,0]]"
HOLE = "[[2,2],[2,4],[4,4],[4,2],[2,2]]"


def exact(path: Path):
    """Return what `read_features` gives with the compiled reader declining every file."""
    with mock.patch.object(sources, "read_file_features", return_value=None):
        return sources.read_features(path)


def outcome(read, path: Path):
    """Return ("ok", features) or ("error", class, message) of ``read(path)``."""
    try:
        return "ok", read(path)
    except (RnscaError, ValueError) as exc:
        return "error", type(exc), str(exc)


def assert_same_features(fast, slow) -> None:
    """Assert two `Features` are equal: arrays bit for bit, properties and ids by value and type."""
    assert orjson.dumps(fast.properties) == orjson.dumps(slow.properties)
    assert orjson.dumps(fast.ids) == orjson.dumps(slow.ids)
    assert fast.crs == slow.crs
    if fast.geometries is not None:  # GeometryCollections: both read by Shapely
        assert shapely.to_wkb(fast.geometries).tolist() == \
            shapely.to_wkb(slow.geometries).tolist()
        return
    assert slow.geometries is None
    for mine, theirs in zip(fast.ragged, slow.ragged, strict=True):
        assert mine.kind == theirs.kind and mine.partial_z == theirs.partial_z
        assert mine.coords.shape == theirs.coords.shape
        assert mine.coords.dtype == theirs.coords.dtype == np.float64
        assert np.array_equal(mine.coords.view(np.uint64), theirs.coords.view(np.uint64))
        assert len(mine.offsets) == len(theirs.offsets)
        for a, b in zip(mine.offsets, theirs.offsets, strict=True):
            assert a.dtype == b.dtype and np.array_equal(a, b)
    for a, b in zip(fast.sources, slow.sources, strict=True):
        assert np.array_equal(a, b)


def check(tmp_path: Path, text: str | bytes, suffix: str = ".geojson", *,
          taken: bool | str | None = None) -> bool:
    """Assert `read_features` and the exact reader agree on `text`; return whether it is valid.

    `taken`: whether the compiled reader must take the document (True), must leave it
    to the exact reader (False), must take it if and only if the exact reader accepts
    it (``"if valid"``), or either (None).
    """
    data = text.encode() if isinstance(text, str) else text
    path = tmp_path / f"input{suffix}"
    path.write_bytes(data)
    read = read_file_features(*padded_bytes(path), sequence=suffix != ".geojson")
    mine, theirs = outcome(sources.read_features, path), outcome(exact, path)
    if taken == "if valid":
        taken = theirs[0] == "ok"
    if taken is not None:
        assert (read is not None) == taken
    assert mine[0] == theirs[0], (mine, theirs)
    if mine[0] == "ok":
        assert_same_features(mine[1], theirs[1])
    else:
        assert mine == theirs
    return theirs[0] == "ok"


def collection(*features: str) -> str:
    return '{"type":"FeatureCollection","features":[' + ",".join(features) + "]}"


def feature(geometry: str, members: str = '"properties":{}') -> str:
    return '{"type":"Feature",' + members + ',"geometry":' + geometry + "}"


def geometry(kind: str, coordinates: str) -> str:
    return '{"type":"' + kind + '","coordinates":' + coordinates + "}"


# --------------------------------------------------------------------------- layouts

def test_a_polygon_with_a_hole_is_read_as_the_exact_reader_reads_it(tmp_path):
    check(tmp_path, collection(feature(geometry("Polygon", f"[{SQUARE},{HOLE}]"))),
          taken=True)


def test_every_geometry_type_and_null_in_one_collection(tmp_path):
    features = [
        geometry("Point", "[1.5,2.5]"), geometry("Point", "[]"),
        geometry("MultiPoint", "[[1,2],[3,4]]"), geometry("MultiPoint", "[]"),
        geometry("LineString", "[[0,0],[1,1],[2,0]]"), geometry("LineString", "[]"),
        geometry("MultiLineString", "[[[0,0],[1,1]],[],[[5,5],[6,6]]]"),
        geometry("Polygon", f"[{SQUARE}]"), geometry("Polygon", "[]"),
        geometry("MultiPolygon", f"[[{SQUARE},{HOLE}],[],[{SQUARE}]]"), "null",
    ]
    check(tmp_path, collection(*(feature(g) for g in features)), taken=True)


def test_a_single_feature_and_a_bare_geometry(tmp_path):
    check(tmp_path, feature(geometry("LineString", "[[0,0],[1,1]]"), '"id":"a"'),
          taken=True)
    check(tmp_path, geometry("MultiPoint", "[[0,0],[1,1]]"), taken=True)


def test_3d_and_mixed_documents_keep_z_and_nan(tmp_path):
    check(tmp_path, geometry("LineString", "[[0,0,1],[1,1,2]]"), taken=True)
    mixed = collection(feature(geometry("Point", "[1,2]")),
                       feature(geometry("LineString", "[[0,0,1],[1,1],[2,2,3,4]]")))
    check(tmp_path, mixed, taken=True)


def test_only_points_share_the_scanned_values_and_stay_correct(tmp_path):
    check(tmp_path, collection(*(feature(geometry("Point", f"[{k},{-k}]"))
                                 for k in range(50))), taken=True)


def test_ids_and_properties_of_every_type(tmp_path):
    members = ['"id":1', '"id":1.0', '"id":"x"', '"id":null', '"id":true', '"id":[1,{}]',
               '"properties":null', '"properties":{"a":{"b":[1,"\\u00e9\\n"]}}', '"x":1']
    check(tmp_path, collection(*(feature(geometry("Point", "[0,0]"), m) for m in members)),
          taken=True)


def test_a_coordinates_key_or_value_in_properties_is_not_geometry(tmp_path):
    members = '"properties":{"coordinates":[[9,9],[8,8]],"name":"coordinates",' \
              '"geometry":{"type":"Point","coordinates":[5,5]}}'
    check(tmp_path, collection(feature(geometry("Point", "[1,2]"), members)), taken=True)


def test_foreign_members_named_like_geometry_members(tmp_path):
    text = ('{"type":"FeatureCollection","coordinates":[1,2],"geometry":{"coordinates":[3,4]},'
            '"features":[' + feature(geometry("Point", "[0,1]")) + "]}")
    check(tmp_path, text)


def test_whitespace_and_indentation(tmp_path):
    document = orjson.loads(collection(feature(geometry("Polygon", f"[{SQUARE}]"))))
    check(tmp_path, orjson.dumps(document, option=orjson.OPT_INDENT_2), taken=True)
    check(tmp_path, " \r\n\t" + collection(feature(geometry("Point", "[ 1 , 2 ]"))) + "\n",
          taken=True)


# --------------------------------------------------------------------------- numbers

@pytest.mark.parametrize("text", [
    "0", "-0", "0.0", "-0.0", "-0e0", "1e5", "1E-7", "1e+2", "-1.5E+300", "2.5e-320",
    "4.9406564584124654e-324", "2.4703282292062328e-324", "2.4703282292062327e-324",
    "1.7976931348623157e308", "9007199254740993", "18446744073709551615",
    "18446744073709551616", "123456789012345678901234567890", "-9223372036854775809",
    "0.1000000000000000055511151231257827021181583404541015625",
    "1.00000000000000011102230246251565404236316680908203125", "1e-400",
    "0.000000000000000000000000000000000000000001", "5.535675565512096",
    "50.269072261469056", "1e0000000000000000000000000000003",
])
def test_numbers_read_as_the_exact_reader_reads_them(tmp_path, text):
    check(tmp_path, geometry("Point", f"[{text},{text},{text}]"), taken=True)


def test_negative_zero_integer_is_positive_zero_as_json_parsers_read_it(tmp_path):
    path = tmp_path / "zero.geojson"
    path.write_text(geometry("MultiPoint", "[[-0,-0.0],[-0e0,0]]"))
    coords = read_file_features(*padded_bytes(path)).points[1]
    assert np.signbit(coords).tolist() == [[False, True], [True, False]]


@pytest.mark.parametrize("text", ["01", "1.", ".5", "NaN", "Infinity", "-Infinity", "+1",
                                  "1e", "1e+", "-", "--1", "0x10", "1e999", "-1e400",
                                  "1.5.3", "1,", "true", '"1"', "null", "[]", "{}"])
def test_bad_numbers_give_the_exact_readers_error(tmp_path, text):
    check(tmp_path, collection(feature(geometry("Point", f"[1,{text}]"))), taken=False)


# ------------------------------------------------------------ left to the exact reader

@pytest.mark.parametrize("text", [
    "",
    "[]",
    "5",
    '{"type":"FeatureCollection","features":[' + feature(geometry("Point", "[1,2]")),
    '{"type":"Feature","properties":{"a":"unclosed}',
    '{"type":"Feature","geometry":null,"properties":{"a":"\\x"}}',
    '{"type":"Feature","geometry":null} {"type":"Feature","geometry":null}',
    collection(feature(geometry("LineString", "[[0,0]]"))),
    collection(feature(geometry("Polygon", "[[[0,0],[1,0],[1,1],[0,1]]]"))),
    collection(feature(geometry("Polygon", "[[[0,0],[1,0],[0,0]]]"))),
    collection(feature(geometry("Polygon", "[[[0,0,1],[1,0,1],[1,1,1],[0,0]]]"))),
    collection(feature(geometry("MultiPoint", "[[1]]"))),
    collection(feature(geometry("MultiPoint", "[1,2]"))),
    collection(feature(geometry("Point", "[[1,2]]"))),
    collection(feature(geometry("MultiLineString", "[[[0,0],[1,1]],[[2,2]]]"))),
    collection(feature(geometry("Polygon", "[[[[0,0]]]]"))),
    collection(feature(geometry("Point", "[[[[[1]]]]]"))),
    collection(feature(geometry("Point", "[1,[2]]"))),
    collection(feature(geometry("Circle", "[1,2]"))),
    collection(feature(geometry("Point", "5"))),
    collection(feature('{"type":"Point"}')),
    collection(feature('{"type":"GeometryCollection","geometries":['
                       + geometry("Point", "[1,2]") + "]}")),
    collection('{"type":"Feature","properties":{}}'),
    collection('{"type":"Thing","geometry":null}'),
    collection("7"),
    '{"type":"FeatureCollection","features":null}',
    collection(feature(geometry("Point", "[1,2]")), feature(geometry("Point", "0"))),
    collection(feature('{"type":"Point","coordinates":[1,2],"coordinates":[3,4]}')),
    collection(feature('{"type":"Point","coordinates":[1,2]}', '"geometry":null')),
    collection(feature('{"type":"Point","co\\u006fordinates":[1,2]}')),
    '{"type":"Feature","properties":{},"geometry":' + geometry("Point", "[1,2]")
    + ',"features":[' + feature(geometry("Point", "[1,2]")) + "]}",
    b'{"type":"Feature","properties":{"a":"\xff"},"geometry":null}',
    b'{"type":"Feature","properties":{"a":"\x01"},"geometry":null}',
    "[" * 2000 + "]" * 2000,
])
def test_documents_left_to_the_exact_reader_give_its_result(tmp_path, text):
    check(tmp_path, text)


def test_truncated_documents_give_the_exact_readers_error(tmp_path):
    text = collection(feature(geometry("Polygon", f"[{SQUARE},{HOLE}]"), '"id":"a\\"b"'))
    for end in range(0, len(text), 7):
        check(tmp_path, text[:end], taken=False)


# --------------------------------------------------------------------------- sequences

@pytest.mark.parametrize("suffix", [".geojsonl", ".geojsons", ".ndjson"])
def test_one_document_per_line(tmp_path, suffix):
    lines = [feature(geometry("Point", "[1,2]"), '"id":1'),
             "\x1e" + geometry("Polygon", f"[{SQUARE}]") + " \r",
             "", " \t",
             collection(feature(geometry("LineString", "[[0,0],[1,1]]")), feature("null"))]
    check(tmp_path, "\n".join(lines) + "\n", suffix, taken=True)


@pytest.mark.parametrize("text", [
    "",
    "\n\n",
    feature(geometry("Point", "[1,2]")) + feature(geometry("Point", "[1,2]")),
    '{"type":"Feature",\n"geometry":null}',
    geometry("Point", "[1,\n2]"),
    feature(geometry("Point", "[1,2]")) + "\x1e" + feature(geometry("Point", "[1,2]")),
    feature(geometry("Point", "[1,2]")) + "\nnot json\n",
    "5\n",
])
def test_sequences_left_to_the_exact_reader_give_its_result(tmp_path, text):
    check(tmp_path, text, ".geojsonl")


# --------------------------------------------------------------------------- the scan itself

def padded(text: bytes) -> np.ndarray:
    data = np.zeros(len(text) + PADDING, dtype=np.uint8)
    data[:len(text)] = np.frombuffer(text, dtype=np.uint8)
    return data


def test_scan_replaces_each_coordinates_value_by_its_index():
    text = collection(feature(geometry("Point", "[1,2]")),
                      feature(geometry("Polygon", f"[{SQUARE}]"))).encode()
    scanned = scan(padded(text), len(text), False)
    assert scanned.status == SCANNED
    assert bytes(scanned.skeleton) == collection(feature(geometry("Point", "0")),
                                                 feature(geometry("Polygon", "1"))).encode()
    assert scanned.geometries.tolist() == [[0, 2, 0], [1, 2, 0]]
    assert scanned.events.tolist() == [2, -1, -1, 2, 2, 2, 2, 2, -2, -2]
    assert scanned.values.tolist() == [1, 2, 0, 0, 10, 0, 10, 10, 0, 10, 0, 0]


def test_scan_leaves_numbers_of_more_than_19_digits_near_a_tie_to_the_caller():
    tie = "9007199254740993.0000000000000000001"  # just above a tie: rounds up
    text = geometry("Point", f"[{tie},1]").encode()
    scanned = scan(padded(text), len(text), False)
    assert scanned.slow.tolist() == [[0, 31, 31 + len(tie)]]
    path_value = read_file_features(padded(text), len(text)).points[1][0, 0]
    assert path_value == float(tie) == 9007199254740994.0


def test_scan_does_not_take_nesting_deeper_than_it_tracks():
    text = b"[" * 1100 + b"]" * 1100
    assert scan(padded(text), len(text), False).status == NOT_TAKEN


@pytest.mark.parametrize("text", [
    '{"type":"FeatureCollection","features":[{"type":"Feature","id":3,"properties":{"a":1},'
    '"geometry":{"type":"Polygon","coordinates":[' + SQUARE + "," + HOLE + "]}}]}",
    '{"type":"LineString","coordinates":[[1,2],[3,4.5]]}',
    '{"type":"Feature","properties":null,"geometry":{"type":"GeometryCollection",'
    '"geometries":[{"type":"Point","coordinates":[1,2]}]}}',  # declined: the exact reader
])
def test_text_in_memory_is_read_as_a_file_is(text):
    """`features_of_geojson_text` (POST /v1/tiles) gives what the exact reader gives."""
    mine = sources.features_of_geojson_text(text.encode())
    theirs = sources.features_of_geojson(orjson.loads(text))
    assert_same_features(mine, theirs)
    assert_same_features(sources.features_of_geojson_text(memoryview(text.encode())), theirs)


@pytest.mark.parametrize("text", ['{"type":"Point","coordinates":[1,NaN]}', '{"type":',
                                  '{"type":"Point","coordinates":[1]}', '[]'])
def test_bad_text_in_memory_gets_the_exact_reader_s_error(text):
    from rnsca.io.geojson import loads

    with pytest.raises(RnscaError) as theirs:
        sources.features_of_geojson(loads(text))
    with pytest.raises(type(theirs.value), match=None) as mine:
        sources.features_of_geojson_text(text.encode())
    assert str(mine.value) == str(theirs.value)
