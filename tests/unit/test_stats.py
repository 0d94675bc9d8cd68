"""ClipStats: the counters' invariants, for every method, mode and backend.

Every evaluated fragment ends in exactly one of five ways (accepted, rejected,
subdivided, clipped, dropped), every fragment that is not subdivided is decided at one
level, and the analytic methods never subdivide. These hold exactly, whatever the input,
so they are checked on seeded random batches that mix every kind of segment.
"""

import json

import numpy as np
import pytest

from rnsca import Backend, ClipStats, Method, Mode, clip_segments
from rnsca.kernels import counters as C
from rnsca.options import MAX_DEPTH_LIMIT

W10 = (0.0, 0.0, 10.0, 10.0)
ANALYTIC = (Method.COHEN_SUTHERLAND, Method.LIANG_BARSKY, Method.NICHOLL_LEE_NICHOLL)
SUBDIVIDING = (Method.RNSCA, Method.MIDPOINT)
# Options that make the subdivision methods work at several depths (tolerances are in
# window units); None: the defaults.
OPTION_SETS = {
    "defaults": {},
    "n3-tol0.01": {"n": 3, "tolerance": 0.01},
    "n64-depth4": {"n": 64, "max_depth": 4, "tolerance": 1e-6},
    "auto-depth0": {"max_depth": 0, "tolerance": 1e-6},
    "n2-tol1e-12": {"n": 2, "tolerance": 1e-12},
}


def mixed_batch(rng, n=300):
    """Random, lattice (on edges and corners), long, and zero-length segments around W10."""
    random = rng.uniform(-15.0, 25.0, size=(n, 4))
    lattice = rng.integers(-2, 7, size=(n, 4)) * 2.5
    centre = rng.uniform(0.0, 10.0, size=(n, 2))
    direction = rng.normal(size=(n, 2)) * 10.0 ** rng.uniform(0, 6, size=(n, 1))
    long = np.concatenate([centre - direction, centre + direction], axis=1)
    zero = np.repeat(rng.uniform(-5.0, 15.0, size=(n // 4, 2)), 2, axis=0).reshape(-1, 4)
    return np.concatenate([random, lattice, long, zero])


@pytest.fixture(scope="module", params=list(OPTION_SETS), ids=str)
def options(request):
    return OPTION_SETS[request.param]


def test_counter_invariants_hold_on_a_mixed_batch(rng, method, mode, backend, options):
    segs = mixed_batch(rng)
    r = clip_segments(segs, W10, method=method, mode=mode, backend=backend, **options)
    s = r.stats
    assert s.segments_in == segs.shape[0]
    assert s.pieces_out == len(r)
    assert len(s.decided_per_level) == C.N_LEVELS == MAX_DEPTH_LIMIT + 1
    counts = (s.fragments_evaluated, s.accepted, s.rejected, s.subdivided, s.clipped,
              s.dropped, s.intersections, s.deepest_level, *s.decided_per_level)
    assert min(counts) >= 0
    assert s.accepted + s.rejected + s.subdivided + s.clipped + s.dropped == s.fragments_evaluated
    assert sum(s.decided_per_level) == s.fragments_evaluated - s.subdivided
    assert s.deepest_level <= r.options.max_depth
    assert not any(s.decided_per_level[s.deepest_level + 1:])
    assert s.fragments_evaluated >= s.segments_in
    assert s.pieces_out <= s.segments_in
    if s.deepest_level > 0:
        assert s.decided_per_level[s.deepest_level] > 0
    if r.mode is Mode.EXACT:
        assert s.dropped == 0
    if method in ANALYTIC:
        assert s.subdivided == 0 and s.dropped == 0 and s.deepest_level == 0
        assert s.decided_per_level[0] == s.fragments_evaluated
    else:
        if mode is Mode.APPROX:
            assert s.intersections == 0 and s.clipped == 0
        else:
            # A clipped leaf tests only the edges its end outcodes flag: at most 4.
            assert s.intersections <= 4 * s.clipped


def test_rnsca_with_fixed_n_evaluates_n_children_per_split(rng, mode, backend):
    segs = mixed_batch(rng)
    for n in (2, 3, 64):
        s = clip_segments(segs, W10, n=n, mode=mode, tolerance=1e-3, backend=backend).stats
        assert s.fragments_evaluated == s.segments_in + n * s.subdivided


def test_rnsca_with_auto_n_evaluates_2_to_64_children_per_split(rng, mode, backend):
    s = clip_segments(mixed_batch(rng), W10, mode=mode, tolerance=1e-3, backend=backend).stats
    children = s.fragments_evaluated - s.segments_in
    assert 2 * s.subdivided <= children <= 64 * s.subdivided


def test_rnsca_has_at_most_four_undecided_leaves_per_segment(rng, mode, backend):
    # A leaf left undecided contains a crossing of an edge line; a segment crosses each
    # of the four lines at most once.
    segs = mixed_batch(rng)
    s = clip_segments(segs, W10, mode=mode, tolerance=1e-9, backend=backend).stats
    assert s.clipped + s.dropped <= 4 * s.segments_in


def test_midpoint_has_at_most_two_final_brackets_per_segment(rng, mode, backend):
    segs = mixed_batch(rng)
    s = clip_segments(segs, W10, method="midpoint", mode=mode, tolerance=1e-9,
                      backend=backend).stats
    assert s.clipped + s.dropped <= 2 * s.segments_in


@pytest.mark.parametrize("method", [Method.LIANG_BARSKY, Method.NICHOLL_LEE_NICHOLL])
def test_one_pass_methods_evaluate_each_segment_once(rng, method, mode, backend):
    s = clip_segments(mixed_batch(rng), W10, method=method, mode=mode, backend=backend).stats
    assert s.fragments_evaluated == s.segments_in
    assert s.accepted + s.rejected + s.clipped == s.segments_in


def test_liang_barsky_divides_at_most_once_per_edge(rng, backend):
    s = clip_segments(mixed_batch(rng), W10, method="liang_barsky", backend=backend).stats
    assert s.intersections <= 4 * s.segments_in


def test_nicholl_lee_nicholl_computes_at_most_two_intersections_per_segment(rng, backend):
    s = clip_segments(mixed_batch(rng), W10, method="nicholl_lee_nicholl",
                      backend=backend).stats
    assert s.intersections <= 2 * (s.clipped + s.rejected)


def test_cohen_sutherland_computes_one_intersection_per_cut(rng, backend):
    s = clip_segments(mixed_batch(rng), W10, method="cohen_sutherland", backend=backend).stats
    assert s.intersections == s.clipped


@pytest.mark.parametrize("method", ANALYTIC)
def test_analytic_methods_give_the_same_result_in_both_modes(rng, method, backend):
    segs = mixed_batch(rng)
    exact = clip_segments(segs, W10, method=method, mode="exact", backend=backend)
    approx = clip_segments(segs, W10, method=method, mode="approx", backend=backend)
    np.testing.assert_array_equal(exact.segments, approx.segments)
    np.testing.assert_array_equal(exact.t, approx.t)
    assert exact.stats == approx.stats


def test_inside_segments_are_each_accepted_once(rng, method, mode, backend):
    segs = rng.uniform(0.0, 10.0, size=(200, 4))
    s = clip_segments(segs, W10, method=method, mode=mode, backend=backend).stats
    assert (s.fragments_evaluated, s.accepted, s.pieces_out) == (200, 200, 200)
    assert s.decided_per_level[0] == 200
    if method is not Method.LIANG_BARSKY:  # it divides before it knows: 4 per segment
        assert s.intersections == 0


def test_segments_beyond_one_edge_are_each_rejected_once(rng, method, mode, backend):
    segs = rng.uniform(0.0, 10.0, size=(200, 4))
    segs[:, [0, 2]] += 20.0  # both ends right of the window
    s = clip_segments(segs, W10, method=method, mode=mode, backend=backend).stats
    assert (s.fragments_evaluated, s.rejected, s.pieces_out) == (200, 200, 0)
    if method is not Method.LIANG_BARSKY:
        assert s.intersections == 0


def test_stats_sum_over_parallel_blocks(backend):
    # 3 x 10,000 segments span several parallel blocks; the totals are the per-kind sums.
    inside = np.tile([[1.0, 1.0, 2.0, 2.0]], (10_000, 1))
    outside = np.tile([[20.0, 1.0, 30.0, 2.0]], (10_000, 1))
    across = np.tile([[-5.0, 5.0, 15.0, 5.0]], (10_000, 1))
    s = clip_segments(np.concatenate([inside, outside, across]), W10,
                      method="liang_barsky", backend=backend).stats
    assert (s.segments_in, s.pieces_out, s.fragments_evaluated) == (30_000, 20_000, 30_000)
    # Liang-Barsky divides for each edge it is not parallel to, until it rejects: 4 for
    # the inside segment, 2 for the one right of the window, 2 for the horizontal one.
    assert (s.accepted, s.rejected, s.clipped, s.intersections) == (10_000, 10_000, 10_000,
                                                                    80_000)


# --- ClipStats itself ------------------------------------------------------------------------

def row(**values):
    r = np.zeros(C.WIDTH, dtype=np.int64)
    for name, value in values.items():
        r[getattr(C, name.upper())] = value
    return r


def test_from_counters_sums_blocks_and_takes_the_deepest_level():
    a = row(evaluated=5, accepted=2, subdivided=1, clipped=2, intersections=3, deepest=1)
    a[C.LEVELS:C.LEVELS + 2] = [0, 4]
    b = row(evaluated=3, rejected=1, subdivided=1, dropped=1, deepest=4)
    b[C.LEVELS + 4] = 2
    s = ClipStats.from_counters(np.stack([a, b]), segments_in=3, pieces_out=2)
    assert (s.segments_in, s.pieces_out, s.fragments_evaluated) == (3, 2, 8)
    assert (s.accepted, s.rejected, s.subdivided, s.clipped, s.dropped) == (2, 1, 2, 2, 1)
    assert (s.intersections, s.deepest_level) == (3, 4)
    assert s.decided_per_level[:5] == (0, 4, 0, 0, 2)


def test_from_counters_of_no_blocks_is_all_zero():
    s = ClipStats.from_counters(np.zeros((0, C.WIDTH)), segments_in=0, pieces_out=0)
    assert s.fragments_evaluated == 0 and s.deepest_level == 0
    assert s.decided_per_level == (0,) * C.N_LEVELS


def test_decided_shallow_fraction_counts_levels_0_and_1():
    r = row()
    r[C.LEVELS:C.LEVELS + 3] = [1, 2, 5]
    assert ClipStats.from_counters(r, 1, 0).decided_shallow_fraction == 3 / 8


def test_decided_shallow_fraction_of_nothing_decided_is_one():
    assert ClipStats.from_counters(row(), 0, 0).decided_shallow_fraction == 1.0


def test_to_dict_is_json_ready_and_complete(backend):
    s = clip_segments([[-5.0, 5.0, 15.0, 5.0]], W10, backend=backend).stats
    d = json.loads(json.dumps(s.to_dict()))
    assert d["segments_in"] == 1 and d["pieces_out"] == 1
    assert d["decided_per_level"] == list(s.decided_per_level)
    assert d["decided_shallow_fraction"] == 1.0
    assert set(d) == {"segments_in", "pieces_out", "fragments_evaluated", "accepted",
                      "rejected", "subdivided", "clipped", "dropped", "intersections",
                      "deepest_level", "decided_per_level", "decided_shallow_fraction",
                      "geometries_in", "geometries_out", "vertices_in", "vertices_out",
                      "runs_evaluated", "runs_accepted", "runs_rejected", "runs_subdivided",
                      "runs_segmented", "runs_deepest_level", "runs_decided_per_level",
                      "segments_decided_per_level", "invalid_polygons", "device"}
    # Segment clips leave the geometry counters at zero.
    assert d["runs_evaluated"] == 0 and d["runs_decided_per_level"] == [0] * 33
    # Only OpenCL says where it ran and what it moved.
    if backend is Backend.OPENCL:
        assert set(d["device"]) == {"device", "precision", "transfers", "bytes_to_device",
                                    "bytes_from_device", "transfer_seconds", "kernel_seconds"}
        assert d["device"]["precision"] in ("float64", "float32")
    else:
        assert d["device"] is None
