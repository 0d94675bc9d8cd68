"""rnsca: fast, exact clipping of geometry against a rectangular window.

The public API lives here; see README.md for a tour.
"""

from rnsca.clip import SegmentClipResult, clip_segments
from rnsca.errors import (
    BackendUnavailableError,
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    LimitExceededError,
    ParseError,
    RnscaError,
    UnsupportedGeometryError,
)
from rnsca.options import Backend, Method, Mode
from rnsca.stats import ClipStats
from rnsca.verify import Verification, verify
from rnsca.window import Window

__version__ = "0.1.0"

__all__ = [
    "Backend",
    "BackendUnavailableError",
    "ClipStats",
    "InvalidGeometryError",
    "InvalidOptionError",
    "InvalidWindowError",
    "LimitExceededError",
    "Method",
    "Mode",
    "ParseError",
    "RnscaError",
    "SegmentClipResult",
    "UnsupportedGeometryError",
    "Verification",
    "Window",
    "clip_segments",
    "verify",
]
