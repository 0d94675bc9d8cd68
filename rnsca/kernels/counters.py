"""Layout of the int64 counter row each kernel block fills; read by ``rnsca.stats``.

A row holds the scalar counters below, then one "decided" count per subdivision level.
Rows are summed over blocks, except ``DEEPEST`` which is a maximum.
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
WIDTH = LEVELS + N_LEVELS
