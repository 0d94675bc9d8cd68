"""Fuzz target: the GeoJSON reader (`rnsca.io.geojson`) and its MessagePack decoder.

The first byte of an input picks what the rest is:

- ``M`` (MessagePack): a header and bytes for `read_positions`, the compiled decoder
  the reader hands ormsgpack's output to, fed here with any bytes at all (the reader
  only ever gives it what ormsgpack writes): ``dim`` (second byte: 2 or 3), the number
  of arrays ``k`` (third byte, at most 15) and their sizes (``k`` bytes), then the
  MessagePack bytes.
- anything else: JSON text for `from_geojson`.

A finding is an exception other than the documented ones (`ParseError` for text that
is not JSON, `InvalidGeometryError` for a document that breaks the rules), an
``IndexError`` from Numba's bounds checks (the runner turns them on), or a disagreement
with the reference below.

References
----------
Documents: the text is parsed by orjson, as rnsca does (the JSON parser is not what is
tested: text orjson refuses must give `ParseError`). The parsed value is then read by
`reference_layout`, a plain recursive walk written from the rules in the
`rnsca.io.geojson` docstring and nothing else: it must refuse exactly the documents
rnsca refuses, naming the same JSON path (the first problem in document order), and
give the same coordinates (bit for bit, 2D or 3D) and offsets for the others.

MessagePack: `reference_positions`, a small decoder written here from the MessagePack
specification with `struct` (arrays and numbers; anything else is not a position), which
must agree with ``ormsgpack.unpackb`` where both decode, and with `read_positions`
everywhere: refused or not, the positions, and which arrays are plain.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import orjson
import ormsgpack

from rnsca.errors import InvalidGeometryError, ParseError
from rnsca.io.geojson import GEOMETRY_TYPES, MAX_COLLECTION_DEPTH, from_geojson
from rnsca.io.msgpack_decode import HAS_Z, MIXED, PARTIAL_Z, PLAIN, REFUSED, read_positions

__all__ = ["MAX_LEN", "setup", "test_one_input", "reference_layout", "reference_positions"]

#: Longest input libFuzzer makes.
MAX_LEN = 2048


# --------------------------------------------------------------------------- documents

class Refused(Exception):
    """The reference refuses the document; ``path`` names the problem."""

    def __init__(self, path: str) -> None:
        super().__init__(path)
        self.path = path


def _at(path: str, member: str) -> str:
    return f"{path}.{member}" if path else member


class _Walk:
    """The reference walk: rules from the `rnsca.io.geojson` docstring, in document order."""

    def __init__(self) -> None:
        self.dim: int | None = None
        # Per kind: geometries, each a list of parts (points: one part of positions;
        # lines: parts; polygons: polygons of rings), positions as lists of numbers.
        self.points: list[list] = []
        self.lines: list[list] = []
        self.polygons: list[list] = []

    def document(self, doc) -> None:
        if not isinstance(doc, dict):
            raise Refused("")
        kind = self.type_of(doc, "")
        if kind == "FeatureCollection":
            features = self.member(doc, "features", "")
            if not isinstance(features, list):
                raise Refused("features")
            for i, feature in enumerate(features):
                self.feature(feature, f"features[{i}]")
        elif kind == "Feature":
            self.feature(doc, "")
        elif kind in GEOMETRY_TYPES:
            self.geometry(doc, "", 0)
        else:
            raise Refused("type")

    @staticmethod
    def type_of(obj: dict, path: str) -> str:
        if "type" not in obj:
            raise Refused(path)
        if not isinstance(obj["type"], str):
            raise Refused(_at(path, "type"))
        return obj["type"]

    @staticmethod
    def member(obj: dict, name: str, path: str):
        if name not in obj:
            raise Refused(path)
        return obj[name]

    def feature(self, feature, path: str) -> None:
        if not isinstance(feature, dict):
            raise Refused(path)
        if self.type_of(feature, path) != "Feature":
            raise Refused(_at(path, "type"))
        geometry = self.member(feature, "geometry", path)
        if geometry is not None:
            self.geometry(geometry, _at(path, "geometry"), 0)

    def geometry(self, geometry, path: str, depth: int) -> None:
        if not isinstance(geometry, dict):
            raise Refused(path)
        kind = self.type_of(geometry, path)
        if kind not in GEOMETRY_TYPES:
            raise Refused(_at(path, "type"))
        if kind == "GeometryCollection":
            if depth >= MAX_COLLECTION_DEPTH:
                raise Refused(path)
            members = self.member(geometry, "geometries", path)
            if not isinstance(members, list):
                raise Refused(_at(path, "geometries"))
            for i, member in enumerate(members):
                self.geometry(member, f"{_at(path, 'geometries')}[{i}]", depth + 1)
            return
        coordinates = self.member(geometry, "coordinates", path)
        path = _at(path, "coordinates")
        if not isinstance(coordinates, list):
            raise Refused(path)
        if kind == "Point":
            self.points.append([self.position(coordinates, path)] if coordinates else [])
        elif kind == "MultiPoint":
            self.points.append([self.position(p, f"{path}[{i}]")
                                for i, p in enumerate(coordinates)])
        elif kind == "LineString":
            self.lines.append([part for part in [self.line(coordinates, path)] if part])
        elif kind == "MultiLineString":
            self.lines.append([part for part in (self.line(self.array(c, f"{path}[{i}]"),
                                                           f"{path}[{i}]")
                                                 for i, c in enumerate(coordinates)) if part])
        elif kind == "Polygon":
            self.polygons.append([p for p in [self.polygon(coordinates, path)] if p])
        else:
            self.polygons.append([p for p in (self.polygon(self.array(c, f"{path}[{i}]"),
                                                           f"{path}[{i}]")
                                              for i, c in enumerate(coordinates)) if p])

    @staticmethod
    def array(value, path: str) -> list:
        if not isinstance(value, list):
            raise Refused(path)
        return value

    def line(self, positions: list, path: str) -> list:
        if len(positions) == 1:
            raise Refused(path)
        return [self.position(p, f"{path}[{i}]") for i, p in enumerate(positions)]

    def polygon(self, rings: list, path: str) -> list:
        out = []
        for i, ring in enumerate(rings):
            ring_path = f"{path}[{i}]"
            self.array(ring, ring_path)
            if len(ring) < 4:
                raise Refused(ring_path)
            positions = [self.position(p, f"{ring_path}[{j}]") for j, p in enumerate(ring)]
            if positions[0] != positions[-1]:
                raise Refused(ring_path)
            out.append(positions)
        return out

    def position(self, position, path: str) -> list[float]:
        """Return the position's coordinates in the document's dimension."""
        if not isinstance(position, list) or len(position) < 2:
            raise Refused(path)
        for i, value in enumerate(position):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise Refused(f"{path}[{i}]")
            try:
                finite = math.isfinite(float(value))
            except OverflowError:
                finite = False
            if not finite:
                raise Refused(f"{path}[{i}]")
        # A document may mix 2D and 3D positions: each keeps its own (numbers after the
        # third dropped); `reference_layout` reads a document with any 3D one as 3D.
        dim = 2 if len(position) == 2 else 3
        self.dim = max(self.dim or 2, dim)
        return [float(value) for value in position[:dim]]


def reference_layout(doc) -> tuple[bool, list[tuple]]:
    """Return ``(has_z, [points, lines, polygons])`` of a parsed document.

    Each of the three is a ``(coords, offsets)`` pair in `shapely.to_ragged_array`'s
    layout. Raises `Refused` naming the JSON path of the first problem.
    """
    walk = _Walk()
    walk.document(doc)
    dim = walk.dim or 2

    def ragged(geometries: list, depth: int) -> tuple:
        levels: list[list[int]] = [[0] for _ in range(depth)]   # innermost first
        coords: list = []

        def add(item: list, level: int) -> None:   # `item` holds things of level - 1
            levels[level].append(levels[level][-1] + len(item))
            if level == 0:
                coords.extend(item)
            else:
                for sub in item:
                    add(sub, level - 1)

        for geometry in geometries:
            add(geometry, depth - 1)
        # A 2D position of a 3D document: Z unknown (NaN), as rnsca reads it.
        coords = [c + [math.nan] * (dim - len(c)) for c in coords]
        array = np.array(coords, dtype=np.float64).reshape(-1, dim)
        return array, tuple(np.array(level, dtype=np.int64) for level in levels)

    return dim == 3, [ragged(walk.points, 1), ragged(walk.lines, 2),
                      ragged(walk.polygons, 3)]


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Return whether two float arrays are equal bit for bit (the sign of zero too)."""
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=True) and np.array_equal(
        np.signbit(a), np.signbit(b))


def _check_document(text: bytes) -> None:
    try:
        doc = orjson.loads(text)
    except orjson.JSONDecodeError:
        try:
            from_geojson(text)
        except ParseError:
            return
        raise AssertionError("rnsca read text that orjson refuses") from None
    try:
        expected = reference_layout(doc)
    except Refused as refused:
        expected = refused
    except RecursionError:
        return   # deeper than Python's stack: not a GeoJSON document either way
    try:
        layout = from_geojson(text)
    except InvalidGeometryError as error:
        assert isinstance(expected, Refused), f"rnsca refused a valid document: {error}"
        assert error.path == expected.path, (
            f"rnsca names {error.path!r}, the reference {expected.path!r}: {error}")
        return
    assert not isinstance(expected, Refused), (
        f"rnsca read a document the reference refuses at {expected.path!r}")
    has_z, arrays = expected
    assert layout.has_z == has_z, f"has_z {layout.has_z}, reference {has_z}"
    for name, (coords, offsets) in zip(("points", "lines", "polygons"), arrays, strict=True):
        _, got_coords, got_offsets = getattr(layout, name)
        assert _same(got_coords, coords), f"{name}: {got_coords!r} != {coords!r}"
        assert len(got_offsets) == len(offsets) and all(
            np.array_equal(a, b) for a, b in zip(got_offsets, offsets, strict=True)), (
            f"{name} offsets: {got_offsets!r} != {offsets!r}")
    # The layout is what a second read of the parsed value gives (the dict path).
    again = from_geojson(doc)
    for name in ("points", "lines", "polygons"):
        assert _same(getattr(again, name)[1], getattr(layout, name)[1]), name


# --------------------------------------------------------------------------- MessagePack

_FORMATS = {0xCA: ">f", 0xCB: ">d", 0xCC: ">B", 0xCD: ">H", 0xCE: ">I", 0xCF: ">Q",
            0xD0: ">b", 0xD1: ">h", 0xD2: ">i", 0xD3: ">q"}


def _decode(data: bytes, at: int):
    """Return ``(value, next)`` of the arrays-and-numbers object at `at`.

    A number is ``(value, is_float64)``; an array a list. Raises ValueError for any
    other object or truncated bytes.
    """
    if at >= len(data):
        raise ValueError("truncated")
    tag = data[at]
    if tag <= 0x7F:
        return (float(tag), False), at + 1
    if tag >= 0xE0:
        return (float(tag - 256), False), at + 1
    if tag in _FORMATS:
        fmt = _FORMATS[tag]
        size = struct.calcsize(fmt)
        if at + 1 + size > len(data):
            raise ValueError("truncated")
        (value,) = struct.unpack_from(fmt, data, at + 1)
        return (float(value), tag == 0xCB), at + 1 + size
    if 0x90 <= tag <= 0x9F or tag in (0xDC, 0xDD):
        if tag <= 0x9F:
            count, at = tag & 0x0F, at + 1
        else:
            size = 2 if tag == 0xDC else 4
            if at + 1 + size > len(data):
                raise ValueError("truncated")
            count, at = int.from_bytes(data[at + 1:at + 1 + size], "big"), at + 1 + size
        items = []
        for _ in range(count):
            item, at = _decode(data, at)
            items.append(item)
        return items, at
    raise ValueError(f"not an array or a number: 0x{tag:02x}")


def reference_positions(data: bytes, sizes: list[int], dim: int):
    """Return ``(positions, plain)`` read as `read_positions` documents, None if refused."""
    try:
        value, end = _decode(data, 0)
    except (ValueError, RecursionError):
        return None
    if end != len(data) or not isinstance(value, list) or len(value) != len(sizes):
        return None
    positions, plain = [], []
    for array, size in zip(value, sizes, strict=True):
        if not isinstance(array, list) or len(array) != size:
            return None
        flag = True
        for position in array:
            if not isinstance(position, list) or len(position) < 2:
                return None
            if any(isinstance(n, list) or not math.isfinite(n[0]) for n in position):
                return None
            # 2D: a position of 3 or more numbers means "read again in 3D" (HAS_Z); 3D:
            # one of 2 numbers gets Z NaN.
            numbers = [n[0] for n in position[:dim]]
            positions.append(numbers + [math.nan] * (dim - len(numbers)))
            flag &= len(position) == dim and all(n[1] for n in position)
        plain.append(flag)
    return positions, plain


def _as_python(value):
    """Return a `_decode` value as ormsgpack would give it (floats; lists)."""
    return [_as_python(v) for v in value] if isinstance(value, list) else value[0]


def _check_messagepack(data: bytes) -> None:
    if len(data) < 2:
        return
    dim, k = (3 if data[0] & 1 else 2), data[1] & 0x0F
    sizes, body = list(data[2:2 + k]), data[2 + k:]
    if len(sizes) < k:
        return
    expected = reference_positions(body, sizes, dim)
    try:
        decoded, _ = _decode(body, 0)
        mine = _as_python(decoded)
    except (ValueError, RecursionError):
        mine = None
    try:
        theirs = ormsgpack.unpackb(body)
    except (ormsgpack.MsgpackDecodeError, RecursionError):
        theirs = None
    if mine is not None and theirs is not None:
        assert _equal_values(mine, theirs), f"the reference decoder and ormsgpack differ: " \
                                            f"{mine!r} != {theirs!r}"
    out = np.full((sum(sizes), dim), np.nan)
    plain = np.zeros(len(sizes), dtype=bool)
    result = read_positions(np.frombuffer(body, dtype=np.uint8),
                            np.array(sizes, dtype=np.int64), out, plain)
    if result == HAS_Z:
        # 2D met a position of 3 or more numbers: the reader reads it all again in 3D.
        assert dim == 2, "HAS_Z in 3D"
        has_long = any(isinstance(p, list) and len(p) >= 3
                       for a in (decoded if mine is not None else []) if isinstance(a, list)
                       for p in a)
        assert mine is None or has_long, "HAS_Z without a position of 3 numbers"
        dim = 3
        expected = reference_positions(body, sizes, dim)
        out = np.full((sum(sizes), dim), np.nan)
        result = read_positions(np.frombuffer(body, dtype=np.uint8),
                                np.array(sizes, dtype=np.int64), out, plain)
    if expected is None:
        assert result == REFUSED, f"read_positions read what the reference refuses: {result}"
        return
    positions, flags = expected
    assert result != REFUSED, "read_positions refused what the reference reads"
    assert _same(out, np.array(positions, dtype=np.float64).reshape(-1, dim)), (
        f"positions {out.tolist()} != {positions}")
    assert plain.tolist() == flags, f"plain {plain.tolist()} != {flags}"
    partial = any(math.isnan(p[-1]) for p in positions) if dim == 3 else False
    assert result == (PARTIAL_Z if partial else PLAIN if all(flags) else MIXED), result


def _equal_values(a, b) -> bool:
    """Return whether two decoded values are equal (NaN equal to NaN)."""
    if isinstance(a, list) or isinstance(b, list):
        return isinstance(a, list) and isinstance(b, (list, tuple)) and len(a) == len(b) \
            and all(_equal_values(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(b, bool) or not isinstance(b, (int, float)):
        return False
    return a == float(b) or (math.isnan(a) and math.isnan(b))


# --------------------------------------------------------------------------- the target

def setup() -> None:
    """Compile the decoder and the writer's helper before the first timed input."""
    from_geojson(b'{"type": "MultiPoint", "coordinates": [[1, 2.5], [3, 4]]}')
    from_geojson(b'{"type": "LineString", "coordinates": [[1, 2, 3], [3, 4.5, 5]]}')


def test_one_input(data: bytes) -> None:
    """Check one input (see the module docstring for its two forms)."""
    if data[:1] == b"M":
        _check_messagepack(data[1:])
    else:
        _check_document(data)
