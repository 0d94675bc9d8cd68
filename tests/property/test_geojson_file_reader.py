"""The compiled GeoJSON file reader reads random documents as the exact reader does.

Documents are drawn as JSON *text*, so that what only text has varies too: every JSON
spelling of a number (integers of any size, ``-0``, exponents in either case, 17-digit
values, subnormals, long digit strings), whitespace and indentation, escaped and
unescaped strings. Each is read by `rnsca.tiles.sources.read_features` and by the exact
reader (orjson and ``from_geojson``, forced by making the compiled reader decline):
the arrays must agree bit for bit, properties and ids by value and type, errors by class
and message; where the exact reader accepts a document without GeometryCollections, the
compiled reader must have taken it. Numbers are also checked one by one against Python's
``float``, which rounds correctly.
"""

from __future__ import annotations

import json
import math
import random
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st

from rnsca.io.geojson_file import read_file_features
from rnsca.kernels.geojson_scan import PADDING, SCANNED, scan
from tests.unit.test_geojson_file_reader import check

#: JSON numbers (RFC 8259, 6), up to 30 digits in each part, exponents to 999.
JSON_NUMBER = r"-?(0|[1-9][0-9]{0,29})(\.[0-9]{1,30})?([eE][+-]?[0-9]{1,3})?"


class Number(str):
    """The text of a JSON number, written as it is."""


def _finite(text: str) -> bool:
    return math.isfinite(float(text))


def _bits_to_float(bits: int) -> float:
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


floats = st.floats(allow_nan=False, allow_infinity=False)
numbers = st.one_of(
    floats.map(repr),                                     # shortest: 16-17 digits
    floats.map(lambda x: f"{x:.17e}"),                    # 18 digits, e+XX
    floats.map(lambda x: f"{x:.30E}"),                    # long, E
    floats.map(lambda x: format(x, ".25g")),
    st.integers(0, (1 << 64) - 1).map(_bits_to_float).filter(math.isfinite).map(repr),
    st.integers(-(10 ** 30), 10 ** 30).map(str),
    st.sampled_from(["0", "-0", "0.0", "-0.0", "0e0", "-0E-0", "1e5", "1E-7", "1e+2",
                     "5e-324", "2.2250738585072011e-308", "1.7976931348623157e308",
                     "9007199254740993", "1e-400", "-1E-999"]),
    st.from_regex(JSON_NUMBER, fullmatch=True).filter(_finite),
).map(Number)

texts = st.text(st.characters(exclude_categories=("Cs",)), max_size=8)
keys = st.sampled_from(["coordinates", "geometry", "type", "features", "id", "properties",
                        "bbox", "name"]) | texts
json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(2 ** 70), 2 ** 70) | floats | texts
    | st.just("coordinates") | numbers,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(keys, inner, max_size=3),
    max_leaves=8)


@st.composite
def positions(draw, dims):
    """A position of 2, 3 or (rarely) 4 numbers, as `dims` ("2d", "3d", "mixed") says."""
    count = {"2d": 2, "3d": 3}.get(dims) or draw(st.sampled_from([2, 3]))
    if draw(st.integers(0, 20)) == 0:
        count = 4
    return [draw(numbers) for _ in range(count)]


def _respelled(position: list) -> list:
    """Return the same position (equal numbers), each number written as Python writes it."""
    return [Number(repr(float(n))) if n != "-0" else Number("0") for n in position]


@st.composite
def rings(draw, dims):
    """A closed ring of 4 to 7 positions (its last the first, maybe respelled)."""
    first = draw(positions(dims))
    middle = draw(st.lists(positions(dims), min_size=2, max_size=5))
    last = _respelled(first) if draw(st.booleans()) else list(first)
    if draw(st.integers(0, 30)) == 0:  # rarely, an open ring: both readers refuse it
        last = draw(positions(dims))
    return [first, *middle, last]


@st.composite
def lines(draw, dims):
    return draw(st.lists(positions(dims), min_size=2, max_size=5))


def polygons(dims):
    return st.lists(rings(dims), min_size=0, max_size=3)


@st.composite
def geometries(draw):
    """A GeoJSON geometry object (a dict with `Number` leaves), or None."""
    dims = draw(st.sampled_from(["2d", "3d", "mixed"]))
    kind = draw(st.sampled_from(["Point", "MultiPoint", "LineString", "MultiLineString",
                                 "Polygon", "MultiPolygon", "null"]))
    empty = draw(st.integers(0, 8)) == 0
    if kind == "null":
        return None
    if kind == "Point":
        coordinates = [] if empty else draw(positions(dims))
    elif kind == "MultiPoint":
        coordinates = draw(st.lists(positions(dims), max_size=4))
    elif kind == "LineString":
        coordinates = [] if empty else draw(lines(dims))
    elif kind == "MultiLineString":
        coordinates = draw(st.lists(lines(dims) | st.just([]), max_size=3))
    elif kind == "Polygon":
        coordinates = [] if empty else draw(polygons(dims))
    else:
        coordinates = draw(st.lists(polygons(dims), max_size=3))
    geometry = {"type": kind, "coordinates": coordinates}
    if draw(st.integers(0, 5)) == 0:
        geometry = {"bbox": [Number("0"), Number("1")], **geometry, "note": "coordinates"}
    if draw(st.booleans()):
        geometry = dict(reversed(geometry.items()))  # coordinates before type
    return geometry


@st.composite
def features(draw):
    feature: dict = {"type": "Feature"}
    if draw(st.booleans()):
        feature["id"] = draw(json_values)
    if draw(st.integers(0, 5)) > 0:
        feature["properties"] = draw(st.none() | st.dictionaries(keys, json_values, max_size=4))
    feature["geometry"] = draw(geometries())
    items = list(feature.items())
    draw(st.randoms(use_true_random=False)).shuffle(items)
    return dict(items)


@st.composite
def documents(draw):
    """A FeatureCollection (mostly), a Feature or a bare Geometry."""
    top = draw(st.sampled_from(["FeatureCollection"] * 4 + ["Feature", "Geometry"]))
    if top == "Feature":
        return draw(features())
    if top == "Geometry":
        return draw(geometries().filter(lambda g: g is not None))
    document: dict = {"type": "FeatureCollection",
                      "features": draw(st.lists(features(), max_size=6))}
    if draw(st.booleans()):
        document["name"] = draw(json_values)
    return document


class Writer:
    """Writes a JSON value with random whitespace and string escapes."""

    def __init__(self, rng: random.Random, newlines: bool = True) -> None:
        self.rng = rng
        self.spaces = ["", " ", "\t", "\r", "  "] + (["\n", "\n  ", "\r\n    "] if newlines else [])
        self.style = rng.choice(["compact", "spaced", "random"])

    def space(self) -> str:
        if self.style == "compact":
            return ""
        if self.style == "spaced":
            return " "
        return self.rng.choice(self.spaces)

    def write(self, value: object) -> str:
        s = self.space
        if isinstance(value, Number):
            return str(value)
        if isinstance(value, str):
            return json.dumps(value, ensure_ascii=self.rng.random() < 0.5)
        if isinstance(value, (bool, int, float)) or value is None:
            return json.dumps(value)
        if isinstance(value, list):
            return "[" + s() + ("," + s()).join(self.write(v) + s() for v in value) + "]"
        assert isinstance(value, dict)
        return "{" + s() + ("," + s()).join(
            self.write(str(k)) + s() + ":" + s() + self.write(v) + s()
            for k, v in value.items()) + "}"


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("geojson-file-reader")


@given(document=documents(), rng=st.randoms(use_true_random=False))
def test_random_documents_read_as_the_exact_reader_reads_them(folder, document, rng):
    text = Writer(rng).write(document)
    valid = check(folder, text, taken="if valid")
    event(f"top level {document.get('type')}, {'valid' if valid else 'refused'}")


@given(document=documents(), rng=st.randoms(use_true_random=False),
       cut=st.floats(0, 1, exclude_max=True))
def test_truncated_documents_give_the_exact_readers_error(folder, document, rng, cut):
    text = Writer(rng).write(document)
    check(folder, text[:int(cut * len(text))], taken=False)


@given(lines=st.lists(documents(), max_size=4), rng=st.randoms(use_true_random=False))
def test_random_sequences_read_as_the_exact_reader_reads_them(folder, lines, rng):
    writer = Writer(rng, newlines=False)
    text = "".join(rng.choice(["", "\x1e", " "]) + writer.write(line)
                   + rng.choice(["\n", "\r\n", "\n\n", " \n"]) for line in lines)
    event("valid" if check(folder, text, ".geojsonl", taken="if valid") else "refused")


def _scanned_value(text: str) -> tuple[float, bool]:
    """Return (the value `scan` reads for number `text` as a coordinate, whether decided)."""
    data = f'{{"type":"Point","coordinates":[{text},0]}}'.encode()
    padded = np.zeros(len(data) + PADDING, dtype=np.uint8)
    padded[:len(data)] = np.frombuffer(data, dtype=np.uint8)
    scanned = scan(padded, len(data), False)
    assert scanned.status == SCANNED
    return float(scanned.values[0]), scanned.slow.shape[0] == 0


def _python_value(text: str) -> float:
    """Return ``float(text)``, but +0.0 for the integer ``-0`` (JSON parsers give int 0)."""
    return 0.0 if text == "-0" else float(text)


def _same(a: float, b: float) -> bool:
    return struct.pack("<d", a) == struct.pack("<d", b)


@given(text=st.from_regex(JSON_NUMBER, fullmatch=True) | numbers)
def test_scanned_numbers_are_pythons_floats(text):
    value, decided = _scanned_value(text)
    event("decided" if decided else "left to the caller")
    if decided:
        assert _same(value, _python_value(text)), (text, value, float(text))


@given(bits=st.integers(0, (1 << 63) - 1), digits=st.integers(16, 19),
       above=st.booleans(), negative=st.booleans())
def test_numbers_next_to_a_tie_round_as_python_does(bits, digits, above, negative):
    """Decimals of 16 to 19 digits a hair from halfway between two floats."""
    from decimal import Decimal, localcontext
    from fractions import Fraction

    low = _bits_to_float(bits)
    high = math.nextafter(low, math.inf)
    if not math.isfinite(high):
        return
    half = (Fraction(low) + Fraction(high)) / 2
    with localcontext() as context:
        context.prec = 800
        exact = Decimal(half.numerator) / Decimal(half.denominator)
        context.prec = digits
        near = +exact
        near = near.next_plus() if above else near.next_minus()
    text = ("-" if negative else "") + format(near, "E").replace("E+", "E")
    value, decided = _scanned_value(text)
    assert decided
    assert _same(value, float(text)), (text, value, float(text))


@given(st.lists(st.from_regex(JSON_NUMBER, fullmatch=True).filter(_finite), min_size=1,
                max_size=20))
def test_numbers_left_to_the_caller_are_read_too(folder, values):
    """End to end, the undecided numbers (more than 19 digits) as well."""
    text = '{"type":"MultiPoint","coordinates":[' + ",".join(
        f"[{v},{v}]" for v in values) + "]}"
    path = folder / "numbers.geojson"
    path.write_text(text)
    data = text.encode()
    padded = np.zeros(len(data) + PADDING, dtype=np.uint8)
    padded[:len(data)] = np.frombuffer(data, dtype=np.uint8)
    read = read_file_features(padded, len(data))
    assert read is not None
    coords = read.points[1]
    assert all(_same(x, _python_value(v)) for x, v in zip(coords[:, 0], values, strict=True))
