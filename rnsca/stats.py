"""ClipStats: what a clipping call did, summed over all its primitives."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from rnsca.kernels import counters as C

__all__ = ["ClipStats"]


@dataclass(frozen=True, slots=True)
class ClipStats:
    """Counters of one clipping call, summed over the input.

    A *fragment* is a whole segment or a piece of one produced by subdivision. Each
    evaluated fragment ends in exactly one of five ways, so
    ``accepted + rejected + subdivided + clipped + dropped == fragments_evaluated``.

    Attributes
    ----------
    segments_in : int
        Input segments.
    pieces_out : int
        Output pieces (at most one per input segment).
    fragments_evaluated : int
        Fragments whose endpoint outcodes were classified (baselines count each
        outcode test of Cohen–Sutherland's loop and each bisection step of midpoint;
        Liang–Barsky and Nicholl–Lee–Nicholl evaluate each segment once).
    accepted : int
        Fragments accepted whole because both outcodes are zero.
    rejected : int
        Fragments rejected whole because their outcodes share an outside bit (or, for
        Liang–Barsky and Nicholl–Lee–Nicholl, rejected by their own tests).
    subdivided : int
        Ambiguous fragments split into further pieces (RNSCA, midpoint).
    clipped : int
        Ambiguous fragments cut by computing intersections (RNSCA exact leaves, each
        cut of Cohen–Sutherland, each segment Liang–Barsky or NLN had to cut).
    dropped : int
        Ambiguous leaves dropped without an intersection (approx mode).
    intersections : int
        Intersection parameters computed against an edge line, one division each,
        counted the same way for every method.
    deepest_level : int
        Deepest subdivision level any fragment reached (0: the whole segment).
    decided_per_level : tuple of int
        Fragments decided (accepted, rejected, clipped or dropped) at each level 0..32.
    """

    segments_in: int
    pieces_out: int
    fragments_evaluated: int
    accepted: int
    rejected: int
    subdivided: int
    clipped: int
    dropped: int
    intersections: int
    deepest_level: int
    decided_per_level: tuple[int, ...]

    @property
    def decided_shallow_fraction(self) -> float:
        """Return the fraction of decided fragments decided at levels 0 and 1 (1.0 if none)."""
        total = sum(self.decided_per_level)
        return 1.0 if total == 0 else sum(self.decided_per_level[:2]) / total

    @classmethod
    def from_counters(cls, rows: np.ndarray, segments_in: int, pieces_out: int) -> ClipStats:
        """Return the stats of per-block counter rows, shape (blocks, counters.WIDTH)."""
        rows = np.asarray(rows, dtype=np.int64).reshape(-1, C.WIDTH)
        total = rows.sum(axis=0)
        deepest = int(rows[:, C.DEEPEST].max()) if rows.shape[0] else 0
        return cls(
            segments_in=int(segments_in),
            pieces_out=int(pieces_out),
            fragments_evaluated=int(total[C.EVALUATED]),
            accepted=int(total[C.ACCEPTED]),
            rejected=int(total[C.REJECTED]),
            subdivided=int(total[C.SUBDIVIDED]),
            clipped=int(total[C.CLIPPED]),
            dropped=int(total[C.DROPPED]),
            intersections=int(total[C.INTERSECTIONS]),
            deepest_level=deepest,
            decided_per_level=tuple(int(v) for v in total[C.LEVELS:C.LEVELS + C.N_LEVELS]),
        )

    def to_dict(self) -> dict:
        """Return the stats as plain JSON-ready values, with the shallow fraction."""
        out = asdict(self)
        out["decided_per_level"] = list(self.decided_per_level)
        out["decided_shallow_fraction"] = self.decided_shallow_fraction
        return out
