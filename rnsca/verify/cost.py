"""What a comparison would cost GEOS where it must node an outline that crosses itself.

Two oracles node an outline: an invalid polygon is made valid (``shapely.make_valid``)
before it is clipped, and a filled path's region is built from its noded outlines
(`rnsca.verify.paths.filled_region`). Both grow faster than the square of the
crossings, and a GEOS call cannot be interrupted: ``make_valid`` of a random ring took
0.3 s for 800 crossings, 2 s for 3,000, 7 s for 6,400 and 80 s for 25,000.
`estimated_crossings` counts them in NumPy from a sample of edges, before any GEOS call,
so that `rnsca.verify` can skip such inputs (``max_crossings``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["estimated_crossings"]

#: Edges of a group tested against all of its edges: a group of at most this many is
#: counted exactly. 64 keeps the cost at 64 tests per edge, and the estimate of a count
#: spread over the edges within about 1 / sqrt(64) = 12 %.
_SAMPLED_EDGES = 64
#: Edge pairs tested at once (about 100 bytes each on their way through: ~100 MB).
_PAIRS_PER_STEP = 1 << 20


def estimated_crossings(start: np.ndarray, end: np.ndarray, group: np.ndarray,
                        groups: int, seed: int = 0) -> np.ndarray:
    """Return, per group of edges, about how many times its edges cross one another.

    Parameters
    ----------
    start, end : ndarray of float64, shape (m, 2)
        The edges' ends.
    group : ndarray of int64, shape (m,)
        The group of each edge, non-decreasing, in ``[0, groups)``.
    groups : int
        Number of groups.
    seed : int
        Seed of the edges sampled in large groups.

    Returns
    -------
    ndarray of float64, shape (groups,)
        Exact for a group of at most 64 edges (every pair is tested). A larger group of
        m edges has 64 edges drawn at random (with replacement), each tested against
        all m, and gives ``m * mean / 2``. Two edges cross when the ends of each lie
        strictly on both sides of the other's line: edges that share an end (neighbours
        along a ring) or only touch do not count.

    Examples
    --------
    >>> bowtie = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    >>> estimated_crossings(bowtie[:-1], bowtie[1:], np.zeros(4, np.int64), 1)
    array([1.])
    """
    counts = np.bincount(group, minlength=groups)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    small = counts[group] <= _SAMPLED_EDGES
    large = np.flatnonzero(counts > _SAMPLED_EDGES)
    drawn = np.repeat(large, _SAMPLED_EDGES)
    rng = np.random.default_rng(seed)
    sampled = np.concatenate([
        np.flatnonzero(small),
        first[drawn] + (rng.random(drawn.shape[0]) * counts[drawn]).astype(np.int64)])
    sampled_group = group[sampled]
    # Each sampled edge stands for this many of its group's edges.
    weight = counts[sampled_group] / np.minimum(counts[sampled_group], _SAMPLED_EDGES)
    total = np.zeros(groups)
    sizes = counts[sampled_group]
    # Consecutive sampled edges whose pairs make one step.
    step_of = np.cumsum(sizes) // _PAIRS_PER_STEP
    bounds = np.flatnonzero(np.diff(step_of)) + 1
    for block in np.split(np.arange(sampled.shape[0]), bounds):
        if not block.size:
            continue
        block_sizes = sizes[block]
        edge = np.repeat(sampled[block], block_sizes)
        # The other edge runs over the sampled edge's whole group.
        offset = np.arange(edge.shape[0]) - np.repeat(np.cumsum(block_sizes) - block_sizes,
                                                      block_sizes)
        other = np.repeat(first[sampled_group[block]], block_sizes) + offset
        crossed = _cross(start[edge], end[edge], start[other], end[other])
        per_edge = np.bincount(np.repeat(np.arange(block.shape[0]), block_sizes),
                               weights=crossed, minlength=block.shape[0])
        np.add.at(total, sampled_group[block], per_edge * weight[block])
    # Every crossing is seen from both of its edges.
    return total / 2.0


def _cross(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Return whether segment a-b and segment c-d cross at a point inside both."""
    with np.errstate(invalid="ignore", over="ignore"):
        return ((np.sign(_side(a, b, c)) * np.sign(_side(a, b, d)) < 0)
                & (np.sign(_side(c, d, a)) * np.sign(_side(c, d, b)) < 0))


def _side(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Return the cross product (b - a) x (p - a): positive where p is left of a-b."""
    return ((b[:, 0] - a[:, 0]) * (p[:, 1] - a[:, 1])
            - (b[:, 1] - a[:, 1]) * (p[:, 0] - a[:, 0]))
