"""Clipping options: strings at the edge, enums and checked numbers inside."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from rnsca.constants import MAX_DEPTH_LIMIT, N_MAX, N_MIN
from rnsca.errors import InvalidOptionError
from rnsca.window import Window

__all__ = ["Method", "Mode", "Backend", "Boundary", "Precision", "SegmentOptions", "N_MIN",
           "N_MAX", "MAX_DEPTH_LIMIT"]

#: In approx mode the default tolerance is this fraction of the window's longer side.
APPROX_RELATIVE_TOLERANCE = 1e-9


class _ChoiceEnum(str, Enum):
    """A string enum whose lookup error lists the valid choices (case-insensitive)."""

    @classmethod
    def _missing_(cls, value):
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
    auto_piece : float
        The piece length that ``n="auto"`` aims for: the window's longer side.
    """

    method: Method
    mode: Mode
    n: int
    max_depth: int
    tolerance: float
    auto_piece: float

    @classmethod
    def resolve(cls, window: Window, *, method="rnsca", n="auto", max_depth=None,
                tolerance=None, mode="exact") -> SegmentOptions:
        """Return checked options, with defaults filled in for `window`.

        Defaults: ``max_depth=32``; ``tolerance`` is ``1e-9 * window.size`` in approx mode
        (the accuracy promise) and infinite in exact mode: an exact leaf is clipped
        analytically, and splitting a segment never saves the clip at its boundary
        crossings, so by default a segment is decided at level 0 (see README, "Exact
        mode"). Pass a tolerance to make exact mode subdivide.
        ``method="midpoint"`` always bisects (N = 2).
        """
        method = Method(method)
        mode = Mode(mode)
        n_value = subdivision_n(n)
        if n_value is None:
            n_value = 0
        if method is Method.MIDPOINT:
            n_value = 2
        depth = subdivision_depth(max_depth, MAX_DEPTH_LIMIT)
        if tolerance is None:
            tol = window.size * APPROX_RELATIVE_TOLERANCE if mode is Mode.APPROX else math.inf
        else:
            tol = positive_tolerance(tolerance)  # +inf means "never subdivide"
        return cls(method, mode, n_value, depth, tol, window.size)


def subdivision_n(n) -> int | None:
    """Return `n` checked (an integer N_MIN..N_MAX), or None for ``"auto"``."""
    if isinstance(n, str):
        if n.lower() != "auto":
            raise InvalidOptionError(
                f"n must be an integer {N_MIN}..{N_MAX} or 'auto', got {n!r}")
        return None
    return _integer("n", n, N_MIN, N_MAX)


def subdivision_depth(max_depth, default: int) -> int:
    """Return `max_depth` checked (an integer 0..MAX_DEPTH_LIMIT), or `default` for None."""
    return default if max_depth is None else _integer("max_depth", max_depth, 0,
                                                      MAX_DEPTH_LIMIT)


def positive_tolerance(value, *, finite: bool = False) -> float:
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


def _integer(name: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int,)) and not (
        hasattr(value, "__index__")
    ):
        raise InvalidOptionError(f"{name} must be an integer {low}..{high}, got {value!r}")
    value = int(value)
    if not low <= value <= high:
        raise InvalidOptionError(f"{name} must be in {low}..{high}, got {value}")
    return value
