"""rnsca: fast, exact clipping of geometry against a rectangular window.

The public API lives here; see README.md for a tour.
"""

from rnsca.arrays import GeometryKind, PathArrays, Ragged
from rnsca.clip import SegmentClipResult, WindowsClipResult, clip, clip_segments
from rnsca.clip_geojson import (
    GeoJSONClipResult,
    GeoJSONWindowsResult,
    clip_geojson,
    clip_geojson_windows,
)
from rnsca.clip_geojson_seq import RecordsClipResult, SequenceClip, clip_geojson_seq, clip_records
from rnsca.clip_svg import (
    Curves,
    Fill,
    FillOutput,
    PathClipResult,
    clip_paths,
    clip_svg,
    flatten_paths,
)
from rnsca.clip_svgdoc import FillMode, clip_svg_document
from rnsca.errors import (
    BackendUnavailableError,
    FontError,
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    LimitExceededError,
    ParseError,
    RnscaError,
    UnsupportedGeometryError,
)
from rnsca.io.svgpath import parse_path, parse_paths, write_path, write_paths
from rnsca.options import Backend, Boundary, Method, Mode
from rnsca.ragged import RaggedClipResult, clip_ragged
from rnsca.stats import ClipStats
from rnsca.verify import Verification, verify
from rnsca.window import Window

__version__ = "0.1.0"

__all__ = [
    "Backend",
    "BackendUnavailableError",
    "Boundary",
    "ClipStats",
    "Curves",
    "Fill",
    "FillOutput",
    "FillMode",
    "FontError",
    "GeoJSONClipResult",
    "GeoJSONWindowsResult",
    "GeometryKind",
    "InvalidGeometryError",
    "InvalidOptionError",
    "InvalidWindowError",
    "LimitExceededError",
    "Method",
    "Mode",
    "ParseError",
    "PathArrays",
    "PathClipResult",
    "Ragged",
    "RaggedClipResult",
    "RecordsClipResult",
    "RnscaError",
    "SegmentClipResult",
    "SequenceClip",
    "UnsupportedGeometryError",
    "Verification",
    "Window",
    "WindowsClipResult",
    "clip",
    "clip_geojson",
    "clip_geojson_windows",
    "clip_geojson_seq",
    "clip_paths",
    "clip_ragged",
    "clip_records",
    "clip_segments",
    "clip_svg",
    "clip_svg_document",
    "flatten_paths",
    "parse_path",
    "parse_paths",
    "verify",
    "write_path",
    "write_paths",
]
