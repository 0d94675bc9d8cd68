"""The clip window: a closed, axis-aligned rectangle, validated once."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from rnsca.errors import InvalidWindowError

__all__ = ["Window", "WindowTable"]


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
    def of(cls, window: Window | Iterable[float]) -> Window:
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


@dataclass(frozen=True, slots=True, eq=False)
class WindowTable:
    """The window of each of many geometries: a table of windows and an index into it.

    Attributes
    ----------
    bounds : ndarray of float64, shape (w, 4)
        ``[xmin, ymin, xmax, ymax]`` rows, each a valid window.
    index : ndarray of int64, shape (count,)
        The row of `bounds` of each geometry.
    """

    bounds: np.ndarray
    index: np.ndarray

    @classmethod
    def of(cls, window: Window | Iterable[float] | Iterable[Iterable[float]],
           count: int) -> WindowTable:
        """Return the table for `count` geometries.

        `window` is a `Window`, four bounds (one window for all), or an array of shape
        (count, 4) with one window per geometry.

        Raises
        ------
        InvalidWindowError
            For a bound that is not finite, ``min >= max``, or a window array of the
            wrong length; the message names the row.
        """
        if isinstance(window, Window):
            single = window
        else:
            try:
                array = np.asarray(window, dtype=np.float64)
            except (TypeError, ValueError):
                raise InvalidWindowError(
                    f"window must be [xmin, ymin, xmax, ymax] or an (n, 4) array, got "
                    f"{window!r}") from None
            if array.ndim == 2:
                if array.shape != (count, 4):
                    raise InvalidWindowError(
                        f"a window array needs one row [xmin, ymin, xmax, ymax] per "
                        f"geometry: shape ({count}, 4), got {array.shape}")
                good = (np.isfinite(array).all(axis=1) & (array[:, 0] < array[:, 2])
                        & (array[:, 1] < array[:, 3])
                        & np.isfinite(array[:, 2] - array[:, 0])
                        & np.isfinite(array[:, 3] - array[:, 1]))
                if not good.all():
                    row = int(np.argmax(~good))
                    try:
                        Window(*array[row])
                    except InvalidWindowError as exc:
                        raise InvalidWindowError(f"window {row}: {exc}") from None
                return cls(np.ascontiguousarray(array), np.arange(count, dtype=np.int64))
            # Not 2-D: four bounds, or an error that Window.of describes.
            single = Window.of(window)  # type: ignore[arg-type]
        table = np.array([[single.xmin, single.ymin, single.xmax, single.ymax]])
        return cls(table, np.zeros(count, dtype=np.int64))

    def __iter__(self):
        """Unpack as ``bounds, index``."""
        return iter((self.bounds, self.index))

    @property
    def is_single(self) -> bool:
        """Return whether one window serves every geometry."""
        return self.bounds.shape[0] == 1

    def smallest(self) -> Window:
        """Return the window whose size sets default tolerances: the smallest one."""
        if self.bounds.shape[0] == 0:
            return Window(0.0, 0.0, 1.0, 1.0)
        size = np.maximum(self.bounds[:, 2] - self.bounds[:, 0],
                          self.bounds[:, 3] - self.bounds[:, 1])
        return Window(*self.bounds[int(np.argmin(size))])

    def of_items(self, item_geometry: np.ndarray) -> np.ndarray:
        """Return the window row of each item (part, ring, polygon) given its geometry."""
        return np.ascontiguousarray(self.index[item_geometry])
