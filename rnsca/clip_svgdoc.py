"""Clip whole SVG documents: every drawn shape cut to a window, the rest left as it was.

`clip_svg_document` reads a document (`rnsca.io.svgdoc`), maps each drawn shape
into the root's user space through the transforms above it, clips them all at once
(one `rnsca.clip_paths` call per way of clipping: strokes, nonzero fills, evenodd
fills), maps the results back into each shape's own coordinates and writes the
document again.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable
from typing import Any

import numpy as np

from rnsca.arrays import PathArrays
from rnsca.backends.auto import backend_for
from rnsca.backends.base import Operation
from rnsca.clip_svg import clip_paths
from rnsca.errors import InvalidOptionError
from rnsca.io.svgdoc import (
    IDENTITY,
    Shape,
    SvgDocument,
    find_shapes,
    inverse_maps,
    largest_stretch,
    map_shapes,
    parse_shapes,
    read_document,
    remove_children,
    set_path_data,
    write_document,
)
from rnsca.io.svgpath import write_paths
from rnsca.options import Curves, Fill, PathOptions, _ChoiceEnum
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["FillMode", "clip_svg_document"]


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
    def _missing_(cls, value: object) -> FillMode:
        choices = ", ".join(repr(m.value) for m in cls)
        if isinstance(value, str):
            for member in cls:
                if member.value == value.lower():
                    return member
        raise InvalidOptionError(f"fill_mode must be one of {choices}, got {value!r}")


def clip_svg_document(document: str | bytes, window: Window | Iterable[float], *,
                      curves: Curves | str = "preserve", fill_mode: FillMode | str = "auto",
                      tolerance: float | None = None, precision: int | None = None,
                      keep_empty: bool = False, **options: Any) -> tuple[str, ClipStats]:
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
        ``method``, ``n``, ``max_depth``, ``mode``, ``backend``, ``fill_output``: as
        for `rnsca.clip_paths` (``fill_output`` applies to the shapes clipped as fills).

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
      <path id="r" d="M0 2H5V6H0Z" />
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
    backend = curve_options.pop("backend")
    checked = PathOptions.resolve(window, curves=curves, fill=None, tolerance=tolerance,
                                  **curve_options)
    backend_for(backend, "paths", 0).capabilities.require(Operation.PATHS, checked.mode)
    curve_options["backend"] = backend
    write_paths(PathArrays.empty(), precision=precision)  # checks `precision`
    doc = read_document(document)
    groups: dict[Fill | None, list[Shape]] = {}
    for shape in find_shapes(doc):
        filled = mode is FillMode.FILL or (mode is FillMode.AUTO and shape.filled)
        fill = Fill(shape.fill_rule) if filled and shape.local != "line" else None
        groups.setdefault(fill, []).append(shape)
    removals: dict[int, tuple[ET.Element, set[int]]] = {}
    stats = [
        _clip_group(doc, group, fill, window, removals, curves=curves, tolerance=tolerance,
                    precision=precision, keep_empty=keep_empty, options=curve_options)
        for fill, group in groups.items()
    ]
    for parent, removed in removals.values():
        remove_children(parent, removed)
    return write_document(doc), ClipStats.combine(stats)


def _clip_group(doc: SvgDocument, shapes: list[Shape], fill: Fill | None, window: Window,
                removals: dict[int, tuple[ET.Element, set[int]]], *, curves: Curves | str,
                tolerance: float | None, precision: int | None, keep_empty: bool,
                options: dict[str, Any]) -> ClipStats:
    """Clip `shapes` (all clipped the same way) in one call; rewrite their elements."""
    matrices = np.array([shape.matrix for shape in shapes], dtype=np.float64)
    identity = bool((matrices == IDENTITY).all())
    arc_tolerance = tolerance
    if tolerance is not None and not identity:
        # Arcs are read in each shape's own units: the largest stretch of any map
        # turns their error into root units.
        arc_tolerance = float(tolerance) / float(largest_stretch(matrices).max())
    paths = parse_shapes(doc, shapes, arc_tolerance)
    root = paths if identity else map_shapes(doc, shapes, paths, matrices)
    result = clip_paths(root, window, curves=curves, fill=fill, tolerance=tolerance,
                        **options)
    clipped = result.paths if identity else \
        map_shapes(doc, shapes, result.paths, inverse_maps(matrices))
    texts = write_paths(clipped, precision=precision)
    inside = _inside(root, window)
    for shape, text, unchanged in zip(shapes, texts, inside.tolist(), strict=True):
        if unchanged:
            continue
        if text or keep_empty:
            set_path_data(shape, text)
        else:
            removals.setdefault(id(shape.parent), (shape.parent, set()))[1].add(
                id(shape.element))
    return result.stats


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


def _reduce(ufunc: np.ufunc, values: np.ndarray, offsets: np.ndarray, empty: float) -> np.ndarray:
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
