"""Glyphs of a font file as paths: by code point or glyph name, laid out, clipped.

`Font` reads a TrueType or OpenType font (``glyf`` quadratics or CFF cubics), a WOFF or
a WOFF2 file (`rnsca.io.opentype`) and gives each glyph's outline as a `PathArrays`
of one path, with the font's curves, in font units (y up). `Font.text_paths` lays out a
string, or a sequence of code points and glyph names, one path per glyph; `clip_glyphs`
clips that layout with `rnsca.clip_paths` (curves kept, filled under the nonzero rule,
as TrueType and CFF outlines are) and writes the clipped path data;
`GlyphClipResult.svg` writes it as a standalone SVG document.

Coordinates (`Units`):

- ``"font"``: the font's units, y up, the em ``unitsPerEm`` units high; the first
  glyph's origin (on the baseline) at `origin`.
- ``"user"``: SVG's user units, y down: ``scale = size / unitsPerEm`` user units per
  font unit, y flipped, the first glyph's origin at `origin` (a baseline at
  ``origin[1]``, glyphs above it at smaller y). A point ``(x, y)`` of a glyph whose pen
  position is ``(px, py)`` (font units) goes to
  ``(origin[0] + scale * (x + px), origin[1] - scale * (y + py))``.

Layout is by advance widths alone (``hmtx``): glyph after glyph along the baseline, a
line break (a newline, or any of `str.splitlines`' separators) returning to
``origin[0]`` one line lower (``ascent - descent + lineGap`` of ``hhea``). There is
no kerning (neither the ``kern`` table nor GPOS), no shaping (GSUB: ligatures,
contextual forms, complex scripts) and no bidirectional or vertical text.

fontTools is the ``fonts`` extra (``pip install 'rnsca[fonts]'``, with brotli for
WOFF2); it is imported when a font is first read, and its absence raises a
ModuleNotFoundError that says so.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from rnsca.arrays import PathArrays
from rnsca.clip_svg import PathClipResult, clip_paths
from rnsca.errors import FontError, InvalidOptionError
from rnsca.io.svgpath import write_path, write_paths
from rnsca.options import Fill, Units
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["Font", "Glyph", "GlyphClipResult", "GlyphRun", "Units", "clip_glyphs"]

# The largest Unicode code point.
_MAX_CODEPOINT = 0x10FFFF

GlyphKey = int | str
# The arrays of a PathArrays. Writable ones: Numba compiles a kernel again for read-only
# arrays (seconds), so the font's cached outlines are copied, never frozen.
_PATH_FIELDS = ("controls", "degree", "subpath_offsets", "closed", "start", "path_offsets")


def _opentype() -> ModuleType:
    """Return `rnsca.io.opentype`, or say which extra to install for fontTools."""
    try:
        from rnsca.io import opentype
    except ModuleNotFoundError as error:
        if not (error.name or "").startswith("fontTools"):
            raise
        raise ModuleNotFoundError("rnsca.fonts needs fontTools: pip install 'rnsca[fonts]'",
                                  name="fontTools") from error
    return opentype


@dataclass(frozen=True, eq=False, slots=True)
class Glyph:
    """One glyph of a font: its outline in font units (y up) and its advance width.

    Attributes
    ----------
    name : str
        The glyph's name in the font (``post`` or CFF names; fontTools makes up
        ``glyph00042``-style names where the font has none).
    codepoint : int or None
        The code point it was asked for by; None when asked for by name.
    advance : int
        Advance width (``hmtx``), font units.
    units_per_em : int
        The font's em, font units.
    paths : PathArrays
        One path, one closed subpath per contour (none for an empty glyph such as a
        space): lines and quadratics (TrueType) or lines and cubics (CFF). Its arrays
        are the caller's (a copy of the font's cache).
    """

    name: str
    codepoint: int | None
    advance: int
    units_per_em: int
    paths: PathArrays

    @property
    def d(self) -> str:
        """Return the outline as SVG path data, font units, every number exact."""
        return write_path(self.paths, precision=None)


@dataclass(frozen=True, eq=False, slots=True)
class GlyphRun:
    """Glyphs laid out along baselines: path ``i`` is glyph ``names[i]`` in place.

    Attributes
    ----------
    paths : PathArrays
        One path per glyph, in the run's `units`.
    names : tuple of str
        The glyph of each path.
    origins : ndarray of float64, shape (n, 2)
        Where each glyph's origin (its left end on the baseline) was placed, in `units`.
    units : Units
        Font units (y up) or user units (y down).
    scale : float
        Units of the run per font unit: 1 in font units, ``size / unitsPerEm`` in user
        units.
    """

    paths: PathArrays
    names: tuple[str, ...]
    origins: np.ndarray
    units: Units
    scale: float

    def __len__(self) -> int:
        """Return the number of glyphs."""
        return len(self.names)


@dataclass(frozen=True, eq=False, slots=True)
class GlyphClipResult:
    """Glyphs clipped to a window: path ``i`` of `paths` and ``d[i]`` are glyph ``i``'s.

    Attributes
    ----------
    run : GlyphRun
        The glyphs before the clip (pass ``run.paths`` and `clip` to `rnsca.verify`).
    clip : PathClipResult
        The clip of ``run.paths``; `paths` and `stats` are its.
    d : list of str
        SVG path data of each clipped glyph (``""`` where nothing is left).
    window : Window
        The window, in the run's units.
    """

    run: GlyphRun
    clip: PathClipResult
    d: list[str]
    window: Window

    @property
    def paths(self) -> PathArrays:
        """Return the clipped glyphs, one path per glyph of the run."""
        return self.clip.paths

    @property
    def stats(self) -> ClipStats:
        """Return the clip's statistics."""
        return self.clip.stats

    def svg(self) -> str:
        """Return a standalone SVG document of the clipped glyphs.

        Its ``viewBox`` is the window; one ``path`` per glyph with something left
        (``data-glyph`` names the glyph), filled under the clip's fill rule (stroked,
        one pixel wide at any zoom, where the clip ran on strokes). In font units (y up)
        the paths keep their coordinates and a group flips them about the window's
        middle (``matrix(1 0 0 -1 0 ymin+ymax)``), so the document shows the glyphs
        upright over the same window.
        """
        w = self.window
        view = " ".join(_number(v) for v in (w.xmin, w.ymin, w.xmax - w.xmin, w.ymax - w.ymin))
        stroke = ""  # vector-effect is not inherited: each path has it
        if self.clip.fill is None:
            paint = 'fill="none" stroke="black"'
            stroke = ' vector-effect="non-scaling-stroke"'
        else:
            paint = f'fill="black" fill-rule="{self.clip.fill}"'
        if self.run.units is Units.FONT:
            paint += f' transform="matrix(1 0 0 -1 0 {_number(w.ymin + w.ymax)})"'
        lines = ['<?xml version="1.0" encoding="UTF-8"?>',
                 f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{view}">',
                 f"  <g {paint}>"]
        lines += [f"    <path data-glyph={quoteattr(name)} d={quoteattr(d)}{stroke}/>"
                  for name, d in zip(self.run.names, self.d, strict=True) if d]
        lines += ["  </g>", "</svg>", ""]
        return "\n".join(lines)


class Font:
    """A font file's glyphs: outlines by code point or glyph name, and text laid out.

    Parameters
    ----------
    source : str or path-like
        A TrueType or OpenType font (.ttf, .otf: ``glyf`` or CFF outlines), WOFF or
        WOFF2 file; the format is read from the file's first bytes.

    Attributes
    ----------
    path : str
        The file read.
    units_per_em : int
        Font units to the em (``head``).
    outlines : str
        ``"truetype"`` (quadratics), ``"cff"`` or ``"cff2"`` (cubics).
    flavor : str or None
        ``"woff"`` or ``"woff2"`` for a web font, None for a plain OpenType file.
    ascent, descent, line_gap : int
        Vertical metrics of ``hhea`` (descent negative), font units.

    Raises
    ------
    FontError
        (a ValueError) The file is missing, unreadable, not such a font, or has no
        outlines; the message names the file.
    ModuleNotFoundError
        fontTools is not installed (or brotli, for a WOFF2 file).

    Examples
    --------
    >>> Font("no-such-font.ttf")
    Traceback (most recent call last):
    ...
    rnsca.errors.FontError: no-such-font.ttf: No such file or directory
    """

    def __init__(self, source: str | os.PathLike[str]) -> None:
        opentype = _opentype()
        self.path = os.fspath(source)
        self._opentype = opentype
        self._font = opentype.read_font(source)
        self._glyph_set = self._font.getGlyphSet()
        self._cmap: dict[int, str] = self._font.getBestCmap() or {}
        self._names = frozenset(self._font.getGlyphOrder())
        self._outlines: dict[str, PathArrays] = {}
        self.units_per_em = int(self._font["head"].unitsPerEm)
        self.outlines: str = opentype.outline_format(self._font)
        self.flavor: str | None = self._font.flavor
        hhea = self._font["hhea"]
        self.ascent, self.descent = int(hhea.ascent), int(hhea.descent)
        self.line_gap = int(hhea.lineGap)

    def __repr__(self) -> str:
        return (f"Font({self.path!r}, outlines={self.outlines!r}, "
                f"units_per_em={self.units_per_em})")

    @property
    def line_height(self) -> int:
        """Return the distance between baselines, ``ascent - descent + line_gap``."""
        return self.ascent - self.descent + self.line_gap

    def glyph(self, key: GlyphKey | None = None, *, name: str | None = None) -> Glyph:
        """Return a glyph by code point, character or glyph name.

        Parameters
        ----------
        key : int or str
            An int is a code point, a one-character str that character, both looked up
            in the font's Unicode cmap; a longer str is a glyph name.
        name : str, keyword only
            A glyph name, whatever its length (instead of `key`).

        Returns
        -------
        Glyph

        Raises
        ------
        FontError
            (a ValueError) The code point is not in the cmap, or no glyph has the name;
            the message names the character and the font.
        TypeError
            Neither or both of `key` and `name`, or a key of another type.
        """
        if (key is None) == (name is None):
            raise TypeError("glyph() takes a code point, a character or a glyph name "
                            "(key), or name=")
        if name is not None:
            if not isinstance(name, str):
                raise TypeError(f"name must be a str, not {type(name).__name__}")
            return self._glyph(self._named(name), None)
        assert key is not None
        glyph_name, codepoint = self._resolve(key)
        return self._glyph(glyph_name, codepoint)

    def text_paths(self, text: str | Sequence[GlyphKey], *, size: float | None = None,
                   units: Units | str | None = None,
                   origin: Iterable[float] = (0.0, 0.0)) -> GlyphRun:
        """Return the glyphs of `text` laid out left to right, one path per glyph.

        Parameters
        ----------
        text : str or sequence of (int or str)
            Characters, each looked up in the cmap, line breaks starting a new line; or
            glyph keys as for `glyph` (code points, characters, glyph names), one line.
        size : float, optional
            The em in user units (the font size); needs, and implies, user units.
        units : {"font", "user"}, optional
            Default: ``"user"`` when `size` is given, else ``"font"``.
        origin : pair of float
            Where the first glyph's origin goes, in the output's units.

        Returns
        -------
        GlyphRun
            A path for every glyph, also those without outline (spaces: no subpath).

        Raises
        ------
        FontError
            A character or glyph is not in the font (the first one, named).
        InvalidOptionError
            `units`, `size` or `origin` is bad: ``"user"`` without a size, a size with
            ``"font"``, a size not a positive finite number, an origin not two finite
            numbers.
        """
        kind, scale = _units(units, size, self.units_per_em)
        start = _origin(origin)
        names: list[str] = []
        pens: list[tuple[float, float]] = []
        for row, line in enumerate(_lines(text)):
            x, y = 0, -row * self.line_height
            for key in line:
                name, _ = self._resolve(key)
                names.append(name)
                pens.append((x, y))
                x += self._advance(name)
        factor = np.array([scale, scale if kind is Units.FONT else -scale])
        pen = np.array(pens, dtype=np.float64).reshape(-1, 2)
        paths = _place([self._outline(n) for n in names], pen, factor, start)
        return GlyphRun(paths, tuple(names), start + pen * factor, kind, scale)

    # ------------------------------------------------------------------ lookups

    def _resolve(self, key: GlyphKey) -> tuple[str, int | None]:
        """Return the glyph name of a code point, character or name, and the code point."""
        if isinstance(key, bool) or not isinstance(key, (int, np.integer, str)):
            raise TypeError(f"a glyph is a code point (int), a character or a glyph name "
                            f"(str), not {type(key).__name__}")
        if isinstance(key, str) and len(key) != 1:
            return self._named(key), None
        codepoint = ord(key) if isinstance(key, str) else int(key)
        if not 0 <= codepoint <= _MAX_CODEPOINT:
            raise FontError(f"{codepoint} is not a Unicode code point (0 to U+10FFFF)")
        name = self._cmap.get(codepoint)
        if name is None:
            raise FontError(f"{_describe(codepoint)} is not in the cmap of {self.path}")
        return name, codepoint

    def _named(self, name: str) -> str:
        if name not in self._names:
            raise FontError(f"{self.path} has no glyph named {name!r}"
                            if name else "a glyph name cannot be empty")
        return name

    def _glyph(self, name: str, codepoint: int | None) -> Glyph:
        cached = self._outline(name)
        paths = PathArrays.from_kernel(**{field: getattr(cached, field).copy()
                                          for field in _PATH_FIELDS})
        return Glyph(name, codepoint, self._advance(name), self.units_per_em, paths)

    def _advance(self, name: str) -> int:
        return int(self._glyph_set[name].width)

    def _outline(self, name: str) -> PathArrays:
        """Return the outline of glyph `name` (font units), read once."""
        paths = self._outlines.get(name)
        if paths is None:
            paths = self._outlines[name] = self._opentype.glyph_outline(self._glyph_set, name)
        return paths


def clip_glyphs(font: Font | str | os.PathLike[str], text: str | Sequence[GlyphKey],
                window: Window | Iterable[float], *, units: Units | str | None = None,
                size: float | None = None, origin: Iterable[float] = (0.0, 0.0),
                fill: Fill | str | None = "nonzero", precision: int | None = None,
                **options: Any) -> GlyphClipResult:
    """Return the glyphs of `text` laid out and clipped to `window`, curves kept.

    Parameters
    ----------
    font : Font, str or path-like
        A font, or its file.
    text : str or sequence of (int or str)
        As for `Font.text_paths`.
    window : Window or sequence of 4 floats
        ``(xmin, ymin, xmax, ymax)`` in the layout's units: font units (y up) or user
        units (y down).
    units, size, origin
        The layout, as for `Font.text_paths`: font units unless a size is given.
    fill : {"nonzero", "evenodd", None}
        The fill rule the outlines are clipped as; TrueType and CFF glyphs fill under
        nonzero (the default). None clips the outlines as strokes.
    precision : int or None
        Significant digits of the path data `d`; None (default) writes each number
        exactly.
    **options
        `rnsca.clip_paths`'s: ``curves`` ("preserve" by default: TrueType quadratics
        stay quadratics, CFF cubics cubics), ``tolerance``, ``method``, ``n``,
        ``max_depth``, ``mode``, ``backend``.

    Returns
    -------
    GlyphClipResult
        The layout, its clip, the clipped path data (one string per glyph) and the
        window; ``.svg()`` writes them as an SVG document.

    Raises
    ------
    InvalidWindowError
        The window is empty or not finite (checked, as the layout's options, before the
        font is read).
    FontError
        The font cannot be read or lacks a character of `text`.
    InvalidOptionError
        A bad layout or clip option.
    """
    window = Window.of(window)
    _units(units, size, 1)  # the options' errors before the font's
    _origin(origin)
    if not isinstance(font, Font):
        font = Font(font)
    run = font.text_paths(text, size=size, units=units, origin=origin)
    clip = clip_paths(run.paths, window, fill=fill, **options)
    return GlyphClipResult(run, clip, write_paths(clip.paths, precision=precision), window)


# ------------------------------------------------------------------ helpers

def _units(units: Units | str | None, size: float | None,
           units_per_em: int) -> tuple[Units, float]:
    """Return the layout's units and its scale (output units per font unit)."""
    kind = (Units.FONT if size is None else Units.USER) if units is None else Units(units)
    if kind is Units.FONT:
        if size is not None:
            raise InvalidOptionError(f"size applies to user units; font units are the "
                                     f"font's own (got size={size!r} with units='font')")
        return kind, 1.0
    if size is None:
        raise InvalidOptionError("units='user' needs a size: the em in user units")
    number = isinstance(size, (int, float, np.integer, np.floating))
    if isinstance(size, bool) or not number or not (math.isfinite(size) and size > 0):
        raise InvalidOptionError(f"size must be a positive finite number, got {size!r}")
    return kind, float(size) / units_per_em


def _origin(origin: Iterable[float]) -> np.ndarray:
    try:
        point = np.array([float(v) for v in origin], dtype=np.float64)
    except (TypeError, ValueError):
        point = np.empty(0)
    if point.shape != (2,) or not np.isfinite(point).all():
        raise InvalidOptionError(f"origin must be two finite numbers (x, y), got {origin!r}")
    return point


def _lines(text: str | Sequence[GlyphKey]) -> list[Sequence[GlyphKey]]:
    """Return the lines of a text (a sequence of glyph keys is one line)."""
    if isinstance(text, str):
        return list(text.splitlines()) or [""]
    if not isinstance(text, Sequence):
        raise TypeError(f"text must be a str or a sequence of code points and glyph "
                        f"names, not {type(text).__name__}")
    return [text]


def _place(outlines: list[PathArrays], pens: np.ndarray, factor: np.ndarray,
           origin: np.ndarray) -> PathArrays:
    """Return the outlines as one `PathArrays`, outline ``i`` moved by ``pens[i]``.

    A point ``p`` of outline ``i`` goes to ``origin + (p + pens[i]) * factor``: an
    affine map, under which a Bézier's control points map to the control points of
    the mapped curve, so curves stay curves of the same degree.
    """
    if not outlines:
        return PathArrays.empty()
    segments = np.cumsum([0] + [o.degree.shape[0] for o in outlines])
    subpaths = np.cumsum([0] + [o.closed.shape[0] for o in outlines])
    return PathArrays(
        controls=np.concatenate([origin + (o.controls + pen) * factor
                                 for o, pen in zip(outlines, pens, strict=True)]),
        degree=np.concatenate([o.degree for o in outlines]),
        subpath_offsets=np.concatenate(
            [[0]] + [o.subpath_offsets[1:] + base
                     for o, base in zip(outlines, segments, strict=False)]),
        closed=np.concatenate([o.closed for o in outlines]),
        start=np.concatenate([origin + (o.start + pen) * factor
                              for o, pen in zip(outlines, pens, strict=True)]),
        path_offsets=subpaths)


def _describe(codepoint: int) -> str:
    """Return ``U+0041 'A'`` (the character left out where it would not print)."""
    char = chr(codepoint)
    return f"U+{codepoint:04X} {char!r}" if char.isprintable() else f"U+{codepoint:04X}"


def _number(value: float) -> str:
    """Return `value` as the shortest number that reads back as it (``2048``, ``0.5``)."""
    text = repr(float(value))
    if text.endswith(".0"):
        text = text[:-2]
    return "0" if text == "-0" else text
