"""SVG path data, properties: exact numbers, the grammar, SVG semantics, round trips.

- every number reads bit for bit as Python's ``float()`` reads it (the kernel's Clinger
  fast path and the fallback alike), or is out of range exactly when ``float()`` gives
  an infinity;
- any text, including NUL, non-ASCII and huge numbers, ends in a `PathArrays` or a
  `ParseError` (never a hang or another exception), and is accepted exactly when a
  plain-Python recursive-descent reading of the SVG 2 grammar accepts it, with the same
  commands and numbers;
- generated paths (every command, absolute and relative, random spellings and
  separators) give the segments SVG's rules give, computed here independently;
- ``parse(write(p, precision=None)) == p``, and with a finite precision every
  coordinate comes back within a few roundings of the path's magnitude.
"""

from __future__ import annotations

import math
import re
import struct

import numpy as np
from hypothesis import assume, given
from hypothesis import strategies as st

from rnsca.errors import InvalidGeometryError, ParseError
from rnsca.io import svgparse, svgpath, svgwrite
from rnsca.io.svgpath import parse_path, parse_paths, write_paths

WSP = " \t\n\r\x0c"
ARGS = {"M": 2, "L": 2, "T": 2, "H": 1, "V": 1, "C": 6, "S": 4, "Q": 4, "A": 7, "Z": 0}
NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def bits(x: float) -> int:
    return struct.unpack("<q", struct.pack("<d", x))[0]


# --------------------------------------------------------------------------- numbers

@st.composite
def number_texts(draw) -> str:
    """Return a number as the grammar spells it, from plain to pathological."""
    kind = draw(st.sampled_from(["parts", "repr", "exponent", "short"]))
    if kind == "repr":
        return repr(draw(st.floats(allow_nan=False, allow_infinity=False)))
    if kind == "exponent":
        x = draw(st.floats(allow_nan=False, allow_infinity=False))
        return f"%.{draw(st.integers(0, 25))}e" % x
    if kind == "short":
        return str(draw(st.integers(-10**6, 10**6)) / 10 ** draw(st.integers(0, 4)))
    sign = draw(st.sampled_from(["", "-", "+"]))
    whole = draw(st.text("0123456789", max_size=30))
    fraction = draw(st.none() | st.text("0123456789", max_size=30))
    if not whole and not fraction:
        whole = "0"
    text = sign + whole + ("" if fraction is None else "." + fraction)
    exponent = draw(st.none() | st.integers(-400, 400) | st.integers(-10**30, 10**30))
    if exponent is not None:
        mark = draw(st.sampled_from(["e", "E"]))
        plus = "+" if exponent >= 0 and draw(st.booleans()) else ""
        text += f"{mark}{plus}{exponent}"
    return text


@given(st.lists(number_texts(), min_size=1, max_size=40))
def test_numbers_read_bit_for_bit_like_python_float(texts):
    if len(texts) % 2:
        texts = [*texts, "0"]
    expected = [float(t) for t in texts]
    # One path per pair too, so fallback numbers span several paths.
    ds = ["M" + " ".join(texts)] + [f"M{a},{b}" for a, b in zip(texts[::2], texts[1::2],
                                                                strict=True)]
    if not all(math.isfinite(x) for x in expected):
        first = next(i for i, x in enumerate(expected) if not math.isfinite(x))
        try:
            parse_paths(ds)
        except ParseError as error:
            assert "number out of range" in str(error)
            assert error.path_index == 0
            assert error.position == 1 + sum(len(t) + 1 for t in texts[:first])
        else:
            raise AssertionError("an infinite number was accepted")
        return
    p = parse_paths(ds)
    got = [*p.start[0].tolist(), *p.controls[: p.subpath_offsets[1], 3].reshape(-1).tolist()]
    assert [bits(x) for x in got] == [bits(x) for x in expected]
    singles = p.start[1:].reshape(-1).tolist()
    assert [bits(x) for x in singles] == [bits(x) for x in expected]


# --------------------------------------------------------------------------- grammar

def skip_wsp(d: str, i: int) -> int:
    while i < len(d) and d[i] in WSP:
        i += 1
    return i


def skip_comma_wsp(d: str, i: int) -> int:
    i = skip_wsp(d, i)
    if i < len(d) and d[i] == ",":
        i = skip_wsp(d, i + 1)
    return i


def reference_groups(d: str):
    """Return the (letter, numbers) groups of `d` per the SVG 2 grammar, or None.

    A plain recursive-descent reading, independent of the kernel: implicit repetition
    is spelled out (pairs after M/m become L/l), flags are single characters.
    """
    n = len(d)
    i = skip_wsp(d, 0)
    if i == n:
        return []
    if d[i] not in "Mm":
        return None
    groups = []
    while True:
        cmd = d[i]
        i += 1
        k = ARGS[cmd.upper()]
        if k == 0:
            groups.append((cmd, []))
            i = skip_wsp(d, i)
            if i == n:
                return groups
            if d[i].upper() not in ARGS:
                return None
            continue
        i = skip_wsp(d, i)
        letter = cmd
        while True:
            args = []
            for a in range(k):
                if a:
                    i = skip_comma_wsp(d, i)
                if cmd in "Aa" and a in (3, 4):
                    if i < n and d[i] in "01":
                        args.append(float(d[i]))
                        i += 1
                        continue
                    return None
                match = NUMBER.match(d, i)
                if not match:
                    return None
                args.append(float(match.group()))
                i = match.end()
            groups.append((letter, args))
            j = skip_wsp(d, i)
            comma = j < n and d[j] == ","
            if comma:
                j = skip_wsp(d, j + 1)
            if j < n and NUMBER.match(d, j):
                i = j
                letter = {"M": "L", "m": "l"}.get(letter, letter)
                continue
            if comma:
                return None
            if j == n:
                return groups
            if d[j].upper() in ARGS:
                i = j
                break
            return None


def kernel_groups(d: str):
    """Return the kernel tokenizer's groups of `d` (numbers converted), or None."""
    data, path_bytes = svgpath._encode([d])
    buf = np.frombuffer(data, dtype=np.uint8)
    counts = svgparse.count_tokens(buf, path_bytes)
    if counts[0, svgparse.ERROR]:
        return None
    offsets = [svgpath._prefix_sum(counts[:, c]) for c in range(3)]
    nums, cmds, fallback = svgparse.write_tokens(buf, path_bytes, *offsets)
    if fallback.shape[0]:
        try:
            svgpath._convert_fallback([d], data, buf, path_bytes, fallback, nums, False)
        except ParseError:
            return None
    groups, q = [], 0
    for c in cmds.tobytes().decode():
        k = ARGS[c.upper()]
        groups.append((c, nums[q:q + k].tolist()))
        q += k
    return groups


PATH_ALPHABET = "MmLlHhVvCcSsQqTtAaZz0123456789011.,-+eE \t\n"


@st.composite
def path_like_texts(draw) -> str:
    """Return text that often nearly follows the grammar: the hard cases."""
    head = draw(st.sampled_from(["", "M0 0", "M1,2", "m-.5.5", " M 1e2 3 "]))
    body = draw(st.text(PATH_ALPHABET, max_size=40))
    return head + body


SHORT_NUMBERS = st.sampled_from(["0", "1", "-1", "12", "-.5", ".5", "1.", "1e2", "+3",
                                 "-2E-1", "0.25", "7e+1", "1e-300", "-0"])


@st.composite
def valid_texts(draw) -> str:
    """Return valid path data: every command, implicit repetition, tight spellings."""
    out = draw(st.sampled_from(["", " ", "\n"]))
    for n in range(draw(st.integers(1, 8))):
        letter = draw(st.sampled_from("MmLlHhVvCcSsQqTtAaZz") if n else st.sampled_from("Mm"))
        out += letter + draw(st.sampled_from(["", " "]))
        k = ARGS[letter.upper()]
        groups = 0 if k == 0 else draw(st.integers(1, 3))
        for g in range(groups):
            for a in range(k):
                if letter in "Aa" and a in (3, 4):
                    text = draw(st.sampled_from("01"))
                else:
                    text = draw(SHORT_NUMBERS)
                if g or a:
                    tight = (text[0] in "-+" or (letter in "Aa" and a == 4)) and draw(
                        st.booleans())
                    out += "" if tight else draw(st.sampled_from([" ", ",", " , ", "\t"]))
                out += text
        out += draw(st.sampled_from(["", " "]))
    return out


@st.composite
def mutated_texts(draw) -> str:
    """Return valid path data with up to two characters inserted, deleted or replaced."""
    d = draw(valid_texts())
    for _ in range(draw(st.integers(0, 2))):
        i = draw(st.integers(0, len(d)))
        c = draw(st.sampled_from(PATH_ALPHABET + "\x00é,,"))
        op = draw(st.sampled_from(["insert", "delete", "replace"]))
        if op == "insert":
            d = d[:i] + c + d[i:]
        elif op == "delete":
            d = d[:i] + d[i + 1:]
        else:
            d = d[:i] + c + d[i + 1:]
    return d


@given(st.one_of(mutated_texts(), path_like_texts(), st.text(max_size=40)))
def test_any_text_is_read_or_rejected_as_the_grammar_says(d):
    expected = reference_groups(d)
    if expected is not None and not all(math.isfinite(x) for _, args in expected
                                        for x in args):
        expected = None   # a number out of range
    try:
        p = parse_path(d)
    except ParseError as error:
        assert expected is None, f"rejected valid {d!r}: {error}"
        assert 0 <= error.position <= len(d)
        assert str(error).startswith(f"position {error.position}: ")
        return
    except InvalidGeometryError:
        # Valid text whose coordinates overflow as they add up.
        assert expected is not None
        return
    assert expected is not None, f"accepted invalid {d!r}"
    assert kernel_groups(d) == expected
    assert len(p) == 1


@given(st.text(PATH_ALPHABET + "\x00é\U0001f600", min_size=1, max_size=60),
       st.integers(0, 5))
def test_bulk_errors_name_the_same_path_and_position_as_single_reads(d, index):
    ds = ["M0 0"] * index + [d] + ["M1 1"]
    try:
        parse_path(d)
    except ParseError as single:
        try:
            parse_paths(ds)
        except ParseError as bulk:
            assert (bulk.path_index, bulk.position) == (index, single.position)
            assert str(bulk) == f"path {index}, {single}"
        else:
            raise AssertionError("bulk read accepted what a single read rejected") from None
    except InvalidGeometryError:
        pass


# --------------------------------------------------------------------------- semantics

COORDINATES = st.one_of(st.integers(-1000, 1000).map(float),
                        st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False))


@st.composite
def spelled(draw, x: float) -> str:
    """Return a spelling of `x` that reads back as exactly `x`."""
    text = draw(st.sampled_from([repr(x), f"{x:.17g}", f"{x:.17e}"]))
    if text.startswith("0.") and draw(st.booleans()):
        text = text[1:]
    elif text.startswith("-0.") and draw(st.booleans()):
        text = "-" + text[2:]
    assert float(text) == x
    return text


@st.composite
def generated_paths(draw):
    """Return (d, expected) for a random path: commands, spellings and separators.

    `expected` lists (degree, control points) per segment and (start, closed) per
    subpath, computed by the SVG rules from the numbers drawn (no arcs: their cubics
    are checked in the unit tests).
    """
    parts, segs, subs = [], [], []
    cx = cy = sx = sy = 0.0
    prev, px, py = None, 0.0, 0.0
    is_open = False

    def sep() -> str:
        return draw(st.sampled_from([" ", ",", " , ", "\t", "\n "]))

    def numbers(values) -> str:
        texts = [draw(spelled(v)) for v in values]
        out = texts[0]
        for t in texts[1:]:
            out += ("" if t[0] == "-" and draw(st.booleans()) else sep()) + t
        return out

    for _ in range(draw(st.integers(0, 12))):
        letter = draw(st.sampled_from("MLHVCSQTZ") if parts else st.just("M"))
        relative = draw(st.booleans())
        ox, oy = (cx, cy) if relative else (0.0, 0.0)
        k = ARGS[letter]
        raw = [draw(COORDINATES) for _ in range(k)]
        cmd = letter.lower() if relative else letter
        parts.append(cmd + draw(st.sampled_from(["", " "])) + (numbers(raw) if k else ""))
        parts.append(draw(st.sampled_from(["", " "])))
        if letter == "M":
            cx, cy = raw[0] + ox, raw[1] + oy
            sx, sy = cx, cy
            subs.append([[cx, cy], False])
            is_open, prev = True, None
            continue
        if not is_open:
            subs.append([[sx, sy], False])
            is_open = True
        if letter == "Z":
            subs[-1][1] = True
            cx, cy = sx, sy
            is_open, prev = False, None
            continue
        if letter in "LHV":
            if letter == "L":
                x, y = raw[0] + ox, raw[1] + oy
            elif letter == "H":
                x, y = raw[0] + ox, cy
            else:
                x, y = cx, raw[0] + oy
            segs.append((1, [[cx, cy], [x, y]]))
            cx, cy, prev = x, y, None
        elif letter in "CS":
            if letter == "C":
                x1, y1, rest = raw[0] + ox, raw[1] + oy, raw[2:]
            else:
                x1, y1 = (2.0 * cx - px, 2.0 * cy - py) if prev == "C" else (cx, cy)
                rest = raw
            x2, y2, x, y = rest[0] + ox, rest[1] + oy, rest[2] + ox, rest[3] + oy
            segs.append((3, [[cx, cy], [x1, y1], [x2, y2], [x, y]]))
            cx, cy, prev, px, py = x, y, "C", x2, y2
        else:
            if letter == "Q":
                x1, y1, rest = raw[0] + ox, raw[1] + oy, raw[2:]
            else:
                x1, y1 = (2.0 * cx - px, 2.0 * cy - py) if prev == "Q" else (cx, cy)
                rest = raw
            x, y = rest[0] + ox, rest[1] + oy
            segs.append((2, [[cx, cy], [x1, y1], [x, y]]))
            cx, cy, prev, px, py = x, y, "Q", x1, y1
    return "".join(parts), segs, subs


@given(generated_paths())
def test_generated_paths_give_the_segments_of_the_svg_rules(case):
    d, segs, subs = case
    p = parse_path(d)
    got = [(int(g), c[:g + 1].tolist()) for g, c in zip(p.degree, p.controls, strict=True)]
    assert got == segs
    assert [[s, c] for s, c in zip(p.start.tolist(), p.closed.tolist(), strict=True)] == subs


# --------------------------------------------------------------------------- round trips

@st.composite
def parsed_paths(draw):
    ds = [draw(generated_paths())[0] for _ in range(draw(st.integers(1, 4)))]
    if draw(st.booleans()):
        ds.append("M0 0A" + " ".join(map(repr, (draw(st.floats(0.1, 100)),
                                                  draw(st.floats(0.1, 100)),
                                                  draw(st.floats(-720, 720)),
                                                  draw(st.integers(0, 1)),
                                                  draw(st.integers(0, 1)),
                                                  draw(COORDINATES), draw(COORDINATES)))))
    return parse_paths(ds)


@given(parsed_paths())
def test_writing_with_precision_none_reads_back_exactly(p):
    assert parse_paths(write_paths(p, precision=None)) == p


@given(parsed_paths(), st.integers(1, 17))
def test_writing_with_a_precision_reads_back_within_its_rounding(p, precision):
    q = parse_paths(write_paths(p, precision=precision))
    for name in ("degree", "subpath_offsets", "closed", "path_offsets"):
        assert np.array_equal(getattr(q, name), getattr(p, name)), name
    # Each number is within 0.5 * 10**(1 - precision) of its value, relative; points
    # the reader computes (reflections, H/V, omitted movetos) add up at most three.
    scale = max(1.0, float(np.abs(p.controls).max(initial=0.0)),
                float(np.abs(p.start).max(initial=0.0)))
    limit = 3 * 0.5 * 10.0 ** (1 - precision) * scale * (1 + 1e-9)
    assert np.abs(q.controls - p.controls).max(initial=0.0) <= limit
    assert np.abs(q.start - p.start).max(initial=0.0) <= limit


@given(parsed_paths())
def test_written_text_is_compact(p):
    for text in write_paths(p, precision=None):
        assume(text)
        assert "  " not in text and ", " not in text
        assert not re.search(r"(?<![0-9.])0\.", text), text     # no leading zero
        assert not re.search(r"\.[0-9]*0(?![0-9])", text), text  # no trailing zero


FLOATS = st.one_of(st.floats(allow_nan=False, allow_infinity=False),
                   st.builds(lambda n, k: n / 10.0**k, st.integers(-10**12, 10**12),
                             st.integers(-30, 30)),
                   st.builds(lambda n, k: n * 10.0**k, st.integers(-999, 999),
                             st.integers(-30, 30)))


@given(FLOATS, st.integers(0, 17))
def test_kernel_number_text_is_pythons_or_left_to_python(x, precision):
    text = np.zeros((1, svgwrite.TEXT_WIDTH), dtype=np.uint8)
    size = svgwrite._format(x, precision, text, 0)
    if size == 0:
        return   # left to Python: a near tie or beyond the exact powers of ten
    got = text[0, :size].tobytes().decode()
    if precision:
        assert got == svgpath._compact(f"%.{precision}g" % x)
    else:
        assert float(got) == x
        assert got == svgpath._compact(repr(x))
