"""verify: comparison of a clip result with Shapely's intersection, and its verdict."""

import dataclasses
import json

import numpy as np
import pytest

from rnsca import (
    InvalidGeometryError,
    InvalidOptionError,
    UnsupportedGeometryError,
    Verification,
    clip_segments,
    verify,
)
from rnsca.verify import approx_leaf_bound

W10 = (0.0, 0.0, 10.0, 10.0)
SEGS = [[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0], [1.0, 1.0, 2.0, 3.0],
        [0.0, 0.0, 10.0, 0.0], [5.0, 5.0, 5.0, 5.0], [-1.0, 1.0, 1.0, -1.0]]


def tampered(result, **fields):
    return dataclasses.replace(result, **fields)


def test_exact_result_passes_with_no_deviation(method, backend):
    r = clip_segments(SEGS, W10, method=method, backend=backend)
    v = verify(SEGS, r, W10)
    assert isinstance(v, Verification)
    assert v.passed and v.false_positives == 0 and v.mode == "exact"
    assert v.max_deviation == 0.0 and v.ratio == 1.0
    assert v.allowed_deviation == 1e-9 * 10.0


def test_approx_result_passes_within_twice_the_leaf_bound(backend):
    r = clip_segments(SEGS, W10, mode="approx", n=3, max_depth=2, backend=backend)
    v = verify(SEGS, r, W10)
    assert v.passed and v.mode == "approx"
    assert 0.0 < v.max_deviation <= v.allowed_deviation
    assert v.ratio < 1.0
    # The longest segment is 20 long: its leaves are at most 20 / 3**2.
    assert v.allowed_deviation == pytest.approx(2 * 20 / 9 + 1e-8)


def test_shifted_piece_fails_with_its_deviation():
    r = clip_segments(SEGS, W10)
    moved = r.segments.copy()
    moved[0] += [0.0, 1e-6, 0.0, 1e-6]
    v = verify(SEGS, tampered(r, segments=moved), W10)
    assert not v.passed
    assert v.max_deviation == pytest.approx(1e-6)
    assert v.false_positives == 0


def test_missing_piece_counts_its_length_as_deviation():
    r = clip_segments(SEGS, W10)
    keep = r.source != 0
    v = verify(SEGS, tampered(r, segments=r.segments[keep], source=r.source[keep],
                              t=r.t[keep]), W10)
    assert not v.passed and v.max_deviation == 10.0
    assert v.ratio == pytest.approx(1 - 10.0 / (10.0 + 10.0 + np.hypot(1, 2)))


def test_piece_for_a_segment_touching_a_corner_counts_its_length():
    r = clip_segments(SEGS, W10)
    extra = np.concatenate([r.segments, [[0.0, 0.0, 0.5, 0.0]]])
    v = verify(SEGS, tampered(r, segments=extra, source=np.append(r.source, 5),
                              t=np.concatenate([r.t, [[0.5, 0.75]]])), W10)
    assert not v.passed and v.max_deviation == 0.5


def test_vertices_outside_the_window_are_false_positives():
    r = clip_segments(SEGS, W10)
    out = r.segments.copy()
    out[0] = [-1.0, 5.0, 11.0, 5.0]
    v = verify(SEGS, tampered(r, segments=out), W10)
    assert v.false_positives == 2 and not v.passed


def test_vertex_outside_by_less_than_1e_9_of_the_window_is_not_a_false_positive():
    r = clip_segments(SEGS, W10)
    out = r.segments.copy()
    out[0, 0] = -0.5e-8
    assert verify(SEGS, tampered(r, segments=out), W10).false_positives == 0


def test_approx_result_with_a_false_positive_fails():
    r = clip_segments(SEGS, W10, mode="approx", n=3, max_depth=2)
    out = r.segments.copy()
    out[0, 0] = -1e-3
    assert not verify(SEGS, tampered(r, segments=out), W10).passed


def test_empty_input_passes_with_ratio_one(method):
    r = clip_segments(np.empty((0, 4)), W10, method=method)
    v = verify(np.empty((0, 4)), r, W10)
    assert v.passed and v.max_deviation == 0.0 and v.ratio == 1.0


def test_zero_length_segment_inside_is_expected_and_outside_is_not():
    segs = [[5.0, 5.0, 5.0, 5.0], [0.0, 10.0, 0.0, 10.0], [11.0, 5.0, 11.0, 5.0]]
    r = clip_segments(segs, W10)
    np.testing.assert_array_equal(r.source, [0, 1])
    assert verify(segs, r, W10).passed


@pytest.mark.parametrize("window, segs", [
    ((0.0, 0.0, 1e-300, 1e-300), [[-1e-300, 5e-301, 2e-300, 5e-301],
                                  [-1e-300, -1e-300, 2e-300, 2e-300]]),
    ((-1e300, -1e300, 1e300, 1e300), [[-2e300, 0.0, 2e300, 0.0],
                                      [-8e307, 3e299, 8e307, -1e299]]),
    ((0.0, 0.0, 1e-160, 1e-160), [[-1e-160, 3e-161, 2e-160, 6e-161]]),
])
def test_verify_works_at_magnitudes_where_geos_alone_fails(window, segs):
    # GEOS returns an empty or wrong intersection around 1e+-150 and beyond; verify
    # compares after an exact power-of-two rescaling.
    r = clip_segments(segs, window)
    v = verify(segs, r, window)
    assert v.passed and v.ratio == pytest.approx(1.0) and v.max_deviation <= v.allowed_deviation


@pytest.mark.parametrize("window, segs", [
    ((0.0, 0.0, 5e-324, 5e-324), [[-1e-323, 0.0, 1e-323, 5e-324]]),
    ((-1e-320, -1e-320, 1e-320, 1e-320), [[-2e-320, 0.0, 2e-320, 5e-321]]),
])
def test_verify_works_for_windows_of_subnormal_size(window, segs):
    # Found by fuzzing the segment endpoint: the power of two that would bring such a
    # window to size 1 is beyond float64 (OverflowError).
    r = clip_segments(segs, window)
    v = verify(segs, r, window)
    assert v.passed and v.max_deviation == 0.0


def test_verify_detects_a_wrong_piece_at_1e300():
    window = (-1e300, -1e300, 1e300, 1e300)
    segs = [[-2e300, 0.0, 2e300, 0.0]]
    r = clip_segments(segs, window)
    v = verify(segs, tampered(r, segments=np.array([[-1e300, 0.0, 0.0, 0.0]])), window)
    assert not v.passed and v.max_deviation == 1e300


def test_verify_refuses_something_other_than_a_clip_result():
    with pytest.raises(UnsupportedGeometryError, match="SegmentClipResult"):
        verify(SEGS, np.zeros((1, 4)), W10)


def test_verify_refuses_segments_that_were_not_the_ones_clipped():
    r = clip_segments(SEGS, W10)
    with pytest.raises(InvalidGeometryError, match="6 segments that were clipped"):
        verify(SEGS[:2], r, W10)


def test_verify_validates_the_original_segments():
    r = clip_segments(SEGS, W10)
    bad = np.array(SEGS)
    bad[1, 0] = np.nan
    with pytest.raises(InvalidGeometryError, match="segment 1"):
        verify(bad, r, W10)


def test_to_dict_is_json_ready():
    r = clip_segments(SEGS, W10)
    d = json.loads(json.dumps(verify(SEGS, r, W10).to_dict()))
    assert d == {"max_deviation": 0.0, "false_positives": 0, "ratio": 1.0, "passed": True,
                 "allowed_deviation": 1e-8, "mode": "exact", "valid": True,
                 "invalid_inputs": 0, "inputs": len(SEGS), "checked": len(SEGS),
                 "sampling": "all", "skipped": 0, "timed_out": False, "note": ""}


def test_approx_leaf_bound_is_the_tolerance_or_one_deepest_leaf():
    r = clip_segments(SEGS, W10, mode="approx", n=4, max_depth=3, tolerance=0.1)
    np.testing.assert_allclose(approx_leaf_bound(np.array([0.0, 6.4, 64.0]), r),
                               [0.1, 0.1, 1.0])


def test_approx_leaf_bound_with_auto_n_assumes_bisection():
    r = clip_segments(SEGS, W10, mode="approx", max_depth=2, tolerance=1e-3)
    np.testing.assert_allclose(approx_leaf_bound(np.array([8.0]), r), [2.0])


def test_explicit_approx_bound_replaces_the_leaf_bound():
    r = clip_segments(SEGS, W10, mode="approx", n=3, max_depth=2)
    v = verify(SEGS, r, W10, approx_bound=1e-12)
    assert not v.passed and v.allowed_deviation == 1e-12 and v.mode == "approx"
    assert verify(SEGS, r, W10, approx_bound=5.0).passed


def test_explicit_mode_overrides_the_results_mode():
    r = clip_segments(SEGS, W10, mode="approx", n=3, max_depth=2)
    v = verify(SEGS, r, W10, mode="exact")
    assert not v.passed and v.mode == "exact" and v.allowed_deviation == 1e-8


def test_segments_refuse_the_interior_boundary():
    r = clip_segments(SEGS, W10)
    with pytest.raises(InvalidOptionError, match="boundary='closed'"):
        verify(SEGS, r, W10, boundary="interior")


def test_a_sample_compares_that_many_inputs_chosen_by_the_seed():
    rng = np.random.default_rng(4)
    segments = rng.random((2000, 4)) * 20 - 5
    window = (0.0, 0.0, 10.0, 10.0)
    result = clip_segments(segments, window)
    whole = verify(segments, result, window)
    assert (whole.inputs, whole.checked, whole.sampling) == (2000, 2000, "all")
    part = verify(segments, result, window, sample=100, seed=3)
    assert part.passed and (part.inputs, part.checked) == (2000, 100)
    assert part.sampling == "random 100 of 2000, seed 3"
    assert verify(segments, result, window, sample=5000).checked == 2000  # more than there are
    # Every output moved: any sample sees it; the same seed sees the same deviation.
    moved = dataclasses.replace(result, segments=result.segments + [0.5, 0.0, 0.5, 0.0])
    first = verify(segments, moved, window, sample=10, seed=1)
    assert not first.passed
    assert verify(segments, moved, window, sample=10, seed=1) == first


def test_a_sample_of_geometries_and_of_paths():
    import shapely

    from rnsca import clip, clip_svg

    window = (0.0, 0.0, 10.0, 10.0)
    lines = shapely.linestrings(np.random.default_rng(2).random((300, 2, 2)) * 20 - 5)
    v = verify(lines, clip(lines, window), window, sample=30)
    assert v.passed and (v.inputs, v.checked) == (300, 30)
    paths = ["M-5 5 L15 5", "M5 -5 C0 5 10 5 5 15", "M-1 -1 L11 11 L-1 11 Z"] * 20
    clipped, _ = clip_svg(paths, window)
    v = verify(paths, clipped, window, sample=7)
    assert v.passed and (v.inputs, v.checked) == (60, 7)


@pytest.mark.parametrize("sample", [0, -1, 2.5, True, "3"])
def test_a_bad_sample_size_is_refused(sample):
    segments = [[-5.0, 5.0, 15.0, 5.0]]
    result = clip_segments(segments, (0, 0, 10, 10))
    with pytest.raises(InvalidOptionError, match="sample must be"):
        verify(segments, result, (0, 0, 10, 10), sample=sample)
