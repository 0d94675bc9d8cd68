"""The constants that the Numba kernels, the OpenCL kernels and the service share.

Each is defined here once. The Numba kernels import them (Numba reads a module-level int
as a compile-time constant, so this costs nothing at run time) and keep their old names
importable (``from rnsca.kernels.outcode import LEFT`` still works). The OpenCL backend
hands every name in `__all__` to ``clip.cl`` as a build option ``-DNAME=value``
(`rnsca.backends.opencl.constant_options`), and ``clip.cl`` defines none of them itself
(a test reads its text to make sure). The service reads the option bounds from here.

Only plain ints: a value that depends on the precision of the device (Dekker's
splitter, the rounding bounds of ``clip.cl``) is not shared and stays with its kernel.

Numba's on-disk cache keys a compiled kernel on its own source file, not on the values
it read from here: after changing a value, clear the cache
(``find rnsca -name '*.nb[ic]' -delete``; see README, "Development").
"""

__all__ = [
    # Outcode bits and edge ids.
    "LEFT",
    "RIGHT",
    "BOTTOM",
    "TOP",
    "NO_EDGE",
    "EDGE_LEFT",
    "EDGE_RIGHT",
    "EDGE_BOTTOM",
    "EDGE_TOP",
    "SURE_SHIFT",
    "UNSURE_BITS",
    # Segment methods.
    "RNSCA",
    "COHEN_SUTHERLAND",
    "LIANG_BARSKY",
    "NICHOLL_LEE_NICHOLL",
    "MIDPOINT",
    # Option bounds.
    "N_MIN",
    "N_MAX",
    "AUTO_N_BASE",
    "MAX_DEPTH_LIMIT",
    # The counter row.
    "EVALUATED",
    "ACCEPTED",
    "REJECTED",
    "SUBDIVIDED",
    "CLIPPED",
    "DROPPED",
    "INTERSECTIONS",
    "DEEPEST",
    "LEVELS",
    "N_LEVELS",
    "SEGMENT_COUNTERS",
    "RUNS_EVALUATED",
    "RUNS_ACCEPTED",
    "RUNS_REJECTED",
    "RUNS_SUBDIVIDED",
    "RUNS_SEGMENTED",
    "RUN_DEEPEST",
    "INVALID_POLYGONS",
    "RUN_LEVELS",
    "SEGMENT_LEVELS",
    "COUNTERS_WIDTH",
    # Fixed-size stacks and loops.
    "STACK_CAPACITY",
    "CS_MAX_MOVES",
    "RUN_STACK_CAPACITY",
    "CURVE_STACK_CAPACITY",
    # Runs of line segments.
    "RUN_LEAF_SEGMENTS",
    "CHUNK_REJECTED",
    "CHUNK_ACCEPTED",
    "CHUNK_SEGMENTED",
    # Bézier segments and runs of them.
    "SEGMENT_REJECTED",
    "SEGMENT_ACCEPTED",
    "SEGMENT_AMBIGUOUS",
    "CURVE_RUN_ACCEPTED",
    "CURVE_RUN_REJECTED",
    "CURVE_RUN_SEGMENTED",
    "FLATTEN_NONE",
    "FLATTEN_ACCEPTED_CURVES",
    "FLATTEN_ALL",
    # Vector tiles of segment pieces.
    "MVT_COORDINATE_LIMIT",
]

# --- Outcode bits and edge ids (rnsca/kernels/outcode.py draws the nine regions) -------
# One bit per window edge a point lies strictly beyond, so that OR-ing two codes says
# "some end is outside" and AND-ing them "both ends are beyond the same edge". Bit k is
# the edge whose id is k (LEFT == 1 << EDGE_LEFT ...).
LEFT = 1    # x < xmin
RIGHT = 2   # x > xmax
BOTTOM = 4  # y < ymin
TOP = 8     # y > ymax

# Which edge cut an end of a clipped piece: an index 0..3 (the bit position above), or
# NO_EDGE for an end that was not cut (an input end point). Negative, so no edge has it.
NO_EDGE = -1
EDGE_LEFT = 0
EDGE_RIGHT = 1
EDGE_BOTTOM = 2
EDGE_TOP = 3

# Wide codes of interpolated points (see `rnsca.kernels.outcode.wide`): bits 0-3 name
# the edges a point is not surely inside of, bits 4-7 (the outcode shifted by
# SURE_SHIFT) those it is surely beyond. SURE_SHIFT is the width of an outcode, and
# UNSURE_BITS (LEFT | RIGHT | BOTTOM | TOP) masks the low half.
SURE_SHIFT = 4
UNSURE_BITS = 15

# --- Segment methods --------------------------------------------------------------------
# The number each segment kernel (Numba's driver, clip.cl's) dispatches on;
# `rnsca.backends.base.METHOD_ID` maps `rnsca.options.Method` to these. Any distinct
# small ints would do; 0 is RNSCA, the default, tested first.
RNSCA = 0
COHEN_SUTHERLAND = 1
LIANG_BARSKY = 2
NICHOLL_LEE_NICHOLL = 3
MIDPOINT = 4

# --- Option bounds ----------------------------------------------------------------------
# N, the pieces per split: at least 2 (one piece would never shrink), at most 64 (the
# split is a loop per piece, and the stacks below are sized for N <= N_MAX).
N_MIN = 2
N_MAX = 64
# `n="auto"` bisects (N = 2) unless bisection cannot reach the tolerance within the levels
# left (then the smallest N that can, at most N_MAX): approx mode refines each boundary
# crossing like a search, and measured at the default resolution on the four benchmark
# sets (1M segments each, README "Choosing N"), N = 2 was within 7% of the best fixed N on
# every set, 3 within 10%, 8 (the rule before) 1.3x to 3.3x slower.
AUTO_N_BASE = 2
# The deepest subdivision level one may ask for, and the default (`max_depth`): levels
# 0..32, so a piece at the deepest level is at most 2**-32 of its segment (N >= 2). The
# per-level counters (N_LEVELS) and the stacks below are sized by it.
MAX_DEPTH_LIMIT = 32

# --- The counter row (rnsca/kernels/counters.py; read by rnsca.stats) -------------------
# Each kernel block fills one int64 row; the rows are summed, except DEEPEST and
# RUN_DEEPEST, which are maxima. The device fills the same row, slot for slot.
EVALUATED = 0      # fragments whose two outcodes were classified
ACCEPTED = 1       # fragments accepted whole (both outcodes zero)
REJECTED = 2       # fragments rejected whole (outcodes share an outside bit)
SUBDIVIDED = 3     # ambiguous fragments split further
CLIPPED = 4        # ambiguous fragments cut by computing intersections
DROPPED = 5        # ambiguous leaves dropped (approx mode)
INTERSECTIONS = 6  # edge intersection parameters computed (one division each)
DEEPEST = 7        # deepest subdivision level reached (max over blocks)
LEVELS = 8         # first of the per-level "decided" counts
N_LEVELS = MAX_DEPTH_LIMIT + 1  # one count per level 0..MAX_DEPTH_LIMIT
SEGMENT_COUNTERS = LEVELS + N_LEVELS  # the segment counters: the head of the row

# Run-level pruning: a run is a stretch of consecutive segments of a line or ring,
# classified by the outcodes of its bounding box.
RUNS_EVALUATED = SEGMENT_COUNTERS   # runs whose bounding box was classified
RUNS_ACCEPTED = RUNS_EVALUATED + 1  # runs inside the window, copied whole
RUNS_REJECTED = RUNS_EVALUATED + 2  # runs outside one edge, skipped whole
RUNS_SUBDIVIDED = RUNS_EVALUATED + 3  # ambiguous runs split into N runs
RUNS_SEGMENTED = RUNS_EVALUATED + 4  # ambiguous runs short enough to clip segment by segment
RUN_DEEPEST = RUNS_EVALUATED + 5    # deepest run level reached (max over blocks)
INVALID_POLYGONS = RUNS_EVALUATED + 6  # polygons whose clip could not be closed consistently
RUN_LEVELS = RUNS_EVALUATED + 7     # runs decided (accepted, rejected, segmented) per level
SEGMENT_LEVELS = RUN_LEVELS + N_LEVELS  # segments decided by the run decided at each level
COUNTERS_WIDTH = SEGMENT_LEVELS + N_LEVELS  # the length of a row

# --- Fixed-size stacks and loops --------------------------------------------------------
# RNSCA's depth-first stack for one segment. A child is split further only if its two
# wide codes differ, that is, if it crosses one of the eight lines that bound the edges'
# rounding bands (edge +- margin). A segment crosses each line at most once and
# computed points are monotone in t, so at most eight children of a piece are split,
# and the stack holds at most seven pending siblings per level plus the current one:
# 8 per level, for N_LEVELS levels, and one to spare.
STACK_CAPACITY = 8 * (N_LEVELS + 1)
# Cohen–Sutherland's loop bound. In exact arithmetic each end moves at most twice (to an
# edge, then across a corner), so four moves decide every segment. Rounding near a corner
# can make an end moved onto one edge test a hair outside the other edge, whose crossing
# lies at or before that end (t no further on): that bit is rounding noise and is cleared
# without moving the end. Every step either moves an end to a later edge crossing (at
# most 4 per end) or clears one of the at most 2 bits an outcode has, so 32 steps always
# decide the segment.
CS_MAX_MOVES = 32
# Run-level RNSCA's depth-first stack of runs of chunks (Numba's `clip_chains`, and
# `classify_runs` on the device). A run of L chunks split N ways has children of at most
# ceil(L / N) chunks, so it is down to single chunks after ceil(log_N L) splits, and each
# split leaves at most N - 1 siblings pending: a run needs at most
# (N - 1) * ceil(log_N L) + 1 entries. For N <= N_MAX and any L below 2**63 (Numba's
# int64 chunk indices) that is at most 694 (N = 64: 63 * 11 + 1); the device, whose
# chunk indices are 32-bit ints, needs at most 379. Both kernels fall back to clipping a
# run segment by segment rather than overflow, so this size never changes a result; it
# is the device's measured size (private memory per work-item: 9 bytes an entry), and
# the Numba kernel, which had 4096 entries (a bound for N = 2 taken with N = 64's
# siblings), never used more than 694 of them either.
RUN_STACK_CAPACITY = 64 * 34
# The depth-first stack of a Bézier segment's pieces (`bezier.clip_path_blocks`): pieces
# are split at levels 0..MAX_DEPTH_LIMIT - 1, each split leaving at most N - 1 siblings
# pending, and the deepest split needs N entries: 63 * 31 + 64 = 2017 for N <= 64.
# A piece that would overflow it is a leaf instead; 64 * 34 is the size it was measured
# with.
CURVE_STACK_CAPACITY = N_MAX * (N_LEVELS + 1)

# --- Runs of line segments (rnsca/kernels/polylines.py) ---------------------------------
# Runs of at most this many segments (a chunk) are clipped segment by segment: below
# it, a bounding box costs about as much as the segments' own outcode tests.
RUN_LEAF_SEGMENTS = 16
# Decisions of chunks made on a device (the OpenCL backend's `classify_runs`), read by
# the host's assembly (`polylines.assemble_chains`): skipped, copied whole, or clipped
# segment by segment.
CHUNK_REJECTED = 0
CHUNK_ACCEPTED = 1
CHUNK_SEGMENTED = 2

# --- Bézier segments and runs of them (rnsca/kernels/bezier.py) -------------------------
# Classes of a segment decided on a device (the OpenCL backend's ``classify_bezier``) by
# the outcodes of its control points (convex hull): all beyond one edge, all inside, or
# neither; the host's path kernel reads them.
SEGMENT_REJECTED = 0
SEGMENT_ACCEPTED = 1
SEGMENT_AMBIGUOUS = 2
# Decisions of a run of segments by the box of its control points (bezier's count pass
# for its write pass, or ``classify_bezier_runs`` on a device for the host).
CURVE_RUN_ACCEPTED = 0
CURVE_RUN_REJECTED = 1
CURVE_RUN_SEGMENTED = 2
# Which segments ``classify_bezier`` flattens (`OpenCLBackend.classify_curves`'
# ``flatten``: "none", "accepted", "all").
FLATTEN_NONE = 0
FLATTEN_ACCEPTED_CURVES = 1
FLATTEN_ALL = 2

# --- Vector tiles of segment pieces (rnsca/tiles/segment_tiles.py) ---------------------
# A piece's quantised coordinates lie strictly within this many tile units of its tile's
# origin: MVT writes a geometry's deltas as zigzag-encoded 32-bit integers (specification
# 2.1, 4.3.2), and two coordinates within +-2**30 are always less than 2**31 apart. Tested
# before rounding (``|v| < limit`` with ``v = (x - x0) * scale + 0.5``), so no
# conversion to an integer ever overflows, on the host or on a device.
MVT_COORDINATE_LIMIT = 1 << 30
