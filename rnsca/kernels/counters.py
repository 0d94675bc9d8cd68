"""Layout of the int64 counter row each kernel block fills; read by ``rnsca.stats``.

A row holds the segment counters, then one "decided" count per subdivision level, then
the counters of run-level pruning (polylines and rings). Rows are summed over blocks,
except ``DEEPEST`` and ``RUN_DEEPEST``, which are maxima. The slots are defined, with
what each counts, in `rnsca.constants` (shared with ``clip.cl``, which fills the same
row); this module names them for the kernels, as ``C.EVALUATED`` ... ``C.WIDTH``.
"""

from rnsca.constants import (  # noqa: F401 (re-exported: the kernels read C.<slot>)
    ACCEPTED,
    CLIPPED,
    DEEPEST,
    DROPPED,
    EVALUATED,
    INTERSECTIONS,
    INVALID_POLYGONS,
    LEVELS,
    N_LEVELS,
    REJECTED,
    RUN_DEEPEST,
    RUN_LEVELS,
    RUNS_ACCEPTED,
    RUNS_EVALUATED,
    RUNS_REJECTED,
    RUNS_SEGMENTED,
    RUNS_SUBDIVIDED,
    SEGMENT_LEVELS,
    SUBDIVIDED,
)
from rnsca.constants import COUNTERS_WIDTH as WIDTH  # noqa: F401 (re-exported)
