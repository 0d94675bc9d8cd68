"""verify within limits: the time limit, the crossings GEOS may be asked to node, and
inputs that cross themselves (whose comparison used to grow with their crossings)."""

import dataclasses
import types

import numpy as np
import pytest
import shapely
from shapely import from_wkt as wkt

from rnsca import InvalidOptionError, clip, clip_segments, clip_svg, verify
from rnsca.verify import geometry

W10 = (0.0, 0.0, 10.0, 10.0)
SQUARE = wkt("POLYGON ((-5 -5, 5 -5, 5 5, -5 5, -5 -5))")


def random_lines(count: int, vertices: int, low: float = -2.0, high: float = 12.0,
                 seed: int = 0) -> np.ndarray:
    """Lines of random vertices: across the window they cross themselves and each other."""
    rng = np.random.default_rng(seed)
    return shapely.linestrings(rng.uniform(low, high, (count, vertices, 2)))


def ticking_clock(monkeypatch) -> None:
    """Make verify's clock read 0, 1, 2, ... seconds, one second more at each reading."""
    readings = iter(range(10**6))
    monkeypatch.setattr(geometry, "time",
                        types.SimpleNamespace(monotonic=lambda: float(next(readings))))


# --- the time limit ------------------------------------------------------------------------

def test_a_time_limit_already_past_compares_nothing_and_gives_no_verdict():
    lines = random_lines(5, 50)
    v = verify(lines, clip(lines, W10), W10, time_limit=0.0)
    assert (v.inputs, v.checked, v.skipped, v.timed_out, v.passed) == (5, 0, 0, True, None)
    assert v.note == ("stopped at the time limit of 0 s: 5 of the 5 inputs chosen were not "
                      "compared")


def test_the_time_limit_stops_before_the_next_chunk_and_counts_what_was_compared(
        monkeypatch):
    # One input a chunk. Lines inside the window are their own clip, so no search for
    # nearest segments reads the clock: it is read at the start (the deadline is then
    # 3.5) and before each chunk, at 1, 2 and 3 (compared) and 4 (past it).
    ticking_clock(monkeypatch)
    monkeypatch.setattr(geometry, "_CHUNK_VERTICES", 1)
    lines = random_lines(10, 20, 1.0, 9.0)
    v = verify(lines, lines, W10, time_limit=3.5)
    assert (v.inputs, v.checked, v.timed_out, v.passed, v.sampling) == (
        10, 3, True, None, "all")
    assert v.note == ("stopped at the time limit of 3.5 s: 7 of the 10 inputs chosen were "
                      "not compared")


def test_a_failure_found_before_the_time_limit_is_a_verdict(monkeypatch):
    ticking_clock(monkeypatch)
    monkeypatch.setattr(geometry, "_CHUNK_VERTICES", 1)
    lines = random_lines(100, 20, 1.0, 9.0)
    moved = lines.copy()
    moved[0] = shapely.affinity.translate(lines[0], 0.5, 0.0)
    v = verify(lines, moved, W10, time_limit=50.0)
    assert v.timed_out and 0 < v.checked < 100
    assert v.passed is False and v.max_deviation == pytest.approx(0.5)


def test_a_sample_is_cut_short_by_the_time_limit_too(monkeypatch):
    ticking_clock(monkeypatch)
    monkeypatch.setattr(geometry, "_CHUNK_VERTICES", 1)
    lines = random_lines(10, 20, 1.0, 9.0)
    v = verify(lines, lines, W10, sample=5, time_limit=2.5)
    assert (v.inputs, v.checked, v.timed_out, v.passed) == (10, 2, True, None)
    assert v.sampling == "random 5 of 10, seed 0" and "3 of the 5 inputs chosen" in v.note


@pytest.mark.parametrize("limit", [-1.0, float("nan"), "soon"])
def test_a_bad_time_limit_is_refused(limit):
    with pytest.raises(InvalidOptionError, match="time_limit must be"):
        verify(SQUARE, SQUARE, W10, time_limit=limit)


def test_comparing_in_chunks_finds_what_comparing_at_once_does(monkeypatch):
    lines = random_lines(6, 30, seed=1)
    geometries = np.concatenate([lines, [SQUARE, wkt("POINT (3 3)"), wkt("POINT (30 3)")]])
    ours = clip(geometries, W10)
    ours[2] = shapely.affinity.translate(ours[2], 1e-3, 0.0)  # one wrong, found either way
    segments = np.random.default_rng(2).uniform(-5, 15, (50, 4))
    paths = ["M-5 5 L15 5", "M5 -5 C0 5 10 5 5 15", "M-1 -1 L11 11 L-1 11 Z"] * 3
    clipped_paths, _ = clip_svg(paths, W10)
    at_once = (verify(geometries, ours, W10),
               verify(segments, clip_segments(segments, W10), W10),
               verify(paths, clipped_paths, W10))
    monkeypatch.setattr(geometry, "_CHUNK_VERTICES", 1)
    in_chunks = (verify(geometries, ours, W10),
                 verify(segments, clip_segments(segments, W10), W10),
                 verify(paths, clipped_paths, W10))
    assert in_chunks == at_once
    assert not at_once[0].passed and at_once[1].passed and at_once[2].passed


# --- crossings GEOS would node -------------------------------------------------------------

def test_an_invalid_polygon_crossing_itself_too_often_is_skipped_before_geos_nodes_it(
        monkeypatch):
    knot = shapely.Polygon(np.random.default_rng(5).uniform(-2, 12, (40, 2)))
    assert not shapely.is_valid(knot)  # its ~200 crossings made valid: ~0.03 s
    geometries = np.array([knot, SQUARE])
    ours = clip(geometries, W10)
    made_valid, make_valid = [], shapely.make_valid

    def recording(geometry, **kwargs):
        made_valid.append(geometry)
        return make_valid(geometry, **kwargs)

    monkeypatch.setattr(shapely, "make_valid", recording)
    v = verify(geometries, ours, W10, max_crossings=50)
    assert (v.inputs, v.checked, v.skipped, v.timed_out, v.passed) == (2, 1, 1, False, None)
    assert not made_valid and v.invalid_inputs == 0
    assert v.note.startswith("1 inputs skipped: GEOS would have to node an outline crossing "
                             "itself about ")
    assert v.note.endswith("times (the most among them; max_crossings is 50)")
    # Under the limit it is compared (its polygon has no oracle: no say in the verdict).
    v = verify(geometries, ours, W10, max_crossings=10_000)
    assert (v.checked, v.skipped, v.invalid_inputs, v.passed) == (2, 0, 1, True)
    assert made_valid


def test_a_filled_path_crossing_itself_too_often_is_skipped():
    points = np.random.default_rng(6).uniform(-2, 12, (40, 2))
    knot = "M" + " L".join(f"{x} {y}" for x, y in points.tolist()) + " Z"
    paths = [knot, "M-1 -1 L11 11 L-1 11 Z"]
    clipped, _ = clip_svg(paths, W10, fill="nonzero")
    v = verify(paths, clipped, W10, fill="nonzero", max_crossings=50)
    assert (v.inputs, v.checked, v.skipped, v.passed) == (2, 1, 1, None)
    assert verify(paths, clipped, W10, fill="nonzero").passed


@pytest.mark.parametrize("limit", [-5, "many"])
def test_a_bad_crossing_limit_is_refused(limit):
    with pytest.raises(InvalidOptionError, match="max_crossings must be"):
        verify(SQUARE, SQUARE, W10, max_crossings=limit)


# --- inputs that cross themselves ---------------------------------------------------------

def test_lines_lying_over_one_another_are_searched_among_their_own_segments(monkeypatch):
    # 20 lines of 100 random vertices, each crossing the others everywhere. The clip's
    # cut points differ from GEOS's by rounding, so points are searched for; each may
    # meet at most its own line's 99 segments.
    lines = random_lines(20, 100, seed=7)
    ours = clip(lines, W10)
    pairs, points, query = [], [], shapely.STRtree.query

    def recording(tree, geometry, *args, **kwargs):
        found = query(tree, geometry, *args, **kwargs)
        pairs.append(found.shape[-1])
        points.append(len(geometry))
        return found

    monkeypatch.setattr(shapely.STRtree, "query", recording)
    v = verify(lines, ours, W10)
    assert v.passed and dataclasses.asdict(v)["checked"] == 20
    assert points and sum(pairs) <= 99 * sum(points)


def test_segments_beyond_geos_are_skipped_with_the_reason_never_failed():
    # A segment 2e300 long across a 0..10 window: GEOS's cut points are off by about eps
    # times its length, far beyond 1e-9 of the window, while rnsca's are exact (checked
    # against rational arithmetic in tests/property/test_vs_exact.py). Found by fuzzing:
    # verification used to report such correct clips as failed.
    segments = np.array([[-1e300, 5.0, 1e300, 5.0], [-5.0, 5.0, 15.0, 5.0],
                         [1e-160, 1e-160, 3.0, 3.0]])
    result = clip_segments(segments, W10)
    assert result.segments[result.source == 0].tolist() == [[0.0, 5.0, 10.0, 5.0]]
    v = verify(segments, result, W10)
    assert (v.inputs, v.checked, v.skipped, v.passed) == (3, 1, 2, None)
    assert "2 segments skipped: GEOS cannot clip them to 1e-9 of the window" in v.note
    # The segment GEOS can judge is still judged.
    wrong = dataclasses.replace(result, segments=result.segments + (result.source == 1)[:, None])
    assert verify(segments, wrong, W10).passed is False
    assert verify(segments[1:2], clip_segments(segments[1:2], W10), W10).passed is True
