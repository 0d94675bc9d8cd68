"""One pass over GeoJSON bytes: the coordinates taken out as numbers, the rest as a skeleton.

`scan` tokenizes a JSON document (or, for GeoJSON text sequences, one document per
line) and treats the ``coordinates`` member of each geometry object apart: its value,
which must be an array of arrays ... of numbers (at most four deep), is read into

- *events*, int32, one per array: ``OPEN`` and ``CLOSE`` around an array of arrays (an
  empty array is ``OPEN, CLOSE``), and for a non-empty array of numbers its count (> 0);
- *values*, float64, every number in document order (`rnsca.kernels.decimals`);

and replaced in the *skeleton*, a copy of the rest of the document, by the geometry's
index (``"coordinates":17``), so that a JSON parser reads the skeleton's types, ids and
properties without making a Python object per number.

A geometry object is one found where a GeoJSON reader looks for one, whatever its
``type`` says (unknown when its coordinates come first): the top-level object (a
Geometry), its ``geometry`` member (a Feature), or the ``geometry`` member of an object
in its ``features`` array (a FeatureCollection). Each geometry records that *pattern*
and its document, so the caller, which knows the top-level type, takes only the
placeholders it expects (a ``coordinates`` member inside ``properties`` is never one).

The scan is strict where it reads numbers (the JSON grammar, RFC 8259, 6) and only as
strict elsewhere as finding the structure needs: it tokenizes strings (escapes),
literals and numbers, checks the nesting and separators, and leaves what else JSON
asks of the skeleton (valid UTF-8, say) to the parser that reads it. Replacing a valid
array by an integer keeps a document valid and an invalid one invalid. It stops with
`NOT_TAKEN` at the first thing it does not take: a syntax error, a value in
coordinates that is neither an array nor a number, an array mixing arrays and numbers,
arrays nested more than four deep, a duplicated ``features``, ``geometry`` or
``coordinates`` key (or one spelled with an escape) where the structure depends on it,
nesting deeper than `MAX_DEPTH`; the caller then reads the document another way.

The bytes must be followed by at least `PADDING` zero bytes: a zero byte is valid
nowhere in JSON, so every loop stops at it without a bounds check.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rnsca.kernels.decimals import decimal_to_double
from rnsca.kernels.jit import inlined, scalar

__all__ = ["CLOSE", "MAX_DEPTH", "NOT_TAKEN", "OPEN", "PADDING", "SCANNED", "Scan", "scan"]

#: Zero bytes `scan` needs after the document (the longest look-ahead: ``\\uXXXX``).
PADDING = 16
#: The deepest nesting `scan` takes (orjson refuses more than 1024 levels anyway).
MAX_DEPTH = 1024
#: Coordinates arrays nest at most this deep (a MultiPolygon's positions).
_COORDINATE_DEPTH = 4

#: `scan` statuses.
SCANNED, NOT_TAKEN = 0, 1
#: Events other than a count of numbers.
OPEN, CLOSE = -1, -2

# Where a container sits: the roles that matter to finding geometry objects.
_OTHER, _ROOT, _ROOT_GEOMETRY, _FEATURES, _FEATURE, _FEATURE_GEOMETRY = 0, 1, 2, 3, 4, 5
# The keys that matter (bit k of a container's `seen` flags key k).
_KEY_OTHER, _KEY_FEATURES, _KEY_GEOMETRY, _KEY_COORDINATES = 0, 1, 2, 3
_FEATURES_WORD = np.frombuffer(b"features", dtype=np.uint8)
_GEOMETRY_WORD = np.frombuffer(b"geometry", dtype=np.uint8)
_COORDINATES_WORD = np.frombuffer(b"coordinates", dtype=np.uint8)

# Parser states.
_VALUE, _VALUE_OR_CLOSE, _KEY, _KEY_OR_CLOSE, _COLON, _AFTER, _END = 0, 1, 2, 3, 4, 5, 6

_QUOTE, _BACKSLASH, _COMMA, _COLON_BYTE, _MINUS = 34, 92, 44, 58, 45
_OPEN_BRACKET, _CLOSE_BRACKET, _OPEN_BRACE, _CLOSE_BRACE = 91, 93, 123, 125
_SPACE, _TAB, _LF, _CR, _RS = 32, 9, 10, 13, 30
_ZERO, _DOT = 48, 46
# A saturated exponent: past it a nonzero number is 0 or infinite either way.
_EXPONENT_CAP = 1_000_000
_TEN = np.uint64(10)


class Scan(NamedTuple):
    """What `scan` read, its arrays trimmed to their lengths.

    Attributes
    ----------
    status : int
        `SCANNED`, or `NOT_TAKEN` (then the arrays are empty).
    skeleton : uint8 array
        The document with each coordinates value replaced by its geometry's index; for a
        sequence, a JSON array of the documents.
    events : int32 array
        `OPEN`, `CLOSE` or a count of numbers (> 0), every geometry's in turn.
    values : float64 array
        The numbers of every coordinates value, in order.
    slow : int64 array, shape (k, 3)
        Value index, first byte and end byte of each number whose value is left to the
        caller (more than 19 significant digits, too close to a tie to decide).
    geometries : int64 array, shape (g, 3)
        For each geometry: its first event, its pattern (0 a top-level geometry, 1 a
        Feature's, 2 a FeatureCollection's) and its document (0 unless a sequence).
    min_numbers, max_numbers : int
        The fewest and most numbers of a non-empty array of numbers (``2**62`` and 0 if
        there is none).
    """

    status: int
    skeleton: np.ndarray
    events: np.ndarray
    values: np.ndarray
    slow: np.ndarray
    geometries: np.ndarray
    min_numbers: int
    max_numbers: int


class _Sink(NamedTuple):
    """The growing outputs of the coordinates reader (replaced when one grows)."""

    events: np.ndarray
    values: np.ndarray
    slow: np.ndarray


@scalar
def _grown(array, needed):
    """Return `array` if it holds `needed` items, else a copy at least twice as long."""
    if needed <= array.shape[0]:
        return array
    out = np.empty(max(needed, 2 * array.shape[0]), dtype=array.dtype)
    out[:array.shape[0]] = array
    return out


@inlined
def _skip_space(data, at, newline):
    """Return the index of the first byte from `at` that is not whitespace.

    Whitespace is JSON's (space, tab, CR and, if `newline`, LF).
    """
    while True:
        c = data[at]
        if c > _SPACE:
            return at
        if c == _SPACE or c == _TAB or c == _CR or (c == _LF and newline):
            at += 1
        else:
            return at


@inlined
def _digit(c):
    """Return the value of ASCII digit byte `c`, or -1."""
    d = np.int64(c) - _ZERO
    return d if 0 <= d <= 9 else -1


@inlined
def _scan_number(data, at):
    """Read the JSON number at `at` (RFC 8259, 6).

    Returns
    -------
    end : int
        The index after it, or -1 if none starts at `at`.
    w : uint64
        Its first (at most 19) significant digits.
    q : int
        The power of ten of the last digit of `w`.
    truncated : bool
        Whether nonzero digits follow those in `w`.
    negative : bool
    integer : bool
        Whether it has neither fraction nor exponent (a JSON parser gives an int).
    """
    w = np.uint64(0)
    q = 0
    digits = 0
    truncated = False
    negative = data[at] == _MINUS
    i = at + 1 if negative else at
    d = _digit(data[i])
    if d < 0:
        return -1, w, q, truncated, negative, True
    i += 1
    if d > 0:
        w = np.uint64(d)
        digits = 1
        d = _digit(data[i])
    else:  # a lone leading zero: "01" ends here, and the caller refuses the 1
        d = -1
    # The digits that fit in w, then those that do not; the power of ten is counted
    # once per run, not per digit (measured: the scan of 10.4M numbers, 0.61 -> 0.58 s).
    while d >= 0 and digits < 19:
        w = w * _TEN + np.uint64(d)
        digits += 1
        i += 1
        d = _digit(data[i])
    more = i
    while d >= 0:
        truncated |= d != 0
        i += 1
        d = _digit(data[i])
    q += i - more
    integer = True
    if data[i] == _DOT:
        integer = False
        i += 1
        d = _digit(data[i])
        if d < 0:
            return -1, w, q, truncated, negative, integer
        if digits == 0:  # leading zeros of the fraction of a number below one
            first = i
            while d == 0:
                i += 1
                d = _digit(data[i])
            q -= i - first
        first = i
        while d >= 0 and digits < 19:
            w = w * _TEN + np.uint64(d)
            digits += 1
            i += 1
            d = _digit(data[i])
        q -= i - first
        while d >= 0:
            truncated |= d != 0
            i += 1
            d = _digit(data[i])
    c = data[i]
    if c == 101 or c == 69:  # e, E
        integer = False
        i += 1
        exponent_negative = data[i] == _MINUS
        if data[i] == _MINUS or data[i] == 43:  # +
            i += 1
        d = _digit(data[i])
        if d < 0:
            return -1, w, q, truncated, negative, integer
        exponent = 0
        while d >= 0:
            if exponent < _EXPONENT_CAP:
                exponent = exponent * 10 + d
            i += 1
            d = _digit(data[i])
        q += -exponent if exponent_negative else exponent
    return i, w, q, truncated, negative, integer


@inlined
def _scan_string(data, at):
    """Return (index after the string starting at quote `at`, whether it has escapes).

    -1 for an unterminated string, a control character or a bad escape. UTF-8 is not
    checked (the skeleton's parser does).
    """
    i = at + 1
    escaped = False
    while True:
        c = data[i]
        if c == _QUOTE:
            return i + 1, escaped
        if c < _SPACE:
            return -1, escaped
        if c == _BACKSLASH:
            escaped = True
            e = data[i + 1]
            if e == 117:  # \uXXXX
                for k in range(i + 2, i + 6):
                    h = data[k]
                    if not (48 <= h <= 57 or 65 <= h <= 70 or 97 <= h <= 102):
                        return -1, escaped
                i += 6
            elif e == _QUOTE or e == _BACKSLASH or e == 47 or e == 98 or e == 102 \
                    or e == 110 or e == 114 or e == 116:  # " \ / b f n r t
                i += 2
            else:
                return -1, escaped
        else:
            i += 1


@inlined
def _scan_literal(data, at):
    """Return the index after ``true``, ``false`` or ``null`` at `at`, or -1."""
    c = data[at]
    if c == 116 and data[at + 1] == 114 and data[at + 2] == 117 and data[at + 3] == 101:
        return at + 4
    if c == 110 and data[at + 1] == 117 and data[at + 2] == 108 and data[at + 3] == 108:
        return at + 4
    if c == 102 and data[at + 1] == 97 and data[at + 2] == 108 and data[at + 3] == 115 \
            and data[at + 4] == 101:
        return at + 5
    return -1


@inlined
def _is_word(data, first, end, word):
    """Return whether bytes ``data[first:end]`` are `word`."""
    if end - first != word.shape[0]:
        return False
    for k in range(word.shape[0]):
        if data[first + k] != word[k]:
            return False
    return True


@inlined
def _key_of(data, first, end):
    """Return the key id of the unescaped key text ``data[first:end]``."""
    if _is_word(data, first, end, _FEATURES_WORD):
        return _KEY_FEATURES
    if _is_word(data, first, end, _GEOMETRY_WORD):
        return _KEY_GEOMETRY
    if _is_word(data, first, end, _COORDINATES_WORD):
        return _KEY_COORDINATES
    return _KEY_OTHER


@inlined
def _role_of(parent, key, is_object, depth):
    """Return the role of a container opened at `depth` as member `key` of `parent`."""
    if depth == 0:
        return _ROOT if is_object else _OTHER
    if parent == _ROOT and key == _KEY_GEOMETRY and is_object:
        return _ROOT_GEOMETRY
    if parent == _ROOT and key == _KEY_FEATURES and not is_object:
        return _FEATURES
    if parent == _FEATURES and is_object:
        return _FEATURE
    if parent == _FEATURE and key == _KEY_GEOMETRY and is_object:
        return _FEATURE_GEOMETRY
    return _OTHER


@inlined
def _pattern_of(role):
    """Return the geometry pattern of an object of `role`, or -1 if it is no geometry."""
    if role == _ROOT:
        return 0
    if role == _ROOT_GEOMETRY:
        return 1
    if role == _FEATURE_GEOMETRY:
        return 2
    return -1


@scalar
def _read_coordinates(data, at, newline, sink, counts):
    """Read the coordinates array at `at` (a ``[``) into the sink.

    `counts` holds the events, values and slow numbers written so far and the fewest
    and most numbers of an array of them; updated. Returns (index after the array, or
    -1 if not taken, and the sink, which may hold new, longer arrays).
    """
    events, values, slow = sink
    n_events, n_values, n_slow = counts[0], counts[1], counts[2]
    fewest, most = counts[3], counts[4]
    depth = 0
    while True:
        depth += 1  # at a "["
        if depth > _COORDINATE_DEPTH:
            return -1, sink
        at = _skip_space(data, at + 1, newline)
        c = data[at]
        if n_events + 2 > events.shape[0]:
            events = _grown(events, n_events + 2)
        if c == _OPEN_BRACKET:  # an array of arrays
            events[n_events] = OPEN
            n_events += 1
            continue
        if c == _CLOSE_BRACKET:
            events[n_events] = OPEN
            events[n_events + 1] = CLOSE
            n_events += 2
            at += 1
        else:  # an array of numbers
            count = 0
            while True:
                end, w, q, truncated, negative, integer = _scan_number(data, at)
                if end < 0:
                    return -1, sink
                value, decided = decimal_to_double(w, q, truncated)
                if not decided:
                    if 3 * n_slow + 3 > slow.shape[0]:
                        slow = _grown(slow, 3 * n_slow + 3)
                    slow[3 * n_slow] = n_values
                    slow[3 * n_slow + 1] = at
                    slow[3 * n_slow + 2] = end
                    n_slow += 1
                # A JSON parser reads "-0" as the integer 0, which converts to +0.0.
                if negative and not (integer and w == 0):
                    value = -value
                if n_values == values.shape[0]:
                    values = _grown(values, n_values + 1)
                values[n_values] = value
                n_values += 1
                count += 1
                at = _skip_space(data, end, newline)
                c = data[at]
                if c == _COMMA:
                    at = _skip_space(data, at + 1, newline)
                elif c == _CLOSE_BRACKET:
                    at += 1
                    break
                else:
                    return -1, sink
            events[n_events] = count
            n_events += 1
            fewest = min(fewest, count)
            most = max(most, count)
        depth -= 1
        # An array just closed: the next element of its parent, or the parent's end.
        while depth > 0:
            at = _skip_space(data, at, newline)
            c = data[at]
            if c == _COMMA:
                at = _skip_space(data, at + 1, newline)
                if data[at] != _OPEN_BRACKET:
                    return -1, sink
                break
            if c != _CLOSE_BRACKET:
                return -1, sink
            if n_events == events.shape[0]:
                events = _grown(events, n_events + 1)
            events[n_events] = CLOSE
            n_events += 1
            depth -= 1
            at += 1
        if depth == 0:
            counts[0], counts[1], counts[2] = n_events, n_values, n_slow
            counts[3], counts[4] = fewest, most
            return at, _Sink(events, values, slow)


@inlined
def _copy(skeleton, length, data, first, end):
    """Append ``data[first:end]`` to the skeleton; return it (maybe grown) and its length."""
    skeleton = _grown(skeleton, length + end - first + 32)
    skeleton[length:length + end - first] = data[first:end]
    return skeleton, length + end - first


@inlined
def _append_index(skeleton, length, index):
    """Append the decimal digits of `index` (>= 0) to the skeleton (room for 20 bytes)."""
    digits = 1
    power = 10
    while index >= power:
        digits += 1
        power *= 10
    for k in range(digits):
        skeleton[length + digits - 1 - k] = _ZERO + index % 10
        index //= 10
    return length + digits


@scalar
def scan(data, size, sequence):
    """Return the `Scan` of the JSON document in ``data[:size]``.

    Parameters
    ----------
    data : uint8 array
        The bytes, then at least `PADDING` zero bytes.
    size : int
        The length of the document.
    sequence : bool
        Read one document per line (GeoJSON text sequences, newline-delimited GeoJSON):
        each line holds one JSON text or none, between bytes RS, space, tab and CR,
        and no text spans lines; the skeleton is then a JSON array of the documents.

    Returns
    -------
    Scan
        `SCANNED`, or `NOT_TAKEN` at the first thing the scan does not take (see the
        module docstring): the caller must read the document another way.
    """
    roles = np.zeros(MAX_DEPTH, dtype=np.uint8)
    objects = np.zeros(MAX_DEPTH, dtype=np.uint8)
    seen = np.zeros(MAX_DEPTH, dtype=np.uint8)
    skeleton = np.empty(size // 4 + 64, dtype=np.uint8)
    length = 0
    copied = 0  # data[:copied] is in the skeleton (or skipped)
    geometries = np.empty(3 * 1024, dtype=np.int64)
    n_geometries = 0
    sink = _Sink(np.empty(size // 16 + 16, dtype=np.int32),
                 np.empty(size // 16 + 16, dtype=np.float64), np.empty(3 * 64, dtype=np.int64))
    counts = np.zeros(5, dtype=np.int64)
    counts[3] = 1 << 62  # no array of numbers yet
    newline = not sequence  # whether LF is whitespace inside a document
    depth = 0
    state = _VALUE
    key = _KEY_OTHER
    document = -1
    at = 0
    line_ended = True  # a sequence's next document may start
    if sequence:
        skeleton[0] = _OPEN_BRACKET
        length = 1
    while True:
        if depth == 0 and (state == _VALUE or state == _END):
            # Between top-level documents.
            if sequence:
                while True:
                    c = data[at]
                    if c == _LF:
                        line_ended = True
                    elif not (c == _SPACE or c == _TAB or c == _CR or c == _RS):
                        break
                    at += 1
            else:
                at = _skip_space(data, at, True)
            if at >= size:
                break
            if state == _END and not (sequence and line_ended):
                return _partial(NOT_TAKEN)
            document += 1
            if sequence:
                if document > 0:
                    skeleton[length] = _COMMA
                    length += 1
                copied = at
                line_ended = False
            state = _VALUE
        else:
            at = _skip_space(data, at, newline)
        c = data[at]
        if state == _VALUE_OR_CLOSE and c == _CLOSE_BRACKET or \
                state == _KEY_OR_CLOSE and c == _CLOSE_BRACE or \
                state == _AFTER and c == (_CLOSE_BRACE if objects[depth - 1] else _CLOSE_BRACKET):
            depth -= 1
            seen[depth] = 0
            at += 1
            state = _AFTER if depth > 0 else _END
        elif state == _VALUE or state == _VALUE_OR_CLOSE:
            parent = roles[depth - 1] if depth > 0 else _OTHER
            is_object = c == _OPEN_BRACE
            pattern = _pattern_of(parent) if depth > 0 and key == _KEY_COORDINATES else -1
            if c == _OPEN_BRACKET and pattern >= 0:
                geometries = _grown(geometries, 3 * n_geometries + 3)
                geometries[3 * n_geometries] = counts[0]
                geometries[3 * n_geometries + 1] = pattern
                geometries[3 * n_geometries + 2] = document
                skeleton, length = _copy(skeleton, length, data, copied, at)
                length = _append_index(skeleton, length, n_geometries)
                n_geometries += 1
                at, sink = _read_coordinates(data, at, newline, sink, counts)
                if at < 0:
                    return _partial(NOT_TAKEN)
                copied = at
                state = _AFTER
            elif is_object or c == _OPEN_BRACKET:
                if depth == MAX_DEPTH:
                    return _partial(NOT_TAKEN)
                roles[depth] = _role_of(parent, key, is_object, depth)
                objects[depth] = is_object
                depth += 1
                at += 1
                state = _KEY_OR_CLOSE if is_object else _VALUE_OR_CLOSE
                key = _KEY_OTHER
                continue
            else:
                if c == _QUOTE:
                    at, _ = _scan_string(data, at)
                elif c == _MINUS or _digit(c) >= 0:
                    at = _scan_number(data, at)[0]
                else:
                    at = _scan_literal(data, at)
                if at < 0:
                    return _partial(NOT_TAKEN)
                state = _AFTER if depth > 0 else _END
        elif state == _KEY or state == _KEY_OR_CLOSE:
            if c != _QUOTE:
                return _partial(NOT_TAKEN)
            end, escaped = _scan_string(data, at)
            if end < 0:
                return _partial(NOT_TAKEN)
            key = _KEY_OTHER
            if roles[depth - 1] != _OTHER:  # where the structure depends on the keys
                if escaped:
                    return _partial(NOT_TAKEN)
                key = _key_of(data, at + 1, end - 1)
                if key != _KEY_OTHER:
                    flag = np.uint8(1 << key)
                    if seen[depth - 1] & flag:
                        return _partial(NOT_TAKEN)
                    seen[depth - 1] |= flag
            at = end
            state = _COLON
        elif state == _COLON:
            if c != _COLON_BYTE:
                return _partial(NOT_TAKEN)
            at += 1
            state = _VALUE
        elif state == _AFTER and c == _COMMA:
            at += 1
            if objects[depth - 1]:
                state = _KEY
            else:
                state = _VALUE
                key = _KEY_OTHER
        else:
            return _partial(NOT_TAKEN)
        if depth == 0 and sequence:
            # A document ended: into the skeleton, and what follows on its line skipped.
            skeleton, length = _copy(skeleton, length, data, copied, at)
            copied = at
    if document < 0 and not sequence:
        return _partial(NOT_TAKEN)
    if sequence:
        skeleton = _grown(skeleton, length + 1)
        skeleton[length] = _CLOSE_BRACKET
        length += 1
    else:
        skeleton, length = _copy(skeleton, length, data, copied, size)
    events, values, slow = sink
    return Scan(SCANNED, skeleton[:length], events[:counts[0]], values[:counts[1]],
                slow[:3 * counts[2]].reshape((-1, 3)),
                geometries[:3 * n_geometries].reshape((-1, 3)),
                counts[3], counts[4])


@scalar
def _partial(status):
    """Return an empty `Scan` with `status` (what was read is of no use to the caller)."""
    return Scan(status, np.empty(0, dtype=np.uint8), np.empty(0, dtype=np.int32),
                np.empty(0, dtype=np.float64), np.empty((0, 3), dtype=np.int64),
                np.empty((0, 3), dtype=np.int64), 0, 0)
