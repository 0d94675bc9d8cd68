"""Warm-up: the kernels each endpoint needs, compiled (or loaded) before it is served.

A cold start compiles for minutes of CPU time on a small machine (measured on one core:
about 17 s for the segment kernels, 30 s for lines, 60 s for polygons, 37 s for SVG), and
a warm one loads everything from Numba's disk cache in seconds.
So warm-up is a list of steps (`Step`), and each endpoint is served as soon as the steps it
needs are done (`ENDPOINT_STEPS`): segments first, the cheapest.

When the first step is not done within `COLD_SECONDS`, the cache is cold: the remaining
steps are then compiled meanwhile in child processes, one per core (`compile_step`),
each writing Numba's disk cache; this process loads each step as its child finishes.
Compiling is single-threaded (Numba holds one compiler lock per process), so this is
how a cold start uses more than one core. The steps share a few small kernels (the
segment clips the line clip's baselines call), which two processes may then both
compile: seconds, against the 17 s the other core would otherwise idle through the
first step. Each step is compiled under a file lock (`step_lock`): the workers of
``rnsca serve --workers N`` share the cache, and a step one of them compiles is
loaded, not compiled again, by the others.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import orjson
import shapely

import rnsca
from rnsca.backends.numba_cpu import (
    warm_up_lines,
    warm_up_paths,
    warm_up_polygons,
    warm_up_segments,
)
from rnsca.backends.registry import available_backends, get_backend
from rnsca.options import Backend
from rnsca.runtime import configure_process

__all__ = ["COLD_SECONDS", "ENDPOINT_STEPS", "STEPS", "Step", "compile_step", "step_lock",
           "steps_for"]

#: A first step not done within this many seconds means the kernel cache is cold.
COLD_SECONDS = 3.0


@dataclass(frozen=True)
class Step:
    """One unit of warm-up: a function that runs kernels so they are compiled or loaded.

    `needs` are steps whose kernels this one calls as well: a child process compiling
    this step waits for them first (under their locks), then loads them.
    """

    name: str
    run: Callable[[], object]
    needs: tuple[str, ...] = ()


def _requests(kind: str) -> None:
    """Answer small requests of `kind` as the service does (checks, verification included).

    The backends' warm-up calls the kernels directly; a request also runs the input checks
    and the verification, whose kernels must not be compiled by a request either: a
    compile holds the process's compiler lock, and a request waiting for it would time out.
    """
    from rnsca.window import Window
    from service import convert, slices
    from service.config import Settings
    from service.schemas import ClipOptions

    settings = Settings(warm_up=False)
    window = [0.0, 0.0, 1.0, 1.0]
    for verify in (True, False):
        if kind == "segments":
            convert.clip_segments_json(orjson.dumps({
                "window": window, "segments": [[-1.0, 0.5, 2.0, 0.5]], "verify": verify}),
                settings)
            convert.clip_segments_binary(np.array([[-1.0, 0.5, 2.0, 0.5]]).tobytes(),
                                         Window(*window), ClipOptions(), verify, settings)
        elif kind == "geojson":
            for document in (_collection([]), _collection([0.5]), _mixed_collection()):
                body = orjson.dumps({"window": window, "verify": verify,
                                     "geojson": document})
                convert.clip_geojson(body, settings)
                slices.parse_sliced(body)  # large bodies' scan, whatever this one's size
        else:
            convert.clip_svg(orjson.dumps({"window": window, "verify": verify, "paths": [
                "M -1 0.5 C 0 2 1 -1 2 0.5 Z", "M -1 0.25 L 2 0.25 A 1 1 0 0 1 0 0"]}),
                settings)


def _collection(z: list[float]) -> dict:
    """Return a FeatureCollection of a point, a line and a polygon across the unit window."""
    ring = [[-1.0, 0.25, *z], [2.0, 0.25, *z], [2.0, 0.75, *z], [-1.0, 0.75, *z],
            [-1.0, 0.25, *z]]
    geometries = [{"type": "Point", "coordinates": [0.5, 0.5, *z]},
                  {"type": "LineString", "coordinates": ring},
                  {"type": "Polygon", "coordinates": [ring]}]
    return {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": g} for g in geometries]}


def _segments() -> None:
    warm_up_segments(get_backend(Backend.NUMBA))
    _requests("segments")


def _lines() -> None:
    warm_up_lines(get_backend(Backend.NUMBA))


def _polygons() -> None:
    warm_up_polygons(get_backend(Backend.NUMBA))


def _mixed_collection() -> dict:
    """Return `_collection` in 3D with a 2D line added (a document mixing both)."""
    mixed = _collection([0.0])
    mixed["features"].append({"type": "Feature", "properties": {}, "geometry": {
        "type": "LineString", "coordinates": [[-1.0, 0.5], [2.0, 0.5]]}})
    return mixed


def _geojson() -> None:
    """Answer small GeoJSON requests (2D, 3D, mixed): the reader's and writer's kernels."""
    _requests("geojson")


def _svg() -> None:
    # The service's own SVG calls (every curve handling and fill rule), then the paths
    # kernels as the backend's warm-up runs them.
    from service.convert import warm_up_svg

    warm_up_paths(get_backend(Backend.NUMBA))
    warm_up_svg()
    _requests("svg")


def _tiles() -> None:
    """Cut a small document into tiles as the tile endpoints do (their kernels)."""
    from rnsca.tiles import FeatureTable, tile_one, tile_table

    table = FeatureTable.of([shapely.LineString([(-10, -10), (10, 10)]),
                             shapely.Point(1, 1), shapely.box(-5, -5, 5, 5)],
                            [{"a": 1}] * 3, [1, 2, 3])
    for _ in tile_table(table, maxzoom=2):
        pass
    tile_one(table, 1, 0, 0)


def _opencl() -> None:
    get_backend(Backend.OPENCL).warm_up()
    # backend="auto": the calibration here, not in the first request that asks for it.
    from rnsca.backends.auto import calibration

    calibration()


#: Every step, in the order they are done: segments first (the cheapest, so the first
#: endpoint is served soonest), the OpenCL backend last (no endpoint waits for it). On a
#: cold start the child processes take them in this order too, a step once the steps it
#: `needs` are compiled (`ClipRunner.warm_up`).
STEPS = (Step("segments", _segments), Step("lines", _lines), Step("polygons", _polygons),
         Step("geojson", _geojson, ("lines", "polygons")), Step("svg", _svg),
         Step("tiles", _tiles, ("lines", "polygons")), Step("opencl", _opencl))

#: The steps each clipping endpoint waits for (by the name `ClipRunner.run` is given).
ENDPOINT_STEPS = {"segments": ("segments",), "geoarrow": ("lines", "polygons"),
                  "geojson": ("lines", "polygons", "geojson"), "svg": ("svg",),
                  "tiles": ("lines", "polygons", "tiles")}


def steps_for(backends: list[Backend] | None = None) -> tuple[Step, ...]:
    """Return the steps to run here: all but OpenCL's when that backend is not available."""
    present = available_backends() if backends is None else backends
    return tuple(s for s in STEPS if s.name != "opencl" or Backend.OPENCL in present)


def _lock_folder() -> Path:
    # One folder per installed copy of rnsca: two checkouts do not wait for each other.
    key = hashlib.sha1(os.path.dirname(rnsca.__file__).encode()).hexdigest()[:12]
    folder = Path(tempfile.gettempdir()) / f"rnsca-warm-up-{key}"
    folder.mkdir(exist_ok=True)
    return folder


@contextmanager
def step_lock(name: str) -> Iterator[None]:
    """Hold the machine-wide lock of step `name` (an advisory file lock) inside the block."""
    with open(_lock_folder() / f"{name}.lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def compile_step(name: str) -> str:
    """Compile step `name` into Numba's disk cache, in a child process; return `name`.

    The steps it needs are done first, each under its lock (loaded, if another process
    compiled them), so that no two processes compile the same kernels at once.
    """
    configure_process()
    by_name = {s.name: s for s in STEPS}
    for needed in by_name[name].needs:
        with step_lock(needed):
            by_name[needed].run()
    with step_lock(name):
        by_name[name].run()
    return name
