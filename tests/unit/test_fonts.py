"""rnsca.fonts on the made fonts: lookups, layout, units, clipping, the SVG document, errors.

`tests.made_fonts` draws each glyph; real fonts are in tests/integration/test_fonts.py.
"""

import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from rnsca import FontError, InvalidOptionError, InvalidWindowError, parse_paths
from rnsca.fonts import Font, Units, clip_glyphs
from tests.made_fonts import make_font

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def font_path(tmp_path_factory):
    return make_font(tmp_path_factory.mktemp("fonts") / "made.ttf")


@pytest.fixture(scope="module")
def font(font_path):
    return Font(font_path)


# --- lookups ------------------------------------------------------------------------------

def test_font_reports_its_format_and_metrics(font, font_path):
    assert (font.path, font.outlines, font.flavor) == (str(font_path), "truetype", None)
    assert (font.units_per_em, font.ascent, font.descent, font.line_gap) == (1000, 800, -200, 0)
    assert font.line_height == 1000


def test_code_point_character_and_name_give_the_same_glyph(font):
    by_codepoint, by_char, by_name = font.glyph(ord("D")), font.glyph("D"), font.glyph("bump")
    assert by_codepoint.name == by_char.name == by_name.name == "bump"
    assert by_codepoint.paths == by_char.paths == by_name.paths
    assert (by_codepoint.codepoint, by_char.codepoint, by_name.codepoint) == (68, 68, None)
    assert font.glyph(name="bump").paths == by_name.paths
    assert by_char.advance == 500
    assert by_char.units_per_em == 1000


def test_glyph_outline_is_in_font_units_y_up(font):
    g = font.glyph("D")
    assert g.d == "M0 0H400Q400 300 200 300T0 0Z"
    assert g.paths.degree.tolist() == [1, 2, 2]


def test_glyph_arrays_are_the_callers_own(font):
    g = font.glyph("L")
    assert g.paths.controls.flags.writeable
    g.paths.controls[0, 0, 0] = -1.0
    assert font.glyph("L").paths.controls[0, 0, 0] == 100
    assert font.text_paths("L").paths.controls[0, 0, 0] == 100


def test_code_point_missing_from_the_cmap_is_named(font, font_path):
    with pytest.raises(FontError) as info:
        font.glyph("A")
    assert str(info.value) == f"U+0041 'A' is not in the cmap of {font_path}"
    assert isinstance(info.value, ValueError)
    with pytest.raises(FontError, match=r"^U\+0007 is not in the cmap"):
        font.glyph(7)


@pytest.mark.parametrize(("key", "message"), [
    (-1, "-1 is not a Unicode code point (0 to U+10FFFF)"),
    (0x110000, "1114112 is not a Unicode code point (0 to U+10FFFF)"),
    ("nosuchglyph", "has no glyph named 'nosuchglyph'"),
    ("", "a glyph name cannot be empty"),
])
def test_bad_glyph_keys_are_named(font, key, message):
    with pytest.raises(FontError, match=message.replace("+", r"\+").replace("(", r"\(")
                       .replace(")", r"\)")):
        font.glyph(key)


@pytest.mark.parametrize("call", [
    lambda f: f.glyph(),
    lambda f: f.glyph("L", name="square"),
    lambda f: f.glyph(76.0),
    lambda f: f.glyph(True),
    lambda f: f.glyph(name=3),
])
def test_glyph_takes_one_key_of_the_right_type(font, call):
    with pytest.raises(TypeError):
        call(font)


# --- layout -------------------------------------------------------------------------------

def test_text_in_font_units_advances_along_the_baseline(font):
    run = font.text_paths("LD")
    assert run.names == ("square", "bump")
    assert run.units is Units.FONT and run.scale == 1.0
    assert run.origins.tolist() == [[0, 0], [600, 0]]
    assert run.paths.path_offsets.tolist() == [0, 1, 2]
    assert run.paths.start.tolist() == [[100, 0], [600, 0]]
    second = run.paths.controls[3:]
    assert second.tolist() == (font.glyph("D").paths.controls + [600, 0]).tolist()
    assert len(run) == 2


def test_origin_moves_the_whole_run(font):
    run = font.text_paths("LD", origin=(-10, 5))
    assert run.origins.tolist() == [[-10, 5], [590, 5]]
    assert run.paths.start.tolist() == [[90, 5], [590, 5]]


def test_user_units_scale_by_size_over_the_em_and_flip_y(font):
    run = font.text_paths("LD", size=20, origin=(5, 30))
    assert run.units is Units.USER and run.scale == 0.02
    # bump: (0, 0) -> (5 + 12, 30); (400, 300) -> (5 + 0.02 * 1000, 30 - 6).
    assert run.origins.tolist() == [[5, 30], [17, 30]]
    bump = run.paths.controls[3:]
    assert bump[:, :3].tolist() == [
        [[17, 30], [25, 30], [25, 30]],
        [[25, 30], [25, 24], [21, 24]],
        [[21, 24], [17, 24], [17, 30]],
    ]
    assert run.paths.degree.tolist() == [1, 1, 1, 1, 2, 2]


def test_units_user_is_implied_by_a_size_and_can_be_named(font):
    assert font.text_paths("L", size=10, units="user").paths == font.text_paths(
        "L", size=10).paths


def test_line_breaks_start_a_new_line_one_line_height_lower(font):
    assert font.text_paths("L\nDL").origins.tolist() == [[0, 0], [0, -1000], [500, -1000]]
    user = font.text_paths("L\r\nD", size=10, origin=(1, 2))
    assert user.origins.tolist() == [[1, 2], [1, 12]]


def test_space_advances_without_an_outline(font):
    run = font.text_paths("L L")
    assert run.names == ("square", "space", "square")
    assert run.origins[:, 0].tolist() == [0, 600, 850]
    assert run.paths.path_offsets.tolist() == [0, 1, 1, 2]


def test_sequence_of_code_points_and_names_is_one_line(font):
    run = font.text_paths([ord("L"), "diamond", "D", "pair"])
    assert run.names == ("square", "diamond", "bump", "pair")
    assert run.origins[:, 0].tolist() == [0, 600, 900, 1400]


def test_empty_text_has_no_glyphs(font):
    run = font.text_paths("")
    assert len(run) == 0 and len(run.paths) == 0
    assert run.origins.shape == (0, 2)


def test_character_missing_from_the_font_fails_the_whole_text(font):
    with pytest.raises(FontError, match=r"U\+0078 'x' is not in the cmap"):
        font.text_paths("LxD")


@pytest.mark.parametrize(("options", "message"), [
    (dict(units="user"), "units='user' needs a size"),
    (dict(units="font", size=12), "size applies to user units"),
    (dict(size=0), "size must be a positive finite number, got 0"),
    (dict(size=-3.0), "size must be a positive finite number"),
    (dict(size=float("inf")), "size must be a positive finite number"),
    (dict(size=True), "size must be a positive finite number"),
    (dict(size="12"), "size must be a positive finite number"),
    (dict(units="pixels"), "units must be one of 'font', 'user', got 'pixels'"),
    (dict(origin=(1,)), "origin must be two finite numbers"),
    (dict(origin=(0, float("nan"))), "origin must be two finite numbers"),
    (dict(origin="ab"), "origin must be two finite numbers"),
])
def test_bad_layout_options_are_named(font, options, message):
    with pytest.raises(InvalidOptionError, match=message.replace("(", r"\(")):
        font.text_paths("L", **options)


def test_text_of_another_type_is_refused(font):
    with pytest.raises(TypeError, match="text must be a str or a sequence"):
        font.text_paths(42)


# --- clipping -----------------------------------------------------------------------------

def test_clip_keeps_the_part_of_each_glyph_inside_the_window(font):
    result = clip_glyphs(font, "LD", (0, 0, 300, 200))
    # Clean fills (the default): one simple ring, the closing line drawn by Z.
    assert result.d == ["M100 200V0H300V200Z", ""]
    assert result.clip.fill == "nonzero"
    assert result.stats.geometries_in == 2 and result.stats.geometries_out == 1
    assert result.paths == parse_paths(result.d)


def test_clip_in_user_units_keeps_quadratics(font):
    result = clip_glyphs(font, "LD", (0, -10, 15, 0), size=10)
    assert result.d == ["M5 0V-4H1V0Z", "M10 0Q10-3 8-3T6 0Z"]
    assert result.run.units is Units.USER


def test_clip_cuts_a_curve_at_the_window_edge(font):
    # The bump's top, y = 300 at x = 200, cut at y = 225: the quadratic
    # (400, 0) (400, 300) (200, 300) has y = 300 (2t - t^2) = 225 at t = 1/2.
    result = clip_glyphs(font, "D", (-50, -50, 450, 225))
    p = result.paths
    assert set(p.degree.tolist()) == {1, 2}
    assert np.isclose(p.controls[:, :, 1].max(), 225, rtol=0, atol=1e-12)
    curves = p.controls[p.degree == 2][:, :3].tolist()
    assert [[400, 0], [400, 150], [350, 225]] in curves


def test_clip_takes_a_font_file_and_precision(font_path):
    result = clip_glyphs(font_path, "D", (0, -10, 15, 0), size=3, precision=2)
    assert result.d == ["M1.2 0Q1.2-.9.6-.9T0 0Z"]


def test_clip_as_strokes(font):
    result = clip_glyphs(font, "L", (0, 0, 300, 200), fill=None)
    assert result.d == ["M100 200V0H300"]


def test_window_is_checked_before_the_font_is_read():
    with pytest.raises(InvalidWindowError):
        clip_glyphs("no-such-font.ttf", "L", (0, 0, 0, 1))
    with pytest.raises(InvalidOptionError, match="needs a size"):
        clip_glyphs("no-such-font.ttf", "L", (0, 0, 1, 1), units="user")


def test_missing_font_file_is_a_font_error(tmp_path):
    with pytest.raises(FontError, match="absent.ttf: No such file or directory"):
        clip_glyphs(tmp_path / "absent.ttf", "L", (0, 0, 1, 1))


# --- the SVG document ---------------------------------------------------------------------

def parse_svg(text):
    root = ET.fromstring(text.encode("utf-8"))
    assert root.tag == f"{SVG}svg"
    (group,) = list(root)
    return root, group, list(group)


def test_svg_in_user_units_has_the_window_as_view_box(font):
    result = clip_glyphs(font, "LD", (0, -10, 15, 0), size=10)
    root, group, paths = parse_svg(result.svg())
    assert root.get("viewBox") == "0 -10 15 10"
    assert (group.get("fill"), group.get("fill-rule"), group.get("transform")) == (
        "black", "nonzero", None)
    assert [(p.get("data-glyph"), p.get("d")) for p in paths] == [
        ("square", result.d[0]), ("bump", result.d[1])]


def test_svg_in_font_units_flips_about_the_window_and_leaves_out_empty_glyphs(font):
    result = clip_glyphs(font, "LD", (0, 0, 300, 200.5))
    root, group, paths = parse_svg(result.svg())
    assert root.get("viewBox") == "0 0 300 200.5"
    assert group.get("transform") == "matrix(1 0 0 -1 0 200.5)"
    assert [p.get("data-glyph") for p in paths] == ["square"]


def test_svg_of_strokes_is_stroked(font):
    result = clip_glyphs(font, "L", (0, 0, 300, 200), fill=None)
    _, group, paths = parse_svg(result.svg())
    assert (group.get("fill"), group.get("stroke")) == ("none", "black")
    assert paths[0].get("vector-effect") == "non-scaling-stroke"


# --- missing dependency -------------------------------------------------------------------

def test_missing_fonttools_names_the_extra(monkeypatch, font_path):
    import rnsca.io

    monkeypatch.delitem(sys.modules, "rnsca.io.opentype", raising=False)
    monkeypatch.delattr(rnsca.io, "opentype", raising=False)
    monkeypatch.setitem(sys.modules, "fontTools", None)
    monkeypatch.setitem(sys.modules, "fontTools.ttLib", None)
    monkeypatch.setitem(sys.modules, "fontTools.pens.basePen", None)
    with pytest.raises(ModuleNotFoundError, match=r"pip install 'rnsca\[fonts\]'"):
        Font(font_path)
