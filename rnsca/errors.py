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
]


class RnscaError(Exception):
    """Root of every error rnsca raises; never raised directly."""


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
