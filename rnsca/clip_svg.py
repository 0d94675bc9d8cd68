"""Clip SVG paths (lines, quadratic and cubic Béziers, arcs) against a window.

`clip_paths` is the columnar form on `PathArrays`; `clip_svg` reads and writes path
data strings around it. `flatten_paths` turns paths into polylines (for verification
and for the flatten-then-clip baseline). The algorithm is in `rnsca.kernels.bezier`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any, SupportsIndex

import numpy as np
import numpy.typing as npt

from rnsca.arrays import PathArrays, exclusive_sum
from rnsca.backends.auto import backend_for
from rnsca.backends.base import Operation, Polylines
from rnsca.errors import InvalidOptionError, InvalidWindowError
from rnsca.io.svgpath import parse_paths, write_paths
from rnsca.many_windows import as_windows, assign_boxes
from rnsca.options import (
    CURVE_RELATIVE_TOLERANCE,
    Backend,
    Curves,
    Fill,
    FillOutput,
    Method,
    Mode,
    PathOptions,
)
from rnsca.stats import ClipStats
from rnsca.window import Window, WindowTable

__all__ = [
    "Curves",
    "Fill",
    "FillOutput",
    "PathClipResult",
    "clip_paths",
    "clip_svg",
    "flatten_paths",
    "CURVE_RELATIVE_TOLERANCE",
]


@dataclass(frozen=True, slots=True)
class PathClipResult:
    """Clipped paths: output path ``i`` is the clip of input path ``source[i]``.

    With one window, output path ``i`` is the clip of input path ``i`` (empty if nothing
    is left). With ``windows=``, output ``i`` is the clip of input path ``source[i]``
    against window ``window[i]``, sorted by window, then source.

    Attributes
    ----------
    paths : PathArrays
        The clipped paths: in input order (one window), or by window then source.
    stats : ClipStats
        ``segments_in`` counts input segments (closing edges included);
        ``pieces_out`` output segments; fragments are pieces of segments tested by the
        outcodes of their control points. With ``windows=``, of every (path, window)
        pair clipped (``geometries_in`` counts the pairs).
    curves, fill, mode : str or None
        The options the clip ran with (``fill`` None for strokes), for `rnsca.verify`.
    fill_output : str or None
        How the fill was written (``"clean"`` or ``"raw"``); None for strokes.
    tolerance : float
        The clip's tolerance (flattening, approx leaves), user units.
    source : ndarray of int64, shape (m,), or None
        With ``windows=``: the input path of each output path. None for one window
        (output ``i`` is input ``i``).
    window : ndarray of int64, shape (m,), or None
        With ``windows=``: the window (its row in ``windows``) of each output path.
    window_offsets : ndarray of int64, shape (k + 1,), or None
        With ``windows=``: window ``w``'s outputs are ``window_offsets[w]:window_offsets[w
        + 1]``.
    windows : ndarray of float64, shape (k, 4), or None
        With ``windows=``: the windows, as checked (for `rnsca.verify`).
    """

    paths: PathArrays
    stats: ClipStats
    curves: str = "preserve"
    fill: str | None = None
    mode: str = "exact"
    tolerance: float = 0.0
    fill_output: str | None = None
    source: np.ndarray | None = None
    window: np.ndarray | None = None
    window_offsets: np.ndarray | None = None
    windows: np.ndarray | None = None

    def __len__(self) -> int:
        """Return the number of output paths."""
        return len(self.paths)

    def window_paths(self, w: int) -> tuple[PathArrays, np.ndarray]:
        """Return window `w`'s output paths and the input path of each (``windows=``).

        Raises
        ------
        ValueError
            For a result of one window.
        """
        if self.window_offsets is None or self.source is None:
            raise ValueError("window_paths is for a clip with windows=")
        first, last = int(self.window_offsets[w]), int(self.window_offsets[w + 1])
        return self.paths.take(np.arange(first, last)), self.source[first:last]


def clip_paths(paths: PathArrays, window: Window | Iterable[float] | None = None, *,
               windows: npt.ArrayLike | None = None, keep_empty: bool = False,
               curves: Curves | str = "preserve", fill: Fill | str | None = None,
               tolerance: float | None = None, method: Method | str = "rnsca",
               n: SupportsIndex | str = "auto", max_depth: SupportsIndex | None = None,
               mode: Mode | str = "exact", backend: Backend | str = "numba",
               resolution: float | str | None = None,
               fill_output: FillOutput | str = "clean") -> PathClipResult:
    """Return paths clipped to a rectangular window, keeping curves as curves.

    Parameters
    ----------
    paths : PathArrays
        Paths of lines, quadratic and cubic Béziers (`rnsca.io.svgpath`).
    window : Window or sequence of 4 floats
        The closed window ``(xmin, ymin, xmax, ymax)``.
    windows : array_like, shape (k, 4), optional
        Many windows instead of `window`: every path is clipped against every window
        its bounding box (of control and start points, `PathArrays.boxes`) touches, in
        one call, and the result says the source path and the window of each output
        (``source``, ``window``, ``window_offsets``; sorted by window, then source). The
        (path, window) pairs come from `rnsca.many_windows.assign_boxes` (a regular grid
        of windows by arithmetic, other sets by a sweep); the pairs' paths are gathered
        and clipped in one kernel call, each against its own window. Default tolerances
        follow the smallest window.
    keep_empty : bool
        With ``windows=``: keep the output of every (path, window) pair whose boxes
        touch, empty where nothing of the path is in the window, instead of dropping
        the empty ones. With one window every input has its output (empty or not).
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
    fill_output : {"clean", "raw"}
        How a fill is written; both paint the same region under either rule (the
        output winds around every point off the window's boundary as often as the
        input). "clean" (default): closed subpaths whose rings are simple, so any
        polygoniser gives the painted region: each path's visible parts joined along the
        window's edges by one line per edge run, never along an edge twice, no spike
        along an edge, no closing line drawn (Z closes); a visible part that touches
        an edge is cut there, and rings meet only at such points (or where the input's
        own outlines meet). Overlapping outlines stay overlapping rings. "raw": one
        closed subpath per input subpath, its outside parts clamped onto the edges:
        faster (no ring building), but a subpath may run along an edge several times,
        back and forth, and touch itself. Strokes ignore it.
    tolerance : float, optional
        Flattening accuracy and approx mode's smallest piece, in user units; default
        `CURVE_RELATIVE_TOLERANCE` times the window's longer side (the smallest
        window's, with ``windows=``).
    resolution : float > 0 or str, optional
        Approx mode: sets the tolerance from the output's resolution instead (see
        `rnsca.clip_segments`); not with `tolerance`.
    method, n, max_depth, mode, backend
        RNSCA's options: N pieces per split (``"auto"``: 4), deepest level (default:
        0 in exact preserve mode, where an ambiguous segment is solved exactly whole
        (measured fastest); 32 otherwise),
        ``mode="approx"`` drops undecided leaves (no root finding; the output stays
        inside the window). ``backend="opencl"`` (float64 devices) classifies every
        segment by its control points, and flattens the curves accepted whole, on the
        device, and runs of segments by their box; the ambiguous segments and the
        output are done on the host by the Numba kernel, from the device's decisions:
        the output is the same. With ``windows=`` the device classifies the pairs of
        one window at a time (one launch per window), the host assembles all at once.

    Returns
    -------
    PathClipResult

    Raises
    ------
    InvalidWindowError, InvalidOptionError
        (ValueError) naming the bad value: a bad window, a bad row of `windows` (not
        finite, ``min >= max``, not 4 columns), no windows, or both or neither of
        `window` and `windows`.

    Examples
    --------
    >>> from rnsca.io.svgpath import parse_paths, write_paths
    >>> paths = parse_paths(["M-1 1H9", "M6 4L8 4"])
    >>> r = clip_paths(paths, windows=[[0, 0, 5, 5], [5, 0, 10, 5], [0, 5, 5, 9]])
    >>> write_paths(r.paths), r.source.tolist(), r.window_offsets.tolist()
    (['M0 1H5', 'M5 1H9', 'M6 4H8'], [0, 0, 1], [0, 1, 3, 3])
    """
    if (window is None) == (windows is None):
        raise InvalidWindowError("give one of window= and windows=")
    bounds = None
    if windows is not None:
        # The (path, window) pairs' paths, each with its window: one clip for them all.
        bounds = as_windows(windows)
        pairs = assign_boxes(paths.boxes(), bounds)
        pair_window = np.repeat(np.arange(bounds.shape[0], dtype=np.int64),
                                np.diff(pairs.window_offsets))
        table = WindowTable(bounds, pair_window)
        clipped_in = paths.take(pairs.segment)
    else:
        assert window is not None
        single = Window.of(window)
        table = WindowTable.of(single, len(paths))
        clipped_in = paths
    options = PathOptions.resolve(table.smallest(), curves=curves, fill=fill,
                                  tolerance=tolerance, method=method, n=n,
                                  max_depth=max_depth, mode=mode, resolution=resolution,
                                  fill_output=fill_output)
    engine = backend_for(backend, "paths", clipped_in.degree.shape[0])
    engine.capabilities.require(Operation.PATHS, options.mode)
    out = engine.clip_paths(clipped_in, table, options)
    m = out.paths.degree.shape[0]
    non_empty = np.diff(out.paths.path_offsets) > 0
    stats = ClipStats.from_counters(out.counters, out.segments_in, m,
                                    geometries_in=len(clipped_in),
                                    geometries_out=int(non_empty.sum()),
                                    vertices_in=int(clipped_in.controls.shape[0]),
                                    vertices_out=m, device=out.device)
    fill = options.fill
    result = PathClipResult(out.paths, stats, options.curves.value,
                            None if fill is None else fill.value,
                            options.mode.value, options.tolerance,
                            None if fill is None else options.fill_output.value)
    if bounds is None:
        return result
    source, pair_window = pairs.segment, table.index
    clipped = out.paths
    if not keep_empty:
        kept = np.flatnonzero(non_empty)
        clipped, source, pair_window = clipped.take(kept), source[kept], pair_window[kept]
    return replace(result, paths=clipped, source=source, window=pair_window,
                   window_offsets=exclusive_sum(np.bincount(pair_window,
                                                            minlength=bounds.shape[0])),
                   windows=bounds)


def clip_svg(d: str | Sequence[str], window: Window | Iterable[float], *,
             curves: Curves | str = "preserve", fill: Fill | str | None = None,
             tolerance: float | None = None, precision: int | None = None,
             **options: Any) -> tuple[str | list[str], ClipStats]:
    """Return SVG path data clipped to a rectangular window, and the stats.

    Parameters
    ----------
    d : str or sequence of str
        Path data (the ``d`` attribute), or many (clipped in one parallel call).
    window : Window or sequence of 4 floats
        The closed window ``(xmin, ymin, xmax, ymax)``, in the path's user units.
    curves, fill, tolerance, **options
        As for `clip_paths` (``method``, ``n``, ``max_depth``, ``mode``,
        ``backend``, ``fill_output``). Arcs are read as cubics within `tolerance` (default: 1e-9 of
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
    'M0 7.97398C3.17644 9.00867 6.82356 9.00867 10 7.97398V5H0Z'
    >>> clip_svg("M2 -1L1 1L3 -1L1 -1Z", (0, 0, 10, 10), fill="nonzero")[0]
    'M1.5 0 1 1 2 0Z'
    >>> clip_svg("M2 -1L1 1L3 -1L1 -1Z", (0, 0, 10, 10), fill="nonzero", fill_output="raw")[0]
    'M2 0H1.5L1 1 2 0Z'
    """
    single = isinstance(d, str)
    if not single and not isinstance(d, Sequence):
        raise TypeError(f"d must be a str or a sequence of str, not {type(d).__name__}")
    paths = parse_paths([d] if isinstance(d, str) else list(d), tolerance=tolerance)
    result = clip_paths(paths, window, curves=curves, fill=fill, tolerance=tolerance,
                        **options)
    written = write_paths(result.paths, precision=precision)
    return (written[0] if single else written), result.stats


def flatten_paths(paths: PathArrays, tolerance: float, *, close: bool = False,
                  backend: Backend | str = "numba") -> Polylines:
    """Return the paths as polylines within `tolerance` of every curve.

    Parameters
    ----------
    paths : PathArrays
    tolerance : float
        Largest distance from a curve to its lines (user units), > 0.
    close : bool
        Close every subpath (fill): the polyline returns to the subpath's start;
        otherwise only subpaths marked closed do.
    backend : {"numba", "opencl", "auto"}
        ``"auto"`` is Numba for curves (the device does a small share of their work;
        `rnsca.backends.auto`).
        Where the segments' points are computed; "opencl" gives the same points: the
        same counts, the coordinates to rounding (a float32 device: exactly, the host
        computes them in float64).

    Returns
    -------
    Polylines
        Unpacks as ``coords`` (V, 2), ``line_offsets`` (L + 1,) int64: one polyline per
        subpath with at least one segment, and ``line_path`` (L,) int64: the path of
        each polyline.

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
    engine = backend_for(backend, "flatten", paths.degree.shape[0])
    engine.capabilities.require(Operation.FLATTEN)
    return engine.flatten_paths(paths, float(tolerance), bool(close))
