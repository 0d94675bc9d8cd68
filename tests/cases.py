"""Named adversarial segments with their literal expected piece, shared by the tests.

At the end, a GeoJSON document mixing 2D and 3D positions and what clipping it gives.

Each `Case` is one segment, a window and what every method must return for it in exact
mode: the one piece ``[x0, y0, x1, y1]`` (in the segment's own direction), or ``None``
when the segment yields no piece. The expected pieces were worked out by hand, or, for
the sloped long and far-away segments, by exact rational arithmetic on the float inputs
(then rounded to the nearest float); see `exact_clip`.

The boundary rules they pin down (issue text, same for every method):

- the window is closed: a segment lying on an edge is inside;
- a segment that only touches the window at one point yields no piece;
- a zero-length segment inside (boundary included) is kept, one outside is not;
- no output coordinate lies outside the window.

A case says nothing about approx mode directly: there a subdivision method may shorten a
piece at each boundary crossing by up to one leaf (see `rnsca.verify.approx_leaf_bound`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

#: The window most cases use.
W10 = (0.0, 0.0, 10.0, 10.0)
UNIT = (0.0, 0.0, 1.0, 1.0)
HUGE = (-1e300, -1e300, 1e300, 1e300)
TINY = (0.0, 0.0, 1e-300, 1e-300)
SUBNORMAL = (0.0, 0.0, 1e-310, 1e-310)
MILLI = (0.0, 0.0, 1e-3, 1e-3)
FAR = (1e6, 1e6, 1e6 + 1.0, 1e6 + 1.0)

#: The smallest positive float (a subnormal): one ulp off an edge at 0.
ULP0 = float(np.nextafter(0.0, 1.0))


@dataclass(frozen=True)
class Case:
    """One segment, its window, and the exact-mode piece every method must return."""

    name: str
    window: tuple[float, float, float, float]
    segment: tuple[float, float, float, float]
    expected: tuple[float, float, float, float] | None
    note: str = ""

    @property
    def size(self) -> float:
        """Return the window's longer side, the scale tolerances are relative to."""
        xmin, ymin, xmax, ymax = self.window
        return max(xmax - xmin, ymax - ymin)

    @property
    def trivial(self) -> bool:
        """Return whether both ends are inside, or beyond one edge: decided with no cut."""
        xmin, ymin, xmax, ymax = self.window
        x0, y0, x1, y1 = self.segment

        def code(x, y):
            return ((x < xmin) * 1) | ((x > xmax) * 2) | ((y < ymin) * 4) | ((y > ymax) * 8)

        c0, c1 = code(x0, y0), code(x1, y1)
        return (c0 | c1) == 0 or (c0 & c1) != 0


def exact_clip(segment, window):
    """Return the clip of `segment` by `window` in exact rational arithmetic.

    Returns ``(piece, (t0, t1))`` rounded to floats, or None when no piece remains (an
    empty intersection or a single point). Used to derive the literals below and by
    tests that need an exact reference at magnitudes Shapely cannot handle.
    """
    x0, y0, x1, y1 = (Fraction(v) for v in segment)
    xmin, ymin, xmax, ymax = (Fraction(v) for v in window)
    dx, dy = x1 - x0, y1 - y0
    if dx == 0 and dy == 0:
        inside = xmin <= x0 <= xmax and ymin <= y0 <= ymax
        return ((float(x0), float(y0), float(x1), float(y1)), (0.0, 1.0)) if inside else None
    u0, u1 = Fraction(0), Fraction(1)
    for p, q in ((-dx, x0 - xmin), (dx, xmax - x0), (-dy, y0 - ymin), (dy, ymax - y0)):
        if p == 0:
            if q < 0:
                return None
            continue
        r = q / p
        if p < 0:
            u0 = max(u0, r)
        else:
            u1 = min(u1, r)
    if u0 >= u1:
        return None
    piece = (x0 + u0 * dx, y0 + u0 * dy, x0 + u1 * dx, y0 + u1 * dy)
    return tuple(float(v) for v in piece), (float(u0), float(u1))


CASES: dict[str, Case] = {}


def _case(name, window, segment, expected, note=""):
    case = Case(name, window, tuple(float(v) for v in segment),
                None if expected is None else tuple(float(v) for v in expected), note)
    CASES[name] = case
    return case


# --- inside, outside, crossing -----------------------------------------------------------
INSIDE = _case("inside", W10, (2, 3, 7, 8), (2, 3, 7, 8))
CROSSING_LEFT_TO_RIGHT = _case("crossing_left_to_right", W10, (-5, 5, 15, 5), (0, 5, 10, 5))
CROSSING_RIGHT_TO_LEFT = _case("crossing_right_to_left", W10, (15, 5, -5, 5), (10, 5, 0, 5),
                               "the piece keeps the segment's direction")
VERTICAL_CROSSING_UPWARD = _case("vertical_crossing_upward", W10, (5, -5, 5, 15), (5, 0, 5, 10))
VERTICAL_CROSSING_DOWNWARD = _case("vertical_crossing_downward", W10, (5, 15, 5, -5),
                                   (5, 10, 5, 0))
HORIZONTAL_LEAVING_RIGHT = _case("horizontal_leaving_right", W10, (5, 5, 20, 5), (5, 5, 10, 5))
SLOPED_LEAVING_RIGHT = _case("sloped_leaving_right", W10, (5, 5, 15, 10), (5, 5, 10, 7.5))
ENTERING_LEFT_LEAVING_TOP = _case("entering_left_leaving_top", W10, (-2, 6, 6, 14),
                                  (0, 8, 2, 10))
CUTTING_TOP_RIGHT_CORNER = _case("cutting_top_right_corner", W10, (7, 12, 12, 7), (9, 10, 10, 9))
OUTSIDE_LEFT = _case("outside_left", W10, (-5, 1, -1, 9), None)
MISSING_TOP_LEFT_CORNER = _case("missing_top_left_corner", W10, (-5, 8, 3, 16), None,
                                "ends beyond different edges, line passes outside the corner")

# --- on the boundary -----------------------------------------------------------------------
ALONG_TOP_EDGE = _case("along_top_edge", W10, (0, 10, 10, 10), (0, 10, 10, 10))
ALONG_BOTTOM_EDGE_BEYOND_BOTH_ENDS = _case("along_bottom_edge_beyond_both_ends", W10,
                                           (-5, 0, 15, 0), (0, 0, 10, 0))
ALONG_LEFT_EDGE_PARTLY = _case("along_left_edge_partly", W10, (0, -5, 0, 5), (0, 0, 0, 5))
ALONG_RIGHT_EDGE_DOWNWARD = _case("along_right_edge_downward", W10, (10, 12, 10, 3),
                                  (10, 10, 10, 3))
ON_EDGE_LINE_BEYOND_CORNER = _case("on_edge_line_beyond_corner", W10, (12, 0, 20, 0), None)
ON_EDGE_LINE_TOUCHING_CORNER = _case("on_edge_line_touching_corner", W10, (10, 0, 20, 0), None,
                                     "shares only the corner (10, 0) with the window")
THROUGH_TWO_CORNERS = _case("through_two_corners", W10, (-5, -5, 15, 15), (0, 0, 10, 10))
THROUGH_THE_OTHER_TWO_CORNERS = _case("through_the_other_two_corners", W10, (-5, 15, 15, -5),
                                      (0, 10, 10, 0))
TOUCHING_BOTTOM_LEFT_CORNER = _case("touching_bottom_left_corner", W10, (-1, 1, 1, -1), None)
TOUCHING_TOP_RIGHT_CORNER = _case("touching_top_right_corner", W10, (9, 11, 11, 9), None)
ENDING_AT_CORNER_FROM_OUTSIDE = _case("ending_at_corner_from_outside", W10, (-5, -5, 0, 0), None)
ENDING_ON_EDGE_FROM_OUTSIDE = _case("ending_on_edge_from_outside", W10, (-5, 5, 0, 5), None)
STARTING_ON_EDGE_GOING_OUT = _case("starting_on_edge_going_out", W10, (10, 5, 15, 5), None)
STARTING_ON_EDGE_GOING_IN = _case("starting_on_edge_going_in", W10, (0, 5, 5, 5), (0, 5, 5, 5))
ENDING_ON_TOP_EDGE_FROM_ABOVE = _case(
    "ending_on_top_edge_from_above", UNIT, (-3.0, 2.0, 0.1, 1.0), None,
    "touches the top edge at its end point (0.1, 1); -3 + (0.1 - -3) rounds to "
    "0.10000000000000009, so interpolating the edge point from P0 misses P1 by one ulp")
DESCENDING_ONTO_TOP_EDGE_FROM_ONE_ULP_ABOVE = _case(
    "descending_onto_top_edge_from_one_ulp_above", UNIT, (0.0, 1.0000000000000002, 1.0, 1.0),
    None, "above the top edge but for its end point; P(t) rounds onto the edge for t >= 1/2")
LEAVING_A_CORNER_BELOW_THE_EDGE_BY_A_SUBNORMAL = _case(
    "leaving_a_corner_below_the_edge_by_a_subnormal", (0.0, 0.0, 0.25, 1.0),
    (0.25000000000000006, 0.0, 0.25, -5e-324), None,
    "from one ulp right of the corner (0.25, 0) to 5e-324 below it: never inside")
THROUGH_A_CORNER_WITH_A_SLOPE_OF_1E_MINUS_153 = _case(
    "through_a_corner_with_a_slope_of_1e_minus_153", (0.0, 0.0, 1e-86, 1e-86),
    (-1e-86, 3.787065011786069e-239, 1e-86, -3.787065011786069e-239), None,
    "crosses the corner (0, 0) from outside to outside; cross products underflow")
ALONG_EDGE_ONE_ULP_OUTSIDE = _case("along_edge_one_ulp_outside", W10, (-ULP0, 0, -ULP0, 10), None)
ALONG_EDGE_ONE_ULP_INSIDE = _case("along_edge_one_ulp_inside", W10, (ULP0, 0, ULP0, 10),
                                  (ULP0, 0, ULP0, 10))
STARTING_ONE_ULP_OUTSIDE = _case("starting_one_ulp_outside", W10, (-ULP0, 5, 5, 5), (0, 5, 5, 5))

# --- zero length ---------------------------------------------------------------------------
ZERO_LENGTH_INSIDE = _case("zero_length_inside", W10, (5, 5, 5, 5), (5, 5, 5, 5))
ZERO_LENGTH_OUTSIDE = _case("zero_length_outside", W10, (20, 5, 20, 5), None)
ZERO_LENGTH_ON_EDGE = _case("zero_length_on_edge", W10, (0, 5, 0, 5), (0, 5, 0, 5))
ZERO_LENGTH_ON_CORNER = _case("zero_length_on_corner", W10, (10, 10, 10, 10), (10, 10, 10, 10))
ZERO_LENGTH_ONE_ULP_OUTSIDE = _case("zero_length_one_ulp_outside", W10, (-ULP0, 5, -ULP0, 5), None)

# --- magnitudes ----------------------------------------------------------------------------
HUGE_HORIZONTAL = _case("huge_horizontal", HUGE, (-2e300, 0, 2e300, 0), (-1e300, 0, 1e300, 0))
HUGE_DIAGONAL = _case("huge_diagonal", HUGE, (-2e300, -2e300, 2e300, 2e300),
                      (-1e300, -1e300, 1e300, 1e300))
HUGE_SLOPED = _case("huge_sloped", HUGE, (-3e300, 1e300, 3e300, -2e300),
                    (-1e300, 0, 1e300, -1e300))
HUGE_SPAN_NEAR_OVERFLOW = _case("huge_span_near_overflow", HUGE, (-8e307, 5e299, 8e307, 5e299),
                                (-1e300, 5e299, 1e300, 5e299), "x1 - x0 = 1.6e308 still fits")
TINY_HORIZONTAL = _case("tiny_horizontal", TINY, (-1e-300, 5e-301, 2e-300, 5e-301),
                        (0, 5e-301, 1e-300, 5e-301))
TINY_DIAGONAL = _case("tiny_diagonal", TINY, (-1e-300, -1e-300, 2e-300, 2e-300),
                      (0, 0, 1e-300, 1e-300))
TINY_ANTIDIAGONAL = _case("tiny_antidiagonal", TINY, (-1e-300, 2e-300, 2e-300, -1e-300),
                          (0, 1e-300, 1e-300, 0))
SUBNORMAL_HORIZONTAL = _case("subnormal_horizontal", SUBNORMAL, (-1e-310, 5e-311, 2e-310, 5e-311),
                             (0, 5e-311, 1e-310, 5e-311), "a window of subnormal size")
FROM_FAR_AWAY_INTO_UNIT = _case("from_far_away_into_unit", UNIT, (-1e200, -1e200, 0.5, 0.5),
                                (0, 0, 0.5, 0.5), "t of the entry rounds to 1")
FAR_HORIZONTAL_THROUGH_UNIT = _case("far_horizontal_through_unit", UNIT,
                                    (-1e200, 0.5, 1e200, 0.5), (0, 0.5, 1, 0.5),
                                    "the whole window lies within one rounding step of t")
VERTICAL_FROM_TINY_TO_HUGE = _case("vertical_from_tiny_to_huge", UNIT, (0.5, -1e-200, 0.5, 1e200),
                                   (0.5, 0, 0.5, 1))
FROM_1E_MINUS_300_TO_1E300 = _case("from_1e_minus_300_to_1e300", UNIT,
                                   (1e-300, 1e-300, 1e300, 1e300), (1e-300, 1e-300, 1, 1))
FAR_WINDOW_HORIZONTAL = _case("far_window_horizontal", FAR,
                              (1e6 - 1, 1e6 + 0.5, 1e6 + 2, 1e6 + 0.5),
                              (1e6, 1e6 + 0.5, 1e6 + 1, 1e6 + 0.5))
FAR_WINDOW_SLOPED = _case("far_window_sloped", FAR, (1e6 - 1, 1e6 - 1, 1e6 + 2, 1e6 + 2.5),
                          (1e6, 1000000.1666666666, 1000000.7142857143, 1e6 + 1))
LONG_SEGMENT_THROUGH_WINDOW = _case(
    "long_segment_through_window", UNIT, (-5000.0, -1499.7, 5000.0, 1500.9),
    (0.0, 0.6000000000000227, 1.0, 0.9000600000000227), "10,000 windows long")
VERY_LONG_SEGMENT_THROUGH_TINY_WINDOW = _case(
    "very_long_segment_through_tiny_window", MILLI,
    (-99999.9995, -29999.9996, 100000.0005, 30000.0004),
    (0.0, 0.00025000000241561795, 0.001, 0.000550000002415618), "2e8 windows long")
EXTREMELY_LONG_SEGMENT_THROUGH_TINY_WINDOW = _case(
    "extremely_long_segment_through_tiny_window", MILLI,
    (-1e12, -3e11, 1e12, 300000000000.0015),
    (0.0, 0.000762939453125, 0.0007902018229166647, 0.001), "2e15 windows long")


# --- GeoJSON mixing 2D and 3D positions (RFC 7946 allows either in any position) -------------

#: A FeatureCollection whose line, polygon and points mix 2D and 3D positions; clip it to
#: `W10`.
MIXED_DIMENSIONS = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "id": 1, "properties": {"name": "road"},
     "geometry": {"type": "LineString",
                  "coordinates": [[-5, 5], [5, 5, 1], [15, 5, 3], [15, 8]]}},
    {"type": "Feature", "id": 2, "properties": {},
     "geometry": {"type": "Polygon", "coordinates": [
         [[-5, -5, 1], [5, -5], [5, 5, 2], [-5, 5, 2], [-5, -5, 1]]]}},
    {"type": "Feature", "id": 3, "properties": {},
     "geometry": {"type": "MultiPoint", "coordinates": [[1, 1], [2, 2, 5], [20, 20, 1]]}},
]}
#: Each position in the dimension it came in; a cut point or corner with Z only where
#: every Z it is computed from is known (a NaN would come out as null: JSON has none).
MIXED_DIMENSIONS_CLIPPED = [
    {"type": "LineString", "coordinates": [[0.0, 5.0], [5.0, 5.0, 1.0], [10.0, 5.0, 2.0]]},
    {"type": "Polygon", "coordinates": [
        [[5.0, 0.0], [5.0, 5.0, 2.0], [0.0, 5.0, 2.0], [0.0, 0.0], [5.0, 0.0]]]},
    {"type": "MultiPoint", "coordinates": [[1.0, 1.0], [2.0, 2.0, 5.0]]},
]
