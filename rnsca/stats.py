"""ClipStats: what a clipping call did, summed over all its primitives."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from rnsca.kernels import counters as C

__all__ = ["ClipStats", "DeviceStats"]

# The stats that are a counter summed over the blocks, and the counter each one reads.
_TOTALS = (
    ("fragments_evaluated", C.EVALUATED), ("accepted", C.ACCEPTED),
    ("rejected", C.REJECTED), ("subdivided", C.SUBDIVIDED), ("clipped", C.CLIPPED),
    ("dropped", C.DROPPED), ("intersections", C.INTERSECTIONS),
    ("runs_evaluated", C.RUNS_EVALUATED), ("runs_accepted", C.RUNS_ACCEPTED),
    ("runs_rejected", C.RUNS_REJECTED), ("runs_subdivided", C.RUNS_SUBDIVIDED),
    ("runs_segmented", C.RUNS_SEGMENTED), ("invalid_polygons", C.INVALID_POLYGONS),
)
# The per-level stats, and the first of their N_LEVELS counters.
_PER_LEVEL = (
    ("decided_per_level", C.LEVELS), ("runs_decided_per_level", C.RUN_LEVELS),
    ("segments_decided_per_level", C.SEGMENT_LEVELS),
)


@dataclass(frozen=True, slots=True)
class DeviceStats:
    """Where an OpenCL clip ran, in what precision, and what moved between host and device.

    Times come from OpenCL event profiling (device clock), so they exclude Python's own
    overhead; their sum is below the call's wall time.

    Attributes
    ----------
    device : str
        ``"<platform> / <device>"`` of the device that ran the kernels.
    precision : str
        ``"float64"`` or ``"float32"`` (see README, "OpenCL backend").
    transfers : int
        Host-device copies, both directions.
    bytes_to_device, bytes_from_device : int
        Bytes copied each way.
    transfer_seconds : float
        Time the copies took.
    kernel_seconds : float
        Time the kernels took (clip, prefix sum, write).
    """

    device: str
    precision: str
    transfers: int = 0
    bytes_to_device: int = 0
    bytes_from_device: int = 0
    # Times vary run to run: two stats of the same work compare equal without them.
    transfer_seconds: float = dataclasses.field(default=0.0, compare=False)
    kernel_seconds: float = dataclasses.field(default=0.0, compare=False)

    @classmethod
    def combine(cls, parts: Iterable[DeviceStats | None]) -> DeviceStats | None:
        """Return the sum of several calls' device stats (None if there are none)."""
        present = [part for part in parts if part is not None]
        if not present:
            return None
        names = {part.device for part in present}
        precisions = {part.precision for part in present}
        return cls(
            device=present[0].device if len(names) == 1 else ", ".join(sorted(names)),
            precision=present[0].precision if len(precisions) == 1
            else ", ".join(sorted(precisions)),
            **{name: sum(getattr(part, name) for part in present)
               for name in ("transfers", "bytes_to_device", "bytes_from_device",
                            "transfer_seconds", "kernel_seconds")})


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
    geometries_in, geometries_out : int
        Input geometries, and output geometries that are not empty (geometry clips).
    vertices_in, vertices_out : int
        Input and output coordinates (geometry clips).
    runs_evaluated, runs_accepted, runs_rejected, runs_subdivided, runs_segmented : int
        Runs of a line or ring whose bounding box was classified; those copied whole,
        skipped whole, split into N runs, and clipped segment by segment.
    runs_deepest_level : int
        Deepest run level reached (0: whole parts and rings).
    runs_decided_per_level : tuple of int
        Runs decided (accepted, rejected or segmented) at each run level 0..32 (deeper
        levels count in the last).
    segments_decided_per_level : tuple of int
        Segments decided by the run decided at each run level: pruning at level 0 or 1
        means whole parts were accepted or rejected in one bounding-box test.
    invalid_polygons : int
        Polygons whose cut rings could not be closed consistently (invalid input:
        self-intersecting or with stray holes); clipped ring by ring, not repaired.
    device : DeviceStats or None
        The OpenCL backend's device, precision, transfers and times; None elsewhere.
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
    geometries_in: int = 0
    geometries_out: int = 0
    vertices_in: int = 0
    vertices_out: int = 0
    runs_evaluated: int = 0
    runs_accepted: int = 0
    runs_rejected: int = 0
    runs_subdivided: int = 0
    runs_segmented: int = 0
    runs_deepest_level: int = 0
    runs_decided_per_level: tuple[int, ...] = (0,) * C.N_LEVELS
    segments_decided_per_level: tuple[int, ...] = (0,) * C.N_LEVELS
    invalid_polygons: int = 0
    device: DeviceStats | None = None

    @property
    def decided_shallow_fraction(self) -> float:
        """Return the fraction of decided fragments decided at levels 0 and 1 (1.0 if none)."""
        total = sum(self.decided_per_level)
        return 1.0 if total == 0 else sum(self.decided_per_level[:2]) / total

    @classmethod
    def from_counters(cls, rows: np.ndarray, segments_in: int, pieces_out: int,
                      **geometry: Any) -> ClipStats:
        """Return the stats of per-block counter rows, shape (blocks, counters.WIDTH).

        `geometry` holds the counts only the caller knows (``geometries_in``, ...).
        """
        rows = np.asarray(rows, dtype=np.int64).reshape(-1, C.WIDTH)
        # One conversion to Python ints, then slices: this runs on every clip call, and
        # per-value conversions cost more than small clips themselves.
        total = rows.sum(axis=0).tolist()
        deepest = [int(rows[:, C.DEEPEST].max()), int(rows[:, C.RUN_DEEPEST].max())] \
            if rows.shape[0] else [0, 0]
        fields: dict[str, Any] = {name: total[column] for name, column in _TOTALS}
        fields.update((name, tuple(total[column:column + C.N_LEVELS]))
                      for name, column in _PER_LEVEL)
        return cls(segments_in=int(segments_in), pieces_out=int(pieces_out),
                   deepest_level=deepest[0], runs_deepest_level=deepest[1], **fields,
                   **geometry)

    @classmethod
    def combine(cls, parts: Iterable[ClipStats]) -> ClipStats:
        """Return the stats of several clipping calls taken as one.

        Counters and per-level tuples add up; the deepest levels are the deepest of
        any part. No parts give all-zero stats.

        Examples
        --------
        >>> a = ClipStats(2, 1, 3, 1, 1, 1, 0, 0, 2, 1, (1, 2) + (0,) * 31)
        >>> b = ClipStats(1, 1, 1, 1, 0, 0, 0, 0, 0, 0, (1,) + (0,) * 32)
        >>> c = ClipStats.combine([a, b])
        >>> c.segments_in, c.deepest_level, c.decided_per_level[:2]
        (3, 1, (2, 2))
        """
        parts = list(parts)
        values: dict[str, Any] = {}
        for field in fields(cls):
            column = [getattr(part, field.name) for part in parts]
            if field.name == "device":
                values[field.name] = DeviceStats.combine(column)
            elif field.name in ("deepest_level", "runs_deepest_level"):
                values[field.name] = max(column, default=0)
            elif field.name.endswith("per_level"):
                total = np.sum(column, axis=0, dtype=np.int64) if column \
                    else np.zeros(C.N_LEVELS, np.int64)
                values[field.name] = tuple(np.asarray(total).tolist())
            else:
                values[field.name] = sum(column)
        return cls(**values)

    def to_dict(self) -> dict:
        """Return the stats as plain JSON-ready values, with the shallow fraction."""
        # Field by field: `dataclasses.asdict` deep-copies each of the 99 per-level
        # counts, which was 38% of a small GeoJSON request's conversion (service load run).
        out = {name: getattr(self, name) for name in _FIELD_NAMES}
        for name in ("decided_per_level", "runs_decided_per_level",
                     "segments_decided_per_level"):
            out[name] = list(out[name])
        if self.device is not None:
            out["device"] = asdict(self.device)
        out["decided_shallow_fraction"] = self.decided_shallow_fraction
        return out


_FIELD_NAMES = tuple(field.name for field in fields(ClipStats))
