"""Many windows for Bézier paths (`rnsca.clip_paths(paths, windows=)`) and the
verification of many-window results (`rnsca.verify` pair by pair): literal cases and
bad input."""

import dataclasses

import numpy as np
import pytest
import shapely

import rnsca
from rnsca import clip_paths, parse_paths, verify, write_paths
from rnsca.errors import InvalidWindowError

WINDOWS = np.array([[0, 0, 5, 5], [5, 0, 10, 5], [0, 5, 5, 9], [20, 20, 30, 30]], dtype=float)


def test_a_line_across_two_windows_is_cut_at_their_shared_edge():
    r = clip_paths(parse_paths(["M-1 1H9", "M6 4L8 4"]), windows=WINDOWS)
    assert write_paths(r.paths) == ["M0 1H5", "M5 1H9", "M6 4H8"]
    assert r.source.tolist() == [0, 0, 1] and r.window.tolist() == [0, 1, 1]
    assert r.window_offsets.tolist() == [0, 1, 3, 3, 3]
    assert r.stats.geometries_in == 3  # the (path, window) pairs whose boxes touch
    paths, source = r.window_paths(1)
    assert write_paths(paths) == ["M5 1H9", "M6 4H8"] and source.tolist() == [0, 1]


def test_keep_empty_keeps_pairs_whose_boxes_touch_but_hold_nothing():
    r = clip_paths(parse_paths(["M0 0L10 4"]), windows=WINDOWS, keep_empty=True)
    assert r.window.tolist() == [0, 1] and write_paths(r.paths) == ["M0 0 5 2", "M5 2 10 4"]
    # This diagonal's box touches the window (0, 5)..(5, 9); the line (y <= 4.5 there)
    # does not reach it.
    r = clip_paths(parse_paths(["M0 0L10 9"]), windows=WINDOWS, keep_empty=True)
    assert r.window.tolist() == [0, 1, 2] and write_paths(r.paths)[2] == ""
    assert clip_paths(parse_paths(["M0 0L10 9"]), windows=WINDOWS).window.tolist() == [0, 1]


def test_fills_and_one_window_per_pair_on_both_backends(backend):
    paths = parse_paths(["M-1 -1H6V6H-1Z", "M6 1Q12 3 6 4Z"])
    r = clip_paths(paths, windows=WINDOWS, fill="evenodd", backend=backend)
    for w, window in enumerate(WINDOWS):
        got, source = r.window_paths(w)
        one = clip_paths(paths, window, fill="evenodd", backend=backend)
        kept = np.flatnonzero(np.diff(one.paths.path_offsets))
        assert got == one.paths.take(kept) and source.tolist() == kept.tolist()


@pytest.mark.parametrize("windows, message", [
    (np.empty((0, 4)), "k >= 1"),
    ([[0, 0, 1]], "shape"),
    ([[0, 0, 1, 1], [2, 0, 1, 1]], "window 1"),
    ([[0, 0, 1, 1], [0, 0, np.nan, 1]], "window 1"),
    ([[0, 0, 1, np.inf]], "window 0"),
    ("windows", "windows must be"),
])
def test_bad_windows_are_value_errors_naming_the_row(windows, message):
    with pytest.raises(InvalidWindowError, match=message) as info:
        clip_paths(parse_paths(["M0 0L1 1"]), windows=windows)
    assert isinstance(info.value, ValueError)


def test_give_one_of_window_and_windows():
    paths = parse_paths(["M0 0L1 1"])
    with pytest.raises(InvalidWindowError, match="one of"):
        clip_paths(paths)
    with pytest.raises(InvalidWindowError, match="one of"):
        clip_paths(paths, (0, 0, 1, 1), windows=WINDOWS)


def test_no_paths_give_no_outputs_in_every_window():
    r = clip_paths(parse_paths([]), windows=WINDOWS)
    assert len(r) == 0 and r.window_offsets.tolist() == [0] * 5


def test_path_boxes_hold_control_and_start_points():
    boxes = parse_paths(["M0 0Q5 4 2 1", "M-1 3", "M1 1L2 2ZM-4 0L0 0"]).boxes()
    assert boxes.tolist() == [[0, 0, 5, 4], [-1, 3, -1, 3], [-4, 0, 2, 2]]


# --- verification of many windows -----------------------------------------------------


def test_verify_compares_every_pair_of_a_path_clip():
    paths = parse_paths(["M -5 5 C 0 15 10 -5 15 5", "M 1 1 L 9 9"])
    for fill in (None, "nonzero"):
        v = verify(paths, clip_paths(paths, windows=WINDOWS, fill=fill), WINDOWS)
        assert v.passed and v.inputs == v.checked == 6 and v.false_positives == 0


def test_verify_finds_a_path_output_moved_or_missing():
    paths = parse_paths(["M-1 1H9"])
    r = clip_paths(paths, windows=WINDOWS)
    moved = dataclasses.replace(r, paths=parse_paths(["M0 1H5", "M5 2H9"]))
    assert verify(paths, moved, WINDOWS).passed is False
    # Nothing given for window 1: the pair is still compared (Shapely has a line there).
    missing = dataclasses.replace(r, paths=r.paths.take([0]), source=r.source[:1],
                                  window=r.window[:1], window_offsets=np.array([0, 1, 1, 1, 1]))
    v = verify(paths, missing, WINDOWS)
    assert v.passed is False and v.inputs == 2


def test_verify_wants_the_windows_the_result_was_clipped_to():
    paths = parse_paths(["M-1 1H9"])
    r = clip_paths(paths, windows=WINDOWS)
    with pytest.raises(InvalidWindowError, match="windows the result was clipped to"):
        verify(paths, r, WINDOWS[:2])


def test_verify_compares_every_pair_of_a_ragged_clip():
    lines = [shapely.LineString([(-5, 1), (15, 1), (15, 8), (1, 8)]),
             shapely.Polygon([(2, 2), (8, 2), (8, 8), (2, 2)])]
    for geometries in ([lines[0]], [lines[1]]):
        triple = shapely.to_ragged_array(geometries)
        r = rnsca.clip_ragged(*triple, windows=WINDOWS)
        v = verify(triple, r, WINDOWS)
        assert v.passed and v.inputs == 3
        shifted = dataclasses.replace(r, coords=r.coords + 0.25)
        assert verify(triple, shifted, WINDOWS).passed is False


def test_verify_compares_every_pair_of_a_geojson_clip():
    document = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": shapely.geometry.mapping(g)}
        for g in (shapely.LineString([(-5, 1), (15, 1)]), shapely.Point(6, 1),
                  shapely.box(1, 1, 8, 8))]}
    result = rnsca.clip_geojson_windows(document, WINDOWS)
    v = verify(None, result, WINDOWS)
    assert v.passed and v.inputs == 2 + 1 + 3
    assert verify(None, result, None).inputs == v.inputs  # the windows it holds
