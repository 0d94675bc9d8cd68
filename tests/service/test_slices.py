"""A large GeoJSON request parsed a slice of features at a time: the whole parse's answer."""

import json

import orjson
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from service import slices
from service.schemas import ClipGeoJSONRequest

WINDOW = [0, 0, 10, 10]


def _whole(body: bytes):
    try:
        return ClipGeoJSONRequest.model_validate_json(body).model_dump()
    except ValueError:
        return "error"


def _sliced(body: bytes, slice_bytes: int = 1):
    request = slices.parse_sliced(body, slice_bytes)
    return None if request is None else request.model_dump()


# Feature-like JSON values: strings full of JSON's own punctuation, nested arrays.
_TEXT = st.text(alphabet='ab,[]{}:"\\ \n\u00e9', max_size=8)
_VALUE = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6)
    | st.floats(allow_nan=False, allow_infinity=False) | _TEXT,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(_TEXT, inner, max_size=3),
    max_leaves=12)
_FEATURE = st.fixed_dictionaries({
    "type": st.just("Feature"), "properties": st.dictionaries(_TEXT, _VALUE, max_size=3),
    "geometry": st.fixed_dictionaries({"type": st.just("LineString"), "coordinates": st.lists(
        st.lists(st.floats(-1e6, 1e6), min_size=2, max_size=3), min_size=2, max_size=4)})})


@settings(max_examples=300, deadline=None)
@given(features=st.lists(_FEATURE, max_size=12), indent=st.sampled_from([None, 1]),
       extra=st.dictionaries(st.sampled_from(["bbox", "name", "features2"]), _VALUE,
                             max_size=2), slice_bytes=st.integers(1, 400),
       geojson_first=st.booleans())
def test_the_sliced_parse_gives_the_whole_parse(features, indent, extra, slice_bytes,
                                                geojson_first):
    geojson = {"type": "FeatureCollection", **extra, "features": features}
    members = [("geojson", geojson), ("window", WINDOW), ("verify", False)]
    if not geojson_first:
        members.reverse()
    body = json.dumps(dict(members), indent=indent).encode()
    sliced = _sliced(body, slice_bytes)
    assert sliced is None or sliced == _whole(body)
    if not extra:  # no escape in a member the scan reads: it must split
        assert sliced == _whole(body)


@pytest.mark.parametrize("body", [
    b'{"window":[0,0,1,1],"geojson":{"type":"FeatureCollection","features":[1,,2]}}',
    b'{"window":[0,0,1,1],"geojson":{"type":"FeatureCollection","features":[,1]}}',
    b'{"window":[0,0,1,1],"geojson":{"type":"FeatureCollection","features":[1,]}}',
    b'{"window":[0,0,1,1],"geojson":{"type":"FeatureCollection","features":[1 2]}}',
    b'{"window":[0,0,1,1],"geojson":{"type":"FeatureCollection","features":[{"a":1]}}',
])
def test_a_malformed_features_array_falls_back_to_the_whole_parse(body):
    assert _sliced(body) is None
    assert _whole(body) == "error"


def test_a_token_orjson_refuses_falls_back_to_the_whole_parse():
    # pydantic reads NaN (the GeoJSON reader then refuses it, naming its path).
    body = b'{"window":[0,0,1,1],"geojson":{"type":"FeatureCollection","features":[NaN]}}'
    assert _sliced(body) is None
    assert str(slices.parse_geojson_request(body).model_dump()) == str(_whole(body))


@pytest.mark.parametrize("body", [
    # A key spelt with an escape, or written twice: the last one wins, so the whole parse
    # decides which array is read.
    b'{"window":[0,0,1,1],"geo\\u006Ason":{"features":[1]},"geojson":{"features":[2]}}',
    b'{"window":[0,0,1,1],"geojson":{"features":[1]},"geojson":{"features":[2]}}',
    b'{"window":[0,0,1,1],"geojson":{"features":[1],"features":[2]}}',
    b'{"window":[0,0,1,1],"geojson":{"feat\\u0075res":[1],"features":[2]}}',
    # No features array where the split looks.
    b'{"window":[0,0,1,1],"geojson":{"type":"Feature","geometry":null}}',
    b'{"window":[0,0,1,1],"geojson":{"features":{"a":[1,2]}}}',
    b'{"window":[0,0,1,1],"other":{"features":[1,2]},"geojson":{"features":[]}}',
])
def test_what_the_scan_cannot_vouch_for_is_parsed_whole(body):
    request = slices.parse_sliced(body)
    if request is not None:  # where it does split, it must agree
        assert request.model_dump() == _whole(body)
    try:
        answer = slices.parse_geojson_request(body).model_dump()
    except ValueError:
        answer = "error"
    assert answer == _whole(body)


def test_a_large_request_is_parsed_in_slices_and_clipped_as_before(monkeypatch):
    from service import convert
    from service.config import Settings

    features = [{"type": "Feature", "properties": {"i": i}, "geometry": {
        "type": "LineString", "coordinates": [[-5, i % 10], [15, i % 10]]}}
        for i in range(20000)]
    body = orjson.dumps({"window": WINDOW, "verify": False, "geojson": {
        "type": "FeatureCollection", "features": features}})
    assert len(body) >= slices.SLICED_PARSE_BYTES
    calls = []
    original = slices.parse_sliced
    monkeypatch.setattr(slices, "parse_sliced", lambda b: calls.append(1) or original(b))
    answer = orjson.loads(convert.clip_geojson(body, Settings(warm_up=False)).content)
    assert calls == [1]
    clipped = answer["geojson"]["features"]
    assert len(clipped) == 20000
    assert clipped[7]["geometry"]["coordinates"] == [[0.0, 7.0], [10.0, 7.0]]
    assert clipped[7]["properties"] == {"i": 7}
