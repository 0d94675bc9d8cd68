"""Bézier segments to SVG path data: choose commands, then lay out the bytes.

`classify` picks each segment's command (L, H, V, Q, T, C, S) and whether each subpath
needs its moveto. The caller formats the distinct numbers once (in Python, where
``repr`` and ``%g`` round correctly) into a table of ASCII strings; `write` then copies
the command letters and table entries of every path into one byte buffer, in two passes
with one body (count, prefix sum, write), one path per ``prange`` iteration.
"""

import numpy as np
from numba import prange

from rnsca.kernels.jit import parallel, scalar

__all__ = [
    "KIND_LETTERS",
    "NUMBER_COUNT",
    "COLUMNS",
    "STARTS_WITH_MINUS",
    "STARTS_WITH_DOT",
    "ENDS_IN_FRACTION",
    "classify",
    "write",
]

# Segment kinds and their command letters.
L, H, V, Q, T, C, S = 0, 1, 2, 3, 4, 5, 6
KIND_LETTERS = np.frombuffer(b"LHVQTCS", dtype=np.uint8).copy()
#: Numbers each kind writes.
NUMBER_COUNT = np.array([2, 1, 1, 4, 2, 6, 4], dtype=np.int64)
#: Which of a segment's 8 control values (x0 y0 x1 y1 x2 y2 x3 y3; row 3 is always the
#: end point) each kind writes, in order.
COLUMNS = np.zeros((7, 8), dtype=np.bool_)
for _kind, _columns in ((L, (6, 7)), (H, (6,)), (V, (7,)), (Q, (2, 3, 6, 7)), (T, (6, 7)),
                        (C, (2, 3, 4, 5, 6, 7)), (S, (4, 5, 6, 7))):
    COLUMNS[_kind, list(_columns)] = True

# Flags of a number's text, for the separator rule: no space is needed before a number
# that starts with '-', nor before one that starts with '.' when the previous one has a
# fraction ("1.5.5" is 1.5 then .5).
STARTS_WITH_MINUS = 1
STARTS_WITH_DOT = 2
ENDS_IN_FRACTION = 4

_M = 77
_Z = 90
_SPACE = 32


@scalar
def _reflects(controls, i, row, prev_row):
    """Return whether control `row` of segment i is what the reader infers for S or T.

    That is the reflection ``2 * start - p`` of control `prev_row` of segment i - 1
    (the reader's exact expression, so the test is exact), or the start point itself
    when `prev_row` is -1 (S or T after another command).
    """
    x0 = controls[i, 0, 0]
    y0 = controls[i, 0, 1]
    if prev_row < 0:
        return controls[i, row, 0] == x0 and controls[i, row, 1] == y0
    return (controls[i, row, 0] == 2.0 * x0 - controls[i - 1, prev_row, 0]
            and controls[i, row, 1] == 2.0 * y0 - controls[i - 1, prev_row, 1])


@parallel
def classify(controls, degree, subpath_offsets, closed, start, path_offsets, t_after_t):
    """Return ``(kind, with_moveto)``: int8 (m,) segment kinds, bool (k,) per subpath.

    A subpath needs no moveto when the previous subpath of its path was closed, it
    starts where that one started and it has a segment or is closed (the reader then
    starts it at that point; an empty open one would vanish). Without `t_after_t`, a
    T never follows a T: the reader computes a T's control point from the previous
    one, so with rounded numbers a chain of T would add up the rounding errors.
    """
    m = controls.shape[0]
    k = closed.shape[0]
    n = path_offsets.shape[0] - 1
    kind = np.empty(m, dtype=np.int8)
    with_moveto = np.ones(k, dtype=np.bool_)
    for p in prange(n):
        for s in range(path_offsets[p], path_offsets[p + 1]):
            first = subpath_offsets[s]
            last = subpath_offsets[s + 1]
            if (s > path_offsets[p] and closed[s - 1] and start[s, 0] == start[s - 1, 0]
                    and start[s, 1] == start[s - 1, 1] and (last > first or closed[s])):
                with_moveto[s] = False
            for i in range(first, last):
                d = degree[i]
                prev = degree[i - 1] if i > first else 0
                if d == 1:
                    if controls[i, 3, 1] == controls[i, 0, 1]:
                        kind[i] = H
                    elif controls[i, 3, 0] == controls[i, 0, 0]:
                        kind[i] = V
                    else:
                        kind[i] = L
                elif d == 2:
                    smooth = _reflects(controls, i, 1, 1 if prev == 2 else -1)
                    if smooth and prev == 2 and not t_after_t and kind[i - 1] == T:
                        smooth = False
                    kind[i] = T if smooth else Q
                else:
                    smooth = _reflects(controls, i, 1, 2 if prev == 3 else -1)
                    kind[i] = S if smooth else C
    return kind, with_moveto


@scalar
def _number(out, n, write, table, table_offsets, flags, entry, after_number, after_fraction):
    """Append table `entry`, after a space if the reader needs one; return the new length."""
    f = flags[entry]
    if after_number and not (f & STARTS_WITH_MINUS) and not (
            f & STARTS_WITH_DOT and after_fraction):
        if write:
            out[n] = _SPACE
        n += 1
    a = table_offsets[entry]
    b = table_offsets[entry + 1]
    if write:
        for j in range(a, b):
            out[n + j - a] = table[j]
    return n + b - a


@scalar
def _write_path(p, write, out, at, kind, with_moveto, subpath_offsets, closed, path_offsets,
                seg_values, seg_value_offsets, start_values, start_value_offsets, table,
                table_offsets, flags):
    """Return the byte length of path p's data; with `write`, write it at ``out[at:]``."""
    n = at
    letter = 0                # the command a number without a letter would continue
    after_number = False
    after_fraction = False
    for s in range(path_offsets[p], path_offsets[p + 1]):
        if with_moveto[s]:
            if write:
                out[n] = _M
            n += 1
            after_number = False
            for v in range(start_value_offsets[s], start_value_offsets[s + 1]):
                e = start_values[v]
                n = _number(out, n, write, table, table_offsets, flags, e, after_number,
                            after_fraction)
                after_number = True
                after_fraction = (flags[e] & ENDS_IN_FRACTION) != 0
            letter = KIND_LETTERS[L]  # pairs after a moveto are linetos
        for i in range(subpath_offsets[s], subpath_offsets[s + 1]):
            c = KIND_LETTERS[kind[i]]
            if c != letter:
                if write:
                    out[n] = c
                n += 1
                letter = c
                after_number = False
            for v in range(seg_value_offsets[i], seg_value_offsets[i + 1]):
                e = seg_values[v]
                n = _number(out, n, write, table, table_offsets, flags, e, after_number,
                            after_fraction)
                after_number = True
                after_fraction = (flags[e] & ENDS_IN_FRACTION) != 0
        if closed[s]:
            if write:
                out[n] = _Z
            n += 1
            letter = _Z               # Z does not repeat: the next command has a letter
            after_number = False
    return n - at


@parallel
def write(kind, with_moveto, subpath_offsets, closed, path_offsets, seg_values,
          seg_value_offsets, start_values, start_value_offsets, table, table_offsets, flags):
    """Return ``(text, path_offsets)``: uint8 ASCII of all paths and each one's bounds.

    ``seg_values[seg_value_offsets[i]:seg_value_offsets[i + 1]]`` are the table entries
    segment i writes (`COLUMNS` order); ``start_values`` likewise for the moveto of
    each subpath that has one. Entry e is ``table[table_offsets[e]:table_offsets[e+1]]``
    with separator `flags` e.
    """
    n = path_offsets.shape[0] - 1
    no_out = np.empty(0, dtype=np.uint8)
    sizes = np.zeros(n + 1, dtype=np.int64)
    for p in prange(n):
        sizes[p + 1] = _write_path(p, False, no_out, 0, kind, with_moveto, subpath_offsets,
                                   closed, path_offsets, seg_values, seg_value_offsets,
                                   start_values, start_value_offsets, table, table_offsets,
                                   flags)
    bounds = np.cumsum(sizes)
    out = np.empty(bounds[n], dtype=np.uint8)
    for p in prange(n):
        _write_path(p, True, out, bounds[p], kind, with_moveto, subpath_offsets, closed,
                    path_offsets, seg_values, seg_value_offsets, start_values,
                    start_value_offsets, table, table_offsets, flags)
    return out, bounds
