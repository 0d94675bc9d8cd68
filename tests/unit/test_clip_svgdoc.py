"""SVG documents: shapes to paths, transforms, fill or stroke, what is left alone, errors."""

import time
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import rnsca
from rnsca import ClipStats, clip_svg, parse_path, verify
from rnsca.clip_svgdoc import clip_svg_document
from rnsca.errors import (
    InvalidOptionError,
    InvalidWindowError,
    ParseError,
    UnsupportedGeometryError,
)
from rnsca.io.svgdoc import MAX_NESTING, SVG_NAMESPACE
from rnsca.io.svgpath import PathArrays

W10 = (0, 0, 10, 10)
NS = {"svg": SVG_NAMESPACE}


def svg(body: str, attributes: str = "") -> str:
    return f'<svg xmlns="{SVG_NAMESPACE}"{attributes}>{body}</svg>'


def clipped(body: str, window=W10, **options) -> str:
    """Return the clipped document of `body` (the root's content), without the root."""
    out, _ = clip_svg_document(svg(body), window, **options)
    head, tail = f'<svg xmlns="{SVG_NAMESPACE}">', "</svg>\n"
    assert out.startswith(head) and out.endswith(tail), out
    return out[len(head):-len(tail)]


def element(out: str, ident: str) -> ET.Element:
    """Return the element with id `ident` of the document `out`."""
    root = ET.fromstring(out if out.startswith(("<svg", "<?xml")) else svg(out))
    found = root.find(f".//*[@id='{ident}']")
    assert found is not None, out
    return found


# --------------------------------------------------------------------------- test oracle

def matrix(*steps) -> np.ndarray:
    """Return the 3x3 matrix of SVG transform steps, as ("translate", tx, ty) tuples."""
    out = np.eye(3)
    for name, *v in steps:
        if name == "translate":
            m = [[1, 0, v[0]], [0, 1, v[1]], [0, 0, 1]]
        elif name == "scale":
            m = [[v[0], 0, 0], [0, v[1], 0], [0, 0, 1]]
        elif name == "rotate":
            a = np.radians(v[0])
            m = [[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]]
        elif name == "skewX":
            m = [[1, np.tan(np.radians(v[0])), 0], [0, 1, 0], [0, 0, 1]]
        else:
            m = [[v[0], v[2], v[4]], [v[1], v[3], v[5]], [0, 0, 1]]
        out = out @ np.array(m, dtype=float)
    return out


def in_root(d: str, m: np.ndarray) -> PathArrays:
    """Return path data `d` mapped to root space by the 3x3 matrix `m`."""
    p = parse_path(d)

    def apply(points):
        out = np.empty_like(points)
        out[..., 0] = m[0, 0] * points[..., 0] + m[0, 1] * points[..., 1] + m[0, 2]
        out[..., 1] = m[1, 0] * points[..., 0] + m[1, 1] * points[..., 1] + m[1, 2]
        return out

    return PathArrays(controls=apply(p.controls), degree=p.degree,
                      subpath_offsets=p.subpath_offsets, closed=p.closed,
                      start=apply(p.start), path_offsets=p.path_offsets)


def assert_clip_in_root(original_d, clipped_d, m, window=W10, fill="nonzero"):
    """Check a clip written in local coordinates against Shapely's clip in root space."""
    result = verify(in_root(original_d, m), in_root(clipped_d, m), window, fill=fill)
    assert result.passed, result


# --------------------------------------------------------------------------- basic shapes

def test_rect_half_outside_becomes_a_path_cut_at_the_edge():
    out = clipped('<rect id="r" class="c" x="-5" y="2" width="10" height="4" '
                  'style="stroke:red" data-n="1"/>')
    assert out == '<path id="r" class="c" d="M0 2H5V6H0Z" style="stroke:red" data-n="1" />'


def test_rect_wholly_inside_is_left_as_it_is():
    body = '<rect x="1" y="1" width="3" height="3" rx="1" transform="translate(2 2)" />'
    assert clipped(body) == body


def test_rounded_rect_corners_are_clipped_as_arcs():
    out = clipped('<rect id="r" x="-2" y="-2" width="6" height="6" rx="2" ry="1"/>')
    d = element(out, "r").get("d")
    assert_clip_in_root("M0-2H2A2 1 0 0 1 4-1V3A2 1 0 0 1 2 4H0A2 1 0 0 1-2 3V-1A2 1 0 0 1 "
                        "0-2Z", d, np.eye(3))
    assert "C" in d   # the corner inside the window stays a curve


@pytest.mark.parametrize("rx, ry, expected", [
    ("", "", "M-1 0H3V2H-1Z"),
    ('rx="1"', "", "M0 0H2A1 1 0 0 1 3 1V1A1 1 0 0 1 2 2H0A1 1 0 0 1-1 1V1A1 1 0 0 1 0 0Z"),
    ('rx="9"', 'ry="-1"', "M1 0H1A2 1 0 0 1 3 1V1A2 1 0 0 1 1 2H1A2 1 0 0 1-1 1V1A2 1 0 0 1 "
                          "1 0Z"),
])
def test_rect_radii_follow_svg2(rx, ry, expected):
    # Same outline as the path SVG 2 gives: a missing or negative radius is the other
    # one, radii at most half the side.
    out = clipped(f'<rect id="r" x="-1" y="0" width="4" height="2" {rx} {ry}/>'
                  f'<path id="p" d="{expected}"/>')
    assert element(out, "r").get("d") == element(out, "p").get("d")


def test_circle_outside_the_corner_keeps_the_quarter_inside():
    out = clipped('<circle id="c" cx="0" cy="0" r="5" fill="blue"/>')
    c = element(out, "c")
    assert c.tag == f"{{{SVG_NAMESPACE}}}path" and c.get("fill") == "blue"
    assert set(c.attrib) == {"id", "d", "fill"}
    assert_clip_in_root("M5 0A5 5 0 0 1 0 5A5 5 0 0 1-5 0A5 5 0 0 1 0-5A5 5 0 0 1 5 0Z",
                        c.get("d"), np.eye(3))


def test_ellipse_with_one_radius_uses_it_for_both():
    out = clipped('<ellipse id="e" cx="10" cy="5" rx="4"/>')
    assert_clip_in_root("M14 5A4 4 0 0 1 10 9A4 4 0 0 1 6 5A4 4 0 0 1 10 1A4 4 0 0 1 14 5Z",
                        element(out, "e").get("d"), np.eye(3))


def test_line_is_clipped_as_a_stroke_even_when_filled():
    assert clipped('<line x1="-5" y1="5" x2="15" y2="5" fill="red"/>', fill_mode="fill") \
        == '<path d="M0 5H10" fill="red" />'


def test_polyline_without_fill_is_cut_into_open_pieces():
    out = clipped('<polyline fill="none" points="-5,5 5,5 5,15 8,15 8,5 15,5"/>')
    assert out == '<path fill="none" d="M0 5H5V10M8 10V5H10" />'


def test_polygon_is_clipped_as_a_closed_fill():
    out = clipped('<polygon points="-5 -5 15 -5 5 15"/>')
    assert out == '<path d="M10 5 7.5 10H2.5L0 5V0H10Z" />'


@pytest.mark.parametrize("shape", [
    '<rect x="-5" width="0" height="3"/>', '<rect x="-5" width="3"/>',
    '<circle cx="-5" r="0"/>', '<ellipse cx="-5" rx="-1" ry="-1"/>', '<path id="p"/>',
    '<polyline points="-5 5"/>', '<polygon points=""/>',
])
def test_shapes_that_do_not_render_are_left_as_they_are(shape):
    out = clipped(shape)
    assert ET.fromstring(svg(out))[0].attrib == ET.fromstring(svg(shape))[0].attrib


def test_paths_with_empty_subpaths_are_judged_by_their_points():
    body = ('<path d="" /><path d="M1 1" /><path d="M20 20" fill="none"/>'
            '<path fill="none" d="M1 1M-5 5H15M2 2"/><path d="M1 1H2" />')
    assert clipped(body) == ('<path d="" /><path d="M1 1" />'
                             '<path fill="none" d="M1 1M0 5H10M2 2" /><path d="M1 1H2" />')


def test_percentages_resolve_against_the_root_viewbox():
    doc = svg('<rect id="r" x="-50%" width="100%" height="10%"/>',
              ' viewBox="0 0 20 40"')
    out, _ = clip_svg_document(doc, (0, 0, 100, 100))
    assert element(out, "r").get("d") == "M10 0V4H0V0Z"


# --------------------------------------------------------------------------- what is removed

def test_shape_wholly_outside_is_removed_with_its_indent():
    doc = svg('\n  <path d="M1 1H2"/>\n  <rect x="20" width="1" height="1"/>\n  '
              '<path d="M30 0H40"/>\n')
    out, stats = clip_svg_document(doc, W10)
    assert out == svg('\n  <path d="M1 1H2" />\n') + "\n"
    assert (stats.geometries_in, stats.geometries_out) == (3, 1)


def test_first_child_removed_gives_its_indent_to_the_parent():
    assert clipped('<g>\n  <path d="M30 0H40"/>\n  <path d="M1 1H2"/>\n</g>') == \
        '<g>\n  <path d="M1 1H2" />\n</g>'


def test_keep_empty_keeps_empty_shapes_as_empty_paths():
    out = clipped('<rect id="r" x="20" width="1" height="1"/><path d="M30 0H40"/>',
                  keep_empty=True)
    assert out == '<path id="r" d="" /><path d="" />'


# --------------------------------------------------------------------------- transforms

CURVE = "M-5 2C0 14 10 14 15 2L5-4Z"


@pytest.mark.parametrize("group, own, m", [
    ("translate(3)", "", matrix(("translate", 3, 0))),
    ("translate(-2,4)", "", matrix(("translate", -2, 4))),
    ("scale(2 0.5)", "", matrix(("scale", 2, 0.5))),
    ("scale(.5)", "rotate(30)", matrix(("scale", .5, .5), ("rotate", 30))),
    ("", "rotate(-45 5 5)", matrix(("translate", 5, 5), ("rotate", -45),
                                   ("translate", -5, -5))),
    ("matrix(1 .2 -.3 .9 4 -1)", "skewX(20)",
     matrix(("matrix", 1, .2, -.3, .9, 4, -1), ("skewX", 20))),
    ("rotate(90)", "translate(0,-10)", matrix(("rotate", 90), ("translate", 0, -10))),
])
def test_transformed_shapes_are_clipped_in_root_space(group, own, m):
    g = f' transform="{group}"' if group else ""
    t = f' transform="{own}"' if own else ""
    out = clipped(f'<g{g}><path id="p" d="{CURVE}"{t}/><text>t</text></g>')
    p = element(out, "p")
    assert p.get("transform") == (own or None)
    assert ET.fromstring(svg(out))[0].get("transform") == (group or None)
    assert p.get("d") != CURVE
    assert_clip_in_root(CURVE, p.get("d"), m)


def test_nested_groups_compose_their_transforms():
    body = ('<g transform="translate(10 0)"><g transform="scale(2)">'
            '<g transform="rotate(90)"><circle id="c" cx="2" cy="3" r="4"/></g></g></g>')
    out = clipped(body)
    m = matrix(("translate", 10, 0), ("scale", 2, 2), ("rotate", 90))
    assert_clip_in_root("M6 3A4 4 0 0 1 2 7A4 4 0 0 1-2 3A4 4 0 0 1 2-1A4 4 0 0 1 6 3Z",
                        element(out, "c").get("d"), m)


def test_quarter_turns_are_exact():
    # rotate(90) maps with exact zeros and ones: the path comes back unrounded.
    out = clipped('<path id="p" transform="rotate(90)" d="M-5-5H5V-15"/>', fill_mode="stroke")
    assert element(out, "p").get("d") == "M0-5H5V-10"


def test_transform_list_separators():
    out = clipped('<path id="p" transform=" translate(1) ,scale(2,2)rotate(0)" '
                  'd="M-5 1H10"/>', fill_mode="stroke")
    assert element(out, "p").get("d") == "M-.5 1H4.5"


def test_singular_transform_leaves_the_shape_as_it_is():
    body = '<rect x="-5" width="20" height="3" transform="scale(0)" />'
    assert clipped(body) == body


def test_root_transform_and_viewbox_are_not_applied():
    doc = (f'<svg xmlns="{SVG_NAMESPACE}" viewBox="0 0 1 1" transform="scale(100)">'
           '<path id="p" d="M-5 5H15" fill="none"/></svg>')
    out, _ = clip_svg_document(doc, W10)
    assert element(out, "p").get("d") == "M0 5H10"


# --------------------------------------------------------------------------- fill or stroke

TRIANGLE = "M-5 5L15 5L5 15"


def test_unfilled_shape_is_clipped_as_a_stroke():
    assert clipped('<path fill="none" d="M-5 2H5V15"/>') == '<path fill="none" d="M0 2H5V10" />'


def test_filled_shape_is_clipped_as_a_closed_region():
    # The fill of the open path is that of its closed outline, cut along the window.
    assert clipped('<path d="M-5 2H5V15"/>') == \
        '<path d="M0 2H5V10H1.1538461538461537L0 8.5Z" />'


def test_fill_mode_overrides_the_fill_of_each_shape():
    body = f'<path d="{TRIANGLE}"/><path fill="none" d="{TRIANGLE}"/>'
    stroke = clip_svg(TRIANGLE, W10)[0]
    fill = clip_svg(TRIANGLE, W10, fill="nonzero")[0]
    assert clipped(body, fill_mode="stroke") == \
        f'<path d="{stroke}" /><path fill="none" d="{stroke}" />'
    assert clipped(body, fill_mode="fill") == \
        f'<path d="{fill}" /><path fill="none" d="{fill}" />'
    assert clipped(body, fill_mode="AUTO") == \
        f'<path d="{fill}" /><path fill="none" d="{stroke}" />'


def test_evenodd_fill_keeps_the_hole_under_its_rule():
    rings = "M-5-5H15V15H-5ZM2 2H8V8H2Z"
    out = clipped(f'<path id="p" fill-rule="evenodd" d="{rings}"/>')
    assert_clip_in_root(rings, element(out, "p").get("d"), np.eye(3), fill="evenodd")


def test_stats_add_up_over_strokes_and_each_fill_rule():
    shapes = [(TRIANGLE, None), ("M-5-5H15V15H-5ZM2 2H8V8H2Z", "evenodd"),
              ("M-5 0 5 20 15 0Z", "nonzero")]
    body = "".join(f'<path fill="{"none" if f is None else "red"}" '
                   f'fill-rule="{f or "nonzero"}" d="{d}"/>' for d, f in shapes)
    _, stats = clip_svg_document(svg(body), W10)
    expected = ClipStats.combine(clip_svg(d, W10, fill=f)[1] for d, f in shapes)
    assert stats == expected
    assert stats.geometries_in == 3 and stats.segments_in == 2 + 8 + 3


def test_document_without_shapes_has_zero_stats():
    out, stats = clip_svg_document(svg("<text>hi</text>"), W10)
    assert out == svg("<text>hi</text>") + "\n"
    assert stats.geometries_in == stats.segments_in == stats.fragments_evaluated == 0


# --------------------------------------------------------------------------- left alone

@pytest.mark.parametrize("container", ["defs", "clipPath", "mask", "pattern", "marker",
                                       "symbol", "svg", "foreignObject"])
def test_shapes_not_drawn_where_they_stand_are_left_alone(container):
    body = (f'<{container} id="k"><rect x="-5" y="-5" width="30" height="30" />'
            f'<g><path d="M-5 5H15" /></g></{container}>')
    assert clipped(body) == body


@pytest.mark.parametrize("other", [
    '<text x="-5" y="5">far <tspan x="-50">out</tspan></text>',
    '<use href="#k" x="-50" />', '<image href="a.png" x="-50" width="100" height="9" />',
    "<title>A</title>", "<desc>d</desc>", '<style>path { fill: none }</style>',
    '<linearGradient id="g"><stop offset="0" /></linearGradient>',
])
def test_other_elements_are_left_as_they_are(other):
    body = f'<g transform="translate(-20)">{other}<path d="M-5 5H50" fill="none"/></g>'
    assert clipped(body) == \
        f'<g transform="translate(-20)">{other}<path d="M20 5H30" fill="none" /></g>'


def test_namespaces_prefixes_and_foreign_elements_are_kept():
    doc = (f'<svg xmlns="{SVG_NAMESPACE}" xmlns:xlink="http://www.w3.org/1999/xlink" '
           'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
           'xmlns:foo="urn:foo">\n'
           '  <g inkscape:label="Layer" inkscape:groupmode="layer">\n'
           '    <foo:rect x="-5" width="20" height="20" />\n'
           '    <use xlink:href="#a" />\n'
           '    <rect x="-5" width="10" height="10" inkscape:label="r" />\n'
           '  </g>\n</svg>')
    out, _ = clip_svg_document(doc, W10)
    assert out == doc.replace('<rect x="-5" width="10" height="10"',
                              '<path d="M5 0V10H0V0Z"') + "\n"
    assert "ns0" not in out


def test_prefixed_svg_elements_are_clipped():
    doc = ('<s:svg xmlns:s="http://www.w3.org/2000/svg"><s:g>'
           '<s:rect x="-1" width="2" height="2"/></s:g></s:svg>')
    out, _ = clip_svg_document(doc, W10)
    assert out == ('<s:svg xmlns:s="http://www.w3.org/2000/svg"><s:g>'
                   '<s:path d="M1 0V2H0V0Z" /></s:g></s:svg>\n')


def test_document_without_a_namespace_is_read_as_svg():
    out, _ = clip_svg_document('<svg><path d="M-5 5H15" fill="none"/></svg>', W10)
    assert out == '<svg><path d="M0 5H10" fill="none" /></svg>\n'


def test_declaration_doctype_comments_and_instructions_are_kept():
    doc = ('<?xml version="1.0" standalone="no"?>\n<!-- made by hand -->\n'
           '<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" '
           '"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd">\n'
           '<?xml-stylesheet href="a.css"?>\n'
           f'<svg xmlns="{SVG_NAMESPACE}"><!-- inside --><?pi x?>'
           '<path d="M-5 5H15" fill="none"/><![CDATA[a<b]]>&lt;&#65;</svg>\n'
           '<!-- after -->\n')
    out, _ = clip_svg_document(doc, W10)
    assert out == (
        '<?xml version="1.0" encoding="UTF-8" standalone="no"?>\n<!-- made by hand -->\n'
        '<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" '
        '"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd">\n'
        '<?xml-stylesheet href="a.css"?>\n'
        f'<svg xmlns="{SVG_NAMESPACE}"><!-- inside --><?pi x?>'
        '<path d="M0 5H10" fill="none" />a&lt;b&lt;A</svg>\n<!-- after -->\n')


def test_bytes_are_decoded_as_declared():
    doc = ('<?xml version="1.0" encoding="ISO-8859-1"?>'
           f'<svg xmlns="{SVG_NAMESPACE}"><text>caf\xe9</text></svg>').encode("latin-1")
    out, _ = clip_svg_document(doc, W10)
    assert out == ('<?xml version="1.0" encoding="UTF-8"?>\n'
                   f'<svg xmlns="{SVG_NAMESPACE}"><text>caf\xe9</text></svg>\n')


def test_options_reach_the_clip():
    body = '<path id="p" fill="none" d="M-5 5C0 10 10 10 15 5"/>'
    flat = element(clipped(body, curves="flatten", tolerance=0.01), "p").get("d")
    assert "C" not in flat and "L" in flat
    assert element(clipped(body, precision=3), "p").get("d") == "M0 7.97C3.18 9.01 6.82 " \
                                                                "9.01 10 7.97"


# --------------------------------------------------------------------------- errors

def test_malformed_xml_reports_line_and_column():
    with pytest.raises(ParseError, match=r"line 3, column 5: mismatched tag") as info:
        clip_svg_document(svg('\n<g>\n  </a></g>'), W10)
    assert (info.value.line, info.value.column) == (3, 5)


def test_bad_path_data_names_the_element_and_its_line():
    doc = svg('\n<g>\n  <path d="M0 0H1"/>\n  <path id="bad" d="M0 0 L1 x"/></g>')
    with pytest.raises(ParseError, match=r'^<path id="bad"> on line 4: d: position 8: '
                                         r"expected a number, found 'x'$") as info:
        clip_svg_document(doc, W10)
    assert (info.value.line, info.value.position) == (4, 8)


@pytest.mark.parametrize("body, message", [
    ('<g transform="scale(1 2 3)"><path d="M0 0H1"/></g>',
     r"<g> on line 1: transform: position 0: scale takes 1 or 2 numbers, got '1 2 3'"),
    ('<path transform="translate(1) shear(2)" d="M0 0H1"/>',
     r"transform: position 13: expected matrix, .* found 'shear\(2\)'"),
    ('<polyline id="q" points="1 2 3"/>',
     r'<polyline id="q"> on line 1: points: an odd number of coordinates \(3\)'),
    ('<polygon points="1 2 3 x"/>', r"points: expected numbers"),
    ('<rect width="ten" height="1"/>', r"width: expected a length, found 'ten'"),
    ('<rect width="1e999" height="1"/>', r"width: number out of range"),
    ('<html/>', None),
])
def test_malformed_attributes_raise_parse_error_naming_the_element(body, message):
    doc = svg(body) if message else "<html/>"
    with pytest.raises(ParseError, match=message or r"not an SVG document: the root "
                                                    r"element is <html>"):
        clip_svg_document(doc, W10)


@pytest.mark.parametrize("attributes, message", [
    ('width="2em" height="1"', "unit 'em' is not supported"),
    ('width="50%" height="1"', "a percentage needs the root's viewBox"),
])
def test_lengths_that_cannot_be_resolved_are_refused(attributes, message):
    with pytest.raises(UnsupportedGeometryError, match=message):
        clip_svg_document(svg(f"<rect {attributes}/>"), W10)


def test_billion_laughs_is_refused_quickly():
    levels = "".join(f'<!ENTITY lol{i} "{f"&lol{i - 1};" * 10}">' for i in range(1, 10))
    doc = (f'<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY lol0 "lol">{levels}]>'
           f'<svg xmlns="{SVG_NAMESPACE}"><text>&lol9;</text></svg>')
    start = time.perf_counter()
    with pytest.raises(ParseError, match="entity declarations are not accepted"):
        clip_svg_document(doc, W10)
    assert time.perf_counter() - start < 0.5


@pytest.mark.parametrize("doctype", [
    '<!DOCTYPE svg [<!ENTITY x SYSTEM "file:///etc/passwd">]>',
    '<!DOCTYPE svg [<!ENTITY % x SYSTEM "http://example.com/x.dtd"> %x;]>',
    '<!DOCTYPE svg [<!ENTITY x SYSTEM "a.png" NDATA png>]>',
])
def test_external_entities_are_refused(doctype):
    with pytest.raises(ParseError, match="entity declarations are not accepted"):
        clip_svg_document(f"{doctype}<svg>&x;</svg>", W10)


def test_undeclared_entities_are_refused_even_with_an_external_dtd():
    doc = ('<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://example.com/svg11.dtd">'
           "<svg><text>&nbsp;</text></svg>")
    with pytest.raises(ParseError, match="undeclared entity 'nbsp'"):
        clip_svg_document(doc, W10)


def test_deep_nesting_is_refused():
    doc = svg("<g>" * MAX_NESTING + "</g>" * MAX_NESTING)
    with pytest.raises(ParseError, match=f"nested more than {MAX_NESTING} deep"):
        clip_svg_document(doc, W10)
    deepest = MAX_NESTING - 2   # the root and the path make two levels more
    ok = svg("<g>" * deepest + '<path d="M-1 1H1" fill="none"/>' + "</g>" * deepest)
    assert 'd="M0 1H1"' in clip_svg_document(ok, W10)[0]


def test_coordinates_overflowing_under_a_transform_name_the_element():
    with pytest.raises(rnsca.InvalidGeometryError, match=r'<path id="p"> on line 1: after '
                                                        r"its transforms: .*finite"):
        clip_svg_document(svg('<path id="p" d="M0 0H1e308" transform="scale(10)"/>'), W10)


@pytest.mark.parametrize("options, error, message", [
    ({"fill_mode": "outline"}, InvalidOptionError,
     "fill_mode must be one of 'auto', 'stroke', 'fill', got 'outline'"),
    ({"curves": "bent"}, InvalidOptionError, "curves must be one of"),
    ({"precision": 0}, InvalidOptionError, "precision must be None or an int"),
    ({"tolerance": -1}, InvalidOptionError, "tolerance must be > 0"),
    ({"method": "midpoint"}, InvalidOptionError, "method='rnsca' only"),
    ({"window": (0, 0, 0, 1)}, InvalidWindowError, "xmin < xmax"),
])
def test_bad_options_are_refused_before_reading(options, error, message):
    window = options.pop("window", W10)
    with pytest.raises(error, match=message):
        clip_svg_document("not even XML", window, **options)


def test_document_must_be_text_or_bytes():
    with pytest.raises(TypeError, match="document must be str or bytes"):
        clip_svg_document(ET.fromstring(svg("")), W10)
