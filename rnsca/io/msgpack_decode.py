"""Bulk helpers of the GeoJSON reader and writer.

Positions out of MessagePack bytes, and geometries that two ragged arrays hold alike.

`read_positions` decodes the MessagePack (https://msgpack.org, "spec.md") bytes of a list
of coordinate arrays, each a list of positions, each a list of numbers: the form in
which `rnsca.io.geojson` has ormsgpack flatten the lists a parsed document holds
(one C pass that writes every number with a tag naming its type). It checks what the
GeoJSON rules ask of each position and stops at the first thing it does not take, so
the caller can let the exact, slow validator name the problem.

`same_geometries` tells which geometries of two aligned ragged arrays are equal, part
for part and coordinate for coordinate: the writer reuses the input's own lists for them.
"""

import numpy as np

from rnsca.kernels.jit import inlined, scalar

__all__ = ["HAS_Z", "MIXED", "PARTIAL_Z", "PLAIN", "REFUSED", "read_positions",
           "same_geometries"]

#: `read_positions` results: every position read, and every array of positions is
#: `PLAIN` (only float64 numbers, exactly as many as the document's dimension) or not
#: (`MIXED`); `PARTIAL_Z`: not all plain either, and some position read in 3D had only
#: two numbers (its Z is NaN).
PLAIN, MIXED, PARTIAL_Z = 0, 1, 2
#: `read_positions` result: something the reader does not take (see its docstring).
REFUSED = -1
#: `read_positions` result when reading 2D: a position of three or more numbers, where
#: reading stopped; the document has Z, read it again in 3D.
HAS_Z = -2

# MessagePack type tags (first byte of an object).
_FIXARRAY, _ARRAY16, _ARRAY32 = 0x90, 0xDC, 0xDD
_FLOAT32, _FLOAT64 = 0xCA, 0xCB
_UINT8, _UINT16, _UINT32, _UINT64 = 0xCC, 0xCD, 0xCE, 0xCF
_INT8, _INT16, _INT32, _INT64 = 0xD0, 0xD1, 0xD2, 0xD3


@inlined
def _unsigned(data, at, size):
    """Return the big-endian unsigned integer of `size` bytes at `at` (fits the caller's checks)."""
    value = np.uint64(0)
    for k in range(size):
        value = (value << np.uint64(8)) | np.uint64(data[at + k])
    return value


@inlined
def _array_length(data, at):
    """Return (length, next offset) of the array header at `at`, or (-1, at) for another object."""
    end = data.shape[0]
    if at >= end:
        return -1, at
    tag = data[at]
    if (tag & 0xF0) == _FIXARRAY:
        return np.int64(tag & 0x0F), at + 1
    if tag == _ARRAY16 and at + 3 <= end:
        return np.int64(_unsigned(data, at + 1, 2)), at + 3
    if tag == _ARRAY32 and at + 5 <= end:
        return np.int64(_unsigned(data, at + 1, 4)), at + 5
    return -1, at


@inlined
def _other_number(data, at, bits32, float32):
    """Return (value, next offset) of a number other than a float64 at `at`, or (0.0, -1).

    `bits32` is a one-element uint32 array and `float32` its float view: they turn the
    bits of a float32 into its value.
    """
    end = data.shape[0]
    if at >= end:
        return 0.0, -1
    tag = np.int64(data[at])  # not uint8: `tag - _UINT8` below must not wrap
    if tag <= 0x7F:  # positive fixint
        return float(tag), at + 1
    if tag >= 0xE0:  # negative fixint
        return float(tag - 256), at + 1
    if tag == _FLOAT32 and at + 5 <= end:
        bits32[0] = np.uint32(_unsigned(data, at + 1, 4))
        return float(float32[0]), at + 5
    if _UINT8 <= tag <= _UINT64:
        size = 1 << (tag - _UINT8)
        if at + 1 + size <= end:
            return float(_unsigned(data, at + 1, size)), at + 1 + size
    if _INT8 <= tag <= _INT64:
        size = 1 << (tag - _INT8)
        if at + 1 + size <= end:
            raw = _unsigned(data, at + 1, size)
            if raw >> np.uint64(8 * size - 1) == 0:
                return float(raw), at + 1 + size
            # Two's complement: the magnitude of a negative number fits 64 bits unsigned,
            # and converting it rounds as converting the negative number would.
            mask = np.uint64(0xFFFFFFFFFFFFFFFF) >> np.uint64(64 - 8 * size)
            return -float(((raw ^ mask) + np.uint64(1)) & mask), at + 1 + size
    return 0.0, -1


@scalar
def read_positions(data, sizes, out, plain):
    """Read a MessagePack list of `len(sizes)` arrays of positions into `out`.

    Parameters
    ----------
    data : uint8 array
        The bytes: an array of arrays (array ``k`` of ``sizes[k]`` positions) of arrays of
        numbers, and nothing after it.
    sizes : int64 array
        The number of positions of each array.
    out : float64 array, shape (sum(sizes), dim)
        Filled with the positions (dim 2 or 3). In 3D, a position of two numbers gets
        Z = NaN (a 2D position in a document that mixes 2D and 3D ones).
    plain : bool array, shape (len(sizes),)
        Set to whether each array holds only float64 numbers, `dim` per position.

    Returns
    -------
    int
        `PLAIN` if every array is plain, `MIXED` if all were read but some are not,
        `PARTIAL_Z` if, besides, a position read in 3D had two numbers. `HAS_Z` (2D
        only) at the first position of three or more numbers: read again in 3D.
        `REFUSED` (``out`` and ``plain`` partly written) if anything is not as asked: a
        length other than `sizes` says, an object that is not an array or a number (nil,
        a boolean, a string, a map, ...), a non-finite number, a position of fewer than
        two numbers (in 3D, numbers after the third are checked, then dropped), or bytes
        left over or missing.
    """
    dim = out.shape[1]
    end = data.shape[0]
    bits64 = np.zeros(1, dtype=np.uint64)
    bits32 = np.zeros(1, dtype=np.uint32)
    float64, float32 = bits64.view(np.float64), bits32.view(np.float32)
    count, at = _array_length(data, 0)
    if count != sizes.shape[0]:
        return REFUSED
    row = 0
    result = PLAIN
    partial_z = False
    for k in range(sizes.shape[0]):
        length, at = _array_length(data, at)
        if length != sizes[k] or row + length > out.shape[0]:
            return REFUSED
        array_plain = True
        for _ in range(length):
            numbers, at = _array_length(data, at)
            # One comparison on the common path: a position of the document's dimension.
            if numbers != dim:
                if numbers < 2:  # also -1: not an array
                    return REFUSED
                if dim == 2:
                    return HAS_Z
                array_plain = False
                if numbers == 2:
                    out[row, 2] = np.nan
                    partial_z = True
            for axis in range(numbers):
                if at + 9 <= end and data[at] == _FLOAT64:
                    bits64[0] = _unsigned(data, at + 1, 8)
                    value = float64[0]
                    at += 9
                else:
                    value, at = _other_number(data, at, bits32, float32)
                    if at < 0:
                        return REFUSED
                    array_plain = False
                if not np.isfinite(value):
                    return REFUSED
                if axis < dim:
                    out[row, axis] = value
            row += 1
        plain[k] = array_plain
        if not array_plain:
            result = MIXED
    if at != data.shape[0] or row != out.shape[0]:
        return REFUSED
    return PARTIAL_Z if partial_z else result


@scalar
def same_geometries(coords, offsets, other_coords, other_offsets):
    """Return which geometries of two ragged arrays of one kind are equal.

    Parameters
    ----------
    coords, other_coords : float64 arrays, shape (n, dim)
    offsets, other_offsets : tuples of int64 arrays
        Innermost level first, as ``shapely.to_ragged_array`` gives them; the last
        arrays of both have one entry per geometry, plus one, and equal lengths.

    Returns
    -------
    bool array
        True for a geometry with the same number of parts at every level, of the same
        sizes, and the same coordinates (``==``, so 0.0 equals -0.0).
    """
    count = offsets[-1].shape[0] - 1
    same = np.zeros(count, dtype=np.bool_)
    depth = len(offsets)
    for i in range(count):
        lo, hi, other_lo, other_hi = i, i + 1, i, i + 1  # items of the level above
        equal = True
        for level in range(depth - 1, -1, -1):
            level_offsets, other_level = offsets[level], other_offsets[level]
            if hi - lo != other_hi - other_lo:
                equal = False
                break
            base, other_base = level_offsets[lo], other_level[other_lo]
            for k in range(1, hi - lo + 1):
                if level_offsets[lo + k] - base != other_level[other_lo + k] - other_base:
                    equal = False
                    break
            if not equal:
                break
            lo, hi = level_offsets[lo], level_offsets[hi]
            other_lo, other_hi = other_level[other_lo], other_level[other_hi]
        if equal:
            for row in range(hi - lo):
                for axis in range(coords.shape[1]):
                    if coords[lo + row, axis] != other_coords[other_lo + row, axis]:
                        equal = False
                        break
                if not equal:
                    break
        same[i] = equal
    return same
