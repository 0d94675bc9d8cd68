"""SVG path data (the ``d`` attribute) to columnar Bézier segments and back.

`parse_paths` reads many path strings at once into one `PathArrays`; `parse_path` reads
one. `write_paths` and `write_path` write them back as compact path data. The module
knows nothing of clipping; the Bézier kernels consume `PathArrays` directly.

Reading follows SVG 2 (section 9.3, "Path data"), with these choices:

- The whole grammar: ``M m L l H h V v C c S s Q q T t A a Z z``, implicit repetition
  (pairs after a moveto are linetos), numbers such as ``-.5.5e-3`` (two numbers) or
  ``1.`` and ``1e+2``, separators only where needed, arc flags without separators
  (``a1 1 0 00 1 1``). A comma may separate numbers, once; it may not follow a command
  letter, precede one, or be doubled. Empty or whitespace-only data is a valid path
  with no subpaths (SVG: rendering disabled).
- Strict: where SVG renders a path up to its first error, we raise `ParseError` with
  the path's index (bulk reads), the 0-based character position, the character found
  and what was expected. Numbers are read exactly as Python's ``float()`` reads them;
  one beyond float64's range is an error too ("number out of range"; grammar errors,
  in any path, are reported first), and so is a coordinate that becomes infinite
  (relative steps summing past 1.8e308; `InvalidGeometryError`).
- ``Z`` closes the subpath: `PathArrays.closed` is set and no closing segment is
  added; the edge back to the subpath's start is implicit. A command after ``Z`` other
  than a moveto starts a new subpath at the same start point. A moveto with no drawing
  command (``"M1 2"``, ``"M1 2 Z"``, ``"M1 2 M3 4"``) is a subpath with no segments.
- Arcs follow SVG 2's "Elliptical arc implementation notes": the ends coincide: no
  segment; a zero radius: a straight line; radii too small to reach the end: scaled up;
  negative radii: their absolute value; the rotation: modulo 360 degrees. Each arc
  becomes cubic Béziers of at most 90 degrees each, as many as keep every point of the
  cubics within `tolerance` of the ellipse.

Writing is the inverse (see `write_paths`): absolute coordinates, ``H``/``V`` for axis
parallel lines, ``S``/``T`` where a control point is the reflection the reader would
compute, no repeated command letters, no separator a reader does not need.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from itertools import pairwise

import numpy as np

from rnsca.arrays import PathArrays
from rnsca.errors import InvalidOptionError, ParseError
from rnsca.io import svgparse, svgwrite

__all__ = [
    "ARC_RELATIVE_TOLERANCE",
    "MAX_PRECISION",
    "PathArrays",
    "parse_path",
    "parse_paths",
    "warm_up_readers",
    "write_path",
    "write_paths",
]

#: The default arc tolerance, relative to each arc's larger radius: with
#: ``tolerance=None`` the cubics of an arc stay within ``1e-9 * max(rx, ry)`` of it
#: (eight pieces per quarter ellipse).
ARC_RELATIVE_TOLERANCE = 1e-9

#: The largest `precision` of the writer: 17 significant digits identify every float64.
MAX_PRECISION = 17

# Fallback numbers up to this many bytes are converted by NumPy in one call (its
# string-to-double conversion is Python's correctly rounded one); longer ones one by one.
_VECTOR_NUMBER_BYTES = 32

# A number of the path grammar, to quote one in an error message.
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


# --------------------------------------------------------------------------- reading

def parse_path(d: str, *, tolerance: float | None = None) -> PathArrays:
    """Return the segments of one SVG path data string as a `PathArrays` of one path.

    Parameters
    ----------
    d : str
        Path data, as in the ``d`` attribute.
    tolerance : float, optional
        Largest distance (user units) from an arc to its cubic Béziers. The default,
        None, is `ARC_RELATIVE_TOLERANCE` times each arc's larger radius.

    Returns
    -------
    PathArrays
        One path.

    Raises
    ------
    ParseError
        `d` breaks the grammar; the message gives the 0-based character position, the
        character found and what was expected; so do the ``position`` and
        ``path_index`` (0) attributes.
    InvalidGeometryError
        A coordinate overflows float64 (relative steps, arcs of huge radius).
    InvalidOptionError
        `tolerance` is not a positive finite number.

    Examples
    --------
    >>> p = parse_path("M0,0 L10,10 Q 20,0 30,10 Z")
    >>> p.degree.tolist(), p.closed.tolist()
    ([1, 2], [True])
    >>> p.controls[1].tolist()
    [[10.0, 10.0], [20.0, 0.0], [30.0, 10.0], [30.0, 10.0]]
    >>> parse_path("M0 0 L1 x")
    Traceback (most recent call last):
    ...
    rnsca.errors.ParseError: position 8: expected a number, found 'x'
    """
    if not isinstance(d, str):
        raise TypeError(f"path data must be a str, not {type(d).__name__}")
    return _parse([d], tolerance, bulk=False)


def parse_paths(ds: Sequence[str], *, tolerance: float | None = None) -> PathArrays:
    """Return the segments of many SVG path data strings, path ``i`` from ``ds[i]``.

    The fast form: all strings are parsed in one parallel pass over their bytes.

    Parameters
    ----------
    ds : sequence of str
        Path data strings.
    tolerance : float, optional
        As for `parse_path`.

    Returns
    -------
    PathArrays
        ``len(ds)`` paths.

    Raises
    ------
    ParseError
        For the first string (lowest index) that breaks the grammar; the message starts
        with ``path <index>, position <character>:`` and the exception has the
        ``path_index`` and ``position`` attributes.
    InvalidGeometryError
        A coordinate overflows float64; the message names the path.
    InvalidOptionError
        `tolerance` is not a positive finite number.

    Examples
    --------
    >>> p = parse_paths(["M1 2", "m1 2 3 4", "M0 0 H5 V5 Z"])
    >>> len(p), p.path_offsets.tolist(), p.subpath_offsets.tolist()
    (3, [0, 1, 2, 3], [0, 0, 1, 3])
    >>> p.controls[0, :2].tolist()   # m1 2 3 4: a moveto, then a relative lineto
    [[1.0, 2.0], [4.0, 6.0]]
    """
    if isinstance(ds, (str, bytes)):
        raise TypeError("parse_paths takes a sequence of strings; use parse_path for one")
    return _parse(ds, tolerance, bulk=True)


def _arc_tolerance(tolerance: float | None) -> tuple[float, float]:
    """Return the kernel's (absolute, relative) tolerance pair; one of them is 0."""
    if tolerance is None:
        return 0.0, ARC_RELATIVE_TOLERANCE
    number = isinstance(tolerance, (int, float, np.integer, np.floating))
    value = float(tolerance) if number else math.nan
    if isinstance(tolerance, bool) or not (math.isfinite(value) and value > 0.0):
        raise InvalidOptionError(f"tolerance must be a positive finite number or None, "
                                 f"not {tolerance!r}")
    return value, 0.0


def _parse(ds: Sequence[str], tolerance: float | None, bulk: bool) -> PathArrays:
    tol_abs, tol_rel = _arc_tolerance(tolerance)
    data, path_bytes = _encode(ds)
    buf = np.frombuffer(data, dtype=np.uint8)
    counts = svgparse.count_tokens(buf, path_bytes)
    bad = np.flatnonzero(counts[:, svgparse.ERROR])
    if bad.size:
        p = int(bad[0])
        raise _parse_error(ds, p, int(counts[p, svgparse.ERROR_AT] - path_bytes[p]),
                           int(counts[p, svgparse.ERROR]), bulk)
    num_offsets = _prefix_sum(counts[:, svgparse.NUMBERS])
    cmd_offsets = _prefix_sum(counts[:, svgparse.GROUPS])
    fallback_offsets = _prefix_sum(counts[:, svgparse.FALLBACKS])
    nums, cmds, fallback = svgparse.write_tokens(buf, path_bytes, num_offsets, cmd_offsets,
                                                 fallback_offsets)
    if fallback.shape[0]:
        _convert_fallback(ds, data, buf, path_bytes, fallback, nums, bulk)
    sizes = svgparse.count_segments(nums, num_offsets, cmds, cmd_offsets, tol_abs, tol_rel)
    seg_offsets = _prefix_sum(sizes[:, 0])
    sub_offsets = _prefix_sum(sizes[:, 1])
    controls, degree, start, closed, subpath_offsets = svgparse.write_segments(
        nums, num_offsets, cmds, cmd_offsets, tol_abs, tol_rel, seg_offsets, sub_offsets)
    return PathArrays(controls=controls, degree=degree, subpath_offsets=subpath_offsets,
                      closed=closed, start=start, path_offsets=sub_offsets)


def _prefix_sum(counts: np.ndarray) -> np.ndarray:
    out = np.zeros(counts.shape[0] + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def _encode(ds: Sequence[str]) -> tuple[bytes, np.ndarray]:
    """Return the UTF-8 bytes of all strings laid end to end, and each one's offsets."""
    text = "".join(ds)   # TypeError naming the item for a non-str
    # Lone surrogates pass through: like any non-ASCII character they are a parse error,
    # reported at their position.
    data = text.encode("utf-8", "surrogatepass")
    n = len(ds)
    if len(data) == len(text):   # ASCII: bytes are characters
        lengths = np.fromiter(map(len, ds), dtype=np.int64, count=n)
    else:
        lengths = np.fromiter((len(s.encode("utf-8", "surrogatepass")) for s in ds),
                              dtype=np.int64, count=n)
    return data, _prefix_sum(lengths)


def _parse_error(ds: Sequence[str], p: int, position: int, code: int, bulk: bool) -> ParseError:
    """Return the ParseError for `code` at byte `position` of path `p`.

    Every byte before the error was accepted by the grammar, hence ASCII, so the byte
    position is also the character position.
    """
    d = ds[p]
    if code == svgparse.OUT_OF_RANGE:
        # The kernel stopped at a number it read: the pattern matches there (the
        # rest of the path, should it ever not).
        match = _NUMBER.match(d, position)
        number = match.group() if match else d[position:]
        found = f"found {number if len(number) <= 40 else number[:37] + '...'!r}"
    elif position < len(d):
        found = f"found {d[position]!r}"
    else:
        found = "found the end of the path"
    where = f"path {p}, position {position}" if bulk else f"position {position}"
    error = ParseError(f"{where}: {svgparse.ERROR_MESSAGES[code]}, {found}")
    error.position = position
    error.path_index = p
    return error


def _convert_fallback(ds: Sequence[str], data: bytes, buf: np.ndarray, path_bytes: np.ndarray,
                      fallback: np.ndarray, nums: np.ndarray, bulk: bool) -> None:
    """Convert the numbers off Clinger's fast path with Python's parser, into `nums`."""
    first, end, where = fallback[:, 0], fallback[:, 1], fallback[:, 2]
    length = end - first
    short = length <= _VECTOR_NUMBER_BYTES
    if short.any():
        # Gather the short numbers into fixed-width, NUL-padded rows and let NumPy parse
        # the lot (bytes to float64 is CPython's correctly rounded strtod).
        width = np.arange(_VECTOR_NUMBER_BYTES)
        index = first[short, None] + width
        rows = np.where(width < length[short, None],
                        buf[np.minimum(index, buf.shape[0] - 1)], 0).astype(np.uint8)
        with np.errstate(over="ignore"):   # out of range: infinity, reported below
            nums[where[short]] = rows.view(f"S{_VECTOR_NUMBER_BYTES}").ravel().astype(
                np.float64)
    for k in np.flatnonzero(~short).tolist():
        nums[where[k]] = float(data[first[k]:end[k]])
    overflow = ~np.isfinite(nums[where])
    if overflow.any():
        k = int(np.flatnonzero(overflow)[0])
        p = int(np.searchsorted(path_bytes, first[k], side="right") - 1)
        raise _parse_error(ds, p, int(first[k] - path_bytes[p]), svgparse.OUT_OF_RANGE, bulk)


# --------------------------------------------------------------------------- writing

def write_path(p: PathArrays, index: int = 0, *, precision: int | None = 6) -> str:
    """Return path `index` of `p` as compact SVG path data.

    Parameters
    ----------
    p : PathArrays
        The paths.
    index : int
        Which path (negative counts from the end).
    precision : int or None
        As for `write_paths`.

    Returns
    -------
    str
        Path data; ``""`` for a path with no subpaths.

    Examples
    --------
    >>> write_path(parse_path("M 0 0 L 10 0 L 10 -10.5 C 0.5 0, 1 1, 2 2 Z"))
    'M0 0H10V-10.5C.5 0 1 1 2 2Z'
    """
    return write_paths(p.path(index), precision=precision)[0]


def write_paths(p: PathArrays, *, precision: int | None = 6) -> list[str]:
    """Return every path of `p` as compact SVG path data.

    Parameters
    ----------
    p : PathArrays
        The paths.
    precision : int or None
        Significant digits of each number (1 to `MAX_PRECISION`), the digits of
        ``'%.*g' % (precision, x)``: each written number is within
        ``0.5 * 10**(1 - precision)`` of its value, relative. None writes the shortest
        decimal that reads back as the same float64, the digits of ``repr(x)``, so
        ``parse_paths(write_paths(p, precision=None)) == p`` exactly.

    Returns
    -------
    list of str
        One string per path.

    Raises
    ------
    InvalidOptionError
        `precision` is not None or an int from 1 to `MAX_PRECISION`.

    Notes
    -----
    Coordinates are absolute. A line is ``H``/``V`` when its end shares its start's y/x,
    ``L`` otherwise; a quadratic is ``T`` and a cubic ``S`` when its first control point
    is the one the reader infers (the reflection of the previous control point computed
    as ``2 * current - previous``, or the current point), ``Q``/``C`` otherwise. A
    command letter is left out when it repeats the previous one (``L`` also after
    ``M``), and ``M`` after ``Z`` when the new subpath starts at the closed one's start.
    Numbers are formatted by a kernel, except the rare ones it cannot round with
    certainty (see `rnsca.io.svgwrite`), which Python formats. They drop leading
    and trailing zeros (``.5``, ``2``), use an exponent when that is shorter (``1e6``,
    ``12e-7``), and are separated by a space only where neither a
    minus sign nor a second decimal point separates them (``1-2``, ``.5.5``). With a
    finite precision the reflections and the points that ``H``, ``V`` and an omitted
    ``M`` take from the current point are computed by the reader from rounded numbers,
    so they are within a few roundings of the original (``T`` never follows ``T``
    then: the reader would add up the roundings along a chain).

    Examples
    --------
    >>> write_paths(parse_paths(["M0 0 l 1 -2 l -0.5 -0.5", "M1 1 Z L 2 2"]))
    ['M0 0 1-2 .5-2.5', 'M1 1ZL2 2']
    >>> write_paths(parse_paths(["M0 0 L 0.1 0.2"]), precision=None)
    ['M0 0 .1.2']
    """
    if precision is not None and (not isinstance(precision, (int, np.integer))
                                  or isinstance(precision, bool)
                                  or not 1 <= precision <= MAX_PRECISION):
        raise InvalidOptionError(f"precision must be None or an int from 1 to "
                                 f"{MAX_PRECISION}, not {precision!r}")
    if len(p) == 0:
        return []
    kind, with_moveto = svgwrite.classify(p.controls, p.degree, p.subpath_offsets, p.closed,
                                          p.start, p.path_offsets, precision is None)
    seg_value_offsets = _prefix_sum(svgwrite.NUMBER_COUNT[kind])
    start_value_offsets = _prefix_sum(with_moveto.astype(np.int64) * 2) + seg_value_offsets[-1]
    values, text, length = svgwrite.format_values(
        p.controls, p.start, kind, with_moveto, seg_value_offsets, start_value_offsets,
        0 if precision is None else precision)
    left = np.flatnonzero(length == 0)
    if left.size:
        _format_in_python(values[left], precision, text, length, left)
    data, bounds = svgwrite.write(kind, with_moveto, p.subpath_offsets, p.closed,
                                  p.path_offsets, seg_value_offsets, start_value_offsets, text,
                                  length)
    out = data.tobytes().decode("ascii")
    return [out[a:b] for a, b in pairwise(bounds.tolist())]


def _format_in_python(values: np.ndarray, precision: int | None, text: np.ndarray,
                      length: np.ndarray, rows: np.ndarray) -> None:
    """Fill `text` and `length` at `rows` with the compact text of `values`.

    Python's ``repr`` and ``%g`` round correctly; each distinct value is formatted once.
    """
    unique, inverse = np.unique(values, return_inverse=True)
    if precision is None:
        texts = [_compact(repr(v)) for v in unique.tolist()]
    else:
        spec = f"%.{precision}g"
        texts = [_compact(spec % v) for v in unique.tolist()]
    width = svgwrite.TEXT_WIDTH
    table = np.frombuffer("".join(t.ljust(width, "\0") for t in texts).encode("ascii"),
                          dtype=np.uint8).reshape(-1, width)
    inverse = inverse.reshape(-1)
    text[rows] = table[inverse]
    length[rows] = np.fromiter(map(len, texts), dtype=np.int8, count=len(texts))[inverse]


def _compact(text: str) -> str:
    """Return the shortest spelling of the decimal `text` (from repr or ``%g``).

    >>> [_compact(t) for t in ("0.5", "-0.25", "100000.0", "1e-05", "1.5e+20", "-0.0")]
    ['.5', '-.25', '1e5', '1e-5', '15e19', '0']
    """
    sign = ""
    if text[0] == "-":
        sign, text = "-", text[1:]
    mantissa, _, exponent = text.partition("e")
    whole, _, fraction = mantissa.partition(".")
    digits = (whole + fraction).lstrip("0")
    if not digits:
        return "0"
    # value = int(digits) * 10**q once trailing zeros are moved into q.
    q = (int(exponent) if exponent else 0) - len(fraction)
    stripped = digits.rstrip("0")
    q += len(digits) - len(stripped)
    digits = stripped
    n = len(digits)
    if q >= 0:
        positional = digits + "0" * q
    elif -q < n:
        positional = f"{digits[:n + q]}.{digits[n + q:]}"
    else:
        positional = "." + "0" * (-q - n) + digits
    scientific = f"{digits}e{q}"
    return sign + (positional if len(positional) <= len(scientific) else scientific)


def warm_up_readers() -> None:
    """Compile (or load from Numba's cache) the path reader's and writer's kernels.

    Reads a path of every command (arcs too) and writes it back, exactly and rounded,
    with enough paths to take the parallel drivers as well.
    """
    sample = "M-1 .5C0 2 1-1 2 .5Q.5 3-1 .5S3 3 4 4T5 5A1 2 30 0 1 6 6H7V8L9 9Zm1 1h1v1z"
    for count in (1, 256):
        paths = parse_paths([sample] * count)
        write_paths(paths, precision=None)
        write_paths(paths, precision=6)
