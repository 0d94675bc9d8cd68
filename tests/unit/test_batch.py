"""rnsca.batch without a cluster: inputs found, partitions planned, outputs written
atomically, the output folder prepared for a resumed run."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys

import pytest
import shapely

from tests.dask_data import WINDOW, frame, require_dask


@pytest.fixture
def batch():
    require_dask()
    import rnsca.batch

    return rnsca.batch


def test_import_rnsca_and_its_cli_import_no_dask():
    code = ("import sys, rnsca, rnsca.cli; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('dask', 'distributed', 'dask_geopandas', 'geopandas') or m in "
            "('rnsca.dask', 'rnsca.batch')))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=120, check=True)
    assert result.stdout.strip() == "[]"


def test_parquet_row_groups_are_joined_up_to_the_partition_size(batch, tmp_path, rng):
    frame(rng, 1_000).to_parquet(tmp_path / "a.parquet", row_group_size=300)
    partitions = batch.plan([tmp_path / "a.parquet"], rows_per_partition=500)
    assert [(p.start, p.stop, p.row_groups) for p in partitions] == [
        (0, 600, (0, 1)), (600, 1000, (2, 3))]
    assert [p.name for p in partitions] == ["000000-000000-a.parquet",
                                            "000000-000001-a.parquet"]


def test_names_sort_in_input_order_and_are_safe(batch, tmp_path, rng):
    for name in ("b c.parquet", "a.parquet"):
        frame(rng, 10).to_parquet(tmp_path / name)
    partitions = batch.plan(batch.find_inputs(str(tmp_path)))
    assert [p.name for p in partitions] == ["000000-000000-a.parquet",
                                            "000001-000000-b_c.parquet"]


@pytest.mark.parametrize("suffix,framing", [(".geojsonl", "lines"), (".geojsons", "rs")])
def test_text_sequences_are_cut_between_records(batch, tmp_path, suffix, framing):
    opener = b"\x1e" if framing == "rs" else b""
    records = [opener + b'{"type": "Point", "coordinates": [%d, 0]}\n' % i
               for i in range(500)]
    path = tmp_path / f"points{suffix}"
    path.write_bytes(b"".join(records))
    partitions = batch.plan([path], bytes_per_partition=1_000)
    assert len(partitions) > 5
    assert partitions[0].start == 0 and partitions[-1].stop == path.stat().st_size
    data = path.read_bytes()
    starts = {0}
    for record in records:
        starts.add(max(starts) + len(record))
    for before, after in itertools.pairwise(partitions):
        assert before.stop == after.start and after.start in starts
    rows = [batch._read_sequence(p) for p in partitions]
    xs = [x for part in rows for x in shapely.get_x(part.geometry).tolist()]
    assert xs == list(range(500)) and len(data) == partitions[-1].stop


def test_a_file_whose_layout_cannot_be_read_is_one_partition(batch, tmp_path):
    (tmp_path / "bad.parquet").write_bytes(b"PAR1 nothing else")
    (partition,) = batch.plan([tmp_path / "bad.parquet"])
    assert (partition.start, partition.stop) == (0, -1)
    job = batch.Job(output=str(tmp_path / "out"), window=WINDOW)
    os.makedirs(job.output)
    with pytest.raises(batch.PartitionError, match=r"bad\.parquet: cannot read"):
        batch.run_partition(partition, job)


def test_find_inputs_skips_hidden_names_and_refuses_other_kinds(batch, tmp_path, rng):
    frame(rng, 10).to_parquet(tmp_path / "a.parquet")
    (tmp_path / "_meta.parquet").write_bytes(b"")
    (tmp_path / ".tmp.parquet").write_bytes(b"")
    (tmp_path / "notes.txt").write_text("")
    assert batch.find_inputs(str(tmp_path)) == [tmp_path / "a.parquet"]
    assert batch.find_inputs(str(tmp_path / "*.parquet")) == [tmp_path / "a.parquet"]
    from rnsca.errors import InvalidOptionError

    with pytest.raises(InvalidOptionError, match="notes.txt: not an input"):
        batch.find_inputs(str(tmp_path / "*"))
    with pytest.raises(InvalidOptionError, match="no such file"):
        batch.find_inputs(str(tmp_path / "none*.fgb"))


def test_a_partition_failing_to_write_leaves_no_file(batch, tmp_path, rng, monkeypatch):
    import geopandas

    frame(rng, 100).to_parquet(tmp_path / "a.parquet")
    (partition,) = batch.plan([tmp_path / "a.parquet"])
    job = batch.Job(output=str(tmp_path / "out"), window=WINDOW)
    os.makedirs(job.output)

    def half_written(self, path, **kwargs):
        with open(path, "wb") as stream:
            stream.write(b"PAR1 half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(geopandas.GeoDataFrame, "to_parquet", half_written)
    with pytest.raises(batch.PartitionError, match="cannot write .*No space left"):
        batch.run_partition(partition, job)
    assert os.listdir(job.output) == []


def test_pending_removes_temporary_files_and_redoes_incomplete_ones(batch, tmp_path, rng):
    frame(rng, 900).to_parquet(tmp_path / "a.parquet", row_group_size=300)
    partitions = batch.plan([tmp_path / "a.parquet"], rows_per_partition=300)
    job = batch.Job(output=str(tmp_path / "out"), window=WINDOW)
    assert batch.pending(job, partitions) == partitions
    batch.run_partition(partitions[0], job)
    batch.run_partition(partitions[1], job)
    with open(job.target(partitions[1]), "r+b") as stream:
        stream.truncate(50)
    leftover = tmp_path / "out" / f".{partitions[2].name}.{'0' * 32}.tmp"
    leftover.write_bytes(b"half")
    assert batch.pending(job, partitions) == partitions[1:]
    assert not leftover.exists()


def test_a_row_clipped_to_nothing_is_dropped_unless_kept(batch, tmp_path):
    import geopandas

    rows = geopandas.GeoDataFrame(
        {"n": [1, 2, 3]}, geometry=[shapely.box(1, 1, 2, 2), shapely.box(500, 500, 501, 501),
                                    None], crs=3857)
    rows.to_parquet(tmp_path / "a.parquet")
    (partition,) = batch.plan([tmp_path / "a.parquet"])
    for keep_empty, expected in ((False, [1]), (True, [1, 2, 3])):
        job = batch.Job(output=str(tmp_path / f"out{keep_empty}"), window=WINDOW,
                        keep_empty=keep_empty)
        os.makedirs(job.output)
        report = batch.run_partition(partition, job)
        written = geopandas.read_parquet(job.target(partition))
        assert written["n"].tolist() == expected and report.rows_out == len(expected)
        if keep_empty:
            assert written.geometry.is_empty.tolist() == [False, True, False]
            assert written.geometry.isna().tolist() == [False, False, True]


def test_geoarrow_refuses_several_geometry_families_naming_wkb(batch, tmp_path):
    import geopandas

    geopandas.GeoDataFrame(geometry=[shapely.box(1, 1, 2, 2), shapely.Point(3, 3)]).to_parquet(
        tmp_path / "a.parquet")
    (partition,) = batch.plan([tmp_path / "a.parquet"])
    job = batch.Job(output=str(tmp_path / "out"), window=WINDOW,
                    encoding=batch.Encoding.GEOARROW)
    os.makedirs(job.output)
    with pytest.raises(batch.PartitionError, match="use --encoding wkb"):
        batch.run_partition(partition, job)


def test_encoding_names_its_choices(batch):
    from rnsca.errors import InvalidOptionError

    with pytest.raises(InvalidOptionError, match="wkb, geoarrow"):
        batch.Encoding("parquet")
    assert batch.Encoding("geoarrow") is batch.Encoding.GEOARROW


def test_windows_files_in_csv_and_json_give_the_same_windows(batch, tmp_path):
    (tmp_path / "w.csv").write_text("xmin, ymin, xmax, ymax\n\n0,0,10,10\n# skip\n-5,2.5,1e3,7\n")
    (tmp_path / "w.json").write_text("[[0, 0, 10, 10], [-5, 2.5, 1000, 7]]")
    expected = ((0.0, 0.0, 10.0, 10.0), (-5.0, 2.5, 1000.0, 7.0))
    assert batch.read_windows(tmp_path / "w.csv") == expected
    assert batch.read_windows(tmp_path / "w.json") == expected


def test_a_windows_file_is_refused_naming_the_file_and_row(batch, tmp_path):
    from rnsca.errors import InvalidOptionError, InvalidWindowError

    (tmp_path / "w.json").write_text("[[0, 0, 10, 10], [0, true, 1, 1]]")
    with pytest.raises(InvalidWindowError, match=r"w\.json: element 1: expected four"):
        batch.read_windows(tmp_path / "w.json")
    (tmp_path / "w.csv").write_text("0,0,10,10\n0,0,inf,1\n")
    with pytest.raises(InvalidWindowError, match=r"w\.csv: line 2: window .* finite"):
        batch.read_windows(tmp_path / "w.csv")
    with pytest.raises(InvalidOptionError, match=r"none\.csv: cannot read"):
        batch.read_windows(tmp_path / "none.csv")


def test_a_job_has_one_window_or_many_and_keeps_no_empty_rows_with_many(batch, tmp_path):
    from rnsca.errors import InvalidOptionError, InvalidWindowError

    with pytest.raises(InvalidWindowError, match="one of window and windows"):
        batch.Job(output=str(tmp_path), window=WINDOW, windows=(WINDOW,))
    with pytest.raises(InvalidOptionError, match="keep_empty"):
        batch.Job(output=str(tmp_path), window=None, windows=(WINDOW,), keep_empty=True)
