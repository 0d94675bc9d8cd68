"""Mapbox Vector Tile features: geometry commands and feature messages, as protobuf bytes.

Specification 2.1 (github.com/mapbox/vector-tile-spec, 2.1/README.md), section 4.3: a
feature's geometry is a stream of commands, each a uint32 ``id | count << 3`` (MoveTo 1,
LineTo 2, ClosePath 7) followed by ``count`` pairs of parameters, the zigzag-encoded
deltas ``(n << 1) ^ (n >> 31)`` from a cursor that starts at (0, 0) for each feature and
runs on across its parts. Coordinates come quantised (int64 tile units, y down).

What each geometry becomes (the spec's rules, 4.3.4):

- POINT: one MoveTo with every point.
- LINESTRING: per part, consecutive repeated positions dropped; a part of fewer than 2
  positions is dropped; MoveTo 1, LineTo (m - 1).
- POLYGON: per ring, repeated positions dropped, and the closing position (the spec
  closes rings by ClosePath); a ring of fewer than 3 positions, or of zero area, is
  dropped, and with an exterior ring its holes. Exterior rings are written with
  positive area by the surveyor's formula in tile coordinates (clockwise on screen),
  holes with negative: a ring of the wrong sign is written backwards.

A feature left with no geometry is not written (size 0). Each feature is written whole
as a ``Layer.features`` entry (field 2): ``id`` (1, when >= 0), ``tags`` (2, packed),
``type`` (3) and ``geometry`` (4, packed); `feature_sizes` counts, `write_features`
writes, with one body (`_geometry`) for both, so the two cannot disagree.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import prange

from rnsca.kernels.jit import borrowing, parallel

__all__ = ["Features", "Shapes", "feature_sizes", "write_features", "tile_sizes",
           "write_tiles", "segment_tile_layout", "MOVE_TO", "LINE_TO", "CLOSE_PATH", "POINT",
           "LINESTRING", "POLYGON", "REPAIRED"]

MOVE_TO, LINE_TO, CLOSE_PATH = 1, 2, 7
#: Feature kinds (``Tile.GeomType``).
POINT, LINESTRING, POLYGON = 1, 2, 3
#: A polygon read from the second polygon `Shapes` (those repaired after rounding);
#: written as a POLYGON.
REPAIRED = 4


class Shapes(NamedTuple):
    """The quantised geometries of one kind, in the GeoArrow layout.

    `q` int64 (v, 2). POINT: `o0` the point offsets of the geometries. LINESTRING: `o0`
    vertex offsets of the parts, `o1` part offsets of the geometries. POLYGON: `o0` ring
    vertex offsets (rings closed), `o1` ring offsets of the polygons, `o2` polygon
    offsets of the geometries. Unused levels are empty.
    """

    q: np.ndarray
    o0: np.ndarray
    o1: np.ndarray
    o2: np.ndarray


class Features(NamedTuple):
    """The features to write, in order: kind, geometry in its kind's `Shapes`, id, tags.

    `kind` int8 (f,) (`POINT`, `LINESTRING`, `POLYGON`, `REPAIRED`); `index` int64 (f,)
    into its kind's `Shapes`; `fid` int64
    (f,), -1 for none; feature ``i``'s tags are ``tags[tag_offsets[i]:tag_offsets[i +
    1]]`` (uint32 key and value indices, interleaved).
    """

    kind: np.ndarray
    index: np.ndarray
    fid: np.ndarray
    tag_offsets: np.ndarray
    tags: np.ndarray


@borrowing
def _varint_size(value):
    size = 1
    while value >= 128:
        value >>= 7
        size += 1
    return size


@borrowing
def _varint(value, write, out, pos):
    """Write `value` (>= 0) as a varint at `pos` if `write`; return the position after."""
    while value >= 128:
        if write:
            out[pos] = np.uint8((value & 127) | 128)
        value >>= 7
        pos += 1
    if write:
        out[pos] = np.uint8(value)
    return pos + 1


@borrowing
def _zigzag(n):
    return (n << 1) ^ (n >> 63)


@borrowing
def _same(q, a, b):
    return q[a, 0] == q[b, 0] and q[a, 1] == q[b, 1]


@borrowing
def _ring_span(q, first, last):
    """Return ``(b, e)``: a closed ring walks ``first``, then ``b..e``.

    The positions equal to the first one next to it on either side are left out (the
    closing position among them): the walk has no repeated position across its ends,
    so dropping repeated consecutive positions gives the same count both ways round.
    """
    e = last - 2
    while e > first and _same(q, e, first):
        e -= 1
    b = first + 1
    while b <= e and _same(q, b, first):
        b += 1
    return b, e


@borrowing
def _vertex(first, b, e, k, backwards):
    """Return the k-th vertex of the walk ``first, b..e``, forwards or backwards."""
    if k == 0:
        return first
    if backwards:
        return e + 1 - k
    return b + k - 1


@borrowing
def _kept(q, first, b, e):
    """Return how many positions the walk ``first, b..e`` keeps (repeats dropped)."""
    m = 1
    prev = first
    for v in range(b, e + 1):
        if not _same(q, v, prev):
            m += 1
            prev = v
    return m


@borrowing
def _ring_area2(q, first, e):
    """Return twice the surveyor's area of the ring ``first..e`` closed back to first."""
    area = 0
    for v in range(first, e + 1):
        w = v + 1 if v < e else first
        area += q[v, 0] * q[w, 1] - q[w, 0] * q[v, 1]
    return area


@borrowing
def _walk(q, first, b, e, backwards, m, close, cursor, write, out, pos):
    """Emit MoveTo, LineTo (m - 1) and, if `close`, ClosePath: one walk of m positions.

    The walk is ``first, b..e`` (`_vertex`). `cursor` is a 2-element int64 array, the
    command cursor, updated.
    """
    prev = -1
    n = 0
    for k in range(e - b + 2):
        v = _vertex(first, b, e, k, backwards)
        if n > 0 and _same(q, v, prev):
            continue
        if n == 0:
            pos = _varint(MOVE_TO | (1 << 3), write, out, pos)
        elif n == 1:
            pos = _varint(LINE_TO | ((m - 1) << 3), write, out, pos)
        pos = _varint(_zigzag(q[v, 0] - cursor[0]), write, out, pos)
        pos = _varint(_zigzag(q[v, 1] - cursor[1]), write, out, pos)
        cursor[0] = q[v, 0]
        cursor[1] = q[v, 1]
        prev = v
        n += 1
    if close:
        pos = _varint(CLOSE_PATH | (1 << 3), write, out, pos)
    return pos


@borrowing
def _geometry(kind, g, points, lines, polygons, repaired, cursor, write, out, pos):
    """Emit geometry `g` of `kind` from `pos`; return the position after (pos: nothing)."""
    cursor[0] = 0
    cursor[1] = 0
    if kind == POINT:
        first = points.o0[g]
        last = points.o0[g + 1]
        if last > first:
            pos = _varint(MOVE_TO | ((last - first) << 3), write, out, pos)
            for v in range(first, last):
                pos = _varint(_zigzag(points.q[v, 0] - cursor[0]), write, out, pos)
                pos = _varint(_zigzag(points.q[v, 1] - cursor[1]), write, out, pos)
                cursor[0] = points.q[v, 0]
                cursor[1] = points.q[v, 1]
        return pos
    if kind == LINESTRING:
        q = lines.q
        for part in range(lines.o1[g], lines.o1[g + 1]):
            first = lines.o0[part]
            e = lines.o0[part + 1] - 1
            if e <= first:
                continue
            m = _kept(q, first, first + 1, e)
            if m >= 2:
                pos = _walk(q, first, first + 1, e, False, m, False, cursor, write, out,
                            pos)
        return pos
    if kind == REPAIRED:
        polygons = repaired
    q = polygons.q
    for polygon in range(polygons.o2[g], polygons.o2[g + 1]):
        for r in range(polygons.o1[polygon], polygons.o1[polygon + 1]):
            first = polygons.o0[r]
            last = polygons.o0[r + 1]
            if last - first < 4:
                if r == polygons.o1[polygon]:
                    break  # no exterior ring: no polygon
                continue
            b, e = _ring_span(q, first, last)
            area = _ring_area2(q, first, e)
            m = _kept(q, first, b, e)
            if m < 3 or area == 0:
                if r == polygons.o1[polygon]:
                    break
                continue
            exterior = r == polygons.o1[polygon]
            backwards = (area < 0) if exterior else (area > 0)
            pos = _walk(q, first, b, e, backwards, m, True, cursor, write, out, pos)
    return pos


@borrowing
def _tags_bytes(features, i):
    size = 0
    for t in range(features.tag_offsets[i], features.tag_offsets[i + 1]):
        size += _varint_size(features.tags[t])
    return size


@borrowing
def _body_size(features, i, geometry_bytes, tag_bytes):
    size = 2 + 1 + _varint_size(geometry_bytes) + geometry_bytes  # type, geometry
    if features.fid[i] >= 0:
        size += 1 + _varint_size(features.fid[i])
    if tag_bytes > 0:
        size += 1 + _varint_size(tag_bytes) + tag_bytes
    return size


@parallel
def feature_sizes(features, points, lines, polygons, repaired, sizes, geometry_bytes):
    """Write each feature's message size in ``sizes`` (0: no geometry left, not written).

    ``geometry_bytes`` gets the size of its packed geometry, for `write_features`.
    """
    nothing = np.empty(0, dtype=np.uint8)
    for i in prange(features.kind.shape[0]):
        cursor = np.zeros(2, dtype=np.int64)
        g = _geometry(features.kind[i], features.index[i], points, lines, polygons, repaired,
                      cursor, False, nothing, 0)
        geometry_bytes[i] = g
        if g == 0:
            sizes[i] = 0
            continue
        body = _body_size(features, i, g, _tags_bytes(features, i))
        sizes[i] = 1 + _varint_size(body) + body


@parallel
def write_features(features, points, lines, polygons, repaired, starts, sizes, geometry_bytes,
                   out):
    """Write each feature of non-zero size at ``out[starts[i]:]`` (a Layer.features entry)."""
    for i in prange(features.kind.shape[0]):
        if sizes[i] == 0:
            continue
        cursor = np.zeros(2, dtype=np.int64)
        tag_bytes = _tags_bytes(features, i)
        pos = starts[i]
        out[pos] = np.uint8(0x12)  # Layer.features, length-delimited
        pos = _varint(_body_size(features, i, geometry_bytes[i], tag_bytes), True, out,
                      pos + 1)
        if features.fid[i] >= 0:
            out[pos] = np.uint8(0x08)  # Feature.id, varint
            pos = _varint(features.fid[i], True, out, pos + 1)
        if tag_bytes > 0:
            out[pos] = np.uint8(0x12)  # Feature.tags, packed
            pos = _varint(tag_bytes, True, out, pos + 1)
            for t in range(features.tag_offsets[i], features.tag_offsets[i + 1]):
                pos = _varint(features.tags[t], True, out, pos)
        out[pos] = np.uint8(0x18)  # Feature.type, varint
        out[pos + 1] = np.uint8(min(features.kind[i], POLYGON))
        out[pos + 2] = np.uint8(0x22)  # Feature.geometry, packed
        pos = _varint(geometry_bytes[i], True, out, pos + 3)
        _geometry(features.kind[i], features.index[i], points, lines, polygons, repaired,
                  cursor, True, out, pos)


@parallel
def tile_sizes(head, tail, ranges, sizes):
    """Write the size of each tile's ``Tile`` message in ``sizes``.

    Tile ``t`` has one layer: the `head` bytes (its name field), its features' bytes
    ``ranges[t, 0]:ranges[t, 1]`` (of `write_features`' output), its keys' fields
    ``ranges[t, 2]:ranges[t, 3]`` and its values' fields ``ranges[t, 4]:ranges[t, 5]``
    (of their blobs), and the `tail` bytes (its extent and version fields): the fields
    in field-number order, as protobuf writes them.
    """
    for t in prange(sizes.shape[0]):
        layer = _layer_size(head, tail, ranges, t)
        sizes[t] = 1 + _varint_size(layer) + layer


def segment_tile_layout(feature_start: np.ndarray, head: np.ndarray, tail: np.ndarray,
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lay out one tile of one layer per window, each holding a run of features' bytes.

    Tile ``w``'s features are bytes ``feature_start[w]:feature_start[w + 1]`` of the
    features written back to back (k + 1 entries). Returns ``(holding, ranges,
    offsets)``: the tiles holding a feature, their `tile_sizes`/`write_tiles` ranges
    (features only: no keys nor values) and every tile's byte offsets (k + 1; a tile
    with no feature has no bytes). The Numba and OpenCL backends frame tiles by it.
    """
    holding = np.flatnonzero(np.diff(feature_start) > 0)
    ranges = np.zeros((holding.shape[0], 6), dtype=np.int64)
    ranges[:, 0] = feature_start[holding]
    ranges[:, 1] = feature_start[holding + 1]
    held_bytes = np.empty(holding.shape[0], dtype=np.int64)
    tile_sizes(head, tail, ranges, held_bytes)
    offsets = np.zeros(feature_start.shape[0], dtype=np.int64)
    offsets[holding + 1] = held_bytes
    np.cumsum(offsets, out=offsets)
    return holding, ranges, offsets


@borrowing
def _layer_size(head, tail, ranges, t):
    return (head.shape[0] + tail.shape[0] + ranges[t, 1] - ranges[t, 0]
            + ranges[t, 3] - ranges[t, 2] + ranges[t, 5] - ranges[t, 4])


@parallel
def write_tiles(head, tail, features, keys, values, ranges, tile_start, out):
    """Write each tile's ``Tile`` message at ``out[tile_start[t]:]`` (see `tile_sizes`).

    ``Tile.layers`` is field 3, length-delimited (tag 0x1A).
    """
    for t in prange(tile_start.shape[0] - 1):
        pos = tile_start[t]
        out[pos] = np.uint8(0x1A)
        pos = _varint(_layer_size(head, tail, ranges, t), True, out, pos + 1)
        pos = _copy(head, 0, head.shape[0], out, pos)
        pos = _copy(features, ranges[t, 0], ranges[t, 1], out, pos)
        pos = _copy(keys, ranges[t, 2], ranges[t, 3], out, pos)
        pos = _copy(values, ranges[t, 4], ranges[t, 5], out, pos)
        _copy(tail, 0, tail.shape[0], out, pos)


@borrowing
def _copy(source, first, last, out, pos):
    """Copy ``source[first:last]`` to ``out[pos:]``; return the position after."""
    for k in range(first, last):
        out[pos] = source[k]
        pos += 1
    return pos
