"""rnsca.fonts on real fonts: outlines as fontTools draws them, layout, clips against Shapely.

DejaVu (TrueType, ``fonts-dejavu-core``) and URW Nimbus (CFF OpenType,
``fonts-urw-base35``), as in test_glyphs.py, whose oracles this reuses: fontTools draws
each glyph itself (``SVGPathPen``, ``AreaPen``, `tests.fonts.FlattenPen`), never
through rnsca.fonts, and Shapely intersects the flattened glyph with the window. In CI a
missing font fails; elsewhere it skips.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import shapely
from shapely import affinity

import rnsca
from rnsca import Fill, parse_paths
from rnsca.fonts import Font, clip_glyphs
from rnsca.verify.paths import filled_region
from tests.fonts import FONTS, exact_signed_area, flat_rings, load_glyph, require_font
from tests.integration.test_glyphs import CHARS, GLYPHS, region
from tests.made_fonts import require_brotli

try:
    from fontTools import subset
    from fontTools.pens.svgPathPen import SVGPathPen
    from fontTools.pens.transformPen import TransformPen
    from fontTools.ttLib import TTFont
except ImportError:  # require_font reports it
    subset = SVGPathPen = TransformPen = TTFont = None

#: Text laid out in the layout and clip tests: counters, a descender, a composite.
TEXT = "Ag@é"


@cache
def font_of(key: str) -> Font:
    return Font(require_font(key).path)


@cache
def ttfont(key: str):
    """Return the font `key` as fontTools reads it, apart from rnsca.fonts."""
    return TTFont(str(require_font(key).path))


def fonttools_path(key: str, name: str, transform=(1, 0, 0, 1, 0, 0)) -> str:
    """Return glyph `name` as fontTools' SVGPathPen writes it, through `transform`."""
    glyph_set = ttfont(key).getGlyphSet()
    pen = SVGPathPen(glyph_set)
    glyph_set[name].draw(TransformPen(pen, transform))
    return pen.getCommands()


# --- outlines -----------------------------------------------------------------------------

@pytest.mark.parametrize(("key", "char"), GLYPHS)
def test_outline_is_the_one_fonttools_draws(key, char):
    font = font_of(key)
    g = font.glyph(char)
    assert g.paths == parse_paths([load_glyph(key, char).d])
    assert font.glyph(name=g.name).paths == g.paths
    assert g.codepoint == ord(char)
    degrees = set(np.unique(g.paths.degree).tolist())
    assert FONTS[key].degree in degrees and degrees <= {1, FONTS[key].degree}


@pytest.mark.parametrize(("key", "char"), GLYPHS)
def test_outline_area_is_fonttools_area(key, char):
    """AreaPen on our arrays (exact curves) and Shapely on the flattened oracle rings."""
    g, oracle = font_of(key).glyph(char), load_glyph(key, char)
    assert exact_signed_area(g.paths) == pytest.approx(oracle.signed_area, rel=1e-12)
    ours = shapely.area(filled_region(flat_rings(g.paths, oracle.tolerance), Fill.NONZERO))
    assert abs(ours - region(key, char, "nonzero").area) <= 2 * oracle.tolerance \
        * oracle.perimeter


@pytest.mark.parametrize("key", FONTS)
def test_glyph_names_and_code_points_agree_with_the_cmap(key):
    font = font_of(key)
    cmap = ttfont(key).getBestCmap()
    for char in CHARS:
        assert font.glyph(char).name == cmap[ord(char)]


# --- layout -------------------------------------------------------------------------------

@pytest.mark.parametrize("key", FONTS)
def test_user_units_place_each_glyph_like_a_transform_pen(key):
    """Scale size / unitsPerEm, y flipped, advances from hmtx: fontTools' TransformPen."""
    font = font_of(key)
    size, origin = 37.5, (12.25, 80.0)
    run = font.text_paths(TEXT, size=size, origin=origin)
    s = size / font.units_per_em
    hmtx = ttfont(key)["hmtx"]
    expected, pen_x = [], 0
    for char in TEXT:
        name = ttfont(key).getBestCmap()[ord(char)]
        expected.append(fonttools_path(key, name, (s, 0, 0, -s, origin[0] + s * pen_x,
                                                    origin[1])))
        pen_x += hmtx[name][0]
    want = parse_paths(expected)
    for field in ("degree", "subpath_offsets", "closed", "path_offsets"):
        assert np.array_equal(getattr(run.paths, field), getattr(want, field)), field
    atol = 1e-12 * size
    np.testing.assert_allclose(run.paths.controls, want.controls, rtol=1e-12, atol=atol)
    np.testing.assert_allclose(run.paths.start, want.start, rtol=1e-12, atol=atol)
    assert run.origins[-1, 0] == pytest.approx(origin[0] + s * (pen_x - hmtx[name][0]))


# --- clipping against Shapely -------------------------------------------------------------

def expected_region(key: str, run, rule: str):
    """Return the union of the run's glyph regions (font units), each moved into place."""
    placed = []
    for char, (ox, oy) in zip(TEXT, run.origins, strict=True):
        s = run.scale
        flip = -s if run.units is rnsca.fonts.Units.USER else s
        placed.append(affinity.affine_transform(region(key, char, rule),
                                                [s, 0, 0, flip, ox, oy]))
    return shapely.union_all(placed)


#: Windows in user units at size 100 (baseline y = 0, ascenders near y = -75): a band
#: through every glyph, the left part, one around the '@', a thin one along the baseline.
USER_WINDOWS = {
    "band": (-10.0, -45.0, 400.0, -30.0),
    "left": (-10.0, -90.0, 95.5, 30.0),
    "at": (130.0, -60.0, 190.0, 0.5),
    "baseline": (0.0, -3.0, 400.0, 0.0),
}


@pytest.mark.parametrize("rule", ["nonzero", "evenodd"])
@pytest.mark.parametrize("window_name", USER_WINDOWS)
@pytest.mark.parametrize("key", FONTS)
def test_clip_paints_shapelys_intersection_of_the_glyphs_and_the_window(key, window_name,
                                                                         rule):
    font = font_of(key)
    window = USER_WINDOWS[window_name]
    result = clip_glyphs(font, TEXT, window, size=100.0, fill=rule)
    assert result.d == rnsca.write_paths(result.paths, precision=None)
    assert set(np.unique(result.paths.degree)) <= {1, FONTS[key].degree}
    s = result.run.scale
    glyphs = [load_glyph(key, char) for char in TEXT]
    tolerance = glyphs[0].tolerance * s
    perimeter = sum(g.perimeter for g in glyphs) * s
    rings = flat_rings(result.paths, tolerance)
    got = shapely.area(filled_region(rings, Fill(rule))) if rings else 0.0
    expected = shapely.area(shapely.intersection(expected_region(key, result.run, rule),
                                                 shapely.box(*window)))
    assert expected > 0
    assert abs(got - expected) <= 2 * tolerance * perimeter, (got, expected)
    assert rnsca.verify(result.run.paths, result.clip, window).passed


@pytest.mark.parametrize("key", FONTS)
def test_clip_in_font_units_matches_the_path_data_clip(key):
    """The issue's case: '@' in font units, window (0, 500, 2000, 1100), nonzero fill."""
    font = font_of(key)
    window = (0.0, 500.0, 2000.0, 1100.0)
    result = clip_glyphs(font, "@", window)
    g = load_glyph(key, "@")
    d, _ = rnsca.clip_svg(g.d, window, fill="nonzero")
    assert result.d == [d]
    got = shapely.area(filled_region(flat_rings(result.paths, g.tolerance), Fill.NONZERO))
    expected = shapely.area(shapely.intersection(region(key, "@", "nonzero"),
                                                 shapely.box(*window)))
    assert abs(got - expected) <= 2 * g.tolerance * g.perimeter


# --- web fonts ----------------------------------------------------------------------------

@pytest.mark.parametrize("flavor", ["woff", "woff2"])
@pytest.mark.parametrize("key", ["dejavu-sans", "nimbus-sans"])
def test_web_font_round_trip_keeps_every_outline(tmp_path, key, flavor):
    """fontTools subsets the font to TEXT and writes it as WOFF or WOFF2; we read it back."""
    if flavor == "woff2":
        require_brotli()
    font = font_of(key)
    options = subset.Options()
    options.flavor = flavor
    options.layout_features = []
    subsetter = subset.Subsetter(options)
    path = tmp_path / f"subset.{flavor}"
    with subset.load_font(str(font.path), options) as web:
        subsetter.populate(text=TEXT)
        subsetter.subset(web)
        subset.save_font(web, str(path), options)
    again = Font(path)
    assert again.flavor == flavor
    assert again.outlines == font.outlines
    assert again.units_per_em == font.units_per_em
    for char in TEXT:
        assert again.glyph(char).paths == font.glyph(char).paths, char
        assert again.glyph(char).advance == font.glyph(char).advance
