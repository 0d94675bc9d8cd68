"""The clip window: a closed, axis-aligned rectangle, validated once."""

from __future__ import annotations

import math
from dataclasses import dataclass

from rnsca.errors import InvalidWindowError

__all__ = ["Window"]


@dataclass(frozen=True, slots=True)
class Window:
    """A closed axis-aligned rectangle ``[xmin, xmax] x [ymin, ymax]``.

    A point on the boundary is inside. Bounds are converted to float and must be
    finite with ``xmin < xmax`` and ``ymin < ymax``.

    Raises
    ------
    InvalidWindowError
        (a ValueError) naming the offending bound.

    Examples
    --------
    >>> Window(0, 0, 10, 5).width
    10.0
    >>> Window(0, 0, 0, 5)
    Traceback (most recent call last):
    ...
    rnsca.errors.InvalidWindowError: window needs xmin < xmax, got xmin=0.0, xmax=0.0
    """

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    def __post_init__(self) -> None:
        for name in ("xmin", "ymin", "xmax", "ymax"):
            value = getattr(self, name)
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise InvalidWindowError(
                    f"window bound {name} must be a number, got {value!r}"
                ) from None
            if not math.isfinite(number):
                raise InvalidWindowError(f"window bound {name} must be finite, got {number}")
            object.__setattr__(self, name, number)
        if not self.xmin < self.xmax:
            raise InvalidWindowError(
                f"window needs xmin < xmax, got xmin={self.xmin}, xmax={self.xmax}"
            )
        if not self.ymin < self.ymax:
            raise InvalidWindowError(
                f"window needs ymin < ymax, got ymin={self.ymin}, ymax={self.ymax}"
            )
        if not (math.isfinite(self.xmax - self.xmin) and math.isfinite(self.ymax - self.ymin)):
            raise InvalidWindowError("window width and height must be finite in float64")

    @classmethod
    def of(cls, window: Window | tuple | list) -> Window:
        """Return `window` as a Window, from a Window or 4 bounds ``[xmin, ymin, xmax, ymax]``."""
        if isinstance(window, Window):
            return window
        try:
            bounds = list(window)
        except TypeError:
            raise InvalidWindowError(
                f"window must be a Window or [xmin, ymin, xmax, ymax], got {window!r}"
            ) from None
        if len(bounds) != 4:
            raise InvalidWindowError(
                f"window must have 4 bounds [xmin, ymin, xmax, ymax], got {len(bounds)}"
            )
        return cls(*bounds)

    @property
    def width(self) -> float:
        """Return the extent along x."""
        return self.xmax - self.xmin

    @property
    def height(self) -> float:
        """Return the extent along y."""
        return self.ymax - self.ymin

    @property
    def size(self) -> float:
        """Return the longer side; the scale that tolerances are relative to."""
        return max(self.width, self.height)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """Return ``(xmin, ymin, xmax, ymax)``."""
        return (self.xmin, self.ymin, self.xmax, self.ymax)
