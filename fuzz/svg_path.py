"""Fuzz target: the SVG path data reader (`rnsca.io.svgpath`, kernels in `svgparse`).

The input bytes are decoded as UTF-8 (invalid bytes become lone surrogates, which the
reader must report like any other stray character) and split at NUL bytes into the
paths of one bulk read (at most `MAX_PATHS`). Every path is read alone (`parse_path`)
and all together (`parse_paths`); a finding is any of:

- an exception other than the documented `ParseError` and `InvalidGeometryError`;
- a disagreement with the reference grammar (below) on accepting a path, or on the
  character position of the first error;
- a bulk read that differs from the single reads (values, or the error of the first
  failing path, prefixed with its index);
- segments that differ from those of the reference interpreter, `svgelements`;
- a written path (``write_paths(..., precision=None)``) that does not read back as the
  same arrays, which the writer promises.

References
----------
Grammar: SVG 2 path data (section 9.3.9) with rnsca's documented choices, written as one
regular expression for the third-party ``regex`` module, whose partial matching tells
whether a prefix can still be completed: the first error is at the end of the longest
prefix that can. Numbers are atomic groups, so they are read greedily (``"12"`` is one
number), as SVG requires; arc flags are single characters. The reference shares no code
with rnsca's tokenizer (a hand-written state machine compiled by Numba).

Geometry: ``svgelements.Path`` (an independent pure-Python SVG library) interprets
relative commands, ``H``/``V``, the reflections of ``S``/``T`` and ``Z``. Two of its
readings differ from SVG and are corrected here: it reflects control points across
command families (an ``S`` after a ``Q``), and it stops at a number with a trailing dot
(``2.``) that ends a command's arguments, so it is given ``2.0`` instead. Its arcs are
compared by what SVG 2's implementation notes define: an arc whose ends coincide draws
nothing, one with a zero radius is a line, any other is a chain of cubics from its
start to its end whose points lie on the ellipse (radii scaled up when too small to
reach the end) and within the arc's sweep. The ellipse is computed here (F.6.5), in
floating point, from the arc's numbers as the grammar captured them: svgelements keeps
the sign of a negative radius where SVG 2 takes its absolute value.

Where the references cannot judge
---------------------------------
- Magnitudes where floating point itself gives out: a path with a number of magnitude
  above `HUGE` may raise `InvalidGeometryError` (documented: relative steps or
  reflections past float64's range, arcs whose squared radii overflow), and its
  geometry is not compared; nor is it with a non-zero magnitude below `TINY` (squares
  underflow in both readers' arc maths).
- Arcs whose ellipse the reference's own floating-point formulas cannot place: radii
  beyond about 1e77 (their squares overflow) or more than 1e6 times one another (the
  coordinates cannot resolve the minor radius); only their ends are checked.
"""

from __future__ import annotations

import math

import numpy as np
import regex

from rnsca.errors import InvalidGeometryError, ParseError
from rnsca.io.svgpath import parse_path, parse_paths, write_paths

__all__ = ["MAX_LEN", "setup", "test_one_input", "reference_error"]

#: Longest input libFuzzer makes: paths of a few hundred characters reach every state.
MAX_LEN = 1024

#: Paths per input, at most.
MAX_PATHS = 16

#: Numbers above this magnitude may overflow in documented ways (see the module notes).
HUGE = 2.0 ** 500
#: Non-zero numbers below this magnitude are not compared geometrically.
TINY = 2.0 ** -500

# --------------------------------------------------------------------------- grammar

# Every repetition is possessive (never gives back what it matched): the grammar never
# needs to, and with backtracking partial matching took seconds on long paths.
_WSP = r"[\t\n\f\r ]"
_SEP = rf"(?:{_WSP}++,?+{_WSP}*+|,{_WSP}*+)?+"   # comma_wsp?
# Atomic: a number is read greedily and never given back ("12" is not "1" then "2").
_NUM = r"(?P<n>(?>[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?))"
_FLAG = r"(?P<f>[01])"


def _items(*fields: str) -> str:
    """Return the pattern of one argument group: its fields, optionally separated."""
    return _SEP.join(fields)


def _sequence(item: str) -> str:
    """Return the pattern of one or more groups (implicit repetition of a command)."""
    return rf"{item}(?:{_SEP}{item})*+"


_PAIR = _items(_NUM, _NUM)
_ARGUMENTS = {
    "Mm": _sequence(_PAIR), "Ll": _sequence(_PAIR), "Tt": _sequence(_PAIR),
    "HhVv": _sequence(_NUM), "SsQq": _sequence(_items(_PAIR, _PAIR)),
    "Cc": _sequence(_items(_PAIR, _PAIR, _PAIR)),
    "Aa": _sequence(_items(_NUM, _NUM, _NUM, _FLAG, _FLAG, _PAIR)),
}
_DRAWTO = "|".join([r"(?P<c>[Zz])"] + [
    rf"(?P<c>[{letters}]){_WSP}*+{arguments}"
    for letters, arguments in _ARGUMENTS.items() if letters != "Mm"])
_MOVETO = rf"(?P<c>[Mm]){_WSP}*+{_ARGUMENTS['Mm']}"
#: A whole path: empty or whitespace only, or a moveto and any commands after it.
PATH = regex.compile(
    rf"{_WSP}*+(?:{_MOVETO}(?:{_WSP}*+(?:{_MOVETO}|{_DRAWTO}))*+{_WSP}*+)?+")

_GROUP_SIZE = {"M": 2, "L": 2, "T": 2, "H": 1, "V": 1, "S": 4, "Q": 4, "C": 6, "A": 7,
               "Z": 0}


def reference_error(d: str) -> int | None:
    """Return the position of the first error in path data `d`, None if it is valid.

    The first error is where the longest prefix that some valid path starts with ends.
    Numbers out of float64's range are errors too, at their first character, after every
    grammar error.
    """
    match = PATH.fullmatch(d)
    if match is None:
        low, high = 0, len(d)          # d[:low] can be completed, d[:high + 1] cannot
        while low < high:
            middle = (low + high + 1) // 2
            if PATH.fullmatch(d, endpos=middle, partial=True) is not None:
                low = middle
            else:
                high = middle - 1
        return low
    for text, at in zip(match.captures("n"), match.starts("n"), strict=True):
        if math.isinf(float(text)):
            return at
    return None


def reference_arcs(d: str) -> list[tuple[float, ...]]:
    """Return ``(rx, ry, rotation, large_arc, sweep)`` of each arc of valid path data `d`.

    Read from the grammar's captures: numbers and flags in order, each group of 7
    arguments after an ``A``/``a`` (or its implicit repetitions) being one arc.
    """
    match = PATH.fullmatch(d)
    assert match is not None
    tokens = sorted([(at, "c", text) for text, at in zip(match.captures("c"),
                                                         match.starts("c"), strict=True)]
                    + [(at, "n", text) for text, at in zip(match.captures("n"),
                                                           match.starts("n"), strict=True)]
                    + [(at, "n", text) for text, at in zip(match.captures("f"),
                                                           match.starts("f"), strict=True)])
    arcs: list[tuple[float, ...]] = []
    letter, arguments = "M", []
    for _, kind, text in tokens:
        if kind == "c":
            letter, arguments = text.upper(), []
            continue
        arguments.append(float(text))
        if len(arguments) == _GROUP_SIZE[letter]:
            if letter == "A":
                arcs.append(tuple(arguments[:5]))
            arguments = []
    return arcs


# --------------------------------------------------------------------------- geometry

def _point(value) -> tuple[float, float]:
    return float(value.x), float(value.y)


def _reference_subpaths(d: str) -> list[dict]:
    """Return the subpaths svgelements reads from `d`: start, closed, and items.

    An item is ``(degree, points)`` for a line or a Bézier curve, or ``("arc", start,
    end, numbers)`` for an arc, `numbers` from `reference_arcs`.
    """
    from svgelements import Arc, Close, CubicBezier, Line, Move, Path, QuadraticBezier

    arcs = iter(reference_arcs(d))
    subpaths: list[dict] = []
    current: dict | None = None
    for segment in Path(_for_svgelements(d)):
        if isinstance(segment, Move):
            current = {"start": _point(segment.end), "closed": False, "items": []}
            subpaths.append(current)
            continue
        assert current is not None, "svgelements: a drawing command before any moveto"
        if isinstance(segment, Close):
            if current["closed"]:   # "ZZ": SVG starts a subpath after Z; it closes at once
                current = {"start": current["start"], "closed": True, "items": []}
                subpaths.append(current)
            current["closed"] = True
            continue
        if current["closed"]:   # after Z: a new subpath at the closed one's start
            current = {"start": current["start"], "closed": False, "items": []}
            subpaths.append(current)
        previous = current["items"][-1] if current["items"] else (None,)
        if isinstance(segment, Line):
            current["items"].append((1, [_point(segment.start), _point(segment.end)]))
        elif isinstance(segment, QuadraticBezier):
            points = [_point(p) for p in (segment.start, segment.control, segment.end)]
            if segment.smooth:
                points[1] = _reflection(previous, 2, points[0])
            current["items"].append((2, points))
        elif isinstance(segment, CubicBezier):
            points = [_point(p) for p in (segment.start, segment.control1, segment.control2,
                                          segment.end)]
            if segment.smooth:
                points[1] = _reflection(previous, 3, points[0])
            current["items"].append((3, points))
        elif isinstance(segment, Arc):
            current["items"].append(("arc", _point(segment.start), _point(segment.end),
                                     next(arcs)))
        else:
            raise AssertionError(f"svgelements: unexpected segment {segment!r}")
    return subpaths


def _for_svgelements(d: str) -> str:
    """Return valid path data `d` with ``0`` after each number's trailing dot.

    svgelements stops reading, silently, at a number such as ``2.`` that ends its
    command's arguments (``"L1 2.M5 5"`` loses the moveto), though SVG's grammar allows
    the form. Each number is atomic, so the added digit changes no other token.
    """
    match = PATH.fullmatch(d)
    assert match is not None
    out, last = [], 0
    for start, end in match.spans("n"):
        text = d[start:end]
        mantissa = regex.match(r"[+-]?[0-9]+\.(?![0-9])", text)
        if mantissa:
            out.append(d[last:start + mantissa.end()] + "0")
            last = start + mantissa.end()
    out.append(d[last:])
    return "".join(out)


def _reflection(previous: tuple, degree: int, current: tuple) -> tuple:
    """Return the first control point of an ``S`` (degree 3) or ``T`` (2) segment.

    SVG: the reflection of the previous segment's last control point about the current
    point if that segment is of the same command family, else the current point.
    svgelements reflects across families (a ``T`` after a ``C``, an ``S`` after a
    ``Q``), which SVG does not, so the reference computes this itself.
    """
    if previous[0] != degree:
        return current
    control = previous[1][-2]
    return 2 * current[0] - control[0], 2 * current[1] - control[1]


def _ellipse(start, end, numbers):
    """Return the centre parameterization of an SVG arc (SVG 2, F.6.5 and F.6.6).

    Returns ``(cx, cy, rx, ry, cos, sin, theta1, delta)``: the ellipse, its rotation, the
    parametric angle at the start and the signed sweep (radians).
    """
    rx, ry, rotation, large_arc, sweep = numbers
    rx, ry = abs(rx), abs(ry)
    phi = math.radians(math.fmod(rotation, 360.0))
    cos, sin = math.cos(phi), math.sin(phi)
    dx, dy = (start[0] - end[0]) / 2, (start[1] - end[1]) / 2
    x1, y1 = cos * dx + sin * dy, -sin * dx + cos * dy
    scale = (x1 / rx) ** 2 + (y1 / ry) ** 2
    if scale > 1:
        # F.6.6.3: radii scaled up to just reach; the centre is then the chord's midpoint
        # (the formula below would give it only up to cancellation in its numerator).
        rx, ry = rx * math.sqrt(scale), ry * math.sqrt(scale)
        root = 0.0
    else:
        numerator = max(0.0, (rx * ry) ** 2 - (rx * y1) ** 2 - (ry * x1) ** 2)
        root = math.sqrt(numerator / ((rx * y1) ** 2 + (ry * x1) ** 2))
    if large_arc == sweep:
        root = -root
    cx1, cy1 = root * rx * y1 / ry, -root * ry * x1 / rx
    cx = cos * cx1 - sin * cy1 + (start[0] + end[0]) / 2
    cy = sin * cx1 + cos * cy1 + (start[1] + end[1]) / 2
    theta1 = math.atan2((y1 - cy1) / ry, (x1 - cx1) / rx)
    theta2 = math.atan2((-y1 - cy1) / ry, (-x1 - cx1) / rx)
    delta = math.fmod(theta2 - theta1, 2 * math.pi)
    if sweep and delta < 0:
        delta += 2 * math.pi
    elif not sweep and delta > 0:
        delta -= 2 * math.pi
    return cx, cy, rx, ry, cos, sin, theta1, delta


def _bezier(points: np.ndarray, t: float) -> np.ndarray:
    """Return the point at `t` of a Bézier curve of control points `points` (de Casteljau)."""
    while len(points) > 1:
        points = (1 - t) * points[:-1] + t * points[1:]
    return points[0]


def _check_arc(cubics: list[np.ndarray], start, end, numbers, tolerance: float,
               where: str) -> None:
    """Check that `cubics` draw the arc from `start` to `end` (see the module notes)."""
    assert cubics, f"{where}: an arc drew no segment"
    assert np.allclose(cubics[0][0], start, rtol=0, atol=tolerance), f"{where}: arc start"
    assert np.allclose(cubics[-1][-1], end, rtol=0, atol=tolerance), f"{where}: arc end"
    try:
        cx, cy, rx, ry, cos, sin, theta1, delta = _ellipse(start, end, numbers)
    except (OverflowError, ZeroDivisionError):
        return   # the notes' formulas square the radii: beyond about 1e77 they overflow
    if not all(map(math.isfinite, (cx, cy, rx, ry, theta1, delta))) or min(rx, ry) < TINY:
        return
    if max(rx, ry) > 1e6 * min(rx, ry):
        # A thin ellipse: float64 coordinates of the size of the major radius cannot
        # resolve the minor one, so no point of it is "on" it to a radial test.
        return
    # Radial error allowed: rnsca's cubics stay within 1e-9 * max(rx, ry) of the
    # ellipse; rounding of the centre adds eps-sized multiples of the coordinates.
    allowed = 1e-7 * max(rx, ry) + tolerance
    for cubic in cubics:
        for t in (0.0, 0.25, 0.5, 0.75, 1.0):
            x, y = _bezier(cubic, t)
            u, v = cos * (x - cx) + sin * (y - cy), -sin * (x - cx) + cos * (y - cy)
            radius = math.hypot(u / rx, v / ry)
            # Distance to the ellipse, to first order: the radial error times the radius
            # in that direction.
            off = abs(radius - 1.0) * math.hypot(u, v) / max(radius, 1e-300)
            assert off <= allowed, (f"{where}: arc point {x!r}, {y!r} is {off:.3g} off the "
                                    f"ellipse (allowed {allowed:.3g})")
            angle = math.atan2(v / ry, u / rx)
            along = math.fmod(angle - theta1, 2 * math.pi)
            if delta >= 0:
                along = along + 2 * math.pi if along < 0 else along
            else:
                along = along - 2 * math.pi if along > 0 else along
            slack = 1e-6 + allowed / min(rx, ry)
            outside = min(abs(along - delta), abs(along)) > slack and (
                abs(along) > abs(delta) or (along >= 0) != (delta >= 0))
            # The end of a full-turn's worth of rounding (angle 2 pi == 0) is inside.
            if outside and abs(abs(along) - 2 * math.pi) > slack:
                raise AssertionError(f"{where}: arc point {x!r}, {y!r} at angle "
                                     f"{along:.6g} is outside the sweep {delta:.6g}")


def _tolerance(*points) -> float:
    """Return the rounding both readers may differ by near `points`: 1e-12 of their size.

    Local, not the path's: a path may hold 1e120 and 6 (``"M0 1e120 L6 6 A..."``).
    """
    return 1e-12 * max(1.0, float(np.abs(np.asarray(points, dtype=np.float64)).max()))


def _near(a, b) -> bool:
    """Return whether two points (or point lists) agree within `_tolerance`."""
    return bool(np.allclose(a, b, rtol=0, atol=_tolerance(a, b)))


def _arc_end(ours: list, k: int, end) -> int:
    """Return the index of the cubic that ends the arc whose first cubic is ``ours[k]``.

    rnsca ends an arc's last cubic at the arc's end exactly: the first cubic from `k`
    that ends there. Failing that (the readers added a relative end differently), the
    first that ends near it (`_near`); `k` if the run of cubics has neither.
    """
    run = k
    while run < len(ours) and len(ours[run]) == 4:
        run += 1
    for test in (lambda p: tuple(p) == tuple(end), lambda p: _near(p, end)):
        for j in range(k, run):
            if test(ours[j][-1]):
                return j
    return k


def _compare_geometry(d: str, paths) -> None:
    """Compare the one path of `paths` (rnsca) with svgelements' reading of `d`."""
    expected = _reference_subpaths(d)
    starts, closed = paths.start, paths.closed
    offsets, degree, controls = paths.subpath_offsets, paths.degree, paths.controls
    where = f"path {d!r}"
    assert len(expected) == len(closed), (
        f"{where}: {len(closed)} subpaths, svgelements {len(expected)}")
    for s, subpath in enumerate(expected):
        here = f"{where}, subpath {s}"
        assert _near(starts[s], subpath["start"]), (
            f"{here}: starts at {starts[s].tolist()}, svgelements {subpath['start']}")
        assert bool(closed[s]) == subpath["closed"], f"{here}: closed {closed[s]}"
        ours = [controls[k, :degree[k] + 1] for k in range(offsets[s], offsets[s + 1])]
        k = 0
        for item in subpath["items"]:
            if item[0] == "arc":
                _, start, end, numbers = item
                if start == end:
                    continue          # no segment
                if numbers[0] == 0 or numbers[1] == 0:
                    item = (1, [start, end])  # a line
                else:
                    last = _arc_end(ours, k, end)
                    cubics = ours[k:last + 1]
                    k = last + 1
                    _check_arc(cubics, start, end, numbers, _tolerance(start, end), here)
                    continue
            assert k < len(ours), f"{here}: missing segment {item}"
            got = ours[k]
            assert len(got) == item[0] + 1 and _near(got, item[1]), (
                f"{here}, segment {k}: {got.tolist()}, svgelements degree {item[0]} "
                f"{item[1]}")
            k += 1
        assert k == len(ours), f"{here}: {len(ours) - k} segments more than svgelements"


def _comparable(d: str) -> bool:
    """Return whether every number of valid path data `d` has a moderate magnitude."""
    match = PATH.fullmatch(d)
    assert match is not None
    values = [abs(float(text)) for text in match.captures("n")]
    return all(v == 0 or TINY <= v <= HUGE for v in values)


# --------------------------------------------------------------------------- the target

def setup() -> None:
    """Compile the reader's and writer's kernels before the first timed input."""
    from rnsca.io.svgpath import warm_up_readers

    warm_up_readers()


def _read_one(d: str):
    """Return rnsca's reading of `d`, or the documented exception it raised."""
    try:
        return parse_path(d)
    except (ParseError, InvalidGeometryError) as error:
        return error


def _check_path(d: str, result) -> None:
    """Check rnsca's reading of one path, `result` (arrays or exception), against `d`."""
    expected_error = reference_error(d)
    if isinstance(result, ParseError):
        assert expected_error is not None, f"{d!r}: rnsca refused a valid path: {result}"
        assert result.position == expected_error, (
            f"{d!r}: rnsca reports position {result.position}, the grammar "
            f"{expected_error}: {result}")
        if "out of range" in str(result):
            number = regex.match(_NUM, d[result.position:]).group()
            found = repr(number if len(number) <= 40 else number[:37] + "...")
        else:
            found = repr(d[result.position]) if result.position < len(d) else "the end"
        assert found in str(result), f"{d!r}: the message does not quote {found}: {result}"
        return
    assert expected_error is None, (
        f"{d!r}: rnsca accepted a path with an error at position {expected_error}")
    if isinstance(result, InvalidGeometryError):
        assert not _comparable(d), f"{d!r}: InvalidGeometryError on moderate numbers: {result}"
        return
    assert len(result) == 1
    again = parse_paths(write_paths(result, precision=None))
    assert again == result, f"{d!r}: written as {write_paths(result, precision=None)!r}, " \
                            f"which reads back differently"
    if _comparable(d):
        _compare_geometry(d, result)


def test_one_input(data: bytes) -> None:
    """Read the paths in `data` alone and together; raise on any finding."""
    # At most MAX_PATHS paths (the last keeps any further NULs, an error): each is read
    # four times, and hundreds of empty paths would only time the reader's overhead.
    ds = data.decode("utf-8", "surrogateescape").split("\0", MAX_PATHS - 1)
    singles = [_read_one(d) for d in ds]
    for d, result in zip(ds, singles, strict=True):
        _check_path(d, result)
    try:
        bulk = parse_paths(ds)
    except (ParseError, InvalidGeometryError) as error:
        failed = [i for i, r in enumerate(singles) if isinstance(r, Exception)]
        assert failed, f"bulk read failed where every single read passed: {error}"
        # Grammar errors of any path come first, then numbers out of range, then
        # coordinates that overflow.
        grammar = [i for i in failed if isinstance(singles[i], ParseError)
                   and "out of range" not in str(singles[i])]
        ranges = [i for i in failed if isinstance(singles[i], ParseError)
                  and "out of range" in str(singles[i])]
        first = (grammar or ranges or failed)[0]
        assert type(error) is type(singles[first]), (
            f"bulk error {error!r}, single reads fail first at path {first}: "
            f"{singles[first]!r}")
        if isinstance(error, ParseError):
            assert error.path_index == first and error.position == singles[first].position, (
                f"bulk error {error} (path {error.path_index}), single reads fail first at "
                f"path {first}: {singles[first]}")
            assert str(error) == f"path {first}, {singles[first]}", (error, singles[first])
        else:
            assert getattr(error, "path_index", first) == first, (error, singles[first])
        return
    assert not any(isinstance(r, Exception) for r in singles), (
        f"bulk read passed where a single read failed: {singles}")
    assert len(bulk) == len(ds)
    for i, single in enumerate(singles):
        assert bulk.path(i) == single, f"path {i} read in bulk differs from alone"
