"""Fuzz target: the SVG document reader and writer (`rnsca.io.svgdoc`), and its clip.

An input is the bytes of a document. A finding is any of:

- an exception other than the documented ones (subclasses of `rnsca.errors.RnscaError`,
  which are ValueError or TypeError), from reading the document, listing its shapes,
  reading their outlines, or clipping it (`rnsca.clip_svg_document`, window
  ``0 0 100 100``);
- a disagreement with the reference reader on accepting the document, or on the tree;
- a document that does not read back, as the same tree, from what the writer wrote
  (reading, writing and clipping must keep everything they do not clip); the same for
  the clipped document, which must read again.

Reference
---------
The standard library's DOM, ``xml.dom.minidom`` as its ``expatbuilder`` builds it
without namespace processing (as rnsca reads: names stay as written, ``xmlns``
declarations are attributes, and a name may hold any number of colons). rnsca builds an
ElementTree itself from expat's events. Both sit on expat, so the XML grammar is not what is
compared: the tree built from it is (tags, attributes in order, text, tails, comments,
processing instructions). Where rnsca refuses on purpose, the reference may accept: an
entity declaration (rnsca refuses every one, against entity expansion and external
entities), a reference to an undeclared entity, and nesting deeper than
`rnsca.io.svgdoc.MAX_NESTING`; rnsca's message must then say which.
"""

from __future__ import annotations

from xml.dom import Node, expatbuilder
from xml.parsers import expat

import rnsca
from rnsca.errors import ParseError, RnscaError
from rnsca.io.svgdoc import (
    find_shapes,
    map_shapes,
    parse_shapes,
    read_document,
    write_document,
)

__all__ = ["MAX_LEN", "setup", "test_one_input"]

#: Longest input libFuzzer makes.
MAX_LEN = 4096

#: The window every document is clipped to.
WINDOW = (0.0, 0.0, 100.0, 100.0)



# What rnsca refuses that expat (and so the reference) accepts, by its message.
_DELIBERATE = ("entity declarations are not accepted", "undeclared entity",
               "nested more than")


def _reference_tree(data: bytes) -> tuple:
    """Return the DOM's tree of `data` as `_shape` gives rnsca's; raises if it refuses.

    Raises ``ExpatError`` for a document that is not well-formed.
    """
    document = expatbuilder.parseString(data, namespaces=False)
    (root,) = [node for node in document.childNodes if node.nodeType == Node.ELEMENT_NODE]
    return _dom_shape(root, None)


def _dom_shape(element, tail: str | None) -> tuple:
    """Return a DOM element as nested tuples: tag, attributes, text, tail, children."""
    text, children = None, []
    pending: list[str] = []   # text before the next child (or the end)
    for node in element.childNodes:
        if node.nodeType in (Node.TEXT_NODE, Node.CDATA_SECTION_NODE):
            pending.append(node.data)
            continue
        joined = "".join(pending) or None
        if children:
            children[-1] = children[-1][:3] + (joined, children[-1][4])
        else:
            text = joined
        pending = []
        if node.nodeType == Node.ELEMENT_NODE:
            children.append(_dom_shape(node, None))
        elif node.nodeType == Node.COMMENT_NODE:
            children.append(("Comment", [], node.data, None, []))
        elif node.nodeType == Node.PROCESSING_INSTRUCTION_NODE:
            data = f"{node.target} {node.data}" if node.data else node.target
            children.append(("ProcessingInstruction", [], data, None, []))
    joined = "".join(pending) or None
    if children:
        children[-1] = children[-1][:3] + (joined, children[-1][4])
    else:
        text = joined
    attributes = list(element.attributes.items())
    return (element.tagName, attributes, text, tail, children)


def _shape(element) -> tuple:
    """Return rnsca's tree under `element` as nested tuples (comments and PIs included)."""
    tag = element.tag
    if callable(tag):   # ElementTree's Comment or ProcessingInstruction factory
        tag = tag.__name__
    return (tag, list(element.attrib.items()), element.text, element.tail,
            [_shape(child) for child in element])


def _check_shapes(doc) -> None:
    """List the shapes, read their outlines and map them: only documented errors."""
    try:
        shapes = find_shapes(doc)
        if shapes:
            import numpy as np

            paths = parse_shapes(doc, shapes, None)
            matrices = np.array([shape.matrix for shape in shapes], dtype=np.float64)
            map_shapes(doc, shapes, paths, matrices)
    except RnscaError:
        pass


def setup() -> None:
    """Compile the path reader's and the Bézier clip's kernels."""
    document = ('<svg xmlns="http://www.w3.org/2000/svg"><path d="M-5 5C0 20 20 0 150 50Z"/>'
                '<rect x="10" y="10" width="200" height="20" rx="3"/>'
                '<g transform="rotate(30)"><circle cx="0" cy="0" r="50"/></g></svg>')
    for curves in ("preserve", "flatten"):
        rnsca.clip_svg_document(document, WINDOW, curves=curves)


def test_one_input(data: bytes) -> None:
    """Read, check, write, reread and clip the document in `data`."""
    try:
        expected = _reference_tree(data)
    except expat.ExpatError as error:
        expected = error
    except RecursionError:
        return   # deeper than Python's stack: both refuse, rnsca by its nesting limit
    try:
        doc = read_document(data)
    except ParseError as error:
        if not isinstance(expected, Exception):
            assert any(reason in str(error) for reason in _DELIBERATE), (
                f"rnsca refused a document the DOM reads: {error}")
        return
    assert not isinstance(expected, Exception), (
        f"rnsca read a document the DOM refuses: {expected}")
    tree = _shape(doc.root)
    assert tree == expected, f"rnsca's tree differs from the DOM's: {tree} != {expected}"
    _check_shapes(doc)
    written = write_document(doc)
    again = read_document(written)
    assert _shape(again.root) == tree, f"the written document reads back differently: " \
                                       f"{written!r}"
    assert write_document(again) == written, "writing is not stable"
    try:
        clipped, _ = rnsca.clip_svg_document(data, WINDOW)
    except RnscaError:
        return
    read_document(clipped)
