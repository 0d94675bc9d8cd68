"""Bézier segments to SVG path data: choose commands, format numbers, lay out bytes.

`classify` picks each segment's command (L, H, V, Q, T, C, S) and whether each subpath
needs its moveto. `format_values` writes each number the commands need as compact
decimal text, one fixed-width row per number; the few it cannot round with certainty
are left (length 0) for the caller, who formats them with Python's correctly rounded
``repr`` or ``%g``. `write` then lays out the command letters and numbers of every path
in one byte buffer, in two passes with one body (count, prefix sum, write), one path
per ``prange`` iteration.

Rounding to p significant digits: ``a * 10**k`` (a = |x|) is computed as a
double-double from an exact Dekker product with 10**k held as a double-double (error
below 2**-100 relative), so its nearest integer, the p digits, is the correctly rounded
one, as in ``'%.{p}g' % x``, unless a half-integer lies within 2**-40 of it (a tie or a
near tie): then the number is left to Python. The shortest form that reads back (the
digits of ``repr``): at 17 digits the interval of decimals that round to x (half the
gap to each neighbouring double, the gap below a power of two being half the gap
above) always holds an integer; the shortest decimal is the largest power of ten with
a multiple in that interval, and among those multiples the one nearest x. An interval
end within the error of an integer (where round-half-even decides) is left to Python.
Magnitudes outside 1e-280..1e280 are left to Python too.
"""

import math
from fractions import Fraction
from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels.jit import borrowing, inlined, parallel, scalar
from rnsca.kernels.outcode import two_product as _two_product

__all__ = [
    "TEXT_WIDTH",
    "KIND_LETTERS",
    "NUMBER_COUNT",
    "COLUMNS",
    "classify",
    "format_values",
    "write",
]

# Segment kinds and their command letters.
L, H, V, Q, T, C, S = 0, 1, 2, 3, 4, 5, 6
KIND_LETTERS = np.frombuffer(b"LHVQTCS", dtype=np.uint8).copy()
#: Numbers each kind writes.
NUMBER_COUNT = np.array([2, 1, 1, 4, 2, 6, 4], dtype=np.int64)
#: Which of a segment's 8 control values (x0 y0 x1 y1 x2 y2 x3 y3; row 3 is always the
#: end point) each kind writes, in order.
COLUMNS = np.zeros((7, 8), dtype=np.bool_)
for _kind, _columns in ((L, (6, 7)), (H, (6,)), (V, (7,)), (Q, (2, 3, 6, 7)), (T, (6, 7)),
                        (C, (2, 3, 4, 5, 6, 7)), (S, (4, 5, 6, 7))):
    COLUMNS[_kind, list(_columns)] = True

#: Bytes per formatted number: the longest compact form of a float64 with up to 17
#: digits is 23 ("-12345678901234567e-324").
TEXT_WIDTH = 24

# The columns each kind writes, as lists padded with -1 (for the kernels).
_COLUMN_LIST = np.full((7, 6), -1, dtype=np.int64)
for _kind in range(7):
    _cols = np.flatnonzero(COLUMNS[_kind])
    _COLUMN_LIST[_kind, :_cols.shape[0]] = _cols

_POW10_INT = np.array([10**k for k in range(19)], dtype=np.int64)

# Powers of ten as double-doubles, 10**k = _P10_HI[k - _P10_MIN] + _P10_LO[...] within
# 2**-106 relative: hi is 10**k correctly rounded, lo the rounded remainder.
_P10_MIN = -300
_P10_MAX = 300
_P10_HI = np.empty(_P10_MAX - _P10_MIN + 1)
_P10_LO = np.empty(_P10_MAX - _P10_MIN + 1)
for _k in range(_P10_MIN, _P10_MAX + 1):
    _exact = Fraction(10) ** _k
    _P10_HI[_k - _P10_MIN] = float(_exact)
    _P10_LO[_k - _P10_MIN] = float(_exact - Fraction(_P10_HI[_k - _P10_MIN]))
# Magnitudes the kernel formats: with up to 17 digits, the scale 10**k stays within the
# table and the Veltkamp split of both factors cannot overflow. Others go to Python.
_SMALLEST = 1e-280
_LARGEST = 1e280
_LOG10_2 = 0.30102999566398120

_M = 77
_Z = 90
_SPACE = 32


@scalar
def _reflects(controls, i, row, prev_row):
    """Return whether control `row` of segment i is what the reader infers for S or T.

    That is the reflection ``2 * start - p`` of control `prev_row` of segment i - 1
    (the reader's exact expression, so the test is exact), or the start point itself
    when `prev_row` is -1 (S or T after another command).
    """
    x0 = controls[i, 0, 0]
    y0 = controls[i, 0, 1]
    if prev_row < 0:
        return controls[i, row, 0] == x0 and controls[i, row, 1] == y0
    return (controls[i, row, 0] == 2.0 * x0 - controls[i - 1, prev_row, 0]
            and controls[i, row, 1] == 2.0 * y0 - controls[i - 1, prev_row, 1])


@parallel
def classify(controls, degree, subpath_offsets, closed, start, path_offsets, t_after_t):
    """Return ``(kind, with_moveto)``: int8 (m,) segment kinds, bool (k,) per subpath.

    A subpath needs no moveto when the previous subpath of its path was closed, it
    starts where that one started and it has a segment or is closed (the reader then
    starts it at that point; an empty open one would vanish). Without `t_after_t`, a
    T never follows a T: the reader computes a T's control point from the previous
    one, so with rounded numbers a chain of T would add up the rounding errors.
    """
    m = controls.shape[0]
    k = closed.shape[0]
    n = path_offsets.shape[0] - 1
    kind = np.empty(m, dtype=np.int8)
    with_moveto = np.ones(k, dtype=np.bool_)
    for p in prange(n):
        for s in range(path_offsets[p], path_offsets[p + 1]):
            first = subpath_offsets[s]
            last = subpath_offsets[s + 1]
            if (s > path_offsets[p] and closed[s - 1] and start[s, 0] == start[s - 1, 0]
                    and start[s, 1] == start[s - 1, 1] and (last > first or closed[s])):
                with_moveto[s] = False
            for i in range(first, last):
                d = degree[i]
                prev = degree[i - 1] if i > first else 0
                if d == 1:
                    if controls[i, 3, 1] == controls[i, 0, 1]:
                        kind[i] = H
                    elif controls[i, 3, 0] == controls[i, 0, 0]:
                        kind[i] = V
                    else:
                        kind[i] = L
                elif d == 2:
                    smooth = _reflects(controls, i, 1, 1 if prev == 2 else -1)
                    if smooth and prev == 2 and not t_after_t and kind[i - 1] == T:
                        smooth = False
                    kind[i] = T if smooth else Q
                else:
                    smooth = _reflects(controls, i, 1, 2 if prev == 3 else -1)
                    kind[i] = S if smooth else C
    return kind, with_moveto


@scalar
def _scaled(a, k):
    """Return ``a * 10**k`` as a double-double (hi, lo), relative error below 2**-100."""
    i = k - _P10_MIN
    hi, lo = _two_product(a, _P10_HI[i])
    lo += a * _P10_LO[i]
    s = hi + lo
    return s, lo - (s - hi)


# Outcomes of `_nearest_digits`.
_DIGITS_OK = 0
_NEAR_TIE = 1
_BEYOND = 2


@scalar
def _nearest_digits(a, p, e):
    """Return ``(status, n, k, hi, lo)``: n, of p digits, the integer nearest a * 10**k.

    `e` estimates floor(log10(a)), a > 0. ``hi + lo`` is ``a * 10**k`` as a
    double-double. Status `_NEAR_TIE`: a half-integer lies too close to ``a * 10**k``
    to tell the rounding (n is then not set); `_BEYOND`: the scale is beyond the table.
    """
    low = _POW10_INT[p - 1]
    k = 0
    for _ in range(3):
        k = p - 1 - e
        if k < _P10_MIN or k > _P10_MAX:
            return _BEYOND, 0, 0, 0.0, 0.0
        hi, lo = _scaled(a, k)
        f = math.floor(hi)
        frac = (hi - f) + lo
        # Above 2**53 hi is an integer and lo may exceed 1 (up to half hi's ulp): move
        # the whole part of the fraction into the integer, in integer arithmetic.
        whole = math.floor(frac)
        frac -= whole
        # hi + lo is within 2**-100 of the product, which is below 2**57: 2**-40 is a
        # wide margin for the fraction.
        if abs(frac - 0.5) <= 2.0**-40:
            return _NEAR_TIE, 0, k, hi, lo
        below = int(f) + int(whole)            # floor(a * 10**k)
        if below >= 10 * low:      # p + 1 digits or more: e was too small
            e += 1
        elif below < low:          # fewer than p digits: e was too large
            e -= 1
        else:
            n = below + (1 if frac > 0.5 else 0)
            if n == 10 * low:      # 99.96 to 3 digits: 100, one exponent higher
                n = low
                k -= 1
                hi, lo = _scaled(a, k)
            return _DIGITS_OK, n, k, hi, lo
    return _BEYOND, 0, 0, 0.0, 0.0


@scalar
def _minus(n, hi, lo):
    """Return ``n - (hi + lo)`` for an int n below 2**62, to about 2**-100 of n."""
    nh = float(n)
    nl = float(n - int(nh))   # exact: n - nh is a small integer
    return (nh - hi) + (nl - lo)


@scalar
def _half_gap(a, k, below):
    """Return half the gap from a to its neighbouring double, times 10**k (to 2**-52).

    Below a power of two the gap is half the gap above.
    """
    mantissa, exponent = math.frexp(a)
    half_gap = math.ldexp(1.0, exponent - 54)
    if below and mantissa == 0.5:
        half_gap *= 0.5
    i = k - _P10_MIN
    return half_gap * _P10_HI[i] + half_gap * _P10_LO[i]


@scalar
def _put_digits(text, row, n, nd, first, split):
    """Write the nd digits of n at ``text[row, first:]``, a '.' after `split` of them.

    Digits come out least significant first (division by the constant 10 is cheap);
    with ``split < nd`` the last ``nd - split`` digits move one place right for the '.'.
    """
    for i in range(nd):           # i: digit index from the right
        at = first + nd - 1 - i
        if i < nd - split:
            at += 1
        text[row, at] = 48 + n % 10
        n //= 10
    if split < nd:
        text[row, first + split] = 46


@scalar
def _put_text(text, row, negative, n, q):
    """Write the compact form of ``-?n * 10**q`` into ``text[row]``; return its length.

    Trailing zeros of n move into q; the positional form (``.05``, ``120``) is kept
    unless the exponent form (``5e-7``, ``12e5``) is shorter.
    """
    while n % 10 == 0:
        n //= 10
        q += 1
    nd = 1
    while nd < 18 and n >= _POW10_INT[nd]:
        nd += 1
    positional = nd + q if q >= 0 else (nd + 1 if -q < nd else 1 - q)
    aq = abs(q)
    q_digits = 1 if aq < 10 else (2 if aq < 100 else 3)
    at = 0
    if negative:
        text[row, 0] = 45          # '-'
        at = 1
    if positional <= nd + 1 + q_digits + (1 if q < 0 else 0):
        if q >= 0:                 # 120
            _put_digits(text, row, n, nd, at, nd)
            for j in range(q):
                text[row, at + nd + j] = 48
        elif -q < nd:              # 1.25
            _put_digits(text, row, n, nd, at, nd + q)
        else:                      # .0025
            text[row, at] = 46
            for j in range(-q - nd):
                text[row, at + 1 + j] = 48
            _put_digits(text, row, n, nd, at + 1 - q - nd, nd)
        return at + positional
    _put_digits(text, row, n, nd, at, nd)   # 25e-7
    at += nd
    text[row, at] = 101            # 'e'
    at += 1
    if q < 0:
        text[row, at] = 45
        at += 1
    for j in range(q_digits):
        text[row, at + q_digits - 1 - j] = 48 + aq % 10
        aq //= 10
    return at + q_digits


@scalar
def _floor_sum(hi, lo, add):
    """Return (floor, fraction) of ``hi + lo + add``: an int, and a double in [0, 1).

    ``hi + lo`` is a double-double below 2**62, `add` a small correction.
    """
    f = math.floor(hi)
    frac = (hi - f) + lo + add
    whole = math.floor(frac)
    return int(f) + int(whole), frac - whole


@scalar
def _widest_power(hi, lo, low_add, up_add, margin):
    """Return ``(below, u, j, close)``: the largest j with a multiple of 10**j in (L, U).

    L and U are ``hi + lo`` plus `low_add` and `up_add`; the multiples are m * 10**j
    for m in below + 1 .. u. j is -1 when no integer lies in between. `close` tells
    whether L or U is within `margin` of an integer.
    """
    below, low_frac = _floor_sum(hi, lo, low_add)
    u, u_frac = _floor_sum(hi, lo, up_add)
    close = min(low_frac, 1.0 - low_frac, u_frac, 1.0 - u_frac) <= margin
    if u_frac == 0.0:
        u -= 1                  # U itself is excluded
    if below >= u:
        return 0, 0, -1, close
    j = 0
    while u // 10 > below // 10:
        u //= 10
        below //= 10
        j += 1
    return below, u, j, close


@scalar
def _shortest(a, e):
    """Return ``(ok, n, q)``: the shortest decimal ``n * 10**q`` that reads as a > 0.

    Among the shortest, the nearest to a (what ``repr`` writes). At 17 digits the
    doubles' rounding interval of a, ``[L, U]`` in units of the 17th digit, always
    holds an integer; the shortest decimal is the largest power of ten 10**j with a
    multiple in it, found by dividing both ends by 10 until no multiple is left
    between them. ok is False when an end, or the rounding, is too close to tell.
    """
    status, n17, k, hi, lo = _nearest_digits(a, 17, e)
    if status != _DIGITS_OK:
        return False, 0, 0
    margin = hi * 2.0**-90 + 2.0**-60
    up = _half_gap(a, k, False)
    down = _half_gap(a, k, True)
    # Integers strictly inside (L, U), and those within the margin of it: a decimal
    # on an end reads as a only if a's last bit is even, too close to decide here.
    below, u, j, close = _widest_power(hi, lo, -down + margin, up - margin, 2.0 * margin)
    if j < 0:
        return False, 0, 0
    if close and _widest_power(hi, lo, -down - margin, up + margin, 0.0)[2] != j:
        return False, 0, 0
    # Multiples of 10**j in the interval: m * 10**j for m in below+1..u; take the one
    # nearest a: round(S / 10**j), clamped into that range.
    r = -_minus(n17, hi, lo)                 # S - n17, within [-1/2, 1/2]
    if j == 0:
        m = n17
    else:
        power = _POW10_INT[j]
        m = n17 // power
        twice = 2 * (n17 - m * power) - power   # 2 * remainder - 10**j, even
        if twice > 0 or (twice == 0 and r > margin):
            m += 1
        elif twice == 0 and r >= -margin:
            return False, 0, 0               # a tie between two candidates
    if m <= below:
        m = below + 1
    elif m > u:
        m = u
    return True, m, j - k


@scalar
def _format(x, precision, text, row):
    """Write x's compact text into ``text[row]``; return its length, or 0 for Python.

    `precision` is the number of significant digits (1 to 17), or 0 for the shortest
    form that reads back as x.
    """
    if x == 0.0:
        text[row, 0] = 48          # '0', also for -0.0
        return 1
    a = abs(x)
    if not _SMALLEST <= a <= _LARGEST:
        return 0
    # floor(log10(a)) or one less, from the binary exponent (no log10); the digit
    # search corrects it.
    e = int(math.floor((math.frexp(a)[1] - 1) * _LOG10_2))
    if a >= _P10_HI[e + 1 - _P10_MIN]:
        e += 1
    if precision > 0:
        status, n, k, hi, lo = _nearest_digits(a, precision, e)
        return _put_text(text, row, x < 0.0, n, -k) if status == _DIGITS_OK else 0
    ok, n, q = _shortest(a, e)
    return _put_text(text, row, x < 0.0, n, q) if ok else 0


@parallel
def format_values(controls, start, kind, with_moveto, seg_value_offsets,
                  start_value_offsets, precision):
    """Return ``(values, text, length)`` of every number the paths write, in order.

    Segment i writes ``values[seg_value_offsets[i]:seg_value_offsets[i + 1]]`` (its
    `COLUMNS`), the moveto of subpath s ``values[start_value_offsets[s]:...]``. Row r of
    `text` (uint8, `TEXT_WIDTH` wide) holds the compact text of ``values[r]`` in its
    first ``length[r]`` bytes; length 0 leaves the row to the caller. `precision` is 1
    to 17 significant digits, or 0 for the shortest round-trip form.
    """
    m = kind.shape[0]
    k = with_moveto.shape[0]
    nv = start_value_offsets[k]
    values = np.empty(nv, dtype=np.float64)
    text = np.empty((nv, TEXT_WIDTH), dtype=np.uint8)
    length = np.zeros(nv, dtype=np.int8)
    for i in prange(m):
        r = seg_value_offsets[i]
        for j in range(6):
            col = _COLUMN_LIST[kind[i], j]
            if col < 0:
                break
            x = controls[i, col // 2, col % 2]
            values[r] = x
            length[r] = _format(x, precision, text, r)
            r += 1
    for s in prange(k):
        if with_moveto[s]:
            for j in range(2):
                r = start_value_offsets[s] + j
                values[r] = start[s, j]
                length[r] = _format(start[s, j], precision, text, r)
    return values, text, length


@inlined
def _put_byte(out, n, write, c):
    """Append byte c at ``out[n]`` (with `write`); return the new length."""
    if write:
        out[n] = c
    return n + 1


@scalar
def _number(out, n, write, text, length, r, after_number, after_fraction):
    """Append number row r, after a space if the reader needs one; return the new length.

    No space is needed before a '-', nor before a '.' when the previous number has a
    fraction ("1.5.5" is 1.5 then .5).
    """
    c = text[r, 0]
    if after_number and c != 45 and not (c == 46 and after_fraction):
        n = _put_byte(out, n, write, _SPACE)
    size = int(length[r])
    if write:
        for j in range(size):
            out[n + j] = text[r, j]
    return n + size


@scalar
def _ends_in_fraction(text, length, r):
    """Return whether number row r has a '.' and no exponent ("1e5.5" is avoided)."""
    dot = False
    for j in range(length[r]):
        if text[r, j] == 101:
            return False
        dot |= text[r, j] == 46
    return dot


class _Layout(NamedTuple):
    """What `write` lays out: the commands of every path and the text of their numbers."""

    kind: np.ndarray                 # int8 (m,) each segment's command (`classify`)
    with_moveto: np.ndarray          # bool (k,) whether each subpath writes its moveto
    subpath_offsets: np.ndarray      # int64 (k + 1,)
    closed: np.ndarray               # bool (k,)
    path_offsets: np.ndarray         # int64 (n + 1,)
    seg_value_offsets: np.ndarray    # int64 (m + 1,) each segment's rows of text
    start_value_offsets: np.ndarray  # int64 (k + 1,) each moveto's rows of text
    text: np.ndarray                 # uint8 (rows, TEXT_WIDTH) (`format_values`)
    length: np.ndarray               # int8 (rows,)


@inlined
def _numbers(out, n, write, text, length, first, last, after_number, after_fraction):
    """Append number rows ``first:last``; return ``(n, after_fraction)`` after them.

    `after_number` and `after_fraction` say what precedes the first row: a number (of
    the same command, its letter left out) and whether it has a fraction. Returned: the
    new length and whether the last row has a fraction (`_ends_in_fraction`). Inlined
    into `_write_path`, which calls it per segment (a call was 9% slower).
    """
    for r in range(first, last):
        n = _number(out, n, write, text, length, r, after_number, after_fraction)
        after_number = True
        after_fraction = _ends_in_fraction(text, length, r)
    return n, after_fraction


@borrowing
def _write_path(p, write, out, at, layout):
    """Return the byte length of path p's data; with `write`, write it at ``out[at:]``.

    `borrowing`: the loops read their arrays from `layout`, each read a reference
    counted with Numba's runtime (measured: 5% slower).
    """
    text = layout.text        # the numbers' rows, for `_numbers`
    length = layout.length
    n = at
    letter = 0                # the command a number without a letter would continue
    after_fraction = False
    for s in range(layout.path_offsets[p], layout.path_offsets[p + 1]):
        if layout.with_moveto[s]:
            n = _put_byte(out, n, write, _M)
            n, after_fraction = _numbers(out, n, write, text, length,
                                         layout.start_value_offsets[s],
                                         layout.start_value_offsets[s + 1], False,
                                         after_fraction)
            letter = KIND_LETTERS[L]  # pairs after a moveto are linetos
        for i in range(layout.subpath_offsets[s], layout.subpath_offsets[s + 1]):
            c = KIND_LETTERS[layout.kind[i]]
            repeated = c == letter    # the letter is left out: numbers follow numbers
            if not repeated:
                n = _put_byte(out, n, write, c)
                letter = c
            n, after_fraction = _numbers(out, n, write, text, length,
                                         layout.seg_value_offsets[i],
                                         layout.seg_value_offsets[i + 1], repeated,
                                         after_fraction)
        if layout.closed[s]:
            n = _put_byte(out, n, write, _Z)
            letter = _Z               # Z does not repeat: the next command has a letter
    return n - at


@parallel
def write(kind, with_moveto, subpath_offsets, closed, path_offsets, seg_value_offsets,
          start_value_offsets, text, length):
    """Return ``(data, bounds)``: uint8 ASCII of all paths and each one's byte bounds.

    The numbers are the rows of `text` that `format_values` laid out (every length
    filled in).
    """
    n = path_offsets.shape[0] - 1
    layout = _Layout(kind, with_moveto, subpath_offsets, closed, path_offsets,
                     seg_value_offsets, start_value_offsets, text, length)
    no_out = np.empty(0, dtype=np.uint8)
    sizes = np.zeros(n + 1, dtype=np.int64)
    for p in prange(n):
        sizes[p + 1] = _write_path(np.int64(p), False, no_out, 0, layout)
    bounds = np.cumsum(sizes)
    out = np.empty(bounds[n], dtype=np.uint8)
    for p in prange(n):
        _write_path(np.int64(p), True, out, bounds[p], layout)
    return out, bounds
