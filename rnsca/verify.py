"""Check clipped output against Shapely's exact intersection (the oracle).

`verify` takes what was clipped and what came out, in any of the forms the library
speaks (segments, Shapely geometries, ragged arrays, GeoJSON), asks Shapely for
``intersection(input, box)`` and says how far apart the two are. Everything is compared
by geometry, never by vertex list, and per dimension: polygons with the polygonal part of
Shapely's answer, lines with its lineal part, points with its points, so a line that only
touches the window (where Shapely returns a point) is expected to give nothing.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import shapely
from shapely.geometry import shape

from rnsca.arrays import Ragged
from rnsca.clip import SegmentClipResult, as_segments
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    ParseError,
    UnsupportedGeometryError,
)
from rnsca.options import Boundary, Method, Mode
from rnsca.ragged import RaggedClipResult, window_table
from rnsca.window import Window

__all__ = ["Verification", "verify", "approx_leaf_bound"]

#: Exact results must lie within this fraction of the window's size of Shapely's.
EXACT_RELATIVE_TOLERANCE = 1e-9
# GEOS computes wrong intersections from about 1e+-110 on; windows up to 2**300 (1e90)
# are compared unscaled.
_LARGEST_UNSCALED_EXPONENT = 300

_POINT, _LINESTRING, _LINEARRING, _POLYGON = (
    int(shapely.GeometryType.POINT), int(shapely.GeometryType.LINESTRING),
    int(shapely.GeometryType.LINEARRING), int(shapely.GeometryType.POLYGON))
_DIMENSION_OF_TYPE = {_POINT: 0, _LINESTRING: 1, _LINEARRING: 1, _POLYGON: 2}
_COLLECT = {0: shapely.multipoints, 1: shapely.multilinestrings, 2: shapely.multipolygons}


@dataclass(frozen=True, slots=True)
class Verification:
    """How a clipped result compares with ``shapely.intersection`` on the same input.

    Attributes
    ----------
    max_deviation : float
        Largest deviation of one input's output from Shapely's clip of that input.
        Segments: the Hausdorff distance between the two pieces. Geometries: the
        Hausdorff distance per dimension (between the boundaries for polygons), taken
        at every vertex of either side and at the points of either line where the
        other side's vertices project and midway between them, so that a gap inside a
        straight stretch is seen too. Where only one side has something, its extent
        counts (a segment's length, the diagonal of a geometry's bounding box, or the
        window's size for a single point).
    false_positives : int
        Output vertices (a ring's closing position not counted twice) outside the
        closed window by more than 1e-9 of its size; a NaN vertex counts too.
    ratio : float
        Output over Shapely's, in total over the input: length for segments and
        lines, area for polygons, count for points (for a mix, the highest dimension
        present in the input); 1.0 when both are zero.
    passed : bool
        Whether the result keeps its mode's promise: exact, deviation within
        ``allowed_deviation`` of every input, valid polygons and no false positive;
        approx, no false positive, valid polygons and deviation within the bound.
    allowed_deviation : float
        Exact: 1e-9 of the window's size (of the largest window, when there is one per
        geometry). Approx: the bound (for segments without one given, the largest of
        the per-segment leaf bounds).
    mode : str
        The promise judged: ``"exact"`` or ``"approx"``.
    valid : bool
        Whether every output polygon is valid (``shapely.is_valid``); True when there
        are none.
    """

    max_deviation: float
    false_positives: int
    ratio: float
    passed: bool
    allowed_deviation: float
    mode: str
    valid: bool = True

    def to_dict(self) -> dict:
        """Return the verification as plain JSON-ready values."""
        return asdict(self)


def approx_leaf_bound(lengths: np.ndarray, result: SegmentClipResult) -> np.ndarray:
    """Return, per segment, the longest leaf approx mode can drop.

    Every split makes at least two pieces (N >= 2), so a piece at level d is at most
    ``L / 2**d`` long (``L / N**d`` for a fixed N); a piece becomes a leaf at
    ``max_depth`` or once it is no longer than `tolerance`. Each end of an approx piece
    is therefore within one leaf of the true end, and a visible part shorter than two
    leaves may vanish, so a segment's deviation is at most twice this bound.
    """
    options = result.options
    base = 2 if options.n == 0 else options.n
    return np.maximum(options.tolerance, lengths / float(base) ** options.max_depth)


def verify(original, clipped, window, *, mode=None, approx_bound=None,
           boundary="closed") -> Verification:
    """Return how `clipped` compares with Shapely's intersection of `original` and `window`.

    Parameters
    ----------
    original
        What was clipped, in the form that matches `clipped`:

        - segments, array_like (n, 4) or (n, 2, 2), for a `SegmentClipResult`;
        - a Shapely geometry, or an array or list of them, for the same kind of
          `clipped` (aligned: one output per input, None or an empty geometry where
          nothing is left);
        - the ``(geometry_type, coords, offsets)`` triple (or a `Ragged`, or a Shapely
          array) for a `RaggedClipResult`, whose ``source`` aligns the two;
        - a GeoJSON dict (Geometry, Feature or FeatureCollection) for a GeoJSON dict.
          Feature collections are aligned feature by feature when `clipped` has as many
          features, or has one for each input feature whose clip is not empty (features
          left empty were dropped); otherwise the two collections are compared whole.
    clipped
        The clip: a `SegmentClipResult`, Shapely geometry or array, `RaggedClipResult`
        or GeoJSON dict. Z values are ignored.
    window : Window, sequence of 4 floats, or array_like (G, 4)
        ``(xmin, ymin, xmax, ymax)``; for geometries also one window per input.
    mode : {"exact", "approx"}, optional
        The promise to judge. Default: the mode a `SegmentClipResult` records, else
        exact.
    approx_bound : float, optional
        Approx mode: the largest deviation to accept. Required for geometries; for
        segments it defaults to twice each segment's leaf bound (`approx_leaf_bound`).
    boundary : {"closed", "interior"}
        The boundary rule the clip followed: closed compares with
        ``shapely.intersection``; interior with ``shapely.clip_by_rect`` for lines and
        points strictly inside for points (polygons: ``intersection`` either way).
        Segments are always closed.

    Returns
    -------
    Verification

    Raises
    ------
    UnsupportedGeometryError
        For a `clipped` of another kind, or an `original` that does not match it.
    InvalidGeometryError
        If `original` has a non-finite coordinate, or is not what was clipped.
    InvalidWindowError, InvalidOptionError
        For a bad window, mode, boundary or bound.

    Notes
    -----
    Shapely (GEOS) loses whole pieces far from 1 (from about 1e+-110 on), so it sees
    tiny and huge windows, with their geometry, scaled by a power of two that brings
    the window's size near 1: exact in floating point, and distances scale back
    exactly. An input polygon that is not valid is compared with the clip of
    ``shapely.make_valid`` of it (GEOS cannot intersect some invalid polygons); the
    output's own validity is reported in ``valid``.

    Examples
    --------
    >>> from rnsca import clip_segments
    >>> segs = [[-5.0, 5.0, 15.0, 5.0]]
    >>> verify(segs, clip_segments(segs, (0, 0, 10, 10)), (0, 0, 10, 10)).passed
    True
    >>> import shapely
    >>> line = shapely.LineString([(-5, 5), (15, 5)])
    >>> v = verify(line, shapely.LineString([(0, 5), (10, 5)]), (0, 0, 10, 10))
    >>> v.passed, v.max_deviation, v.ratio
    (True, 0.0, 1.0)
    >>> verify(line, shapely.LineString([(0, 5), (12, 5)]), (0, 0, 10, 10)).false_positives
    1
    """
    boundary = Boundary(boundary)
    if approx_bound is not None:
        approx_bound = _bound(approx_bound)
    if isinstance(clipped, SegmentClipResult):
        if boundary is not Boundary.CLOSED:
            raise InvalidOptionError("segments are always clipped with boundary='closed'")
        return _verify_segments(original, clipped, window,
                                clipped.mode if mode is None else Mode(mode), approx_bound)
    mode = Mode.EXACT if mode is None else Mode(mode)
    if mode is Mode.APPROX and approx_bound is None:
        raise InvalidOptionError(
            "verify in approx mode needs approx_bound (the largest deviation to accept) "
            "for geometries")
    if isinstance(clipped, dict):
        originals, delivered, source, window = _geojson_pair(original, clipped, window,
                                                             boundary)
    elif isinstance(clipped, RaggedClipResult):
        originals = _ragged_originals(original)
        delivered, source = _ragged_outputs(clipped, originals.shape[0])
    elif clipped is None or _is_geometry_like(clipped):
        originals, delivered = _aligned_geometries(original, clipped)
        source = np.arange(delivered.shape[0])
    else:
        raise UnsupportedGeometryError(
            "verify compares a SegmentClipResult, a RaggedClipResult, Shapely geometries or "
            f"a GeoJSON dict, got {type(clipped).__name__}")
    bounds = _window_bounds(window, originals.shape[0])
    return _verify_geometries(originals, delivered, source, bounds, mode, approx_bound,
                              boundary)


def _bound(value) -> float:
    try:
        bound = float(value)
    except (TypeError, ValueError):
        raise InvalidOptionError(f"approx_bound must be a number, got {value!r}") from None
    if not bound >= 0.0:
        raise InvalidOptionError(f"approx_bound must be >= 0, got {bound}")
    return bound


# --- segments -----------------------------------------------------------------------------

def _unit_scale(window: Window, segments: np.ndarray) -> float:
    """Return the power of two by which Shapely should see the geometry.

    Windows smaller than 1 are scaled up to a size in [0.5, 1) (exact: nothing
    underflows, and subnormal offsets become normal numbers GEOS handles). Windows from
    1 to 2**300 are left alone. Larger ones are scaled down the same way (there,
    coordinates below 2**-1074 of the new unit flush to zero, which is why it is not
    done where it is not needed). The scale is made smaller if needed so that no scaled
    coordinate exceeds about 2**1000.
    """
    exponent = math.frexp(window.size)[1]
    if 0 < exponent <= _LARGEST_UNSCALED_EXPONENT:
        return 1.0
    largest = max(float(np.abs(segments).max(initial=0.0)), *map(abs, window.bounds))
    exponent = max(exponent, math.frexp(largest)[1] - 1000)
    return math.ldexp(1.0, -exponent)


def _verify_segments(original, clipped: SegmentClipResult, window, mode: Mode,
                     approx_bound: float | None) -> Verification:
    window = Window.of(window)
    segments = as_segments(original)
    n = segments.shape[0]
    size = window.size
    if clipped.stats.segments_in != n or (len(clipped) and clipped.source.max() >= n):
        raise InvalidGeometryError(
            f"verify needs the {clipped.stats.segments_in} segments that were clipped, "
            f"got {n}")

    # GEOS loses whole pieces to overflow or underflow far from 1 (from about 1e+-110 on),
    # so Shapely sees tiny and huge windows scaled by a power of two that brings their
    # size near 1: exact in floating point, and distances scale back exactly.
    scale = _unit_scale(window, segments)
    scaled = segments * scale
    ours_length = np.zeros(n)
    ours = np.full(n, None, dtype=object)
    if len(clipped):
        pieces = clipped.segments * scale
        ours[clipped.source] = shapely.linestrings(pieces.reshape(-1, 2, 2))
        ours_length[clipped.source] = np.hypot(pieces[:, 2] - pieces[:, 0],
                                               pieces[:, 3] - pieces[:, 1])

    lines = shapely.linestrings(scaled.reshape(-1, 2, 2))
    box = shapely.box(*(bound * scale for bound in window.bounds))
    expected = shapely.intersection(lines, box)
    # Keep the input's dimension: a point where a segment touches the window is no piece.
    is_line = shapely.get_type_id(expected) == shapely.GeometryType.LINESTRING
    expected = np.where(is_line & ~shapely.is_empty(expected), expected, None)
    # Shapely returns nothing for a zero-length segment; inside the window it is kept.
    zero = (segments[:, 0] == segments[:, 2]) & (segments[:, 1] == segments[:, 3])
    inside_point = ((segments[:, 0] >= window.xmin) & (segments[:, 0] <= window.xmax)
                    & (segments[:, 1] >= window.ymin) & (segments[:, 1] <= window.ymax))
    expected[zero & inside_point] = lines[zero & inside_point]
    expected_length = np.where(expected == None, 0.0, shapely.length(expected))  # noqa: E711

    has_ours = ours != None  # noqa: E711
    has_expected = expected != None  # noqa: E711
    deviation = np.zeros(n)
    both = has_ours & has_expected
    if both.any():
        deviation[both] = shapely.hausdorff_distance(ours[both], expected[both])
    deviation[has_ours & ~has_expected] = ours_length[has_ours & ~has_expected]
    deviation[~has_ours & has_expected] = expected_length[~has_ours & has_expected]
    total_expected = float(expected_length.sum())
    total_ours = float(ours_length.sum())
    ratio = 1.0 if total_expected == 0.0 and total_ours == 0.0 else (
        total_ours / total_expected if total_expected > 0 else float("inf"))
    # Back to the caller's units (dividing by a power of two is exact).
    deviation /= scale
    ours_length /= scale
    expected_length /= scale

    margin = EXACT_RELATIVE_TOLERANCE * size
    if len(clipped):
        xs = clipped.segments[:, 0::2]
        ys = clipped.segments[:, 1::2]
        outside = ((xs < window.xmin - margin) | (xs > window.xmax + margin)
                   | (ys < window.ymin - margin) | (ys > window.ymax + margin))
        false_positives = int(outside.sum())
    else:
        false_positives = 0

    if mode is Mode.APPROX and approx_bound is not None:
        within = bool((deviation <= approx_bound).all())
        allowed_deviation = approx_bound
    elif mode is Mode.APPROX and clipped.method in (Method.RNSCA, Method.MIDPOINT):
        lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
        allowed = 2.0 * approx_leaf_bound(lengths, clipped) + margin
        within = (bool((deviation <= allowed).all())
                  and bool((ours_length <= expected_length + margin).all()))
        allowed_deviation = float(allowed.max()) if n else margin
    else:
        # Exact, or approx by an analytic method (which always clips exactly).
        within = bool((deviation <= margin).all())
        allowed_deviation = margin
    max_deviation = float(deviation.max()) if n else 0.0
    return Verification(max_deviation, false_positives, ratio,
                        within and false_positives == 0, allowed_deviation, mode.value)


# --- inputs of every form: original geometries, delivered output, input index of each ---------

def _is_geometry_like(value) -> bool:
    if isinstance(value, shapely.Geometry):
        return True
    if isinstance(value, (list, tuple)):
        return all(item is None or isinstance(item, shapely.Geometry) for item in value)
    if isinstance(value, np.ndarray) and value.dtype == object:
        items = value.ravel()
        return bool((shapely.is_geometry(items) | (items == None)).all())  # noqa: E711
    return False


def _geometry_array(value, name: str) -> np.ndarray:
    """Return `value` (a geometry or a sequence of them) as a 1-d object array."""
    if isinstance(value, shapely.Geometry):
        return np.array([value], dtype=object)
    if not _is_geometry_like(value):
        raise UnsupportedGeometryError(
            f"{name} must be a Shapely geometry or an array of them, "
            f"got {type(value).__name__}")
    array = np.asarray(value, dtype=object)
    if array.ndim != 1:
        raise UnsupportedGeometryError(f"{name} must be 1-d, got shape {array.shape}")
    return array


def _aligned_geometries(original, clipped) -> tuple[np.ndarray, np.ndarray]:
    originals = _geometry_array(original, "original")
    outputs = _geometry_array([None] if clipped is None else clipped, "clipped")
    if originals.shape != outputs.shape:
        raise InvalidGeometryError(
            f"verify needs one clipped geometry per original (None or empty where nothing "
            f"is left): got {originals.shape[0]} originals and {outputs.shape[0]} outputs")
    return originals, outputs


def _ragged_originals(original) -> np.ndarray:
    if isinstance(original, Ragged):
        return original.to_shapely()
    if _is_geometry_like(original):
        return _geometry_array(original, "original")
    if isinstance(original, (tuple, list)) and len(original) == 3:
        return Ragged.of(*original).to_shapely()
    raise UnsupportedGeometryError(
        "a RaggedClipResult is compared with the (geometry_type, coords, offsets) triple "
        f"that was clipped, a Ragged or Shapely geometries, got {type(original).__name__}")


def _ragged_outputs(result, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the output geometries of a ragged result and the input index of each."""
    stats_count = getattr(result.stats, "geometries_in", count)
    source = np.asarray(result.source, dtype=np.int64)
    if stats_count != count or (source.size and (source.min() < 0 or source.max() >= count)):
        raise InvalidGeometryError(
            f"verify needs the {stats_count} geometries that were clipped, got {count}")
    geometries = shapely.from_ragged_array(result.geometry_type, result.coords, result.offsets)
    return geometries, source


def _geojson_geometries(obj, name: str) -> tuple[np.ndarray, bool]:
    """Return the geometries of a GeoJSON dict and whether it is a FeatureCollection."""
    if not isinstance(obj, dict):
        raise UnsupportedGeometryError(
            f"a GeoJSON clip is compared with the GeoJSON that was clipped; {name} is a "
            f"{type(obj).__name__}")
    kind = obj.get("type")
    if kind == "FeatureCollection":
        features = obj.get("features")
        if not isinstance(features, list):
            raise ParseError(f"{name}.features must be a list")
        items = [_feature_geometry(feature, f"{name}.features[{i}]")
                 for i, feature in enumerate(features)]
    elif kind == "Feature":
        items = [_feature_geometry(obj, name)]
    else:
        items = [_shape(obj, name)]
    array = np.empty(len(items), dtype=object)
    array[:] = items
    return array, kind == "FeatureCollection"


def _feature_geometry(feature, path: str):
    if not isinstance(feature, dict) or "geometry" not in feature:
        raise ParseError(f"{path} must be a Feature with a geometry member")
    return _shape(feature["geometry"], f"{path}.geometry")


def _shape(geometry, path: str):
    if geometry is None:
        return None
    try:
        return shape(geometry)
    except (KeyError, TypeError, ValueError, AttributeError, IndexError,
            shapely.errors.GEOSException) as exc:
        raise ParseError(f"{path} is not a GeoJSON geometry: {exc}") from None


def _geojson_pair(original, clipped, window, boundary: Boundary):
    """Return original and clipped geometries of two GeoJSON dicts, aligned, and the window.

    Features are matched one to one when there are as many on both sides, else with the
    originals whose clip is not empty (what ``keep_empty=False`` keeps); failing both,
    the collections are compared whole, as one input in one window.
    """
    originals, is_collection = _geojson_geometries(original, "original")
    outputs, _ = _geojson_geometries(clipped, "clipped")
    if outputs.shape == originals.shape:
        return originals, outputs, np.arange(outputs.shape[0]), window
    if is_collection:
        kept = np.flatnonzero(
            _clip_is_not_empty(originals, _window_bounds(window, originals.shape[0]),
                               boundary))
        if kept.shape == outputs.shape:
            return originals, outputs, kept, window
    if not isinstance(window, Window) and np.ndim(window) == 2:
        raise InvalidGeometryError(
            f"verify cannot match {outputs.shape[0]} clipped features with "
            f"{originals.shape[0]} originals, and one window per feature needs them matched")
    whole = np.empty(1, dtype=object)
    whole[0] = shapely.geometrycollections([g for g in originals if g is not None])
    return whole, outputs, np.zeros(outputs.shape[0], dtype=np.int64), window


def _window_bounds(window, count: int) -> np.ndarray:
    """Return (count, 4) validated window bounds, one row per input."""
    windows, index = window_table(window, count)
    return windows[index]


# --- the comparison ---------------------------------------------------------------------------

def _verify_geometries(originals, delivered, source, bounds, mode: Mode, approx_bound,
                       boundary: Boundary) -> Verification:
    """Return the verification of `delivered` geometries, each the clip of input `source`."""
    originals = shapely.force_2d(originals)
    delivered = shapely.force_2d(delivered)
    _check_finite(originals)
    count = originals.shape[0]
    sizes = np.maximum(bounds[:, 2] - bounds[:, 0], bounds[:, 3] - bounds[:, 1])
    margins = EXACT_RELATIVE_TOLERANCE * sizes

    # Shapely sees tiny and huge windows scaled by a power of two (see `_unit_scale`).
    scales = _unit_scales(bounds, originals, delivered, source)
    scaled_bounds = bounds * scales[:, None]
    input_parts, input_index = _atomic_parts(_scaled(originals, scales))
    output_parts, output_piece = _atomic_parts(_scaled(delivered, scales[source]))
    output_index = source[output_piece]
    false_positives = _count_outside(_atomic_parts(delivered), source, bounds, margins)
    valid = _polygons_valid(output_parts, output_piece)
    input_dims = _dimensions(input_parts)
    output_dims = _dimensions(output_parts)

    deviation = np.zeros(count)
    measures = {}
    for dim in (0, 1, 2):
        expected, expected_index = _expected_parts(
            input_parts[input_dims == dim], input_index[input_dims == dim], scaled_bounds,
            dim, boundary)
        ours, ours_index = _grouped(output_parts[output_dims == dim],
                                    output_index[output_dims == dim])
        if not (expected.size or ours.size):
            continue
        a = _collect(ours, ours_index, count, dim)
        b = _collect(expected, expected_index, count, dim)
        # np.maximum keeps a NaN (from a NaN output vertex): it must not pass.
        deviation = np.maximum(deviation, _deviation(a, b, dim, sizes * scales))
        measures[dim] = (_measure(ours, ours_index, dim, count),
                         _measure(expected, expected_index, dim, count))
    deviation = deviation / scales

    dims = input_dims if input_dims.size else output_dims
    ratio = _ratio(measures.get(int(dims.max())) if dims.size else None, scales,
                   int(dims.max()) if dims.size else 0)
    if mode is Mode.APPROX:
        allowed_deviation = approx_bound
        within = bool((deviation <= approx_bound).all())
    else:
        allowed_deviation = float(margins.max()) if count else 0.0
        within = bool((deviation <= margins).all())
    max_deviation = float(np.max(deviation)) if count else 0.0
    return Verification(max_deviation, false_positives, ratio,
                        within and valid and false_positives == 0, allowed_deviation,
                        mode.value, valid)


def _check_finite(geometries: np.ndarray) -> None:
    coords, index = shapely.get_coordinates(geometries, return_index=True)
    bad = ~np.isfinite(coords).all(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        raise InvalidGeometryError(
            f"original geometry {int(index[row])} has a non-finite coordinate: "
            f"{coords[row].tolist()}")


def _unit_scales(bounds: np.ndarray, originals, delivered, source) -> np.ndarray:
    """Return, per input, the power of two by which Shapely should see it.

    The rule of `_unit_scale`: windows from 1 to 2**300 are left alone, smaller and
    larger ones scaled to a size in [0.5, 1), less if a coordinate would exceed 2**1000.
    """
    sizes = np.maximum(bounds[:, 2] - bounds[:, 0], bounds[:, 3] - bounds[:, 1])
    exponents = np.frexp(sizes)[1].astype(np.int64)
    scaled = (exponents <= 0) | (exponents > _LARGEST_UNSCALED_EXPONENT)
    scales = np.ones(bounds.shape[0])
    if scaled.any():
        with np.errstate(invalid="ignore"):
            largest = np.abs(bounds).max(axis=1)
            for geoms, owner in ((originals, np.arange(bounds.shape[0])), (delivered, source)):
                extent = np.nan_to_num(np.abs(shapely.bounds(geoms)), nan=0.0, posinf=0.0)
                np.maximum.at(largest, owner, extent.max(axis=1, initial=0.0))
        exponents = np.maximum(exponents, np.frexp(largest)[1] - 1000)
        scales[scaled] = np.ldexp(1.0, -exponents[scaled])
    return scales


def _scaled(geometries: np.ndarray, scales: np.ndarray) -> np.ndarray:
    if (scales == 1.0).all():
        return geometries
    coords, index = shapely.get_coordinates(geometries, return_index=True)
    return shapely.set_coordinates(geometries.copy(), coords * scales[index, None])


def _atomic_parts(geometries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the non-empty points, lines and polygons of each geometry, with its index.

    Multi-part geometries and collections (nested too) are taken apart; linear rings
    become line strings. Parts come grouped by geometry index, in increasing order.
    """
    parts = np.asarray(geometries, dtype=object)
    index = np.arange(parts.shape[0])
    while True:
        nested = shapely.get_type_id(parts) >= int(shapely.GeometryType.MULTIPOINT)
        if not nested.any():
            break
        inner, inner_index = shapely.get_parts(parts[nested], return_index=True)
        parts = np.concatenate([parts[~nested], inner])
        index = np.concatenate([index[~nested], index[nested][inner_index]])
    keep = (parts != None) & ~shapely.is_empty(parts)  # noqa: E711
    parts, index = parts[keep], index[keep]
    rings = shapely.get_type_id(parts) == _LINEARRING
    if rings.any():
        coords, ring = shapely.get_coordinates(parts[rings], return_index=True)
        parts[rings] = shapely.linestrings(coords, indices=ring)
    order = np.argsort(index, kind="stable")
    return parts[order], index[order]


def _grouped(parts: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(index, kind="stable")
    return parts[order], index[order]


def _dimensions(parts: np.ndarray) -> np.ndarray:
    types = shapely.get_type_id(parts)
    dims = np.full(types.shape, -1)
    for type_id, dim in _DIMENSION_OF_TYPE.items():
        dims[types == type_id] = dim
    return dims


def _expected_parts(parts, index, bounds: np.ndarray, dim: int, boundary: Boundary):
    """Return Shapely's clip of input parts of one dimension, keeping that dimension."""
    if not parts.size:
        return parts, index
    xmin, ymin, xmax, ymax = bounds[index].T
    if dim == 0:
        xy = shapely.get_coordinates(parts)
        x, y = xy[:, 0], xy[:, 1]
        if boundary is Boundary.CLOSED:
            inside = (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)
        else:
            inside = (x > xmin) & (x < xmax) & (y > ymin) & (y < ymax)
        return parts[inside], index[inside]
    if dim == 2:
        # GEOS cannot intersect some invalid polygons; their oracle is the valid reading.
        invalid = ~shapely.is_valid(parts)
        if invalid.any():
            parts = parts.copy()
            parts[invalid] = shapely.make_valid(parts[invalid])
    if dim == 1 and boundary is Boundary.INTERIOR:
        # clip_by_rect takes one rectangle per call.
        clipped = np.empty(parts.shape[0], dtype=object)
        clipped[:] = [shapely.clip_by_rect(part, *rect)
                      for part, rect in zip(parts, bounds[index], strict=True)]
    else:
        clipped = shapely.intersection(parts, shapely.box(xmin, ymin, xmax, ymax))
    pieces, piece_index = _atomic_parts(clipped)
    keep = _dimensions(pieces) == dim
    return _grouped(pieces[keep], index[piece_index[keep]])


def _collect(parts, index, count: int, dim: int) -> np.ndarray:
    """Return one multi-geometry per input (None where it has no part); `index` sorted."""
    out = np.full(count, None, dtype=object)
    if parts.size:
        _COLLECT[dim](parts, indices=index, out=out)
    return out


def _measure(parts, index, dim: int, count: int) -> np.ndarray:
    """Return per input the count (points), length (lines) or area (polygons) of its parts."""
    if dim == 0:
        weights = np.ones(parts.shape[0])
    else:
        weights = shapely.length(parts) if dim == 1 else shapely.area(parts)
    return np.bincount(index, weights=weights, minlength=count)


def _polygons_valid(parts: np.ndarray, piece: np.ndarray) -> bool:
    """Return whether the polygons of each delivered geometry form a valid (multi)polygon."""
    polygons = _dimensions(parts) == 2
    if not polygons.any():
        return True
    collected = shapely.multipolygons(parts[polygons], indices=piece[polygons],
                                      out=np.full(int(piece.max()) + 1, None, dtype=object))
    return bool(shapely.is_valid(collected[collected != None]).all())  # noqa: E711


def _deviation(a: np.ndarray, b: np.ndarray, dim: int, sizes: np.ndarray) -> np.ndarray:
    """Return, per input, the deviation between our parts `a` and Shapely's `b`."""
    has_a = a != None  # noqa: E711
    has_b = b != None  # noqa: E711
    deviation = np.zeros(a.shape[0])
    both = has_a & has_b
    if both.any():
        if dim == 0:
            deviation[both] = shapely.hausdorff_distance(a[both], b[both])
        elif dim == 1:
            deviation[both] = _lineal_hausdorff(a[both], b[both])
        else:
            deviation[both] = _lineal_hausdorff(shapely.boundary(a[both]),
                                                shapely.boundary(b[both]))
    alone = has_a ^ has_b
    if alone.any():
        box = shapely.bounds(np.where(has_a, a, b)[alone])
        extent = np.hypot(box[:, 2] - box[:, 0], box[:, 3] - box[:, 1])
        deviation[alone] = np.where(extent > 0, extent, sizes[alone])
    return deviation


def _positions(lines: np.ndarray):
    """Return the vertices of (multi)line strings, their line index and distance along it.

    The distance runs along the parts in order, as ``shapely.line_locate_point`` and
    ``line_interpolate_point`` measure it on a MultiLineString.
    """
    parts, part_line = shapely.get_parts(lines, return_index=True)
    coords, part = shapely.get_coordinates(parts, return_index=True)
    step = np.zeros(coords.shape[0])
    if coords.shape[0] > 1:
        same = part[1:] == part[:-1]
        step[1:] = np.where(same, np.hypot(*(coords[1:] - coords[:-1]).T), 0.0)
    line = part_line[part]
    along = np.cumsum(step)
    first = np.ones(line.shape[0], dtype=bool)
    first[1:] = line[1:] != line[:-1]
    along -= np.maximum.accumulate(np.where(first, along, 0.0))
    return coords, line, along


def _lineal_hausdorff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the Hausdorff distance between aligned (multi)line strings `a` and `b`.

    GEOS's discrete Hausdorff distance measures only from vertices, so it misses a gap
    inside a straight stretch (two pieces with a hole between them against one piece:
    every vertex of each lies on the other). Here each side is also sampled where the
    other side's vertices project onto it and midway between consecutive such points,
    which finds such a gap's middle exactly. Cost: vertices of one side times segments
    of the other, per input.
    """
    deviation = np.zeros(a.shape[0])
    for source, target in ((a, b), (b, a)):
        coords, line, _ = _positions(source)
        points = shapely.points(coords)
        np.maximum.at(deviation, line, shapely.distance(points, target[line]))
        _, target_line, target_along = _positions(target)
        along = np.concatenate([target_along, shapely.line_locate_point(target[line], points)])
        owner = np.concatenate([target_line, line])
        order = np.lexsort((along, owner))
        along, owner = along[order], owner[order]
        between = (owner[1:] == owner[:-1]) & (along[1:] > along[:-1])
        if between.any():
            middle = 0.5 * (along[1:] + along[:-1])[between]
            holder = owner[1:][between]
            samples = shapely.line_interpolate_point(target[holder], middle)
            np.maximum.at(deviation, holder, shapely.distance(samples, source[holder]))
    return deviation


def _count_outside(parts_and_piece, source: np.ndarray, bounds: np.ndarray,
                   margins: np.ndarray) -> int:
    """Return how many output vertices lie outside their window by more than the margin."""
    parts, piece = parts_and_piece
    index = source[piece]
    polygons = shapely.get_type_id(parts) == _POLYGON
    coords, owner = shapely.get_coordinates(parts[~polygons], return_index=True)
    owner = index[~polygons][owner]
    if polygons.any():
        rings, ring_polygon = shapely.get_rings(parts[polygons], return_index=True)
        ring_coords, ring = shapely.get_coordinates(rings, return_index=True)
        # A ring's last position repeats its first.
        last = np.ones(ring.shape[0], dtype=bool)
        last[:-1] = ring[1:] != ring[:-1]
        coords = np.concatenate([coords, ring_coords[~last]])
        owner = np.concatenate([owner, index[polygons][ring_polygon[ring[~last]]]])
    x, y = coords[:, 0], coords[:, 1]
    margin = margins[owner]
    xmin, ymin, xmax, ymax = bounds[owner].T
    inside = ((x >= xmin - margin) & (x <= xmax + margin)
              & (y >= ymin - margin) & (y <= ymax + margin))
    return int((~inside).sum())


def _ratio(measures, scales: np.ndarray, dim: int) -> float:
    """Return the total of our measure over Shapely's, in common units."""
    if measures is None:
        return 1.0
    ours, expected = measures
    # Bring every input to the units of the most scaled-down one (no overflow at 1e300).
    unit = (scales.min() / scales) ** dim
    total_ours = float((ours * unit).sum())
    total_expected = float((expected * unit).sum())
    if total_expected == 0.0:
        return 1.0 if total_ours == 0.0 else float("inf")
    return total_ours / total_expected


def _clip_is_not_empty(originals, bounds: np.ndarray, boundary: Boundary) -> np.ndarray:
    """Return, per input, whether Shapely's clip keeps something of the input's dimension."""
    originals = shapely.force_2d(originals)
    _check_finite(originals)
    count = originals.shape[0]
    scales = _unit_scales(bounds, originals, np.empty(0, dtype=object),
                          np.empty(0, dtype=np.int64))
    parts, index = _atomic_parts(_scaled(originals, scales))
    dims = _dimensions(parts)
    kept = np.zeros(count, dtype=bool)
    for dim in (0, 1, 2):
        _, expected_index = _expected_parts(parts[dims == dim], index[dims == dim],
                                            bounds * scales[:, None], dim, boundary)
        kept[expected_index] = True
    return kept
