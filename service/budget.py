"""Limits on what one request may cost, checked before any clipping.

Two limits: the input's size in vertices (``max_vertices``, 413) and an estimate of the
work, in fragments evaluated (``work_budget``, 422). Every fragment costs about the same
(measured: 17-22 ns each with two threads, for every method and mode), so the estimate is
a bound on the time a request can take.

The bound follows RNSCA's recursion. A segment is decided at level 0 unless it is
ambiguous (its end outcodes differ and share no outside bit); an ambiguous piece splits
into N pieces, and at each level at most four pieces of a straight segment are ambiguous
(one per crossing of an extended window edge: a piece that crosses none has both ends in
one of the nine regions, so it is accepted or rejected). Subdivision stops at
``max_depth`` or once a piece is no longer than ``tolerance``. Exact mode with the default
(infinite) tolerance never subdivides, and the analytic methods never do: their work is
one fragment per segment (a few more for Cohen–Sutherland, counted as one).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from rnsca.kernels.segments import auto_n
from rnsca.options import MAX_DEPTH_LIMIT, Method, Mode, approx_tolerance
from rnsca.window import Window
from service.errors import TooManyVerticesError, WorkOverBudgetError

if TYPE_CHECKING:
    from service.schemas import ClipOptions

__all__ = ["subdivision_cost", "segment_work", "check_vertices", "check_work",
           "geometry_vertex_cap", "AMBIGUOUS_PER_LEVEL"]

#: Ambiguous pieces per level of one straight segment, at most.
AMBIGUOUS_PER_LEVEL = 4


def _subdivides(options: ClipOptions, window: Window) -> bool:
    if options.method not in (Method.RNSCA, Method.MIDPOINT):
        return False
    return options.mode is Mode.APPROX or options.tolerance is not None


def _tolerance(options: ClipOptions, window: Window) -> float:
    if options.tolerance is not None:
        return options.tolerance
    return approx_tolerance(window, options.resolution)


def subdivision_cost(options: ClipOptions, window: Window, length: float | None) -> int:
    """Return the most fragments one ambiguous segment of `length` can add below level 0.

    `length` None means unknown (the bound then runs to ``max_depth``).

    Examples
    --------
    >>> from service.schemas import ClipOptions
    >>> w = Window(0, 0, 1, 1)
    >>> subdivision_cost(ClipOptions(), w, 100.0)   # exact, infinite tolerance
    0
    >>> approx = ClipOptions.model_validate({"mode": "approx", "n": 2, "max_depth": 3},
    ...                                     strict=False)
    >>> subdivision_cost(approx, w, 100.0)
    24
    """
    if not _subdivides(options, window):
        return 0
    depth = MAX_DEPTH_LIMIT if options.max_depth is None else options.max_depth
    tolerance = _tolerance(options, window)
    piece = math.inf if length is None else float(length)
    cost = 0
    for level in range(1, depth + 1):
        if piece <= tolerance:
            break
        if options.method is Method.MIDPOINT:
            n = 2
        elif options.n == "auto":
            n = auto_n(piece, tolerance, depth - level + 1)  # the kernel's own rule
        else:
            n = options.n
        cost += AMBIGUOUS_PER_LEVEL * n
        piece /= n
    return cost


def segment_work(segments: np.ndarray, window: Window, options: ClipOptions) -> int:
    """Return the bound on fragments evaluated for clipping `segments` (n, 4) float64."""
    count = segments.shape[0]
    if count == 0 or not _subdivides(options, window):
        return count
    x0, y0, x1, y1 = segments.T
    with np.errstate(invalid="ignore", over="ignore"):
        codes0 = _outcodes(x0, y0, window)
        codes1 = _outcodes(x1, y1, window)
        ambiguous = ((codes0 | codes1) != 0) & ((codes0 & codes1) == 0)
        lengths = np.hypot(x1 - x0, y1 - y0)[ambiguous]
    if not ambiguous.any():
        return count
    longest = float(lengths.max())
    return count + int(ambiguous.sum()) * subdivision_cost(
        options, window, longest if math.isfinite(longest) else None)


def _outcodes(x: np.ndarray, y: np.ndarray, window: Window) -> np.ndarray:
    return ((x < window.xmin).astype(np.uint8) | (x > window.xmax) << 1
            | (y < window.ymin) << 2 | (y > window.ymax) << 3)


def check_vertices(vertices: int, limit: int) -> None:
    """Raise `TooManyVerticesError` if `vertices` exceeds `limit`."""
    if vertices > limit:
        raise TooManyVerticesError(
            f"the input has {vertices} vertices, more than this server's limit of {limit}",
            vertices=vertices, limit=limit)


def check_work(work: int, budget: int) -> None:
    """Raise `WorkOverBudgetError` if the estimated `work` exceeds `budget`."""
    if work > budget:
        raise WorkOverBudgetError(
            f"the request may evaluate up to {work} fragments, more than this server's "
            f"work budget of {budget}; lower options.max_depth or options.n, use exact "
            "mode with no tolerance, or send less input", work=work, budget=budget)


def geometry_vertex_cap(options: ClipOptions, window: Window, max_vertices: int,
                        budget: int) -> tuple[int, bool]:
    """Return the most vertices a geometry request may have, and whether the budget set it.

    The length of a geometry's segments is not known before it is read, so every vertex
    is charged the bound of a segment of unknown length.

    Examples
    --------
    >>> from service.schemas import GeometryOptions
    >>> geometry_vertex_cap(GeometryOptions(), Window(0, 0, 1, 1), 1000, 10**9)
    (1000, False)
    >>> approx = GeometryOptions.model_validate({"mode": "approx", "n": 2, "max_depth": 4},
    ...                                         strict=False)
    >>> geometry_vertex_cap(approx, Window(0, 0, 1, 1), 1000, 3300)
    (100, True)
    """
    per_vertex = 1 + subdivision_cost(options, window, None)
    by_budget = budget // per_vertex
    return (by_budget, True) if by_budget < max_vertices else (max_vertices, False)
