"""Clip SVG paths (lines, quadratic and cubic Béziers, arcs) against a window.

`clip_paths` is the columnar form on `PathArrays`; `clip_svg` reads and writes path
data strings around it. `flatten_paths` turns paths into polylines (for verification
and for the flatten-then-clip baseline). The algorithm is in `rnsca.kernels.bezier`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np

from rnsca.arrays import exclusive_sum
from rnsca.backends.registry import get_backend
from rnsca.errors import InvalidOptionError
from rnsca.io.svgpath import PathArrays, parse_paths, write_paths
from rnsca.kernels import bezier as BZ
from rnsca.kernels import counters as C
from rnsca.options import (
    MAX_DEPTH_LIMIT,
    Backend,
    Method,
    Mode,
    _ChoiceEnum,
    positive_tolerance,
    subdivision_depth,
    subdivision_n,
)
from rnsca.stats import ClipStats
from rnsca.window import Window

__all__ = [
    "Curves",
    "Fill",
    "PathClipResult",
    "clip_paths",
    "clip_svg",
    "flatten_paths",
    "CURVE_RELATIVE_TOLERANCE",
]

#: Default `tolerance` of curve clipping, relative to the window's longer side: how far
#: flattened lines may stray from the curve (``curves="flatten"``), and the size below
#: which approx mode stops subdividing.
CURVE_RELATIVE_TOLERANCE = 1e-6

# Subpaths per block of the parallel kernel: enough work per block to pay for its
# scratch arrays, enough blocks to balance the threads (at most _BLOCK subpaths, and at
# least _MIN_BLOCKS blocks when there are that many subpaths: a few long paths, such as
# the 200 curves of 500 cubics of the benchmark, are still shared out evenly).
_BLOCK = 64
_MIN_BLOCKS = 32


class Curves(_ChoiceEnum):
    """What the clipped output is made of."""

    PRESERVE = "preserve"
    """Béziers of the input's degrees, cut where they cross the window's edges."""
    FLATTEN = "flatten"
    """Lines: curves flattened within `tolerance`, then clipped as lines."""


class Fill(str, Enum):
    """How a closed path is filled; the clip keeps the fill inside the window."""

    NONZERO = "nonzero"
    EVENODD = "evenodd"

    @classmethod
    def of(cls, value) -> Fill | None:
        """Return the fill rule, or None (strokes) for None or "none"."""
        if value is None or (isinstance(value, str) and value.lower() == "none"):
            return None
        if isinstance(value, cls):
            return value
        if isinstance(value, str):
            for member in cls:
                if member.value == value.lower():
                    return member
        raise InvalidOptionError(
            f"fill must be 'nonzero', 'evenodd' or None (strokes), got {value!r}")


@dataclass(frozen=True, slots=True)
class PathClipResult:
    """Clipped paths: one output path per input path (empty where nothing is left).

    Attributes
    ----------
    paths : PathArrays
        The clipped paths, in input order.
    stats : ClipStats
        ``segments_in`` counts input segments (closing edges included);
        ``pieces_out`` output segments; fragments are pieces of segments tested by the
        outcodes of their control points.
    curves, fill, mode : str or None
        The options the clip ran with (``fill`` None for strokes), for `rnsca.verify`.
    tolerance : float
        The clip's tolerance (flattening, approx leaves), user units.
    """

    paths: PathArrays
    stats: ClipStats
    curves: str = "preserve"
    fill: str | None = None
    mode: str = "exact"
    tolerance: float = 0.0


@dataclass(frozen=True, slots=True)
class _CurveOptions:
    curves: Curves
    fill: Fill | None
    mode: Mode
    n_split: int
    leaf_depth: int
    tolerance: float
    backend: Backend


def _resolve(window: Window, *, curves, fill, tolerance, method, n, max_depth, mode,
             backend) -> _CurveOptions:
    curves = Curves(curves)
    fill = Fill.of(fill)
    mode = Mode(mode)
    if Method(method) is not Method.RNSCA:
        raise InvalidOptionError(
            f"curves are clipped by method='rnsca' only, got {method!r} (the line "
            "baselines clip curves after flatten_paths)")
    backend = Backend(backend)
    if backend not in (Backend.NUMBA, Backend.OPENCL):
        raise InvalidOptionError(
            f"curves are clipped on backend='numba' or 'opencl', got {backend.value!r}")
    n_split = subdivision_n(n)
    if n_split is None:
        n_split = BZ.CURVE_N_AUTO
    depth = subdivision_depth(max_depth, BZ.EXACT_LEAF_DEPTH if (
        mode is Mode.EXACT and curves is Curves.PRESERVE) else MAX_DEPTH_LIMIT)
    tol = window.size * CURVE_RELATIVE_TOLERANCE if tolerance is None else \
        positive_tolerance(tolerance, finite=True)
    return _CurveOptions(curves, fill, mode, n_split, depth, tol, backend)


def _kernel_input(paths: PathArrays, subpath_source, window: Window,
                  options: _CurveOptions) -> tuple[BZ.PathInput, BZ.Box, BZ.Options]:
    """Return the path kernel's records of the paths, the window and the options."""
    return (BZ.PathInput(paths.controls, paths.degree, paths.subpath_offsets, paths.closed,
                         paths.start, subpath_source),
            BZ.Box(*window.bounds),
            BZ.Options(fill=options.fill is not None, flatten=options.curves is Curves.FLATTEN,
                       exact=options.mode is Mode.EXACT, n_split=int(options.n_split),
                       leaf_depth=int(options.leaf_depth),
                       tolerance=float(options.tolerance)))


def clip_paths(paths: PathArrays, window, *, curves="preserve", fill=None, tolerance=None,
               method="rnsca", n="auto", max_depth=None, mode="exact",
               backend="numba") -> PathClipResult:
    """Return paths clipped to a rectangular window, keeping curves as curves.

    Parameters
    ----------
    paths : PathArrays
        Paths of lines, quadratic and cubic Béziers (`rnsca.io.svgpath`).
    window : Window or sequence of 4 floats
        The closed window ``(xmin, ymin, xmax, ymax)``.
    curves : {"preserve", "flatten"}
        "preserve": visible parts as Béziers of the same degree, cut exactly where
        they cross an edge (to about 1e-15 of the parameter, ends snapped onto the
        edge). "flatten": lines within `tolerance` of the curves.
    fill : {None, "nonzero", "evenodd"}
        None: paths are strokes; each visible part becomes an open subpath (a closed
        subpath visible whole stays closed). A fill rule: each subpath is closed and
        gives one closed subpath whose fill inside the window, under that rule, is
        the input's (outside parts are replaced by runs along the window's edge);
        subpaths that leave nothing are dropped.
    tolerance : float, optional
        Flattening accuracy and approx mode's smallest piece, in user units; default
        `CURVE_RELATIVE_TOLERANCE` times the window's longer side.
    method, n, max_depth, mode, backend
        RNSCA's options: N pieces per split (``"auto"``: 4), deepest level (default:
        0 in exact preserve mode, where an ambiguous segment is solved exactly whole
        (measured fastest); 32 otherwise),
        ``mode="approx"`` drops undecided leaves (no root finding; the output stays
        inside the window). ``backend="opencl"`` (float64 devices) classifies every
        segment by its control points, and flattens the curves accepted whole, on the
        device, and runs of segments by their box; the ambiguous segments and the
        output are done on the host by the Numba kernel, from the device's decisions:
        the output is the same.

    Returns
    -------
    PathClipResult

    Raises
    ------
    InvalidWindowError, InvalidOptionError
        (ValueError) naming the bad value.
    """
    window = Window.of(window)
    options = _resolve(window, curves=curves, fill=fill, tolerance=tolerance, method=method,
                       n=n, max_depth=max_depth, mode=mode, backend=backend)
    n_subpaths = paths.closed.shape[0]
    subpath_source = np.repeat(np.arange(len(paths), dtype=np.int64),
                               np.diff(paths.path_offsets))
    block = max(1, min(_BLOCK, n_subpaths // _MIN_BLOCKS))
    n_blocks = max(1, -(-n_subpaths // block))
    counters = np.zeros((n_blocks, C.WIDTH), dtype=np.int64)
    n_segments = np.zeros(n_subpaths, dtype=np.int64)
    n_out = np.zeros(n_subpaths, dtype=np.int64)
    kernel_input = _kernel_input(paths, subpath_source, window, options)
    nothing = np.empty(0, dtype=np.int64)
    device_stats = None
    if options.backend is Backend.OPENCL:
        segment_class, run_decisions, point_start, points, device_stats = get_backend(
            options.backend).classify_curves(
                paths.controls, paths.degree, window, options.tolerance,
                "accepted" if options.curves is Curves.FLATTEN else "none",
                paths.subpath_offsets)
        decisions = BZ.Decisions(True, run_decisions, segment_class, point_start, points)
    else:
        decisions = BZ.Decisions(False, np.empty(paths.degree.shape[0], dtype=np.int8),
                                 np.empty(0, np.uint8), nothing, np.empty((0, 2)))
    BZ.clip_path_blocks(*kernel_input, decisions,
                        BZ.Layout(n_segments, n_out, nothing, nothing),
                        BZ.Output(False, np.empty((0, 4, 2)), np.empty(0, np.int8), nothing,
                                  np.empty((0, 2)), np.empty(0, bool), nothing),
                        counters, block)
    segment_start = exclusive_sum(n_segments)
    subpath_start = exclusive_sum(n_out)
    m = int(segment_start[-1])
    k = int(subpath_start[-1])
    out_ctrl = np.empty((m, 4, 2))
    out_deg = np.empty(m, dtype=np.int8)
    out_first = np.empty(k + 1, dtype=np.int64)
    out_first[k] = m
    out_start = np.empty((k, 2))
    out_closed = np.empty(k, dtype=bool)
    out_from = np.empty(k, dtype=np.int64)
    BZ.clip_path_blocks(*kernel_input, decisions,
                        BZ.Layout(n_segments, n_out, segment_start, subpath_start),
                        BZ.Output(True, out_ctrl, out_deg, out_first, out_start, out_closed,
                                  out_from),
                        np.zeros((n_blocks, C.WIDTH), dtype=np.int64), block)
    kept = out_from >= 0
    if not kept.all():  # entries freed by joining the two ends of a closed stroke
        out_first = np.append(out_first[:-1][kept], m)
        out_start, out_closed, out_from = out_start[kept], out_closed[kept], out_from[kept]
    path_offsets = exclusive_sum(np.bincount(out_from, minlength=len(paths)))
    clipped = PathArrays.from_kernel(controls=out_ctrl, degree=out_deg,
                                     subpath_offsets=out_first, closed=out_closed,
                                     start=out_start, path_offsets=path_offsets)
    segments_in = paths.degree.shape[0] + BZ.closing_edges(
        paths.controls, paths.subpath_offsets, paths.closed, paths.start, options.fill is not None)
    non_empty = int((np.diff(path_offsets) > 0).sum())
    stats = ClipStats.from_counters(counters, segments_in, m, geometries_in=len(paths),
                                    geometries_out=non_empty,
                                    vertices_in=int(paths.controls.shape[0]),
                                    vertices_out=m, device=device_stats)
    return PathClipResult(clipped, stats, options.curves.value,
                          None if options.fill is None else options.fill.value,
                          options.mode.value, options.tolerance)


def clip_svg(d, window, *, curves="preserve", fill=None, tolerance=None, precision=None,
             **options):
    """Return SVG path data clipped to a rectangular window, and the stats.

    Parameters
    ----------
    d : str or sequence of str
        Path data (the ``d`` attribute), or many (clipped in one parallel call).
    window : Window or sequence of 4 floats
        The closed window ``(xmin, ymin, xmax, ymax)``, in the path's user units.
    curves, fill, tolerance, **options
        As for `clip_paths` (``method``, ``n``, ``max_depth``, ``mode``,
        ``backend``). Arcs are read as cubics within `tolerance` (default: 1e-9 of
        each arc's radius).
    precision : int or None
        Significant digits of the written numbers; None (default) writes each number
        exactly (shortest round-trip form).

    Returns
    -------
    (str or list of str, ClipStats)
        The clipped path data in the form `d` came in (``""`` where nothing is left).

    Raises
    ------
    ParseError
        Malformed path data: the message names the path (for a list), the character
        position and what was expected.
    InvalidWindowError, InvalidOptionError, InvalidGeometryError
        (ValueError) naming the bad value.

    Examples
    --------
    >>> d = "M-5 5 C0 10 10 10 15 5"
    >>> clip_svg(d, (0, 0, 10, 10), precision=6)[0]
    'M0 7.97398C3.17644 9.00867 6.82356 9.00867 10 7.97398'
    >>> clip_svg(d, (0, 0, 10, 10), fill="nonzero", precision=6)[0]
    'M0 5V7.97398C3.17644 9.00867 6.82356 9.00867 10 7.97398V5H0Z'
    """
    single = isinstance(d, str)
    if not single and not isinstance(d, Sequence):
        raise TypeError(f"d must be a str or a sequence of str, not {type(d).__name__}")
    paths = parse_paths([d] if single else list(d), tolerance=tolerance)
    result = clip_paths(paths, window, curves=curves, fill=fill, tolerance=tolerance,
                        **options)
    written = write_paths(result.paths, precision=precision)
    return (written[0] if single else written), result.stats


def flatten_paths(paths: PathArrays, tolerance: float, *, close: bool = False,
                  backend="numba"):
    """Return the paths as polylines within `tolerance` of every curve.

    Parameters
    ----------
    paths : PathArrays
    tolerance : float
        Largest distance from a curve to its lines (user units), > 0.
    close : bool
        Close every subpath (fill): the polyline returns to the subpath's start;
        otherwise only subpaths marked closed do.
    backend : {"numba", "opencl"}
        Where the segments' points are computed; "opencl" gives the same points: the
        same counts, the coordinates to rounding (a float32 device: exactly, the host
        computes them in float64).

    Returns
    -------
    coords : ndarray, shape (V, 2)
    line_offsets : ndarray of int64, shape (L + 1,)
        One polyline per subpath with at least one segment.
    line_path : ndarray of int64, shape (L,)
        The path of each polyline.

    Raises
    ------
    InvalidOptionError
        For a bad tolerance or backend.
    BackendUnavailableError
        For ``backend="opencl"`` where OpenCL is missing.
    """
    if not (tolerance > 0 and math.isfinite(tolerance)):
        raise InvalidOptionError(f"tolerance must be a positive finite number, got "
                                 f"{tolerance!r}")
    backend = Backend(backend)
    if backend not in (Backend.NUMBA, Backend.OPENCL):
        raise InvalidOptionError(f"paths are flattened on backend='numba' or 'opencl', got "
                                 f"{backend.value!r}")
    sub = paths.subpath_offsets
    if backend is Backend.OPENCL:
        _, _, segment_points, points, _ = get_backend(backend).classify_curves(
            paths.controls, paths.degree, None, float(tolerance), "all")
        steps = np.diff(segment_points)
    else:
        steps = BZ.flatten_steps(paths.controls, paths.degree, float(tolerance))
        segment_points = exclusive_sum(steps)
    has_line = np.diff(sub) > 0
    closes = has_line & (paths.closed | close)
    ends = paths.start.copy()
    ends[has_line] = paths.controls[sub[1:][has_line] - 1, 3]
    closes &= (ends != paths.start).any(axis=1)
    points_per_line = segment_points[sub[1:]] - segment_points[sub[:-1]] + has_line + closes
    line_offsets = exclusive_sum(points_per_line[has_line])
    lines = np.flatnonzero(has_line)
    coords = np.empty((int(line_offsets[-1]), 2))
    if backend is Backend.OPENCL:
        # The device's points are the segments' in order; each line adds its start
        # point before them (and its start again after them where it closes).
        segment_subpath = np.repeat(np.arange(sub.shape[0] - 1), np.diff(sub))
        line_of_subpath = np.cumsum(has_line) - 1
        shift = (line_offsets[:-1][line_of_subpath[segment_subpath]] + 1
                 - segment_points[sub[:-1]][segment_subpath])
        coords[np.repeat(shift, steps) + np.arange(points.shape[0])] = points
        coords[line_offsets[:-1]] = paths.start[lines]
        closing = closes[lines]
        coords[line_offsets[1:][closing] - 1] = paths.start[lines[closing]]
    else:
        BZ.flatten_into(paths.controls, paths.degree, float(tolerance), sub, paths.start,
                        lines, closes, steps, segment_points, line_offsets, coords)
    subpath_path = np.repeat(np.arange(len(paths), dtype=np.int64), np.diff(paths.path_offsets))
    return coords, line_offsets, subpath_path[has_line]
