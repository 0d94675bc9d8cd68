"""GeoJSON text sequences: records cut from pieces of any size, in both framings."""

import io

import orjson
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rnsca.errors import InvalidOptionError, LimitExceededError, ParseError
from rnsca.io.geojson_seq import (
    RS,
    Framing,
    RecordSplitter,
    framing_of_path,
    read_records,
    record_bytes,
    split_records,
    write_records,
)

POINT = {"type": "Point", "coordinates": [1.5, 2.0]}
FEATURE = {"type": "Feature", "id": "a\nb", "properties": {"text": "line\nbreak \u00e9"},
           "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 1]]}}


def every_split(data: bytes):
    """Each way of cutting `data` in two pieces, and one piece per byte."""
    for cut in range(len(data) + 1):
        yield [data[:cut], data[cut:]]
    yield [data[i:i + 1] for i in range(len(data))]


def test_rs_framed_records_come_out_whole_however_the_bytes_are_cut():
    data = record_bytes(POINT, Framing.RS) + record_bytes(FEATURE, Framing.RS)
    for pieces in every_split(data):
        texts = list(split_records(pieces, Framing.RS))
        assert [orjson.loads(t) for t in texts] == [POINT, FEATURE], pieces


def test_newline_delimited_records_come_out_whole_however_the_bytes_are_cut():
    data = record_bytes(POINT, "lines") + record_bytes(FEATURE, "lines")
    for pieces in every_split(data):
        texts = list(split_records(pieces, Framing.LINES))
        assert [orjson.loads(t) for t in texts] == [POINT, FEATURE], pieces


def test_rs_framed_text_may_span_lines_and_repeated_rs_are_skipped():
    pretty = orjson.dumps(POINT, option=orjson.OPT_INDENT_2)
    data = b"\n " + RS + pretty + b"\n" + RS + RS + b" \n" + RS + b'{"type": "Point", ' \
        b'"coordinates": [3, 4]}'  # the last one without its LF
    assert [orjson.loads(t) for t in split_records([data], Framing.RS)] == [
        POINT, {"type": "Point", "coordinates": [3, 4]}]


def test_blank_lines_and_crlf_endings_of_newline_delimited_records():
    data = b"\r\n" + orjson.dumps(POINT) + b"\r\n\n   \n" + orjson.dumps(FEATURE)
    texts = list(split_records([data], Framing.LINES))
    assert [orjson.loads(t) for t in texts] == [POINT, FEATURE]


def test_records_are_numbered_without_the_skipped_blanks():
    splitter = RecordSplitter(Framing.LINES)
    assert splitter.feed(b"\n\n{}\n\n{}\n") == [b"{}", b"{}"]
    assert splitter.records == 2


def test_framing_is_decided_by_the_first_byte_that_is_not_whitespace():
    rs = b"  \n" + record_bytes(POINT, Framing.RS)
    splitter = RecordSplitter()
    assert splitter.feed(rs[:2]) == [] and splitter.framing is None
    assert splitter.feed(rs[2:]) == []  # a text ends at the next RS, or the end
    assert splitter.framing is Framing.RS
    assert splitter.finish() == [orjson.dumps(POINT) + b"\n"]
    lines = RecordSplitter()
    lines.feed(b"\n{}")
    assert lines.framing is Framing.LINES


def test_rs_framing_refuses_a_stream_that_does_not_start_with_rs():
    splitter = RecordSplitter(Framing.RS)
    with pytest.raises(ParseError, match="RS") as caught:
        splitter.feed(orjson.dumps(POINT) + b"\n")
    assert caught.value.record == 0


def test_a_record_longer_than_the_limit_is_refused_before_it_ends():
    splitter = RecordSplitter(Framing.LINES, max_record_bytes=100)
    assert splitter.feed(b"{}\n") == [b"{}"]
    splitter.feed(b"[" + b"0," * 40)            # 81 bytes: not yet over
    with pytest.raises(LimitExceededError, match="record 1 is longer than") as caught:
        splitter.feed(b"0," * 20)                 # past 100, no LF in sight
    assert caught.value.record == 1


def test_a_record_at_the_limit_passes():
    text = b'{"a": "' + b"x" * 91 + b'"}'
    assert len(text) == 100
    assert list(split_records([text + b"\n"], "lines", max_record_bytes=100)) == [text]


def test_read_records_parses_and_names_the_bad_record():
    data = b"{}\n[1, 2]\n{nope}\n"
    records = read_records(io.BytesIO(data), block=3)
    assert next(records) == {} and next(records) == [1, 2]
    with pytest.raises(ParseError, match="record 2 is not valid JSON") as caught:
        next(records)
    assert (caught.value.record, caught.value.position) == (2, 1)


def test_write_then_read_gives_the_records_back_in_both_framings():
    for framing in Framing:
        out = io.BytesIO()
        assert write_records([POINT, FEATURE, POINT], out, framing) == 3
        assert list(read_records(io.BytesIO(out.getvalue()))) == [POINT, FEATURE, POINT]


def test_rs_records_are_rs_text_lf():
    assert record_bytes(POINT, Framing.RS) == RS + orjson.dumps(POINT) + b"\n"
    assert record_bytes(FEATURE, Framing.LINES).count(b"\n") == 1  # the LF in text escaped


def test_framing_names_and_media_types():
    assert Framing("rs").media_type == "application/geo+json-seq"
    assert Framing.LINES.media_type == "application/x-ndjson"
    with pytest.raises(InvalidOptionError, match="rs, lines"):
        Framing("csv")
    assert framing_of_path("a.geojsonseq") is Framing.RS
    assert framing_of_path("a.ndjson") is Framing.LINES


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2**53, 2**53) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner,
                                                                max_size=3),
    max_leaves=8)


@given(records=st.lists(json_values, max_size=8), framing=st.sampled_from(list(Framing)),
       cuts=st.lists(st.integers(0, 10_000), max_size=10))
def test_any_records_cut_anywhere_come_back_equal(records, framing, cuts):
    data = b"".join(record_bytes(r, framing) for r in records)
    bounds = sorted({0, len(data), *(c % (len(data) + 1) for c in cuts)})
    pieces = [data[a:b] for a, b in zip(bounds, bounds[1:], strict=False)]
    texts = list(split_records(pieces, framing))
    assert [orjson.loads(t) for t in texts] == records


def test_the_records_before_a_bad_one_are_returned_before_it_is_raised():
    splitter = RecordSplitter(Framing.LINES, max_record_bytes=10)
    assert splitter.feed(b"{}\n[1]\n" + b"[" + b"0," * 10 + b"0]\n{}\n") == [b"{}", b"[1]"]
    assert isinstance(splitter.error, LimitExceededError) and splitter.error.record == 2
    with pytest.raises(LimitExceededError, match="record 2"):
        splitter.feed(b"{}\n")
    with pytest.raises(LimitExceededError, match="record 2"):
        splitter.finish()
    texts = split_records([b"{}\n{}\n{" + b" " * 20], max_record_bytes=10)
    assert next(texts) == b"{}" and next(texts) == b"{}"
    with pytest.raises(LimitExceededError, match="record 2"):
        next(texts)
