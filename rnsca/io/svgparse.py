"""SVG path data to Bézier segments: tokenize, convert numbers, build segments.

The input is the UTF-8 bytes of many path strings laid end to end, with
``path_bytes[i]:path_bytes[i + 1]`` the bytes of path i. Every path is parsed on its
own, so the drivers run one path per ``prange`` iteration. Variable-size outputs use two
passes with one body and a ``write`` flag (count, prefix sum in the caller, write):

1. `count_tokens` / `write_tokens`: check the grammar of SVG 2 (section 9.3.9, "The
   grammar for path data") and split each path into argument groups (one command letter
   per group, implicit repetition spelled out: the pairs after ``M`` become ``L``) and
   numbers (arc flags included, as 0.0 or 1.0). A number is converted in the kernel when
   Clinger's fast path applies (below); any other is written as 0.0 and its byte span
   recorded for the caller, who converts it with Python's correctly rounded parser.
2. `count_segments` / `write_segments`: interpret the groups as SVG does (relative
   coordinates, ``H``/``V``, the reflected control points of ``S``/``T``, ``Z``, arcs
   converted to cubic Béziers) into the columnar layout of
   `rnsca.io.svgpath.PathArrays`.

Number conversion (Clinger 1990, "How to read floating point numbers accurately"): a
decimal ``m * 10**e`` whose integer mantissa ``m`` is below 2**53 and with
``|e| <= 22`` is one IEEE multiplication or division of two exact doubles (10**22 is the
largest exact power of ten), hence correctly rounded, bit for bit what Python's
``float()`` gives. Realistic path data (fonts, icons: a few digits) always takes this
path; 16- and 17-digit numbers (``repr`` output) and large exponents fall back. So do
numbers beyond float64's range: the caller finds them infinite and reports them, after
every grammar error.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels.jit import borrowing, inlined, parallel, scalar

__all__ = [
    "ERROR_MESSAGES",
    "OUT_OF_RANGE",
    "count_tokens",
    "write_tokens",
    "count_segments",
    "write_segments",
    "arc_error",
]

# Error codes of the tokenizer (0: no error); `ERROR_MESSAGES` says what was expected.
# OUT_OF_RANGE is the caller's, for a number that converts to infinity.
EXPECTED_MOVETO = 1
EXPECTED_NUMBER = 2
EXPECTED_DIGIT = 3
EXPECTED_EXPONENT_DIGIT = 4
EXPECTED_FLAG = 5
EXPECTED_NUMBER_OR_COMMAND = 6
EXPECTED_COMMAND = 7
OUT_OF_RANGE = 8

ERROR_MESSAGES = {
    EXPECTED_MOVETO: "expected a moveto command ('M' or 'm')",
    EXPECTED_NUMBER: "expected a number",
    EXPECTED_DIGIT: "expected a digit",
    EXPECTED_EXPONENT_DIGIT: "expected a digit in the exponent",
    EXPECTED_FLAG: "expected an arc flag ('0' or '1')",
    EXPECTED_NUMBER_OR_COMMAND: "expected a number, a command letter or the end of the path",
    EXPECTED_COMMAND: "expected a command letter or the end of the path",
    OUT_OF_RANGE: "number out of range",
}

# Columns of the per-path rows `count_tokens` returns.
NUMBERS, GROUPS, FALLBACKS, ERROR, ERROR_AT = 0, 1, 2, 3, 4

# Character classes, one byte per character code; bytes >= 0x80 (non-ASCII) are in no
# class, so they stop the tokenizer with an error like any other stray character.
_WSP = 1       # SVG 2 wsp: tab, line feed, form feed, carriage return, space
_DIGIT = 2
_NUMBER = 4    # may start a number: digit, sign, '.'
_CLASS = np.zeros(256, dtype=np.uint8)
for _c in b"\t\n\x0c\r ":
    _CLASS[_c] = _WSP
for _c in b"0123456789":
    _CLASS[_c] = _DIGIT | _NUMBER
for _c in b"+-.":
    _CLASS[_c] = _NUMBER

# Arguments per command letter; -1 for a byte that is no command.
_ARGS = np.full(256, -1, dtype=np.int8)
for _letters, _n in ((b"Zz", 0), (b"HhVv", 1), (b"MmLlTt", 2), (b"SsQq", 4), (b"Cc", 6),
                     (b"Aa", 7)):
    for _c in _letters:
        _ARGS[_c] = _n

# The exact powers of ten in float64 (10**22 is the largest; 10**23 is not a double).
_POW10 = np.array([10.0**k for k in range(23)])
# The fast path needs an integer mantissa that is exact in float64.
_TWO_53 = 2**53
# Significant digits kept in the int64 mantissa; more digits mean the fallback (such a
# mantissa is >= 10**17 > 2**53, outside the fast path anyway), and no overflow.
_MAX_DIGITS = 18
# Decimal exponents are accumulated only up to this magnitude (larger ones overflow or
# underflow any double anyway), so no digit string can overflow the int64 exponent.
_EXPONENT_CAP = 100_000

_COMMA = 44
_DOT = 46
_MINUS = 45
_PLUS = 43
_LOWER_E = 101
_UPPER_E = 69
_ZERO = 48
_ONE = 49
_CASE_BIT = 32  # ASCII lower case = upper case | 32


@scalar
def _skip_wsp(buf, i, last):
    while i < last and _CLASS[buf[i]] == _WSP:
        i += 1
    return i


@scalar
def _skip_comma_wsp(buf, i, last):
    """Skip the optional ``comma_wsp`` of the grammar: ``wsp* (',' wsp*)?``."""
    i = _skip_wsp(buf, i, last)
    if i < last and buf[i] == _COMMA:
        i = _skip_wsp(buf, i + 1, last)
    return i


@inlined
def _scan_digits(buf, i, last, mantissa, n_kept):
    """Append the digits at ``buf[i:]`` to `mantissa`, which keeps `_MAX_DIGITS`.

    Returns ``(end, mantissa, n_kept, n_read)``: the index after the digits, the
    mantissa and its count of significant digits (leading zeros are not kept), and how
    many digits were read before it was full; the other ``end - i - n_read`` are dropped.
    Inlined: as a call it cost the tokenizer 8% more instructions.
    """
    n_read = 0
    while i < last and _CLASS[buf[i]] & _DIGIT:
        if n_kept < _MAX_DIGITS:
            d = int(buf[i]) - _ZERO
            if n_kept > 0 or d != 0:
                mantissa = mantissa * 10 + d
                n_kept += 1
            n_read += 1
        i += 1
    return i, mantissa, n_kept, n_read


@scalar
def _scan_number(buf, i, last):
    """Scan the number starting at ``buf[i]`` (a digit, sign or '.').

    Returns ``(end, error, value, exact)``: the index after the number, an error code
    (0, or a code with ``end`` the offending index), the value, and whether the value is
    the correctly rounded one (Clinger's fast path). Grammar (SVG 1.1 / CSS numbers):
    ``sign? (digits ('.' digits?)? | '.' digits) ([eE] sign? digits)?``.
    """
    negative = buf[i] == _MINUS
    if buf[i] == _MINUS or buf[i] == _PLUS:
        i += 1
    first = i
    i, mantissa, n_kept, n_read = _scan_digits(buf, i, last, 0, 0)
    n_digits = i - first
    # value = mantissa * 10**exponent: each integer digit dropped is a factor of ten,
    # each fraction digit kept a tenth.
    exponent = n_digits - n_read
    if i < last and buf[i] == _DOT:
        first = i + 1
        i, mantissa, n_kept, n_fraction = _scan_digits(buf, first, last, mantissa, n_kept)
        exponent -= n_fraction
        n_read += n_fraction
        n_digits += i - first
    dropped = n_digits > n_read   # a significant digit did not fit in `mantissa`
    if n_digits == 0:
        return i, EXPECTED_DIGIT, 0.0, False
    if i < last and (buf[i] == _LOWER_E or buf[i] == _UPPER_E):
        i += 1
        exponent_negative = False
        if i < last and (buf[i] == _MINUS or buf[i] == _PLUS):
            exponent_negative = buf[i] == _MINUS
            i += 1
        if i >= last or not _CLASS[buf[i]] & _DIGIT:
            return i, EXPECTED_EXPONENT_DIGIT, 0.0, False
        e = 0
        while i < last and _CLASS[buf[i]] & _DIGIT:
            if e < _EXPONENT_CAP:
                e = e * 10 + (int(buf[i]) - _ZERO)
            i += 1
        exponent += -e if exponent_negative else e
    if mantissa == 0:
        # Zero with any exponent ("0e999"); `dropped` is impossible without a kept digit.
        return i, 0, -0.0 if negative else 0.0, True
    value = 0.0
    exact = False
    if not dropped and mantissa < _TWO_53:
        if 0 <= exponent <= 22:
            value = float(mantissa) * _POW10[exponent]
            exact = True
        elif -22 <= exponent < 0:
            value = float(mantissa) / _POW10[-exponent]
            exact = True
        elif 22 < exponent <= 22 + 15:
            # Clinger's extension: move the excess power of ten into the mantissa
            # while it stays an exact integer ("1234e25" = 1234000 * 1e22).
            scaled = mantissa
            k = exponent - 22
            while k > 0 and scaled < _TWO_53:
                scaled *= 10
                k -= 1
            if scaled < _TWO_53:
                value = float(scaled) * _POW10[22]
                exact = True
    if negative:
        value = -value
    return i, 0, value, exact


@borrowing
def _tokenize(buf, first, last, write, nums, num_at, cmds, cmd_at, fallback, fallback_at):
    """Check and split the path ``buf[first:last]`` into argument groups and numbers.

    Returns ``(n_numbers, n_groups, n_fallbacks, error, error_at)``. With `write`, the
    numbers go to ``nums[num_at:]``, the group letters to ``cmds[cmd_at:]`` and the rows
    ``(start, end, number index)`` of numbers the caller must convert to
    ``fallback[fallback_at:]``; without it, nothing is written (the arrays may be empty).
    Every step advances ``i`` or returns, so no input can make it loop forever.
    `borrowing`, so its calls per number count no references to `buf` (measured: 3 to
    8% faster).
    """
    n_nums = 0
    n_cmds = 0
    n_fb = 0
    i = _skip_wsp(buf, first, last)
    if i == last:
        return 0, 0, 0, 0, 0   # empty path data: valid, renders nothing
    if buf[i] != 77 and buf[i] != 109:   # 'M', 'm'
        return 0, 0, 0, EXPECTED_MOVETO, i
    while True:
        cmd = buf[i]                      # a command letter (checked by the caller)
        n_args = _ARGS[cmd]
        i += 1
        if n_args == 0:                   # Z or z: no arguments, no repetition
            if write:
                cmds[cmd_at + n_cmds] = cmd
            n_cmds += 1
            i = _skip_wsp(buf, i, last)
            if i == last:
                break
            if _ARGS[buf[i]] < 0:
                return n_nums, n_cmds, n_fb, EXPECTED_COMMAND, i
            continue
        i = _skip_wsp(buf, i, last)
        group = cmd
        is_arc = (cmd | _CASE_BIT) == 97  # 'a'
        while True:                       # one argument group per iteration
            if write:
                cmds[cmd_at + n_cmds] = group
            n_cmds += 1
            for a in range(n_args):
                if a > 0:
                    i = _skip_comma_wsp(buf, i, last)
                if is_arc and (a == 3 or a == 4):
                    # Flags are single characters, so "a1 1 0 00 1 1" reads two flags.
                    if i < last and (buf[i] == _ZERO or buf[i] == _ONE):
                        if write:
                            nums[num_at + n_nums] = float(int(buf[i]) - _ZERO)
                        n_nums += 1
                        i += 1
                        continue
                    return n_nums, n_cmds, n_fb, EXPECTED_FLAG, i
                if i >= last or not _CLASS[buf[i]] & _NUMBER:
                    return n_nums, n_cmds, n_fb, EXPECTED_NUMBER, i
                end, error, value, exact = _scan_number(buf, i, last)
                if error != 0:
                    return n_nums, n_cmds, n_fb, error, end
                if write:
                    nums[num_at + n_nums] = value
                    if not exact:
                        row = fallback_at + n_fb
                        fallback[row, 0] = i
                        fallback[row, 1] = end
                        fallback[row, 2] = num_at + n_nums
                if not exact:
                    n_fb += 1
                n_nums += 1
                i = end
            # After a group: another group (implicit repetition), a command, or the end.
            j = _skip_wsp(buf, i, last)
            comma = j < last and buf[j] == _COMMA
            if comma:
                j = _skip_wsp(buf, j + 1, last)
            if j < last and _CLASS[buf[j]] & _NUMBER:
                i = j
                if group == 77:           # after "M x y" more pairs are "L"
                    group = 76
                elif group == 109:        # and after "m x y", "l"
                    group = 108
                continue
            if comma:                     # a comma must be followed by a number
                return n_nums, n_cmds, n_fb, EXPECTED_NUMBER, j
            if j == last:
                return n_nums, n_cmds, n_fb, 0, 0
            if _ARGS[buf[j]] >= 0:
                i = j
                break
            return n_nums, n_cmds, n_fb, EXPECTED_NUMBER_OR_COMMAND, j
    return n_nums, n_cmds, n_fb, 0, 0


@parallel
def count_tokens(buf, path_bytes):
    """Return int64 (n, 5) rows: numbers, groups, fallbacks, error code, error byte.

    `buf` is uint8; path i is ``buf[path_bytes[i]:path_bytes[i + 1]]``. The error byte
    is an index into `buf` (0 when the error code is 0).
    """
    n = path_bytes.shape[0] - 1
    out = np.zeros((n, 5), dtype=np.int64)
    no_nums = np.empty(0, dtype=np.float64)
    no_cmds = np.empty(0, dtype=np.uint8)
    no_fallback = np.empty((0, 3), dtype=np.int64)
    for p in prange(n):
        n_nums, n_cmds, n_fb, error, at = _tokenize(
            buf, path_bytes[p], path_bytes[p + 1], False, no_nums, 0, no_cmds, 0,
            no_fallback, 0)
        out[p, NUMBERS] = n_nums
        out[p, GROUPS] = n_cmds
        out[p, FALLBACKS] = n_fb
        out[p, ERROR] = error
        out[p, ERROR_AT] = at
    return out


@parallel
def write_tokens(buf, path_bytes, num_offsets, cmd_offsets, fallback_offsets):
    """Return ``(nums, cmds, fallback)`` for paths that `count_tokens` passed.

    The offsets (int64, n + 1) are the prefix sums of `count_tokens`' columns.
    `fallback` rows are ``(start byte, end byte, index into nums)``.
    """
    n = path_bytes.shape[0] - 1
    nums = np.empty(num_offsets[n], dtype=np.float64)
    cmds = np.empty(cmd_offsets[n], dtype=np.uint8)
    fallback = np.empty((fallback_offsets[n], 3), dtype=np.int64)
    for p in prange(n):
        _tokenize(buf, path_bytes[p], path_bytes[p + 1], True, nums, num_offsets[p], cmds,
                  cmd_offsets[p], fallback, fallback_offsets[p])
    return nums, cmds, fallback


# --------------------------------------------------------------------------- arcs

class ArcTolerance(NamedTuple):
    """How closely an arc's cubics follow it."""

    absolute: float     # > 0: in user units
    relative: float     # otherwise: this times the arc's larger radius


@scalar
def arc_error(angle):
    """Return the largest radial distance from a unit-circle arc to its cubic.

    The cubic through the arc's ends with tangent lengths ``4/3 tan(angle / 4)``
    deviates from the circle by at most ``2/27 sin(angle/4)**6 / cos(angle/4)**2``
    (Goldapp 1991, "Approximation of circular arcs by cubic polynomials"), 2.7e-4 for a
    quarter circle.
    """
    s = math.sin(0.25 * angle)
    c = math.cos(0.25 * angle)
    return (2.0 / 27.0) * s**6 / (c * c)


# An arc is split into pieces of at most 90 degrees, fewer than 1 + 1e-12 quarter
# turns counting as one, so a quarter circle whose angle rounds up is one piece.
_QUARTER = 0.5 * math.pi * (1.0 + 1e-12)
# Tolerances below a few ulps of the radius ask for pieces that cannot be more accurate
# than the float64 coordinates of their control points; capping them bounds the piece
# count (about 340 for a full circle) whatever the caller asks.
_MIN_RELATIVE_TOLERANCE = 4.0 * 2.220446049250313e-16


@scalar
def _arc_setup(x0, y0, rx, ry, angle, large, sweep, x, y):
    """Return the centre parameterisation of an SVG arc, per the SVG 2 notes.

    Returns ``(kind, cx, cy, rx, ry, cos_phi, sin_phi, theta, delta)``: kind 0 (the ends
    coincide: no segment), 1 (a radius is zero, or the chord is negligible against the
    radii: a straight line) or 2 (an arc of the ellipse centred at (cx, cy) with the
    radii and rotation given, from angle `theta` through `delta` radians). Implements
    SVG 2, appendix "Elliptical arc implementation notes": out-of-range radii are
    scaled up (B.2.5), the rotation is taken modulo 360 degrees and the flags choose
    the centre and the direction (B.2.4).
    """
    if x0 == x and y0 == y:
        return 0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0
    rx = abs(rx)
    ry = abs(ry)
    if rx == 0.0 or ry == 0.0:
        return 1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0
    # Modulo 360 into [0, 360), exactly (fmod is exact), so 390 and -330 are 30.
    phi = np.fmod(angle, 360.0)
    if phi < 0.0:
        phi += 360.0
    phi = math.radians(phi)
    cos_phi = math.cos(phi)
    sin_phi = math.sin(phi)
    hx = 0.5 * (x0 - x)
    hy = 0.5 * (y0 - y)
    # The start relative to the chord's midpoint, in the frame where the ellipse is
    # the unit circle (rotated by -phi, scaled by 1/rx, 1/ry): (ux, uy); the end is at
    # (-ux, -uy). Working here avoids the rx**2 * ry**2 products of the notes (F.6.5),
    # which overflow for radii beyond 1e77.
    ux = (cos_phi * hx + sin_phi * hy) / rx
    uy = (-sin_phi * hx + cos_phi * hy) / ry
    lam = ux * ux + uy * uy
    if lam == 0.0 or not math.isfinite(lam):
        # The half chord underflows against the radii (or overflows): at float64
        # precision the arc is its chord.
        return 1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0
    if lam >= 1.0:
        # Radii too small to reach: scale them up until they just do (B.2.5); the
        # centre is then the chord's midpoint and the arc a half ellipse.
        scale = math.sqrt(lam)
        rx *= scale
        ry *= scale
        ux /= scale
        uy /= scale
        coef = 0.0
    else:
        # Distance of the centre from the midpoint, in units of the half chord (F.6.5.2).
        coef = math.sqrt((1.0 - lam) / lam)
        if large == sweep:
            coef = -coef
    # Centre in the unit frame (F.6.5.2: cx' = coef rx y1'/ry, cy' = -coef ry x1'/rx).
    vx = coef * uy
    vy = -coef * ux
    cx = cos_phi * (rx * vx) - sin_phi * (ry * vy) + 0.5 * (x0 + x)
    cy = sin_phi * (rx * vx) + cos_phi * (ry * vy) + 0.5 * (y0 + y)
    theta = math.atan2(uy - vy, ux - vx)
    delta = math.atan2(-uy - vy, -ux - vx) - theta
    # F.6.5.6: the sweep flag picks the direction of travel.
    if sweep and delta < 0.0:
        delta += 2.0 * math.pi
    elif not sweep and delta > 0.0:
        delta -= 2.0 * math.pi
    return 2, cx, cy, rx, ry, cos_phi, sin_phi, theta, delta


@scalar
def _arc_pieces(rx, ry, delta, tolerance):
    """Return how many cubic pieces keep the arc within `tolerance` (each <= 90 degrees).

    The cubics approximate the unit circle within `arc_error` of the piece angle; the
    affine map to the ellipse stretches distances by at most max(rx, ry). The test is
    made on the unit circle, against the tolerance relative to that radius: so it holds
    for radii whose absolute tolerance would underflow (1e-320) or that overflowed when
    scaled up to reach the end (infinite: then the arc's points do too, and the caller
    reports them), and the count stays bounded (found by fuzzing: both gave counts
    beyond any array, or no end).
    """
    radius = max(rx, ry)
    if tolerance.absolute > 0.0:
        relative = tolerance.absolute / radius    # 0 for an infinite radius
    else:
        relative = tolerance.relative
    relative = max(relative, _MIN_RELATIVE_TOLERANCE)
    sweep = abs(delta)
    n = max(1, int(math.ceil(sweep / _QUARTER)))
    # arc_error(a) <= a**6 / 47198 for a <= 90 degrees, so this n is nearly right;
    # the loop corrects the estimate upwards.
    estimate = int(math.ceil(sweep / (47198.0 * relative) ** (1.0 / 6.0)))
    n = max(n, estimate - 1)
    while arc_error(sweep / n) > relative:
        n += 1
    return n


@scalar
def _put(out, at, deg, x0, y0, x1, y1, x2, y2, x3, y3):
    """Write segment `at` of `out` (`Segments`); unused control rows repeat the end point."""
    controls = out.controls
    controls[at, 0, 0] = x0
    controls[at, 0, 1] = y0
    controls[at, 1, 0] = x1
    controls[at, 1, 1] = y1
    controls[at, 2, 0] = x2
    controls[at, 2, 1] = y2
    controls[at, 3, 0] = x3
    controls[at, 3, 1] = y3
    out.degree[at] = deg


@scalar
def _start_subpath(out, row, x, y, first_segment):
    """Write subpath `row` of `out` (`Segments`): open, starting at (x, y)."""
    out.start[row, 0] = x
    out.start[row, 1] = y
    out.closed[row] = False
    out.subpath_offsets[row] = first_segment


@scalar
def _point(nums, q, ox, oy):
    """Return the point ``(nums[q], nums[q + 1])`` relative to the origin (ox, oy)."""
    return nums[q] + ox, nums[q + 1] + oy


@borrowing
def _arc(start, rx, ry, angle, large, sweep, end, tolerance, write, out, at):
    """Return the number of segments of one SVG arc; with `write`, write them at `at`.

    The arc goes from the point `start` to the point `end`, (x, y) tuples, with the
    radii, rotation and flags given; `out` is a `Segments` record.
    """
    x0, y0 = start
    x, y = end
    kind, cx, cy, rx, ry, cos_phi, sin_phi, theta, delta = _arc_setup(
        x0, y0, rx, ry, angle, large, sweep, x, y)
    if kind == 0:
        return 0
    if kind == 1:
        if write:
            _put(out, at, 1, x0, y0, x, y, x, y, x, y)
        return 1
    n = _arc_pieces(rx, ry, delta, tolerance)
    if not write:
        return n
    step = delta / n
    k = (4.0 / 3.0) * math.tan(0.25 * step)
    # Point and tangent (d/dtheta) at theta = ellipse frame mapped by rotation phi.
    ax = x0
    ay = y0
    c = math.cos(theta)
    s = math.sin(theta)
    for j in range(n):
        t = theta + (j + 1) * step
        c1 = math.cos(t)
        s1 = math.sin(t)
        if j == n - 1:
            bx = x        # the last piece ends exactly at the arc's given end
            by = y
        else:
            bx = cx + cos_phi * (rx * c1) - sin_phi * (ry * s1)
            by = cy + sin_phi * (rx * c1) + cos_phi * (ry * s1)
        # Tangents at both ends: derivative of the ellipse point, times k.
        dax = k * (-cos_phi * (rx * s) - sin_phi * (ry * c))
        day = k * (-sin_phi * (rx * s) + cos_phi * (ry * c))
        dbx = k * (-cos_phi * (rx * s1) - sin_phi * (ry * c1))
        dby = k * (-sin_phi * (rx * s1) + cos_phi * (ry * c1))
        _put(out, at + j, 3, ax, ay, ax + dax, ay + day, bx - dbx, by - dby, bx, by)
        ax = bx
        ay = by
        c = c1
        s = s1
    return n


# --------------------------------------------------------------------------- segments

class Segments(NamedTuple):
    """The arrays `_build` writes, in the layout of `rnsca.io.svgpath.PathArrays`.

    The count pass gives empty ones, untouched.
    """

    controls: np.ndarray         # float64 (m, 4, 2)
    degree: np.ndarray           # int8 (m,)
    start: np.ndarray            # float64 (k, 2)
    closed: np.ndarray           # bool (k,)
    subpath_offsets: np.ndarray  # int64 (k + 1,) each subpath's first segment


@borrowing
def _build(nums, num_at, cmds, cmd_first, cmd_last, tolerance, write, out, seg_at, sub_at):
    """Interpret one path's groups as segments and subpaths (SVG 2, section 9.3).

    The groups are ``cmds[cmd_first:cmd_last]``, their numbers ``nums[num_at:]``; arcs
    become cubics within `tolerance` (`ArcTolerance`). Returns ``(n_segments,
    n_subpaths)``. With `write` (a literal, so the count pass compiles without the
    writes), segment rows go to ``out.controls[seg_at:]`` and ``out.degree[seg_at:]``,
    subpath rows to ``out.start[sub_at:]``, ``out.closed[sub_at:]`` and
    ``out.subpath_offsets[sub_at:]`` (the global index of each subpath's first
    segment). The first group is a moveto (checked by the tokenizer).
    """
    q = num_at
    n_seg = 0
    n_sub = 0
    cx = 0.0          # current point
    cy = 0.0
    sx = 0.0          # start of the current subpath
    sy = 0.0
    is_open = False   # a subpath is open (False before the first M and after Z)
    # For the reflections of S and T: the degree of the previous segment (0 after M, Z
    # and A) and (px, py) its last control point before the end point.
    prev = 0
    px = 0.0
    py = 0.0
    for g in range(cmd_first, cmd_last):
        cmd = cmds[g]
        lower = cmd | _CASE_BIT               # the letter in lower case
        # Origin of the coordinates: the current point for relative commands, else -0.0,
        # the exact identity of addition (x + 0.0 would turn -0.0 into 0.0).
        ox = cx if cmd & _CASE_BIT else -0.0
        oy = cy if cmd & _CASE_BIT else -0.0
        if lower == 109:                      # m: a new subpath
            cx, cy = _point(nums, q, ox, oy)
            q += 2
            sx = cx
            sy = cy
            is_open = False
            prev = 0
        if not is_open:
            # A subpath starts at M, and at any other command after Z, at the closed
            # one's initial point (SVG 2, 9.3.4): at the current point either way.
            if write:
                _start_subpath(out, sub_at + n_sub, cx, cy, seg_at + n_seg)
            n_sub += 1
            is_open = True
        at = seg_at + n_seg
        if lower == 109:
            continue
        if lower == 122:                      # z: close; the closing edge is implicit
            if write:
                out.closed[sub_at + n_sub - 1] = True
            cx = sx
            cy = sy
            is_open = False
            prev = 0
            continue
        if lower == 97:                       # a
            x, y = _point(nums, q + 5, ox, oy)
            n_seg += _arc((cx, cy), nums[q], nums[q + 1], nums[q + 2], nums[q + 3] != 0.0,
                          nums[q + 4] != 0.0, (x, y), tolerance, write, out, at)
            q += 7
            cx = x
            cy = y
            prev = 0
            continue
        # One segment of degree `deg` from (cx, cy) through (x1, y1) and (x2, y2) to
        # (x, y); the rows a line or a quadratic does not use repeat the end point.
        if lower == 108 or lower == 104 or lower == 118:    # l, h, v
            deg = 1
            if lower == 108:
                x, y = _point(nums, q, ox, oy)
                q += 2
            elif lower == 104:
                x = nums[q] + ox
                y = cy
                q += 1
            else:
                x = cx
                y = nums[q] + oy
                q += 1
            x1 = x2 = x
            y1 = y2 = y
        else:                                 # c, s, q, t
            deg = 3 if lower == 99 or lower == 115 else 2
            if lower == 99 or lower == 113:   # c, q: the first control point is given
                x1, y1 = _point(nums, q, ox, oy)
                q += 2
            elif prev == deg:
                # s after c or s, t after q or t: the reflection of the previous last
                # control point about the current point; the writer tests for S and T
                # with this same expression.
                x1 = 2.0 * cx - px
                y1 = 2.0 * cy - py
            else:
                x1 = cx
                y1 = cy
            x2 = x1
            y2 = y1
            if deg == 3:
                x2, y2 = _point(nums, q, ox, oy)
                q += 2
            px = x2                           # the control point before the end
            py = y2
            x, y = _point(nums, q, ox, oy)
            q += 2
            if deg == 2:
                x2 = x
                y2 = y
        if write:
            _put(out, at, deg, cx, cy, x1, y1, x2, y2, x, y)
        n_seg += 1
        cx = x
        cy = y
        prev = deg
    return n_seg, n_sub


@parallel
def count_segments(nums, num_offsets, cmds, cmd_offsets, tol_abs, tol_rel):
    """Return int64 (n, 2) rows: segments and subpaths of each path.

    `tol_abs` > 0 is the arc tolerance in user units; otherwise each arc's tolerance
    is ``tol_rel * max(rx, ry)``.
    """
    n = num_offsets.shape[0] - 1
    out = np.zeros((n, 2), dtype=np.int64)
    tolerance = ArcTolerance(tol_abs, tol_rel)
    nothing = Segments(np.empty((0, 4, 2), dtype=np.float64), np.empty(0, dtype=np.int8),
                       np.empty((0, 2), dtype=np.float64), np.empty(0, dtype=np.bool_),
                       np.empty(0, dtype=np.int64))
    for p in prange(n):
        n_seg, n_sub = _build(nums, num_offsets[p], cmds, cmd_offsets[p], cmd_offsets[p + 1],
                              tolerance, False, nothing, 0, 0)
        out[p, 0] = n_seg
        out[p, 1] = n_sub
    return out


@parallel
def write_segments(nums, num_offsets, cmds, cmd_offsets, tol_abs, tol_rel, seg_offsets,
                   sub_offsets):
    """Return ``(controls, degree, start, closed, subpath_offsets)`` of every path.

    `seg_offsets` and `sub_offsets` (int64, n + 1) are the prefix sums of
    `count_segments`; the arrays returned have the layout of `PathArrays`.
    """
    n = num_offsets.shape[0] - 1
    m = seg_offsets[n]
    k = sub_offsets[n]
    controls = np.empty((m, 4, 2), dtype=np.float64)
    degree = np.empty(m, dtype=np.int8)
    start = np.empty((k, 2), dtype=np.float64)
    closed = np.empty(k, dtype=np.bool_)
    subpath_offsets = np.empty(k + 1, dtype=np.int64)
    subpath_offsets[k] = m
    tolerance = ArcTolerance(tol_abs, tol_rel)
    segments = Segments(controls, degree, start, closed, subpath_offsets)
    for p in prange(n):
        _build(nums, num_offsets[p], cmds, cmd_offsets[p], cmd_offsets[p + 1], tolerance,
               True, segments, seg_offsets[p], sub_offsets[p])
    return controls, degree, start, closed, subpath_offsets
