"""The Numba backend: count, prefix-sum, write over the parallel segment kernel."""

from __future__ import annotations

import numpy as np

from rnsca.kernels import counters as C
from rnsca.kernels import segments as K
from rnsca.options import Backend, Method, Mode, SegmentOptions
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = ["NumbaBackend"]

_METHOD_ID = {
    Method.RNSCA: K.RNSCA,
    Method.COHEN_SUTHERLAND: K.COHEN_SUTHERLAND,
    Method.LIANG_BARSKY: K.LIANG_BARSKY,
    Method.NICHOLL_LEE_NICHOLL: K.NICHOLL_LEE_NICHOLL,
    Method.MIDPOINT: K.MIDPOINT,
}
# Segments per prange iteration: large enough that per-block scratch and counters cost
# nothing, small enough that the scratch columns (14 x 16 KiB) stay in L2 cache.
BLOCK_SIZE = 2048
# Inputs of at most this many blocks run on the calling thread (see the serial driver).
SERIAL_BLOCKS = 4


class NumbaBackend:
    """Run the Numba kernels on the CPU, in parallel over blocks of segments."""

    kind = Backend.NUMBA

    def clip_segments(self, segments: np.ndarray, window: Window, options: SegmentOptions):
        """Return ``(pieces, source, t, stats)``; see `ClipBackend.clip_segments`."""
        n = segments.shape[0]
        n_blocks = max(1, -(-n // BLOCK_SIZE))
        args = (segments, window.xmin, window.ymin, window.xmax, window.ymax,
                _METHOD_ID[options.method], options.n, options.max_depth, options.tolerance,
                options.auto_piece, options.mode is Mode.EXACT, BLOCK_SIZE)
        driver = K.clip_segment_blocks_serial if n_blocks <= SERIAL_BLOCKS \
            else K.clip_segment_blocks
        block_count = np.zeros(n_blocks, dtype=np.int64)
        counters = np.zeros((n_blocks, C.WIDTH), dtype=np.int64)
        no_pieces = (np.empty((0, 4)), np.empty(0, dtype=np.int64), np.empty((0, 2)))
        driver(*args, False, np.zeros(n_blocks, dtype=np.int64), *no_pieces,
                              block_count, counters)
        block_start = np.zeros(n_blocks, dtype=np.int64)
        np.cumsum(block_count[:-1], out=block_start[1:])
        m = int(block_count.sum())
        pieces = np.empty((m, 4), dtype=np.float64)
        source = np.empty(m, dtype=np.int64)
        t = np.empty((m, 2), dtype=np.float64)
        driver(*args, True, block_start, pieces, source, t,
                              np.empty(n_blocks, dtype=np.int64), np.zeros_like(counters))
        return pieces, source, t, ClipStats.from_counters(counters, n, m)

    def warm_up(self) -> None:
        """Compile (or load from the cache) the kernels, so the first real call is fast."""
        window = Window(0.0, 0.0, 1.0, 1.0)
        for n in (1, BLOCK_SIZE * (SERIAL_BLOCKS + 1)):  # both drivers
            segments = np.tile([[-1.0, 0.5, 2.0, 0.5]], (n, 1))
            for method in Method:
                self.clip_segments(segments, window, SegmentOptions.resolve(window, method=method))
