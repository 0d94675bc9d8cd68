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

What travels together is one record (named tuples; see `rnsca.kernels.records`): the
vertices (`Vertices`), the parts and their windows (`Lines`), where a line is cut
(`Cut`), where its chains go (`ChainsOut`), a block's counters and scratch
(`BlockState`), the chunk codes and plans (`Chunks`, one part's: `PartPlan`), decisions
made on a device (`Decisions`). The flags that choose a pass (`write`,
`break_at_boundary`) stay arguments, passed as constants, so that each pass compiles
without the other's branches.
"""

from typing import NamedTuple

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
from rnsca.kernels.jit import (
    borrowing,
    borrowing_per_constant,
    inlined,
    parallel,
    parallel_per_constant,
    scalar,
    scalar_per_constant,
)
from rnsca.kernels.outcode import outcode
from rnsca.kernels.records import Window, window_of
from rnsca.kernels.segments import (
    RNSCA,
    SegmentStack,
    clip_one,
    rnsca_segment,
    segment_stack,
)
from rnsca.kernels.stacks import interval_at, put_interval

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
    "ChainsOut",
    "Chunks",
    "Cut",
    "Decisions",
    "Lines",
    "PartCounts",
    "Piece",
    "BlockState",
    "PartPlan",
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


class Cut(NamedTuple):
    """Where a line is cut into chains: its window, and whether edge pieces are dropped.

    With `drop_edge_runs` a piece along a window edge is not visible (lines with
    ``boundary="interior"``, and rings). Whether chains also break at a vertex on the
    boundary (rings) is each function's `break_at_boundary` argument: a constant where
    it is passed (``False`` for lines, ``True`` for rings), so that Numba compiles the
    line version without the test.
    """

    window: Window
    drop_edge_runs: bool


class ChainsOut(NamedTuple):
    """Where chains go: vertices from ``xy[v]`` (and ``z[v]``), chain starts from ``starts[c]``.

    `flat` is ``xy.reshape(-1)`` (see `Vertices`). In the counting pass nothing is
    written, and the arrays may be empty. Whether a function writes is its own `write`
    argument, not a field: passed as a constant (``True``, ``False``), it lets Numba
    compile the counting and the writing versions each without the other's branches.
    """

    xy: np.ndarray
    flat: np.ndarray
    z: np.ndarray
    starts: np.ndarray


class BlockState(NamedTuple):
    """What one block of geometries counts into and works in.

    `st` is the block's counter row (`counters`); `run_stack` (`RUN_STACK_CAPACITY`, 3)
    the runs pending, empty where no run is decided; `segment_stack` the scratch of
    `segments.rnsca_segment`; `codes` (`CODE_SCRATCH_BYTES`) that of `code_chunks`, empty
    where nothing is coded.
    """

    st: np.ndarray
    run_stack: np.ndarray
    segment_stack: SegmentStack
    codes: np.ndarray


class Piece(NamedTuple):
    """The piece [t0, t1] of a segment the segment core kept, from (ax, ay) to (bx, by)."""

    t0: float
    t1: float
    ax: float
    ay: float
    bx: float
    by: float


class Chunks(NamedTuple):
    """The chunk codes and plans of a line array (`clip_lines`).

    Part p's chunks are ``chunk_start[p]`` on: the OR and AND of each one's vertex codes
    (`code_chunks`), and from the same row on, the part's plan, the runs the count pass
    decided (`clip_chains`), up to ``plan_end[p]``.
    """

    chunk_start: np.ndarray
    chunk_or: np.ndarray
    chunk_and: np.ndarray
    plan: np.ndarray
    plan_end: np.ndarray


class PartPlan(NamedTuple):
    """One part's chunk codes and plan rows (views of `Chunks` from its first chunk).

    Empty (rings): the runs are coded from the vertices, and no plan is recorded.
    """

    chunk_or: np.ndarray
    chunk_and: np.ndarray
    plan: np.ndarray


class Decisions(NamedTuple):
    """Chunk decisions made elsewhere (the OpenCL backend's device), for `assemble_chains`.

    Part (or ring) r's chunk k was ``decision[chunk_start[r] + k]`` (``CHUNK_*``); a
    segmented chunk's segments have `keep` and `pieces` rows (t0, t1, ax, ay, bx, by)
    from ``piece_start[chunk_start[r] + k]`` on. `decided` False: nothing was decided
    (all empty), the kernels decide.
    """

    decided: bool
    chunk_start: np.ndarray
    decision: np.ndarray
    piece_start: np.ndarray
    keep: np.ndarray
    pieces: np.ndarray


class Lines(NamedTuple):
    """The parts and geometries of a ragged line array, and their windows.

    Geometry g owns parts ``geometry_parts[g]`` to ``geometry_parts[g+1] - 1``; part p
    runs through vertices ``part_offsets[p]`` to ``part_offsets[p+1] - 1`` (of a
    `Vertices`); geometry g is clipped against ``window_of(windows, geometry_window,
    g)``.
    """

    part_offsets: np.ndarray
    geometry_parts: np.ndarray
    windows: np.ndarray
    geometry_window: np.ndarray


class PartCounts(NamedTuple):
    """Per part: output vertices and chains (the count pass), and their starts (prefix sums).

    A part with a non-finite coordinate gets ``n_vertices = -1``. The starts are empty
    in the count pass.
    """

    n_vertices: np.ndarray
    n_chains: np.ndarray
    vertex_start: np.ndarray
    chain_start: np.ndarray


@scalar
def _edge_bits(x, y, window):
    """Return which window edge lines the point lies on (LEFT, RIGHT, BOTTOM, TOP bits)."""
    xmin, ymin, xmax, ymax = window
    return ((x == xmin) * 1) | ((x == xmax) * 2) | ((y == ymin) * 4) | ((y == ymax) * 8)


@scalar
def on_one_edge(ax, ay, bx, by, window):
    """Return whether the segment (a, b) of the closed window lies along one of its edges."""
    return (_edge_bits(ax, ay, window) & _edge_bits(bx, by, window)) != 0


@scalar
def bound_chains(xy, first, last, window):
    """Return upper bounds (vertices, chains, crossings) for clipping ``xy[first..last]``.

    A vertex inside the closed window is output at most once, twice if it lies on the
    boundary (rings break there); a segment that is neither inside nor beyond one edge
    (ambiguous) adds at most two cut points and one chain; a segment along an edge or a
    vertex on the boundary may break a chain. Crossings (all of those breaks) bound the
    chains' ends for polygon assembly. One branch-free pass, so the write pass can be
    given a slot without a counting pass that repeats the clipping.
    """
    xmin, ymin, xmax, ymax = window
    vertices = 0
    crossings = 0
    cp = outcode(xy[first, 0], xy[first, 1], xmin, ymin, xmax, ymax)
    bp = _edge_bits(xy[first, 0], xy[first, 1], window)
    vertices += cp == 0
    crossings += bp != 0
    for i in range(first + 1, last + 1):
        c = outcode(xy[i, 0], xy[i, 1], xmin, ymin, xmax, ymax)
        b = _edge_bits(xy[i, 0], xy[i, 1], window)
        vertices += c == 0
        ambiguous = ((cp | c) != 0) & ((cp & c) == 0)
        along = ((cp | c) == 0) & ((bp & b) != 0)
        crossings += ambiguous | along
        crossings += (b != 0) & (c == 0)
        cp = c
        bp = b
    return vertices + 2 * crossings, crossings + 1, crossings


@inlined
def _append(line, out, write, v, x, y, z):
    if write:
        out.xy[v, 0] = x
        out.xy[v, 1] = y
        if line.has_z:
            out.z[v] = z
    return v + 1


@inlined
def _emit_piece(line, out, write, i, piece, v, c, last_v, breaks):
    """Add `piece` of segment i to the chains; return (v, c, last_v).

    The piece continues the chain if the chain ends at vertex i and the piece starts
    there, unless `breaks` (rings break at a vertex on the boundary). Without `write`
    only the positions advance (the counting pass).
    """
    xy = line.xy
    z = line.z
    t0, t1, ax, ay, bx, by = piece
    if breaks or not (last_v == i and ax == xy[i, 0] and ay == xy[i, 1]):
        if write:
            out.starts[c] = v
        c += 1
        za = 0.0
        if line.has_z:
            za = z[i] if t0 == 0.0 else z[i] + t0 * (z[i + 1] - z[i])
        v = _append(line, out, write, v, ax, ay, za)
    end_is_vertex = bx == xy[i + 1, 0] and by == xy[i + 1, 1]
    zb = 0.0
    if line.has_z:
        zb = z[i + 1] if end_is_vertex else z[i] + t1 * (z[i + 1] - z[i])
    v = _append(line, out, write, v, bx, by, zb)
    return v, c, (i + 1) if end_is_vertex else -1


@inlined
def _emit_run(line, out, write, a, b, v, c, last_v):
    """Add the whole run of vertices a..b (inside the window); return (v, c, last_v).

    The copy runs over views of the coordinates as one row (``flat``) from index 0,
    which vectorizes.
    """
    start = a + 1
    if last_v != a:
        if write:
            out.starts[c] = v
        c += 1
        start = a
    count = b + 1 - start
    if write:
        src = line.flat[2 * start:2 * (b + 1)]
        dst = out.flat[2 * v:2 * (v + count)]
        for k in range(src.shape[0]):
            dst[k] = src[k]
        if line.has_z:
            src_z = line.z[start:b + 1]
            dst_z = out.z[v:v + count]
            for k in range(count):
                dst_z[k] = src_z[k]
    return v + count, c, b


@inlined
def _clip_segments(line, a, b, cut, break_at_boundary, options, out, write, v, c, last_v,
                   block):
    """Clip segments a..b-1 one by one into the chains; return (v, c, last_v).

    With `break_at_boundary` (rings) a chain also breaks at a vertex on the boundary, so
    that a ring touching the window's edge from inside is cut there too. Inlined: as a
    call, passing its records' hundred-odd words cost more per run than the segments
    (measured: the curve workload's write pass 20% slower).
    """
    xy = line.xy
    window = cut.window
    xmin, ymin, xmax, ymax = window
    st = block.st
    if options.method != RNSCA:
        for i in range(a, b):
            keep, t0, t1, ax, ay, bx, by = clip_one(
                xy[i, 0], xy[i, 1], xy[i + 1, 0], xy[i + 1, 1], window, options, st)
            v, c, last_v = _emit_visible(line, i, keep, Piece(t0, t1, ax, ay, bx, by), cut,
                                         break_at_boundary, out, write, v, c, last_v)
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
            visible = not (cut.drop_edge_runs and on_one_edge(xy[i, 0], xy[i, 1], xy[i + 1, 0],
                                                              xy[i + 1, 1], window))
            breaks = break_at_boundary and _edge_bits(xy[i, 0], xy[i, 1], window) != 0
            if stretch >= 0 and (breaks or not visible):
                v, c, last_v = _emit_run(line, out, write, stretch, i, v, c, last_v)
                stretch = -1
            if visible and stretch < 0:
                stretch = i
                if breaks:
                    last_v = -1  # the stretch starts a chain of its own
            continue
        if stretch >= 0:
            v, c, last_v = _emit_run(line, out, write, stretch, i, v, c, last_v)
            stretch = -1
        if c0 & c1:
            rejected += 1
            continue
        keep, t0, t1, ax, ay, bx, by = rnsca_segment(
            xy[i, 0], xy[i, 1], xy[i + 1, 0], xy[i + 1, 1], window, options, st,
            block.segment_stack)
        v, c, last_v = _emit_visible(line, i, keep, Piece(t0, t1, ax, ay, bx, by), cut,
                                     break_at_boundary, out, write, v, c, last_v)
    if stretch >= 0:
        v, c, last_v = _emit_run(line, out, write, stretch, b, v, c, last_v)
    st[C.EVALUATED] += accepted + rejected
    st[C.LEVELS] += accepted + rejected
    st[C.ACCEPTED] += accepted
    st[C.REJECTED] += rejected
    return v, c, last_v


@inlined
def _emit_visible(line, i, keep, piece, cut, break_at_boundary, out, write, v, c, last_v):
    """Add the piece of segment i the segment core kept, unless it is not visible."""
    if keep and not (cut.drop_edge_runs and on_one_edge(piece.ax, piece.ay, piece.bx,
                                                        piece.by, cut.window)):
        breaks = break_at_boundary and _edge_bits(line.xy[i, 0], line.xy[i, 1],
                                                  cut.window) != 0
        return _emit_piece(line, out, write, i, piece, v, c, last_v, breaks)
    return v, c, last_v


@scalar
def run_box_codes(xy, a, b, window):
    """Return the outcodes of the bounding box corners of vertices a..b, and strictness.

    The third value says whether the box lies strictly inside the window (no vertex on
    an edge line), which ``drop_edge_runs`` needs before accepting a run whole.
    """
    xmin, ymin, xmax, ymax = window
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
def vertex_code(x, y, window, strict):
    """Return the vertex code: outcode, `NOT_FINITE`, if `strict` `NOT_STRICTLY_INSIDE`.

    The OR and AND of a run's codes classify the run as its bounding box's outcodes
    would (see the module docstring). ``x - x == y - y`` is false exactly when x or y is
    NaN or infinite (IEEE arithmetic; no fast-math flag is set).
    """
    xmin, ymin, xmax, ymax = window
    code = outcode(x, y, xmin, ymin, xmax, ymax) | (not (x - x == y - y)) * NOT_FINITE
    if strict:
        code |= ((x <= xmin) | (x >= xmax) | (y <= ymin) | (y >= ymax)) * NOT_STRICTLY_INSIDE
    return code


@scalar
def chunk_count(first, last):
    """Return how many chunks of `RUN_LEAF_SEGMENTS` segments the line first..last has."""
    return 0 if last <= first else (last - first + RUN_LEAF_SEGMENTS - 1) // RUN_LEAF_SEGMENTS


@borrowing
def code_chunks(flat, first, last, window, strict, codes, chunk_or, chunk_and, c0):
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
            codes[i] = vertex_code(points[2 * i], points[2 * i + 1], window, strict)
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
def _vertex_run_codes(xy, a, b, window, strict):
    """Return the OR and AND of the codes of vertices a..b (`vertex_code`)."""
    any_ = 0
    every = _ALL_CODE_BITS
    for k in range(a, b + 1):
        code = vertex_code(xy[k, 0], xy[k, 1], window, strict)
        any_ |= code
        every &= code
    return any_, every


@borrowing_per_constant  # each caller's flags fold away (see `rnsca.kernels.jit`)
def clip_chains(line, first, last, cut, break_at_boundary, options, out, write, v, c, block,
                part):
    """Clip the line through vertices ``line.xy[first..last]`` into chains.

    Writes the chains' vertices from ``out.xy[v]`` (and ``out.z``) on, and the start of
    each chain at ``out.starts[c]`` on; the caller guarantees room (`bound_chains`).
    Returns ``(v, c, starts_at_first, ends_at_last, plan_end)``: the next free
    positions, whether the first chain starts at vertex `first` itself, whether the
    last ends at vertex `last` (a ring's chains across its closing vertex join there),
    and the end of the plan (below).

    With `break_at_boundary` (rings) a chain also breaks at a vertex on the boundary.
    Runs are whole chunks of `RUN_LEAF_SEGMENTS` segments, classified by the OR and AND
    of their vertex codes: from the part's chunk codes (``part.chunk_or``,
    ``part.chunk_and``, see `code_chunks`, which must have been given
    ``strict=cut.drop_edge_runs``) or, if those are empty, from the vertices. Runs are
    pruned only for ``options.method == RNSCA``; the baselines clip every segment.
    Without `write` nothing is written and only the counts come back (the exact
    counting pass).

    If ``part.plan`` (int64 (k, 2)) is not empty, the decided runs that leave something
    are also recorded in its rows, in input order, for `emit_plan` to replay without
    deciding again: ``[first chunk, end chunk]`` for a run accepted whole (adjacent
    ones merged), ``[first chunk, -end chunk]`` for a run clipped segment by segment. A
    line of k chunks needs at most k rows; the last value returned is how many it took.
    """
    c_begin = c
    last_v = -1
    if last <= first:
        return v, c, False, False, 0
    xy = line.xy
    window = cut.window
    drop_edge_runs = cut.drop_edge_runs
    chunk_or = part.chunk_or
    chunk_and = part.chunk_and
    plan = part.plan
    st = block.st
    run_stack = block.run_stack
    coded = chunk_or.shape[0] > 0
    recording = plan.shape[0] > 0
    n_plan = 0
    if options.method != RNSCA:
        v, c, last_v = _clip_segments(line, first, last, cut, break_at_boundary, options, out,
                                      write, v, c, last_v, block)
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
        n_runs = options.n_fixed if options.n_fixed > 0 else RUN_N_AUTO
        put_interval(run_stack, 0, 0, chunk_count(first, last), 0)
        sp = 1
        while sp > 0:
            sp -= 1
            ca, cb, level = interval_at(run_stack, sp)
            a = first + ca * RUN_LEAF_SEGMENTS
            b = min(first + cb * RUN_LEAF_SEGMENTS, last)
            slot = _level_slot(level)
            deepest = max(deepest, level)
            evaluated += 1
            if coded:
                any_, every = _chunk_run_codes(chunk_or, chunk_and, ca, cb)
            else:
                any_, every = _vertex_run_codes(xy, a, b, window, drop_edge_runs)
            if (any_ & OUTSIDE) == 0 and not (drop_edge_runs and (any_ & NOT_STRICTLY_INSIDE)):
                accepted += 1
                st[C.RUN_LEVELS + slot] += 1
                st[C.SEGMENT_LEVELS + slot] += b - a
                v, c, last_v = _emit_run(line, out, write, a, b, v, c, last_v)
                if recording:
                    if n_plan > 0 and plan[n_plan - 1, 1] == ca:
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
                v, c, last_v = _clip_segments(line, a, b, cut, break_at_boundary, options, out,
                                              write, v, c, last_v, block)
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
                    put_interval(run_stack, sp + k - j, lo, hi, level + 1)
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
    starts_at_first = _starts_at(line, first, window, break_at_boundary, out, c_begin)
    return v, c, starts_at_first, last_v == last, n_plan


@inlined
def _starts_at(line, first, window, break_at_boundary, out, c_begin):
    """Return whether chain `c_begin` (written) starts at vertex `first` and continues it.

    A ring breaks at its closing vertex on the boundary: its first chain then does not
    continue its last one there.
    """
    xy = line.xy
    start = out.starts[c_begin]
    if not (out.xy[start, 0] == xy[first, 0] and out.xy[start, 1] == xy[first, 1]):
        return False
    return not (break_at_boundary and _edge_bits(xy[first, 0], xy[first, 1], window) != 0)


@borrowing
def emit_plan(line, first, last, cut, options, out, v, c, block, plan):
    """Write the chains of the line ``line.xy[first..last]`` as `clip_chains` recorded them.

    Replays `plan` (the part's rows): runs accepted whole are copied, the others clipped
    segment by segment, exactly as `clip_chains` did when it recorded them. Returns
    ``(v, c)``. The segment core counts into ``block.st`` again (give it a scratch row).
    """
    last_v = -1
    for k in range(plan.shape[0]):
        a = first + plan[k, 0] * RUN_LEAF_SEGMENTS
        if plan[k, 1] >= 0:
            b = min(first + plan[k, 1] * RUN_LEAF_SEGMENTS, last)
            v, c, last_v = _emit_run(line, out, True, a, b, v, c, last_v)
        else:
            b = min(first - plan[k, 1] * RUN_LEAF_SEGMENTS, last)
            v, c, last_v = _clip_segments(line, a, b, cut, False, options, out, True, v, c,
                                          last_v, block)
    return v, c


@scalar_per_constant
def _line_block(blk, block_size, line, lines, options, drop_edge_runs, write, chunks, counts,
                out, counters):
    """Count or write the parts of geometries ``blk * block_size`` on: the body of a pass.

    The count pass codes each part's chunks (`code_chunks`, which also checks that the
    coordinates are finite: a part with a non-finite one gets ``n_vertices = -1``),
    runs RNSCA over its runs (`clip_chains` without writing), which counts the output
    exactly and the stats into the block's counter row, and records the decided runs in
    the part's rows of ``chunks.plan`` (from ``chunk_start[p]`` to ``plan_end[p]``). The
    write pass replays the plan (`emit_plan`) from ``counts.vertex_start[p]`` and
    ``counts.chain_start[p]``: runs are not decided twice, and only the segments of
    ambiguous chunks are clipped twice. Allocates the block's state; the parts are done
    by `_line_parts`, which borrows it.
    """
    st = np.zeros(C.WIDTH, dtype=np.int64) if write else counters[blk]
    # The write pass replays plans: it needs neither the run stack nor the code scratch.
    block = BlockState(st, np.empty((0 if write else RUN_STACK_CAPACITY, 3), dtype=np.int64),
                       segment_stack(),
                       np.empty(0 if write else CODE_SCRATCH_BYTES, dtype=np.uint8))
    n_geometries = lines.geometry_parts.shape[0] - 1
    _line_parts(blk * block_size, min(n_geometries, (blk + 1) * block_size), line, lines,
                options, drop_edge_runs, write, chunks, counts, out, block)


@borrowing_per_constant
def _line_parts(g_begin, g_end, line, lines, options, drop_edge_runs, write, chunks, counts,
                out, block):
    """Count or write the parts of geometries g_begin..g_end-1 (see `_line_block`)."""
    part_offsets = lines.part_offsets
    geometry_parts = lines.geometry_parts
    for g in range(g_begin, g_end):
        cut = Cut(window_of(lines.windows, lines.geometry_window, g), drop_edge_runs)
        for p in range(geometry_parts[g], geometry_parts[g + 1]):
            first = part_offsets[p]
            last = part_offsets[p + 1] - 1
            c0 = chunks.chunk_start[p]
            if write:
                emit_plan(line, first, last, cut, options, out, counts.vertex_start[p],
                          counts.chain_start[p], block, chunks.plan[c0:chunks.plan_end[p]])
                continue
            line_or, _ = code_chunks(line.flat, first, last, cut.window, drop_edge_runs,
                                     block.codes, chunks.chunk_or, chunks.chunk_and, c0)
            if line_or & NOT_FINITE:
                counts.n_vertices[p] = -1
                counts.n_chains[p] = 0
                chunks.plan_end[p] = c0
                continue
            part = PartPlan(chunks.chunk_or[c0:], chunks.chunk_and[c0:], chunks.plan[c0:])
            v, c, _, _, rows = clip_chains(line, first, last, cut, False, options, out, False, 0,
                                           0, block, part)
            chunks.plan_end[p] = c0 + rows
            counts.n_vertices[p] = v
            counts.n_chains[p] = c


@parallel_per_constant
def _line_pass(block_size, line, lines, options, drop_edge_runs, write, chunks, counts, out,
               counters):
    """Run `_line_block` over every block, one prange iteration each."""
    for blk in prange(counters.shape[0]):
        # int64, as the serial pass passes it: one specialisation of the block, not two
        _line_block(np.int64(blk), block_size, line, lines, options, drop_edge_runs, write, chunks,
                    counts, out, counters)


@scalar_per_constant
def _line_pass_serial(block_size, line, lines, options, drop_edge_runs, write, chunks, counts,
                      out, counters):
    """Do what `_line_pass` does on the calling thread (small inputs)."""
    for blk in range(counters.shape[0]):
        _line_block(blk, block_size, line, lines, options, drop_edge_runs, write, chunks,
                    counts, out, counters)


@scalar
def _exclusive_sum(counts):
    out = np.empty(counts.shape[0] + 1, dtype=np.int64)
    out[0] = 0
    for i in range(counts.shape[0]):
        out[i + 1] = out[i] + counts[i]
    return out


@scalar
def clip_lines(line, lines, options, drop_edge_runs):
    """Clip every part of a ragged line array into chains: count, prefix sum, write.

    Parameters
    ----------
    line : Vertices
        The vertices: ``xy`` float64 (n, 2), C-contiguous, checked here to be finite
        (fused into the coding pass); ``z`` finite, or empty for 2D.
    lines : Lines
        The parts (no part of exactly one vertex), their geometries and windows
        (``geometry_window`` empty: row 0 for all geometries).
    options : CoreOptions
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
    part_offsets = lines.part_offsets
    geometry_parts = lines.geometry_parts
    n_parts = part_offsets.shape[0] - 1
    n_geometries = geometry_parts.shape[0] - 1
    has_z = line.has_z
    chunk_start = np.empty(n_parts + 1, dtype=np.int64)
    chunk_start[0] = 0
    for p in range(n_parts):
        chunk_start[p + 1] = chunk_start[p] + chunk_count(part_offsets[p],
                                                          part_offsets[p + 1] - 1)
    chunks = Chunks(chunk_start, np.empty(chunk_start[n_parts], dtype=np.uint8),
                    np.empty(chunk_start[n_parts], dtype=np.uint8),
                    np.empty((max(chunk_start[n_parts], 1), 2), dtype=np.int64),
                    np.empty(n_parts, dtype=np.int64))
    # About 64 blocks for load balance, 1..1024 geometries each.
    block_size = max(1, min(1024, (n_geometries + 63) // 64))
    n_blocks = max(1, (n_geometries + block_size - 1) // block_size)
    serial = line.xy.shape[0] < SERIAL_VERTICES
    counters = np.zeros((n_blocks, C.WIDTH), dtype=np.int64)
    nothing_i = np.empty(0, dtype=np.int64)
    nothing_xy = np.empty((0, 2), dtype=np.float64)
    nothing_z = np.empty(0, dtype=np.float64)
    counts = PartCounts(np.empty(n_parts, dtype=np.int64), np.empty(n_parts, dtype=np.int64),
                        nothing_i, nothing_i)
    nowhere = ChainsOut(nothing_xy, nothing_xy.reshape(-1), nothing_z, nothing_i)
    if serial:
        _line_pass_serial(block_size, line, lines, options, drop_edge_runs, False, chunks,
                          counts, nowhere, counters)
    else:
        _line_pass(block_size, line, lines, options, drop_edge_runs, False, chunks, counts,
                   nowhere, counters)
    n_vertices = counts.n_vertices
    for p in range(n_parts):
        if n_vertices[p] < 0:
            return nothing_xy, nothing_z, np.zeros(1, dtype=np.int64), \
                np.zeros(n_geometries + 1, dtype=np.int64), counters, p
    vertex_start = _exclusive_sum(counts.n_vertices)
    chain_start = _exclusive_sum(counts.n_chains)
    m = vertex_start[n_parts]
    out_xy = np.empty((m, 2), dtype=np.float64)
    out_z = np.empty(m if has_z else 0, dtype=np.float64)
    chain_offsets = np.empty(chain_start[n_parts] + 1, dtype=np.int64)
    chain_offsets[chain_start[n_parts]] = m
    counts = PartCounts(counts.n_vertices, counts.n_chains, vertex_start, chain_start)
    out = ChainsOut(out_xy, out_xy.reshape(-1), out_z, chain_offsets)
    if serial:
        _line_pass_serial(block_size, line, lines, options, drop_edge_runs, True, chunks,
                          counts, out, counters)
    else:
        _line_pass(block_size, line, lines, options, drop_edge_runs, True, chunks, counts, out,
                   counters)
    geometry_chains = np.empty(n_geometries + 1, dtype=np.int64)
    geometry_chains[0] = 0
    for g in range(n_geometries):
        geometry_chains[g + 1] = chain_start[geometry_parts[g + 1]]
    return out_xy, out_z, chain_offsets, geometry_chains, counters, -1


@borrowing
def assemble_chains(line, first, last, cut, break_at_boundary, decisions, chunk0, out, write,
                    v, c):
    """Emit the chains of the line ``line.xy[first..last]`` from decisions made elsewhere.

    ``decisions.decision[chunk0 + k]`` says what became of the line's chunk k
    (``CHUNK_*``); the segments of a segmented chunk have ``keep`` and ``pieces`` rows
    (t0, t1, ax, ay, bx, by) from ``piece_start[chunk0 + k]`` on. The chains are the
    ones `clip_chains` emits for those decisions (its `_emit_run` and `_emit_piece`; an
    accepted run of chunks copied chunk by chunk is the same chain), and so is the
    return value: ``(v, c, starts_at_first, ends_at_last)``.
    """
    xy = line.xy
    decision = decisions.decision
    keep = decisions.keep
    pieces = decisions.pieces
    c_begin = c
    last_v = -1
    for k in range(chunk_count(first, last)):
        a = first + k * RUN_LEAF_SEGMENTS
        b = min(a + RUN_LEAF_SEGMENTS, last)
        d = decision[chunk0 + k]
        if d == CHUNK_ACCEPTED:
            v, c, last_v = _emit_run(line, out, write, a, b, v, c, last_v)
        elif d == CHUNK_SEGMENTED:
            row = decisions.piece_start[chunk0 + k]
            for i in range(a, b):
                if keep[row]:
                    piece = Piece(pieces[row, 0], pieces[row, 1], pieces[row, 2],
                                  pieces[row, 3], pieces[row, 4], pieces[row, 5])
                    if not (cut.drop_edge_runs and on_one_edge(piece.ax, piece.ay, piece.bx,
                                                               piece.by, cut.window)):
                        breaks = break_at_boundary and _edge_bits(
                            xy[i, 0], xy[i, 1], cut.window) != 0
                        v, c, last_v = _emit_piece(line, out, write, i, piece, v, c, last_v,
                                                   breaks)
                row += 1
    if c == c_begin or not write:
        return v, c, False, False
    return v, c, _starts_at(line, first, cut.window, break_at_boundary, out, c_begin), \
        last_v == last


@parallel
def assemble_line_blocks(line, part_offsets, windows, part_window, drop_edge_runs, block_size,
                         write, decisions, counts, out):
    """Count (``write=False``) or write the chains of every part from device decisions.

    The host half of the OpenCL line clip (`assemble_chains` per part, against
    ``window_of(windows, part_window, p)``); the counts and the layout are those of
    `clip_lines`.
    """
    n_parts = part_offsets.shape[0] - 1
    n_blocks = -(-n_parts // block_size)
    for blk in prange(n_blocks):
        _assemble_block(np.int64(blk), line, part_offsets, windows, part_window, drop_edge_runs,
                        block_size, write, decisions, counts, out)


@borrowing
def _assemble_block(blk, line, part_offsets, windows, part_window, drop_edge_runs, block_size,
                    write, decisions, counts, out):
    """Count or write the chains of parts ``blk * block_size`` on (`assemble_line_blocks`)."""
    n_parts = part_offsets.shape[0] - 1
    for p in range(blk * block_size, min(n_parts, (blk + 1) * block_size)):
        cut = Cut(window_of(windows, part_window, p), drop_edge_runs)
        v0 = counts.vertex_start[p] if write else 0
        c0 = counts.chain_start[p] if write else 0
        v, c, _, _ = assemble_chains(line, part_offsets[p], part_offsets[p + 1] - 1, cut, False,
                                     decisions, decisions.chunk_start[p], out, write, v0, c0)
        if not write:
            counts.n_vertices[p] = v
            counts.n_chains[p] = c
