"""Decimal numbers to float64, correctly rounded: the Eisel-Lemire algorithm.

A decimal ``w * 10**q`` (``w`` an integer of at most 19 digits) becomes the nearest
float64, ties to even, with one or two 64 x 64 -> 128-bit multiplications by a table of
128-bit approximations of ``5**q``. Reference: D. Lemire, "Number parsing at a gigabyte
per second", Software: Practice and Experience 51(8), 2021; the algorithm as the
fast_float library writes it (``compute_float``), which N. Mushtak and D. Lemire, "Fast
number parsing without fallback" (2023), prove exact for every ``w < 2**64`` and ``q``
with no fallback. A decimal of more than 19 significant digits is read from its first
19 (``w``) and decided only when ``w`` and ``w + 1`` round alike (`decimal_to_double`
then says so), as fast_float does; the caller converts the rare others another way.

Why here and not pyarrow (an optional dependency, fast_float inside): converting while
the scan reads the digits added 0.13 s to reading 10.4M coordinates of 16-17 digits (the
scan 0.49 -> 0.61 s), where ``pyarrow.compute.cast`` of the same numbers as strings took
0.27 s, besides the copy of their texts it would need.

No 128-bit integers in Numba: products are put together from 32-bit halves. Every
constant is an ``np.uint64``: Numba types uint64 mixed with int64 as float64.
"""

from __future__ import annotations

import math

import numpy as np

from rnsca.kernels.jit import inlined

__all__ = ["POWERS_OF_FIVE", "SMALLEST_POWER", "LARGEST_POWER", "decimal_to_double"]

#: Below ``10**SMALLEST_POWER`` every decimal of at most 19 digits rounds to zero, above
#: ``10**LARGEST_POWER`` to infinity.
SMALLEST_POWER, LARGEST_POWER = -342, 308


def _powers_of_five() -> np.ndarray:
    """Return the (high, low) 64-bit words of the 128-bit approximation of each 5**q.

    Row ``q - SMALLEST_POWER``. For q >= 0, ``5**q`` shifted so its top bit is bit 127,
    truncated; for q < 0, ``2**b / 5**-q`` rounded up (floor plus one), likewise
    normalized: fast_float's table (script/table_generation.py), exact integers here.
    """
    rows = []
    for q in range(SMALLEST_POWER, 0):
        power = 5 ** -q
        bits = power.bit_length()  # 5**-q is no power of two: 2**(bits-1) < power < 2**bits
        scaled = (1 << (bits + 127 if q >= -27 else 2 * bits + 128)) // power + 1
        while scaled >= 1 << 128:
            scaled >>= 1
        rows.append(scaled)
    for q in range(0, LARGEST_POWER + 1):
        power = 5 ** q
        shift = 128 - power.bit_length()
        rows.append(power << shift if shift >= 0 else power >> -shift)
    mask = (1 << 64) - 1
    return np.array([[row >> 64, row & mask] for row in rows], dtype=np.uint64)


#: The table `decimal_to_double` multiplies by, (651, 2) uint64.
POWERS_OF_FIVE = _powers_of_five()

_LOW32 = np.uint64(0xFFFFFFFF)
_ALL_ONES = np.uint64(0xFFFFFFFFFFFFFFFF)
_U1 = np.uint64(1)
_U3 = np.uint64(3)
_U32 = np.uint64(32)
_U63 = np.uint64(63)
# The low bits of the first product that are below the 55 bits kept (53 + 2 for
# rounding): all ones means the truncated table could have carried into them.
_PRECISION_MASK = np.uint64(0x1FF)
_HIDDEN_BIT = np.uint64(1 << 52)
_MANTISSA_OVERFLOW = np.uint64(2 << 52)


@inlined
def _multiply(a, b):
    """Return the (high, low) 64-bit words of the 128-bit product of uint64 `a` and `b`."""
    a_low, a_high = a & _LOW32, a >> _U32
    b_low, b_high = b & _LOW32, b >> _U32
    low_low = a_low * b_low
    high_low = a_high * b_low
    # At most 2**64 - 1: (2**32 - 1)**2 + 2 * (2**32 - 1).
    middle = (low_low >> _U32) + (high_low & _LOW32) + a_low * b_high
    high = a_high * b_high + (high_low >> _U32) + (middle >> _U32)
    return high, (middle << _U32) | (low_low & _LOW32)


@inlined
def _leading_zeros(w):
    """Return the number of leading zero bits of a nonzero uint64 (a binary search)."""
    count = 0
    for width in (32, 16, 8, 4, 2, 1):
        if w >> np.uint64(64 - width) == 0:
            w = w << np.uint64(width)
            count += width
    return count


@inlined
def _eisel_lemire(w, q):
    """Return the nearest float64 to ``w * 10**q`` (uint64 w > 0, SMALLEST <= q <= LARGEST)."""
    lz = _leading_zeros(w)
    w = w << np.uint64(lz)
    row = q - SMALLEST_POWER
    high, low = _multiply(w, POWERS_OF_FIVE[row, 0])
    if high & _PRECISION_MASK == _PRECISION_MASK:
        # The bits kept may be off by one unit of the truncated table: add the product
        # by its low word (its high word only), carrying into `high`.
        carry_in, _ = _multiply(w, POWERS_OF_FIVE[row, 1])
        room = _ALL_ONES - low
        if carry_in > room:
            low = carry_in - room - _U1
            high += _U1
        else:
            low += carry_in
    upper_bit = high >> _U63
    shift = upper_bit + np.uint64(9)
    mantissa = high >> shift
    # floor(log2(10**q)) + 63 + 1023 (the bias), as fast_float's `power`.
    power2 = ((217706 * q) >> 16) + 63 + np.int64(upper_bit) - lz + 1023
    if power2 <= 0:
        # Subnormal (or zero): the 53 + 1 bits kept shifted down to the fixed exponent.
        # No tie to settle here: round to even happens only for -4 <= q <= 23.
        if -power2 + 1 >= 64:
            return 0.0
        mantissa = mantissa >> np.uint64(-power2 + 1)
        mantissa = (mantissa + (mantissa & _U1)) >> _U1
        return math.ldexp(float(mantissa), -1074)
    # A tie (the dropped bits exactly one half) is possible only where 5**q is exact
    # in 64 bits: there, round down to even instead of up.
    if low <= _U1 and -4 <= q <= 23 and mantissa & _U3 == _U1 \
            and (mantissa << shift) == high:
        mantissa = mantissa & ~_U1
    mantissa = (mantissa + (mantissa & _U1)) >> _U1
    if mantissa >= _MANTISSA_OVERFLOW:  # rounded up to the next power of two
        mantissa = _HIDDEN_BIT
        power2 += 1
    if power2 >= 0x7FF:
        return np.inf
    # mantissa holds the hidden bit: exact as a float64, and scaling by 2**k is exact.
    return math.ldexp(float(mantissa), int(power2) - 1075)


@inlined
def _scaled(w, q):
    """Return the nearest float64 to ``w * 10**q`` for any uint64 `w` and int `q`."""
    if w == 0 or q < SMALLEST_POWER:
        return 0.0
    if q > LARGEST_POWER:
        return np.inf
    return _eisel_lemire(w, q)


@inlined
def decimal_to_double(w, q, truncated):
    """Return (the float64 nearest ``w * 10**q``, whether it is decided).

    Parameters
    ----------
    w : uint64
        The first (at most 19) significant digits, as an integer.
    q : int64
        The power of ten of the last digit of `w`.
    truncated : bool
        Whether nonzero digits followed those of `w`: the number lies strictly between
        ``w * 10**q`` and ``(w + 1) * 10**q``, and is decided only if both round to the
        same float64 (rounding is monotonic); undecided (False, 0.0) otherwise.

    Returns
    -------
    value : float64
        Not negative; the caller applies the sign. Infinity past the largest float64.
    decided : bool
    """
    value = _scaled(w, q)
    if truncated and _scaled(w + _U1, q) != value:
        return 0.0, False
    return value, True
