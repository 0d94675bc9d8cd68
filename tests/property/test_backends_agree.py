"""Each backend against an oracle, on inputs drawn where clipping code goes wrong.

OpenCL (default device, float64) is checked against Numba with the same options: the
sources must be identical, the parameter intervals and coordinates equal up to rounding
(the kernels evaluate the same formulas in the same order, so in practice they are
bit-identical), and every counter of `ClipStats` equal. Numba itself is checked against
the clip computed in exact rational arithmetic (`tests.cases.exact_clip`): in exact mode
within 1e-9 of the window's size, in approx mode never more than the true clip and
within one leaf of it at each cut end.

Inputs are drawn to hit the cases where clipping code goes wrong: end points on the
boundary, one ulp either side of it, on the corners, along the edges, zero-length
segments, lattice points where subdivision points fall exactly on an edge, and
coordinates from 1e-300 to 1e300.
"""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from rnsca import Backend, Method, Mode, Window, clip_segments
from tests.checks import (
    assert_inside_window,
    assert_piece_is_expected,
    assert_well_formed,
    exact_pieces,
)
from tests.conftest import require_backend

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

N_CHOICES = ["auto", 2, 3, 5, 8, 64]
DEPTH_CHOICES = [0, 1, 2, 5, 12, 32]
# Tolerance as a fraction of the window's size; None: the mode's default.
TOLERANCE_CHOICES = [None, 1e-12, 1e-3, 0.3, 10.0]


# --- windows ---------------------------------------------------------------------------

@st.composite
def windows(draw, min_exponent=-300, max_exponent=300):
    """A window of any aspect ratio, at a scale 10**e, possibly far from the origin."""
    e = draw(st.integers(min_exponent, max_exponent))
    scale = 10.0 ** e
    width = draw(st.floats(0.05, 20.0)) * scale
    height = draw(st.floats(0.05, 20.0)) * scale
    x = draw(st.floats(-10.0, 10.0)) * scale
    y = draw(st.floats(-10.0, 10.0)) * scale
    assume(x + width > x and y + height > y)  # the width survives the offset's rounding
    return Window(x, y, x + width, y + height)


def _coordinates(w: Window, axis: str):
    """Values that matter along one axis: bounds, one ulp either side, thirds, far out."""
    low, high = (w.xmin, w.xmax) if axis == "x" else (w.ymin, w.ymax)
    size = high - low
    return [low, high, np.nextafter(low, -np.inf), np.nextafter(low, np.inf),
            np.nextafter(high, -np.inf), np.nextafter(high, np.inf),
            low + size / 2, low + size / 3, high - size / 3, low - size, high + size,
            low - size / 7, high + size / 64, low - 1e6 * size, high + 1e6 * size]


# --- segment sets ----------------------------------------------------------------------

@st.composite
def random_segments(draw, w: Window):
    """End points spread over three window sizes around the window."""
    n = draw(st.integers(1, 12))
    span = 3 * w.size
    xs = st.floats(w.xmin - span, w.xmax + span, allow_nan=False, allow_infinity=False)
    ys = st.floats(w.ymin - span, w.ymax + span, allow_nan=False, allow_infinity=False)
    rows = [[draw(xs), draw(ys), draw(xs), draw(ys)] for _ in range(n)]
    return np.array(rows, dtype=np.float64)


@st.composite
def boundary_segments(draw, w: Window):
    """End points on edges, corners, one ulp off them, along edges, or repeated (zero length)."""
    xs, ys = _coordinates(w, "x"), _coordinates(w, "y")
    point = st.tuples(st.sampled_from(xs), st.sampled_from(ys))
    n = draw(st.integers(1, 12))
    rows = []
    for _ in range(n):
        kind = draw(st.sampled_from(["any", "zero", "along", "corner"]))
        p = draw(point)
        if kind == "zero":
            q = p
        elif kind == "along":  # both ends share an x or a y: parallel to an edge
            q = (p[0], draw(st.sampled_from(ys))) if draw(st.booleans()) else (
                draw(st.sampled_from(xs)), p[1])
        elif kind == "corner":  # symmetric about a corner: through it, in either direction
            cx = draw(st.sampled_from([w.xmin, w.xmax]))
            cy = draw(st.sampled_from([w.ymin, w.ymax]))
            d = draw(st.floats(1e-6, 3.0)) * w.size
            sx, sy = draw(st.sampled_from([-1.0, 1.0])), draw(st.sampled_from([-1.0, 1.0]))
            p, q = (cx - sx * d, cy - sy * d), (cx + sx * d, cy + sy * d)
        else:
            q = draw(point)
        rows.append([p[0], p[1], q[0], q[1]])
    return np.array(rows, dtype=np.float64)


@st.composite
def lattice_segments(draw, w: Window):
    """End points on a lattice of 1/8 window steps: subdivision points land on edges."""
    n = draw(st.integers(1, 12))
    k = st.integers(-24, 32)
    rows = [[w.xmin + draw(k) * w.width / 8, w.ymin + draw(k) * w.height / 8,
             w.xmin + draw(k) * w.width / 8, w.ymin + draw(k) * w.height / 8] for _ in range(n)]
    return np.array(rows, dtype=np.float64)


@st.composite
def wide_segments(draw, w: Window):
    """Coordinates of any magnitude from 1e-300 to 1e300, either sign, and exact zeros."""
    magnitude = st.builds(lambda e, m, s: s * m * 10.0 ** e, st.integers(-300, 299),
                          st.floats(1.0, 9.99), st.sampled_from([-1.0, 1.0]))
    value = st.one_of(magnitude, st.just(0.0), st.sampled_from(_coordinates(w, "x")),
                      st.sampled_from(_coordinates(w, "y")))
    n = draw(st.integers(1, 10))
    rows = np.array([[draw(value) for _ in range(4)] for _ in range(n)], dtype=np.float64)
    # Keep only rows whose coordinate differences fit in float64 (the library refuses others).
    with np.errstate(over="ignore"):
        fits = np.isfinite(rows[:, 2:] - rows[:, :2]).all(axis=1)
    return rows[fits]


@st.composite
def options(draw, w: Window):
    """A method, a mode, and the options of subdivision; the tolerance scales with the window."""
    tolerance = draw(st.sampled_from(TOLERANCE_CHOICES))
    return {
        "method": draw(st.sampled_from(Method)),
        "mode": draw(st.sampled_from(Mode)),
        "n": draw(st.sampled_from(N_CHOICES)),
        "max_depth": draw(st.sampled_from(DEPTH_CHOICES)),
        "tolerance": None if tolerance is None else tolerance * w.size,
    }


# --- the comparison --------------------------------------------------------------------

@pytest.fixture(scope="module", params=[Backend.NUMBA,
                                        pytest.param(Backend.OPENCL, marks=pytest.mark.opencl)],
                ids=lambda b: b.value)
def candidate(request):
    """Each backend, checked against its oracle (`assert_backends_agree`)."""
    return require_backend(request.param)


def assert_backends_agree(segments, window: Window, opts: dict, candidate=Backend.NUMBA) -> None:
    """The method and mode in `opts` give the oracle's pieces on `candidate`.

    Numba: the exact rational clip. OpenCL: Numba's pieces and stats.
    """
    if candidate is Backend.NUMBA:
        result = clip_segments(segments, window, **opts)
        method, mode = Method(opts.get("method", "rnsca")), Mode(opts.get("mode", "exact"))
        assert_well_formed(result, segments.shape[0])
        assert_inside_window(result, window)
        assert_piece_is_expected(result, segments, exact_pieces(segments, window), window,
                                 method, mode)
        return
    ref = clip_segments(segments, window, backend="numba", **opts)
    got = clip_segments(segments, window, backend=candidate, **opts)
    where = f"{candidate.value}: {opts} window={window.bounds}"
    np.testing.assert_array_equal(ref.source, got.source, err_msg=where)
    np.testing.assert_allclose(ref.t, got.t, rtol=1e-12, atol=1e-300, err_msg=where)
    np.testing.assert_allclose(ref.segments, got.segments, rtol=1e-12,
                               atol=1e-12 * window.size, err_msg=where)
    # Only OpenCL reports a device; every counter of the work itself must agree.
    assert ref.stats == dataclasses.replace(got.stats, device=None), where


def assert_all_methods_agree(segments, window: Window, opts: dict,
                             candidate=Backend.NUMBA) -> None:
    """Every method x mode gives the same pieces and stats on both backends."""
    for method in Method:
        for mode in Mode:
            assert_backends_agree(segments, window, {**opts, "method": method, "mode": mode},
                                  candidate)


def _draw_case(data, segment_strategy, **window_kwargs):
    w = data.draw(windows(**window_kwargs), label="window")
    segs = data.draw(segment_strategy(w), label="segments")
    opts = data.draw(options(w), label="options")
    # A segment 2**63 window sizes long overflows the kernel's n="auto" split count;
    # that known kernel bug has its own test (`test_auto_split_count_...`) below.
    assume(not _overflows_auto_n(segs, w))
    return segs, w, opts


def _overflows_auto_n(segments, window: Window) -> bool:
    length = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    with np.errstate(over="ignore"):
        return bool((length / window.size >= 2.0 ** 62).any())


UNIT = Window(0.0, 0.0, 1.0, 1.0)


@SETTINGS
@given(st.data())
def test_random_segments_agree(candidate, data):
    assert_backends_agree(*_draw_case(data, random_segments), candidate)


@SETTINGS
@given(st.data())
def test_segments_on_edges_and_corners_agree(candidate, data):
    assert_backends_agree(*_draw_case(data, boundary_segments), candidate)


@SETTINGS
@given(st.data())
def test_lattice_segments_agree(candidate, data):
    assert_backends_agree(*_draw_case(data, lattice_segments, min_exponent=-3, max_exponent=3),
                          candidate)


@SETTINGS
@given(st.data())
def test_segments_from_1e_minus_300_to_1e300_agree(candidate, data):
    assert_backends_agree(*_draw_case(data, wide_segments), candidate)


@settings(max_examples=8, deadline=None)
@given(st.sampled_from(N_CHOICES), st.sampled_from(DEPTH_CHOICES),
       st.sampled_from(TOLERANCE_CHOICES))
@example("auto", 32, 1e-12)
@example(64, 32, 1e-12)
def test_a_mixed_batch_agrees_for_every_option(candidate, n, max_depth, tolerance):
    # One batch with every kind of segment, so each option setting meets all of them.
    rng = np.random.default_rng(7)
    batch = np.concatenate([
        rng.uniform(-2.0, 3.0, size=(200, 4)),
        np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0], [-1.0, -1.0, 2.0, 2.0],
                  [-1.0, 2.0, 2.0, -1.0], [-1.0, 0.0, 0.0, 1.0], [0.5, 0.5, 0.5, 0.5],
                  [-1e15, 0.5, 1e15, 0.5], [-1e-300, 1e-300, 1e-300, -1e-300],
                  [np.nextafter(0.0, -1.0), 0.5, 2.0, 0.5], [1.0, -5.0, 1.0, 5.0]]),
    ])
    opts = {"n": n, "max_depth": max_depth,
            "tolerance": None if tolerance is None else tolerance * UNIT.size}
    assert_all_methods_agree(batch, UNIT, opts, candidate)


def test_auto_split_count_of_a_segment_2e63_windows_long_is_capped(candidate):
    # n="auto" splits a piece into ceil(length / window size) pieces, at most 64. The
    # kernel's `auto_n` converts that ceiling to int64 before capping it, which overflows
    # past 2**63 (to a negative N: no children), so the segment vanishes from the output.
    segs = np.array([[-1e19, 0.5, 1e19, 0.5], [1.0, 0.0, 0.0, 0.0]])
    assert_all_methods_agree(segs[:1], UNIT, {"n": "auto"}, candidate)
    assert_all_methods_agree(segs[1:], Window(0.0, 0.0, 1e-19, 1e-19), {"n": "auto"},
                             candidate)


def test_ties_between_equal_parameters_agree(candidate):
    # Candidate ends of equal t from different subtrees (see the unit test of the same
    # segment): only the kernel's depth-first order picks between them.
    segs = np.array([[0.5, -0.875, 2.25, 2.25]])
    for n in (2, 3, 5, 7):
        for max_depth in (3, 8, 32):
            assert_backends_agree(segs, UNIT, {"method": "rnsca", "mode": "exact", "n": n,
                                               "max_depth": max_depth, "tolerance": 1e-9},
                                  candidate)


def test_empty_input_agrees(candidate):
    assert_all_methods_agree(np.empty((0, 4)), UNIT, {}, candidate)


def test_long_segments_split_in_many_pieces_agree(candidate):
    # A segment far longer than the window: n="auto" cuts it into up to 64 pieces at once.
    segs = np.array([[-1e6, 0.3, 1e6, 0.7], [-1e6, -1e6, 1e6, 1e6], [0.5, -1e12, 0.5, 1e12],
                     [-math.pi * 1e5, 0.0, math.e * 1e5, 1.0]])
    for tolerance in (None, 1e-12, 1e-6):
        assert_all_methods_agree(segs, UNIT, {"tolerance": tolerance}, candidate)
