"""The line kernel's coding pass and run pruning, compiled and (NUMBA_DISABLE_JIT=1) not.

`code_chunks` must give, for every chunk of 16 segments, the OR and AND of its vertices'
codes (the outcode test of the chunk's bounding box, without the box), across the steps
it codes at a time; `clip_lines` must clip long lines exactly as segment-by-segment
clipping does, and refuse a non-finite coordinate wherever it lies.
"""

import math

import numpy as np
import pytest
import shapely

from rnsca import InvalidGeometryError, clip_ragged
from rnsca.kernels import polylines as PL
from rnsca.kernels.outcode import outcode
from rnsca.kernels.records import Window

# Under NUMBA_DISABLE_JIT the kernels run as Python on NumPy scalars, which warn on inf - inf.
pytestmark = pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")

WINDOW = (250.0, 250.0, 750.0, 750.0)
STEP = PL.CODE_STEP_CHUNKS * PL.RUN_LEAF_SEGMENTS  # segments coded per step


def reference_codes(xy, window, strict):
    """Return the vertex codes of `xy` computed one by one."""
    xmin, ymin, xmax, ymax = window
    codes = []
    for x, y in xy:
        code = outcode(x, y, xmin, ymin, xmax, ymax)
        if not (math.isfinite(x) and math.isfinite(y)):
            code |= PL.NOT_FINITE
        if strict and (x <= xmin or x >= xmax or y <= ymin or y >= ymax):
            code |= PL.NOT_STRICTLY_INSIDE
        codes.append(code)
    return np.array(codes)


def wandering_line(n_vertices, seed=0):
    """Return a random walk across [0, 1000]^2 that crosses the window's edges often."""
    rng = np.random.default_rng(seed)
    steps = rng.normal(0.0, 40.0, size=(n_vertices, 2))
    return np.ascontiguousarray(np.abs((np.cumsum(steps, axis=0) + 500.0) % 2000.0 - 1000.0))


@pytest.mark.parametrize("n_segments", [1, 15, 16, 17, 33, STEP - 1, STEP, STEP + 1,
                                        2 * STEP + 7])
@pytest.mark.parametrize("strict", [False, True])
def test_chunk_codes_are_the_or_and_and_of_their_vertices_codes(n_segments, strict):
    first = 3  # the line starts inside the array, as parts do
    xy = wandering_line(first + n_segments + 1 + 2, seed=n_segments)
    if n_segments > 40:
        xy[first + 40] = [WINDOW[0], 500.0]  # a vertex on an edge line
    last = first + n_segments
    n_chunks = PL.chunk_count(first, last)
    chunk_or = np.zeros(n_chunks + 2, dtype=np.uint8)
    chunk_and = np.zeros(n_chunks + 2, dtype=np.uint8)
    codes = np.empty(PL.CODE_SCRATCH_BYTES, dtype=np.uint8)
    line_or, line_and = PL.code_chunks(xy.reshape(-1), first, last, Window(*WINDOW), strict,
                                       codes, chunk_or, chunk_and, 1)
    expected = reference_codes(xy[first:last + 1], WINDOW, strict)
    for k in range(n_chunks):
        members = expected[16 * k:16 * k + 17]
        assert chunk_or[1 + k] == np.bitwise_or.reduce(members), k
        assert chunk_and[1 + k] == np.bitwise_and.reduce(members), k
    assert (chunk_or[0], chunk_or[-1], chunk_and[0], chunk_and[-1]) == (0, 0, 0, 0)
    assert line_or == np.bitwise_or.reduce(expected)
    assert line_and == np.bitwise_and.reduce(expected)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("row", [0, 17, STEP, STEP + 1, 2 * STEP + 6])
def test_chunk_codes_flag_a_non_finite_vertex_in_any_step(bad, row):
    xy = wandering_line(2 * STEP + 7)
    xy[row, row % 2] = bad
    codes = np.empty(PL.CODE_SCRATCH_BYTES, dtype=np.uint8)
    n_chunks = PL.chunk_count(0, xy.shape[0] - 1)
    chunk_or = np.zeros(n_chunks, dtype=np.uint8)
    chunk_and = np.zeros(n_chunks, dtype=np.uint8)
    line_or, _ = PL.code_chunks(xy.reshape(-1), 0, xy.shape[0] - 1, Window(*WINDOW), False,
                                codes, chunk_or, chunk_and, 0)
    assert line_or & PL.NOT_FINITE
    flagged = np.flatnonzero(chunk_or & PL.NOT_FINITE)
    # Chunk k holds vertices 16k to 16k + 16: a vertex on a chunk boundary is in two.
    holding = [k for k in range(n_chunks) if 16 * k <= row <= 16 * k + 16]
    assert flagged.tolist() == holding


@pytest.mark.parametrize("boundary", ["closed", "interior"])
def test_long_lines_are_clipped_as_segment_by_segment_clipping_does(boundary):
    lines = [shapely.LineString(wandering_line(n, seed=n)) for n in (2, 40, STEP + 300,
                                                                     2 * STEP + 17)]
    triple = shapely.to_ragged_array(lines)
    pruned = clip_ragged(*triple, WINDOW, boundary=boundary, keep_empty=True)
    per_segment = clip_ragged(*triple, WINDOW, boundary=boundary, keep_empty=True,
                              method="liang_barsky")
    assert pruned.geometry_type == per_segment.geometry_type
    for level_pruned, level_segment in zip(pruned.offsets, per_segment.offsets, strict=True):
        np.testing.assert_array_equal(level_pruned, level_segment)
    np.testing.assert_allclose(pruned.coords, per_segment.coords, rtol=0, atol=1e-9)
    reference = shapely.intersection(lines, shapely.box(*WINDOW))
    np.testing.assert_allclose(shapely.length(pruned.to_shapely()),
                               shapely.length(reference), rtol=1e-12)


def test_runs_decide_every_segment_once_at_some_level():
    lines = [shapely.LineString(wandering_line(n, seed=n)) for n in (STEP + 300, 5000)]
    stats = clip_ragged(*shapely.to_ragged_array(lines), WINDOW).stats
    assert sum(stats.segments_decided_per_level) == stats.segments_in
    assert stats.runs_accepted > 0 and stats.runs_rejected > 0 and stats.runs_segmented > 0
    assert stats.runs_deepest_level >= 2


@pytest.mark.parametrize("bad", [math.nan, math.inf])
@pytest.mark.parametrize("row", [5, STEP + 2, 2 * STEP + 16])
def test_non_finite_coordinate_deep_in_a_long_line_raises_naming_it(bad, row):
    lines = [shapely.LineString(wandering_line(300)),
             shapely.LineString(wandering_line(2 * STEP + 17, seed=1))]
    kind, coords, offsets = shapely.to_ragged_array(lines)
    coords = coords.copy()
    coords[300 + row, 1] = bad
    with pytest.raises(InvalidGeometryError, match=rf"geometry 1 .*coords\[{300 + row}\]"):
        clip_ragged(kind, coords, offsets, WINDOW)
