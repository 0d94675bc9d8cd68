"""Font files to `PathArrays`: TrueType and CFF outlines point by point, web fonts, errors.

The fonts are made by `tests.made_fonts`, whose docstring draws each glyph.
"""

import pytest

from rnsca.errors import FontError
from tests.made_fonts import make_font, reopen, require_brotli
from tests.missing import missing

try:
    from rnsca.io import opentype
except ImportError:  # reported by the fixture below: a skip here, a failure in CI
    opentype = None


@pytest.fixture(autouse=True)
def _fonttools():
    if opentype is None:
        missing("fontTools is not installed (pip install 'rnsca[fonts]', in the dev extra)")


def outline(path, name):
    return opentype.glyph_outline(reopen(path).getGlyphSet(), name)


def segments(paths):
    """Return (degree, [control points used]) per segment."""
    return [(int(g), c[:g + 1].tolist()) for g, c in zip(paths.degree, paths.controls,
                                                         strict=True)]


@pytest.fixture
def truetype(tmp_path):
    return make_font(tmp_path / "made.ttf")


@pytest.fixture
def cff(tmp_path):
    return make_font(tmp_path / "made.otf", "cff")


def test_square_of_lines_is_one_closed_subpath_with_an_implicit_closing_line(truetype):
    p = outline(truetype, "square")
    assert segments(p) == [(1, [[100, 0], [500, 0]]), (1, [[500, 0], [500, 400]]),
                           (1, [[500, 400], [100, 400]])]
    assert p.start.tolist() == [[100, 0]]
    assert p.closed.tolist() == [True]
    assert p.subpath_offsets.tolist() == [0, 3]
    assert p.path_offsets.tolist() == [0, 1]
    # Unused control rows repeat the end point.
    assert p.controls[0].tolist() == [[100, 0], [500, 0], [500, 0], [500, 0]]


def test_contour_of_off_curve_points_only_starts_at_the_implied_point(truetype):
    p = outline(truetype, "diamond")
    assert p.start.tolist() == [[50, 50]]
    assert segments(p) == [
        (2, [[50, 50], [100, 0], [150, 50]]),
        (2, [[150, 50], [200, 100], [150, 150]]),
        (2, [[150, 150], [100, 200], [50, 150]]),
        (2, [[50, 150], [0, 100], [50, 50]]),
    ]
    assert p.controls[0, 3].tolist() == [150, 50]


def test_closing_run_of_two_off_curve_points_is_two_quadratics_through_their_midpoint(
        truetype):
    p = outline(truetype, "bump")
    assert segments(p) == [(1, [[0, 0], [400, 0]]),
                           (2, [[400, 0], [400, 300], [200, 300]]),
                           (2, [[200, 300], [0, 300], [0, 0]])]
    assert p.closed.tolist() == [True]


def test_composite_draws_each_component_through_its_transform(truetype):
    p = outline(truetype, "pair")
    assert p.start.tolist() == [[700, 0], [50, 500]]
    assert p.subpath_offsets.tolist() == [0, 3, 6]
    assert p.closed.tolist() == [True, True]
    assert [c for _, c in segments(p)][3:] == [[[50, 500], [250, 500]],
                                               [[250, 500], [250, 700]],
                                               [[250, 700], [50, 700]]]


def test_cff_curves_are_cubics(cff):
    p = outline(cff, "bump")
    assert segments(p) == [(1, [[0, 0], [400, 0]]),
                           (3, [[400, 0], [400, 300], [0, 300], [0, 0]])]
    diamond = outline(cff, "diamond")
    assert diamond.degree.tolist() == [3, 3, 3, 3]
    assert diamond.controls[0].tolist() == [[50, 50], [83, 17], [117, 17], [150, 50]]


def test_glyph_without_outline_has_no_subpath(truetype):
    p = outline(truetype, "space")
    assert len(p) == 1
    assert p.closed.shape == (0,)
    assert p.controls.shape == (0, 4, 2)


@pytest.mark.parametrize("flavor", ["woff", "woff2"])
@pytest.mark.parametrize("outlines", ["truetype", "cff"])
def test_web_fonts_give_the_outlines_of_the_plain_font(tmp_path, outlines, flavor):
    if flavor == "woff2":
        require_brotli()
    plain = make_font(tmp_path / "plain", outlines)
    web = make_font(tmp_path / "web", outlines, flavor)
    font = opentype.read_font(web)
    assert font.flavor == flavor
    assert opentype.outline_format(font) == outlines
    for name in ("square", "diamond", "bump", "space"):
        assert opentype.glyph_outline(font.getGlyphSet(), name) == outline(plain, name)


# --- errors ---------------------------------------------------------------------------

def error_of(path):
    with pytest.raises(FontError) as info:
        opentype.read_font(path)
    assert isinstance(info.value, ValueError)
    return str(info.value)


def test_missing_file_is_named(tmp_path):
    path = tmp_path / "absent.ttf"
    assert error_of(path) == f"{path}: No such file or directory"


def test_directory_is_not_a_font(tmp_path):
    assert error_of(tmp_path) == f"{tmp_path}: Is a directory"


def test_text_file_is_not_a_font(tmp_path):
    path = tmp_path / "notes.ttf"
    path.write_text("these are not the glyphs you are looking for\n")
    message = error_of(path)
    assert message.startswith(f"{path}: not a TrueType, OpenType, WOFF or WOFF2 font")


def test_truncated_font_is_refused(truetype):
    data = truetype.read_bytes()
    truetype.write_bytes(data[:200])
    assert error_of(truetype).startswith(f"{truetype}: ")


def test_font_without_outline_tables_is_refused(truetype):
    font = reopen(truetype)
    for tag in ("glyf", "loca"):
        del font[tag]
    font.save(str(truetype))
    assert error_of(truetype) == (f"{truetype}: the font has no outlines (none of the "
                                  f"tables 'glyf', 'CFF ', 'CFF2')")


def test_woff2_without_brotli_names_the_extra(tmp_path, monkeypatch):
    require_brotli()
    path = make_font(tmp_path / "made.woff2", flavor="woff2")
    from fontTools.ttLib import woff2

    monkeypatch.setattr(woff2, "haveBrotli", False)
    with pytest.raises(ModuleNotFoundError, match=r"needs brotli: pip install 'rnsca\[fonts\]'"):
        opentype.read_font(path)
