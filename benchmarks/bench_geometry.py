"""Geometry clipping benchmarks (issue 3): curves, polygons with holes, GeoJSON.

Columnar pipelines, compared fairly: every contender starts from the same ragged arrays
(``coords`` and ``offsets`` as ``shapely.to_ragged_array`` gives them, the GeoArrow
layout) and ends with ragged arrays plus the index of the source geometry of each output
geometry:

- ``rnsca:clip_ragged``: `rnsca.clip_ragged` with its defaults (``boundary="closed"``);
  ``rnsca:clip_ragged:interior`` the same with ``boundary="interior"``, the semantics
  of GEOS ``clip_by_rect``;
- ``shapely:clip_by_rect``: ``shapely.from_ragged_array``, ``shapely.clip_by_rect``,
  then back with ``shapely.to_ragged_array``. Shapely 2.2 promotes a mix of single and
  multi geometries to the multi type itself, but refuses geometry collections, and
  ``clip_by_rect`` answers ``GEOMETRYCOLLECTION EMPTY`` where nothing is left, so the
  pipeline also drops empty results (``shapely.is_empty``) and, should a result be a
  collection with lower-dimensional leftovers, keeps only its parts of the input's
  dimension; all of that is timed, since it is what a caller has to do;
- ``shapely:intersection``: the same with ``shapely.intersection(geoms, box)``
  (``boundary="closed"`` semantics);
- ``opencl:clip_ragged`` (lines and polygons) and ``opencl:segments:rnsca`` (lines),
  where OpenCL is available: `rnsca.clip_ragged` and `rnsca.clip_segments` with
  ``backend="opencl"`` (run pruning of lines and rings and segment clipping on the
  device, chains and polygons assembled on the host); the record's ``device`` holds
  the wall, kernel, transfer and host times of one more call;
- ``segments:cohen_sutherland`` and ``segments:rnsca`` (lines only): per-segment
  clipping of the same lines with `rnsca.clip_segments`, on the (m, 4) segment array of
  the lines built beforehand (the explosion is not timed);
- ``objects:*`` (no target): Shapely geometry arrays in and out,
  ``shapely.clip_by_rect`` / ``shapely.intersection`` on the array, and `rnsca.clip` on
  the array (its conversions to and from ragged arrays counted).

Every contender is called once on the whole input before timing (compiles the kernels,
makes Shapely's first call), then all are timed round-robin (see `benchmarks.timing`).
Outside the timing, each output is converted to Shapely geometries and measured (length
or area per source geometry) and, for polygons, checked with ``shapely.is_valid``.

The GeoJSON workload times `rnsca.io.geojson.loads` (parse, orjson),
`rnsca.clip_geojson` (clip) and `rnsca.io.geojson.dumps` (serialize, orjson) of one
FeatureCollection as three stages of one pipeline, for both output forms of the clip
(nested lists, NumPy arrays), and the clip's own steps (read, clip_ragged, write).
"""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely

import rnsca
from benchmarks import datasets
from benchmarks.bench_segments import backend_unavailable_reason, device_split
from benchmarks.machine import load_average
from benchmarks.timing import Contender, Policy, time_round_robin
from rnsca.io import geojson as geojson_format

__all__ = [
    "SUBJECT",
    "SUBJECT_INTERIOR",
    "REF_SHAPELY",
    "REF_INTERSECTION",
    "REF_CS",
    "GeometryPlan",
    "FULL_PLAN",
    "QUICK_PLAN",
    "shapely_columnar",
    "run_curves",
    "run_polygons",
    "run_geojson",
    "GEOJSON_PIPELINES",
    "evaluate_geometry_targets",
]

SUBJECT = "rnsca:clip_ragged"
SUBJECT_INTERIOR = "rnsca:clip_ragged:interior"
REF_SHAPELY = "shapely:clip_by_rect"
REF_INTERSECTION = "shapely:intersection"
REF_CS = "segments:cohen_sutherland"
SEG_RNSCA = "segments:rnsca"
OBJ_CLIP_BY_RECT = "objects:shapely:clip_by_rect"
OBJ_INTERSECTION = "objects:shapely:intersection"
OBJ_RNSCA = "objects:rnsca:clip"
OPENCL_RAGGED = "opencl:clip_ragged"
OPENCL_SEGMENTS = "opencl:segments:rnsca"

#: Which output each contender's geometry should match (same boundary semantics).
_REFERENCE_OF = {
    SUBJECT: REF_INTERSECTION,
    SUBJECT_INTERIOR: REF_SHAPELY,
    REF_SHAPELY: REF_INTERSECTION,
    REF_INTERSECTION: REF_INTERSECTION,
    REF_CS: REF_INTERSECTION,
    SEG_RNSCA: REF_INTERSECTION,
    OBJ_CLIP_BY_RECT: REF_SHAPELY,
    OBJ_INTERSECTION: REF_INTERSECTION,
    OBJ_RNSCA: REF_INTERSECTION,
    OPENCL_RAGGED: REF_INTERSECTION,
    OPENCL_SEGMENTS: REF_INTERSECTION,
}

_MULTI_OF = {shapely.GeometryType.LINESTRING: shapely.GeometryType.MULTILINESTRING,
             shapely.GeometryType.POLYGON: shapely.GeometryType.MULTIPOLYGON}


@dataclass(frozen=True)
class GeometryPlan:
    """Sizes and timing of one geometry run (full or quick).

    Attributes
    ----------
    n_curves : int
        Number of smooth polylines (the paper: 200).
    n_polygons : int
        Number of polygons with holes (issue: 100,000).
    geojson_lines, geojson_polygons : int
        Lines and polygons of the FeatureCollection (136 and 14,500: about 50 MB).
    policy : Policy
        Timing of the columnar, segment and object contenders.
    geojson_repeats : int
        Runs of the parse, clip, serialize pipeline (the best of each stage is kept).
    """

    n_curves: int
    n_polygons: int
    geojson_lines: int
    geojson_polygons: int
    policy: Policy
    geojson_repeats: int


FULL_PLAN = GeometryPlan(n_curves=200, n_polygons=100_000, geojson_lines=136,
                         geojson_polygons=14_500,
                         policy=Policy(min_sample=0.05, budget=2.0, min_repeats=3,
                                       max_repeats=7),
                         geojson_repeats=3)
QUICK_PLAN = GeometryPlan(n_curves=6, n_polygons=2_000, geojson_lines=5, geojson_polygons=300,
                          policy=Policy(min_sample=0.002, budget=0.01, min_repeats=1,
                                        max_repeats=1),
                          geojson_repeats=1)


# --------------------------------------------------------------------------- contenders


@dataclass(frozen=True)
class _Ragged:
    """A ragged triple with the source index of each geometry (Shapely's side)."""

    geometry_type: shapely.GeometryType
    coords: np.ndarray
    offsets: tuple
    source: np.ndarray


def _keep_dimension(clipped: np.ndarray, odd: np.ndarray,
                    part_type: shapely.GeometryType) -> np.ndarray:
    """Replace the results at `odd` by multi geometries of their `part_type` parts only.

    `odd` marks results that are neither `part_type` nor its multi type: collections
    holding lower-dimensional leftovers next to the wanted parts, or leftovers alone
    (a point where a line touches the window). What is not of the input's dimension is
    dropped, as rnsca does.
    """
    parts, index = shapely.get_parts(clipped[odd], return_index=True)
    nested = shapely.get_type_id(parts) >= int(shapely.GeometryType.MULTIPOINT)
    while nested.any():  # members of a collection may be multi geometries themselves
        inner, inner_index = shapely.get_parts(parts[nested], return_index=True)
        index = np.concatenate([index[~nested], index[nested][inner_index]])
        parts = np.concatenate([parts[~nested], inner])
        nested = shapely.get_type_id(parts) >= int(shapely.GeometryType.MULTIPOINT)
    keep = (shapely.get_type_id(parts) == int(part_type)) & ~shapely.is_empty(parts)
    rows = np.flatnonzero(odd)
    out = clipped.copy()
    out[rows] = shapely.from_wkt("GEOMETRYCOLLECTION EMPTY")
    if keep.any():
        maker = (shapely.multilinestrings if part_type == shapely.GeometryType.LINESTRING
                 else shapely.multipolygons)
        order = np.argsort(index[keep], kind="stable")
        kept_index = index[keep][order]
        used = np.unique(kept_index)
        out[rows[used]] = maker(parts[keep][order],
                                indices=np.searchsorted(used, kept_index))
    return out


def shapely_columnar(op: Callable[[np.ndarray], np.ndarray], geometry_type, coords, offsets,
                     part_type: shapely.GeometryType) -> Callable[[], _Ragged]:
    """Return the call of Shapely's columnar pipeline: ragged in, `op`, ragged out.

    ``from_ragged_array`` -> ``op(geoms)`` -> drop empty results -> (results of another
    type, i.e. lower-dimensional leftovers alone or in a collection: keep only their
    `part_type` parts) -> ``to_ragged_array``, with the index of each output geometry's
    source. Results mixing single and multi geometries come back as the multi type
    (``to_ragged_array`` promotes them).
    """
    allowed = np.array([int(part_type), int(_MULTI_OF[part_type])])

    def call() -> _Ragged:
        geoms = shapely.from_ragged_array(geometry_type, coords, offsets)
        clipped = op(geoms)
        nonempty = ~shapely.is_empty(clipped)
        odd = nonempty & ~np.isin(shapely.get_type_id(clipped), allowed)
        if odd.any():
            clipped = _keep_dimension(clipped, odd, part_type)
            nonempty = ~shapely.is_empty(clipped)
        source = np.flatnonzero(nonempty)
        kept = clipped[source]
        if kept.size == 0:
            return _Ragged(geometry_type, np.empty((0, 2)), (), source)
        out_type, out_coords, out_offsets = shapely.to_ragged_array(kept)
        return _Ragged(out_type, out_coords, out_offsets, source)
    return call


def _rnsca_ragged(geometry_type, coords, offsets, window, **options) -> Callable[[], object]:
    def call():
        return rnsca.clip_ragged(geometry_type, coords, offsets, window, **options)
    return call


def _clip_by_rect(window) -> Callable[[np.ndarray], np.ndarray]:
    xmin, ymin, xmax, ymax = window
    return lambda geoms: shapely.clip_by_rect(geoms, xmin, ymin, xmax, ymax)


def _intersection(window) -> Callable[[np.ndarray], np.ndarray]:
    box = shapely.box(*window)
    return lambda geoms: shapely.intersection(geoms, box)


def _segments_call(segments, window, method: str, backend: str = "numba"
                   ) -> Callable[[], object]:
    def call():
        return rnsca.clip_segments(segments, window, method=method, backend=backend)
    return call


def _objects_call(op: Callable[[np.ndarray], np.ndarray], geoms) -> Callable[[], np.ndarray]:
    return lambda: op(geoms)


def _rnsca_objects(geoms, window) -> Callable[[], np.ndarray]:
    return lambda: rnsca.clip(geoms, window)


# --------------------------------------------------------------------------- checks


@dataclass
class _Output:
    """What a contender's output measures: per source geometry, counts, validity."""

    per_source: np.ndarray
    geometries: int
    coords: int
    invalid: int | None


def _measure(geoms: np.ndarray, dimension: int) -> np.ndarray:
    return shapely.length(geoms) if dimension == 1 else shapely.area(geoms)


def _summarize(result, n_in: int, dimension: int, segment_line: np.ndarray | None) -> _Output:
    """Convert any contender's output to Shapely geometries and measure it (not timed)."""
    if isinstance(result, rnsca.SegmentClipResult):
        pieces = result.segments
        lengths = np.hypot(pieces[:, 2] - pieces[:, 0], pieces[:, 3] - pieces[:, 1])
        per_source = np.bincount(segment_line[result.source], weights=lengths,
                                 minlength=n_in)
        return _Output(per_source, len(result), 2 * len(result), None)
    if isinstance(result, np.ndarray):  # aligned geometry array (objects pipelines)
        geoms, source = result, np.arange(result.shape[0])
        nonempty = ~shapely.is_empty(geoms)
        geoms, source = geoms[nonempty], source[nonempty]
        n_coords = int(shapely.get_num_coordinates(geoms).sum())
    else:  # RaggedClipResult or _Ragged
        source = np.asarray(result.source)
        if source.size == 0:
            return _Output(np.zeros(n_in), 0, 0, 0 if dimension == 2 else None)
        geoms = shapely.from_ragged_array(result.geometry_type, result.coords, result.offsets)
        n_coords = int(result.coords.shape[0])
    per_source = np.bincount(source, weights=_measure(geoms, dimension), minlength=n_in)
    invalid = int(np.count_nonzero(~shapely.is_valid(geoms))) if dimension == 2 else None
    return _Output(per_source, int(geoms.shape[0]), n_coords, invalid)


def _agreement(out: _Output, ref: _Output) -> dict:
    total, ref_total = float(out.per_source.sum()), float(ref.per_source.sum())
    diff = np.abs(out.per_source - ref.per_source)
    return {"measure": total, "reference_measure": ref_total,
            "relative_difference": abs(total - ref_total) / ref_total if ref_total else None,
            "max_abs_difference_per_source": float(diff.max()) if diff.size else 0.0,
            "sources_differing": int(np.count_nonzero(diff > 1e-9 * max(ref_total, 1.0)))}


# --------------------------------------------------------------------------- one workload


def _record(c: Contender, kind: str, n_coords: int) -> dict:
    rec = {
        "label": c.label,
        "kind": kind,
        "seconds": c.best,
        "seconds_median": statistics.median(c.samples),
        "repeats": len(c.samples),
        "number": c.number,
        "coords_per_s": n_coords / c.best if c.best > 0 else None,
        "stats": None,
    }
    stats = getattr(c.last, "stats", None)
    if stats is not None:
        rec["stats"] = stats.to_dict()
        if stats.device is not None:
            rec["device"] = device_split(c.call)
    return rec


def _add_ratios(runs: list[dict]) -> None:
    """Give each run its time ratio (this run / reference) and speed-ups over the references."""
    by_label = {r["label"]: r for r in runs}
    for r in runs:
        r["time_ratio"] = {}
        for key, ref in (("shapely_clip_by_rect", REF_SHAPELY),
                         ("shapely_intersection", REF_INTERSECTION),
                         ("segments_cohen_sutherland", REF_CS)):
            other = by_label.get(ref)
            r["time_ratio"][key] = (r["seconds"] / other["seconds"]
                                    if other and other["seconds"] > 0 else None)


def _time_workload(name: str, contenders: list[tuple[str, str, Callable[[], object]]],
                   policy: Policy, n_in: int, n_coords: int, dimension: int,
                   segment_line: np.ndarray | None, log: Callable[[str], None]) -> list[dict]:
    """Warm up, time round-robin, then check every contender's output; return the runs."""
    timed = []
    warm = {}
    for label, _, call in contenders:
        start = time.perf_counter()
        warm[label] = call()  # compile, first-call overheads; also the output checked below
        log(f"  {name}: warm-up {label} {time.perf_counter() - start:.3f} s")
        timed.append(Contender(label, call))
    log(f"  {name}: timing {len(timed)} contenders (best of up to {policy.max_repeats})")
    time_round_robin(timed, policy)
    kinds = {label: kind for label, kind, _ in contenders}
    runs = [_record(c, kinds[c.label], n_coords) for c in timed]
    outputs = {label: _summarize(result, n_in, dimension, segment_line)
               for label, result in warm.items()}
    del warm
    for r in runs:
        out = outputs[r["label"]]
        ref_label = _REFERENCE_OF[r["label"]]
        r["output"] = {"geometries": out.geometries, "coords": out.coords,
                       "invalid": out.invalid, "reference": ref_label,
                       **_agreement(out, outputs[ref_label])}
    _add_ratios(runs)
    return runs


def _curve_contenders(geometry_type, coords, offsets, segments, geoms, window):
    part = shapely.GeometryType.LINESTRING
    return [
        (SUBJECT, "rnsca", _rnsca_ragged(geometry_type, coords, offsets, window)),
        (SUBJECT_INTERIOR, "rnsca",
         _rnsca_ragged(geometry_type, coords, offsets, window, boundary="interior")),
        (REF_SHAPELY, "shapely",
         shapely_columnar(_clip_by_rect(window), geometry_type, coords, offsets, part)),
        (REF_INTERSECTION, "shapely",
         shapely_columnar(_intersection(window), geometry_type, coords, offsets, part)),
        (REF_CS, "segments", _segments_call(segments, window, "cohen_sutherland")),
        (SEG_RNSCA, "segments", _segments_call(segments, window, "rnsca")),
        (OBJ_CLIP_BY_RECT, "objects", _objects_call(_clip_by_rect(window), geoms)),
        (OBJ_INTERSECTION, "objects", _objects_call(_intersection(window), geoms)),
        (OBJ_RNSCA, "objects", _rnsca_objects(geoms, window)),
    ] + ([] if backend_unavailable_reason("opencl") else [
        (OPENCL_RAGGED, "opencl",
         _rnsca_ragged(geometry_type, coords, offsets, window, backend="opencl")),
        (OPENCL_SEGMENTS, "opencl", _segments_call(segments, window, "rnsca", "opencl")),
    ])


def run_curves(plan: GeometryPlan, log: Callable[[str], None] = print) -> list[dict]:
    """Time the curve workload at each window of `datasets.CURVE_WINDOWS`; one dict each."""
    raw_coords, raw_offsets = datasets.smooth_polylines(plan.n_curves)
    geoms = shapely.from_ragged_array(shapely.GeometryType.LINESTRING, raw_coords,
                                      (raw_offsets,))
    geometry_type, coords, offsets = shapely.to_ragged_array(geoms)
    segments = datasets.explode_lines(coords, offsets[0])
    counts = np.diff(offsets[0])
    segment_line = np.repeat(np.arange(plan.n_curves), counts - 1)
    results = []
    for share, window in datasets.CURVE_WINDOWS.items():
        name = f"curves-{share}"
        xmin, ymin, xmax, ymax = window
        inside = ((coords[:, 0] >= xmin) & (coords[:, 0] <= xmax)
                  & (coords[:, 1] >= ymin) & (coords[:, 1] <= ymax))
        info = {
            "name": name, "family": "curves", "geometry_type": geometry_type.name,
            "window": list(window), "window_area_share": share,
            "geometries": plan.n_curves, "coords": int(coords.shape[0]),
            "segments": int(segments.shape[0]),
            "vertices_per_line": [int(counts.min()), int(counts.max())],
            "vertices_inside": float(inside.mean()),
            "segments_level0": datasets.classify(segments, window),
            "description": ("smooth polylines (sums of sinusoids folded into [0,1000]^2), "
                            f"window covering {share} of the extent, centred"),
        }
        log(f"workload {name}")
        info["load_average_before"] = load_average()
        runs = _time_workload(name, _curve_contenders(geometry_type, coords, offsets, segments,
                                                      geoms, window),
                              plan.policy, plan.n_curves, int(coords.shape[0]), 1,
                              segment_line, log)
        info["load_average_after"] = load_average()
        results.append({"workload": info, "runs": runs})
        gc.collect()
    return results


def run_polygons(plan: GeometryPlan, log: Callable[[str], None] = print) -> dict:
    """Time the polygons-with-holes workload (window [250, 750]^2)."""
    window = datasets.POLYGON_WINDOW
    raw = datasets.star_polygons(plan.n_polygons)
    geoms = shapely.from_ragged_array(shapely.GeometryType.POLYGON, raw[0], raw[1:])
    geometry_type, coords, offsets = shapely.to_ragged_array(geoms)
    del raw
    bounds = shapely.bounds(geoms)
    xmin, ymin, xmax, ymax = window
    inside = ((bounds[:, 0] >= xmin) & (bounds[:, 1] >= ymin)
              & (bounds[:, 2] <= xmax) & (bounds[:, 3] <= ymax))
    outside = ((bounds[:, 2] < xmin) | (bounds[:, 0] > xmax)
               | (bounds[:, 3] < ymin) | (bounds[:, 1] > ymax))
    name = f"polygons-{plan.n_polygons}"
    info = {
        "name": name, "family": "polygons", "geometry_type": geometry_type.name,
        "window": list(window), "geometries": plan.n_polygons, "coords": int(coords.shape[0]),
        "rings": int(offsets[0].shape[0] - 1),
        "input_invalid": int(np.count_nonzero(~shapely.is_valid(geoms))),
        "bbox_level0": {"inside": float(inside.mean()), "outside": float(outside.mean()),
                        "crossing": float(1.0 - inside.mean() - outside.mean())},
        "description": ("star-shaped polygons, shell 40 vertices (CCW) + hole 10 vertices "
                        "(CW), R in [5,40], centres uniform in [0,1000]^2; window [250,750]^2"),
    }
    part = shapely.GeometryType.POLYGON
    contenders = [
        (SUBJECT, "rnsca", _rnsca_ragged(geometry_type, coords, offsets, window)),
        (SUBJECT_INTERIOR, "rnsca",
         _rnsca_ragged(geometry_type, coords, offsets, window, boundary="interior")),
        (REF_SHAPELY, "shapely",
         shapely_columnar(_clip_by_rect(window), geometry_type, coords, offsets, part)),
        (REF_INTERSECTION, "shapely",
         shapely_columnar(_intersection(window), geometry_type, coords, offsets, part)),
        (OBJ_CLIP_BY_RECT, "objects", _objects_call(_clip_by_rect(window), geoms)),
        (OBJ_INTERSECTION, "objects", _objects_call(_intersection(window), geoms)),
        (OBJ_RNSCA, "objects", _rnsca_objects(geoms, window)),
    ] + ([] if backend_unavailable_reason("opencl") else [
        (OPENCL_RAGGED, "opencl",
         _rnsca_ragged(geometry_type, coords, offsets, window, backend="opencl")),
    ])
    log(f"workload {name}")
    info["load_average_before"] = load_average()
    runs = _time_workload(name, contenders, plan.policy, plan.n_polygons,
                          int(coords.shape[0]), 2, None, log)
    info["load_average_after"] = load_average()
    return {"workload": info, "runs": runs}


# --------------------------------------------------------------------------- GeoJSON


def _stage(call: Callable[[], object]) -> tuple[float, object]:
    """Return (seconds, result) of one call with the garbage collector paused."""
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        start = time.perf_counter()
        result = call()
        seconds = time.perf_counter() - start
    finally:
        if gc_was_enabled:
            gc.enable()
    return seconds, result


def _count_kinds(collection: dict) -> dict:
    kinds: dict[str, int] = {}
    for feature in collection["features"]:
        kind = feature["geometry"]["type"] if feature.get("geometry") else "null"
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


#: The two output forms of `rnsca.clip_geojson`: nested lists (default) or NumPy views.
GEOJSON_PIPELINES = {"lists": {}, "arrays": {"arrays": True}}


def _clip_parts(parsed: dict, window, arrays: bool) -> tuple[dict[str, float], object]:
    """Time what `rnsca.clip_geojson` does, step by step: read, clip each kind, write."""
    seconds: dict[str, float] = {}
    seconds["read"], layout = _stage(lambda: geojson_format.from_geojson(parsed))
    clipped = {}
    seconds["clip_ragged"] = 0.0
    for kind in ("points", "lines", "polygons"):
        if layout.geometry_count(kind) == 0:
            continue
        t, result = _stage(lambda kind=kind: rnsca.clip_ragged(*getattr(layout, kind), window,
                                                               keep_empty=True))
        seconds["clip_ragged"] += t
        seconds[f"clip_ragged_{kind}"] = t
        clipped[kind] = (result.geometry_type, result.coords, result.offsets)
    seconds["write"], document = _stage(
        lambda: geojson_format.to_geojson(layout, **clipped, arrays=arrays))
    return seconds, document


def run_geojson(plan: GeometryPlan, log: Callable[[str], None] = print) -> dict:
    """Time parse, clip (`rnsca.clip_geojson`) and serialize of one FeatureCollection.

    Parse and serialize are `rnsca.io.geojson.loads` and ``dumps`` (orjson; ``dumps``
    writes NumPy arrays too). For each output form of `GEOJSON_PIPELINES`, each repeat
    runs the three stages in order on fresh objects (the clip gets the parsed collection,
    the serializer the clipped one), then, on another fresh parse, the clip's own steps
    one by one (`_clip_parts`: ``from_geojson``, ``clip_ragged`` per geometry kind,
    ``to_geojson``). The best time of each stage and step over the repeats is reported.
    """
    window = datasets.POLYGON_WINDOW
    collection = datasets.geojson_collection(plan.geojson_lines, plan.geojson_polygons)
    data = geojson_format.dumps(collection)
    kinds_in = _count_kinds(collection)
    del collection
    name = f"geojson-{len(data) / 1e6:.0f}MB"
    log(f"workload {name}")
    small = geojson_format.dumps(datasets.geojson_collection(3, 20))
    for options in GEOJSON_PIPELINES.values():  # compiles every kernel involved
        clipped, _ = rnsca.clip_geojson(geojson_format.loads(small), window, **options)
        geojson_format.dumps(clipped)
    info = {"name": name, "family": "geojson", "window": list(window), "bytes_in": len(data),
            "features_in": sum(kinds_in.values()), "geometry_kinds_in": kinds_in,
            "lines": plan.geojson_lines, "polygons": plan.geojson_polygons,
            "description": ("FeatureCollection of smooth lines (1/5 MultiLineString) and "
                            "star polygons with a hole (1/10 MultiPolygon), with properties; "
                            "window [250,750]^2")}
    info["load_average_before"] = load_average()
    pipelines = {}
    for label, options in GEOJSON_PIPELINES.items():
        samples: dict[str, list[float]] = {"parse": [], "clip": [], "serialize": []}
        parts: dict[str, list[float]] = {}
        out_bytes = b""
        stats = features_out = None
        for k in range(plan.geojson_repeats):
            gc.collect()
            seconds, parsed = _stage(lambda: geojson_format.loads(data))
            samples["parse"].append(seconds)
            seconds, (clipped, clip_stats) = _stage(
                lambda obj=parsed, opts=options: rnsca.clip_geojson(obj, window, **opts))
            samples["clip"].append(seconds)
            del parsed
            seconds, out_bytes = _stage(lambda obj=clipped: geojson_format.dumps(obj))
            samples["serialize"].append(seconds)
            if k == 0:
                stats = clip_stats.to_dict()
                features_out = len(clipped["features"])
            del clipped
            gc.collect()
            part_seconds, document = _clip_parts(geojson_format.loads(data), window,
                                                 bool(options.get("arrays")))
            if k == 0 and geojson_format.dumps(document) != out_bytes:
                raise AssertionError("clip_geojson and its steps disagree on the output")
            del document
            for step, t in part_seconds.items():
                parts.setdefault(step, []).append(t)
            log(f"  {name} ({label}): repeat {k + 1}: "
                + ", ".join(f"{s} {v[-1]:.3f} s" for s, v in samples.items())
                + "; steps " + ", ".join(f"{s} {v[-1]:.3f} s" for s, v in parts.items()))
        best = {s: min(v) for s, v in samples.items()}
        io = best["parse"] + best["serialize"]
        pipelines[label] = {
            "options": options,
            "stages": {s: {"seconds": best[s], "seconds_median": statistics.median(v),
                           "repeats": len(v), "mb_per_s": len(data) / 1e6 / best[s]}
                       for s, v in samples.items()},
            "clip_steps": {s: min(v) for s, v in parts.items()},
            "clip_over_parse_and_serialize": best["clip"] / io if io > 0 else None,
            "total_seconds": sum(best.values()),
            "features_out": features_out,
            "bytes_out": len(out_bytes),
            "stats": stats,
        }
    info["load_average_after"] = load_average()
    return {"workload": info, "pipelines": pipelines}


# --------------------------------------------------------------------------- targets


def _target(key, description, workload, value, limit, op, unit, note=None) -> dict:
    if value is None:
        met = None
    elif op == ">=":
        met = value >= limit
    elif op == "<":
        met = value < limit
    else:  # "=="
        met = value == limit
    out = {"key": key, "description": description, "workload": workload, "value": value,
           "op": op, "limit": limit, "unit": unit, "met": met}
    if note:
        out["note"] = note
    return out


def _speedup(runs: dict, ref: str) -> float | None:
    subject, other = runs.get(SUBJECT), runs.get(ref)
    if subject is None or other is None or subject["seconds"] <= 0:
        return None
    return other["seconds"] / subject["seconds"]


def evaluate_geometry_targets(curves: list[dict], polygons: dict, geojson: dict) -> list[dict]:
    """Return the issue-3 targets, each with its value (from this run) and verdict."""
    targets = []
    for w in curves:
        info = w["workload"]
        runs = {r["label"]: r for r in w["runs"]}
        share = info["window_area_share"]
        key = share.rstrip("%")
        targets.append(_target(f"curves_{key}_vs_shapely",
                               f"curves, window {share}: speed-up over Shapely clip_by_rect "
                               "(columnar)", info["name"], _speedup(runs, REF_SHAPELY), 10.0,
                               ">=", "x"))
        if float(key) <= 10.0:
            targets.append(_target(f"curves_{key}_vs_cohen_sutherland",
                                   f"curves, window {share}: speed-up over per-segment numba "
                                   "Cohen-Sutherland", info["name"], _speedup(runs, REF_CS),
                                   2.0, ">=", "x"))
    runs = {r["label"]: r for r in polygons["runs"]}
    name = polygons["workload"]["name"]
    targets.append(_target("polygons_vs_shapely", "polygons: speed-up over Shapely "
                           "clip_by_rect (columnar)", name, _speedup(runs, REF_SHAPELY), 5.0,
                           ">=", "x"))
    subject = runs.get(SUBJECT)
    targets.append(_target("polygons_valid", "polygons: invalid output geometries (rnsca)",
                           name, subject and subject["output"]["invalid"], 0, "==", "count"))
    for label, pipeline in geojson["pipelines"].items():
        key = "geojson_clip_share" + ("" if label == "lists" else f"_{label}")
        targets.append(_target(key, f"GeoJSON ({label}): clip time / (parse + serialize time)",
                               geojson["workload"]["name"],
                               pipeline["clip_over_parse_and_serialize"], 0.5, "<", "x"))
    return targets
