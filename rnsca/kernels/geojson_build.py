"""Ragged arrays from the coordinates `rnsca.kernels.geojson_scan` read.

`build` walks the events of each geometry, given its GeoJSON type, checks them against
the rules of `rnsca.io.geojson` and writes the geometry into one of three ragged arrays:
MULTIPOINT (Point, MultiPoint), MULTILINESTRING (LineString, MultiLineString) and
MULTIPOLYGON (Polygon, MultiPolygon), in document order, in the layout
``rnsca.io.geojson.from_geojson`` gives. It runs twice over one body, as the clip
kernels do: a pass that counts (and checks) and a pass that writes into arrays of the
counted sizes. Serial: the events of a geometry start where the previous one's end.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rnsca.kernels.geojson_scan import CLOSE, OPEN
from rnsca.kernels.jit import inlined, scalar

__all__ = ["BUILT", "CURSOR_SLOTS", "REFUSED", "ROW_SLOTS", "TYPE_CODES", "Layout", "build"]

#: The code of each GeoJSON geometry type in `build`'s ``types``; ``code // 2`` is the
#: array it goes to (0 points, 1 lines, 2 polygons).
TYPE_CODES = {"Point": 0, "MultiPoint": 1, "LineString": 2, "MultiLineString": 3,
              "Polygon": 4, "MultiPolygon": 5}
_POINT, _MULTIPOINT, _LINESTRING, _MULTILINESTRING, _POLYGON, _MULTIPOLYGON = range(6)

#: `build` results: all geometries read, or the first that breaks a rule (the caller's
#: exact reader then names the problem).
BUILT, REFUSED = 0, 1

# `cursor` slots: rows and items written so far, in each array.
_POINT_ROWS, _POINTS = 0, 1
_LINE_ROWS, _PARTS, _LINES = 2, 3, 4
_POLYGON_ROWS, _RINGS, _POLYGONS, _SHAPES = 5, 6, 7, 8
#: The length of `build`'s cursor.
CURSOR_SLOTS = 9
#: The cursor slots, and `Layout` fields, of the three coords arrays.
ROW_SLOTS = (_POINT_ROWS, _LINE_ROWS, _POLYGON_ROWS)


class Layout(NamedTuple):
    """The three ragged arrays `build` writes (offsets int64, innermost level first).

    Offsets start at 0 (set by the caller); coords are float64 (n, 2), or (n, 3) with Z
    NaN for a position of two numbers. In the counting pass, arrays of length 0.
    """

    point_coords: np.ndarray
    point_offsets: np.ndarray     #: positions of each point-like geometry
    line_coords: np.ndarray
    part_offsets: np.ndarray      #: positions of each line part
    line_offsets: np.ndarray      #: parts of each line-like geometry
    polygon_coords: np.ndarray
    ring_offsets: np.ndarray      #: positions of each ring
    polygon_offsets: np.ndarray   #: rings of each polygon
    shape_offsets: np.ndarray     #: polygons of each polygon-like geometry


@inlined
def _position(events, values, e, v, coords, row, write):
    """Read the position at event `e` (numbers from `v`); return (next e or -1, next v).

    A position has two or more numbers, all finite; Z is the third (NaN if absent in a
    3D `coords`), and the numbers after it are dropped.
    """
    count = events[e]
    if count < 2:  # also OPEN: an array where numbers belong
        return -1, v
    for k in range(count):
        if not np.isfinite(values[v + k]):
            return -1, v
    if write and coords.shape[0] > 0:
        coords[row, 0] = values[v]
        coords[row, 1] = values[v + 1]
        if coords.shape[1] == 3:
            coords[row, 2] = values[v + 2] if count >= 3 else np.nan
    return e + 1, v + count


@inlined
def _same_position(values, first, first_count, last, last_count):
    """Return whether two positions are equal: in x, y and Z, or x and y, both 2D."""
    if values[first] != values[last] or values[first + 1] != values[last + 1]:
        return False
    if first_count >= 3 and last_count >= 3:
        return values[first + 2] == values[last + 2]
    return first_count == 2 and last_count == 2


@inlined
def _positions(events, values, e, v, coords, row, write):
    """Read the array of positions at event `e`.

    Returns (next e or -1, next v, number of positions, whether the first and last are
    equal).
    """
    if events[e] != OPEN:
        return -1, v, 0, False
    e += 1
    count = 0
    first, first_count, last, last_count = v, 0, v, 0
    while events[e] != CLOSE:
        last, last_count = v, events[e]
        if count == 0:
            first, first_count = last, last_count
        e, v = _position(events, values, e, v, coords, row + count, write)
        if e < 0:
            return -1, v, 0, False
        count += 1
    closed = count > 0 and _same_position(values, first, first_count, last, last_count)
    return e + 1, v, count, closed


@inlined
def _points(events, values, e, v, kind, out, cursor, write):
    """Read a Point or MultiPoint; return (next e or -1, next v)."""
    row = cursor[_POINT_ROWS]
    if kind == _POINT:
        if events[e] == OPEN and events[e + 1] == CLOSE:  # empty
            e += 2
        else:
            e, v = _position(events, values, e, v, out.point_coords, row, write)
            row += 1
    else:
        e, v, count, _ = _positions(events, values, e, v, out.point_coords, row, write)
        row += count
    cursor[_POINT_ROWS] = row
    cursor[_POINTS] += 1
    if write:
        out.point_offsets[cursor[_POINTS]] = row
    return e, v


@inlined
def _line_part(events, values, e, v, out, cursor, write):
    """Read one line (no part if it is empty); return (next e or -1, next v)."""
    e, v, count, _ = _positions(events, values, e, v, out.line_coords,
                                cursor[_LINE_ROWS], write)
    if e < 0 or count == 1:
        return -1, v
    if count > 0:
        cursor[_LINE_ROWS] += count
        cursor[_PARTS] += 1
        if write:
            out.part_offsets[cursor[_PARTS]] = cursor[_LINE_ROWS]
    return e, v


@inlined
def _geometry(read_one, single, events, values, e, v, out, cursor, write, slot, offsets,
              inner):
    """Read one geometry: one member with `read_one` if `single`, else an array of them.

    A LineString or MultiLineString (`_line_part`), a Polygon or MultiPolygon
    (`_polygon`). The geometry is counted at ``cursor[slot]`` and, if `write`, its end
    written to `offsets`: ``cursor[inner]``, its members' count so far. Return (next e or
    -1, next v).
    """
    if single:
        e, v = read_one(events, values, e, v, out, cursor, write)
    elif events[e] != OPEN:
        return -1, v
    else:
        e += 1
        while e >= 0 and events[e] != CLOSE:
            e, v = read_one(events, values, e, v, out, cursor, write)
        if e >= 0:
            e += 1
    if e < 0:
        return e, v
    cursor[slot] += 1
    if write:
        offsets[cursor[slot]] = cursor[inner]
    return e, v


@inlined
def _polygon(events, values, e, v, out, cursor, write):
    """Read one polygon's rings (no polygon if it has none); return (next e or -1, next v)."""
    if events[e] != OPEN:
        return -1, v
    e += 1
    rings = 0
    while events[e] != CLOSE:
        e, v, count, closed = _positions(events, values, e, v, out.polygon_coords,
                                         cursor[_POLYGON_ROWS], write)
        if e < 0 or count < 4 or not closed:
            return -1, v
        cursor[_POLYGON_ROWS] += count
        cursor[_RINGS] += 1
        if write:
            out.ring_offsets[cursor[_RINGS]] = cursor[_POLYGON_ROWS]
        rings += 1
    if rings > 0:
        cursor[_POLYGONS] += 1
        if write:
            out.polygon_offsets[cursor[_POLYGONS]] = cursor[_RINGS]
    return e + 1, v


@scalar
def build(events, values, types, out, cursor, write):
    """Check every geometry and, if `write`, write it into `out`.

    Parameters
    ----------
    events : int32 array
        The events of `rnsca.kernels.geojson_scan.scan`, every geometry's in turn.
    values : float64 array
        Its numbers (the undecided ones filled in by the caller).
    types : int8 array
        The `TYPE_CODES` code of each geometry.
    out : Layout
        Arrays of the sizes the counting pass gave (``write``), or of length 0. A coords
        array of no rows is not written: the caller already has those positions (the
        values viewed as (n, dim), where they are all of one array and of one dimension).
    cursor : int64 array of `CURSOR_SLOTS`, zeros
        Counts rows, parts, rings, polygons and geometries of each array: after the
        counting pass, the sizes to allocate.
    write : bool

    Returns
    -------
    int
        `BUILT`, or `REFUSED` at the first geometry that breaks a rule: a position of
        fewer than two numbers or a non-finite one, a LineString of one position, a ring
        of fewer than four or not closed, an array nested other than the type says.
    """
    e, v = 0, 0
    for g in range(types.shape[0]):
        kind = types[g]
        if kind <= _MULTIPOINT:
            e, v = _points(events, values, e, v, kind, out, cursor, write)
        elif kind <= _MULTILINESTRING:
            e, v = _geometry(_line_part, kind == _LINESTRING, events, values, e, v, out,
                             cursor, write, _LINES, out.line_offsets, _PARTS)
        else:
            e, v = _geometry(_polygon, kind == _POLYGON, events, values, e, v, out,
                             cursor, write, _SHAPES, out.shape_offsets, _POLYGONS)
        if e < 0:
            return REFUSED
    if e != events.shape[0] or v != values.shape[0]:
        return REFUSED
    return BUILT
