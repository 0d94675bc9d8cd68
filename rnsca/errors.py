"""The rnsca exception hierarchy; it knows nothing of HTTP."""

__all__ = [
    "RnscaError",
    "ParseError",
    "InvalidGeometryError",
    "InvalidWindowError",
    "InvalidOptionError",
    "UnsupportedGeometryError",
    "LimitExceededError",
    "BackendUnavailableError",
    "FontError",
]


class RnscaError(Exception):
    """Root of every error rnsca raises; never raised directly.

    Where the input is at fault, the code that finds it says where in attributes of the
    error, so that callers (the CLI, the service) can point there in their own terms; an
    attribute no one set is None.

    Attributes
    ----------
    path : str or None
        JSON path of the bad member of a GeoJSON document (the service prefixes its own).
    position : int or None
        Offset in the text (SVG path data, JSON) where parsing stopped.
    path_index : int or None
        Index of the SVG path at fault among those parsed together.
    line, column : int or None
        Line (and column, from 1) of the SVG document element at fault.
    geometry : int or None
        Index of the geometry at fault in a ragged array.
    row : int or None
        Index of the segment (row of the segments array) at fault.
    record : int or None
        Number (from 0) of the text at fault in a GeoJSON text sequence; `path` and
        `position` are then within that text.
    detail : str or None
        The message without its location, for callers that name the location themselves.
    """

    path: str | None = None
    position: int | None = None
    path_index: int | None = None
    line: int | None = None
    column: int | None = None
    geometry: int | None = None
    row: int | None = None
    record: int | None = None
    detail: str | None = None


class ParseError(RnscaError, ValueError):
    """GeoJSON or SVG path text is malformed."""


class InvalidGeometryError(RnscaError, ValueError):
    """Geometry has a bad shape, dtype, offsets or a non-finite coordinate."""


class InvalidWindowError(RnscaError, ValueError):
    """The clip window is not a finite rectangle with min < max on both axes."""


class InvalidOptionError(RnscaError, ValueError):
    """A clipping option has an unknown or out-of-range value."""


class UnsupportedGeometryError(RnscaError, TypeError, ValueError):
    """The operation does not accept this kind of geometry (bad input: also a ValueError)."""


class LimitExceededError(RnscaError):
    """Input is larger than the limit the caller set."""


class BackendUnavailableError(RnscaError, RuntimeError):
    """The requested backend (or its precision) is not present here."""


class FontError(RnscaError, ValueError):
    """A font file cannot be read, or has no glyph for the code point or name asked for."""
