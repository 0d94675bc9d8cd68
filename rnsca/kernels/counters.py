"""Layout of the int64 counter row each kernel block fills; read by ``rnsca.stats``.

A row holds the segment counters below, then one "decided" count per subdivision level,
then the counters of run-level pruning (polylines and rings). Rows are summed over
blocks, except ``DEEPEST`` and ``RUN_DEEPEST``, which are maxima.
"""

EVALUATED = 0      # fragments whose two outcodes were classified
ACCEPTED = 1       # fragments accepted whole (both outcodes zero)
REJECTED = 2       # fragments rejected whole (outcodes share an outside bit)
SUBDIVIDED = 3     # ambiguous fragments split further
CLIPPED = 4        # ambiguous fragments cut by computing intersections
DROPPED = 5        # ambiguous leaves dropped (approx mode)
INTERSECTIONS = 6  # edge intersection parameters computed (one division each)
DEEPEST = 7        # deepest subdivision level reached (max over blocks)
LEVELS = 8         # first of the per-level "decided" counts
N_LEVELS = 33      # levels 0..32

# Run-level pruning: a run is a stretch of consecutive segments of a line or ring,
# classified by the outcodes of its bounding box.
RUNS_EVALUATED = LEVELS + N_LEVELS  # runs whose bounding box was classified
RUNS_ACCEPTED = RUNS_EVALUATED + 1  # runs inside the window, copied whole
RUNS_REJECTED = RUNS_EVALUATED + 2  # runs outside one edge, skipped whole
RUNS_SUBDIVIDED = RUNS_EVALUATED + 3  # ambiguous runs split into N runs
RUNS_SEGMENTED = RUNS_EVALUATED + 4  # ambiguous runs short enough to clip segment by segment
RUN_DEEPEST = RUNS_EVALUATED + 5    # deepest run level reached (max over blocks)
INVALID_POLYGONS = RUNS_EVALUATED + 6  # polygons whose clip could not be closed consistently
RUN_LEVELS = RUNS_EVALUATED + 7     # runs decided (accepted, rejected, segmented) per level
SEGMENT_LEVELS = RUN_LEVELS + N_LEVELS  # segments decided by the run decided at each level
WIDTH = SEGMENT_LEVELS + N_LEVELS
