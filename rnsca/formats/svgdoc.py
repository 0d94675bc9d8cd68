"""Clip whole SVG documents: every drawn shape cut to a window, the rest left as it was.

`clip_svg_document` reads a document, turns its drawn shapes into path data, maps each
into the root's user space through the transforms above it, clips them all at once
(one `rnsca.clip_paths` call per way of clipping: strokes, nonzero fills, evenodd
fills), maps the results back into each shape's own coordinates and writes the
document again. Reading and writing keep everything else: elements, attributes in
their order, namespace prefixes as written, text, comments, processing instructions.

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
from dataclasses import dataclass, field
from xml.parsers import expat

import numpy as np

from rnsca.clip_svg import Fill, _resolve, clip_paths
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    ParseError,
    UnsupportedGeometryError,
)
from rnsca.formats.svgpath import PathArrays, parse_paths, write_paths
from rnsca.options import _ChoiceEnum
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["FillMode", "MAX_NESTING", "SVG_NAMESPACE", "clip_svg_document"]

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

# An affine map as SVG writes it, ``matrix(a b c d e f)``: x' = a x + c y + e,
# y' = b x + d y + f.
_IDENTITY = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)


class FillMode(_ChoiceEnum):
    """How each drawn shape of a document is clipped."""

    AUTO = "auto"
    """Per element: as a fill (under its fill-rule) when its fill is not none, else as
    a stroke. A shape both filled and stroked is clipped as a fill."""
    STROKE = "stroke"
    """Every shape as a stroke: outlines cut into open pieces, nothing added."""
    FILL = "fill"
    """Every shape as a fill under its fill-rule (a <line> has no inside: a stroke)."""

    @classmethod
    def _missing_(cls, value):
        choices = ", ".join(repr(m.value) for m in cls)
        if isinstance(value, str):
            for member in cls:
                if member.value == value.lower():
                    return member
        raise InvalidOptionError(f"fill_mode must be one of {choices}, got {value!r}")


def clip_svg_document(document, window, *, curves="preserve", fill_mode="auto",
                      tolerance=None, precision=None, keep_empty=False,
                      **options) -> tuple[str, ClipStats]:
    """Return an SVG document with every drawn shape clipped to a window, and the stats.

    Every ``<path>`` drawn where it stands (in the root or in ``<g>``, ``<a>`` and
    ``<switch>`` containers) is clipped; so are the basic shapes (``<rect>``, rounded
    or not, ``<circle>``, ``<ellipse>``, ``<line>``, ``<polyline>``, ``<polygon>``),
    which become a ``<path>`` with their other attributes (id, class, style, fill,
    stroke, transform...) kept. Everything else is left as it is.

    Parameters
    ----------
    document : str or bytes
        The SVG document. Bytes are decoded as their XML declaration says (UTF-8 by
        default); a str is taken as already decoded.
    window : Window or sequence of 4 floats
        ``(xmin, ymin, xmax, ymax)`` in the root's user space: the coordinates the
        root ``<svg>`` element's children are written in (its ``viewBox`` is not
        applied to them).
    curves : {"preserve", "flatten"}
        As for `rnsca.clip_paths`.
    fill_mode : {"auto", "stroke", "fill"}
        How shapes are clipped (`FillMode`): "auto" per element, from its computed
        ``fill`` (not none: a fill under its ``fill-rule``; none: a stroke).
    tolerance : float, optional
        As for `rnsca.clip_paths`, in root user units (default: 1e-6 of the window's
        longer side); arcs (in path data, circles, ellipses, rounded corners) are read
        as cubics within it too (default: 1e-9 of each arc's radius).
    precision : int or None
        Significant digits of the written path data; None (default) writes each
        number exactly (shortest round-trip form).
    keep_empty : bool
        Keep shapes whose clip is empty as ``<path d="">`` instead of removing them.
    **options
        ``method``, ``n``, ``max_depth``, ``mode``, ``backend``: as for
        `rnsca.clip_paths`.

    Returns
    -------
    (str, ClipStats)
        The document, and the stats of all its clips taken together
        (`ClipStats.combine`): ``geometries_in`` counts the shapes clipped. The text
        starts with an XML declaration (``encoding="UTF-8"``: encode it as UTF-8) when
        the input had one.

    Raises
    ------
    ParseError
        The XML is malformed (``line L, column C``, 1-based, also as the ``line`` and
        ``column`` attributes), declares entities, nests elements deeper than
        `MAX_NESTING`, has no ``<svg>`` root, or a shape's path data, points, lengths
        or transform are malformed (the message names the element, its id and line).
    UnsupportedGeometryError
        A shape's length is in font-relative units (em, ex...), or a percentage with no
        viewBox (nor width and height) on the root to resolve it against.
    InvalidGeometryError
        A coordinate becomes infinite (the element is named).
    InvalidWindowError, InvalidOptionError
        (ValueError) naming the bad value; they are checked before the document is
        read.

    Notes
    -----
    Transforms: each shape is mapped to the root's user space by the ``transform``
    attributes of its ancestors and its own (``matrix``, ``translate``, ``scale``,
    ``rotate(a [cx cy])``, ``skewX``, ``skewY`` and lists of them), clipped there, and
    mapped back by the inverse map: its path data stays in its own coordinates and
    every ``transform`` attribute stays where it was (an affine map takes a Bézier to
    the Bézier of the mapped control points, so curves stay exact). The root's own
    ``transform`` is not applied. A shape under a singular transform (``scale(0)``)
    covers no area; it is left as it is.

    Fill or stroke: ``fill`` and ``fill-rule`` are read from the ``style`` attribute,
    then the presentation attribute, then inherited from the ancestors (the root
    included); the default fill is black, the default rule nonzero. CSS rules in
    ``<style>`` elements, and the ``transform`` and geometry properties in ``style``,
    are not read. A fill clip closes every subpath and adds runs along the window's
    edges, so a shape that is also stroked shows stroke along the cut: use
    ``fill_mode="stroke"`` to keep outlines only. A stroke clip cuts the outline into
    open pieces: markers appear at the new ends, and ``pathLength`` dash scaling
    refers to the old length. The stroke's width is not taken into account: the
    outline, not its painted band, is clipped.

    Output: a shape whose control points all lie in the window is left as it is
    (a ``<rect>`` inside stays a ``<rect>``). A shape whose clip is empty is removed,
    with the whitespace before it (``keep_empty`` keeps it as an empty ``<path>``).
    Shapes that do not render (a ``<rect>`` of zero width, a ``<path>`` without
    ``d``) are left as they are.

    Not clipped, left as they are: ``<use>`` (and what it references inside
    ``<defs>``; a ``<use>`` of a drawn shape shows that shape clipped, in the use's
    coordinates), ``<text>``, ``<image>``, ``<foreignObject>``, nested ``<svg>``
    elements and everything inside ``<defs>``, ``<clipPath>``, ``<mask>``,
    ``<pattern>``, ``<marker>`` and ``<symbol>`` (not drawn where they stand).

    Reading: whitespace between the top-level items before and after the root is not
    kept (each is written on its own line); a DOCTYPE is written back without its
    internal subset; entity declarations are refused, so are references to entities
    other than XML's five.

    Examples
    --------
    >>> text = '''<svg xmlns="http://www.w3.org/2000/svg">
    ...   <rect id="r" x="-5" y="2" width="10" height="4"/>
    ...   <text x="1" y="1">kept</text>
    ... </svg>'''
    >>> out, stats = clip_svg_document(text, (0, 0, 10, 10))
    >>> print(out)
    <svg xmlns="http://www.w3.org/2000/svg">
      <path id="r" d="M0 2H5V6H0V2Z" />
      <text x="1" y="1">kept</text>
    </svg>
    <BLANKLINE>
    >>> stats.geometries_in, stats.geometries_out
    (1, 1)
    """
    window = Window.of(window)
    mode = FillMode(fill_mode)
    curve_options = dict(method="rnsca", n="auto", max_depth=None, mode="exact",
                         backend="numba") | options
    _resolve(window, curves=curves, fill=None, tolerance=tolerance, **curve_options)
    write_paths(PathArrays.empty(), precision=precision)  # checks `precision`
    doc = _read_document(document)
    shapes = _find_shapes(doc, mode)
    groups: dict[Fill | None, list[_Shape]] = {}
    for shape in shapes:
        groups.setdefault(shape.fill, []).append(shape)
    removals: dict[int, tuple[ET.Element, set[int]]] = {}
    stats = [
        _clip_group(doc, group, fill, window, removals, curves=curves, tolerance=tolerance,
                    precision=precision, keep_empty=keep_empty, options=curve_options)
        for fill, group in groups.items()
    ]
    for parent, removed in removals.values():
        _remove_children(parent, removed)
    return _write_document(doc), ClipStats.combine(stats)


# --------------------------------------------------------------------------- clipping

@dataclass(slots=True)
class _Shape:
    """A drawn shape: its element, path data in its own coordinates, how to clip it."""

    element: ET.Element
    parent: ET.Element
    local: str                  # "path", "rect", ...
    d: str
    matrix: tuple[float, ...]   # own coordinates to the root's, (a, b, c, d, e, f)
    fill: Fill | None           # None: a stroke


def _clip_group(doc, shapes: list[_Shape], fill: Fill | None, window: Window,
                removals: dict, *, curves, tolerance, precision, keep_empty,
                options) -> ClipStats:
    """Clip `shapes` (all clipped the same way) in one call; rewrite their elements."""
    matrices = np.array([shape.matrix for shape in shapes], dtype=np.float64)
    identity = bool((matrices == _IDENTITY).all())
    arc_tolerance = tolerance
    if tolerance is not None and not identity:
        # Arcs are read in each shape's own units: the largest stretch of any map
        # turns their error into root units.
        arc_tolerance = float(tolerance) / float(_largest_stretch(matrices).max())
    paths = _parse_shapes(doc, shapes, arc_tolerance)
    root = paths if identity else _named(doc, shapes, _map_paths, paths, matrices)
    result = clip_paths(root, window, curves=curves, fill=fill, tolerance=tolerance,
                        **options)
    clipped = result.paths if identity else \
        _named(doc, shapes, _map_paths, result.paths, _invert(matrices))
    texts = write_paths(clipped, precision=precision)
    inside = _inside(root, window)
    for shape, text, unchanged in zip(shapes, texts, inside.tolist(), strict=True):
        if unchanged:
            continue
        if text or keep_empty:
            _set_path_data(shape, text)
        else:
            removals.setdefault(id(shape.parent), (shape.parent, set()))[1].add(
                id(shape.element))
    return result.stats


def _parse_shapes(doc, shapes: list[_Shape], tolerance) -> PathArrays:
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


def _invert(m: np.ndarray) -> np.ndarray:
    """Return the inverse of each map (n, 6); the caller has excluded singular ones."""
    a, b, c, d, e, f = m.T
    det = a * d - b * c
    return np.stack([d / det, -b / det, -c / det, a / det, (c * f - d * e) / det,
                     (b * e - a * f) / det], axis=1)


def _largest_stretch(m: np.ndarray) -> np.ndarray:
    """Return each map's largest singular value: the most it lengthens a vector."""
    a, b, c, d = m[:, 0], m[:, 1], m[:, 2], m[:, 3]
    s = a * a + b * b + c * c + d * d
    det = a * d - b * c
    return np.sqrt((s + np.sqrt(np.maximum(s * s - 4 * det * det, 0.0))) / 2)


def _inside(paths: PathArrays, window: Window) -> np.ndarray:
    """Return, per path, whether all its control points lie in the window.

    Such a path is its own clip (a Bézier lies in the hull of its control points), so
    its element is left as it was. A path with no points counts as inside.
    """
    c = paths.controls
    segment_low = np.minimum(np.minimum(c[:, 0], c[:, 1]), np.minimum(c[:, 2], c[:, 3]))
    segment_high = np.maximum(np.maximum(c[:, 0], c[:, 1]), np.maximum(c[:, 2], c[:, 3]))
    low = np.minimum(_reduce(np.minimum, segment_low, paths.subpath_offsets, np.inf),
                     paths.start)
    high = np.maximum(_reduce(np.maximum, segment_high, paths.subpath_offsets, -np.inf),
                      paths.start)
    low = _reduce(np.minimum, low, paths.path_offsets, np.inf)
    high = _reduce(np.maximum, high, paths.path_offsets, -np.inf)
    xmin, ymin, xmax, ymax = window.bounds
    return ((low[:, 0] >= xmin) & (low[:, 1] >= ymin)
            & (high[:, 0] <= xmax) & (high[:, 1] <= ymax))


def _reduce(ufunc, values: np.ndarray, offsets: np.ndarray, empty: float) -> np.ndarray:
    """Return `ufunc` reduced over each run ``offsets[i]:offsets[i + 1]`` of `values`.

    Runs are contiguous; an empty run gives `empty`. Only non-empty runs are passed to
    ``reduceat``, so each reduces exactly its own rows.
    """
    counts = np.diff(offsets)
    out = np.full((counts.shape[0],) + values.shape[1:], empty)
    full = counts > 0
    if full.any():
        out[full] = ufunc.reduceat(values, offsets[:-1][full], axis=0)
    return out


def _set_path_data(shape: _Shape, d: str) -> None:
    """Write the clipped path data; a basic shape becomes a <path> in its place."""
    element = shape.element
    if shape.local == "path":
        element.set("d", d)
        return
    geometry = _GEOMETRY[shape.local]
    attributes = {}
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


def _remove_children(parent: ET.Element, removed: set[int]) -> None:
    """Remove the children of `parent` whose ids are in `removed`, and their indents.

    The whitespace before a removed element goes with it: its tail takes the place of
    the text before it, unless that text is not whitespace (mixed content: joined).
    """
    kept = []
    for child in parent:
        if id(child) not in removed:
            kept.append(child)
            continue
        before = kept[-1].tail if kept else parent.text
        after = child.tail
        text = after if not (before or "").strip() else before + (after or "")
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
    fill_rule: Fill
    namespaces: dict


def _find_shapes(doc, mode: FillMode) -> list[_Shape]:
    """Return the drawn shapes of the document, in document order.

    Descends only into containers; shapes that do not render, and shapes under a
    singular transform, are left out (and so left as they are).
    """
    root = doc.root
    namespaces = _declare({"": None}, root)
    local = _svg_name(root.tag, namespaces)
    if local != "svg":
        raise ParseError(f"not an SVG document: the root element is <{root.tag}>, not "
                         f"<svg> (in the SVG namespace {SVG_NAMESPACE} or none)")
    context = _paint(root, _Context(_IDENTITY, True, Fill.NONZERO, namespaces))
    shapes = []
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
        filled = mode is FillMode.FILL or (mode is FillMode.AUTO and inner.filled)
        fill = inner.fill_rule if filled and local != "line" else None
        shapes.append(_Shape(element, parent, local, d, matrix, fill))
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
            fill_rule = Fill.NONZERO
        elif value in ("nonzero", "evenodd"):
            fill_rule = Fill(value)
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

def _transform(doc, element: ET.Element) -> tuple[float, ...]:
    """Return the map of the element's ``transform`` attribute (identity if none).

    Raises ParseError naming the element and the character position for a malformed
    list.
    """
    text = element.get("transform")
    if text is None or not text.strip() or text.strip() == "none":
        return _IDENTITY
    matrix = _IDENTITY
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
    if n == _IDENTITY:
        return m
    if m == _IDENTITY:
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

def _outline(doc, element: ET.Element, local: str) -> str | None:
    """Return the shape's outline as path data (SVG 2's equivalent path).

    None if the shape does not render (zero size, no ``d``, fewer than 2 points).
    """
    if local == "path":
        return element.get("d")

    def length(name: str, axis: str, default: float | None = 0.0) -> float | None:
        return _length(doc, element, name, axis, default)

    if local == "rect":
        return _rect_outline(length)
    if local in ("circle", "ellipse"):
        cx, cy = length("cx", "x"), length("cy", "y")
        if local == "circle":
            rx = ry = length("r", "xy")
        else:
            rx, ry = length("rx", "x", None), length("ry", "y", None)
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


def _rect_outline(length) -> str | None:
    """Return a rectangle's outline; rounded corners as arcs, radii as SVG 2 sets them."""
    x, y = length("x", "x"), length("y", "y")
    w, h = length("width", "x", None), length("height", "y", None)
    if w is None or h is None or not (w > 0 and h > 0):
        return None
    rx, ry = length("rx", "x", None), length("ry", "y", None)
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


def _length(doc, element: ET.Element, name: str, axis: str, default):
    """Return a length attribute in user units (`default` when absent).

    Absolute units convert at 96 per inch; a percentage is of the root viewport's
    width (``axis`` "x"), height ("y") or normalized diagonal ("xy").
    """
    text = element.get(name)
    if text is None:
        return default
    try:   # the common case: a plain number ("1_0", "inf" and "nan" go on below)
        value = float(text)
    except ValueError:
        pass
    else:
        if math.isfinite(value) and "_" not in text:
            return value
    if text.strip() == "auto":
        return default
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


def _describe(doc, element: ET.Element) -> str:
    """Return ``<tag id="...">`` (or ``<tag>``) and its line, to name it in errors."""
    ident = element.get("id")
    name = f'<{element.tag} id="{ident}">' if ident is not None else f"<{element.tag}>"
    line = doc.lines.get(element)
    return name if line is None else f"{name} on line {line}"


def _element_error(doc, element: ET.Element, message: str) -> ParseError:
    error = ParseError(f"{_describe(doc, element)}: {message}")
    error.line = doc.lines.get(element)
    return error


# --------------------------------------------------------------------------- reading

@dataclass(eq=False)
class _Document:
    """A parsed document: the root element and what surrounds it."""

    root: ET.Element | None = None
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
            unit = match.group(2).lower() if match else None
            if unit not in _UNITS or not float(match.group(1)) > 0:
                raise UnsupportedGeometryError(
                    f"{who}: a percentage needs the root's viewBox (or its width and "
                    f"height in absolute units) to resolve against")
            size.append(float(match.group(1)) * _UNITS[unit])
        return size[0], size[1]


class _Reader:
    """Expat handlers that build an ElementTree, refusing entity declarations."""

    def __init__(self) -> None:
        self.parser = parser = expat.ParserCreate()   # no namespace processing
        parser.buffer_text = True
        parser.ordered_attributes = True
        parser.specified_attributes = True              # no defaults from a DTD
        self.builder = ET.TreeBuilder(insert_comments=True, insert_pis=True)
        self.doc = _Document()
        self.depth = 0
        parser.StartElementHandler = self.start
        parser.EndElementHandler = self.end
        parser.CharacterDataHandler = self.data
        parser.CommentHandler = self.comment
        parser.ProcessingInstructionHandler = self.pi
        parser.XmlDeclHandler = self.declaration
        parser.StartDoctypeDeclHandler = self.doctype
        parser.EntityDeclHandler = self.entity
        parser.UnparsedEntityDeclHandler = self.entity
        parser.SkippedEntityHandler = self.skipped_entity
        parser.ExternalEntityRefHandler = self.skipped_entity

    def read(self, data) -> _Document:
        try:
            self.parser.Parse(data, True)
        except expat.ExpatError as error:
            raise _xml_error(error.lineno, error.offset,
                             expat.ErrorString(error.code)) from None
        self.doc.root = self.builder.close()
        return self.doc

    def fail(self, message: str) -> ParseError:
        return _xml_error(self.parser.CurrentLineNumber,
                          self.parser.CurrentColumnNumber, message)

    def start(self, name, attributes) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise self.fail(f"elements nested more than {MAX_NESTING} deep")
        element = self.builder.start(name, dict(zip(attributes[::2], attributes[1::2],
                                                    strict=True)))
        self.doc.lines[element] = self.parser.CurrentLineNumber

    def end(self, name) -> None:
        self.depth -= 1
        self.builder.end(name)

    def data(self, text) -> None:
        if self.depth:
            self.builder.data(text)

    def comment(self, text) -> None:
        if self.depth:
            self.builder.comment(text)
        else:
            self._outside(f"<!--{text}-->")

    def pi(self, target, text) -> None:
        if self.depth:
            self.builder.pi(target, text)
        else:
            self._outside(f"<?{target} {text}?>" if text else f"<?{target}?>")

    def declaration(self, version, encoding, standalone) -> None:
        alone = {1: ' standalone="yes"', 0: ' standalone="no"'}.get(standalone, "")
        self.doc.declaration = f'<?xml version="{version}" encoding="UTF-8"{alone}?>'

    def doctype(self, name, system_id, public_id, has_internal_subset) -> None:
        def quoted(text):
            return f"'{text}'" if '"' in text else f'"{text}"'
        if public_id:
            ids = f" PUBLIC {quoted(public_id)} {quoted(system_id or '')}"
        else:
            ids = f" SYSTEM {quoted(system_id)}" if system_id else ""
        self._outside(f"<!DOCTYPE {name}{ids}>")

    def entity(self, name, *_) -> None:
        raise self.fail(f"entity declarations are not accepted (found {name!r}): "
                        f"entities could expand without bound or read external files")

    def skipped_entity(self, name, *_) -> None:
        raise self.fail(f"reference to an undeclared entity {name!r}")

    def _outside(self, text: str) -> None:
        (self.doc.epilog if self.doc.lines else self.doc.prolog).append(text)


def _read_document(document) -> _Document:
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


def _write_document(doc: _Document) -> str:
    """Return the document as text: declaration, prolog, root, epilog, a line each."""
    parts = [] if doc.declaration is None else [doc.declaration]
    parts += doc.prolog
    parts.append(ET.tostring(doc.root, encoding="unicode"))
    parts += doc.epilog
    return "\n".join(parts) + "\n"
