"""RNSCA on runs of vertices: clip lines and rings into chains of visible vertices.

A line (or ring) is a run of consecutive segments. RNSCA's idea applied to runs: give a
run the Cohen–Sutherland outcodes of its bounding box's two corners. Both zero: the run
lies in the window and is copied whole. The codes share a bit: the whole run lies
beyond one edge and is skipped. Otherwise the run is ambiguous: split it into N runs of
equal vertex count and recurse, until a run is short enough (`RUN_LEAF_SEGMENTS`) to be
clipped segment by segment by the segment core (`rnsca_segment`, or a baseline). Long
lines that lie mostly inside or mostly outside are decided in a few bounding boxes.

The visible pieces are joined into *chains*: a piece continues the current chain when
it starts exactly where the chain ends, at the shared input vertex; a cut end (a
crossing) ends the chain. Chains therefore come out in input order and direction.

With ``drop_edge_runs`` a piece lying along a window edge is not visible: that is the
``boundary="interior"`` rule for lines, and how rings are cut for polygon clipping
(a ring that runs along the window's edge is broken there; `polygons.py` closes the
chains by walking the boundary).

Stacks are explicit (no recursion), so the logic ports to OpenCL.
"""

import numpy as np
from numba import prange

from rnsca.kernels import counters as C
from rnsca.kernels.jit import parallel, scalar
from rnsca.kernels.outcode import outcode
from rnsca.kernels.segments import (
    RNSCA,
    STACK_CAPACITY,
    clip_one,
    rnsca_segment,
)

__all__ = [
    "CHUNK_ACCEPTED",
    "CHUNK_REJECTED",
    "CHUNK_SEGMENTED",
    "RUN_LEAF_SEGMENTS",
    "RUN_STACK_CAPACITY",
    "RUN_N_AUTO",
    "assemble_chains",
    "assemble_line_blocks",
    "bound_chains",
    "box_chunks",
    "chunk_count",
    "clip_chains",
    "clip_line_blocks",
    "run_box_codes",
]

# Runs of at most this many segments are clipped segment by segment: below it, a
# bounding box costs about as much as the segments' own outcode tests.
RUN_LEAF_SEGMENTS = 16
# ``n="auto"`` for runs: a bounding box pass costs the same whatever N is, so a larger
# N decides more of the run per pass; 16 keeps the stack and the per-child overhead small.
RUN_N_AUTO = 16
# Depth-first: at most N - 1 pending siblings per level, and a run of 2**63 vertices
# split in two (the smallest N) is down to a leaf within 63 levels.
RUN_STACK_CAPACITY = 64 * 64


@scalar
def _edge_bits(x, y, xmin, ymin, xmax, ymax):
    """Return which window edge lines the point lies on (LEFT, RIGHT, BOTTOM, TOP bits)."""
    return ((x == xmin) * 1) | ((x == xmax) * 2) | ((y == ymin) * 4) | ((y == ymax) * 8)


@scalar
def on_one_edge(ax, ay, bx, by, xmin, ymin, xmax, ymax):
    """Return whether the segment (a, b) of the closed window lies along one of its edges."""
    return (_edge_bits(ax, ay, xmin, ymin, xmax, ymax)
            & _edge_bits(bx, by, xmin, ymin, xmax, ymax)) != 0


@scalar
def bound_chains(xy, first, last, xmin, ymin, xmax, ymax):
    """Return upper bounds (vertices, chains, crossings) for clipping ``xy[first..last]``.

    A vertex inside the closed window is output at most once, twice if it lies on the
    boundary (rings break there); a segment that is neither inside nor beyond one edge
    (ambiguous) adds at most two cut points and one chain; a segment along an edge or a
    vertex on the boundary may break a chain. Crossings (all of those breaks) bound the
    chains' ends for polygon assembly. One branch-free pass, so the write pass can be
    given a slot without a counting pass that repeats the clipping.
    """
    vertices = 0
    crossings = 0
    cp = outcode(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax)
    bp = _edge_bits(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax)
    vertices += cp == 0
    crossings += bp != 0
    for i in range(first + 1, last + 1):
        c = outcode(xy[i, 0], xy[i, 1], xmin, ymin, xmax, ymax)
        b = _edge_bits(xy[i, 0], xy[i, 1], xmin, ymin, xmax, ymax)
        vertices += c == 0
        ambiguous = ((cp | c) != 0) & ((cp & c) == 0)
        along = ((cp | c) == 0) & ((bp & b) != 0)
        crossings += ambiguous | along
        crossings += (b != 0) & (c == 0)
        cp = c
        bp = b
    return vertices + 2 * crossings, crossings + 1, crossings


@scalar
def _append(out_xy, out_z, has_z, write, v, x, y, z):
    if write:
        out_xy[v, 0] = x
        out_xy[v, 1] = y
        if has_z:
            out_z[v] = z
    return v + 1


@scalar
def _emit_piece(xy, z, has_z, write, i, t0, t1, ax, ay, bx, by, out_xy, out_z, out_starts,
                v, c, last_v, breaks):
    """Add the piece [t0, t1] of segment i to the chains; return (v, c, last_v).

    The piece continues the chain if the chain ends at vertex i and the piece starts
    there, unless `breaks` (rings break at a vertex on the boundary). Without `write`
    only the positions advance (the counting pass).
    """
    if breaks or not (last_v == i and ax == xy[i, 0] and ay == xy[i, 1]):
        if write:
            out_starts[c] = v
        c += 1
        za = 0.0
        if has_z:
            za = z[i] if t0 == 0.0 else z[i] + t0 * (z[i + 1] - z[i])
        v = _append(out_xy, out_z, has_z, write, v, ax, ay, za)
    end_is_vertex = bx == xy[i + 1, 0] and by == xy[i + 1, 1]
    zb = 0.0
    if has_z:
        zb = z[i + 1] if end_is_vertex else z[i] + t1 * (z[i + 1] - z[i])
    v = _append(out_xy, out_z, has_z, write, v, bx, by, zb)
    return v, c, (i + 1) if end_is_vertex else -1


@scalar
def _emit_run(xy, z, has_z, write, a, b, out_xy, out_z, out_starts, v, c, last_v):
    """Add the whole run of vertices a..b (inside the window); return (v, c, last_v)."""
    start = a + 1
    if last_v != a:
        if write:
            out_starts[c] = v
        c += 1
        start = a
    if not write:
        return v + b + 1 - start, c, b
    for k in range(start, b + 1):
        out_xy[v, 0] = xy[k, 0]
        out_xy[v, 1] = xy[k, 1]
        if has_z:
            out_z[v] = z[k]
        v += 1
    return v, c, b


@scalar
def _clip_segments(xy, z, has_z, write, a, b, xmin, ymin, xmax, ymax, method, n_fixed,
                   max_depth, tol, auto_piece, exact, drop_edge_runs, break_at_boundary, out_xy,
                   out_z, out_starts, v, c, last_v, st, stack_f, stack_i):
    """Clip segments a..b-1 one by one into the chains; return (v, c, last_v).

    With `break_at_boundary` (rings) a chain also breaks at a vertex on the boundary,
    so that a ring touching the window's edge from inside is cut there too.
    """
    for i in range(a, b):
        x0 = xy[i, 0]
        y0 = xy[i, 1]
        x1 = xy[i + 1, 0]
        y1 = xy[i + 1, 1]
        if method == RNSCA:
            # RNSCA's level 0, here rather than in the call (which passes three arrays,
            # each reference-counted): most segments of a leaf run are decided by it.
            c0 = outcode(x0, y0, xmin, ymin, xmax, ymax)
            c1 = outcode(x1, y1, xmin, ymin, xmax, ymax)
            if (c0 | c1) == 0 or (c0 & c1) != 0:
                st[C.EVALUATED] += 1
                st[C.LEVELS] += 1
                if c0 & c1:
                    st[C.REJECTED] += 1
                    continue
                st[C.ACCEPTED] += 1
                keep, t0, t1, ax, ay, bx, by = True, 0.0, 1.0, x0, y0, x1, y1
            else:
                keep, t0, t1, ax, ay, bx, by = rnsca_segment(
                    x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol,
                    auto_piece, exact, st, stack_f, stack_i)
        else:
            keep, t0, t1, ax, ay, bx, by = clip_one(
                method, x0, y0, x1, y1, xmin, ymin, xmax, ymax, max_depth, tol, exact, st)
        if keep and not (drop_edge_runs and on_one_edge(ax, ay, bx, by, xmin, ymin, xmax, ymax)):
            breaks = break_at_boundary and _edge_bits(x0, y0, xmin, ymin, xmax, ymax) != 0
            v, c, last_v = _emit_piece(xy, z, has_z, write, i, t0, t1, ax, ay, bx, by,
                                       out_xy, out_z, out_starts, v, c, last_v, breaks)
    return v, c, last_v


@scalar
def run_box_codes(xy, a, b, xmin, ymin, xmax, ymax):
    """Return the outcodes of the bounding box corners of vertices a..b, and strictness.

    The third value says whether the box lies strictly inside the window (no vertex on
    an edge line), which ``drop_edge_runs`` needs before accepting a run whole.
    """
    lo_x = xy[a, 0]
    hi_x = lo_x
    lo_y = xy[a, 1]
    hi_y = lo_y
    for k in range(a + 1, b + 1):
        x = xy[k, 0]
        y = xy[k, 1]
        lo_x = min(lo_x, x)
        hi_x = max(hi_x, x)
        lo_y = min(lo_y, y)
        hi_y = max(hi_y, y)
    strict = (lo_x > xmin) & (hi_x < xmax) & (lo_y > ymin) & (hi_y < ymax)
    return (outcode(lo_x, lo_y, xmin, ymin, xmax, ymax),
            outcode(hi_x, hi_y, xmin, ymin, xmax, ymax), strict)


@scalar
def _level_slot(level):
    return C.N_LEVELS - 1 if level >= C.N_LEVELS else level


@scalar
def _range_box_codes(xy, first, last, boxes, box0, ca, cb, xmin, ymin, xmax, ymax):
    """Return `run_box_codes` for the chunks ca..cb-1 of the line from vertex `first`.

    With stored chunk boxes (``boxes[box0 + k]`` = [xmin, ymin, xmax, ymax] of chunk k)
    the run's box is their union, so a level of the recursion costs one step per chunk,
    not per vertex; without (``boxes`` empty: rings) the vertices are scanned.
    """
    if boxes.shape[0] == 0:
        a = first + ca * RUN_LEAF_SEGMENTS
        b = min(first + cb * RUN_LEAF_SEGMENTS, last)
        return run_box_codes(xy, a, b, xmin, ymin, xmax, ymax)
    lo_x = boxes[box0 + ca, 0]
    lo_y = boxes[box0 + ca, 1]
    hi_x = boxes[box0 + ca, 2]
    hi_y = boxes[box0 + ca, 3]
    for k in range(box0 + ca + 1, box0 + cb):
        lo_x = min(lo_x, boxes[k, 0])
        lo_y = min(lo_y, boxes[k, 1])
        hi_x = max(hi_x, boxes[k, 2])
        hi_y = max(hi_y, boxes[k, 3])
    strict = (lo_x > xmin) & (hi_x < xmax) & (lo_y > ymin) & (hi_y < ymax)
    return (outcode(lo_x, lo_y, xmin, ymin, xmax, ymax),
            outcode(hi_x, hi_y, xmin, ymin, xmax, ymax), strict)


@scalar
def chunk_count(first, last):
    """Return how many chunks of `RUN_LEAF_SEGMENTS` segments the line first..last has."""
    return 0 if last <= first else (last - first + RUN_LEAF_SEGMENTS - 1) // RUN_LEAF_SEGMENTS


@scalar
def box_chunks(xy, first, last, boxes, box0):
    """Store the bounding box of each chunk of the line first..last at ``boxes[box0:]``.

    One pass over the coordinates; the recursion then prunes runs by the union of their
    chunks' boxes without scanning vertices again.
    """
    for k in range(chunk_count(first, last)):
        a = first + k * RUN_LEAF_SEGMENTS
        b = min(a + RUN_LEAF_SEGMENTS, last)
        lo_x = xy[a, 0]
        hi_x = lo_x
        lo_y = xy[a, 1]
        hi_y = lo_y
        for i in range(a + 1, b + 1):
            lo_x = min(lo_x, xy[i, 0])
            hi_x = max(hi_x, xy[i, 0])
            lo_y = min(lo_y, xy[i, 1])
            hi_y = max(hi_y, xy[i, 1])
        boxes[box0 + k, 0] = lo_x
        boxes[box0 + k, 1] = lo_y
        boxes[box0 + k, 2] = hi_x
        boxes[box0 + k, 3] = hi_y


@scalar
def clip_chains(xy, z, has_z, write, first, last, xmin, ymin, xmax, ymax, method, n_fixed,
                max_depth, tol, auto_piece, exact, drop_edge_runs, break_at_boundary, out_xy,
                out_z, out_starts, v, c, st, run_stack, stack_f, stack_i, boxes, box0):
    """Clip the line through vertices ``xy[first..last]`` into chains.

    Writes the chains' vertices from ``out_xy[v]`` (and ``out_z``) on, and the start of
    each chain at ``out_starts[c]`` on; the caller guarantees room (`bound_chains`).
    Returns ``(v, c, starts_at_first, ends_at_last)``: the next free positions, whether
    the first chain starts at vertex `first` itself and whether the last ends at vertex
    `last` (a ring's chains across its closing vertex join there).

    Runs are whole chunks of `RUN_LEAF_SEGMENTS` segments; their boxes come from
    `boxes` (see `box_chunks`) or, if it is empty, from the vertices. Runs are pruned
    only for ``method == RNSCA``; the baselines clip every segment. Without `write`
    nothing is written and only the counts come back (the exact counting pass).
    """
    c_begin = c
    last_v = -1
    if last <= first:
        return v, c, False, False
    if method != RNSCA:
        v, c, last_v = _clip_segments(xy, z, has_z, write, first, last, xmin, ymin, xmax, ymax,
                                      method, n_fixed, max_depth, tol, auto_piece, exact,
                                      drop_edge_runs, break_at_boundary, out_xy, out_z,
                                      out_starts, v, c, last_v, st, stack_f, stack_i)
    else:
        n_runs = n_fixed if n_fixed > 0 else RUN_N_AUTO
        run_stack[0, 0] = 0
        run_stack[0, 1] = chunk_count(first, last)
        run_stack[0, 2] = 0
        sp = 1
        while sp > 0:
            sp -= 1
            ca = run_stack[sp, 0]
            cb = run_stack[sp, 1]
            level = run_stack[sp, 2]
            a = first + ca * RUN_LEAF_SEGMENTS
            b = min(first + cb * RUN_LEAF_SEGMENTS, last)
            slot = _level_slot(level)
            if level > st[C.RUN_DEEPEST]:
                st[C.RUN_DEEPEST] = level
            st[C.RUNS_EVALUATED] += 1
            lo, hi, strict = _range_box_codes(xy, first, last, boxes, box0, ca, cb,
                                              xmin, ymin, xmax, ymax)
            if (lo | hi) == 0 and (strict or not drop_edge_runs):
                st[C.RUNS_ACCEPTED] += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
                v, c, last_v = _emit_run(xy, z, has_z, write, a, b, out_xy, out_z,
                                         out_starts, v, c, last_v)
            elif lo & hi:
                st[C.RUNS_REJECTED] += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
            elif cb - ca <= 1 or sp + n_runs > RUN_STACK_CAPACITY:
                st[C.RUNS_SEGMENTED] += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
                v, c, last_v = _clip_segments(xy, z, has_z, write, a, b, xmin, ymin, xmax,
                                              ymax, method, n_fixed, max_depth, tol, auto_piece,
                                              exact, drop_edge_runs, break_at_boundary,
                                              out_xy, out_z, out_starts, v, c, last_v, st,
                                              stack_f, stack_i)
            else:
                st[C.RUNS_SUBDIVIDED] += 1
                # Children cover the chunks ca..cb-1 in n (or fewer) runs of nearly equal
                # length, pushed last first so they pop in input order.
                k = min(n_runs, cb - ca)
                for j in range(k, 0, -1):
                    run_stack[sp, 0] = ca + (cb - ca) * (j - 1) // k
                    run_stack[sp, 1] = ca + (cb - ca) * j // k
                    run_stack[sp, 2] = level + 1
                    sp += 1
    if c == c_begin or not write:
        return v, c, False, False
    starts_at_first = out_xy[out_starts[c_begin], 0] == xy[first, 0] and \
        out_xy[out_starts[c_begin], 1] == xy[first, 1]
    if break_at_boundary and _edge_bits(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax) != 0:
        starts_at_first = False  # a ring breaks at its closing vertex on the boundary
    return v, c, starts_at_first, last_v == last


@parallel
def clip_line_blocks(xy, z, has_z, part_offsets, part_window, windows, method, n_fixed,
                     max_depth, tol, auto_piece, exact, drop_edge_runs, block_size, write,
                     chunk_start, boxes, vertex_start, chain_start, out_xy, out_z, out_starts,
                     n_vertices, n_chains, counters):
    """Count (``write=False``) or write (``write=True``) every part of a ragged line array.

    Part ``p`` is ``xy[part_offsets[p]:part_offsets[p+1]]``, clipped against
    ``windows[part_window[p]]``; its chunk boxes live at ``boxes[chunk_start[p]:]``.
    The count pass stores the boxes (`box_chunks`) and counts each part's output exactly
    (`clip_chains` without writing: only ambiguous chunks do any work twice); the write
    pass writes part p's chains from ``vertex_start[p]`` and ``chain_start[p]`` (the
    exclusive sums of the counts), so the output is allocated once, at its size. Stats
    are counted in the write pass, one counter row per block.
    """
    n_parts = part_offsets.shape[0] - 1
    n_blocks = counters.shape[0]
    for blk in prange(n_blocks):
        st = counters[blk] if write else np.zeros(C.WIDTH, dtype=np.int64)
        run_stack = np.empty((RUN_STACK_CAPACITY, 3), dtype=np.int64)
        stack_f = np.empty((STACK_CAPACITY, 6), dtype=np.float64)
        stack_i = np.empty((STACK_CAPACITY, 3), dtype=np.int64)
        for p in range(blk * block_size, min(n_parts, (blk + 1) * block_size)):
            first = part_offsets[p]
            last = part_offsets[p + 1] - 1
            w = part_window[p]
            xmin = windows[w, 0]
            ymin = windows[w, 1]
            xmax = windows[w, 2]
            ymax = windows[w, 3]
            v0 = 0
            c0 = 0
            if write:
                v0 = vertex_start[p]
                c0 = chain_start[p]
            else:
                box_chunks(xy, first, last, boxes, chunk_start[p])
            v, c, _, _ = clip_chains(xy, z, has_z, write, first, last, xmin, ymin, xmax, ymax,
                                     method, n_fixed, max_depth, tol, auto_piece, exact,
                                     drop_edge_runs, False, out_xy, out_z, out_starts, v0, c0,
                                     st, run_stack, stack_f, stack_i, boxes, chunk_start[p])
            if not write:
                n_vertices[p] = v
                n_chains[p] = c


# Decisions of chunks made on a device (the OpenCL backend's `classify_runs`): skipped,
# copied whole, or clipped segment by segment.
CHUNK_REJECTED = 0
CHUNK_ACCEPTED = 1
CHUNK_SEGMENTED = 2


@scalar
def assemble_chains(xy, z, has_z, write, first, last, drop_edge_runs, xmin, ymin, xmax, ymax,
                    decision, chunk0, piece_start, keep, pieces, out_xy, out_z, out_starts, v,
                    c):
    """Emit the chains of the line ``xy[first..last]`` from decisions made elsewhere.

    `decision[chunk0 + k]` says what became of the line's chunk k (``CHUNK_*``); the
    segments of a segmented chunk have ``keep`` and ``pieces`` rows (t0, t1, ax, ay, bx,
    by) from ``piece_start[chunk0 + k]`` on. The chains are the ones `clip_chains` emits
    for those decisions (its `_emit_run` and `_emit_piece`): an accepted run of chunks
    copied chunk by chunk is the same chain. Returns ``(v, c)``.
    """
    last_v = -1
    for k in range(chunk_count(first, last)):
        a = first + k * RUN_LEAF_SEGMENTS
        b = min(a + RUN_LEAF_SEGMENTS, last)
        d = decision[chunk0 + k]
        if d == CHUNK_ACCEPTED:
            v, c, last_v = _emit_run(xy, z, has_z, write, a, b, out_xy, out_z, out_starts, v, c,
                                     last_v)
        elif d == CHUNK_SEGMENTED:
            row = piece_start[chunk0 + k]
            for i in range(a, b):
                if keep[row]:
                    ax = pieces[row, 2]
                    ay = pieces[row, 3]
                    bx = pieces[row, 4]
                    by = pieces[row, 5]
                    if not (drop_edge_runs and on_one_edge(ax, ay, bx, by, xmin, ymin, xmax,
                                                           ymax)):
                        v, c, last_v = _emit_piece(xy, z, has_z, write, i, pieces[row, 0],
                                                   pieces[row, 1], ax, ay, bx, by, out_xy,
                                                   out_z, out_starts, v, c, last_v, False)
                row += 1
    return v, c


@parallel
def assemble_line_blocks(xy, z, has_z, part_offsets, part_window, windows, drop_edge_runs,
                         block_size, write, chunk_start, decision, piece_start, keep, pieces,
                         vertex_start, chain_start, out_xy, out_z, out_starts, n_vertices,
                         n_chains):
    """Count (``write=False``) or write the chains of every part from device decisions.

    The host half of the OpenCL line clip (`assemble_chains` per part); the counts and
    the layout are those of `clip_line_blocks`.
    """
    n_parts = part_offsets.shape[0] - 1
    n_blocks = -(-n_parts // block_size)
    for blk in prange(n_blocks):
        for p in range(blk * block_size, min(n_parts, (blk + 1) * block_size)):
            w = part_window[p]
            v0 = vertex_start[p] if write else 0
            c0 = chain_start[p] if write else 0
            v, c = assemble_chains(xy, z, has_z, write, part_offsets[p], part_offsets[p + 1] - 1,
                                   drop_edge_runs, windows[w, 0], windows[w, 1], windows[w, 2],
                                   windows[w, 3], decision, chunk_start[p], piece_start, keep,
                                   pieces, out_xy, out_z, out_starts, v0, c0)
            if not write:
                n_vertices[p] = v
                n_chains[p] = c
