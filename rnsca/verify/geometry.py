"""Check clipped output against Shapely's exact intersection (the oracle).

`verify` takes what was clipped and what came out, in any of the forms the library
speaks (segments, Shapely geometries, ragged arrays, GeoJSON), asks Shapely for
``intersection(input, box)`` and says how far apart the two are. Everything is compared
by geometry, never by vertex list, and per dimension: polygons with the polygonal part of
Shapely's answer, lines with its lineal part, points with its points, so a line that only
touches the window (where Shapely returns a point) is expected to give nothing.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields, replace
from typing import Any, TypeAlias, cast

import numpy as np
import numpy.typing as npt
import shapely
from shapely.geometry import shape

from rnsca.arrays import PathArrays, Ragged, to_shapely
from rnsca.clip import SegmentClipResult, as_segments
from rnsca.clip_geojson import GeoJSONClipResult, GeoJSONWindowsResult
from rnsca.clip_svg import CURVE_RELATIVE_TOLERANCE, Fill, PathClipResult
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    ParseError,
    UnsupportedGeometryError,
)
from rnsca.io.svgpath import parse_paths
from rnsca.many_windows import as_windows, assign_boxes
from rnsca.options import Boundary, Method, Mode
from rnsca.ragged import RaggedClipResult
from rnsca.verify.cost import estimated_crossings
from rnsca.verify.hausdorff import hausdorff
from rnsca.verify.paths import paths_to_shapely, select_paths
from rnsca.window import Window, WindowTable

__all__ = ["Verification", "verify", "approx_leaf_bound"]

#: Exact results must lie within this fraction of the window's size of Shapely's.
EXACT_RELATIVE_TOLERANCE = 1e-9
# GEOS computes wrong intersections from about 1e+-110 on; windows up to 2**300 (1e90)
# are compared unscaled.
_LARGEST_UNSCALED_EXPONENT = 300
# Tiny windows are scaled up by at most 2**1000: 2**1074 would bring a subnormal window
# to 1, but no float64 is that large (found by fuzzing: OverflowError, or inf for
# geometries).
_LARGEST_SCALE_EXPONENT = 1000

_POINT, _LINESTRING, _LINEARRING, _POLYGON = (
    int(shapely.GeometryType.POINT), int(shapely.GeometryType.LINESTRING),
    int(shapely.GeometryType.LINEARRING), int(shapely.GeometryType.POLYGON))
_DIMENSION_OF_TYPE = {_POINT: 0, _LINESTRING: 1, _LINEARRING: 1, _POLYGON: 2}
_COLLECT = {0: shapely.multipoints, 1: shapely.multilinestrings, 2: shapely.multipolygons}
#: One window, or (geometries only) one per input.
_Windows: TypeAlias = "Window | Iterable[float] | Iterable[Iterable[float]]"


@dataclass(frozen=True, slots=True)
class Verification:
    """How a clipped result compares with ``shapely.intersection`` on the same input.

    Attributes
    ----------
    max_deviation : float
        Largest deviation of one input's output from Shapely's clip of that input.
        Segments: the Hausdorff distance between the two pieces. Geometries: the
        Hausdorff distance per dimension (between the boundaries for polygons), taken
        at every vertex of either side and at the points of either line where the
        other side's vertices project and midway between them, so that a gap inside a
        straight stretch is seen too. Where only one side has something, its extent
        counts (a segment's length, the diagonal of a geometry's bounding box, or the
        window's size for a single point).
    false_positives : int
        Output vertices (a ring's closing position not counted twice) outside the
        closed window by more than 1e-9 of its size; a NaN vertex counts too.
    ratio : float
        Output over Shapely's, in total over the input: length for segments and
        lines, area for polygons, count for points (for a mix, the highest dimension
        present in the input); 1.0 when both are zero.
    passed : bool or None
        Whether the result keeps its mode's promise: exact, deviation within
        ``allowed_deviation`` of every input, valid polygons and no false positive;
        approx, no false positive, valid polygons and deviation within the bound. An
        input whose polygons are invalid has no oracle: it is clipped ring by ring, not
        repaired, so neither its output's validity nor its deviation from the clip of
        ``shapely.make_valid`` of it (still reported in `max_deviation`, `valid` and
        `ratio`) decides the verdict (see `invalid_inputs`). None (no verdict) when some
        inputs chosen were not compared (`skipped`, `timed_out`) and none of those
        compared broke the promise; False as soon as one did.
    allowed_deviation : float
        Exact: 1e-9 of the window's size (of the largest window, when there is one per
        geometry). Approx: the bound (for segments without one given, the largest of
        the per-segment leaf bounds).
    mode : str
        The promise judged: ``"exact"`` or ``"approx"``.
    valid : bool
        Whether every output polygon is valid (``shapely.is_valid``, the polygons of one
        output geometry taken together); True when there are none.
    invalid_inputs : int
        Input geometries whose polygons are not valid (self-intersecting rings, say).
    inputs : int
        Inputs of the clip (segments, geometries or paths).
    checked : int
        Inputs compared: all of them, or a random sample (``verify(..., sample=k)``),
        less those skipped and those left at the time limit; the other fields then speak
        for the inputs compared only.
    sampling : str
        ``"all"``, or ``"random <k> of <n>, seed <s>"``: uniform, without replacement.
    skipped : int
        Inputs chosen but not compared, so not verified: GEOS would have to node an
        outline that crosses itself too often (``verify(..., max_crossings=)``), or a
        segment is beyond what GEOS clips to 1e-9 of the window (longer than
        `GEOS_MAX_WINDOWS` windows, or a non-zero coordinate below 2**-500).
    timed_out : bool
        Whether comparing stopped at the time limit (``verify(..., time_limit=)``): the
        inputs chosen after the last one compared were not compared.
    note : str
        What was not compared and why, in words; empty when every input chosen was.
    """

    max_deviation: float
    false_positives: int
    ratio: float
    passed: bool | None
    allowed_deviation: float
    mode: str
    valid: bool = True
    invalid_inputs: int = 0
    inputs: int = 0
    checked: int = 0
    sampling: str = "all"
    skipped: int = 0
    timed_out: bool = False
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Return the verification as plain JSON-ready values."""
        # Its fields are flat values: a copy of them, without `asdict`'s recursive deep copy
        # (measured: a tenth of a small verified GeoJSON request's verification).
        return {field.name: getattr(self, field.name) for field in fields(self)}


def approx_leaf_bound(lengths: np.ndarray, result: SegmentClipResult) -> np.ndarray:
    """Return, per segment, the longest leaf approx mode can drop.

    Every split makes at least two pieces (N >= 2), so a piece at level d is at most
    ``L / 2**d`` long (``L / N**d`` for a fixed N); a piece becomes a leaf at
    ``max_depth`` or once it is no longer than `tolerance`. Each end of an approx piece
    is therefore within one leaf of the true end, and a visible part shorter than two
    leaves may vanish, so a segment's deviation is at most twice this bound. No leaf is
    shorter than the parameter's resolution, ``eps * L`` (README, "Limits": a segment
    ~1e15 windows long cannot be cut finer than about a tenth of the window).
    """
    options = result.options
    base = 2 if options.n == 0 else options.n
    leaf = np.maximum(options.tolerance, lengths / float(base) ** options.max_depth)
    return np.maximum(leaf, lengths * np.finfo(np.float64).eps)


def verify(original: Any, clipped: Any, window: _Windows, *, mode: Mode | str | None = None,
           approx_bound: float | None = None, boundary: Boundary | str = "closed",
           fill: Fill | str | None = None, tolerance: float | None = None,
           sample: int | None = None, seed: int = 0, time_limit: float | None = None,
           max_crossings: float | None = None) -> Verification:
    """Return how `clipped` compares with Shapely's intersection of `original` and `window`.

    Parameters
    ----------
    original
        What was clipped, in the form that matches `clipped`:

        - segments, array_like (n, 4) or (n, 2, 2), for a `SegmentClipResult`;
        - a Shapely geometry, or an array or list of them, for the same kind of
          `clipped` (aligned: one output per input, None or an empty geometry where
          nothing is left);
        - the ``(geometry_type, coords, offsets)`` triple (or a `Ragged`, or a Shapely
          array) for a `RaggedClipResult`, whose ``source`` aligns the two;
        - for a `GeoJSONClipResult` (what `rnsca.clip_geojson` returns), the document
          that was clipped, or None: the result holds the arrays read from it and their
          clips, one output per input, so nothing is read again or matched by guess;
        - a GeoJSON dict (Geometry, Feature or FeatureCollection) for a GeoJSON dict
          made elsewhere. Feature collections are aligned feature by feature when
          `clipped` has as many features; otherwise the two collections are compared
          whole (pass the `GeoJSONClipResult` to compare feature by feature).
        - SVG path data (a str or a list of them) or a `PathArrays`, for a
          `PathClipResult` or path data. Both sides are flattened within `tolerance`
          and compared as lines (strokes) or as the regions their fill rule paints.
    clipped
        The clip: a `SegmentClipResult`, Shapely geometry or array, `RaggedClipResult`,
        `GeoJSONClipResult`, GeoJSON dict, `PathClipResult` or SVG path data. Z values
        are ignored.
    window : Window, sequence of 4 floats, or array_like (G, 4)
        ``(xmin, ymin, xmax, ymax)``; for geometries also one window per input.
    mode : {"exact", "approx"}, optional
        The promise to judge. Default: the mode a `SegmentClipResult` records, else
        exact.
    approx_bound : float, optional
        Approx mode: the largest deviation to accept. Required for geometries; for
        segments it defaults to twice each segment's leaf bound (`approx_leaf_bound`).
    boundary : {"closed", "interior"}
        The boundary rule the clip followed: closed compares with
        ``shapely.intersection``; interior with ``shapely.clip_by_rect`` for lines and
        points strictly inside for points (polygons: ``intersection`` either way).
        Segments are always closed.
    fill : {None, "nonzero", "evenodd"}
        Paths: the fill rule the clip followed (None: strokes); a `PathClipResult`
        knows its own.
    tolerance : float, optional
        Paths: the flattening accuracy of the comparison; default 1e-6 of the window's
        size (the original is flattened 100 times finer, so that a shallow crossing of
        an edge is not displaced along it). The allowed deviation grows by twice it,
        and in exact mode it is ``1e-9 * size + 2 * tolerance``, plus the clip's own
        tolerance for a `PathClipResult` of ``curves="flatten"``.
    sample : int >= 1, optional
        Compare only this many inputs, drawn uniformly at random without replacement
        (all of them when there are no more): verification costs about as much per input
        as Shapely's clip, often more than the clip itself. `Verification` says how many
        were checked and how they were chosen.
    seed : int
        The random sample's seed (the same seed chooses the same inputs).
    time_limit : float >= 0, optional
        Seconds the comparison may take. Inputs are compared in order, a chunk of about
        65,000 vertices at a time; no chunk starts past the limit, and one in progress is
        dropped when its search for nearest segments reaches the limit (a GEOS call in
        progress cannot be stopped). `Verification` says how many were compared and
        that it stopped (``timed_out``, ``note``); ``passed`` is then None unless a
        compared input broke the promise.
    max_crossings : float >= 0, optional
        Skip an input whose comparison would make GEOS node an outline that crosses
        itself more than about this many times: an invalid polygon (its oracle is made
        valid first) or a filled path (its region is built from its noded outlines).
        GEOS's time there grows faster than the square of the crossings (`make_valid`:
        0.3 s for 800, 80 s for 25,000); they are estimated from a sample of edges
        before any GEOS call (`rnsca.verify.cost`). Skipped inputs are counted in
        ``skipped``, not compared. Lines need no such limit: they are compared with
        Shapely's clip of each segment, which nodes nothing.

    Returns
    -------
    Verification

    Raises
    ------
    UnsupportedGeometryError
        For a `clipped` of another kind, or an `original` that does not match it.
    InvalidGeometryError
        If `original` has a non-finite coordinate, or is not what was clipped.
    InvalidWindowError, InvalidOptionError
        For a bad window, mode, boundary, bound, sample, time limit or crossing limit.

    Notes
    -----
    Shapely (GEOS) loses whole pieces far from 1 (from about 1e+-110 on), so it sees
    tiny and huge windows, with their geometry, scaled by a power of two that brings
    the window's size near 1: exact in floating point, and distances scale back
    exactly. An input polygon that is not valid has no oracle: it is compared with the
    clip of ``shapely.make_valid`` of it (GEOS cannot intersect some invalid polygons),
    and reported, but does not decide ``passed`` (see `Verification`). Lines are
    compared with Shapely's intersection of each of their segments with the window (the
    same point set as the whole line's, without noding a line against itself).

    Examples
    --------
    >>> from rnsca import clip_segments
    >>> segs = [[-5.0, 5.0, 15.0, 5.0]]
    >>> verify(segs, clip_segments(segs, (0, 0, 10, 10)), (0, 0, 10, 10)).passed
    True
    >>> import shapely
    >>> line = shapely.LineString([(-5, 5), (15, 5)])
    >>> v = verify(line, shapely.LineString([(0, 5), (10, 5)]), (0, 0, 10, 10))
    >>> v.passed, v.max_deviation, v.ratio
    (True, 0.0, 1.0)
    >>> verify(line, shapely.LineString([(0, 5), (12, 5)]), (0, 0, 10, 10)).false_positives
    1
    >>> late = verify(line, shapely.LineString([(0, 5), (10, 5)]), (0, 0, 10, 10),
    ...               time_limit=0.0)
    >>> late.passed, late.checked, late.timed_out
    (None, 0, True)
    """
    boundary = Boundary(boundary)
    if approx_bound is not None:
        approx_bound = _non_negative(approx_bound, "approx_bound")
    if sample is not None and (isinstance(sample, bool) or not isinstance(sample, int | np.integer)
                               or sample < 1):
        raise InvalidOptionError(f"sample must be an integer >= 1, got {sample!r}")
    chooser = _Coverage(sample, seed, _limit(time_limit, "time_limit"),
                        _limit(max_crossings, "max_crossings"))
    if isinstance(clipped, PathClipResult) or (_is_path_data(clipped)
                                                and _is_path_data(original)):
        # Paths and segments are clipped to one window (`Window.of` refuses a table).
        return chooser.report(_verify_paths(original, clipped, window, mode, approx_bound,
                                            fill, tolerance, chooser))
    if isinstance(clipped, SegmentClipResult):
        if boundary is not Boundary.CLOSED:
            raise InvalidOptionError("segments are always clipped with boundary='closed'")
        return chooser.report(_verify_segments(
            original, clipped, cast("Window | Iterable[float]", window),
            clipped.mode if mode is None else Mode(mode), approx_bound, chooser))
    mode = Mode.EXACT if mode is None else Mode(mode)
    if mode is Mode.APPROX and approx_bound is None:
        raise InvalidOptionError(
            "verify in approx mode needs approx_bound (the largest deviation to accept) "
            "for geometries")
    if isinstance(clipped, GeoJSONWindowsResult):
        originals, delivered, source, window = _geojson_windows_pairs(clipped, window)
    elif isinstance(clipped, RaggedClipResult) and clipped.window_offsets is not None:
        originals, delivered, source, window = _ragged_window_pairs(
            _ragged_originals(original), clipped, window)
    elif isinstance(clipped, GeoJSONClipResult):
        originals, delivered, source = _geojson_result_pairs(clipped)
    elif isinstance(clipped, dict):
        originals, delivered, source, window = _geojson_pair(original, clipped, window)
    elif isinstance(clipped, RaggedClipResult):
        originals = _ragged_originals(original)
        delivered, source = _ragged_outputs(clipped, originals.shape[0])
    elif clipped is None or _is_geometry_like(clipped):
        originals, delivered = _aligned_geometries(original, clipped)
        source = np.arange(delivered.shape[0])
    else:
        raise UnsupportedGeometryError(
            "verify compares a SegmentClipResult, a RaggedClipResult, a GeoJSONClipResult, "
            "Shapely geometries or "
            f"a GeoJSON dict, got {type(clipped).__name__}")
    bounds = _window_bounds(window, originals.shape[0])
    rows = chooser.rows(originals.shape[0])
    if rows is not None:
        originals, bounds = originals[rows], bounds[rows]
        delivered, source = chooser.outputs(rows, delivered, source)
    return chooser.report(_verify_geometries(originals, delivered, source, bounds, mode,
                                             approx_bound, boundary, chooser))


#: Vertices (input and output) compared at once: the unit of the time limit's checks
#: and of the comparison's memory. Measured on self-crossing lines of 2,000 random
#: vertices: 0.7 s and 100 MB more peak memory a chunk; ordinary lines take less.
_CHUNK_VERTICES = 1 << 16
#: Vertices a flattened curve segment makes, as chunks count them: a DejaVu glyph's
#: quadratics flattened at 1e-8 of the window (the originals' accuracy) gave 640 each,
#: and 64 at the output's 1e-6.
_VERTICES_PER_CURVE = 700


class _OutOfTime(Exception):
    """Raised inside a chunk's comparison when the time limit has passed."""


class _Coverage:
    """Which inputs a verification compares, and how far it got.

    All of them or a seeded random sample (`rows`), compared a chunk of consecutive
    inputs at a time (`compare`) until the deadline; a chunk in progress at the
    deadline is dropped. Inputs too costly to compare (``max_crossings``) are marked
    by the comparison itself (`_Compared.skipped`).
    """

    def __init__(self, size: int | None, seed: int, time_limit: float | None,
                 max_crossings: float | None) -> None:
        self.size = size
        self.seed = seed
        self.time_limit = time_limit
        self.deadline = None if time_limit is None else time.monotonic() + time_limit
        self.max_crossings = max_crossings
        self.inputs = 0
        self.chosen: np.ndarray | None = None
        self.compared = 0
        self.skipped = 0
        self.beyond_geos = 0
        self.most_crossings = 0.0
        self.timed_out = False

    def rows(self, count: int) -> np.ndarray | None:
        """Return the sorted input rows to compare, or None for all `count` of them."""
        self.inputs = count
        if self.size is None or self.size >= count:
            return None
        rng = np.random.default_rng(self.seed)
        self.chosen = np.sort(rng.choice(count, self.size, replace=False))
        return self.chosen

    @staticmethod
    def outputs(rows: np.ndarray, delivered: np.ndarray, source: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray]:
        """Return the outputs of the chosen inputs, their sources renumbered 0..len(rows)."""
        keep = np.isin(source, rows)
        return delivered[keep], np.searchsorted(rows, source[keep])

    def check_time(self) -> None:
        """Raise `_OutOfTime` once the deadline has passed."""
        if self.deadline is not None and time.monotonic() >= self.deadline:
            raise _OutOfTime

    def compare(self, weights: np.ndarray,
                compare_chunk: Callable[[int, int], _Compared]) -> _Compared:
        """Return ``compare_chunk(lo, hi)`` of consecutive inputs, chunk after chunk.

        `weights` gives each input's vertices; a chunk holds inputs that start within
        the same `_CHUNK_VERTICES` (one input of more is a chunk of its own). No chunk
        starts past the deadline, and one that reaches it is dropped: the result holds
        whole chunks, the first ones.
        """
        start = np.cumsum(weights) - weights
        ends = np.append(np.flatnonzero(np.diff(start // _CHUNK_VERTICES)) + 1,
                         weights.shape[0])
        chunks, lo = [], 0
        for hi in ends[ends > 0]:
            try:
                self.check_time()
                chunks.append(compare_chunk(lo, int(hi)))
            except _OutOfTime:
                self.timed_out = True
                break
            lo = int(hi)
        compared = _Compared.concatenate(chunks)
        skipped = compared.skipped
        self.skipped = int(skipped.sum())
        self.beyond_geos = int(compared.beyond_geos.sum())
        self.most_crossings = float(compared.crossings[skipped].max(initial=0.0))
        self.compared = int((~skipped).sum())
        return compared.take(~skipped)

    def report(self, verification: Verification) -> Verification:
        """Return `verification` with what it compared, how it chose, and what it left."""
        chosen = self.inputs if self.chosen is None else int(self.chosen.shape[0])
        sampling = "all" if self.chosen is None else (
            f"random {chosen} of {self.inputs}, seed {self.seed}")
        notes = []
        if self.timed_out:
            notes.append(f"stopped at the time limit of {self.time_limit:.3g} s: "
                         f"{chosen - self.compared - self.skipped} of the {chosen} inputs "
                         "chosen were not compared")
        if self.skipped > self.beyond_geos:
            notes.append(f"{self.skipped - self.beyond_geos} inputs skipped: GEOS would have "
                         f"to node an outline crossing itself about "
                         f"{self.most_crossings:.3g} times (the most among them; "
                         f"max_crossings is {self.max_crossings:g})")
        if self.beyond_geos:
            notes.append(f"{self.beyond_geos} segments skipped: GEOS cannot clip them to "
                         f"1e-9 of the window (longer than {GEOS_MAX_WINDOWS:g} windows, or "
                         "coordinates below 2**-500)")
        passed = verification.passed
        if passed and (self.timed_out or self.skipped):
            passed = None  # nothing compared failed, but not everything was compared
        return replace(verification, passed=passed, inputs=self.inputs,
                       checked=self.compared, sampling=sampling, skipped=self.skipped,
                       timed_out=self.timed_out, note="; ".join(notes))


def _limit(value: float | None, name: str) -> float | None:
    """Return a time or crossing limit as a float >= 0 (None: no limit)."""
    return None if value is None else _non_negative(value, name)


def _non_negative(value: float, name: str) -> float:
    """Return option `name` as a float >= 0, or raise InvalidOptionError naming it."""
    try:
        limit = float(value)
    except (TypeError, ValueError):
        raise InvalidOptionError(f"{name} must be a number >= 0, got {value!r}") from None
    if not limit >= 0.0:
        raise InvalidOptionError(f"{name} must be >= 0, got {limit}")
    return limit


@dataclass
class _Compared:
    """What comparing some inputs found, a row per input; `_judge` sums it up.

    Measures are as Shapely saw them, ``scale`` times the caller's units. A skipped
    row (too costly to compare) holds no finding.
    """

    deviation: np.ndarray        # from Shapely's clip, caller's units; NaN: a NaN vertex
    allowed: np.ndarray          # the deviation the promise allows
    kept: np.ndarray             # the promise is kept, or the input has no oracle
    false_positives: np.ndarray  # output vertices outside the window
    valid: np.ndarray            # the output's polygons are valid
    no_oracle: np.ndarray        # the input's polygons are not valid
    measures: np.ndarray         # (n, 2, 3): count, length, area of ours, of Shapely's
    scale: np.ndarray            # the power of two Shapely saw the input scaled by
    dimension: np.ndarray        # (n, 2): highest of the input's, the output's parts; -1
    crossings: np.ndarray        # estimated crossings GEOS would node (0: not estimated)
    skipped: np.ndarray          # not compared: `crossings` over the limit, or beyond GEOS
    beyond_geos: np.ndarray      # skipped: a segment GEOS cannot clip to 1e-9 of the window

    @classmethod
    def blank(cls, count: int) -> _Compared:
        """Return `count` rows that found nothing wrong, to be filled in."""
        return cls(np.zeros(count), np.zeros(count), np.ones(count, dtype=bool),
                   np.zeros(count, dtype=np.int64), np.ones(count, dtype=bool),
                   np.zeros(count, dtype=bool), np.zeros((count, 2, 3)), np.ones(count),
                   np.full((count, 2), -1), np.zeros(count), np.zeros(count, dtype=bool),
                   np.zeros(count, dtype=bool))

    @classmethod
    def concatenate(cls, parts: list[_Compared]) -> _Compared:
        """Return the rows of `parts`, one after the other."""
        if not parts:
            return cls.blank(0)
        return cls(*(np.concatenate([getattr(p, f.name) for p in parts])
                     for f in fields(cls)))

    def take(self, rows: np.ndarray) -> _Compared:
        """Return the rows `rows` (a mask or indices)."""
        return _Compared(*(getattr(self, f.name)[rows] for f in fields(self)))


def _judge(compared: _Compared, mode: str, allowed_if_none: float) -> Verification:
    """Return the verification of the compared rows (none: `allowed_if_none` allowed)."""
    count = compared.deviation.shape[0]
    # np.max keeps a NaN (from a NaN output vertex): it must not pass.
    return Verification(
        float(np.max(compared.deviation)) if count else 0.0,
        int(compared.false_positives.sum()), _ratio(compared), bool(compared.kept.all()),
        float(np.max(compared.allowed)) if count else allowed_if_none, mode,
        bool(compared.valid.all()), int(compared.no_oracle.sum()))


def _is_path_data(value: object) -> bool:
    return isinstance(value, (str, PathArrays)) or (
        isinstance(value, (list, tuple)) and len(value) > 0
        and all(isinstance(v, str) for v in value))


def _as_paths(value: object, name: str) -> PathArrays:
    if isinstance(value, PathArrays):
        return value
    if isinstance(value, str):
        return parse_paths([value])
    if isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        return parse_paths(list(value))
    raise UnsupportedGeometryError(
        f"{name} must be SVG path data (str or list of str) or a PathArrays to compare "
        f"with clipped paths, got {type(value).__name__}")


def _verify_paths(original: object, clipped: object, window: _Windows,
                  mode: Mode | str | None, approx_bound: float | None,
                  fill: Fill | str | None, tolerance: float | None,
                  chooser: _Coverage) -> Verification:
    """Return the verification of clipped paths (see `verify`).

    A clip with ``windows=`` is compared pair by pair: each (path, window) pair whose
    boxes touch is one input, its output (or nothing) compared in that window.
    """
    flattened_by = 0.0  # a flatten-mode clip's lines are within its tolerance of the curves
    originals_paths = _as_paths(original, "original")
    if isinstance(clipped, PathClipResult):
        delivered_paths = clipped.paths
        fill = clipped.fill if fill is None else fill
        mode = Mode(clipped.mode if mode is None else mode)
        if clipped.curves == "flatten":
            flattened_by = clipped.tolerance
    else:
        delivered_paths = _as_paths(clipped, "clipped")
        mode = Mode.EXACT if mode is None else Mode(mode)
    rule = Fill.of(fill)
    if isinstance(clipped, PathClipResult) and clipped.window_offsets is not None:
        assert clipped.window is not None and clipped.source is not None
        table = _windows_of(window, clipped.windows)
        pair_input, pair_window, output_pair = _window_pairs(
            originals_paths.boxes(), table, clipped.window, clipped.source)
        originals_paths = originals_paths.take(pair_input)
        delivered_paths = _aligned_paths(delivered_paths, output_pair, pair_input.shape[0])
        bounds = table[pair_window]
    else:
        one = Window.of(cast("Window | Iterable[float]", window))
        bounds = np.tile(np.array(one.bounds), (len(originals_paths), 1))
        if len(originals_paths) != len(delivered_paths):
            raise InvalidGeometryError(
                f"verify needs one clipped path per original: {len(delivered_paths)} "
                f"clipped, {len(originals_paths)} originals")
    sizes = np.maximum(bounds[:, 2] - bounds[:, 0], bounds[:, 3] - bounds[:, 1])
    smallest = float(sizes.min()) if sizes.size else 1.0
    flat = (smallest * CURVE_RELATIVE_TOLERANCE if tolerance is None
            else _non_negative(tolerance, "tolerance"))
    if not flat > 0:
        raise InvalidOptionError(f"tolerance must be > 0, got {tolerance!r}")
    if mode is Mode.APPROX:
        if approx_bound is None:
            raise InvalidOptionError(
                "verify in approx mode needs approx_bound (the largest deviation to accept)")
        allowed = approx_bound + 2.0 * flat + flattened_by
    else:
        largest = float(sizes.max()) if sizes.size else 1.0
        allowed = EXACT_RELATIVE_TOLERANCE * largest + 2.0 * flat + flattened_by
    # The original is flattened 100 times finer: where a curve crosses an edge at a
    # shallow angle theta, its flattened crossing moves along the edge by up to
    # tolerance / sin(theta), which the allowance (2 * tolerance) would not cover.
    rows = chooser.rows(len(originals_paths))
    chosen = np.arange(len(originals_paths)) if rows is None else rows
    # Flattening is most of the cost: only the chosen paths, a chunk at a time.
    segments = np.diff(originals_paths.subpath_offsets)
    curves = np.bincount(np.repeat(np.arange(segments.shape[0]), segments),
                         weights=originals_paths.degree > 1, minlength=segments.shape[0])
    per_subpath = 1 + segments + (_VERTICES_PER_CURVE - 1) * curves
    weights = np.add.reduceat(np.append(per_subpath, 0), originals_paths.path_offsets[:-1])
    weights[np.diff(originals_paths.path_offsets) == 0] = 0

    def compare_chunk(lo: int, hi: int) -> _Compared:
        which = chosen[lo:hi]
        originals, crossings = paths_to_shapely(select_paths(originals_paths, which),
                                                flat / 100.0, rule, chooser.max_crossings)
        delivered, delivered_crossings = paths_to_shapely(
            select_paths(delivered_paths, which), flat, rule, chooser.max_crossings)
        skipped = (originals == None) | (delivered == None)  # noqa: E711
        built = np.flatnonzero(~skipped)
        compared = _Compared.blank(which.shape[0])
        found = _compare_geometries(originals[built], delivered[built], np.arange(built.shape[0]),
                                    bounds[which][built], Mode.APPROX, allowed,
                                    Boundary.CLOSED, chooser)
        for f in fields(_Compared):
            getattr(compared, f.name)[built] = getattr(found, f.name)
        # Too costly to build a region of, or (once built) to make valid.
        compared.skipped |= skipped
        compared.crossings[:] = np.maximum(compared.crossings,
                                           np.maximum(crossings, delivered_crossings))
        return compared

    return _judge(chooser.compare(weights[chosen], compare_chunk), mode.value, allowed)


def _aligned_paths(paths: PathArrays, index: np.ndarray, count: int) -> PathArrays:
    """Return `count` paths: path ``index[i]`` is ``paths``'s path i, the others empty."""
    padded = PathArrays.from_kernel(
        controls=paths.controls, degree=paths.degree, subpath_offsets=paths.subpath_offsets,
        closed=paths.closed, start=paths.start,
        path_offsets=np.append(paths.path_offsets, paths.path_offsets[-1]))
    rows = np.full(count, len(paths), dtype=np.int64)  # the empty path appended
    rows[index] = np.arange(len(paths))
    return padded.take(rows)


# --- segments -----------------------------------------------------------------------------

def _unit_scale(window: Window, segments: np.ndarray) -> float:
    """Return the power of two by which Shapely should see the geometry.

    Windows smaller than 1 are scaled up to a size in [0.5, 1) (exact: nothing
    underflows, and subnormal offsets become normal numbers GEOS handles). Windows from
    1 to 2**300 are left alone. Larger ones are scaled down the same way (there,
    coordinates below 2**-1074 of the new unit flush to zero, which is why it is not
    done where it is not needed). The scale is made smaller if needed so that no scaled
    coordinate exceeds about 2**1000, and is at most 2**`_LARGEST_SCALE_EXPONENT` (a
    float64: a window of subnormal size becomes about 2**-74, still far from where GEOS
    fails).
    """
    exponent = math.frexp(window.size)[1]
    if 0 < exponent <= _LARGEST_UNSCALED_EXPONENT:
        return 1.0
    largest = max(float(np.abs(segments).max(initial=0.0)), *map(abs, window.bounds))
    exponent = max(exponent, math.frexp(largest)[1] - 1000, -_LARGEST_SCALE_EXPONENT)
    return math.ldexp(1.0, -exponent)


def _verify_segments(original: npt.ArrayLike, clipped: SegmentClipResult,
                     window: Window | Iterable[float], mode: Mode,
                     approx_bound: float | None, chooser: _Coverage) -> Verification:
    window = Window.of(window)
    segments = as_segments(original)
    n = segments.shape[0]
    if clipped.stats.segments_in != n or (len(clipped) and clipped.source.max() >= n):
        raise InvalidGeometryError(
            f"verify needs the {clipped.stats.segments_in} segments that were clipped, "
            f"got {n}")
    rows = chooser.rows(n)
    if rows is not None:
        keep = np.isin(clipped.source, rows)
        clipped = replace(clipped, segments=clipped.segments[keep],
                          source=np.searchsorted(rows, clipped.source[keep]),
                          t=clipped.t[keep],
                          stats=replace(clipped.stats, segments_in=int(rows.shape[0])))
        segments = segments[rows]
        n = segments.shape[0]

    # GEOS loses whole pieces to overflow or underflow far from 1 (from about 1e+-110 on),
    # so Shapely sees tiny and huge windows scaled by a power of two that brings their
    # size near 1: exact in floating point, and distances scale back exactly.
    scale = _unit_scale(window, segments)
    order = np.argsort(clipped.source, kind="stable")
    pieces, source = clipped.segments[order], clipped.source[order]

    def compare_chunk(lo: int, hi: int) -> _Compared:
        first, last = np.searchsorted(source, [lo, hi])
        return _compare_segments(segments[lo:hi], pieces[first:last],
                                 source[first:last] - lo, window, scale, mode, approx_bound,
                                 clipped)

    compared = chooser.compare(np.full(n, 2), compare_chunk)
    if mode is Mode.APPROX and approx_bound is not None:
        return _judge(compared, mode.value, approx_bound)
    return _judge(compared, mode.value, EXACT_RELATIVE_TOLERANCE * window.size)


#: Segments longer than this many windows are beyond GEOS. Measured against exact
#: rational clips of 50 random segments through a 0..10 window at each length: GEOS's
#: cut points exact at 1e21 and 1e29 windows, no piece at all from 1e37 windows on (a
#: segment 2e299 windows long, found by fuzzing, was reported failed), while rnsca's
#: stayed within 2e-15 of exact at every length. 1e20 leaves a margin.
GEOS_MAX_WINDOWS = 1e20
#: Non-zero coordinates below this (as Shapely sees them, scaled) are beyond GEOS too:
#: products of two of them underflow, and it returns points outside the box.
_GEOS_SMALLEST = 2.0 ** -500


def _beyond_geos(segments: np.ndarray, window: Window, scale: float) -> np.ndarray:
    """Return, per segment, whether GEOS cannot clip it to 1e-9 of the window."""
    magnitude = np.abs(segments)
    tiny = (magnitude != 0) & (magnitude * scale < _GEOS_SMALLEST)
    with np.errstate(over="ignore"):
        span = np.maximum(np.abs(segments[:, 2] - segments[:, 0]),
                          np.abs(segments[:, 3] - segments[:, 1]))
    return tiny.any(axis=1) | (span > GEOS_MAX_WINDOWS * window.size)


def _compare_segments(segments: np.ndarray, pieces: np.ndarray, source: np.ndarray,
                      window: Window, scale: float, mode: Mode, approx_bound: float | None,
                      clipped: SegmentClipResult) -> _Compared:
    """Return the comparison of `segments` and their `pieces` (each of segment `source`)."""
    n = segments.shape[0]
    compared = _Compared.blank(n)
    scaled = segments * scale
    ours_length = np.zeros(n)
    ours = np.full(n, None, dtype=object)
    if pieces.shape[0]:
        scaled_pieces = pieces * scale
        ours[source] = shapely.linestrings(scaled_pieces.reshape(-1, 2, 2))
        ours_length[source] = np.hypot(scaled_pieces[:, 2] - scaled_pieces[:, 0],
                                       scaled_pieces[:, 3] - scaled_pieces[:, 1])

    # Not judged where GEOS is no oracle (reported as skipped, never as failed), nor sent
    # to it: their rows hold a point at the origin instead.
    beyond = _beyond_geos(segments, window, scale)
    lines = shapely.linestrings(np.where(beyond[:, None], 0.0, scaled).reshape(-1, 2, 2))
    box = shapely.box(*(bound * scale for bound in window.bounds))
    expected = shapely.intersection(lines, box)
    # Keep the input's dimension: a point where a segment touches the window is no piece.
    is_line = shapely.get_type_id(expected) == shapely.GeometryType.LINESTRING
    # (NumPy's stubs read a None `y` as the one-argument `where`, which returns indices.)
    expected = cast(np.ndarray,
                    np.where(is_line & ~shapely.is_empty(expected), expected, None))
    # Shapely returns nothing for a zero-length segment; inside the window it is kept.
    zero = (segments[:, 0] == segments[:, 2]) & (segments[:, 1] == segments[:, 3])
    inside_point = ((segments[:, 0] >= window.xmin) & (segments[:, 0] <= window.xmax)
                    & (segments[:, 1] >= window.ymin) & (segments[:, 1] <= window.ymax))
    expected[zero & inside_point] = lines[zero & inside_point]
    expected_length = np.where(expected == None, 0.0, shapely.length(expected))  # noqa: E711

    has_ours = ours != None  # noqa: E711
    has_expected = expected != None  # noqa: E711
    deviation = np.zeros(n)
    both = has_ours & has_expected
    if both.any():
        deviation[both] = shapely.hausdorff_distance(ours[both], expected[both])
    deviation[has_ours & ~has_expected] = ours_length[has_ours & ~has_expected]
    deviation[~has_ours & has_expected] = expected_length[~has_ours & has_expected]
    compared.measures[:, 0, 1], compared.measures[:, 1, 1] = ours_length, expected_length
    compared.scale[:] = scale
    compared.dimension[:] = 1
    # Back to the caller's units (dividing by a power of two is exact).
    deviation /= scale
    ours_length /= scale
    expected_length /= scale

    margin = EXACT_RELATIVE_TOLERANCE * window.size
    if pieces.shape[0]:
        xs, ys = pieces[:, 0::2], pieces[:, 1::2]
        outside = ((xs < window.xmin - margin) | (xs > window.xmax + margin)
                   | (ys < window.ymin - margin) | (ys > window.ymax + margin))
        compared.false_positives[:] = np.bincount(source, weights=outside.sum(axis=1),
                                                  minlength=n).astype(np.int64)

    if mode is Mode.APPROX and approx_bound is not None:
        compared.allowed[:] = approx_bound
        within = deviation <= approx_bound
    elif mode is Mode.APPROX and clipped.method in (Method.RNSCA, Method.MIDPOINT):
        lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
        compared.allowed[:] = 2.0 * approx_leaf_bound(lengths, clipped) + margin
        within = (deviation <= compared.allowed) & (ours_length <= expected_length + margin)
    else:
        # Exact, or approx by an analytic method (which always clips exactly).
        compared.allowed[:] = margin
        within = deviation <= margin
    compared.deviation[:] = deviation
    compared.kept[:] = within & (compared.false_positives == 0)
    compared.skipped[:] = beyond
    compared.beyond_geos[:] = beyond
    return compared


# --- inputs of every form: original geometries, delivered output, input index of each ---------

def _is_geometry_like(value: object) -> bool:
    if isinstance(value, shapely.Geometry):
        return True
    if isinstance(value, (list, tuple)):
        return all(item is None or isinstance(item, shapely.Geometry) for item in value)
    if isinstance(value, np.ndarray) and value.dtype == object:
        items = value.ravel()
        return bool((shapely.is_geometry(items) | (items == None)).all())  # noqa: E711
    return False


def _geometry_array(value: object, name: str) -> np.ndarray:
    """Return `value` (a geometry or a sequence of them) as a 1-d object array."""
    if isinstance(value, shapely.Geometry):
        return np.array([value], dtype=object)
    if not _is_geometry_like(value):
        raise UnsupportedGeometryError(
            f"{name} must be a Shapely geometry or an array of them, "
            f"got {type(value).__name__}")
    array = np.asarray(value, dtype=object)
    if array.ndim != 1:
        raise UnsupportedGeometryError(f"{name} must be 1-d, got shape {array.shape}")
    return array


def _aligned_geometries(original: object, clipped: object) -> tuple[np.ndarray, np.ndarray]:
    originals = _geometry_array(original, "original")
    outputs = _geometry_array([None] if clipped is None else clipped, "clipped")
    if originals.shape != outputs.shape:
        raise InvalidGeometryError(
            f"verify needs one clipped geometry per original (None or empty where nothing "
            f"is left): got {originals.shape[0]} originals and {outputs.shape[0]} outputs")
    return originals, outputs


def _ragged_originals(original: object) -> np.ndarray:
    if isinstance(original, Ragged):
        return original.to_shapely()
    if _is_geometry_like(original):
        return _geometry_array(original, "original")
    if isinstance(original, (tuple, list)) and len(original) == 3:
        # Z is not compared: a NaN one (a position without Z) is taken, and dropped.
        return Ragged.of(*original, partial_z=True).to_shapely()
    raise UnsupportedGeometryError(
        "a RaggedClipResult is compared with the (geometry_type, coords, offsets) triple "
        f"that was clipped, a Ragged or Shapely geometries, got {type(original).__name__}")


def _ragged_outputs(result: RaggedClipResult, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the output geometries of a ragged result and the input index of each."""
    stats_count = getattr(result.stats, "geometries_in", count)
    source = np.asarray(result.source, dtype=np.int64)
    if stats_count != count or (source.size and (source.min() < 0 or source.max() >= count)):
        raise InvalidGeometryError(
            f"verify needs the {stats_count} geometries that were clipped, got {count}")
    # In 2D: Z is not compared, and may be NaN (`clip_ragged(partial_z=True)`).
    # `to_shapely`: Shapely fails on arrays whose geometries are all empty.
    geometries = to_shapely(result.geometry_type, _xy(result.coords), result.offsets)
    return geometries, source


def _xy(coords: np.ndarray) -> np.ndarray:
    """Return x and y of (n, 2) or (n, 3) coordinates, C-contiguous as Shapely takes them."""
    return coords if coords.shape[1] == 2 else np.ascontiguousarray(coords[:, :2])


def _geojson_geometries(obj: object, name: str) -> tuple[np.ndarray, bool]:
    """Return the geometries of a GeoJSON dict and whether it is a FeatureCollection."""
    if not isinstance(obj, dict):
        raise UnsupportedGeometryError(
            f"a GeoJSON clip is compared with the GeoJSON that was clipped; {name} is a "
            f"{type(obj).__name__}")
    kind = obj.get("type")
    if kind == "FeatureCollection":
        features = obj.get("features")
        if not isinstance(features, list):
            raise ParseError(f"{name}.features must be a list")
        items = [_feature_geometry(feature, f"{name}.features[{i}]")
                 for i, feature in enumerate(features)]
    elif kind == "Feature":
        items = [_feature_geometry(obj, name)]
    else:
        items = [_shape(obj, name)]
    array = np.empty(len(items), dtype=object)
    array[:] = items
    return array, kind == "FeatureCollection"


def _feature_geometry(feature: object, path: str) -> shapely.Geometry | None:
    if not isinstance(feature, dict) or "geometry" not in feature:
        raise ParseError(f"{path} must be a Feature with a geometry member")
    return _shape(feature["geometry"], f"{path}.geometry")


def _shape(geometry: object, path: str) -> shapely.Geometry | None:
    if geometry is None:
        return None
    try:
        return shape(geometry)
    except ValueError:
        # Shapely reads a geometry's positions into one array, so it refuses 2D and 3D
        # positions mixed (RFC 7946 allows them). Z is not compared: read x and y only.
        try:
            return shape(_xy_only(geometry))
        except (KeyError, TypeError, ValueError, AttributeError, IndexError,
                shapely.errors.GEOSException) as exc:
            raise ParseError(f"{path} is not a GeoJSON geometry: {exc}") from None
    except (KeyError, TypeError, AttributeError, IndexError,
            shapely.errors.GEOSException) as exc:
        raise ParseError(f"{path} is not a GeoJSON geometry: {exc}") from None


def _xy_only(geometry: object) -> object:
    """Return a GeoJSON geometry with every position cut to its first two numbers.

    Anything that is not a geometry as expected comes back as it was, for `shape` to
    refuse.
    """
    if not isinstance(geometry, dict):
        return geometry
    if geometry.get("type") == "GeometryCollection":
        members = geometry.get("geometries")
        if isinstance(members, (list, tuple)):
            return {**geometry, "geometries": [_xy_only(member) for member in members]}
        return geometry
    return {**geometry, "coordinates": _xy_positions(geometry.get("coordinates"))}


def _xy_positions(value: object) -> object:
    """Return nested coordinate arrays with each position (an array of numbers) cut to 2."""
    if not isinstance(value, (list, tuple)) or not value:
        return value
    if not isinstance(value[0], (list, tuple)):
        return value[:2]  # a position
    return [_xy_positions(item) for item in value]


def _geojson_result_pairs(
        result: GeoJSONClipResult) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the inputs and outputs a GeoJSON clip holds, kind after kind, and the sources.

    Output ``i`` of each kind is the clip of input ``i`` (`GeoJSONClipResult.outputs`).
    """
    originals, delivered = [], []
    for kind, clipped in result.outputs.items():
        geometry_type, coords, offsets = result.inputs[kind]
        # In 2D: Z is not compared, and a document that mixes 2D and 3D positions has
        # NaN for the missing ones, which Shapely need not see.
        originals.append(to_shapely(geometry_type, _xy(coords), offsets))
        delivered.append(to_shapely(clipped.geometry_type, _xy(clipped.coords),
                                    clipped.offsets))
    if not originals:
        nothing = np.empty(0, dtype=object)
        return nothing, nothing, np.empty(0, dtype=np.int64)
    originals_array = np.concatenate(originals)
    return originals_array, np.concatenate(delivered), np.arange(originals_array.shape[0])


def _geojson_pair(original: object, clipped: dict, window: _Windows,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, _Windows]:
    """Return original and clipped geometries of two GeoJSON dicts, aligned, and the window.

    Features are matched one to one when there are as many on both sides; otherwise the
    collections are compared whole, as one input in one window.
    """
    originals, _ = _geojson_geometries(original, "original")
    outputs, _ = _geojson_geometries(clipped, "clipped")
    if outputs.shape == originals.shape:
        return originals, outputs, np.arange(outputs.shape[0]), window
    if not isinstance(window, Window) and np.ndim(cast("npt.ArrayLike", window)) == 2:
        raise InvalidGeometryError(
            f"verify cannot match {outputs.shape[0]} clipped features with "
            f"{originals.shape[0]} originals, and one window per feature needs them matched")
    whole = np.empty(1, dtype=object)
    whole[0] = shapely.geometrycollections([g for g in originals if g is not None])
    return whole, outputs, np.zeros(outputs.shape[0], dtype=np.int64), window


def _window_pairs(boxes: np.ndarray, windows: np.ndarray, out_window: np.ndarray,
                  out_source: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the (input, window) pairs to compare, and the pair of each output.

    The pairs are those the clip found (every input against every window its box
    touches: `rnsca.many_windows.assign_boxes` again, on the same boxes) and those of
    the outputs, should an output lie in a window its input's box does not touch (its
    oracle is then empty). Returns ``(pair_input, pair_window, output_pair)``, the pairs
    sorted by window, then input.
    """
    n = boxes.shape[0]
    found = assign_boxes(boxes, windows)
    found_window = np.repeat(np.arange(windows.shape[0], dtype=np.int64),
                             np.diff(found.window_offsets))
    out_window = np.asarray(out_window, dtype=np.int64)
    out_source = np.asarray(out_source, dtype=np.int64)
    if out_source.size and (out_source.min() < 0 or out_source.max() >= n
                            or out_window.min() < 0 or out_window.max() >= windows.shape[0]):
        raise InvalidGeometryError(
            f"verify needs the {n} inputs and the {windows.shape[0]} windows that were "
            "clipped: an output names another input or window")
    keys = np.union1d(found_window * n + found.segment, out_window * n + out_source)
    return keys % max(n, 1), keys // max(n, 1), np.searchsorted(keys, out_window * n
                                                                + out_source)


def _windows_of(window: _Windows, held: np.ndarray | None) -> np.ndarray:
    """Return the (k, 4) windows a many-window result was clipped against.

    `window` as given to `verify`, else (None) the windows the result holds.
    """
    if window is None:
        if held is None:
            raise InvalidWindowError("verify needs the windows the result was clipped to")
        return held
    table = as_windows(cast("npt.ArrayLike", window))
    if held is not None and not np.array_equal(table, held):
        raise InvalidWindowError(
            f"verify needs the {held.shape[0]} windows the result was clipped to "
            "(windows=), in their order")
    return table


def _ragged_window_pairs(originals: np.ndarray, result: RaggedClipResult, window: _Windows,
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return originals, outputs, their pair and the window of each pair (``windows=``).

    Each (input, window) pair is one input of the comparison: the input geometry
    repeated per window its box touches, with that window.
    """
    assert result.window is not None
    table = _windows_of(window, None)
    pair_input, pair_window, output_pair = _window_pairs(
        shapely.bounds(originals), table, result.window, result.source)
    delivered = to_shapely(result.geometry_type, _xy(result.coords), result.offsets)
    return originals[pair_input], delivered, output_pair, table[pair_window]


def _geojson_windows_pairs(result: GeoJSONWindowsResult, window: _Windows,
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return `_ragged_window_pairs` of every kind a many-window GeoJSON clip holds."""
    table = _windows_of(window, result.windows)
    originals, delivered, source, bounds = [], [], [], []
    pairs = 0
    for kind, clipped in result.outputs.items():
        geometry_type, coords, offsets = result.inputs[kind]
        kind_originals, kind_delivered, kind_source, kind_bounds = _ragged_window_pairs(
            to_shapely(geometry_type, _xy(coords), offsets), clipped, table)
        originals.append(kind_originals)
        delivered.append(kind_delivered)
        source.append(kind_source + pairs)
        bounds.append(kind_bounds)
        pairs += kind_originals.shape[0]
    if not originals:
        nothing = np.empty(0, dtype=object)
        return nothing, nothing, np.empty(0, dtype=np.int64), np.empty((0, 4))
    return (np.concatenate(originals), np.concatenate(delivered), np.concatenate(source),
            np.concatenate(bounds))


def _window_bounds(window: _Windows, count: int) -> np.ndarray:
    """Return (count, 4) validated window bounds, one row per input."""
    windows, index = WindowTable.of(window, count)
    return windows[index]


# --- the comparison ---------------------------------------------------------------------------

def _verify_geometries(originals: np.ndarray, delivered: np.ndarray, source: np.ndarray,
                       bounds: np.ndarray, mode: Mode, approx_bound: float | None,
                       boundary: Boundary, chooser: _Coverage) -> Verification:
    """Return the verification of `delivered` geometries, each the clip of input `source`."""
    originals = shapely.force_2d(originals)
    delivered = shapely.force_2d(delivered)
    _check_finite(originals)
    count = originals.shape[0]
    order = np.argsort(source, kind="stable")
    delivered, source = delivered[order], source[order]
    weights = shapely.get_num_coordinates(originals) + np.bincount(
        source, weights=shapely.get_num_coordinates(delivered), minlength=count)

    def compare_chunk(lo: int, hi: int) -> _Compared:
        first, last = np.searchsorted(source, [lo, hi])
        return _compare_geometries(originals[lo:hi], delivered[first:last],
                                   source[first:last] - lo, bounds[lo:hi], mode, approx_bound,
                                   boundary, chooser)

    if mode is Mode.APPROX:
        assert approx_bound is not None  # callers refuse approx mode without a bound
        return _judge(chooser.compare(weights, compare_chunk), mode.value, approx_bound)
    return _judge(chooser.compare(weights, compare_chunk), mode.value, 0.0)


def _compare_geometries(originals: np.ndarray, delivered: np.ndarray, source: np.ndarray,
                        bounds: np.ndarray, mode: Mode, approx_bound: float | None,
                        boundary: Boundary, chooser: _Coverage) -> _Compared:
    """Return the comparison of `delivered` geometries, each the clip of input `source`.

    With ``chooser.max_crossings``, an input whose polygons are invalid and whose rings
    cross too often to be made valid is skipped before any GEOS call that nodes them.
    """
    count = originals.shape[0]
    compared = _Compared.blank(count)
    sizes = np.maximum(bounds[:, 2] - bounds[:, 0], bounds[:, 3] - bounds[:, 1])
    margins = EXACT_RELATIVE_TOLERANCE * sizes

    # Shapely sees tiny and huge windows scaled by a power of two (see `_unit_scale`).
    scales = _unit_scales(bounds, originals, delivered, source)
    scaled_bounds = bounds * scales[:, None]
    input_parts, input_index = _atomic_parts(_scaled(originals, scales))
    input_valid = _polygons_valid(input_parts, input_index, count)
    if chooser.max_crossings is not None:
        compared.crossings[:] = _crossings_to_make_valid(input_parts, input_index,
                                                         input_valid, count)
        compared.skipped[:] = compared.crossings > chooser.max_crossings
        if compared.skipped.any():
            keep = ~compared.skipped[input_index]
            input_parts, input_index = input_parts[keep], input_index[keep]
            keep = ~compared.skipped[source]
            delivered, source = delivered[keep], source[keep]
    output_parts, output_piece = _atomic_parts(_scaled(delivered, scales[source]))
    output_index = source[output_piece]
    compared.false_positives[:] = _count_outside(_atomic_parts(delivered), source, bounds,
                                                 margins, count)
    output_valid = _polygons_valid(output_parts, output_piece, delivered.shape[0])
    np.logical_and.at(compared.valid, source, output_valid)
    input_dims = _dimensions(input_parts)
    output_dims = _dimensions(output_parts)
    np.maximum.at(compared.dimension[:, 0], input_index, input_dims)
    np.maximum.at(compared.dimension[:, 1], output_index, output_dims)

    deviation = np.zeros(count)
    for dim in (0, 1, 2):
        expected, expected_index = _expected_parts(
            input_parts[input_dims == dim], input_index[input_dims == dim], scaled_bounds,
            dim, boundary, input_valid)
        ours, ours_index = _grouped(output_parts[output_dims == dim],
                                    output_index[output_dims == dim])
        if not (expected.size or ours.size):
            continue
        a = _collect(ours, ours_index, count, dim)
        b = _collect(expected, expected_index, count, dim)
        # np.maximum keeps a NaN (from a NaN output vertex): it must not pass.
        deviation = np.maximum(deviation, _deviation(a, b, dim, sizes * scales,
                                                     chooser.check_time))
        compared.measures[:, 0, dim] = _measure(ours, ours_index, dim, count)
        compared.measures[:, 1, dim] = _measure(expected, expected_index, dim, count)
    compared.deviation[:] = deviation / scales
    compared.scale[:] = scales
    if mode is Mode.APPROX:
        assert approx_bound is not None  # callers refuse approx mode without a bound
        compared.allowed[:] = approx_bound
    else:
        compared.allowed[:] = margins
    compared.no_oracle[:] = ~input_valid
    # An invalid input polygon is clipped ring by ring: its output need not be valid, and
    # it has no oracle to be within the allowed deviation of.
    compared.kept[:] = (((compared.deviation <= compared.allowed) & compared.valid)
                        | ~input_valid) & (compared.false_positives == 0)
    return compared


def _crossings_to_make_valid(parts: np.ndarray, index: np.ndarray, valid: np.ndarray,
                             count: int) -> np.ndarray:
    """Return per input the estimated crossings of the polygons ``make_valid`` would node.

    Only an input whose polygons are not valid is made valid (`_expected_parts`), each
    polygon part on its own: its rings' edges are counted together.
    """
    polygons = np.flatnonzero((_dimensions(parts) == 2) & ~valid[index])
    if not polygons.size:
        return np.zeros(count)
    rings, polygon = shapely.get_rings(parts[polygons], return_index=True)
    coords, ring = shapely.get_coordinates(rings, return_index=True)
    edge = np.flatnonzero(ring[1:] == ring[:-1])  # vertex k to k + 1 of one ring
    per_polygon = estimated_crossings(coords[edge], coords[edge + 1], polygon[ring[edge]],
                                      polygons.shape[0])
    return np.bincount(index[polygons], weights=per_polygon, minlength=count)


def _check_finite(geometries: np.ndarray) -> None:
    coords, index = shapely.get_coordinates(geometries, return_index=True)
    bad = ~np.isfinite(coords).all(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        raise InvalidGeometryError(
            f"original geometry {int(index[row])} has a non-finite coordinate: "
            f"{coords[row].tolist()}")


def _unit_scales(bounds: np.ndarray, originals: np.ndarray, delivered: np.ndarray,
                 source: np.ndarray) -> np.ndarray:
    """Return, per input, the power of two by which Shapely should see it.

    The rule of `_unit_scale`: windows from 1 to 2**300 are left alone, smaller and
    larger ones scaled to a size in [0.5, 1), less if a coordinate would exceed 2**1000,
    and by at most 2**`_LARGEST_SCALE_EXPONENT`.
    """
    sizes = np.maximum(bounds[:, 2] - bounds[:, 0], bounds[:, 3] - bounds[:, 1])
    exponents = np.frexp(sizes)[1].astype(np.int64)
    scaled = (exponents <= 0) | (exponents > _LARGEST_UNSCALED_EXPONENT)
    scales = np.ones(bounds.shape[0])
    if scaled.any():
        with np.errstate(invalid="ignore"):
            largest = np.abs(bounds).max(axis=1)
            for geoms, owner in ((originals, np.arange(bounds.shape[0])), (delivered, source)):
                extent = np.nan_to_num(np.abs(shapely.bounds(geoms)), nan=0.0, posinf=0.0)
                np.maximum.at(largest, owner, extent.max(axis=1, initial=0.0))
        exponents = np.maximum(np.maximum(exponents, np.frexp(largest)[1] - 1000),
                               -_LARGEST_SCALE_EXPONENT)
        scales[scaled] = np.ldexp(1.0, -exponents[scaled])
    return scales


def _scaled(geometries: np.ndarray, scales: np.ndarray) -> np.ndarray:
    if (scales == 1.0).all():
        return geometries
    coords, index = shapely.get_coordinates(geometries, return_index=True)
    return shapely.set_coordinates(geometries.copy(), coords * scales[index, None])


def _atomic_parts(geometries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the non-empty points, lines and polygons of each geometry, with its index.

    Multi-part geometries and collections (nested too) are taken apart; linear rings
    become line strings. Parts come grouped by geometry index, in increasing order.
    """
    parts = np.asarray(geometries, dtype=object)
    index = np.arange(parts.shape[0])
    while True:
        nested = shapely.get_type_id(parts) >= int(shapely.GeometryType.MULTIPOINT)
        if not nested.any():
            break
        inner, inner_index = shapely.get_parts(parts[nested], return_index=True)
        parts = np.concatenate([parts[~nested], inner])
        index = np.concatenate([index[~nested], index[nested][inner_index]])
    keep = (parts != None) & ~shapely.is_empty(parts)  # noqa: E711
    parts, index = parts[keep], index[keep]
    rings = shapely.get_type_id(parts) == _LINEARRING
    if rings.any():
        coords, ring = shapely.get_coordinates(parts[rings], return_index=True)
        parts[rings] = shapely.linestrings(coords, indices=ring)
    order = np.argsort(index, kind="stable")
    return parts[order], index[order]


def _grouped(parts: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(index, kind="stable")
    return parts[order], index[order]


def _dimensions(parts: np.ndarray) -> np.ndarray:
    types = shapely.get_type_id(parts)
    dims = np.full(types.shape, -1)
    for type_id, dim in _DIMENSION_OF_TYPE.items():
        dims[types == type_id] = dim
    return dims


def _expected_parts(parts: np.ndarray, index: np.ndarray, bounds: np.ndarray, dim: int,
                    boundary: Boundary, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return Shapely's clip of input parts of one dimension, keeping that dimension.

    `valid` says per input whether its polygons are valid (`_polygons_valid`).
    """
    if not parts.size:
        return parts, index
    xmin, ymin, xmax, ymax = bounds[index].T
    if dim == 0:
        xy = shapely.get_coordinates(parts)
        x, y = xy[:, 0], xy[:, 1]
        if boundary is Boundary.CLOSED:
            inside = (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)
        else:
            inside = (x > xmin) & (x < xmax) & (y > ymin) & (y < ymax)
        return parts[inside], index[inside]
    if dim == 2:
        # GEOS cannot intersect some invalid polygons; their oracle is the valid reading.
        invalid = ~valid[index]
        if invalid.any():
            parts = parts.copy()
            parts[invalid] = shapely.make_valid(parts[invalid])
    if dim == 1 and boundary is Boundary.CLOSED:
        # A simple line (GEOS finds its first crossing, if any, and stops) has nothing for
        # the overlay to node: one intersection each, the same point set as its segments'
        # and cheaper (a small verified GeoJSON request: about 12% more requests/s); the
        # others segment by segment.
        simple = shapely.is_simple(parts)
        if simple.all():
            return _intersected(parts, index, bounds, dim)
        by_segment = _clip_lines_by_segment(parts[~simple], index[~simple], bounds)
        if not simple.any():
            return by_segment
        whole = _intersected(parts[simple], index[simple], bounds, dim)
        return _grouped(np.concatenate([whole[0], by_segment[0]]),
                        np.concatenate([whole[1], by_segment[1]]))
    if dim == 1:
        # clip_by_rect takes one rectangle per call. It walks each line once (GEOS's
        # RectangleIntersection): no noding, so a self-crossing line costs no more.
        clipped = np.empty(parts.shape[0], dtype=object)
        clipped[:] = [shapely.clip_by_rect(part, *rect)
                      for part, rect in zip(parts, bounds[index], strict=True)]
        return _of_dimension(clipped, index, dim)
    return _intersected(parts, index, bounds, dim)


def _intersected(parts: np.ndarray, index: np.ndarray, bounds: np.ndarray,
                 dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Return Shapely's intersection of `parts` with their windows, of dimension `dim`.

    Part i's window is ``bounds[index[i]]``; the pieces come grouped by input index.
    """
    return _of_dimension(shapely.intersection(parts, shapely.box(*bounds[index].T)), index, dim)


def _of_dimension(clipped: np.ndarray, index: np.ndarray,
                  dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the atomic parts of dimension `dim` of `clipped` (row i of input index[i])."""
    pieces, piece_index = _atomic_parts(clipped)
    keep = _dimensions(pieces) == dim
    return _grouped(pieces[keep], index[piece_index[keep]])


def _clip_lines_by_segment(parts: np.ndarray, index: np.ndarray,
                           bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return Shapely's intersection of line parts with their windows, taken segment by segment.

    ``intersection(line, box)`` nodes the line with itself (GEOS's overlay), so a line
    that crosses itself k times costs time and memory in k, up to n**2 / 2 for n
    vertices: measured, 5.6 s and 700 MB for one line of 2,000 random vertices, whose
    answer has 830,000 parts. The intersection of each segment with the box is the same
    point set, and a segment cannot cross itself. A segment with both ends in the closed
    window lies in it whole (the window is convex) and one with both ends beyond the same
    edge lies outside: only the others are asked of GEOS, which keeps an end inside the
    window exactly. Pieces that meet end to start are joined again, so that a correct
    clip compares equal as a whole. Returns the lines, grouped by input index.
    """
    coords, part = shapely.get_coordinates(parts, return_index=True)
    # A repeated vertex makes a segment of no length (the overlay drops it too).
    repeated = np.zeros(coords.shape[0], dtype=bool)
    repeated[1:] = (part[1:] == part[:-1]) & (coords[1:] == coords[:-1]).all(axis=1)
    coords, part = coords[~repeated], part[~repeated]
    first = np.flatnonzero(part[1:] == part[:-1])  # segment k runs from vertex first[k]
    start, end, owner = coords[first], coords[first + 1], part[first]
    xmin, ymin, xmax, ymax = bounds[index[owner]].T

    def inside(p: np.ndarray) -> np.ndarray:
        return (p[:, 0] >= xmin) & (p[:, 0] <= xmax) & (p[:, 1] >= ymin) & (p[:, 1] <= ymax)

    whole = inside(start) & inside(end)
    beyond = (((start[:, 0] < xmin) & (end[:, 0] < xmin))
              | ((start[:, 0] > xmax) & (end[:, 0] > xmax))
              | ((start[:, 1] < ymin) & (end[:, 1] < ymin))
              | ((start[:, 1] > ymax) & (end[:, 1] > ymax)))
    asked = np.flatnonzero(~whole & ~beyond)
    kept = whole.copy()
    piece_start, piece_end = start.copy(), end.copy()
    if asked.size:
        clipped = shapely.intersection(
            shapely.linestrings(np.stack([start[asked], end[asked]], axis=1)),
            shapely.box(xmin[asked], ymin[asked], xmax[asked], ymax[asked]))
        # A segment meets the convex window in one segment, a point (no piece) or nothing.
        line = ((shapely.get_type_id(clipped) == _LINESTRING)
                & (shapely.get_num_coordinates(clipped) >= 2))
        xy = shapely.get_coordinates(clipped[line]).reshape(-1, 2, 2)
        rows = asked[line]
        # In the segment's direction, for the joining below.
        backwards = ((xy[:, 1] - xy[:, 0]) * (end[rows] - start[rows])).sum(axis=1) < 0
        xy[backwards] = xy[backwards, ::-1]
        piece_start[rows], piece_end[rows] = xy[:, 0], xy[:, 1]
        kept[rows] = True
    k = np.flatnonzero(kept)
    piece_start, piece_end, owner = piece_start[k], piece_end[k], owner[k]
    # A new line where the previous piece is of another part, of a segment not next to
    # this one, or ends elsewhere than this one starts.
    opens = np.ones(k.shape[0], dtype=bool)
    opens[1:] = ((owner[1:] != owner[:-1]) | (k[1:] != k[:-1] + 1)
                 | (piece_start[1:] != piece_end[:-1]).any(axis=1))
    # Each line is its first piece's start, then every piece's end.
    end_at = np.arange(k.shape[0]) + np.cumsum(opens)
    vertices = np.empty((end_at[-1] + 1 if k.size else 0, 2))
    line_of = np.empty(vertices.shape[0], dtype=np.int64)
    line_id = np.cumsum(opens) - 1
    vertices[end_at] = piece_end
    vertices[end_at[opens] - 1] = piece_start[opens]
    line_of[end_at] = line_id
    line_of[end_at[opens] - 1] = line_id[opens]
    lines = shapely.linestrings(vertices, indices=line_of) if k.size \
        else np.empty(0, dtype=object)
    return _grouped(np.asarray(lines, dtype=object), index[owner[opens]])


def _collect(parts: np.ndarray, index: np.ndarray, count: int, dim: int) -> np.ndarray:
    """Return one multi-geometry per input (None where it has no part); `index` sorted."""
    out = np.full(count, None, dtype=object)
    if parts.size:
        _COLLECT[dim](parts, indices=index, out=out)
    return out


def _measure(parts: np.ndarray, index: np.ndarray, dim: int, count: int) -> np.ndarray:
    """Return per input the count (points), length (lines) or area (polygons) of its parts."""
    if dim == 0:
        weights = np.ones(parts.shape[0])
    else:
        weights = shapely.length(parts) if dim == 1 else shapely.area(parts)
    return np.bincount(index, weights=weights, minlength=count)


def _polygons_valid(parts: np.ndarray, index: np.ndarray, count: int) -> np.ndarray:
    """Return, per geometry, whether its polygon parts form a valid (multi)polygon."""
    valid = np.ones(count, dtype=bool)
    polygons = _dimensions(parts) == 2
    if polygons.any():
        collected = _collect(parts[polygons], index[polygons], count, 2)
        has = collected != None  # noqa: E711
        valid[has] = shapely.is_valid(collected[has])
    return valid


def _deviation(a: np.ndarray, b: np.ndarray, dim: int, sizes: np.ndarray,
               check_time: Callable[[], None]) -> np.ndarray:
    """Return, per input, the deviation between our parts `a` and Shapely's `b`.

    `check_time` is called between searches for nearest segments; what it raises ends
    the comparison.
    """
    has_a = a != None  # noqa: E711
    has_b = b != None  # noqa: E711
    deviation = np.zeros(a.shape[0])
    both = has_a & has_b
    # Identical once normalized (a part accepted whole, say): no deviation to measure.
    with np.errstate(invalid="ignore"):  # NaN output vertices are measured below
        both[both] = ~shapely.equals_exact(shapely.normalize(a[both]),
                                          shapely.normalize(b[both]), tolerance=0.0)
    if both.any():
        measured_a, measured_b = a[both], b[both]
        if dim == 2:
            # Between the boundaries, as GEOS measures polygons.
            measured_a, measured_b = shapely.boundary(measured_a), shapely.boundary(measured_b)
        deviation[both] = hausdorff(measured_a, measured_b, dim > 0,
                                    EXACT_RELATIVE_TOLERANCE * sizes[both], check_time)
    alone = has_a ^ has_b
    if alone.any():
        box = shapely.bounds(np.where(has_a, a, b)[alone])
        extent = np.hypot(box[:, 2] - box[:, 0], box[:, 3] - box[:, 1])
        deviation[alone] = np.where(extent > 0, extent, sizes[alone])
    return deviation


def _count_outside(parts_and_piece: tuple[np.ndarray, np.ndarray], source: np.ndarray,
                   bounds: np.ndarray, margins: np.ndarray, count: int) -> np.ndarray:
    """Return per input how many output vertices lie outside its window beyond the margin."""
    parts, piece = parts_and_piece
    index = source[piece]
    polygons = shapely.get_type_id(parts) == _POLYGON
    coords, owner = shapely.get_coordinates(parts[~polygons], return_index=True)
    owner = index[~polygons][owner]
    if polygons.any():
        rings, ring_polygon = shapely.get_rings(parts[polygons], return_index=True)
        ring_coords, ring = shapely.get_coordinates(rings, return_index=True)
        # A ring's last position repeats its first.
        last = np.ones(ring.shape[0], dtype=bool)
        last[:-1] = ring[1:] != ring[:-1]
        coords = np.concatenate([coords, ring_coords[~last]])
        owner = np.concatenate([owner, index[polygons][ring_polygon[ring[~last]]]])
    x, y = coords[:, 0], coords[:, 1]
    margin = margins[owner]
    xmin, ymin, xmax, ymax = bounds[owner].T
    inside = ((x >= xmin - margin) & (x <= xmax + margin)
              & (y >= ymin - margin) & (y <= ymax + margin))
    return np.bincount(owner[~inside], minlength=count)


def _ratio(compared: _Compared) -> float:
    """Return the total of our measure over Shapely's, in common units.

    In the highest dimension among the inputs' parts (the outputs', where no input has
    a part); 1.0 when both totals are zero.
    """
    dims = compared.dimension[:, 0]
    if not (dims >= 0).any():
        dims = compared.dimension[:, 1]
    if not (dims >= 0).any():
        return 1.0
    dim = int(dims.max())
    # Bring every input to the units of the most scaled-down one (no overflow at 1e300).
    scales = compared.scale
    unit = (scales.min() / scales) ** dim
    total_ours = float((compared.measures[:, 0, dim] * unit).sum())
    total_expected = float((compared.measures[:, 1, dim] * unit).sum())
    if total_expected == 0.0:
        return 1.0 if total_ours == 0.0 else float("inf")
    return total_ours / total_expected
