"""Clip SVG paths (lines, quadratic and cubic Béziers, arcs) against a window.

`clip_paths` is the columnar form on `PathArrays`; `clip_svg` reads and writes path
data strings around it. `flatten_paths` turns paths into polylines (for verification
and for the flatten-then-clip baseline). The algorithm is in `rnsca.kernels.bezier`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, SupportsIndex

from rnsca.arrays import PathArrays
from rnsca.backends.auto import backend_for
from rnsca.backends.base import Operation, Polylines
from rnsca.errors import InvalidOptionError
from rnsca.io.svgpath import parse_paths, write_paths
from rnsca.options import (
    CURVE_RELATIVE_TOLERANCE,
    Backend,
    Curves,
    Fill,
    Method,
    Mode,
    PathOptions,
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


@dataclass(frozen=True, slots=True)
class PathClipResult:
    """Clipped paths: output path ``i`` is the clip of input path ``i`` (empty if nothing is left).

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


def clip_paths(paths: PathArrays, window: Window | Iterable[float], *,
               curves: Curves | str = "preserve", fill: Fill | str | None = None,
               tolerance: float | None = None, method: Method | str = "rnsca",
               n: SupportsIndex | str = "auto", max_depth: SupportsIndex | None = None,
               mode: Mode | str = "exact", backend: Backend | str = "numba",
               resolution: float | str | None = None) -> PathClipResult:
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
    options = PathOptions.resolve(window, curves=curves, fill=fill, tolerance=tolerance,
                                  method=method, n=n, max_depth=max_depth, mode=mode,
                                  resolution=resolution)
    engine = backend_for(backend, "paths", paths.degree.shape[0])
    engine.capabilities.require(Operation.PATHS, options.mode)
    out = engine.clip_paths(paths, window, options)
    m = out.paths.degree.shape[0]
    non_empty = int((out.paths.path_offsets[1:] > out.paths.path_offsets[:-1]).sum())
    stats = ClipStats.from_counters(out.counters, out.segments_in, m,
                                    geometries_in=len(paths), geometries_out=non_empty,
                                    vertices_in=int(paths.controls.shape[0]),
                                    vertices_out=m, device=out.device)
    return PathClipResult(out.paths, stats, options.curves.value,
                          None if options.fill is None else options.fill.value,
                          options.mode.value, options.tolerance)


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
