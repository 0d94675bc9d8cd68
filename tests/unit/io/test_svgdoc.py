"""Reading SVG documents: the drawn shapes and their paint (clipping: test_clip_svgdoc)."""

import pytest

from rnsca.io.svgdoc import SVG_NAMESPACE, find_shapes, read_document

TRIANGLE = "M-5 5L15 5L5 15"


def svg(body: str, attributes: str = "") -> str:
    return f'<svg xmlns="{SVG_NAMESPACE}"{attributes}>{body}</svg>'


@pytest.mark.parametrize("body, fill", [
    (f'<path id="p" d="{TRIANGLE}"/>', "nonzero"),
    (f'<path id="p" fill="none" d="{TRIANGLE}"/>', None),
    (f'<path id="p" style="fill: none" fill="red" d="{TRIANGLE}"/>', None),
    (f'<path id="p" style="fill:red" fill="none" d="{TRIANGLE}"/>', "nonzero"),
    (f'<path id="p" style="FILL : NONE !important" d="{TRIANGLE}"/>', None),
    (f'<g fill="none"><g><path id="p" d="{TRIANGLE}"/></g></g>', None),
    (f'<g style="fill:none"><path id="p" fill="inherit" d="{TRIANGLE}"/></g>', None),
    (f'<g fill="none"><path id="p" fill="currentColor" d="{TRIANGLE}"/></g>', "nonzero"),
    (f'<g fill="none"><path id="p" fill="initial" d="{TRIANGLE}"/></g>', "nonzero"),
    (f'<path id="p" fill-rule="evenodd" d="{TRIANGLE}"/>', "evenodd"),
    (f'<g style="fill-rule:evenodd"><path id="p" d="{TRIANGLE}"/></g>', "evenodd"),
    (f'<g fill-rule="evenodd"><path id="p" fill-rule="nonzero" d="{TRIANGLE}"/></g>',
     "nonzero"),
    (f'<g fill-rule="evenodd"><path id="p" fill-rule="bogus" d="{TRIANGLE}"/></g>',
     "evenodd"),
])
def test_fill_and_fill_rule_come_from_style_attributes_and_ancestors(body, fill):
    (shape,) = find_shapes(read_document(svg(body)))
    assert (shape.fill_rule if shape.filled else None) == fill


def test_root_fill_is_inherited():
    doc = read_document(svg(f'<path d="{TRIANGLE}"/>', ' fill="none"'))
    assert [shape.filled for shape in find_shapes(doc)] == [False]
