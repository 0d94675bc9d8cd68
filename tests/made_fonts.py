"""Small fonts made with fontTools' FontBuilder, whose outlines the tests know point by point.

`make_font` writes one to a file: TrueType (``glyf`` quadratics) or CFF (cubics), as a
plain OpenType file, WOFF or WOFF2. Units per em 1000, ascent 800, descent -200, no line
gap: baselines 1000 units apart. The glyphs (`GLYPHS`) and what fontTools draws of them:

- ``L`` (glyph ``square``, advance 600): a square of lines, (100, 0) to (500, 400).
- ``O`` (``diamond``, advance 300): TrueType: a contour of four off-curve points only,
  (100, 0) (200, 100) (100, 200) (0, 100): it starts at the implied on-curve point
  (50, 50) and is four quadratics through the implied midpoints. CFF: the same curve as
  cubics (degree-elevated quadratics, control points rounded to integers by the CFF
  writer: (83, 17) (117, 17) ...).
- ``D`` (``bump``, advance 500): a line (0, 0) to (400, 0), then a closing run of two
  off-curve points (400, 300) (0, 300) back to (0, 0): two quadratics meeting at the
  implied (200, 300). CFF: a line then one cubic.
- ``E`` (``pair``, advance 700; TrueType only): a composite of ``square`` moved by
  (600, 0) and ``square`` scaled by 0.5 and moved by (0, 500).
- space (``space``, advance 250): no outline.
"""

from __future__ import annotations

from pathlib import Path

from tests.missing import missing

try:
    from fontTools.fontBuilder import FontBuilder
    from fontTools.pens.t2CharStringPen import T2CharStringPen
    from fontTools.pens.ttGlyphPen import TTGlyphPen
    from fontTools.ttLib import TTFont
except ImportError:  # reported by `make_font`
    FontBuilder = None

__all__ = ["ADVANCES", "CMAP", "make_font", "reopen", "require_brotli"]

#: Code point -> glyph name of the made fonts.
CMAP = {ord("L"): "square", ord("O"): "diamond", ord("D"): "bump", ord("E"): "pair",
        ord(" "): "space"}
#: Advance width of each glyph.
ADVANCES = {".notdef": 500, "square": 600, "diamond": 300, "bump": 500, "pair": 700,
            "space": 250}


def _draw_square(pen) -> None:
    pen.moveTo((100, 0))
    pen.lineTo((500, 0))
    pen.lineTo((500, 400))
    pen.lineTo((100, 400))
    pen.closePath()


def _draw_diamond(pen, cubic: bool) -> None:
    if not cubic:
        pen.qCurveTo((100, 0), (200, 100), (100, 200), (0, 100), None)
        pen.closePath()
        return
    # The same four quadratics, degree-elevated: c1 = p0 + 2/3 (p1 - p0), c2 = p2 + 2/3 (p1 - p2).
    points = [(50, 50), (100, 0), (150, 50), (200, 100), (150, 150), (100, 200), (50, 150),
              (0, 100), (50, 50)]
    pen.moveTo(points[0])
    for i in range(0, 8, 2):
        p0, p1, p2 = points[i], points[i + 1], points[i + 2]
        c1 = tuple(a + 2 * (b - a) / 3 for a, b in zip(p0, p1, strict=True))
        c2 = tuple(c + 2 * (b - c) / 3 for b, c in zip(p1, p2, strict=True))
        pen.curveTo(c1, c2, p2)
    pen.closePath()


def _draw_bump(pen, cubic: bool) -> None:
    pen.moveTo((0, 0))
    pen.lineTo((400, 0))
    if cubic:
        pen.curveTo((400, 300), (0, 300), (0, 0))
    else:
        pen.qCurveTo((400, 300), (0, 300), (0, 0))
    pen.closePath()


def make_font(path: Path, outlines: str = "truetype", flavor: str | None = None) -> Path:
    """Write the made font to `path` and return it (skip or fail if fontTools is missing).

    Parameters
    ----------
    outlines : {"truetype", "cff"}
    flavor : {None, "woff", "woff2"}
    """
    if FontBuilder is None:
        missing("fontTools is not installed (pip install fonttools, in the dev extra)")
    cubic = outlines == "cff"
    order = [".notdef", "square", "diamond", "bump", "space"] + ([] if cubic else ["pair"])
    builder = FontBuilder(1000, isTTF=not cubic)
    builder.setupGlyphOrder(order)
    builder.setupCharacterMap({c: n for c, n in CMAP.items() if n in order})
    drawers = {"square": _draw_square, "diamond": lambda p: _draw_diamond(p, cubic),
               "bump": lambda p: _draw_bump(p, cubic)}
    if cubic:
        strings = {}
        for name in order:
            pen = T2CharStringPen(ADVANCES[name], None)
            if name in drawers:
                drawers[name](pen)
            strings[name] = pen.getCharString()
        builder.setupCFF("MadeCFF-Regular", {"FullName": "Made CFF"}, strings, {})
        lsb = {name: 0 for name in order}
    else:
        glyphs: dict = {}
        for name in order:
            pen = TTGlyphPen(glyphs)  # the glyphs so far: components must come first
            if name in drawers:
                drawers[name](pen)
            elif name == "pair":
                pen.addComponent("square", (1, 0, 0, 1, 600, 0))
                pen.addComponent("square", (0.5, 0, 0, 0.5, 0, 500))
            glyphs[name] = pen.glyph()
        builder.setupGlyf(glyphs)
        glyf = builder.font["glyf"]
        lsb = {name: getattr(glyf[name], "xMin", 0) for name in order}
    builder.setupHorizontalMetrics({name: (ADVANCES[name], lsb[name]) for name in order})
    builder.setupHorizontalHeader(ascent=800, descent=-200)
    builder.setupNameTable({"familyName": "Made", "styleName": "Regular"})
    builder.setupOS2(sTypoAscender=800, sTypoDescender=-200, usWinAscent=800,
                     usWinDescent=200)
    builder.setupPost()
    builder.font.flavor = flavor
    builder.save(str(path))
    return path


def reopen(path: Path):
    """Return the font at `path` read by fontTools (for oracles that draw it themselves)."""
    return TTFont(str(path))


def require_brotli() -> None:
    """Skip (fail in CI) unless brotli, which WOFF2 needs, is installed."""
    try:
        import brotli  # noqa: F401
    except ImportError:
        missing("brotli is not installed (pip install 'rnsca[fonts]'; in the dev extra)")
