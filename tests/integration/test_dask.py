"""rnsca.dask: frames and segment arrays clipped on a real LocalCluster of two worker
processes equal the single-process library call (rows, order, index, properties)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

import rnsca
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    UnsupportedGeometryError,
)
from tests.dask_data import (
    WINDOW,
    assert_same_frames,
    frame,
    local_client,
    reference,
    require_dask,
)

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def client():
    require_dask()
    with local_client(2) as client:
        yield client


@pytest.fixture
def data(rng):
    require_dask()
    whole = frame(rng, 900)
    whole.index = [f"r{i:04d}" for i in range(len(whole))]   # labels (sorted), not positions
    return whole


def test_dask_frame_equals_the_library_call_and_keeps_meta_and_divisions(client, data):
    import dask_geopandas

    import rnsca.dask

    lazy = dask_geopandas.from_geopandas(data, npartitions=4)
    clipped = rnsca.dask.clip(lazy, WINDOW)
    assert isinstance(clipped, dask_geopandas.GeoDataFrame)
    assert clipped.npartitions == 4 and clipped.divisions == lazy.divisions
    got = clipped.compute()
    assert got.dtypes.equals(clipped._meta.dtypes)
    # The same rows as Dask holds them (its strings are Arrow strings).
    assert_same_frames(got, reference(lazy.compute()))
    assert 0 < len(got) < len(data)


def test_dask_series_equals_the_library_call(client, data):
    import dask_geopandas

    import rnsca.dask

    lazy = dask_geopandas.from_geopandas(data, npartitions=3)
    clipped = rnsca.dask.clip(lazy.geometry, WINDOW)
    assert isinstance(clipped, dask_geopandas.GeoSeries)
    got = clipped.compute()
    expected = reference(lazy.compute()).geometry
    assert got.index.tolist() == expected.index.tolist() and got.crs == expected.crs
    assert shapely.equals_exact(np.asarray(got.array, dtype=object),
                                np.asarray(expected.array, dtype=object), tolerance=0).all()


def test_plain_geopandas_is_clipped_in_process(data):
    import geopandas

    import rnsca.dask

    got = rnsca.dask.clip(data, WINDOW)
    assert isinstance(got, geopandas.GeoDataFrame)
    assert_same_frames(got, reference(data))


def test_keep_empty_keeps_every_row_and_a_missing_geometry_stays_missing(client, data):
    import dask_geopandas

    import rnsca.dask

    lazy = dask_geopandas.from_geopandas(data, npartitions=2)
    got = rnsca.dask.clip(lazy, WINDOW, keep_empty=True).compute()
    assert_same_frames(got, reference(lazy.compute(), keep_empty=True))
    values = np.asarray(got.geometry.array, dtype=object)
    assert len(got) == len(data)
    assert shapely.is_missing(values).sum() == 1 and shapely.is_empty(values).sum() > 0


def test_spatial_partitions_are_cut_to_the_window(client, data):
    import dask_geopandas

    import rnsca.dask

    lazy = dask_geopandas.from_geopandas(data, npartitions=2)
    lazy.calculate_spatial_partitions()
    clipped = rnsca.dask.clip(lazy, WINDOW)
    regions = clipped.spatial_partitions
    assert regions is not None and shapely.box(*WINDOW).covers(regions.union_all())
    got = clipped.compute()
    for number in range(clipped.npartitions):
        part = clipped.get_partition(number).compute()
        assert regions.iloc[number].covers(part.geometry.union_all())
    assert len(got) > 0


def test_options_and_window_are_checked_before_anything_runs(data):
    import dask_geopandas

    import rnsca.dask

    lazy = dask_geopandas.from_geopandas(data, npartitions=2)
    with pytest.raises(InvalidOptionError, match="method"):
        rnsca.dask.clip(lazy, WINDOW, method="nope")
    with pytest.raises(InvalidWindowError):
        rnsca.dask.clip(lazy, (10, 0, 0, 10))
    with pytest.raises(InvalidWindowError, match="one of window= and windows="):
        rnsca.dask.clip(lazy, WINDOW, windows=[WINDOW, WINDOW])
    with pytest.raises(InvalidWindowError, match="window 1"):
        rnsca.dask.clip(lazy, windows=[WINDOW, (10, 0, 0, 10)])
    with pytest.raises(InvalidOptionError, match="keep_empty applies to one window"):
        rnsca.dask.clip(lazy, windows=[WINDOW], keep_empty=True)
    with pytest.raises(InvalidOptionError, match="has a column 'name'"):
        rnsca.dask.clip(lazy, windows=[WINDOW], window_column="name")
    with pytest.raises(UnsupportedGeometryError, match="dask_geopandas or geopandas"):
        rnsca.dask.clip([shapely.Point(1, 1)], WINDOW)


FRAME_WINDOWS = [(0.0, 0.0, 50.0, 50.0), (40.0, 40.0, 100.0, 100.0),
                 (-20.0, 60.0, 10.0, 130.0)]


def _windows_reference(data, windows=FRAME_WINDOWS):
    """The library call with windows=, rows by source then window, the window column."""
    import geopandas

    result = rnsca.clip(np.asarray(data.geometry.array, dtype=object), windows=windows)
    order = np.lexsort((result.window, result.source))
    out = data.iloc[result.source[order]].copy()
    out["geometry"] = geopandas.GeoSeries(result.geometries[order], index=out.index,
                                          crs=data.crs)
    out["window"] = result.window[order].astype(np.int64)
    return out


def test_dask_frame_with_many_windows_equals_the_library_call(client, data):
    import dask_geopandas

    import rnsca.dask

    lazy = dask_geopandas.from_geopandas(data, npartitions=4)
    clipped = rnsca.dask.clip(lazy, windows=FRAME_WINDOWS)
    assert clipped.divisions == lazy.divisions
    assert list(clipped._meta.columns) == [*data.columns, "window"]
    got = clipped.compute()
    assert got.dtypes.equals(clipped._meta.dtypes)
    expected = _windows_reference(lazy.compute())
    assert_same_frames(got, expected)
    assert got.index.duplicated().any() and set(got["window"]) == {0, 1, 2}
    # In process, a plain frame and a series (a frame of its geometry and the window).
    assert_same_frames(rnsca.dask.clip(data, windows=FRAME_WINDOWS),
                       _windows_reference(data))
    series = rnsca.dask.clip(data.geometry, windows=FRAME_WINDOWS, window_column="w")
    assert list(series.columns) == ["geometry", "w"]
    assert series["w"].tolist() == _windows_reference(data)["window"].tolist()


def test_a_bad_geometry_is_named_by_its_index_label(client, data):
    import dask_geopandas

    import rnsca.dask

    data.loc["r0007", "geometry"] = shapely.LineString([(0, 0), (np.nan, 5)])
    lazy = rnsca.dask.clip(dask_geopandas.from_geopandas(data, npartitions=3), WINDOW)
    with pytest.raises(InvalidGeometryError, match="row .r0007. .*non-finite"):
        lazy.compute()


@pytest.fixture
def segments(rng):
    require_dask()
    return rng.uniform(-50, 150, (20_000, 4))


def _assert_same_segment_results(got, expected):
    assert np.array_equal(got.segments, expected.segments)
    assert np.array_equal(got.source, expected.source)
    assert np.array_equal(got.t, expected.t)
    assert got.stats == expected.stats


def test_dask_segments_equal_the_library_call_with_global_sources(client, segments):
    import dask
    import dask.array as da

    import rnsca.dask

    lazy = rnsca.dask.clip(da.from_array(segments, chunks=(3_000, 2)), WINDOW)
    assert np.isnan(lazy.segments.shape[0]) and lazy.segments.numblocks[0] == 7
    expected = rnsca.clip_segments(segments, WINDOW)
    _assert_same_segment_results(lazy.compute(), expected)
    pieces, source = dask.compute(lazy.segments, lazy.source)
    assert np.array_equal(pieces, expected.segments)
    assert np.array_equal(source, expected.source)


def test_dask_segments_with_many_windows_equal_the_library_call(client, segments):
    import dask.array as da

    import rnsca.dask

    windows = [[0, 0, 50, 50], [50, 50, 100, 100], [-20, 10, 30, 90]]
    got = rnsca.dask.clip(da.from_array(segments, chunks=4_000), windows=windows).compute()
    expected = rnsca.clip_segments(segments, windows=windows)
    _assert_same_segment_results(got, expected)
    assert np.array_equal(got.window, expected.window)
    assert np.array_equal(got.window_offsets, expected.window_offsets)


def test_a_bad_segment_is_named_by_its_global_row(client, segments):
    import dask.array as da

    import rnsca.dask

    segments[12_345, 1] = np.inf
    lazy = rnsca.dask.clip(da.from_array(segments, chunks=5_000), WINDOW)
    with pytest.raises(InvalidGeometryError, match="segment 12345 ") as caught:
        lazy.compute()
    assert caught.value.row == 12_345


def test_segment_arrays_need_four_columns_and_known_chunks(segments):
    import dask.array as da

    import rnsca.dask

    with pytest.raises(InvalidGeometryError, match=r"shape \(n, 4\)"):
        rnsca.dask.clip(da.from_array(segments[:, :3]), WINDOW)
    unknown = da.from_array(segments, chunks=5_000)
    unknown = unknown[unknown[:, 0] > 0]
    with pytest.raises(InvalidGeometryError, match="compute_chunk_sizes"):
        rnsca.dask.clip(unknown, WINDOW)
    with pytest.raises(InvalidOptionError):
        rnsca.dask.clip(da.from_array(segments), WINDOW, mode="sideways")


def test_a_worker_killed_mid_compute_changes_nothing(client, rng):
    import os

    import dask_geopandas
    import pandas as pd
    from distributed import as_completed

    import rnsca.dask

    data = frame(rng, 12_000)
    lazy = dask_geopandas.from_geopandas(data, npartitions=12)
    parts = client.compute([rnsca.dask.clip(lazy, WINDOW).get_partition(number)
                            for number in range(12)])
    killed = []
    for _ in as_completed(parts):
        busy = [address for address, keys in client.processing().items() if keys]
        if not killed and busy:
            pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
            os.kill(pid, 9)
            killed.append(pid)
    assert killed, "no worker was busy to kill"
    got = pd.concat(client.gather(parts))
    assert_same_frames(got, reference(lazy.compute()))
    client.wait_for_workers(2, timeout=120)
