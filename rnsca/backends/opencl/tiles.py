"""Vector tiles of segment pieces on an OpenCL device: only the tiles' bytes come back.

`OpenCLBackend.encode_segment_tiles` (the pieces of a many-window clip, sorted by window,
one MVT layer per window) in the steps of the segments' compaction, with the pieces
where they are:

1. ``segment_feature_sizes``: each piece quantised, and the bytes of its feature (0 for
   a piece whose ends round to one position), one work-item per piece; each
   work-group's first piece that does not quantise into MVT's range;
2. an inclusive prefix sum of the sizes (each feature's place in the stream of all);
   ``reduce_first_bad``; ``tile_feature_starts``: each tile's first feature byte in
   that stream, and the first bad piece;
3. one read of those k + 2 numbers; the host lays the tiles out (each tile's size by
   `rnsca.kernels.mvt.tile_sizes`, the Numba backend's framing) and sends up where
   each tile starts (k + 1 numbers);
4. ``write_segment_features`` (each feature at its place in its tile) and
   ``write_tile_frames`` (each tile's header and the layer's last fields), then one
   read of the tiles' bytes.

The features' bytes never cross the bus: what goes up is the pieces (host input only),
the tiles' offsets, quantisation and layer fields, and the layout; what comes down,
the per-tile counts and the tiles.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import pyopencl as cl

from rnsca.backends.base import TileLayer
from rnsca.backends.opencl.runs import Ledger
from rnsca.backends.opencl.segments import _Raw, groups_for
from rnsca.kernels import mvt as MVT

__all__ = ["EncodedOnDevice", "encode_on_device"]


class EncodedOnDevice(NamedTuple):
    """The tiles' bytes and offsets, or (`first_bad` < m) the first piece out of range."""

    data: np.ndarray
    offsets: np.ndarray
    first_bad: int


def encode_on_device(device: Any, kernels: Any, ledger: Ledger, pieces: cl.Buffer,
                     source: cl.Buffer | None, m: int, layer: TileLayer,
                     local_size: int) -> EncodedOnDevice:
    """Encode `m` device pieces (float64 (m, 4)) as one tile per window; see the module.

    `source` is their int64 ids on the device, or None (no ids). The caller holds
    ``device.call_lock`` and settles `ledger` (the final read is awaited here). The
    kernels wait for ``ledger.ready`` (the pieces' staged upload).
    """
    k = layer.window_offsets.shape[0] - 1
    nothing = EncodedOnDevice(np.empty(0, np.uint8), np.zeros(k + 1, np.int64), m)
    if m == 0:
        return nothing
    queue = device.queue
    alloc = device.allocator
    window_offsets = ledger.upload(queue, layer.window_offsets, alloc)
    quantisation = ledger.upload(queue, layer.quantisation, alloc)
    source_or_nowhere = device.nowhere if source is None else source
    groups = groups_for(m, local_size)
    sizes = alloc(8 * m)
    position = alloc(8 * m)
    first_bad = alloc(8 * groups)
    summary = alloc(16)
    starts = alloc(8 * (k + 2))
    counted = kernels.segment_feature_sizes(
        queue, (groups * local_size,), (local_size,), pieces, np.int64(m),
        source_or_nowhere, np.int32(source is not None), window_offsets, np.int64(k),
        quantisation, sizes, first_bad, wait_for=ledger.ready)
    scanned = device.scan()(_Raw(sizes, queue, alloc), _Raw(position, queue, alloc),
                            queue=queue, size=m, allocator=alloc, wait_for=[counted])
    reduced = kernels.reduce_first_bad(queue, (local_size,), (local_size,), first_bad,
                                       np.int64(groups), summary, wait_for=[scanned])
    started = kernels.tile_feature_starts(queue, (k + 2,), None, position, window_offsets,
                                          np.int64(k), summary, starts, wait_for=[reduced])
    ledger.kernel_events += [counted, scanned, reduced, started]
    feature_start = ledger.read(queue, starts, np.int64, k + 2)
    cl.wait_for_events(ledger.copy_events[-1:])
    bad = int(feature_start[k + 1])
    if bad < m:
        return nothing._replace(first_bad=bad)
    # The tiles' layout: the Numba backend's framing of each tile holding a feature.
    offsets = MVT.segment_tile_layout(feature_start[:k + 1], layer.head, layer.tail)[2]
    total = int(offsets[-1])
    if total == 0:
        return EncodedOnDevice(nothing.data, offsets, m)
    tile_start = ledger.upload(queue, offsets, alloc)
    head = ledger.upload(queue, layer.head, alloc)
    tail = ledger.upload(queue, layer.tail, alloc)
    out = alloc(total)
    head_size, tail_size = layer.head.shape[0], layer.tail.shape[0]
    ledger.kernel_events += [
        kernels.write_segment_features(
            queue, (m,), None, pieces, np.int64(m), source_or_nowhere,
            np.int32(source is not None), window_offsets, np.int64(k), quantisation, sizes,
            position, starts, tile_start, np.int64(head_size),
            np.int64(head_size + tail_size), out),
        kernels.write_tile_frames(queue, (k,), None, starts, tile_start, np.int64(k), head,
                                  np.int64(head_size), tail, np.int64(tail_size), out)]
    data = ledger.read(queue, out, np.uint8, total)
    cl.wait_for_events(ledger.copy_events[-1:])
    return EncodedOnDevice(data, offsets, m)
