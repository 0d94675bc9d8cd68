"""`read_positions`: the MessagePack decoder of the GeoJSON reader, against ormsgpack's own.

The reader must take every encoding MessagePack allows for what it accepts (not only
the ones ormsgpack writes: float32, non-minimal array headers), read exactly what
``ormsgpack.unpackb`` reads, and refuse anything else without reading past the bytes
it is given: truncated, corrupted or trailing bytes are refused, never a crash.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import ormsgpack
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rnsca.io.msgpack_decode import HAS_Z, MIXED, PARTIAL_Z, PLAIN, REFUSED, read_positions


def read(data: bytes, sizes, dim: int):
    """Return (result, positions, plain) of reading `data` as arrays of `sizes` positions."""
    sizes = np.asarray(sizes, dtype=np.int64)
    out = np.full((int(sizes.sum()), dim), np.nan)
    plain = np.zeros(sizes.shape[0], dtype=bool)
    result = read_positions(np.frombuffer(data, dtype=np.uint8), sizes, out, plain)
    return result, out, plain


def array_header(n: int, width: int) -> bytes:
    """The header of an array of `n` items, in fixarray (0), array16 (2) or array32 (4) form."""
    if width == 0:
        return bytes([0x90 | n])
    return (b"\xdc" + n.to_bytes(2, "big")) if width == 2 else (b"\xdd" + n.to_bytes(4, "big"))


def test_float32_and_every_array_header_form_are_read():
    position = array_header(2, 4) + b"\xca" + struct.pack(">f", 1.5) + b"\xcb" + \
        struct.pack(">d", -2.25)
    other = array_header(2, 2) + b"\x07" + b"\xd0\xfe"  # [7, -2] (an int8)
    data = array_header(1, 2) + array_header(2, 0) + position + other
    result, out, plain = read(data, [2], 2)
    assert result == MIXED and not plain[0]
    assert out.tolist() == [[1.5, -2.25], [7.0, -2.0]]


def test_plain_arrays_hold_only_float64_numbers_of_the_dimension():
    data = ormsgpack.packb([[[0.5, 1.5], [2.5, 3.5]], [[1.0, 2.0]]])
    result, out, plain = read(data, [2, 1], 2)
    assert result == PLAIN and plain.tolist() == [True, True]
    assert out.tolist() == [[0.5, 1.5], [2.5, 3.5], [1.0, 2.0]]


@pytest.mark.parametrize("data, sizes, dim", [
    (b"", [1], 2),
    (b"\x91", [1], 2),
    (b"\x91\x91\x92\xcb\x3f\xf0", [1], 2),  # a float cut short
    (b"\x91\x91\x92\x01\x02\x00", [1], 2),  # a byte left over
    (b"\x91\x91\x92\x01\xcd\x01", [1], 2),  # a uint16 cut short
    (b"\x91\x91\x92\x01\xdc\x00", [1], 2),  # an array16 header cut short
    (b"\x91\x91\x92\x01\xc3", [1], 2),  # true
    (b"\x91\x91\x92\x01\xc0", [1], 2),  # nil
    (b"\x91\x91\x92\x01\xa1a", [1], 2),  # a string
    (b"\x91\x91\x92\x01\x80", [1], 2),  # a map
    (b"\x91\x91\x92\x01\xcb\x7f\xf8\x00\x00\x00\x00\x00\x00", [1], 2),  # NaN
    (b"\x91\x91\x92\x01\xca\x7f\x80\x00\x00", [1], 2),  # float32 infinity
    (b"\x91\x91\x91\x01", [1], 3),  # 1 number in 3D
    (b"\x91\x91\x93\x01\x02\xc0", [1], 3),  # nil as Z
    (b"\x91\x92\x92\x01\x02", [1], 2),  # two positions said, one read
    (b"\x92\x91\x92\x01\x02", [1], 2),  # two arrays said, one given
])
def test_what_is_not_as_asked_is_refused(data, sizes, dim):
    assert read(data, sizes, dim)[0] == REFUSED


def test_three_numbers_in_2d_stop_the_read_to_read_again_in_3d():
    data = ormsgpack.packb([[[0.5, 1.5], [2.5, 3.5]], [[1.0, 2.0, 3.0], "not read"]])
    assert read(data, [2, 2], 2)[0] == HAS_Z


def test_two_numbers_in_3d_are_a_position_without_z():
    data = ormsgpack.packb([[[0.5, 1.5, 2.5]], [[1.0, 2.0], [3.0, 4.0, 5.0]]])
    result, out, plain = read(data, [1, 2], 3)
    assert result == PARTIAL_Z and plain.tolist() == [True, False]
    np.testing.assert_array_equal(out, [[0.5, 1.5, 2.5], [1.0, 2.0, np.nan], [3.0, 4.0, 5.0]])


def test_numbers_after_z_are_checked_then_dropped():
    result, out, plain = read(ormsgpack.packb([[[1.5, 2.5, 3.5, 4.5]]]), [1], 3)
    assert result == MIXED and out.tolist() == [[1.5, 2.5, 3.5]] and not plain[0]
    assert read(ormsgpack.packb([[[1.5, 2.5, 3.5, math.inf]]]), [1], 3)[0] == REFUSED
    assert read(ormsgpack.packb([[[1.5, 2.5, 3.5, "x"]]]), [1], 3)[0] == REFUSED


def unpack_whole(data: bytes):
    """Return the object `data` holds, or None if it holds none or has bytes after it.

    ``ormsgpack.unpackb`` ignores bytes after the object; MessagePack objects delimit
    themselves, so the object ends at the shortest prefix that decodes.
    """
    for end in range(1, len(data) + 1):
        try:
            value = ormsgpack.unpackb(data[:end])
        except (ormsgpack.MsgpackDecodeError, ValueError, TypeError):
            continue
        return value if end == len(data) else None
    return None


NUMBERS = st.one_of(st.floats(allow_nan=False, allow_infinity=False),
                    st.integers(-(2 ** 63), 2 ** 64 - 1))


def positions_of(value, dim):
    """Return the positions `value` (what unpackb gave) holds if the reader should take it."""
    if not isinstance(value, list):
        return None
    out = []
    for array in value:
        if not isinstance(array, list):
            return None
        for position in array:
            if not isinstance(position, list) or len(position) < dim or (
                    dim == 2 and len(position) > 2):
                return None
            if not all(type(v) in (int, float) and math.isfinite(v) for v in position):
                return None
            out.append([float(v) for v in position[:dim]])
    return out


@given(arrays=st.lists(st.lists(st.lists(NUMBERS, min_size=2, max_size=2), max_size=6),
                       min_size=1, max_size=4),
       cuts=st.lists(st.tuples(st.integers(0, 10 ** 6), st.integers(0, 255)), max_size=3),
       truncate=st.integers(0, 10 ** 6) | st.none())
def test_corrupted_bytes_are_read_as_ormsgpack_reads_them_or_refused(arrays, cuts, truncate):
    data = bytearray(ormsgpack.packb(arrays))
    for at, byte in cuts:  # overwrite a few bytes
        data[at % len(data)] = byte
    if truncate is not None:
        data = data[:truncate % (len(data) + 1)]
    sizes = [len(a) for a in arrays]
    result, out, _ = read(bytes(data), sizes, 2)
    value = unpack_whole(bytes(data))
    expected = None if value is None else positions_of(value, 2)
    if expected is not None and [len(a) for a in value] != sizes:
        expected = None
    if result in (REFUSED, HAS_Z):  # HAS_Z: a position of 3 or more numbers in 2D
        assert expected is None
    else:
        assert expected is not None
        np.testing.assert_array_equal(out, np.asarray(expected, dtype=np.float64).reshape(-1, 2))
