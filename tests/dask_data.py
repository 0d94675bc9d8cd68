"""Inputs, references and clusters shared by the Dask tests (rnsca.dask, rnsca batch).

`frame` makes a seeded GeoDataFrame of lines and polygons with properties of several
dtypes (some rows outside the window, some inside, some across it, one missing
geometry); `reference` is the single-process library call the Dask results must equal:
`rnsca.clip` on the geometry column, rows left with nothing dropped.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np
import shapely

import rnsca
from tests.missing import missing

try:
    import dask_geopandas
    import distributed
    import geopandas
    import pandas as pd
    import pyarrow  # noqa: F401

    import rnsca.batch
    import rnsca.dask
except ImportError as error:  # pragma: no cover - the dev extra installs them
    IMPORT_ERROR: ImportError | None = error
else:
    IMPORT_ERROR = None

WINDOW = (0.0, 0.0, 100.0, 100.0)


def require_dask() -> None:
    """Skip (fail in CI) where the dask extra is not installed."""
    if IMPORT_ERROR is not None:
        missing(f"the dask extra is not installed (pip install '.[dask]'): {IMPORT_ERROR}")


def geometries(rng: np.random.Generator, count: int) -> np.ndarray:
    """Return `count` seeded lines and polygons around the window (a third beyond it)."""
    start = rng.uniform(-60, 160, (count, 2))
    walks = start[:, None, :] + rng.normal(0, 6, (count, 12, 2)).cumsum(axis=1)
    lines = shapely.linestrings(walks)
    radius = rng.uniform(1, 25, count)
    polygons = shapely.buffer(shapely.points(start), radius, quad_segs=4)
    holed = shapely.difference(polygons, shapely.buffer(shapely.points(start), radius / 3))
    out = np.where(np.arange(count) % 3 == 0, lines,
                   np.where(np.arange(count) % 3 == 1, polygons, holed))
    return out


def frame(rng: np.random.Generator, count: int, first: int = 0) -> geopandas.GeoDataFrame:
    """Return a frame of `count` features with an int, a float, a str and a nullable column."""
    values = geometries(rng, count)
    values[count // 2] = None  # one missing geometry
    numbers = np.arange(first, first + count)
    return geopandas.GeoDataFrame(
        {"id": numbers, "weight": rng.uniform(0, 1, count),
         "name": [f"feature {i}" for i in numbers],
         "note": pd.array([None if i % 5 == 0 else i % 7 for i in numbers], dtype="Int64")},
        geometry=values, crs="EPSG:3857")


def reference(whole: geopandas.GeoDataFrame, window=WINDOW,
              keep_empty: bool = False) -> geopandas.GeoDataFrame:
    """Return the single-process library call: `rnsca.clip` of the geometry column."""
    clipped = rnsca.clip(np.asarray(whole.geometry.array, dtype=object), window)
    kept = np.ones(len(whole), bool) if keep_empty else \
        ~shapely.is_missing(clipped) & ~shapely.is_empty(clipped)
    out = whole.iloc[np.flatnonzero(kept)].copy()
    out[whole.geometry.name] = geopandas.GeoSeries(clipped[kept], index=out.index,
                                                   crs=whole.crs)
    return out


def assert_same_frames(got, expected) -> None:
    """Assert the rows, their order, properties, index labels and geometries are equal."""
    assert list(got.columns) == list(expected.columns)
    assert got.index.tolist() == expected.index.tolist()
    assert got.crs == expected.crs
    name = expected.geometry.name
    pd.testing.assert_frame_equal(pd.DataFrame(got.drop(columns=name)),
                                  pd.DataFrame(expected.drop(columns=name)))
    a = np.asarray(got.geometry.array, dtype=object)
    b = np.asarray(expected.geometry.array, dtype=object)
    assert np.array_equal(shapely.is_missing(a), shapely.is_missing(b))
    present = ~shapely.is_missing(b)
    assert shapely.equals_exact(a[present], b[present], tolerance=0).all()


@contextlib.contextmanager
def local_client(workers: int = 2) -> Iterator[distributed.Client]:
    """Yield a client of a LocalCluster of `workers` processes (1 thread each) on loopback.

    Bounded waits: the workers must be up within 120 s; closing takes at most 60 s.
    """
    cluster = rnsca.batch.local_cluster(workers, dashboard_address=":0")
    client = distributed.Client(cluster, timeout=120)
    try:
        client.wait_for_workers(workers, timeout=120)
        yield client
    finally:
        cluster.close(timeout=60)
        client.close(timeout=60)


__all__ = ["WINDOW", "assert_same_frames", "dask_geopandas", "frame", "geometries",
           "local_client", "reference", "require_dask"]
