"""rnsca batch on a real LocalCluster of two worker processes: the output equals the
single-process library call; a worker killed mid-job, a corrupt partition and a job
stopped half-way leave the output complete, valid and without duplicates."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest
import shapely

import rnsca
from tests.dask_data import (
    WINDOW,
    assert_same_frames,
    frame,
    local_client,
    reference,
    require_dask,
)

pytestmark = pytest.mark.slow

ROWS = 1_200          # per input file
ROW_GROUP = 300       # so that each file makes several partitions
FILES = 3


@pytest.fixture(scope="module")
def client():
    require_dask()
    with local_client(2) as client:
        yield client


@pytest.fixture
def inputs(tmp_path, rng):
    """Three GeoParquet files of lines and polygons (row groups of 300), and all rows."""
    require_dask()
    import pandas as pd

    folder = tmp_path / "in"
    folder.mkdir()
    parts = []
    for number in range(FILES):
        part = frame(rng, ROWS, first=number * ROWS)
        part.to_parquet(folder / f"roads-{number}.parquet", row_group_size=ROW_GROUP)
        parts.append(part)
    whole = pd.concat(parts, ignore_index=True)
    return folder, whole


def _job(tmp_path, **kwargs):
    import rnsca.batch

    return rnsca.batch.Job(output=str(tmp_path / "out"), window=WINDOW, **kwargs)


def _plan(folder, rows=ROW_GROUP):
    import rnsca.batch

    return rnsca.batch.plan(rnsca.batch.find_inputs(str(folder)), rows_per_partition=rows)


def _read_output(folder):
    """Return the output dataset's rows in file order (how a reader of the folder sees it)."""
    import geopandas
    import pandas as pd

    files = sorted(name for name in os.listdir(folder) if name.endswith(".parquet"))
    assert not [name for name in os.listdir(folder) if name.startswith(".")]
    parts = [geopandas.read_parquet(folder / name) for name in files]
    return pd.concat(parts, ignore_index=True) if parts else None


def _expected(whole, **kwargs):
    return reference(whole, **kwargs).reset_index(drop=True)


def test_batch_equals_the_single_process_library_call(client, inputs, tmp_path):
    import pyarrow.parquet as pq

    import rnsca.batch

    folder, whole = inputs
    partitions = _plan(folder)
    assert len(partitions) == FILES * ROWS // ROW_GROUP
    report = rnsca.batch.run(_job(tmp_path), partitions, client)
    assert not report.failed and len(report.written) == len(partitions)
    assert sum(r.rows_in for r in report.written) == len(whole)
    got = _read_output(tmp_path / "out")
    assert_same_frames(got, _expected(whole))
    # GeoParquet 1.1: WKB column, bbox covering column, the whole dataset readable at once.
    one = pq.read_metadata(tmp_path / "out" / partitions[0].name)
    geo = json.loads(one.metadata[b"geo"])
    assert geo["version"] == "1.1.0" and geo["columns"]["geometry"]["encoding"] == "WKB"
    assert geo["columns"]["geometry"]["covering"]["bbox"]["xmin"] == ["bbox", "xmin"]
    table = pq.read_table(tmp_path / "out")
    assert table.num_rows == len(got) and "bbox" in table.column_names


def test_geoarrow_output_has_one_schema_across_partitions(client, inputs, tmp_path):
    import geopandas
    import pyarrow.dataset as ds

    import rnsca.batch

    folder, whole = inputs
    lines = whole[whole.geometry.geom_type == "LineString"].reset_index(drop=True)
    # Beyond the window: the last partition is left empty, and must still match.
    lines.loc[len(lines) - 200:, "geometry"] = shapely.LineString([(500, 500), (600, 600)])
    source = tmp_path / "lines.parquet"
    lines.to_parquet(source, row_group_size=200)
    partitions = _plan(source, rows=200)
    report = rnsca.batch.run(_job(tmp_path, encoding=rnsca.batch.Encoding.GEOARROW),
                             partitions, client)
    assert not report.failed and any(r.rows_out == 0 for r in report.written)
    dataset = ds.dataset(tmp_path / "out", format="parquet")
    assert all(f.physical_schema.field("geometry").metadata[b"ARROW:extension:name"]
               == b"geoarrow.multilinestring" for f in dataset.get_fragments())
    got = geopandas.read_parquet(tmp_path / "out")
    expected = _expected(lines)
    assert got["id"].tolist() == expected["id"].tolist()
    assert shapely.equals(np.asarray(got.geometry.array, dtype=object),
                          np.asarray(expected.geometry.array, dtype=object)).all()


def test_a_worker_killed_mid_job_loses_and_duplicates_nothing(client, inputs, tmp_path):
    import rnsca.batch

    folder, whole = inputs
    partitions = _plan(folder, rows=ROW_GROUP)
    killed = []

    def kill_a_busy_worker(partition, report, error):
        if killed:
            return
        busy = [address for address, keys in client.processing().items() if keys]
        if not busy:
            return
        pids = client.run(os.getpid, workers=busy[:1])
        os.kill(pids[busy[0]], 9)
        killed.append(busy[0])

    report = rnsca.batch.run(_job(tmp_path), partitions, client, on_done=kill_a_busy_worker)
    assert killed, "no worker was busy to kill"
    assert not report.failed and len(report.written) == len(partitions)
    assert_same_frames(_read_output(tmp_path / "out"), _expected(whole))
    client.wait_for_workers(2, timeout=120)   # the nanny restarts the killed worker


def test_a_corrupt_file_fails_alone_naming_it(client, inputs, tmp_path):
    import pyarrow.parquet as pq

    import rnsca.batch

    folder, whole = inputs
    broken = folder / "roads-1.parquet"
    data = bytearray(broken.read_bytes())
    data[len(data) // 2:] = b"\0" * (len(data) - len(data) // 2)   # footer and half gone
    broken.write_bytes(bytes(data))
    partitions = _plan(folder)
    report = rnsca.batch.run(_job(tmp_path), partitions, client)
    assert len(report.failed) == 1
    failed, message = report.failed[0]
    assert failed.path == str(broken) and str(broken) in message and "cannot read" in message
    # The other files' partitions are all there, complete and equal to the library call.
    good = whole[whole["id"] // ROWS != 1].reset_index(drop=True)
    assert_same_frames(_read_output(tmp_path / "out"), _expected(good))
    for name in os.listdir(tmp_path / "out"):
        if name.endswith(".parquet"):
            assert pq.read_metadata(tmp_path / "out" / name).num_rows >= 0


def test_a_bad_geometry_is_named_by_file_and_row(client, inputs, tmp_path):
    import rnsca.batch

    folder, whole = inputs
    bad = whole.iloc[ROWS:2 * ROWS].reset_index(drop=True)
    # Across the window's edge, so that it reaches the clip (see the report: a NaN
    # geometry whose finite bounds lie inside the window is returned by rnsca.clip as is).
    bad.loc[777, "geometry"] = shapely.LineString([(-5, 1), (np.nan, 2), (5, 5)])
    bad.to_parquet(folder / "roads-1.parquet", row_group_size=ROW_GROUP)
    report = rnsca.batch.run(_job(tmp_path), _plan(folder), client)
    assert len(report.failed) == 1
    message = report.failed[0][1]
    assert message.startswith(f"{folder / 'roads-1.parquet'}: row 777 ")
    assert "non-finite" in message
    written = {r.name for r in report.written}
    assert len(written) == FILES * ROWS // ROW_GROUP - 1


def test_resume_writes_only_what_is_missing(client, inputs, tmp_path):
    import rnsca.batch

    folder, whole = inputs
    partitions = _plan(folder)
    job = _job(tmp_path)

    class Stop(Exception):
        pass

    done = []

    def stop_half_way(partition, report, error):
        done.append(partition.name)
        if len(done) == len(partitions) // 2:
            raise Stop

    with pytest.raises(Stop):
        rnsca.batch.run(job, partitions, client, on_done=stop_half_way)
    out = tmp_path / "out"
    # Tasks running when the job stopped (cancelled, but not interrupted) finish first.
    deadline = time.monotonic() + 60
    while any(client.processing().values()) and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(0.5)
    before = {name: os.stat(out / name).st_mtime_ns for name in os.listdir(out)
              if name.endswith(".parquet")}
    assert 0 < len(before) < len(partitions)
    # A file cut short (as by a crash outside rnsca's control) is redone too.
    victim = sorted(before)[0]
    (out / victim).write_bytes((out / victim).read_bytes()[:100])
    report = rnsca.batch.run(job, partitions, client)
    assert not report.failed
    rewritten = {r.name for r in report.written}
    assert rewritten == {p.name for p in partitions} - set(before) | {victim}
    assert report.skipped == len(before) - 1
    for name, stamp in before.items():
        if name != victim:
            assert os.stat(out / name).st_mtime_ns == stamp
    assert_same_frames(_read_output(out), _expected(whole))


def test_another_job_into_the_same_output_is_refused(client, inputs, tmp_path):
    import rnsca.batch
    from rnsca.errors import InvalidOptionError

    folder, _ = inputs
    partitions = _plan(folder)
    rnsca.batch.run(_job(tmp_path), partitions, client)
    other = rnsca.batch.Job(output=str(tmp_path / "out"), window=(0.0, 0.0, 50.0, 50.0))
    with pytest.raises(InvalidOptionError, match="differs in: window"):
        rnsca.batch.run(other, partitions, client)


def test_flatgeobuf_and_text_sequences_equal_the_library_call(client, inputs, tmp_path):
    import rnsca.batch

    _, whole = inputs
    rows = whole.iloc[:900].copy()
    rows["note"] = rows["note"].astype("float64")   # as GDAL and JSON give it back
    # A missing geometry needs a FlatGeobuf without its spatial index.
    rows.to_file(tmp_path / "roads.fgb", driver="FlatGeobuf",
                 layer_options={"SPATIAL_INDEX": "NO"})
    _write_lines(rows, tmp_path / "roads.geojsonl")
    for name, rows_per_partition, size in (("roads.fgb", 250, 1 << 27),
                                           ("roads.geojsonl", 10**6, 60_000)):
        partitions = rnsca.batch.plan([tmp_path / name], rows_per_partition=rows_per_partition,
                                      bytes_per_partition=size)
        assert len(partitions) > 2
        job = rnsca.batch.Job(output=str(tmp_path / f"out-{name}"), window=WINDOW)
        report = rnsca.batch.run(job, partitions, client)
        assert not report.failed
        got = _read_output(tmp_path / f"out-{name}")
        expected = _expected(rows)
        assert got["id"].tolist() == expected["id"].tolist(), name
        assert np.allclose(got["weight"], expected["weight"]), name
        assert shapely.equals_exact(np.asarray(got.geometry.array, dtype=object),
                                    np.asarray(expected.geometry.array, dtype=object),
                                    tolerance=1e-9).all(), name


def _write_lines(rows, path):
    """Write `rows` as newline-delimited GeoJSON (one Feature per line)."""
    import orjson

    with open(path, "wb") as stream:
        for row, geometry in zip(rows.drop(columns="geometry").to_dict("records"),
                                 rows.geometry, strict=True):
            properties = {k: (None if v is None or v != v else v) for k, v in row.items()}
            feature = {"type": "Feature", "properties": properties,
                       "geometry": None if geometry is None
                       else json.loads(shapely.to_geojson(geometry))}
            stream.write(orjson.dumps(feature, option=orjson.OPT_SERIALIZE_NUMPY) + b"\n")


def test_cli_on_a_scheduler_writes_the_dataset_and_resumes(client, inputs, tmp_path):
    folder, whole = inputs
    out = tmp_path / "out"
    command = [sys.executable, "-m", "rnsca.cli", "batch", str(folder), str(out),
               "--window", ",".join(map(str, WINDOW)), "--scheduler", client.scheduler.address,
               "--rows-per-partition", str(ROW_GROUP), "--no-progress"]
    first = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    assert "dashboard: http" in first.stderr
    report = json.loads(first.stderr.strip().splitlines()[-1])
    assert report["written"] == FILES * ROWS // ROW_GROUP and report["failed"] == 0
    assert_same_frames(_read_output(out), _expected(whole))
    again = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stderr.strip().splitlines()[-1])["skipped"] == report["written"]


def test_cli_on_its_own_local_cluster_reports_a_bad_file_and_exits_1(inputs, tmp_path):
    folder, whole = inputs
    (folder / "roads-2.parquet").write_bytes(b"not parquet at all")
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "batch", str(folder / "*.parquet"), str(out),
         "--window", ",".join(map(str, WINDOW)), "--workers", "2",
         "--rows-per-partition", str(2 * ROW_GROUP), "--no-progress"],
        capture_output=True, text=True, timeout=300)
    assert result.returncode == 1, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
    assert errors == [errors[0]] and str(folder / "roads-2.parquet") in errors[0]
    good = whole[whole["id"] < 2 * ROWS].reset_index(drop=True)
    assert_same_frames(_read_output(out), _expected(good))


def test_cli_refuses_a_bad_window_and_an_unknown_input_kind(tmp_path):
    require_dask()
    (tmp_path / "a.shp").write_bytes(b"")
    for arguments, expected in (
            ([str(tmp_path / "a.shp"), str(tmp_path / "o"), "--window", "0,0,1,1"],
             "not an input rnsca batch reads"),
            ([str(tmp_path), str(tmp_path / "o"), "--window", "0,0,1"], "--window"),
            ([str(tmp_path / "none.parquet"), str(tmp_path / "o"), "--window", "0,0,1,1"],
             "no such file")):
        result = subprocess.run([sys.executable, "-m", "rnsca.cli", "batch", *arguments],
                                capture_output=True, text=True, timeout=120)
        assert result.returncode == 2 and expected in result.stderr, result.stderr


WINDOWS = [(0.0, 0.0, 50.0, 50.0), (40.0, 40.0, 100.0, 100.0), (-20.0, 60.0, 10.0, 130.0),
           (500.0, 500.0, 501.0, 501.0)]


def _expected_windows(whole, windows=WINDOWS):
    """The single-process library call with windows=, its rows by source then window."""
    import geopandas

    result = rnsca.clip(np.asarray(whole.geometry.array, dtype=object), windows=windows)
    order = np.lexsort((result.window, result.source))
    out = whole.iloc[result.source[order]].copy()
    out["geometry"] = geopandas.GeoSeries(result.geometries[order], index=out.index,
                                          crs=whole.crs)
    out["window"] = result.window[order].astype(np.int64)
    return out.reset_index(drop=True)


def test_many_windows_equal_the_single_process_library_call(client, inputs, tmp_path):
    import rnsca.batch

    folder, whole = inputs
    partitions = _plan(folder)
    job = rnsca.batch.Job(output=str(tmp_path / "out"), window=None, windows=tuple(WINDOWS))
    report = rnsca.batch.run(job, partitions, client)
    assert not report.failed and len(report.written) == len(partitions)
    got = _read_output(tmp_path / "out")
    expected = _expected_windows(whole)
    assert_same_frames(got, expected)
    # Rows in several windows come out once per window; the empty window holds nothing.
    assert len(got) > whole.geometry.notna().sum() * 0.3
    assert got.duplicated("id").any() and set(got["window"]) == {0, 1, 2}


def test_cli_windows_file_on_a_scheduler(client, inputs, tmp_path):
    folder, whole = inputs
    windows = tmp_path / "windows.csv"
    windows.write_text("xmin,ymin,xmax,ymax\n" + "\n".join(
        ",".join(map(str, w)) for w in WINDOWS) + "\n")
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "batch", str(folder), str(out), "--windows",
         str(windows), "--window-column", "tile", "--scheduler", client.scheduler.address,
         "--rows-per-partition", str(2 * ROW_GROUP), "--no-progress"],
        capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    expected = _expected_windows(whole).rename(columns={"window": "tile"})
    assert_same_frames(_read_output(out), expected)


def test_cli_names_the_file_and_line_of_a_bad_window(inputs, tmp_path):
    folder, _ = inputs
    for name, text, expected in (
            ("w.csv", "0,0,10,10\n# note\n5,5,1,20\n", "w.csv: line 3: window [5.0, 5.0, 1.0, "
             "20.0] must be finite with xmin < xmax"),
            ("w.csv", "xmin,ymin,xmax,ymax\n0,0,10\n", "w.csv: line 2: expected four numbers"),
            ("w.txt", "0,0,10,ten\n", "w.txt: line 1: expected four numbers"),
            ("w.json", "[[0, 0, 10, 10], [0, 0, 1]]", "w.json: element 1: expected four"),
            ("w.json", '{"a": 1}', "w.json: expected a JSON array"),
            ("w.csv", "# nothing\n", "w.csv: no window in the file")):
        path = tmp_path / name
        path.write_text(text)
        result = subprocess.run(
            [sys.executable, "-m", "rnsca.cli", "batch", str(folder), str(tmp_path / "o"),
             "--windows", str(path), "--workers", "1"],
            capture_output=True, text=True, timeout=120)
        assert result.returncode == 2, result.stderr
        assert expected in result.stderr and "Traceback" not in result.stderr, result.stderr
    assert not (tmp_path / "o").exists()
    result = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "batch", str(folder), str(tmp_path / "o"),
         "--windows", str(path), "--window", "0,0,1,1"],
        capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "one of --window" in result.stderr
