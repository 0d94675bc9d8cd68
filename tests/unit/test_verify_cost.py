"""The crossings estimate that decides, before GEOS is asked, what is too costly to compare."""

import numpy as np
import shapely
from hypothesis import given
from hypothesis import strategies as st

from rnsca.verify.cost import estimated_crossings


def ring_edges(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    closed = np.vstack([points, points[:1]])
    return closed[:-1], closed[1:]


def crossings_by_shapely(start: np.ndarray, end: np.ndarray) -> int:
    """Count pairs of edges whose interiors cross at a point (`shapely.crosses`)."""
    edges = shapely.linestrings(np.stack([start, end], axis=1))
    left, right = shapely.STRtree(edges).query(edges, predicate="crosses")
    return int((left < right).sum())


@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=3, max_size=40))
def test_a_small_ring_is_counted_exactly_as_shapely_sees_its_crossings(points):
    # A small grid: edges along one another, through vertices and touching are common.
    start, end = ring_edges(np.array(points, dtype=float))
    got = estimated_crossings(start, end, np.zeros(start.shape[0], np.int64), 1)
    assert got.tolist() == [crossings_by_shapely(start, end)]


def test_edges_of_other_groups_do_not_count():
    start, end = ring_edges(np.array([[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]]))
    # The same bowtie twice, in two groups: each crosses itself once; an empty third.
    group = np.repeat([0, 1], start.shape[0])
    got = estimated_crossings(np.vstack([start, start]), np.vstack([end, end]), group, 3)
    assert got.tolist() == [1.0, 1.0, 0.0]


def test_a_large_ring_is_estimated_from_a_sample():
    rng = np.random.default_rng(0)
    start, end = ring_edges(rng.uniform(0, 1, (600, 2)))
    exact = crossings_by_shapely(start, end)
    got = estimated_crossings(start, end, np.zeros(600, np.int64), 1)
    assert abs(got[0] - exact) <= 0.25 * exact
    # Seeded: the same edges, the same estimate.
    assert estimated_crossings(start, end, np.zeros(600, np.int64), 1) == got
