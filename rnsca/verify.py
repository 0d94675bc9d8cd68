"""Check clipped output against Shapely's exact intersection (the oracle)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import shapely

from rnsca.clip import SegmentClipResult, as_segments
from rnsca.errors import InvalidGeometryError, UnsupportedGeometryError
from rnsca.options import Method, Mode
from rnsca.window import Window

__all__ = ["Verification", "verify", "approx_leaf_bound"]

#: Exact results must lie within this fraction of the window's size of Shapely's.
EXACT_RELATIVE_TOLERANCE = 1e-9
# GEOS computes wrong intersections from about 1e+-110 on; windows up to 2**300 (1e90)
# are compared unscaled.
_LARGEST_UNSCALED_EXPONENT = 300


@dataclass(frozen=True, slots=True)
class Verification:
    """How a clipped result compares with ``shapely.intersection`` on the same input.

    Attributes
    ----------
    max_deviation : float
        Largest Hausdorff distance between an output piece and Shapely's clip of the
        same segment; where only one side has a piece, that piece's length counts.
    false_positives : int
        Output vertices outside the closed window by more than 1e-9 of its size.
    ratio : float
        Total output length over Shapely's (1.0 when both are zero).
    passed : bool
        Whether the result keeps its mode's promise: exact, deviation within
        ``allowed_deviation``; approx, no false positive and every segment within its
        own leaf bound (`allowed_deviation` is then the largest of those bounds).
    allowed_deviation : float
    mode : str
    """

    max_deviation: float
    false_positives: int
    ratio: float
    passed: bool
    allowed_deviation: float
    mode: str

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


def verify(original, clipped: SegmentClipResult, window) -> Verification:
    """Return how `clipped` compares with Shapely's intersection of `original` and `window`.

    Parameters
    ----------
    original : array_like, shape (n, 4) or (n, 2, 2)
        The segments that were clipped.
    clipped : SegmentClipResult
        What `clip_segments` returned for them.
    window : Window or sequence of 4 floats

    Examples
    --------
    >>> from rnsca import clip_segments
    >>> segs = [[-5.0, 5.0, 15.0, 5.0]]
    >>> verify(segs, clip_segments(segs, (0, 0, 10, 10)), (0, 0, 10, 10)).passed
    True
    """
    if not isinstance(clipped, SegmentClipResult):
        raise UnsupportedGeometryError(
            f"verify compares a SegmentClipResult, got {type(clipped).__name__}")
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

    approx = clipped.mode is Mode.APPROX and clipped.method in (Method.RNSCA, Method.MIDPOINT)
    if approx:
        lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
        allowed = 2.0 * approx_leaf_bound(lengths, clipped) + margin
        within = (bool((deviation <= allowed).all())
                  and bool((ours_length <= expected_length + margin).all()))
        allowed_deviation = float(allowed.max()) if n else margin
    else:
        within = bool((deviation <= margin).all())
        allowed_deviation = margin
    max_deviation = float(deviation.max()) if n else 0.0
    return Verification(max_deviation, false_positives, ratio,
                        within and false_positives == 0, allowed_deviation,
                        clipped.mode.value)
