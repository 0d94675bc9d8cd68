"""The interface every backend implements."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from rnsca.kernels import segments as K
from rnsca.options import Backend, Method, SegmentOptions
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["METHOD_ID", "ClipBackend"]

#: The number each segment kernel (Numba and OpenCL) knows a method by.
METHOD_ID = {
    Method.RNSCA: K.RNSCA,
    Method.COHEN_SUTHERLAND: K.COHEN_SUTHERLAND,
    Method.LIANG_BARSKY: K.LIANG_BARSKY,
    Method.NICHOLL_LEE_NICHOLL: K.NICHOLL_LEE_NICHOLL,
    Method.MIDPOINT: K.MIDPOINT,
}


class ClipBackend(Protocol):
    """A place where the clipping kernels run; every backend gives the same pieces."""

    kind: Backend

    def clip_segments(
        self, segments: np.ndarray, window: Window, options: SegmentOptions
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, ClipStats]:
        """Return ``(pieces (m, 4), source (m,), t (m, 2), stats)`` for validated segments.

        `segments` is float64 (n, 4), C-contiguous, finite, with finite differences.
        Pieces come in input order, at most one per segment, all inside the window.
        """
        ...
