"""Read and write SVG documents: the drawn shapes as path data, the rest kept as it was.

`read_document` parses a document and `find_shapes` lists its drawn shapes (``<path>``
and the basic shapes, in the root and in ``<g>``, ``<a>`` and ``<switch>``): each with
its outline as path data in its own coordinates, the map of the transforms above it
into the root's user space, and its paint (fill, fill-rule). `parse_shapes`,
`map_shapes` and `inverse_maps` turn them into `PathArrays` in root units and back;
`set_path_data` and `remove_children` put new path data in place, and `write_document`
writes the document again. Reading and writing keep everything else: elements,
attributes in their order, namespace prefixes as written, text, comments, processing
instructions. Clipping a document is `rnsca.clip_svgdoc`; this module knows nothing of it.

The document is read with the standard library's expat, without namespace processing
(names stay as written, so the output has the same prefixes and ``xmlns``
declarations, never ``ns0:``), and refusing entity declarations, so neither entity
expansion ("billion laughs") nor external entities (XXE) can happen.
"""

from __future__ import annotations

import functools
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NoReturn
from xml.parsers import expat

import numpy as np

from rnsca.errors import InvalidGeometryError, ParseError, UnsupportedGeometryError
from rnsca.io.svgpath import PathArrays, parse_paths

__all__ = ["IDENTITY", "MAX_NESTING", "SVG_NAMESPACE", "Shape", "SvgDocument", "find_shapes",
           "inverse_maps", "largest_stretch", "map_shapes", "parse_shapes", "read_document",
           "remove_children", "set_path_data", "write_document"]

#: The SVG namespace; elements in it, or in no namespace at all, are SVG elements.
SVG_NAMESPACE = "http://www.w3.org/2000/svg"

#: Deepest element nesting accepted. The writer (ElementTree's) recurses once per
#: level, so a bound well below Python's recursion limit keeps any document writable.
MAX_NESTING = 256

# Containers whose children are drawn where they are; the walk descends only into
# these. Everything else (defs, clipPath, mask, pattern, marker, symbol, nested svg,
# use, text, image, foreignObject, metadata...) is left as it is, subtree included.
_CONTAINERS = frozenset({"g", "a", "switch"})

# Attributes that give each basic shape its geometry; a clipped shape becomes a
# <path> without them.
_GEOMETRY = {
    "rect": ("x", "y", "width", "height", "rx", "ry"),
    "circle": ("cx", "cy", "r"),
    "ellipse": ("cx", "cy", "rx", "ry"),
    "line": ("x1", "y1", "x2", "y2"),
    "polyline": ("points",),
    "polygon": ("points",),
    "path": ("d",),
}

# Absolute length units in user units (CSS pixels).
_UNITS = {"": 1.0, "px": 1.0, "in": 96.0, "cm": 96.0 / 2.54, "mm": 96.0 / 25.4,
          "q": 96.0 / 101.6, "pt": 96.0 / 72.0, "pc": 16.0}

_NUMBER = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_NUMBER_RE = re.compile(_NUMBER)
# A list of numbers: separated by a comma, spaces, or nothing before a sign or a dot.
_NUMBER_LIST = re.compile(rf"\s*(?:{_NUMBER}(?:(?:\s*,\s*|\s+|(?=[+.-])){_NUMBER})*)?\s*")
_LENGTH = re.compile(rf"\s*({_NUMBER})\s*([a-zA-Z]*|%)\s*")
_TRANSFORM = re.compile(r"\s*(matrix|translate|scale|rotate|skewX|skewY)\s*\(([^()]*)\)"
                        r"\s*(?:,\s*)?")
_TRANSFORM_ARITY = {"matrix": (6,), "translate": (1, 2), "scale": (1, 2),
                    "rotate": (1, 3), "skewX": (1,), "skewY": (1,)}
_CSS_COMMENT = re.compile(r"/\*.*?\*/", re.S)

#: The identity map. An affine map is written as SVG writes it, ``matrix(a b c d e f)``:
#: x' = a x + c y + e, y' = b x + d y + f.
IDENTITY = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)


# --------------------------------------------------------------------------- shapes

@dataclass(slots=True)
class Shape:
    """A drawn shape: its element, path data in its own coordinates, its paint."""

    element: ET.Element
    parent: ET.Element
    local: str                  # "path", "rect", ...
    d: str
    matrix: tuple[float, ...]   # own coordinates to the root's, (a, b, c, d, e, f)
    filled: bool                # its computed fill is not none
    fill_rule: str              # its computed fill-rule: "nonzero" or "evenodd"


def parse_shapes(doc: SvgDocument, shapes: list[Shape],
                 tolerance: float | None) -> PathArrays:
    """Return the path data of `shapes` parsed at once; errors name the element."""
    try:
        return parse_paths([shape.d for shape in shapes], tolerance=tolerance)
    except (ParseError, InvalidGeometryError) as error:
        index = getattr(error, "path_index", None)
        if index is None:
            raise
        message = re.sub(r"^path \d+(, |: )", "", str(error))
        shape = shapes[index]
        what = "d" if shape.local == "path" else "outline"
        raised = type(error)(f"{_describe(doc, shape.element)}: {what}: {message}")
        raised.__dict__.update(error.__dict__)
        raised.line = doc.lines.get(shape.element)
        raise raised from None


def map_shapes(doc: SvgDocument, shapes: list[Shape], paths: PathArrays,
               matrices: np.ndarray) -> PathArrays:
    """Return `paths` with path ``i`` mapped by ``matrices[i]``; errors name the element."""
    return _named(doc, shapes, _map_paths, paths, matrices)


def _named(doc, shapes, function, paths, matrices):
    """Call ``function(paths, matrices)``; an invalid result names the shape's element."""
    try:
        return function(paths, matrices)
    except InvalidGeometryError as error:
        index = getattr(error, "path_index", None)
        if index is None:
            raise
        message = re.sub(r"^path \d+: ", "", str(error))
        raise InvalidGeometryError(
            f"{_describe(doc, shapes[index].element)}: after its transforms: "
            f"{message}") from None


def _map_paths(paths: PathArrays, matrices: np.ndarray) -> PathArrays:
    """Return `paths` with path ``i`` mapped by ``matrices[i]`` (a, b, c, d, e, f).

    One vectorized step over all control points and subpath starts. The map is written
    out as ``a*x + c*y + e`` (not a matmul, whose kernels may round differently from
    row to row): a point shared by two segments maps to the same float64 in both, so
    the mapped paths stay continuous, exactly.
    """
    subpath_path = np.repeat(np.arange(len(paths)), np.diff(paths.path_offsets))
    segment_path = np.repeat(subpath_path, np.diff(paths.subpath_offsets))
    return PathArrays(controls=_apply(matrices[segment_path, None, :], paths.controls),
                      degree=paths.degree, subpath_offsets=paths.subpath_offsets,
                      closed=paths.closed, start=_apply(matrices[subpath_path], paths.start),
                      path_offsets=paths.path_offsets)


def _apply(m: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Return `points` (..., 2) mapped by the matrices `m` (..., 6), broadcast."""
    x, y = points[..., 0], points[..., 1]
    out = np.empty(np.broadcast_shapes(points.shape, m.shape[:-1] + (2,)))
    with np.errstate(over="ignore", invalid="ignore"):  # PathArrays names the path
        out[..., 0] = m[..., 0] * x + m[..., 2] * y + m[..., 4]
        out[..., 1] = m[..., 1] * x + m[..., 3] * y + m[..., 5]
    return out


def inverse_maps(m: np.ndarray) -> np.ndarray:
    """Return the inverse of each map (n, 6); the caller has excluded singular ones."""
    a, b, c, d, e, f = m.T
    det = a * d - b * c
    return np.stack([d / det, -b / det, -c / det, a / det, (c * f - d * e) / det,
                     (b * e - a * f) / det], axis=1)


def largest_stretch(m: np.ndarray) -> np.ndarray:
    """Return each map's largest singular value: the most it lengthens a vector."""
    a, b, c, d = m[:, 0], m[:, 1], m[:, 2], m[:, 3]
    s = a * a + b * b + c * c + d * d
    det = a * d - b * c
    return np.sqrt((s + np.sqrt(np.maximum(s * s - 4 * det * det, 0.0))) / 2)


def set_path_data(shape: Shape, d: str) -> None:
    """Write the clipped path data; a basic shape becomes a <path> in its place."""
    element = shape.element
    if shape.local == "path":
        element.set("d", d)
        return
    geometry = _GEOMETRY[shape.local]
    attributes: dict[str, str] = {}
    for name, value in element.attrib.items():
        if name in geometry:
            attributes.setdefault("d", d)  # where the first geometry attribute was
        else:
            attributes[name] = value
    attributes.setdefault("d", d)
    prefix = element.tag[:len(element.tag) - len(shape.local)]
    element.tag = prefix + "path"
    element.attrib.clear()
    element.attrib.update(attributes)


def remove_children(parent: ET.Element, removed: set[int]) -> None:
    """Remove the children of `parent` whose ids are in `removed`, and their indents.

    The whitespace before a removed element goes with it: its tail takes the place of
    the text before it, unless that text is not whitespace (mixed content: joined).
    """
    kept = []
    for child in parent:
        if id(child) not in removed:
            kept.append(child)
            continue
        before = (kept[-1].tail if kept else parent.text) or ""
        after = child.tail
        text = after if not before.strip() else before + (after or "")
        if kept:
            kept[-1].tail = text
        else:
            parent.text = text
    parent[:] = kept


# --------------------------------------------------------------------------- the walk

@dataclass(frozen=True, slots=True)
class _Context:
    """What an element inherits: its parent's map to the root, paint and namespaces."""

    matrix: tuple[float, ...]
    filled: bool
    fill_rule: str
    namespaces: dict


def find_shapes(doc: SvgDocument) -> list[Shape]:
    """Return the drawn shapes of the document, in document order, with their paint.

    Descends only into containers; shapes that do not render, and shapes under a
    singular transform, are left out (and so left as they are).
    """
    root = doc.root
    namespaces = _declare({"": None}, root)
    local = _svg_name(root.tag, namespaces)
    if local != "svg":
        raise ParseError(f"not an SVG document: the root element is <{root.tag}>, not "
                         f"<svg> (in the SVG namespace {SVG_NAMESPACE} or none)")
    context = _paint(root, _Context(IDENTITY, True, "nonzero", namespaces))
    shapes: list[Shape] = []
    stack = [(child, root, context) for child in reversed(root)]
    while stack:
        element, parent, context = stack.pop()
        if not isinstance(element.tag, str):  # a comment or processing instruction
            continue
        namespaces = _declare(context.namespaces, element)
        local = _svg_name(element.tag, namespaces)
        if local not in _CONTAINERS and local not in _GEOMETRY:
            continue
        matrix = _compose(context.matrix, _transform(doc, element))
        inner = _paint(element, _Context(matrix, context.filled, context.fill_rule,
                                         namespaces))
        if local in _CONTAINERS:
            stack.extend((child, element, inner) for child in reversed(element))
            continue
        d = _outline(doc, element, local)
        if d is None or not _invertible(matrix):
            continue
        shapes.append(Shape(element, parent, local, d, matrix, inner.filled,
                            inner.fill_rule))
    return shapes


def _declare(namespaces: dict, element: ET.Element) -> dict:
    """Return the prefixes in scope inside `element` (a copy if it declares any)."""
    declared = {name: uri for name, uri in element.attrib.items()
                if name == "xmlns" or name.startswith("xmlns:")}
    if not declared:
        return namespaces
    out = dict(namespaces)
    for name, uri in declared.items():
        out[name[6:]] = uri or None   # "xmlns" -> "", "xmlns:p" -> "p"
    return out


def _svg_name(tag: str, namespaces: dict) -> str | None:
    """Return the local name of an SVG element's tag, None for other namespaces."""
    prefix, _, local = tag.rpartition(":")
    if prefix not in namespaces:
        return None
    uri = namespaces[prefix]
    return local if uri == SVG_NAMESPACE or (uri is None and not prefix) else None


def _paint(element: ET.Element, context: _Context) -> _Context:
    """Return `context` with the element's own fill and fill-rule applied."""
    style = _declarations(element.get("style"))
    fill = style.get("fill", element.get("fill"))
    rule = style.get("fill-rule", element.get("fill-rule"))
    filled, fill_rule = context.filled, context.fill_rule
    if fill is not None:
        value = fill.strip().lower()
        if value == "initial":
            filled = True
        elif value not in ("inherit", "unset", ""):
            filled = value != "none"
    if rule is not None:
        value = rule.strip().lower()
        if value == "initial":
            fill_rule = "nonzero"
        elif value in ("nonzero", "evenodd"):
            fill_rule = value
    if (filled, fill_rule) == (context.filled, context.fill_rule):
        return context
    return _Context(context.matrix, filled, fill_rule, context.namespaces)


def _declarations(style: str | None) -> dict[str, str]:
    """Return the properties of a ``style`` attribute (lower-case names)."""
    if not style:
        return {}
    out = {}
    for declaration in _CSS_COMMENT.sub("", style).split(";"):
        name, colon, value = declaration.partition(":")
        if colon:
            value = re.sub(r"!\s*important\s*$", "", value.strip(), flags=re.I)
            out[name.strip().lower()] = value.strip()
    return out


# --------------------------------------------------------------------------- transforms

def _transform(doc: SvgDocument, element: ET.Element) -> tuple[float, ...]:
    """Return the map of the element's ``transform`` attribute (identity if none).

    Raises ParseError naming the element and the character position for a malformed
    list.
    """
    text = element.get("transform")
    if text is None or not text.strip() or text.strip() == "none":
        return IDENTITY
    matrix: tuple[float, ...] = IDENTITY
    position = 0
    while position < len(text):
        match = _TRANSFORM.match(text, position)
        if match is None:
            rest = text[position:].lstrip()
            if not rest:
                break
            raise _element_error(doc, element, f"transform: position "
                                 f"{len(text) - len(rest)}: expected matrix, translate, "
                                 f"scale, rotate, skewX or skewY, found {rest[:12]!r}")
        name, args = match.group(1), match.group(2)
        values = _numbers(args)
        if values is None or len(values) not in _TRANSFORM_ARITY[name]:
            counts = " or ".join(map(str, _TRANSFORM_ARITY[name]))
            raise _element_error(doc, element, f"transform: position {match.start(1)}: "
                                 f"{name} takes {counts} numbers, got {args.strip()!r}")
        matrix = _compose(matrix, _function_matrix(name, values))
        position = match.end()
    return matrix


def _function_matrix(name: str, v: list[float]) -> tuple[float, ...]:
    """Return the map of one transform function."""
    if name == "matrix":
        return tuple(v)
    if name == "translate":
        return (1.0, 0.0, 0.0, 1.0, v[0], v[1] if len(v) == 2 else 0.0)
    if name == "scale":
        return (v[0], 0.0, 0.0, v[1] if len(v) == 2 else v[0], 0.0, 0.0)
    if name == "rotate":
        cos, sin = _cos_sin(v[0])
        rotation = (cos, sin, -sin, cos, 0.0, 0.0)
        if len(v) == 1:
            return rotation
        cx, cy = v[1], v[2]
        return _compose(_compose((1.0, 0.0, 0.0, 1.0, cx, cy), rotation),
                        (1.0, 0.0, 0.0, 1.0, -cx, -cy))
    tangent = math.tan(math.radians(v[0]))
    return (1.0, 0.0, tangent, 1.0, 0.0, 0.0) if name == "skewX" else \
        (1.0, tangent, 0.0, 1.0, 0.0, 0.0)


def _cos_sin(degrees: float) -> tuple[float, float]:
    """Return the cosine and sine of an angle, exact for multiples of 90 degrees."""
    turn = math.fmod(degrees, 360.0)
    quarter = {0.0: (1.0, 0.0), 90.0: (0.0, 1.0), 180.0: (-1.0, 0.0), 270.0: (0.0, -1.0)}
    exact = quarter.get(turn % 360.0)
    if exact is not None:
        return exact
    radians = math.radians(turn)
    return math.cos(radians), math.sin(radians)


def _compose(m: tuple[float, ...], n: tuple[float, ...]) -> tuple[float, ...]:
    """Return the map that applies `n`, then `m`."""
    if n == IDENTITY:
        return m
    if m == IDENTITY:
        return n
    a, b, c, d, e, f = m
    return (a * n[0] + c * n[1], b * n[0] + d * n[1],
            a * n[2] + c * n[3], b * n[2] + d * n[3],
            a * n[4] + c * n[5] + e, b * n[4] + d * n[5] + f)


@functools.lru_cache(maxsize=256)   # siblings share their group's map
def _invertible(m: tuple[float, ...]) -> bool:
    """Return whether the map is finite and its inverse too (not singular)."""
    det = m[0] * m[3] - m[1] * m[2]
    return all(map(math.isfinite, m)) and det != 0.0 and math.isfinite(1.0 / det) \
        and all(math.isfinite(v / det) for v in m)


def _numbers(text: str) -> list[float] | None:
    """Return the numbers of a comma/space separated list, None if malformed."""
    if _NUMBER_LIST.fullmatch(text) is None:
        return None
    return [float(token) for token in _NUMBER_RE.findall(text)]


# --------------------------------------------------------------------------- basic shapes

def _outline(doc: SvgDocument, element: ET.Element, local: str) -> str | None:
    """Return the shape's outline as path data (SVG 2's equivalent path).

    None if the shape does not render (zero size, no ``d``, fewer than 2 points).
    """
    if local == "path":
        return element.get("d")

    def length(name: str, axis: str) -> float:
        value = _length(doc, element, name, axis)
        return 0.0 if value is None else value

    def optional_length(name: str, axis: str) -> float | None:
        return _length(doc, element, name, axis)

    if local == "rect":
        return _rect_outline(length, optional_length)
    if local in ("circle", "ellipse"):
        cx, cy = length("cx", "x"), length("cy", "y")
        rx: float | None
        ry: float | None
        if local == "circle":
            rx = ry = length("r", "xy")
        else:
            rx, ry = optional_length("rx", "x"), optional_length("ry", "y")
            rx, ry = (rx if rx is not None else ry), (ry if ry is not None else rx)
        if rx is None or ry is None or not (rx > 0 and ry > 0):
            return None
        arc = f"A{rx!r} {ry!r} 0 0 1"
        return (f"M{cx + rx!r} {cy!r}{arc} {cx!r} {cy + ry!r}{arc} {cx - rx!r} {cy!r}"
                f"{arc} {cx!r} {cy - ry!r}{arc} {cx + rx!r} {cy!r}Z")
    if local == "line":
        return (f"M{length('x1', 'x')!r} {length('y1', 'y')!r}"
                f"L{length('x2', 'x')!r} {length('y2', 'y')!r}")
    values = _numbers(element.get("points", ""))
    if values is None:
        raise _element_error(doc, element, "points: expected numbers separated by "
                             "commas or spaces")
    if len(values) % 2:
        raise _element_error(doc, element, f"points: an odd number of coordinates "
                             f"({len(values)})")
    if len(values) < 4:
        return None
    pairs = " ".join(f"{x!r} {y!r}" for x, y in zip(values[::2], values[1::2], strict=True))
    return f"M{pairs}" + ("Z" if local == "polygon" else "")


def _rect_outline(length: Callable[[str, str], float],
                  optional_length: Callable[[str, str], float | None]) -> str | None:
    """Return a rectangle's outline; rounded corners as arcs, radii as SVG 2 sets them.

    `length` reads a length attribute (0 when absent), `optional_length` too (None).
    """
    x, y = length("x", "x"), length("y", "y")
    w, h = optional_length("width", "x"), optional_length("height", "y")
    if w is None or h is None or not (w > 0 and h > 0):
        return None
    rx, ry = optional_length("rx", "x"), optional_length("ry", "y")
    rx = None if rx is not None and rx < 0 else rx   # negative: invalid, i.e. auto
    ry = None if ry is not None and ry < 0 else ry
    rx, ry = (rx if rx is not None else ry), (ry if ry is not None else rx)
    rx, ry = min(rx or 0.0, w / 2), min(ry or 0.0, h / 2)
    if rx == 0 or ry == 0:
        return f"M{x!r} {y!r}H{x + w!r}V{y + h!r}H{x!r}Z"
    arc = f"A{rx!r} {ry!r} 0 0 1"
    return (f"M{x + rx!r} {y!r}H{x + w - rx!r}{arc} {x + w!r} {y + ry!r}V{y + h - ry!r}"
            f"{arc} {x + w - rx!r} {y + h!r}H{x + rx!r}{arc} {x!r} {y + h - ry!r}"
            f"V{y + ry!r}{arc} {x + rx!r} {y!r}Z")


def _length(doc: SvgDocument, element: ET.Element, name: str, axis: str) -> float | None:
    """Return a length attribute in user units (None when absent or ``auto``).

    Absolute units convert at 96 per inch; a percentage is of the root viewport's
    width (``axis`` "x"), height ("y") or normalized diagonal ("xy").
    """
    text = element.get(name)
    if text is None:
        return None
    try:   # the common case: a plain number ("1_0", "inf" and "nan" go on below)
        value = float(text)
    except ValueError:
        pass
    else:
        if math.isfinite(value) and "_" not in text:
            return value
    if text.strip() == "auto":
        return None
    match = _LENGTH.fullmatch(text)
    if match is None:
        raise _element_error(doc, element, f"{name}: expected a length, found {text!r}")
    value = float(match.group(1))
    unit = match.group(2).lower()
    if not math.isfinite(value):
        raise _element_error(doc, element, f"{name}: number out of range, found {text!r}")
    if unit in _UNITS:
        return value * _UNITS[unit]
    if unit != "%":
        raise UnsupportedGeometryError(
            f"{_describe(doc, element)}: {name}: unit {unit!r} is not supported (use "
            f"user units, px, in, cm, mm, Q, pt, pc or %)")
    width, height = doc.viewport(_describe(doc, element))
    reference = {"x": width, "y": height,
                 "xy": math.hypot(width, height) / math.sqrt(2.0)}[axis]
    return value / 100.0 * reference


def _describe(doc: SvgDocument, element: ET.Element) -> str:
    """Return ``<tag id="...">`` (or ``<tag>``) and its line, to name it in errors."""
    ident = element.get("id")
    name = f'<{element.tag} id="{ident}">' if ident is not None else f"<{element.tag}>"
    line = doc.lines.get(element)
    return name if line is None else f"{name} on line {line}"


def _element_error(doc: SvgDocument, element: ET.Element, message: str) -> ParseError:
    error = ParseError(f"{_describe(doc, element)}: {message}")
    error.line = doc.lines.get(element)
    return error


# --------------------------------------------------------------------------- reading

@dataclass(eq=False)
class SvgDocument:
    """A parsed document: the root element and what surrounds it."""

    root: ET.Element
    declaration: str | None = None
    prolog: list[str] = field(default_factory=list)    # doctype, comments, PIs
    epilog: list[str] = field(default_factory=list)
    lines: dict = field(default_factory=dict)           # element -> its line (1-based)

    def viewport(self, who: str) -> tuple[float, float]:
        """Return the root viewport's size in user units, for percentages."""
        box = _numbers(self.root.get("viewBox", ""))
        if box is not None and len(box) == 4 and box[2] > 0 and box[3] > 0:
            return box[2], box[3]
        size = []
        for name in ("width", "height"):
            match = _LENGTH.fullmatch(self.root.get(name, ""))
            if match is None or match.group(2).lower() not in _UNITS \
                    or not float(match.group(1)) > 0:
                raise UnsupportedGeometryError(
                    f"{who}: a percentage needs the root's viewBox (or its width and "
                    f"height in absolute units) to resolve against")
            size.append(float(match.group(1)) * _UNITS[match.group(2).lower()])
        return size[0], size[1]


class _Reader:
    """Expat handlers that build an ElementTree, refusing entity declarations."""

    def __init__(self) -> None:
        self.parser = parser = expat.ParserCreate()   # no namespace processing
        parser.buffer_text = True
        parser.ordered_attributes = True
        parser.specified_attributes = True              # no defaults from a DTD
        self.builder = ET.TreeBuilder(insert_comments=True, insert_pis=True)
        # What the document will hold besides its root.
        self.declaration: str | None = None
        self.prolog: list[str] = []
        self.epilog: list[str] = []
        self.lines: dict[ET.Element, int] = {}
        self.depth = 0
        parser.StartElementHandler = self.start
        parser.EndElementHandler = self.end
        parser.CharacterDataHandler = self.data
        parser.CommentHandler = self.comment
        parser.ProcessingInstructionHandler = self.pi
        parser.XmlDeclHandler = self.xml_declaration
        parser.StartDoctypeDeclHandler = self.doctype
        parser.EntityDeclHandler = self.entity
        parser.UnparsedEntityDeclHandler = self.entity
        parser.SkippedEntityHandler = self.skipped_entity
        parser.ExternalEntityRefHandler = self.skipped_entity

    def read(self, data: str | bytes) -> SvgDocument:
        try:
            self.parser.Parse(data, True)
        except expat.ExpatError as error:
            raise _xml_error(error.lineno, error.offset,
                             expat.ErrorString(error.code)) from None
        return SvgDocument(self.builder.close(), self.declaration, self.prolog, self.epilog,
                           self.lines)

    def fail(self, message: str) -> ParseError:
        return _xml_error(self.parser.CurrentLineNumber,
                          self.parser.CurrentColumnNumber, message)

    def start(self, name: str, attributes: list[str]) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise self.fail(f"elements nested more than {MAX_NESTING} deep")
        element = self.builder.start(name, dict(zip(attributes[::2], attributes[1::2],
                                                    strict=True)))
        self.lines[element] = self.parser.CurrentLineNumber

    def end(self, name: str) -> None:
        self.depth -= 1
        self.builder.end(name)

    def data(self, text: str) -> None:
        if self.depth:
            self.builder.data(text)

    def comment(self, text: str) -> None:
        if self.depth:
            self.builder.comment(text)
        else:
            self._outside(f"<!--{text}-->")

    def pi(self, target: str, text: str) -> None:
        if self.depth:
            self.builder.pi(target, text)
        else:
            self._outside(f"<?{target} {text}?>" if text else f"<?{target}?>")

    def xml_declaration(self, version: str, encoding: str | None, standalone: int) -> None:
        alone = {1: ' standalone="yes"', 0: ' standalone="no"'}.get(standalone, "")
        self.declaration = f'<?xml version="{version}" encoding="UTF-8"{alone}?>'

    def doctype(self, name: str, system_id: str | None, public_id: str | None,
                has_internal_subset: bool) -> None:
        def quoted(text):
            return f"'{text}'" if '"' in text else f'"{text}"'
        if public_id:
            ids = f" PUBLIC {quoted(public_id)} {quoted(system_id or '')}"
        else:
            ids = f" SYSTEM {quoted(system_id)}" if system_id else ""
        self._outside(f"<!DOCTYPE {name}{ids}>")

    def entity(self, name: str, *_: object) -> NoReturn:
        raise self.fail(f"entity declarations are not accepted (found {name!r}): "
                        f"entities could expand without bound or read external files")

    def skipped_entity(self, name: str, *_: object) -> NoReturn:
        raise self.fail(f"reference to an undeclared entity {name!r}")

    def _outside(self, text: str) -> None:
        (self.epilog if self.lines else self.prolog).append(text)


def read_document(document: str | bytes | bytearray | memoryview) -> SvgDocument:
    """Return the parsed document; ParseError with the line and column if malformed."""
    if isinstance(document, (bytearray, memoryview)):
        document = bytes(document)
    if not isinstance(document, (str, bytes)):
        raise TypeError(f"document must be str or bytes, not {type(document).__name__}")
    return _Reader().read(document)


def _xml_error(line: int, column: int, message: str) -> ParseError:
    """Return a ParseError at 1-based `line` and 0-based `column` (reported 1-based)."""
    error = ParseError(f"SVG document: line {line}, column {column + 1}: {message}")
    error.line, error.column = line, column + 1
    return error


def write_document(doc: SvgDocument) -> str:
    """Return the document as text: declaration, prolog, root, epilog, a line each."""
    parts = [] if doc.declaration is None else [doc.declaration]
    parts += doc.prolog
    parts.append(ET.tostring(doc.root, encoding="unicode"))
    parts += doc.epilog
    return "\n".join(parts) + "\n"
