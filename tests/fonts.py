"""Glyph outlines from the fonts of Debian packages, read with fontTools, for the tests.

Fonts are found by their path in the Debian package that ships them (`FONTS`); `.ci/run`
installs the packages. Outside CI a missing font or fontTools skips the tests that need
it, with the reason; in CI (``CI=true``) it fails them.

Besides the path data (``SVGPathPen``), a glyph is drawn into pens written here, so that
the oracles never go through rnsca's own parser or flattener: `FlattenPen` samples every
curve finely (a stated chord tolerance) into closed rings, and fontTools' ``AreaPen``
integrates the exact curves (Green's theorem). `draw_paths` replays clipped
`PathArrays` into the same pens.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path

import numpy as np
import shapely

from rnsca import PathArrays
from tests.missing import missing

try:
    from fontTools.pens.areaPen import AreaPen
    from fontTools.pens.basePen import BasePen
    from fontTools.pens.boundsPen import BoundsPen
    from fontTools.pens.recordingPen import DecomposingRecordingPen
    from fontTools.pens.svgPathPen import SVGPathPen
    from fontTools.ttLib import TTFont
except ImportError:  # reported by `require_font`, which every glyph test goes through
    AreaPen = BasePen = BoundsPen = DecomposingRecordingPen = SVGPathPen = TTFont = None

__all__ = [
    "FONTS",
    "Font",
    "Glyph",
    "FlattenPen",
    "draw_paths",
    "exact_signed_area",
    "flat_lines",
    "flat_rings",
    "load_glyph",
    "require_font",
]



@dataclass(frozen=True)
class Font:
    """A font file from a Debian package, and the degree of its curves."""

    path: Path
    package: str
    degree: int  # 2: TrueType quadratics (glyf); 3: CFF cubics


FONTS = {
    "dejavu-sans": Font(Path("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"),
                        "fonts-dejavu-core", 2),
    "dejavu-serif": Font(Path("/usr/share/fonts/truetype/dejavu/DejaVuSerif.ttf"),
                         "fonts-dejavu-core", 2),
    "nimbus-sans": Font(Path("/usr/share/fonts/opentype/urw-base35/NimbusSans-Regular.otf"),
                        "fonts-urw-base35", 3),
    "nimbus-roman": Font(Path("/usr/share/fonts/opentype/urw-base35/NimbusRoman-Regular.otf"),
                         "fonts-urw-base35", 3),
}


def require_font(key: str) -> Font:
    """Return the font `key`, or fail (CI) or skip (elsewhere) saying what is missing."""
    font = FONTS[key]
    message = None
    if TTFont is None:
        message = "fontTools is not installed (pip install fonttools, in the dev extra)"
    elif not font.path.is_file():
        message = (f"{font.path} not found: install the Debian package {font.package} "
                   f"(apt-get install {font.package}; .ci/run does)")
    if message is not None:
        missing(message)
    return font


if BasePen is not None:
    class FlattenPen(BasePen):
        """Collect each contour as a closed ring of points within `tolerance` of it.

        A curve is sampled at equal parameter steps, as many as keep every chord within
        `tolerance` of the curve: a chord over a parameter step h lies within
        ``max|B''| h**2 / 8`` of the curve, and ``max|B''|`` is at most
        ``2 |p0 - 2 p1 + p2|`` (quadratic) or ``6 max(|p0 - 2 p1 + p2|, |p1 - 2 p2 + p3|)``
        (cubic).
        """

        def __init__(self, tolerance: float, glyphset=None):
            super().__init__(glyphset)
            self.tolerance = tolerance
            self.rings: list[np.ndarray] = []  # closed contours, last point = first
            self.lines: list[np.ndarray] = []  # open contours (strokes)
            self._points: list[np.ndarray] = []

        def _steps(self, bound: float) -> int:
            return max(1, math.ceil(math.sqrt(bound / (8.0 * self.tolerance))))

        def _moveTo(self, p):
            self._points = [np.array([p], dtype=float)]

        def _lineTo(self, p):
            self._points.append(np.array([p], dtype=float))

        def _qCurveToOne(self, p1, p2):
            p0, p1, p2 = self._points[-1][-1], np.asarray(p1, float), np.asarray(p2, float)
            n = self._steps(2.0 * float(np.hypot(*(p0 - 2 * p1 + p2))))
            t = np.linspace(0.0, 1.0, n + 1)[1:, None]
            self._points.append((1 - t) ** 2 * p0 + 2 * t * (1 - t) * p1 + t * t * p2)

        def _curveToOne(self, p1, p2, p3):
            p0 = self._points[-1][-1]
            p1, p2, p3 = (np.asarray(p, float) for p in (p1, p2, p3))
            second = max(np.hypot(*(p0 - 2 * p1 + p2)), np.hypot(*(p1 - 2 * p2 + p3)))
            n = self._steps(6.0 * float(second))
            t = np.linspace(0.0, 1.0, n + 1)[1:, None]
            self._points.append((1 - t) ** 3 * p0 + 3 * t * (1 - t) ** 2 * p1
                                + 3 * t * t * (1 - t) * p2 + t ** 3 * p3)

        def _closePath(self):
            ring = np.concatenate(self._points)
            if (ring[-1] != ring[0]).any():
                ring = np.concatenate([ring, ring[:1]])
            self.rings.append(ring)
            self._points = []

        def _endPath(self):
            self.lines.append(np.concatenate(self._points))
            self._points = []
else:
    FlattenPen = None


def draw_paths(paths: PathArrays, pen, close: bool = True) -> None:
    """Replay every subpath of `paths` into a fontTools pen (all closed, if `close`)."""
    for s in range(paths.closed.shape[0]):
        a, b = paths.subpath_offsets[s], paths.subpath_offsets[s + 1]
        if a == b:
            continue
        pen.moveTo(tuple(paths.start[s]))
        for i in range(a, b):
            c, d = paths.controls[i], int(paths.degree[i])
            if d == 1:
                pen.lineTo(tuple(c[1]))
            elif d == 2:
                pen.qCurveTo(tuple(c[1]), tuple(c[2]))
            else:
                pen.curveTo(tuple(c[1]), tuple(c[2]), tuple(c[3]))
        if close or paths.closed[s]:
            pen.closePath()
        else:
            pen.endPath()


def flat_rings(paths: PathArrays, tolerance: float) -> list[np.ndarray]:
    """Return every subpath of `paths` closed and flattened by `FlattenPen`."""
    pen = FlattenPen(tolerance)
    draw_paths(paths, pen)
    return pen.rings


def flat_lines(paths: PathArrays, tolerance: float) -> list[np.ndarray]:
    """Return every subpath of `paths` as a polyline (closed ones back to their start)."""
    pen = FlattenPen(tolerance)
    draw_paths(paths, pen, close=False)
    return pen.rings + pen.lines


def exact_signed_area(paths: PathArrays) -> float:
    """Return the integral of the winding number over the plane (curves exactly)."""
    pen = AreaPen()
    draw_paths(paths, pen)
    return float(pen.value)


@dataclass(frozen=True, eq=False)
class Glyph:
    """A glyph's outline: path data, bounding box, and its oracle rings."""

    font: str
    char: str
    d: str  # as SVGPathPen writes it: Z closes a contour with an implicit line
    d_closed: str  # the same outline with every closing line drawn before its Z
    bounds: tuple[float, float, float, float]
    units_per_em: int
    tolerance: float  # the chord tolerance of `rings`
    rings: tuple[np.ndarray, ...]
    signed_area: float  # AreaPen: the integral of the winding number (exact curves)

    @cached_property
    def polygons(self) -> np.ndarray:
        """Each ring as a Polygon (the glyphs used are made of simple rings)."""
        return np.array([shapely.Polygon(r) for r in self.rings], dtype=object)

    @cached_property
    def orientation(self) -> np.ndarray:
        """+1 for each counter-clockwise ring, -1 for each clockwise one."""
        return np.array([1.0 if shapely.LinearRing(r).is_ccw else -1.0 for r in self.rings])

    @cached_property
    def perimeter(self) -> float:
        """Return the total length of the outline."""
        return float(sum(np.hypot(*np.diff(r, axis=0).T).sum() for r in self.rings))


@cache
def _font(key: str):
    return TTFont(str(FONTS[key].path))


@cache
def load_glyph(key: str, char: str, relative_tolerance: float = 1e-7) -> Glyph:
    """Return the glyph of `char` in font `key`, flattened within `relative_tolerance` em."""
    font = _font(key)
    glyphs = font.getGlyphSet()
    name = font.getBestCmap()[ord(char)]
    recording, bounds = DecomposingRecordingPen(glyphs), BoundsPen(glyphs)
    glyphs[name].draw(recording)
    glyphs[name].draw(bounds)
    em = font["head"].unitsPerEm
    tolerance = relative_tolerance * em
    flat, area = FlattenPen(tolerance, glyphs), AreaPen(glyphs)
    glyphs[name].draw(flat)
    glyphs[name].draw(area)
    return Glyph(key, char, _path_data(recording.value, False),
                 _path_data(recording.value, True), tuple(float(v) for v in bounds.bounds),
                 em, tolerance, tuple(flat.rings), float(area.value))


def _path_data(operations, explicit_close: bool) -> str:
    """Return SVG path data of recorded pen operations, closing lines drawn if asked."""
    pen = SVGPathPen(None)
    start = current = None
    for op, args in operations:
        if op == "closePath" and explicit_close and current != start:
            pen.lineTo(start)
        getattr(pen, op)(*args)
        if op == "moveTo":
            start = args[0]
        if args:
            current = args[-1]
        if current is None:  # a TrueType contour of off-curve points only: closed by its curve
            start = None
    return pen.getCommands()
