"""Font files read with fontTools: glyph outlines as `PathArrays`, in font units.

`read_font` opens an OpenType font (TrueType ``glyf`` or CFF outlines), a WOFF or a WOFF2
file; `glyph_outline` returns one glyph's contours as a `PathArrays` of one path, in font
units with y up, with the font's own curves:

- TrueType (``glyf``): quadratic Béziers. A run of off-curve points has an implied
  on-curve point halfway between each two; a contour of off-curve points only starts at
  the implied point between its last and its first. fontTools' ``BasePen`` makes those
  points explicit (``decomposeQuadraticSegment``), so each segment is one quadratic.
- CFF (``CFF ``, ``CFF2`` at the default location): cubic Béziers.
- Composite glyphs: each component drawn in place through its transform (fontTools'
  ``DecomposingPen``, which ``BasePen`` is).

Every contour is a closed subpath: ``closed`` is set and the line back to its start is
implicit, as after ``Z``; a closing curve is an explicit segment. Only the outlines are
read (no hinting, no bitmaps, no colour layers).

This module imports fontTools (the ``fonts`` extra) when it is imported; `rnsca.fonts`
imports it on first use. WOFF2 also needs brotli (in the ``fonts`` extra too).
"""

from __future__ import annotations

import io
import os
from typing import Any

import numpy as np
from fontTools.pens.basePen import BasePen
from fontTools.ttLib import TTFont, TTLibError

from rnsca.arrays import PathArrays
from rnsca.errors import FontError

__all__ = ["INSTALL_HINT", "OUTLINE_TABLES", "glyph_outline", "outline_format", "read_font"]

#: What to install for this module and WOFF2 decoding.
INSTALL_HINT = "pip install 'rnsca[fonts]'"
#: The tables that hold outlines, and the name of each format.
OUTLINE_TABLES = {"glyf": "truetype", "CFF ": "cff", "CFF2": "cff2"}

Point = tuple[float, float]


def read_font(source: str | os.PathLike[str]) -> Any:
    """Return the font in file `source` as a fontTools ``TTFont``.

    Parameters
    ----------
    source : str or path-like
        A TrueType or OpenType font (.ttf, .otf), a WOFF (.woff) or WOFF2 (.woff2) file;
        the format is read from the file's first bytes, not its name.

    Returns
    -------
    fontTools.ttLib.TTFont
        With the tables the outlines need already read (``head``, ``hmtx``, ``cmap`` and
        the outline table).

    Raises
    ------
    FontError
        The file cannot be opened, is not a font of those formats (a font collection
        too), or a table the outlines need is missing or damaged; the message names the
        file and what is wrong.
    ModuleNotFoundError
        A WOFF2 file, and brotli is not installed.
    """
    name = os.fspath(source)
    try:  # read whole: the font then holds no open file
        with open(name, "rb") as stream:
            data = stream.read()
    except OSError as error:
        raise FontError(f"{name}: {error.strerror or error}") from None
    try:
        font = TTFont(io.BytesIO(data))
    except ImportError as error:  # fontTools' WOFF2 reader without brotli
        raise ModuleNotFoundError(f"{name}: reading WOFF2 needs brotli: {INSTALL_HINT}",
                                  name="brotli") from error
    except TTLibError as error:
        raise FontError(f"{name}: not a TrueType, OpenType, WOFF or WOFF2 font ({error})"
                        ) from None
    except Exception as error:  # noqa: BLE001 - fontTools reports damage in many types
        raise FontError(f"{name}: not a readable font ({type(error).__name__}: {error})"
                        ) from None
    if outline_format(font) is None:
        raise FontError(f"{name}: the font has no outlines (none of the tables "
                        f"{', '.join(repr(t) for t in OUTLINE_TABLES)})")
    try:  # read now what every glyph needs, so that a damaged table is found here
        for tag in ("head", "hhea", "hmtx", "cmap", next(t for t in OUTLINE_TABLES
                                                          if t in font)):
            font[tag]
    except Exception as error:  # noqa: BLE001 - as above
        raise FontError(f"{name}: damaged or missing font table ({type(error).__name__}: "
                        f"{error})") from None
    return font


def outline_format(font: Any) -> str | None:
    """Return ``"truetype"``, ``"cff"`` or ``"cff2"``: the outlines of `font` (None: none)."""
    return next((kind for tag, kind in OUTLINE_TABLES.items() if tag in font), None)


def glyph_outline(glyphs: Any, name: str) -> PathArrays:
    """Return the contours of glyph `name` as one path, in font units (y up).

    Parameters
    ----------
    glyphs : fontTools glyph set
        ``TTFont.getGlyphSet()`` of the font.
    name : str
        A glyph name of the font.

    Returns
    -------
    PathArrays
        One path, one closed subpath per contour (none for a glyph without outline,
        such as a space); segments of degree 1 and 2 (TrueType) or 1 and 3 (CFF).

    Raises
    ------
    FontError
        The glyph's outline cannot be drawn (damaged data).
    """
    pen = _OutlinePen(glyphs)
    try:
        glyphs[name].draw(pen)
    except Exception as error:  # noqa: BLE001 - damaged glyph data, in fontTools' types
        raise FontError(f"glyph {name!r}: cannot draw its outline "
                        f"({type(error).__name__}: {error})") from None
    return pen.paths()


class _OutlinePen(BasePen):
    """A fontTools pen that collects contours as rows of `PathArrays` control points.

    ``BasePen`` splits TrueType runs of off-curve points into single quadratics
    (``_qCurveToOne``), CFF's cubics arrive as ``_curveToOne``, and components are
    drawn through their transforms; each segment is stored from the current point.
    """

    def __init__(self, glyphs: Any) -> None:
        super().__init__(glyphs)
        self._controls: list[tuple[Point, Point, Point, Point]] = []
        self._degree: list[int] = []
        self._starts: list[Point] = []
        self._closed: list[bool] = []
        self._ends: list[int] = [0]  # segment offsets of the subpaths

    def _moveTo(self, pt: Point) -> None:  # noqa: N802 - fontTools' pen protocol
        self._starts.append(pt)

    def _lineTo(self, pt: Point) -> None:  # noqa: N802
        self._add(1, self._getCurrentPoint(), pt, pt, pt)

    def _qCurveToOne(self, pt1: Point, pt2: Point) -> None:  # noqa: N802
        self._add(2, self._getCurrentPoint(), pt1, pt2, pt2)

    def _curveToOne(self, pt1: Point, pt2: Point, pt3: Point) -> None:  # noqa: N802
        self._add(3, self._getCurrentPoint(), pt1, pt2, pt3)

    def _closePath(self) -> None:  # noqa: N802
        self._end(True)

    def _endPath(self) -> None:  # noqa: N802 - an open contour (not in glyf or CFF data)
        self._end(False)

    def _add(self, degree: int, *points: Point) -> None:
        self._controls.append(points)  # type: ignore[arg-type]
        self._degree.append(degree)

    def _end(self, closed: bool) -> None:
        self._closed.append(closed)
        self._ends.append(len(self._degree))

    def paths(self) -> PathArrays:
        """Return the contours drawn so far as one path."""
        k = len(self._closed)
        return PathArrays(
            controls=np.array(self._controls, dtype=np.float64).reshape(-1, 4, 2),
            degree=np.array(self._degree, dtype=np.int8),
            subpath_offsets=np.array(self._ends, dtype=np.int64),
            closed=np.array(self._closed, dtype=bool),
            start=np.array(self._starts, dtype=np.float64).reshape(k, 2),
            path_offsets=np.array([0, k], dtype=np.int64))
