"""Assertions shared by the test layers, and a Shapely oracle independent of `rnsca.verify`.

Shapely (GEOS) is the spec for what a clip should return, but GEOS works in double
precision and loses whole pieces far from 1 (from about 1e+-110 on). For windows below
1 or above 1e90 the oracle here therefore hands Shapely the geometry scaled by a power of
two that brings the window's size near 1: scaling by a power of two is exact in floating
point (short of flushing subnormals when scaling down), so Shapely answers for the same
geometry, and its answer scales back exactly.

Distances between pieces are computed here with NumPy (point-to-segment distances), not
with `shapely.hausdorff_distance`, so the oracle shares no code with `rnsca.verify`.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from rnsca import Method, Mode, SegmentClipResult, Window, clip_segments
from rnsca.verify import approx_leaf_bound
from tests.cases import exact_clip

#: Exact mode: every piece within this fraction of the window's size of the true clip.
EXACT_RELATIVE = 1e-9
#: Methods that decide every segment analytically, so their approx mode is exact too.
ANALYTIC = frozenset({Method.COHEN_SUTHERLAND, Method.LIANG_BARSKY, Method.NICHOLL_LEE_NICHOLL})
EPS = float(np.finfo(np.float64).eps)


def is_exact(method, mode) -> bool:
    """Return whether `method` in `mode` promises the analytic clip."""
    return Method(method) in ANALYTIC or Mode(mode) is Mode.EXACT


def unit_scale(window: Window, *arrays: np.ndarray) -> float:
    """Return the power of two by which Shapely should see the geometry.

    Windows smaller than 1 are scaled up to a size in [0.5, 1) (exact, and subnormal
    offsets become normal numbers); windows from 1 to 2**300 are left alone (scaling
    down would flush subnormal offsets such as one ulp off an edge at 0); larger ones
    are scaled down likewise. Smaller if needed to keep every coordinate finite.
    """
    exponent = math.frexp(window.size)[1]
    if 0 < exponent <= 300:
        return 1.0
    largest = max([abs(b) for b in window.bounds]
                  + [float(np.abs(a).max(initial=0.0)) for a in arrays])
    # At most 2**1000: a subnormal window would need 2**1074, not a float64.
    exponent = max(exponent, math.frexp(largest)[1] - 1000, -1000)
    return math.ldexp(1.0, -exponent)


#: Longest segment, in windows, whose GEOS clip is within 1e-9 of the window.
GEOS_MAX_WINDOWS = 1e5


def shapely_can_judge(window: Window, segments: np.ndarray) -> np.ndarray:
    """Return, per segment, whether GEOS can be trusted with it (see `shapely_pieces`).

    Not with a non-zero coordinate below 2**-500 (about 3e-151), before or after
    `unit_scale`: products of two such numbers underflow in GEOS, which then returns
    points outside the box, drops lines along an edge, or keeps a segment that only
    touches the box. Nor with a segment longer than `GEOS_MAX_WINDOWS` windows: GEOS's
    cut points then carry an error of eps times the length, beyond 1e-9 of the window
    (rnsca's do not: they are checked to 1e12 windows against exact arithmetic).
    `tests.property.test_vs_exact` covers all those inputs.
    """
    scale = unit_scale(window, segments)
    tiny = 2.0 ** -500

    def normal(values):
        values = np.abs(values)
        return (values == 0) | (np.minimum(values, values * scale) >= tiny)

    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    rows = normal(segments).all(axis=1)
    with np.errstate(over="ignore"):
        span = np.maximum(np.abs(segments[:, 2] - segments[:, 0]),
                          np.abs(segments[:, 3] - segments[:, 1]))
    rows &= span <= GEOS_MAX_WINDOWS * window.size
    return rows & bool(normal(np.array(window.bounds)).all())


def exact_pieces(segments, window) -> list[np.ndarray | None]:
    """Return, per segment, its clip in exact rational arithmetic (`tests.cases.exact_clip`),
    rounded to the nearest floats; None for no piece (same rules as `shapely_pieces`)."""
    bounds = Window.of(window).bounds
    out: list[np.ndarray | None] = []
    for seg in np.asarray(segments, dtype=np.float64).reshape(-1, 4):
        clipped = exact_clip(seg, bounds)
        out.append(None if clipped is None else np.array(clipped[0]))
    return out


def lengths(segments: np.ndarray) -> np.ndarray:
    """Return the length of each row ``[x0, y0, x1, y1]`` (overflow-safe via hypot)."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    return np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])


# --- the Shapely oracle --------------------------------------------------------------------

def shapely_pieces(segments, window) -> list[np.ndarray | None]:
    """Return, per segment, the piece ``shapely.intersection`` gives, or None.

    The piece is oriented like its segment. Closed-window rules as rnsca's: a point of
    contact is no piece; a zero-length segment inside (boundary included) is its own
    piece (Shapely returns nothing for it).
    """
    window = Window.of(window)
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    scale = unit_scale(window, segments)
    box = shapely.box(*(b * scale for b in window.bounds))
    clipped = shapely.intersection(shapely.linestrings((segments * scale).reshape(-1, 2, 2)),
                                   box)
    out: list[np.ndarray | None] = []
    for seg, geom in zip(segments, clipped, strict=True):
        if seg[0] == seg[2] and seg[1] == seg[3]:
            inside = (window.xmin <= seg[0] <= window.xmax
                      and window.ymin <= seg[1] <= window.ymax)
            out.append(seg.copy() if inside else None)
            continue
        parts = [p for p in shapely.get_parts(geom)
                 if shapely.get_type_id(p) == shapely.GeometryType.LINESTRING
                 and shapely.length(p) > 0]
        if not parts:
            out.append(None)
            continue
        coords = np.concatenate([shapely.get_coordinates(p) for p in parts])
        along = (coords - seg[:2] * scale) @ (seg[2:] - seg[:2])  # scaled: no underflow
        ends = np.concatenate([coords[np.argmin(along)], coords[np.argmax(along)]])
        out.append(ends / scale)
    return out


def _point_segment_distance(p: np.ndarray, seg: np.ndarray) -> float:
    a, b = seg[:2], seg[2:]
    d = b - a
    dd = float(d @ d)
    t = 0.0 if dd == 0.0 else min(1.0, max(0.0, float((p - a) @ d) / dd))
    return float(np.hypot(*(p - (a + t * d))))


def distance_to_piece(point: np.ndarray, piece: np.ndarray) -> float:
    """Return the distance from `point` to the segment `piece`."""
    scale = math.ldexp(1.0, -math.frexp(max(float(np.abs(point).max()),
                                            float(np.abs(piece).max()), 1e-300))[1])
    return _point_segment_distance(point * scale, piece * scale) / scale


def hausdorff(a: np.ndarray | None, b: np.ndarray | None) -> float:
    """Return the Hausdorff distance between two pieces; a missing one counts its partner's
    length (0.0 when both are missing)."""
    if a is None and b is None:
        return 0.0
    if a is None or b is None:
        return float(lengths(a if b is None else b)[0])
    scale = math.ldexp(1.0, -math.frexp(max(float(np.abs(a).max()), float(np.abs(b).max()),
                                                1e-300))[1])
    a, b = a * scale, b * scale
    return max(_point_segment_distance(a[:2], b), _point_segment_distance(a[2:], b),
               _point_segment_distance(b[:2], a), _point_segment_distance(b[2:], a)) / scale


def pieces_by_source(result: SegmentClipResult, n: int) -> list[np.ndarray | None]:
    """Return a list of length `n`: the piece of each input segment, or None."""
    out: list[np.ndarray | None] = [None] * n
    for piece, i in zip(result.segments, result.source, strict=True):
        out[int(i)] = piece
    return out


# --- assertions ----------------------------------------------------------------------------

def assert_well_formed(result: SegmentClipResult, n: int) -> None:
    """Check the result's shapes and dtypes, source order, and t's range."""
    m = len(result)
    assert result.segments.shape == (m, 4) and result.segments.dtype == np.float64
    assert result.source.shape == (m,) and result.source.dtype == np.int64
    assert result.t.shape == (m, 2) and result.t.dtype == np.float64
    assert m <= n
    assert np.all(np.diff(result.source) > 0), f"source not strictly increasing: {result.source}"
    if m:
        assert 0 <= result.source[0] and result.source[-1] < n
        assert np.all((0.0 <= result.t[:, 0]) & (result.t[:, 0] <= result.t[:, 1])
                      & (result.t[:, 1] <= 1.0)), f"t outside 0 <= t0 <= t1 <= 1: {result.t}"
    assert result.stats.segments_in == n
    assert result.stats.pieces_out == m


def assert_inside_window(result: SegmentClipResult, window) -> None:
    """Check that no output coordinate lies outside the closed window (no tolerance)."""
    w = Window.of(window)
    xs, ys = result.segments[:, 0::2], result.segments[:, 1::2]
    outside = (xs < w.xmin) | (xs > w.xmax) | (ys < w.ymin) | (ys > w.ymax)
    assert not outside.any(), (
        f"pieces {np.flatnonzero(outside.any(axis=1)).tolist()} have a vertex outside "
        f"{w.bounds}: {result.segments[outside.any(axis=1)].tolist()}")


def assert_t_matches_pieces(result: SegmentClipResult, segments) -> None:
    """Check that each piece's ends are P(t0) and P(t1) of its source, within rounding.

    P(t) = P0 + t (P1 - P0) is evaluated in floating point; the ends themselves may be
    exact edge values or clamped. Both differ from the true point by a few ulps of the
    segment's largest coordinate or span.
    """
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    src = segments[result.source]
    p0, d = src[:, :2], src[:, 2:] - src[:, :2]
    scale = np.maximum(np.abs(src).max(axis=1), np.abs(d).max(axis=1))
    for k, col in ((0, slice(0, 2)), (1, slice(2, 4))):
        expected = p0 + result.t[:, k:k + 1] * d
        err = np.abs(expected - result.segments[:, col]).max(axis=1)
        bad = err > 16 * EPS * scale
        assert not bad.any(), (
            f"end {k} of pieces {np.flatnonzero(bad).tolist()} is not P(t): "
            f"pieces {result.segments[bad].tolist()}, t {result.t[bad].tolist()}, "
            f"segments {src[bad].tolist()}")


def assert_piece_is_expected(result: SegmentClipResult, segments, expected, window,
                             method, mode) -> None:
    """Check each segment's piece against its expected piece (or None), per the mode.

    Exact promise: Hausdorff distance within 1e-9 of the window's size. Approx promise
    (RNSCA and midpoint in approx mode): no piece where none is expected; each end of a
    piece within one leaf of the expected end and on the expected piece; a missing piece
    only if the expected one is at most two leaves long.
    """
    window = Window.of(window)
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    margin = EXACT_RELATIVE * window.size
    ours = pieces_by_source(result, segments.shape[0])
    bounds = approx_leaf_bound(lengths(segments), result)
    for i, (seg, got, want) in enumerate(zip(segments, ours, expected, strict=True)):
        where = f"segment {i} {seg.tolist()} in {window.bounds}: got {got}, want {want}"
        if is_exact(method, mode):
            assert hausdorff(got, want) <= margin, where
            continue
        bound = bounds[i] + margin
        if want is None:  # nothing, or a piece too short to tell from a point
            assert got is None or lengths(got)[0] <= margin, where
        elif got is None:
            assert lengths(want)[0] <= 2 * bound, where
        else:
            assert distance_to_piece(got[:2], want) <= margin, where
            assert distance_to_piece(got[2:], want) <= margin, where
            assert np.hypot(*(got[:2] - want[:2])) <= bound, where
            assert np.hypot(*(got[2:] - want[2:])) <= bound, where


def clip_case(case, method, mode, backend, **options) -> SegmentClipResult:
    """Clip one `tests.cases.Case` and run the checks every result must pass."""
    result = clip_segments([case.segment], case.window, method=method, mode=mode,
                           backend=backend, **options)
    assert_well_formed(result, 1)
    assert_inside_window(result, case.window)
    return result


def assert_case(case, method, mode, backend, **options) -> None:
    """Check that clipping `case` gives its literal expected piece (or none), per the mode.

    A trivial case (both ends inside, or both beyond one edge) has its exact answer in
    every mode; otherwise approx mode gets the approx promise.
    """
    result = clip_case(case, method, mode, backend, **options)
    expected = None if case.expected is None else np.array(case.expected)
    if case.trivial or is_exact(method, mode):
        if expected is None:
            assert len(result) == 0, f"{case.name}: expected no piece, got {result.segments}"
            return
        assert len(result) == 1, f"{case.name}: expected {case.expected}, got no piece"
        np.testing.assert_allclose(result.segments[0], expected, rtol=0,
                                   atol=EXACT_RELATIVE * case.size, err_msg=case.name)
        return
    assert_piece_is_expected(result, [case.segment], [expected], case.window, method, mode)
