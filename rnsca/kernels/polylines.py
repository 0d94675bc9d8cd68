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

A run's bounding box is never built: the outcodes of its corners share a bit exactly
when every vertex lies beyond that edge (the AND of the vertices' outcodes has the bit),
and both are zero exactly when every vertex is inside (the OR is zero). So a run is
classified by the OR and AND of its vertices' codes (`vertex_code`), the same decisions
as the box test. Lines are coded once, in chunks of `RUN_LEAF_SEGMENTS` segments, by a
vectorized pass that also checks that the coordinates are finite (`code_chunks`); a run
of chunks then costs one step per chunk at every level of the recursion, and accepted
runs are copied whole.

Stacks are explicit (no recursion), so the logic ports to OpenCL.
"""

import numpy as np
from numba import prange

# The chunk length, the run stack's size and the device's chunk decisions are defined in
# rnsca.constants (shared with clip.cl); importable from here as before.
from rnsca.constants import (
    CHUNK_ACCEPTED,
    CHUNK_REJECTED,
    CHUNK_SEGMENTED,
    RUN_LEAF_SEGMENTS,
    RUN_STACK_CAPACITY,
)
from rnsca.kernels import counters as C
from rnsca.kernels.jit import borrowing, inlined, parallel, scalar
from rnsca.kernels.outcode import outcode
from rnsca.kernels.records import CoreOptions, Window
from rnsca.kernels.segments import (
    RNSCA,
    STACK_CAPACITY,
    SegmentStack,
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
    "OUTSIDE",
    "NOT_STRICTLY_INSIDE",
    "NOT_FINITE",
    "assemble_chains",
    "assemble_line_blocks",
    "bound_chains",
    "chunk_count",
    "clip_chains",
    "clip_lines",
    "code_chunks",
    "run_box_codes",
    "vertex_code",
]

# ``n="auto"`` for runs: a bounding box pass costs the same whatever N is, so a larger
# N decides more of the run per pass; 16 keeps the stack and the per-child overhead small.
RUN_N_AUTO = 16

# Bits of a vertex code (`vertex_code`): the outcode, then two flags.
OUTSIDE = 15                # the Cohen–Sutherland outcode (LEFT | RIGHT | BOTTOM | TOP)
NOT_STRICTLY_INSIDE = 16    # on an edge line or beyond (only when asked: `strict`)
NOT_FINITE = 32             # x or y is NaN or infinite
_ALL_CODE_BITS = 63         # the neutral start of an AND of codes
# `code_chunks` codes this many chunks per step into a scratch of bytes that stays in L1
# cache; the OR and AND of a chunk's 16 codes are taken two 8-byte words at a time.
CODE_STEP_CHUNKS = 256
CODE_SCRATCH_BYTES = CODE_STEP_CHUNKS * RUN_LEAF_SEGMENTS + 8
# Lines with fewer vertices in all run on the calling thread: waking the worker threads
# costs more than clipping them.
SERIAL_VERTICES = 32768


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


@inlined
def _append(out_xy, out_z, has_z, write, v, x, y, z):
    if write:
        out_xy[v, 0] = x
        out_xy[v, 1] = y
        if has_z:
            out_z[v] = z
    return v + 1


@inlined
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


@inlined
def _emit_run(flat_xy, z, has_z, write, a, b, flat_out, out_z, out_starts, v, c, last_v):
    """Add the whole run of vertices a..b (inside the window); return (v, c, last_v).

    `flat_xy` and `flat_out` are the input and output coordinates as one row each
    (``xy.reshape(-1)``): the copy then runs over views from index 0 and vectorizes.
    """
    start = a + 1
    if last_v != a:
        if write:
            out_starts[c] = v
        c += 1
        start = a
    count = b + 1 - start
    if write:
        src = flat_xy[2 * start:2 * (b + 1)]
        dst = flat_out[2 * v:2 * (v + count)]
        for k in range(src.shape[0]):
            dst[k] = src[k]
        if has_z:
            src_z = z[start:b + 1]
            dst_z = out_z[v:v + count]
            for k in range(count):
                dst_z[k] = src_z[k]
    return v + count, c, b


@borrowing
def _clip_segments(xy, z, has_z, write, a, b, xmin, ymin, xmax, ymax, method, n_fixed,
                   max_depth, tol, auto_piece, exact, drop_edge_runs, break_at_boundary, out_xy,
                   out_z, out_starts, v, c, last_v, st, stack_f, stack_i, flat_xy, flat_out):
    """Clip segments a..b-1 one by one into the chains; return (v, c, last_v).

    With `break_at_boundary` (rings) a chain also breaks at a vertex on the boundary,
    so that a ring touching the window's edge from inside is cut there too.
    `flat_xy` and `flat_out` are `xy` and `out_xy` as one row each (see `_emit_run`).
    """
    if method != RNSCA:
        for i in range(a, b):
            keep, t0, t1, ax, ay, bx, by = clip_one(
                xy[i, 0], xy[i, 1], xy[i + 1, 0], xy[i + 1, 1], Window(xmin, ymin, xmax, ymax),
                CoreOptions(method, n_fixed, max_depth, tol, auto_piece, exact), st)
            v, c, last_v = _emit_visible(xy, z, has_z, write, i, keep, t0, t1, ax, ay, bx,
                                         by, xmin, ymin, xmax, ymax, drop_edge_runs,
                                         break_at_boundary, out_xy, out_z, out_starts, v, c,
                                         last_v)
        return v, c, last_v
    # RNSCA's level 0 for every segment, decided here from its end points' outcodes
    # (each computed once) with the counts kept in registers: most segments of a leaf
    # run are inside or beyond an edge, and a call per segment (its array arguments
    # are reference-counted) would cost more than the test. Stretches of accepted
    # segments are copied as runs; only the ambiguous ones reach the segment core.
    accepted = 0
    rejected = 0
    stretch = -1  # first vertex of the stretch of accepted segments being gathered
    c1 = outcode(xy[a, 0], xy[a, 1], xmin, ymin, xmax, ymax)
    for i in range(a, b):
        c0 = c1
        c1 = outcode(xy[i + 1, 0], xy[i + 1, 1], xmin, ymin, xmax, ymax)
        if (c0 | c1) == 0:
            accepted += 1
            visible = not (drop_edge_runs and on_one_edge(xy[i, 0], xy[i, 1], xy[i + 1, 0],
                                                          xy[i + 1, 1], xmin, ymin, xmax,
                                                          ymax))
            breaks = break_at_boundary and _edge_bits(xy[i, 0], xy[i, 1], xmin, ymin, xmax,
                                                      ymax) != 0
            if stretch >= 0 and (breaks or not visible):
                v, c, last_v = _emit_run(flat_xy, z, has_z, write, stretch, i, flat_out,
                                         out_z, out_starts, v, c, last_v)
                stretch = -1
            if visible and stretch < 0:
                stretch = i
                if breaks:
                    last_v = -1  # the stretch starts a chain of its own
            continue
        if stretch >= 0:
            v, c, last_v = _emit_run(flat_xy, z, has_z, write, stretch, i, flat_out, out_z,
                                     out_starts, v, c, last_v)
            stretch = -1
        if c0 & c1:
            rejected += 1
            continue
        keep, t0, t1, ax, ay, bx, by = rnsca_segment(
            xy[i, 0], xy[i, 1], xy[i + 1, 0], xy[i + 1, 1], Window(xmin, ymin, xmax, ymax),
            CoreOptions(method, n_fixed, max_depth, tol, auto_piece, exact), st,
            SegmentStack(stack_f, stack_i))
        v, c, last_v = _emit_visible(xy, z, has_z, write, i, keep, t0, t1, ax, ay, bx, by,
                                     xmin, ymin, xmax, ymax, drop_edge_runs, break_at_boundary,
                                     out_xy, out_z, out_starts, v, c, last_v)
    if stretch >= 0:
        v, c, last_v = _emit_run(flat_xy, z, has_z, write, stretch, b, flat_out, out_z,
                                 out_starts, v, c, last_v)
    st[C.EVALUATED] += accepted + rejected
    st[C.LEVELS] += accepted + rejected
    st[C.ACCEPTED] += accepted
    st[C.REJECTED] += rejected
    return v, c, last_v


@inlined
def _emit_visible(xy, z, has_z, write, i, keep, t0, t1, ax, ay, bx, by, xmin, ymin, xmax,
                  ymax, drop_edge_runs, break_at_boundary, out_xy, out_z, out_starts, v, c,
                  last_v):
    """Add the piece of segment i the segment core kept, unless it is not visible."""
    if keep and not (drop_edge_runs and on_one_edge(ax, ay, bx, by, xmin, ymin, xmax, ymax)):
        breaks = break_at_boundary and _edge_bits(xy[i, 0], xy[i, 1], xmin, ymin, xmax,
                                                  ymax) != 0
        return _emit_piece(xy, z, has_z, write, i, t0, t1, ax, ay, bx, by, out_xy, out_z,
                           out_starts, v, c, last_v, breaks)
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
def vertex_code(x, y, xmin, ymin, xmax, ymax, strict):
    """Return the vertex code: outcode, `NOT_FINITE`, if `strict` `NOT_STRICTLY_INSIDE`.

    The OR and AND of a run's codes classify the run as its bounding box's outcodes
    would (see the module docstring). ``x - x == y - y`` is false exactly when x or y is
    NaN or infinite (IEEE arithmetic; no fast-math flag is set).
    """
    code = outcode(x, y, xmin, ymin, xmax, ymax) | (not (x - x == y - y)) * NOT_FINITE
    if strict:
        code |= ((x <= xmin) | (x >= xmax) | (y <= ymin) | (y >= ymax)) * NOT_STRICTLY_INSIDE
    return code


@scalar
def chunk_count(first, last):
    """Return how many chunks of `RUN_LEAF_SEGMENTS` segments the line first..last has."""
    return 0 if last <= first else (last - first + RUN_LEAF_SEGMENTS - 1) // RUN_LEAF_SEGMENTS


@borrowing
def code_chunks(flat, first, last, xmin, ymin, xmax, ymax, strict, codes, chunk_or, chunk_and,
                c0):
    """Store the OR and AND of each chunk's vertex codes; return those of the whole line.

    `flat` is the coordinate array as one row (x0, y0, x1, y1, ...); the line runs
    through vertices first..last. Chunk k (vertices ``first + 16k`` to
    ``min(first + 16k + 16, last)``) gets ``chunk_or[c0 + k]`` and ``chunk_and[c0 + k]``.
    `codes` is scratch of `CODE_SCRATCH_BYTES` bytes. One pass over the coordinates:
    the codes of a step are computed by a loop that LLVM vectorizes (it runs from 0
    over a view; with an arbitrary start, Numba's negative-index handling prevents
    that), then each chunk's 16 codes are combined as two 8-byte words.
    """
    line_or = 0
    line_and = _ALL_CODE_BITS
    step = CODE_STEP_CHUNKS * RUN_LEAF_SEGMENTS
    for s in range(0, last - first, step):
        n_codes = min(step, last - first - s) + 1
        points = flat[2 * (first + s):2 * (first + s + n_codes)]
        for i in range(n_codes):
            codes[i] = vertex_code(points[2 * i], points[2 * i + 1], xmin, ymin, xmax, ymax,
                                   strict)
        n_chunks = (n_codes - 1 + RUN_LEAF_SEGMENTS - 1) // RUN_LEAF_SEGMENTS
        # Pad the last chunk with the last vertex's code, neutral for both OR and AND.
        end = codes[n_codes - 1]
        for i in range(n_codes, n_chunks * RUN_LEAF_SEGMENTS + 1):
            codes[i] = end
        # Codes use bits 0-5 only, so the words are non-negative and shifts bring in zeros.
        # Chunk k's codes are words 2k and 2k+1; its closing vertex is the first byte of
        # word 2k+2 (the scratch holds that word for the last chunk too).
        words = codes[:8 * (2 * n_chunks + 1)].view(np.int64)
        k0 = c0 + s // RUN_LEAF_SEGMENTS
        out_or = chunk_or[k0:k0 + n_chunks]
        out_and = chunk_and[k0:k0 + n_chunks]
        for k in range(n_chunks):
            lo = words[2 * k]
            hi = words[2 * k + 1]
            closing = words[2 * k + 2] & 0xFF
            any_ = lo | hi
            every = lo & hi
            any_ |= any_ >> 32
            any_ |= any_ >> 16
            any_ |= any_ >> 8
            every &= every >> 32
            every &= every >> 16
            every &= every >> 8
            any_ = (any_ | closing) & 0xFF
            every &= closing
            out_or[k] = any_
            out_and[k] = every
            line_or |= any_
            line_and &= every
    return line_or, line_and


@inlined
def _chunk_run_codes(chunk_or, chunk_and, first_chunk, end_chunk):
    """Return the OR and AND of the stored codes of chunks first_chunk..end_chunk-1."""
    any_ = 0
    every = _ALL_CODE_BITS
    if end_chunk - first_chunk > 32:
        # Long runs (whole lines): over views from 0, which LLVM vectorizes.
        ors = chunk_or[first_chunk:end_chunk]
        ands = chunk_and[first_chunk:end_chunk]
        for k in range(ors.shape[0]):
            any_ |= ors[k]
            every &= ands[k]
        return any_, every
    for k in range(first_chunk, end_chunk):
        any_ |= chunk_or[k]
        every &= chunk_and[k]
    return any_, every


@inlined
def _vertex_run_codes(xy, a, b, xmin, ymin, xmax, ymax, strict):
    """Return the OR and AND of the codes of vertices a..b (`vertex_code`)."""
    any_ = 0
    every = _ALL_CODE_BITS
    for k in range(a, b + 1):
        code = vertex_code(xy[k, 0], xy[k, 1], xmin, ymin, xmax, ymax, strict)
        any_ |= code
        every &= code
    return any_, every


@borrowing
def clip_chains(xy, z, has_z, write, first, last, xmin, ymin, xmax, ymax, method, n_fixed,
                max_depth, tol, auto_piece, exact, drop_edge_runs, break_at_boundary, out_xy,
                out_z, out_starts, v, c, st, run_stack, stack_f, stack_i, chunk_or, chunk_and,
                c0, plan, plan0):
    """Clip the line through vertices ``xy[first..last]`` into chains.

    Writes the chains' vertices from ``out_xy[v]`` (and ``out_z``) on, and the start of
    each chain at ``out_starts[c]`` on; the caller guarantees room (`bound_chains`).
    Returns ``(v, c, starts_at_first, ends_at_last, plan_end)``: the next free
    positions, whether the first chain starts at vertex `first` itself, whether the
    last ends at vertex `last` (a ring's chains across its closing vertex join there),
    and the end of the plan (below).

    Runs are whole chunks of `RUN_LEAF_SEGMENTS` segments, classified by the OR and AND
    of their vertex codes: from the chunk codes at ``chunk_or[c0:]``, ``chunk_and[c0:]``
    (see `code_chunks`, which must have been given ``strict=drop_edge_runs``) or, if
    those are empty, from the vertices. Runs are pruned only for ``method == RNSCA``;
    the baselines clip every segment. Without `write` nothing is written and only the
    counts come back (the exact counting pass).

    If `plan` (int64 (k, 2)) is not empty, the decided runs that leave something are
    also recorded from ``plan[plan0]`` on, in input order, for `emit_plan` to replay
    without deciding again: ``[first chunk, end chunk]`` for a run accepted whole
    (adjacent ones merged), ``[first chunk, -end chunk]`` for a run clipped segment by
    segment. A line of k chunks needs at most k rows.
    """
    c_begin = c
    last_v = -1
    if last <= first:
        return v, c, False, False, plan0
    flat_xy = xy.reshape(-1)
    flat_out = out_xy.reshape(-1)
    coded = chunk_or.shape[0] > 0
    recording = plan.shape[0] > 0
    n_plan = plan0
    if method != RNSCA:
        v, c, last_v = _clip_segments(xy, z, has_z, write, first, last, xmin, ymin, xmax, ymax,
                                      method, n_fixed, max_depth, tol, auto_piece, exact,
                                      drop_edge_runs, break_at_boundary, out_xy, out_z,
                                      out_starts, v, c, last_v, st, stack_f, stack_i, flat_xy,
                                      flat_out)
        if recording:
            plan[n_plan, 0] = 0
            plan[n_plan, 1] = -chunk_count(first, last)
            n_plan += 1
    else:
        # Run counters in registers, added to `st` at the end; the per-level counts go
        # to `st` directly.
        evaluated = 0
        accepted = 0
        rejected = 0
        subdivided = 0
        segmented = 0
        deepest = st[C.RUN_DEEPEST]
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
            deepest = max(deepest, level)
            evaluated += 1
            if coded:
                any_, every = _chunk_run_codes(chunk_or, chunk_and, c0 + ca, c0 + cb)
            else:
                any_, every = _vertex_run_codes(xy, a, b, xmin, ymin, xmax, ymax,
                                                drop_edge_runs)
            if (any_ & OUTSIDE) == 0 and not (drop_edge_runs and (any_ & NOT_STRICTLY_INSIDE)):
                accepted += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
                v, c, last_v = _emit_run(flat_xy, z, has_z, write, a, b, flat_out, out_z,
                                         out_starts, v, c, last_v)
                if recording:
                    if n_plan > plan0 and plan[n_plan - 1, 1] == ca:
                        plan[n_plan - 1, 1] = cb  # continues the accepted run before it
                    else:
                        plan[n_plan, 0] = ca
                        plan[n_plan, 1] = cb
                        n_plan += 1
            elif every & OUTSIDE:
                rejected += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
            elif cb - ca <= 1 or sp + n_runs > RUN_STACK_CAPACITY:
                segmented += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
                v, c, last_v = _clip_segments(xy, z, has_z, write, a, b, xmin, ymin, xmax,
                                              ymax, method, n_fixed, max_depth, tol, auto_piece,
                                              exact, drop_edge_runs, break_at_boundary,
                                              out_xy, out_z, out_starts, v, c, last_v, st,
                                              stack_f, stack_i, flat_xy, flat_out)
                if recording:
                    plan[n_plan, 0] = ca
                    plan[n_plan, 1] = -cb
                    n_plan += 1
            else:
                subdivided += 1
                # Children cover the chunks ca..cb-1 in k = min(n, cb - ca) runs of nearly
                # equal length: child j (1..k) ends at ca + floor((cb - ca) j / k), found
                # without a division per child (integer division is slow) by carrying the
                # remainder. They are pushed last first so they pop in input order.
                k = min(n_runs, cb - ca)
                step = (cb - ca) // k
                rest = (cb - ca) - step * k
                lo = ca
                carry = 0
                for j in range(1, k + 1):
                    hi = lo + step
                    carry += rest
                    if carry >= k:
                        carry -= k
                        hi += 1
                    run_stack[sp + k - j, 0] = lo
                    run_stack[sp + k - j, 1] = hi
                    run_stack[sp + k - j, 2] = level + 1
                    lo = hi
                sp += k
        st[C.RUN_DEEPEST] = deepest
        st[C.RUNS_EVALUATED] += evaluated
        st[C.RUNS_ACCEPTED] += accepted
        st[C.RUNS_REJECTED] += rejected
        st[C.RUNS_SUBDIVIDED] += subdivided
        st[C.RUNS_SEGMENTED] += segmented
    if c == c_begin or not write:
        return v, c, False, False, n_plan
    starts_at_first = out_xy[out_starts[c_begin], 0] == xy[first, 0] and \
        out_xy[out_starts[c_begin], 1] == xy[first, 1]
    if break_at_boundary and _edge_bits(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax) != 0:
        starts_at_first = False  # a ring breaks at its closing vertex on the boundary
    return v, c, starts_at_first, last_v == last, n_plan


@borrowing
def emit_plan(xy, z, has_z, first, last, xmin, ymin, xmax, ymax, method, n_fixed, max_depth,
              tol, auto_piece, exact, drop_edge_runs, out_xy, out_z, out_starts, v, c, st,
              stack_f, stack_i, plan, plan0, plan_end):
    """Write the chains of the line ``xy[first..last]`` as recorded by `clip_chains`.

    Replays ``plan[plan0:plan_end]``: runs accepted whole are copied, the others
    clipped segment by segment, exactly as `clip_chains` did when it recorded them.
    Returns ``(v, c)``. The segment core counts into `st` again (pass a scratch row).
    """
    flat_xy = xy.reshape(-1)
    flat_out = out_xy.reshape(-1)
    last_v = -1
    for k in range(plan0, plan_end):
        a = first + plan[k, 0] * RUN_LEAF_SEGMENTS
        if plan[k, 1] >= 0:
            b = min(first + plan[k, 1] * RUN_LEAF_SEGMENTS, last)
            v, c, last_v = _emit_run(flat_xy, z, has_z, True, a, b, flat_out, out_z,
                                     out_starts, v, c, last_v)
        else:
            b = min(first - plan[k, 1] * RUN_LEAF_SEGMENTS, last)
            v, c, last_v = _clip_segments(xy, z, has_z, True, a, b, xmin, ymin, xmax, ymax,
                                          method, n_fixed, max_depth, tol, auto_piece, exact,
                                          drop_edge_runs, False, out_xy, out_z, out_starts, v,
                                          c, last_v, st, stack_f, stack_i, flat_xy, flat_out)
    return v, c


@scalar
def _line_block(blk, block_size, xy, z, has_z, part_offsets, geometry_parts, geometry_window,
                windows, method, n_fixed, max_depth, tol, auto_piece, exact, drop_edge_runs,
                write, chunk_start, chunk_or, chunk_and, plan, plan_end, vertex_start,
                chain_start, out_xy, out_z, out_starts, n_vertices, n_chains, counters):
    """Count or write the parts of geometries ``blk * block_size`` on: the body of a pass.

    The count pass codes each part's chunks (`code_chunks`, which also checks that the
    coordinates are finite: a part with a non-finite one gets ``n_vertices = -1``),
    runs RNSCA over its runs (`clip_chains` without writing), which counts the output
    exactly and the stats into the block's counter row, and records the decided runs
    in the part's rows of `plan` (from ``chunk_start[p]`` to ``plan_end[p]``). The write
    pass replays the plan (`emit_plan`) from ``vertex_start[p]`` and ``chain_start[p]``:
    runs are not decided twice, and only the segments of ambiguous chunks are clipped
    twice.
    """
    n_geometries = geometry_parts.shape[0] - 1
    st = np.zeros(C.WIDTH, dtype=np.int64) if write else counters[blk]
    # The write pass replays plans: it needs neither the run stack nor the code scratch.
    run_stack = np.empty((0 if write else RUN_STACK_CAPACITY, 3), dtype=np.int64)
    stack_f = np.empty((STACK_CAPACITY, 6), dtype=np.float64)
    stack_i = np.empty((STACK_CAPACITY, 3), dtype=np.int64)
    codes = np.empty(0 if write else CODE_SCRATCH_BYTES, dtype=np.uint8)
    flat = xy.reshape(-1)
    for g in range(blk * block_size, min(n_geometries, (blk + 1) * block_size)):
        w = geometry_window[g] if geometry_window.shape[0] > 0 else 0
        xmin = windows[w, 0]
        ymin = windows[w, 1]
        xmax = windows[w, 2]
        ymax = windows[w, 3]
        for p in range(geometry_parts[g], geometry_parts[g + 1]):
            first = part_offsets[p]
            last = part_offsets[p + 1] - 1
            if write:
                emit_plan(xy, z, has_z, first, last, xmin, ymin, xmax, ymax, method, n_fixed,
                          max_depth, tol, auto_piece, exact, drop_edge_runs, out_xy, out_z,
                          out_starts, vertex_start[p], chain_start[p], st, stack_f, stack_i,
                          plan, chunk_start[p], plan_end[p])
                continue
            line_or, _ = code_chunks(flat, first, last, xmin, ymin, xmax, ymax, drop_edge_runs,
                                     codes, chunk_or, chunk_and, chunk_start[p])
            if line_or & NOT_FINITE:
                n_vertices[p] = -1
                n_chains[p] = 0
                plan_end[p] = chunk_start[p]
                continue
            v, c, _, _, plan_end[p] = clip_chains(
                xy, z, has_z, False, first, last, xmin, ymin, xmax, ymax, method, n_fixed,
                max_depth, tol, auto_piece, exact, drop_edge_runs, False, out_xy, out_z,
                out_starts, 0, 0, st, run_stack, stack_f, stack_i, chunk_or, chunk_and,
                chunk_start[p], plan, chunk_start[p])
            n_vertices[p] = v
            n_chains[p] = c


@parallel
def _line_pass(block_size, xy, z, has_z, part_offsets, geometry_parts, geometry_window,
               windows, method, n_fixed, max_depth, tol, auto_piece, exact, drop_edge_runs,
               write, chunk_start, chunk_or, chunk_and, plan, plan_end, vertex_start,
               chain_start, out_xy, out_z, out_starts, n_vertices, n_chains, counters):
    """Run `_line_block` over every block, one prange iteration each."""
    for blk in prange(counters.shape[0]):
        _line_block(blk, block_size, xy, z, has_z, part_offsets, geometry_parts,
                    geometry_window, windows, method, n_fixed, max_depth, tol, auto_piece,
                    exact, drop_edge_runs, write, chunk_start, chunk_or, chunk_and, plan,
                    plan_end, vertex_start, chain_start, out_xy, out_z, out_starts, n_vertices,
                    n_chains, counters)


@scalar
def _line_pass_serial(block_size, xy, z, has_z, part_offsets, geometry_parts, geometry_window,
                      windows, method, n_fixed, max_depth, tol, auto_piece, exact,
                      drop_edge_runs, write, chunk_start, chunk_or, chunk_and, plan, plan_end,
                      vertex_start, chain_start, out_xy, out_z, out_starts, n_vertices,
                      n_chains, counters):
    """Do what `_line_pass` does on the calling thread (small inputs)."""
    for blk in range(counters.shape[0]):
        _line_block(blk, block_size, xy, z, has_z, part_offsets, geometry_parts,
                    geometry_window, windows, method, n_fixed, max_depth, tol, auto_piece,
                    exact, drop_edge_runs, write, chunk_start, chunk_or, chunk_and, plan,
                    plan_end, vertex_start, chain_start, out_xy, out_z, out_starts, n_vertices,
                    n_chains, counters)


@scalar
def _exclusive_sum(counts):
    out = np.empty(counts.shape[0] + 1, dtype=np.int64)
    out[0] = 0
    for i in range(counts.shape[0]):
        out[i + 1] = out[i] + counts[i]
    return out


@scalar
def clip_lines(xy, z, part_offsets, geometry_parts, geometry_window, windows, method, n_fixed,
               max_depth, tol, auto_piece, exact, drop_edge_runs):
    """Clip every part of a ragged line array into chains: count, prefix sum, write.

    Parameters
    ----------
    xy : float64 (n, 2), C-contiguous
        Vertices; part p is ``xy[part_offsets[p]:part_offsets[p+1]]`` (no part of
        exactly one vertex). Checked here to be finite (fused into the coding pass).
    z : float64 (n,) or (0,)
        Z of each vertex (finite), or empty for 2D.
    part_offsets, geometry_parts : int64
        Geometry g owns parts ``geometry_parts[g]`` to ``geometry_parts[g+1] - 1``.
    geometry_window : int64 (G,) or (0,)
        Row of `windows` for each geometry; empty: row 0 for all.
    windows : float64 (w, 4)
        ``[xmin, ymin, xmax, ymax]`` rows.
    method, n_fixed, max_depth, tol, auto_piece, exact
        The segment core's options (see `segments`).
    drop_edge_runs : bool
        Pieces along a window edge are not visible (``boundary="interior"``).

    Returns
    -------
    out_xy : float64 (m, 2)
    out_z : float64 (m,) or (0,)
    chain_offsets : int64 (chains + 1,)
    geometry_chains : int64 (G + 1,)
        Geometry g's chains are ``geometry_chains[g]`` to ``geometry_chains[g+1] - 1``.
    counters : int64 (blocks, counters.WIDTH)
        Stats, one row per block.
    bad_part : int
        -1, or the first part holding a non-finite coordinate (then nothing is clipped
        and the other outputs are empty).

    Notes
    -----
    The count pass codes every chunk once, decides the runs (RNSCA), counts each part
    exactly and records the decisions; the write pass replays them. Both passes are one
    prange over blocks of geometries, each writing only its own parts' slots; the
    prefix sums between them run here rather than in Python (a call costs less).
    """
    n_parts = part_offsets.shape[0] - 1
    n_geometries = geometry_parts.shape[0] - 1
    has_z = z.shape[0] > 0
    chunk_start = np.empty(n_parts + 1, dtype=np.int64)
    chunk_start[0] = 0
    for p in range(n_parts):
        chunk_start[p + 1] = chunk_start[p] + chunk_count(part_offsets[p],
                                                          part_offsets[p + 1] - 1)
    chunk_or = np.empty(chunk_start[n_parts], dtype=np.uint8)
    chunk_and = np.empty(chunk_start[n_parts], dtype=np.uint8)
    plan = np.empty((max(chunk_start[n_parts], 1), 2), dtype=np.int64)
    plan_end = np.empty(n_parts, dtype=np.int64)
    # About 64 blocks for load balance, 1..1024 geometries each.
    block_size = max(1, min(1024, (n_geometries + 63) // 64))
    n_blocks = max(1, (n_geometries + block_size - 1) // block_size)
    serial = xy.shape[0] < SERIAL_VERTICES
    counters = np.zeros((n_blocks, C.WIDTH), dtype=np.int64)
    n_vertices = np.empty(n_parts, dtype=np.int64)
    n_chains = np.empty(n_parts, dtype=np.int64)
    nothing_i = np.empty(0, dtype=np.int64)
    nothing_xy = np.empty((0, 2), dtype=np.float64)
    nothing_z = np.empty(0, dtype=np.float64)
    args_count = (block_size, xy, z, has_z, part_offsets, geometry_parts, geometry_window,
                  windows, method, n_fixed, max_depth, tol, auto_piece, exact, drop_edge_runs,
                  False, chunk_start, chunk_or, chunk_and, plan, plan_end, nothing_i,
                  nothing_i, nothing_xy, nothing_z, nothing_i, n_vertices, n_chains, counters)
    if serial:
        _line_pass_serial(*args_count)
    else:
        _line_pass(*args_count)
    for p in range(n_parts):
        if n_vertices[p] < 0:
            return nothing_xy, nothing_z, np.zeros(1, dtype=np.int64), \
                np.zeros(n_geometries + 1, dtype=np.int64), counters, p
    vertex_start = _exclusive_sum(n_vertices)
    chain_start = _exclusive_sum(n_chains)
    m = vertex_start[n_parts]
    out_xy = np.empty((m, 2), dtype=np.float64)
    out_z = np.empty(m if has_z else 0, dtype=np.float64)
    chain_offsets = np.empty(chain_start[n_parts] + 1, dtype=np.int64)
    chain_offsets[chain_start[n_parts]] = m
    args_write = (block_size, xy, z, has_z, part_offsets, geometry_parts, geometry_window,
                  windows, method, n_fixed, max_depth, tol, auto_piece, exact, drop_edge_runs,
                  True, chunk_start, chunk_or, chunk_and, plan, plan_end, vertex_start,
                  chain_start, out_xy, out_z, chain_offsets, n_vertices, n_chains, counters)
    if serial:
        _line_pass_serial(*args_write)
    else:
        _line_pass(*args_write)
    geometry_chains = np.empty(n_geometries + 1, dtype=np.int64)
    geometry_chains[0] = 0
    for g in range(n_geometries):
        geometry_chains[g + 1] = chain_start[geometry_parts[g + 1]]
    return out_xy, out_z, chain_offsets, geometry_chains, counters, -1


@scalar
def assemble_chains(xy, z, has_z, write, first, last, drop_edge_runs, break_at_boundary, xmin,
                    ymin, xmax, ymax, decision, chunk0, piece_start, keep, pieces, out_xy, out_z,
                    out_starts, v, c):
    """Emit the chains of the line ``xy[first..last]`` from decisions made elsewhere.

    `decision[chunk0 + k]` says what became of the line's chunk k (``CHUNK_*``); the
    segments of a segmented chunk have ``keep`` and ``pieces`` rows (t0, t1, ax, ay, bx,
    by) from ``piece_start[chunk0 + k]`` on. The chains are the ones `clip_chains` emits
    for those decisions (its `_emit_run` and `_emit_piece`; an accepted run of chunks
    copied chunk by chunk is the same chain), and so is the return value:
    ``(v, c, starts_at_first, ends_at_last)``.
    """
    c_begin = c
    last_v = -1
    flat_xy = xy.reshape(-1)
    flat_out = out_xy.reshape(-1)
    for k in range(chunk_count(first, last)):
        a = first + k * RUN_LEAF_SEGMENTS
        b = min(a + RUN_LEAF_SEGMENTS, last)
        d = decision[chunk0 + k]
        if d == CHUNK_ACCEPTED:
            v, c, last_v = _emit_run(flat_xy, z, has_z, write, a, b, flat_out, out_z,
                                     out_starts, v, c, last_v)
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
                        breaks = break_at_boundary and _edge_bits(
                            xy[i, 0], xy[i, 1], xmin, ymin, xmax, ymax) != 0
                        v, c, last_v = _emit_piece(xy, z, has_z, write, i, pieces[row, 0],
                                                   pieces[row, 1], ax, ay, bx, by, out_xy,
                                                   out_z, out_starts, v, c, last_v, breaks)
                row += 1
    if c == c_begin or not write:
        return v, c, False, False
    starts_at_first = out_xy[out_starts[c_begin], 0] == xy[first, 0] and \
        out_xy[out_starts[c_begin], 1] == xy[first, 1]
    if break_at_boundary and _edge_bits(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax) != 0:
        starts_at_first = False  # a ring breaks at its closing vertex on the boundary
    return v, c, starts_at_first, last_v == last


@parallel
def assemble_line_blocks(xy, z, has_z, part_offsets, part_window, windows, drop_edge_runs,
                         block_size, write, chunk_start, decision, piece_start, keep, pieces,
                         vertex_start, chain_start, out_xy, out_z, out_starts, n_vertices,
                         n_chains):
    """Count (``write=False``) or write the chains of every part from device decisions.

    The host half of the OpenCL line clip (`assemble_chains` per part); the counts and
    the layout are those of `clip_lines`.
    """
    n_parts = part_offsets.shape[0] - 1
    n_blocks = -(-n_parts // block_size)
    for blk in prange(n_blocks):
        for p in range(blk * block_size, min(n_parts, (blk + 1) * block_size)):
            w = part_window[p]
            v0 = vertex_start[p] if write else 0
            c0 = chain_start[p] if write else 0
            v, c, _, _ = assemble_chains(xy, z, has_z, write, part_offsets[p],
                                         part_offsets[p + 1] - 1, drop_edge_runs, False,
                                         windows[w, 0], windows[w, 1], windows[w, 2],
                                         windows[w, 3], decision, chunk_start[p], piece_start,
                                         keep, pieces, out_xy, out_z, out_starts, v0, c0)
            if not write:
                n_vertices[p] = v
                n_chains[p] = c
