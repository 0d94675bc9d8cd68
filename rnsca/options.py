"""Clipping options: strings at the edge, enums and checked numbers inside."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import SupportsIndex

from rnsca.constants import MAX_DEPTH_LIMIT, N_MAX, N_MIN
from rnsca.errors import InvalidOptionError
from rnsca.window import Window

__all__ = ["Method", "Mode", "Backend", "Boundary", "Precision", "SegmentOptions", "Curves",
           "Fill", "FillOutput", "PathOptions", "N_MIN", "N_MAX", "MAX_DEPTH_LIMIT",
           "CURVE_RELATIVE_TOLERANCE", "APPROX_DEFAULT_PIXELS", "approx_tolerance",
           "Units"]

#: Approx mode's default resolution: the window's longer side in this many pixels, the
#: grid of a vector tile (the Mapbox Vector Tile extent). Output at that resolution
#: cannot show a loss below one pixel, and every level deeper doubles the work.
APPROX_DEFAULT_PIXELS = 4096
#: In approx mode the default tolerance is this fraction of the window's longer side.
APPROX_RELATIVE_TOLERANCE = 1.0 / APPROX_DEFAULT_PIXELS
#: Default `tolerance` of curve clipping, relative to the window's longer side: how far
#: flattened lines may stray from the curve (``curves="flatten"``), and the size below
#: which approx mode stops subdividing.
CURVE_RELATIVE_TOLERANCE = 1e-6


class _ChoiceEnum(str, Enum):
    """A string enum whose lookup error lists the valid choices (case-insensitive)."""

    @classmethod
    def _missing_(cls, value: object) -> _ChoiceEnum:
        if isinstance(value, str):
            for member in cls:
                if member.value == value.lower():
                    return member
        choices = ", ".join(repr(m.value) for m in cls)
        raise InvalidOptionError(f"{cls.__name__.lower()} must be one of {choices}, got {value!r}")

    def __str__(self) -> str:
        return self.value


class Method(_ChoiceEnum):
    """Segment clipping algorithm; all share one output contract."""

    RNSCA = "rnsca"
    """Recursive N-subdivision: outcode-classify N pieces, recurse into ambiguous ones."""
    COHEN_SUTHERLAND = "cohen_sutherland"
    """Cohen–Sutherland (1967): outcodes, then cut at one edge at a time."""
    LIANG_BARSKY = "liang_barsky"
    """Liang–Barsky (1984): parametric clip against the four boundary half-planes."""
    NICHOLL_LEE_NICHOLL = "nicholl_lee_nicholl"
    """Nicholl–Lee–Nicholl (1987): region tests pick the edges, at most two intersections."""
    MIDPOINT = "midpoint"
    """Sproull–Sutherland midpoint subdivision: bisection towards each visible end."""


class Mode(_ChoiceEnum):
    """What subdivision methods do with a piece still undecided at the last level."""

    EXACT = "exact"
    """Clip it with Liang–Barsky: the output is the analytic clip."""
    APPROX = "approx"
    """Drop it: no intersection computed; output is a subset of the true clip."""


class Backend(_ChoiceEnum):
    """Where the kernels run."""

    NUMBA = "numba"
    """Numba-compiled, parallel over blocks of primitives (default)."""
    OPENCL = "opencl"
    """OpenCL kernels (pyopencl) on a GPU or any other OpenCL device."""


class Precision(_ChoiceEnum):
    """Floating-point precision of the OpenCL kernels."""

    AUTO = "auto"
    """float64 where the device has ``cl_khr_fp64``, else float32 (reported in the stats)."""
    FLOAT64 = "float64"
    """float64, the Numba backend's results; a device without fp64 is an error."""
    FLOAT32 = "float32"
    """float32 on any device, within the error bound documented in the README."""


class Boundary(_ChoiceEnum):
    """Whether parts lying on the window's edge belong to the clip (lines and points)."""

    CLOSED = "closed"
    """Keep them, as ``shapely.intersection`` does (the window is a closed set)."""
    INTERIOR = "interior"
    """Drop parts that only run along or touch the edge, as GEOS ``clip_by_rect`` does."""


class Units(_ChoiceEnum):
    """The coordinates of glyph outlines taken from a font (`rnsca.fonts`)."""

    FONT = "font"
    """Font units, y up: the font's own coordinates (``unitsPerEm`` to the em)."""
    USER = "user"
    """User units, y down as in SVG: the em scaled to the font size, y flipped."""


@dataclass(frozen=True, slots=True)
class SegmentOptions:
    """Validated options for one segment clipping call.

    Attributes
    ----------
    method, mode : Method, Mode
    n : int
        Pieces per subdivision, 2..64, or 0 for ``"auto"``.
    max_depth : int
        Deepest subdivision level, 0..32.
    tolerance : float
        A piece no longer than this is not subdivided further (absolute units).
    """

    method: Method
    mode: Mode
    n: int
    max_depth: int
    tolerance: float

    @classmethod
    def resolve(cls, window: Window, *, method: Method | str = "rnsca",
                n: SupportsIndex | str = "auto", max_depth: SupportsIndex | None = None,
                tolerance: float | None = None, mode: Mode | str = "exact",
                resolution: float | str | None = None) -> SegmentOptions:
        """Return checked options, with defaults filled in for `window`.

        Defaults: ``max_depth=32``; ``tolerance`` is infinite in exact mode (an exact leaf
        is clipped analytically, and splitting a segment never saves the clip at its
        boundary crossings, so by default a segment is decided at level 0; see README,
        "Exact mode"; pass a tolerance to make exact mode subdivide), and in approx mode
        the `resolution` (`approx_tolerance`). ``method="midpoint"`` always bisects
        (N = 2).
        """
        method = Method(method)
        mode = Mode(mode)
        n_value = subdivision_n(n)
        if n_value is None:
            n_value = 0
        if method is Method.MIDPOINT:
            n_value = 2
        depth = subdivision_depth(max_depth, MAX_DEPTH_LIMIT)
        if resolution is not None and mode is not Mode.APPROX:
            raise InvalidOptionError(
                "resolution applies to mode='approx' (exact mode is exact to the last ulp)")
        if tolerance is None:
            tol = approx_tolerance(window, resolution) if mode is Mode.APPROX else math.inf
        elif resolution is not None:
            raise InvalidOptionError("give tolerance or resolution, not both (a resolution "
                                     "sets the tolerance)")
        else:
            tol = positive_tolerance(tolerance)  # +inf means "never subdivide"
        return cls(method, mode, n_value, depth, tol)


def approx_tolerance(window: Window, resolution: float | str | None = None) -> float:
    """Return approx mode's tolerance for `window` at the output `resolution`.

    A piece no longer than the tolerance is a leaf, and approx mode drops undecided
    leaves, so each piece end lies within one tolerance of the true end: below the
    output's resolution, the loss cannot show. `resolution` is a length in output units
    (a float > 0), or ``"<k>px"``: the window's longer side drawn as k pixels (a vector
    tile of extent 4096 is ``"4096px"``). Default: ``"4096px"``.

    Examples
    --------
    >>> w = Window(0.0, 0.0, 512.0, 256.0)
    >>> approx_tolerance(w), approx_tolerance(w, "256px"), approx_tolerance(w, 0.5)
    (0.125, 2.0, 0.5)
    """
    if resolution is None:
        return window.size * APPROX_RELATIVE_TOLERANCE
    if isinstance(resolution, str):
        text = resolution.strip().lower()
        pixels = text[:-2].strip() if text.endswith("px") else ""
        if not pixels.isdigit() or int(pixels) < 1:
            raise InvalidOptionError(
                f"resolution must be a length > 0 or '<pixels>px' (e.g. '4096px'), got "
                f"{resolution!r}")
        return window.size / int(pixels)
    try:
        return positive_tolerance(resolution, finite=True)
    except InvalidOptionError:
        raise InvalidOptionError(f"resolution must be a length > 0 or '<pixels>px' (e.g. "
                                 f"'4096px'), got {resolution!r}") from None


def subdivision_n(n: SupportsIndex | str) -> int | None:
    """Return `n` checked (an integer N_MIN..N_MAX), or None for ``"auto"``."""
    if isinstance(n, str):
        if n.lower() != "auto":
            raise InvalidOptionError(
                f"n must be an integer {N_MIN}..{N_MAX} or 'auto', got {n!r}")
        return None
    return _integer("n", n, N_MIN, N_MAX)


def subdivision_depth(max_depth: SupportsIndex | None, default: int) -> int:
    """Return `max_depth` checked (an integer 0..MAX_DEPTH_LIMIT), or `default` for None."""
    return default if max_depth is None else _integer("max_depth", max_depth, 0,
                                                      MAX_DEPTH_LIMIT)


def positive_tolerance(value: float, *, finite: bool = False) -> float:
    """Return `value` as a float > 0 (and finite if asked), else InvalidOptionError."""
    if isinstance(value, bool):
        raise InvalidOptionError(f"tolerance must be a positive number, got {value!r}")
    try:
        tol = float(value)
    except (TypeError, ValueError):
        raise InvalidOptionError(f"tolerance must be a positive number, got {value!r}") from None
    if not tol > 0:  # NaN fails too
        raise InvalidOptionError(f"tolerance must be > 0, got {value!r}")
    if finite and not math.isfinite(tol):
        raise InvalidOptionError(f"tolerance must be a finite number, got {value!r}")
    return tol


def _integer(name: str, value: SupportsIndex, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int,)) and not (
        hasattr(value, "__index__")
    ):
        raise InvalidOptionError(f"{name} must be an integer {low}..{high}, got {value!r}")
    value = int(value)
    if not low <= value <= high:
        raise InvalidOptionError(f"{name} must be in {low}..{high}, got {value}")
    return value


class Curves(_ChoiceEnum):
    """What clipped paths are made of."""

    PRESERVE = "preserve"
    """Béziers of the input's degrees, cut where they cross the window's edges."""
    FLATTEN = "flatten"
    """Lines: curves flattened within `tolerance`, then clipped as lines."""


class Fill(str, Enum):
    """How a closed path is filled; the clip keeps the fill inside the window."""

    NONZERO = "nonzero"
    EVENODD = "evenodd"

    @classmethod
    def of(cls, value: Fill | str | None) -> Fill | None:
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


class FillOutput(_ChoiceEnum):
    """How a filled path's clip is written: both paint the same region, under either rule."""

    CLEAN = "clean"
    """Closed subpaths whose rings are simple: the visible parts joined by one line per
    window edge run, no run along an edge twice, no zero-area spike; rings meet only at
    points (or where the input's own outlines meet). Any polygoniser gives the painted
    region (default)."""
    RAW = "raw"
    """One closed subpath per input subpath, its outside parts clamped onto the window's
    edges: faster, but a subpath may run along an edge several times, back and forth,
    and touch itself there."""

    @classmethod
    def _missing_(cls, value: object) -> FillOutput:
        try:
            return super()._missing_(value)  # type: ignore[return-value]
        except InvalidOptionError:
            raise InvalidOptionError(f"fill_output must be one of 'clean', 'raw', got "
                                     f"{value!r}") from None


@dataclass(frozen=True, slots=True)
class PathOptions:
    """Validated options for one path clipping call.

    Attributes
    ----------
    curves : Curves
    fill : Fill or None
        None: strokes.
    fill_output : FillOutput
        How fills are written (strokes ignore it).
    mode : Mode
    n_split : int
        Pieces per subdivision of an ambiguous curve.
    leaf_depth : int
        Deepest subdivision level.
    tolerance : float
        Flattening accuracy and approx mode's smallest piece (absolute units).
    """

    curves: Curves
    fill: Fill | None
    fill_output: FillOutput
    mode: Mode
    n_split: int
    leaf_depth: int
    tolerance: float

    @classmethod
    def resolve(cls, window: Window, *, curves: Curves | str = "preserve",
                fill: Fill | str | None = None, tolerance: float | None = None,
                method: Method | str = "rnsca", n: SupportsIndex | str = "auto",
                max_depth: SupportsIndex | None = None,
                mode: Mode | str = "exact",
                resolution: float | str | None = None,
                fill_output: FillOutput | str = "clean") -> PathOptions:
        """Return checked options, with defaults filled in for `window`.

        Defaults: N = `bezier.CURVE_N_AUTO` for ``n="auto"``; depth
        `bezier.EXACT_LEAF_DEPTH` in exact preserve mode (an ambiguous segment is solved
        exactly whole: measured fastest), 32 otherwise; tolerance
        `CURVE_RELATIVE_TOLERANCE` times the window's longer side (it is also the
        flattening accuracy), or in approx mode the `resolution` if one is given
        (`approx_tolerance`).
        """
        from rnsca.kernels.bezier import CURVE_N_AUTO, EXACT_LEAF_DEPTH

        curves = Curves(curves)
        fill = Fill.of(fill)
        output = FillOutput(fill_output)
        mode = Mode(mode)
        if Method(method) is not Method.RNSCA:
            raise InvalidOptionError(
                f"curves are clipped by method='rnsca' only, got {method!r} (the line "
                "baselines clip curves after flatten_paths)")
        n_split = subdivision_n(n)
        if n_split is None:
            n_split = CURVE_N_AUTO
        depth = subdivision_depth(max_depth, EXACT_LEAF_DEPTH if (
            mode is Mode.EXACT and curves is Curves.PRESERVE) else MAX_DEPTH_LIMIT)
        if resolution is not None and mode is not Mode.APPROX:
            raise InvalidOptionError(
                "resolution applies to mode='approx' (exact mode is exact to the last ulp)")
        if resolution is not None and tolerance is not None:
            raise InvalidOptionError("give tolerance or resolution, not both (a resolution "
                                     "sets the tolerance)")
        if resolution is not None:
            tol = approx_tolerance(window, resolution)
        else:
            tol = window.size * CURVE_RELATIVE_TOLERANCE if tolerance is None else \
                positive_tolerance(tolerance, finite=True)
        return cls(curves, fill, output, mode, n_split, depth, tol)
