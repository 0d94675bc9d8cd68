"""Clip a GeoJSON document: read it into ragged arrays, clip each kind, write it back."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, fields
from itertools import zip_longest
from typing import Any

import numpy as np

from rnsca.arrays import exclusive_sum
from rnsca.io.geojson import from_geojson, write_geojson
from rnsca.many_windows import as_windows
from rnsca.ragged import RaggedClipResult, clip_ragged
from rnsca.stats import ClipStats, DeviceStats
from rnsca.window import Window

__all__ = ["GeoJSONClipResult", "GeoJSONWindowsResult", "clip_geojson",
           "clip_geojson_windows", "combine_stats"]

_KINDS = ("points", "lines", "polygons")


@dataclass(frozen=True, slots=True)
class GeoJSONClipResult:
    """A clipped GeoJSON document, its stats, and where every output came from.

    Unpacks (and indexes) as ``(document, stats)``.

    Attributes
    ----------
    document : dict
        The clipped GeoJSON object (see `clip_geojson`).
    stats : ClipStats
    feature_source : ndarray of int64
        For a FeatureCollection, the input feature of each output feature; ``[0]`` for a
        Feature or a Geometry.
    inputs : dict
        For each geometry kind the document holds (``"points"``, ``"lines"``,
        ``"polygons"``), the ``(geometry_type, coords, offsets)`` read from it: geometry
        ``i`` is the ``i``-th of that kind walking the document (see
        `rnsca.io.geojson.GeoJSONLayout`).
    outputs : dict
        For the same kinds, the `RaggedClipResult` of clipping them: output ``i`` is the
        clip of input ``i`` (empty where nothing is left), so `rnsca.verify` compares them
        without reading either document again.
    """

    document: dict
    stats: ClipStats
    feature_source: np.ndarray
    inputs: dict
    outputs: dict

    def __iter__(self) -> Iterator[Any]:
        """Unpack as ``document, stats``."""
        return iter((self.document, self.stats))

    def __len__(self) -> int:
        return 2

    def __getitem__(self, index: int) -> Any:
        """Return ``(document, stats)[index]``."""
        return (self.document, self.stats)[index]


def clip_geojson(obj: dict | str | bytes | bytearray | memoryview,
                 window: Window | Iterable[float], *, keep_empty: bool = False,
                 max_vertices: int | None = None, arrays: bool = False,
                 **options: Any) -> GeoJSONClipResult:
    """Return a GeoJSON object clipped to a rectangular window, and the stats of the clip.

    Every geometry is clipped as ``shapely.intersection`` with the window would, keeping
    its dimension (see `rnsca.clip_ragged`). Each position is written with the number of
    coordinates it came with, in a document that mixes 2D and 3D positions too: a new
    one (a cut point, a window corner) has Z only if every Z it is computed from is
    known (see `rnsca.io.geojson`). The document keeps its shape: Features keep
    ``properties``, ``id`` and foreign members, ``bbox`` is recomputed where there was one,
    and each geometry takes the type of what is left (a LineString cut in two becomes a
    MultiLineString; a single part stays single; Multi* types stay Multi*). Members the
    clip does not change are shared with the input, not copied: those above, and the
    ``coordinates`` of a geometry the clip leaves as it was, if they are lists of
    floats (see `rnsca.io.geojson.to_geojson`).

    Parameters
    ----------
    obj : dict or str or bytes
        A GeoJSON Geometry, Feature or FeatureCollection, or JSON text holding one.
    window : Window or sequence of 4 floats
        ``[xmin, ymin, xmax, ymax]``, one window for the whole document.
    keep_empty : bool
        False (default): Features left empty (or with a null geometry) are dropped, and
        so are empty members of GeometryCollections. True: they are kept, with an empty
        ``coordinates`` array (null geometries stay null). The top-level object is
        always returned.
    max_vertices : int, optional
        Refuse documents with more positions than this.
    arrays : bool
        Write coordinates as NumPy arrays instead of nested lists (faster for large
        documents; serialize with `rnsca.io.geojson.dumps`).
    **options
        ``boundary``, ``method``, ``n``, ``max_depth``, ``tolerance``, ``mode``,
        ``backend``, as for `rnsca.clip_ragged`.

    Returns
    -------
    GeoJSONClipResult
        Unpacks as ``(document, stats)``: the clipped document (see
        `rnsca.io.geojson.to_geojson`) and the stats of the up to three clips (points,
        lines, polygons) added up; it also holds which input feature each output feature
        came from, and the arrays clipped and their clips (for `rnsca.verify`).

    Raises
    ------
    ParseError
        `obj` is text that is not JSON.
    InvalidGeometryError
        The GeoJSON is invalid; the message (and ``path`` attribute) names the JSON path
        of the first problem, e.g. ``features[12].geometry.coordinates[0][3][1]``.
    LimitExceededError
        More than `max_vertices` positions.
    InvalidWindowError, InvalidOptionError
        A bad window or option.

    Examples
    --------
    >>> line = {"type": "LineString", "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20],
    ...                                                [8, 5], [15, 5]]}
    >>> doc = {"type": "Feature", "id": 1, "properties": {"name": "a"}, "geometry": line}
    >>> clipped, stats = clip_geojson(doc, [0, 0, 10, 10])
    >>> clipped["geometry"]["type"]
    'MultiLineString'
    >>> for part in clipped["geometry"]["coordinates"]:
    ...     print(part)
    [[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]]
    [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]
    >>> clipped["id"], clipped["properties"], stats.geometries_in
    (1, {'name': 'a'}, 1)
    """
    window = Window.of(window)
    layout = from_geojson(obj, max_vertices=max_vertices)
    inputs: dict[str, tuple] = {}
    outputs: dict[str, RaggedClipResult] = {}
    for kind in _KINDS:
        if layout.geometry_count(kind) == 0:
            continue
        inputs[kind] = getattr(layout, kind)
        geometry_type, coords, offsets = inputs[kind]
        # A document that mixes 2D and 3D positions has NaN Z for the 2D ones: clipping
        # carries it to every vertex computed from them, written back as 2D.
        outputs[kind] = clip_ragged(geometry_type, coords, offsets, window, keep_empty=True,
                                    partial_z=layout.partial_z, **options)
    stats = [result.stats for result in outputs.values()]
    if not stats:
        # Nothing to clip: still check the options, and report zero counts.
        geometry_type, coords, offsets = layout.points
        stats.append(clip_ragged(geometry_type, coords, offsets, window, keep_empty=True,
                                 **options).stats)
    clipped = {kind: (result.geometry_type, result.coords, result.offsets)
               for kind, result in outputs.items()}
    document, feature_source = write_geojson(layout, **clipped, keep_empty=keep_empty,
                                             arrays=arrays)
    return GeoJSONClipResult(document, combine_stats(stats), feature_source, inputs, outputs)


@dataclass(frozen=True, slots=True)
class GeoJSONWindowsResult:
    """A GeoJSON document clipped to many windows: one document per window, and the stats.

    Unpacks as ``(documents, stats)``.

    Attributes
    ----------
    documents : list of dict
        Document ``w`` is the input clipped to window ``w``, as `clip_geojson` writes it
        (a FeatureCollection keeps the features that have something in the window).
    stats : ClipStats
        Of the clips of every (geometry, window) pair, added up.
    feature_source : list of ndarray of int64
        For each window, the input feature of each output feature (see
        `GeoJSONClipResult.feature_source`).
    inputs : dict
        As `GeoJSONClipResult.inputs`: the arrays read from the document, by kind.
    outputs : dict
        For the same kinds, the `RaggedClipResult` of clipping them against every window
        (``windows=``: each output's ``source`` and ``window``), so `rnsca.verify`
        compares every (geometry, window) pair without reading a document again.
    windows : ndarray of float64, shape (k, 4)
        The windows, as checked.
    """

    documents: list
    stats: ClipStats
    feature_source: list
    inputs: dict = dataclasses.field(default_factory=dict)
    outputs: dict = dataclasses.field(default_factory=dict)
    windows: np.ndarray | None = None

    def __iter__(self) -> Iterator[Any]:
        """Unpack as ``documents, stats``."""
        return iter((self.documents, self.stats))


def clip_geojson_windows(obj: dict | str | bytes | bytearray | memoryview,
                         windows: Any, *, keep_empty: bool = False,
                         max_vertices: int | None = None, arrays: bool = False,
                         **options: Any) -> GeoJSONWindowsResult:
    """Return a GeoJSON object clipped to each of many windows, and the stats.

    Each kind of geometry the document holds (points, lines, polygons) is clipped once
    against all the windows (`rnsca.clip_ragged` with ``windows=``); then one document
    is written per window, as `clip_geojson` writes one.

    Parameters
    ----------
    obj : dict or str or bytes
        A GeoJSON Geometry, Feature or FeatureCollection, or JSON text holding one.
    windows : array_like, shape (k, 4)
        ``[xmin, ymin, xmax, ymax]`` rows.
    keep_empty, max_vertices, arrays, **options
        As for `clip_geojson`.

    Returns
    -------
    GeoJSONWindowsResult

    Raises
    ------
    As `clip_geojson`; `InvalidWindowError` for a bad row of `windows`.

    Examples
    --------
    >>> line = {"type": "LineString", "coordinates": [[-5, 1], [15, 1]]}
    >>> docs, stats = clip_geojson_windows(line, [[0, 0, 5, 5], [5, 0, 10, 5], [0, 5, 5, 9]])
    >>> [d["coordinates"] for d in docs]
    [[[0.0, 1.0], [5.0, 1.0]], [[5.0, 1.0], [10.0, 1.0]], []]
    """
    table = as_windows(windows)
    k = table.shape[0]
    layout = from_geojson(obj, max_vertices=max_vertices)
    inputs: dict[str, tuple] = {}
    outputs: dict[str, RaggedClipResult] = {}
    for kind in _KINDS:
        if layout.geometry_count(kind) == 0:
            continue
        geometry_type, coords, offsets = inputs[kind] = getattr(layout, kind)
        outputs[kind] = clip_ragged(geometry_type, coords, offsets, windows=table,
                                    partial_z=layout.partial_z, **options)
    stats = [result.stats for result in outputs.values()]
    if not stats:
        geometry_type, coords, offsets = layout.points
        stats.append(clip_ragged(geometry_type, coords, offsets, windows=table,
                                 **options).stats)
    documents, sources = [], []
    for w in range(k):
        clipped = {kind: _window_part(result, w, layout.geometry_count(kind))
                   for kind, result in outputs.items()}
        document, feature_source = write_geojson(layout, **clipped, keep_empty=keep_empty,
                                                 arrays=arrays)
        documents.append(document)
        sources.append(feature_source)
    return GeoJSONWindowsResult(documents, combine_stats(stats), sources, inputs, outputs,
                                table)


def _window_part(result: RaggedClipResult, w: int, count: int) -> tuple:
    """Return window `w`'s outputs as a triple aligned with the `count` inputs.

    The inputs with no output in the window get an empty geometry: only the outermost
    offsets change (`result` is of a MULTI kind, as a layout's arrays are).
    """
    assert result.window_offsets is not None
    first, last = int(result.window_offsets[w]), int(result.window_offsets[w + 1])
    outer = result.offsets[-1]
    inner_first, inner_last = int(outer[first]), int(outer[last])
    per_input = np.zeros(count, dtype=np.int64)
    per_input[result.source[first:last]] = np.diff(outer[first:last + 1])
    levels = list(result.offsets[:-1])
    # The inner levels of the window's outputs, from the start of its first one.
    item_first, item_last = inner_first, inner_last
    cut = []
    for level in reversed(levels):
        cut.append(level[item_first:item_last + 1] - level[item_first])
        item_first, item_last = int(level[item_first]), int(level[item_last])
    offsets = (*reversed(cut), exclusive_sum(per_input))
    return (result.geometry_type, result.coords[item_first:item_last], offsets)


def combine_stats(stats: Iterable[ClipStats]) -> ClipStats:
    """Return the stats of several clipping calls as those of one.

    Counters and per-level tuples add up (tuples elementwise); the deepest levels are the
    deepest of any call.

    Examples
    --------
    >>> a = ClipStats(1, 1, 1, 1, 0, 0, 0, 0, 0, 0, (1,), runs_deepest_level=2)
    >>> b = ClipStats(2, 0, 2, 0, 2, 0, 0, 0, 0, 0, (2, 1), runs_deepest_level=1)
    >>> c = combine_stats([a, b])
    >>> c.segments_in, c.decided_per_level, c.runs_deepest_level
    (3, (3, 1), 2)
    """
    stats = list(stats)
    if len(stats) == 1:
        return stats[0]
    values: dict[str, Any] = {}
    for field in fields(ClipStats):
        parts = [getattr(s, field.name) for s in stats]
        if field.name == "device":
            values[field.name] = DeviceStats.combine(parts)
        elif field.name.endswith("deepest_level"):
            values[field.name] = max(parts)
        elif isinstance(parts[0], tuple):
            values[field.name] = tuple(sum(level) for level in zip_longest(*parts, fillvalue=0))
        else:
            values[field.name] = sum(parts)
    return ClipStats(**values)
