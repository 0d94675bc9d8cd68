"""Vector tiles of clipped segments: the last step of clip, tile, encode, on any backend.

`encode_segment_tiles` takes the pieces of a many-window clip
(``rnsca.clip_segments(segments, windows=tiles)``: sorted by window, with
``window_offsets``) and returns one Mapbox Vector Tile (specification 2.1) per window,
of one layer: each piece a LINESTRING feature, its id the input segment it came from.
On the OpenCL backend the pieces stay on the device, where the clip left them, and only
the tiles' bytes come back (`rnsca.backends.opencl.tiles`); the Numba backend encodes
with the kernels of `rnsca.tiles.encode_zoom` (`rnsca.kernels.mvt`). The bytes are the
same on both.

Examples
--------
>>> import rnsca
>>> windows = [(0, 0, 10, 10), (10, 0, 20, 10), (20, 0, 30, 10)]
>>> tiled = rnsca.clip_segments([[5, 5, 15, 5], [25, 1, 25, 1.001]], windows=windows)
>>> tiles = encode_segment_tiles(tiled, windows, extent=16)
>>> len(tiles), [len(tiles.tile(w)) for w in range(len(tiles))]
(3, [30, 30, 0])
>>> tiles.tile(0).hex(" ")
'1a 1c 0a 08 73 65 67 6d 65 6e 74 73 12 0c 08 00 18 02 22 06 09 10 10 0a 10 00 28 10 78 02'

Tile 2 is empty: its piece is 0.001 units long, less than a tile unit (10 / 16), and its
two ends round to one position.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rnsca.backends.auto import backend_for
from rnsca.backends.base import Operation, TileLayer
from rnsca.clip import is_device_array
from rnsca.errors import (
    BackendUnavailableError,
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
)
from rnsca.many_windows import as_windows
from rnsca.options import Backend
from rnsca.stats import DeviceStats
from rnsca.tiles.vector_tile import Layer

__all__ = ["EncodedTiles", "MAX_EXTENT", "encode_segment_tiles"]

#: The largest extent (tile units per side), as `rnsca.tiles.tile_table` takes it.
MAX_EXTENT = 2**20


@dataclass(frozen=True, slots=True)
class EncodedTiles:
    """Vector tiles, one per window, back to back in one buffer.

    Attributes
    ----------
    data : ndarray of uint8
        Every tile's ``Tile`` message, in window order.
    offsets : ndarray of int64, shape (k + 1,)
        Tile ``w`` is ``data[offsets[w]:offsets[w + 1]]``; empty (no bytes) where no
        feature is left.
    backend : Backend
        The backend that encoded them.
    device : DeviceStats or None
        A device's transfers and times.
    """

    data: np.ndarray
    offsets: np.ndarray
    backend: Backend
    device: DeviceStats | None = None

    def __len__(self) -> int:
        return self.offsets.shape[0] - 1

    def tile(self, w: int) -> bytes:
        """Return tile `w`'s bytes (``b""`` for a tile with no feature)."""
        return self.data[self.offsets[w]:self.offsets[w + 1]].tobytes()


def encode_segment_tiles(result: Any, windows: npt.ArrayLike, *, extent: int = 4096,
                         layer: str = "segments",
                         backend: Backend | str | None = None) -> EncodedTiles:
    """Return the pieces of each window as a Mapbox Vector Tile (one layer, `layer`).

    Parameters
    ----------
    result : SegmentClipResult
        Of ``rnsca.clip_segments(..., windows=windows)``: the pieces sorted by window,
        with ``window_offsets``; its ``source`` (if kept) gives the features' ids. From
        the OpenCL backend on device input, its device arrays are encoded where they are.
    windows : array_like, shape (k, 4)
        The windows the pieces were clipped to: tile ``w`` spans ``windows[w]``.
    extent : int in 1..MAX_EXTENT
        Tile units per side (default 4096).
    layer : str
        The layer's name (not empty).
    backend : {"numba", "opencl", "auto"}, optional
        Default: OpenCL for pieces on a device, else Numba.

    Returns
    -------
    EncodedTiles
        ``k`` tiles. Tile ``w`` holds a LINESTRING feature per piece: id the piece's
        source (no id without ``source``), no tags, the geometry MoveTo its first end,
        LineTo its second (MVT 4.3). A piece end ``(x, y)`` in window
        ``(x0, y0, x1, y1)`` is at ``floor((x - x0) * sx + 0.5)``,
        ``floor((y1 - y) * sy + 0.5)`` (y down), with ``sx = extent / (x1 - x0)`` and
        ``sy = extent / (y1 - y0)`` computed once per window in float64, every operation
        rounded on its own (no fused multiply-add) on every backend. A piece whose ends
        round to one position is left out (a line needs two, MVT 4.3.4); a tile left
        with no feature has no bytes. The layer's extent is `extent`, its version 2.

    Raises
    ------
    InvalidOptionError
        For an extent or layer name out of range, or a `result` that is not the
        many-window clip of `windows` (no ``window_offsets``, or another count).
    InvalidWindowError
        For bad windows, or one so narrow that its scale overflows.
    InvalidGeometryError
        For a piece 2**30 tile units or more from its tile's origin (not a piece of
        that window), or pieces on a device asked of a backend without device arrays.
    BackendUnavailableError
        If `backend` cannot run here, or cannot encode tiles (OpenCL in float32).
    """
    if isinstance(extent, bool) or not isinstance(extent, int | np.integer) or not (
            1 <= extent <= MAX_EXTENT):
        raise InvalidOptionError(f"extent must be an int in 1..{MAX_EXTENT}, got {extent!r}")
    if not isinstance(layer, str) or not layer:
        raise InvalidOptionError(f"layer must be a non-empty name, got {layer!r}")
    window_offsets = getattr(result, "window_offsets", None)
    if window_offsets is None:
        raise InvalidOptionError(
            "result has no window_offsets: encode the result of "
            "rnsca.clip_segments(segments, windows=windows), pieces sorted by window")
    table = as_windows(windows)
    window_offsets = np.ascontiguousarray(window_offsets, dtype=np.int64)
    pieces, source = result.segments, result.source
    m = int(pieces.shape[0])
    if (window_offsets.ndim != 1 or window_offsets.shape[0] != table.shape[0] + 1
            or window_offsets[0] != 0 or window_offsets[-1] != m
            or (np.diff(window_offsets) < 0).any()):
        raise InvalidOptionError(
            f"result's window_offsets (shape {window_offsets.shape}, "
            f"{window_offsets[-1:].tolist()} pieces) do not match the {table.shape[0]} "
            f"windows and {m} pieces: pass the windows the result was clipped with")
    with np.errstate(over="ignore"):
        scales = extent / (table[:, 2:] - table[:, :2])
    good = (np.isfinite(scales) & (scales > 0)).all(axis=1)
    if not good.all():
        row = int(np.argmin(good))
        raise InvalidWindowError(
            f"window {row} {table[row].tolist()} is too narrow or too wide for {extent} "
            "tile units (extent / width is not a finite float64 above 0)")
    quantisation = np.ascontiguousarray(np.column_stack(
        [table[:, 0], table[:, 3], scales[:, 0], scales[:, 1]]))
    # The layer's other fields, as protobuf serializes them: before the features (name,
    # 1) and after them (extent, 5; version, 15).
    fields = TileLayer(window_offsets, quantisation,
                       np.frombuffer(Layer(name=layer).SerializePartialToString(), np.uint8),
                       np.frombuffer(Layer(version=2, extent=int(extent))
                                     .SerializePartialToString(), np.uint8))
    on_device = is_device_array(pieces)
    if backend is None:
        backend = Backend.OPENCL if on_device else Backend.NUMBA
    engine = backend_for(backend, Operation.TILES.value, m)
    capabilities = engine.capabilities
    if not capabilities.supports(Operation.TILES):
        raise BackendUnavailableError(
            f"backend {engine.kind.value!r} does not encode tiles here (it runs "
            f"{capabilities.precision.value}; the tiles' quantisation is float64's on every "
            "backend): use a float64 device, or backend='numba' on the pieces brought to "
            "the host")
    if on_device and not capabilities.device_arrays:
        raise InvalidGeometryError(
            "the pieces are in pyopencl arrays, on an OpenCL device: encode them with "
            "backend='opencl', or bring them to the host (.get())")
    encoded = engine.encode_segment_tiles(pieces, source, fields)
    return EncodedTiles(encoded.data, encoded.offsets, engine.kind, encoded.device)
