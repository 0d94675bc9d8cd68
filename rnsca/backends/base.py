"""The interface every backend implements."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from rnsca.options import Backend, SegmentOptions
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["ClipBackend"]


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
