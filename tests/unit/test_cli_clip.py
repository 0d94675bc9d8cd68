"""``rnsca clip``: GeoJSON files and stdin/stdout through Typer's runner, and one real process."""

import json
import subprocess
import sys

import orjson
import pytest
from typer.testing import CliRunner

import rnsca
from rnsca.cli import app
from tests.cases import MIXED_DIMENSIONS, MIXED_DIMENSIONS_CLIPPED

WINDOW = ["--window", "0,0,10,10"]

LINE = {"type": "LineString", "coordinates": [[-5, 1], [5, 1], [5, 20], [8, 20], [8, 5], [15, 5]]}
FAR = {"type": "Point", "coordinates": [50, 50]}
HOLED = {"type": "Polygon", "coordinates": [
    [[-5, -5], [15, -5], [15, 5], [-5, 5], [-5, -5]], [[2, 1], [2, 3], [4, 3], [4, 1], [2, 1]]]}
DOCUMENT = {
    "type": "FeatureCollection", "name": "demo", "bbox": [-5, -5, 15, 50],
    "features": [
        {"type": "Feature", "id": 1, "properties": {"name": "line"}, "geometry": LINE},
        {"type": "Feature", "id": 2, "properties": {"name": "far"}, "geometry": FAR},
        {"type": "Feature", "id": 3, "properties": {"name": "holed"}, "geometry": HOLED,
         "source": "survey"},
    ],
}
CLIPPED_LINE = {"type": "MultiLineString", "coordinates": [
    [[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]}
CLIPPED = {
    "type": "FeatureCollection", "name": "demo", "bbox": [0.0, 0.0, 10.0, 10.0],
    "features": [
        {"type": "Feature", "id": 1, "properties": {"name": "line"}, "geometry": CLIPPED_LINE},
        {"type": "Feature", "id": 3, "properties": {"name": "holed"}, "source": "survey",
         "geometry": {"type": "Polygon", "coordinates": [
             [[10.0, 5.0], [0.0, 5.0], [0.0, 0.0], [10.0, 0.0], [10.0, 5.0]],
             [[2.0, 1.0], [2.0, 3.0], [4.0, 3.0], [4.0, 1.0], [2.0, 1.0]]]}},
    ],
}


@pytest.fixture
def runner():
    return CliRunner()


@pytest.fixture
def source(tmp_path):
    path = tmp_path / "demo.geojson"
    path.write_bytes(orjson.dumps(DOCUMENT))
    return path


def run(runner, *args, stdin=None):
    return runner.invoke(app, ["clip", *args], input=stdin)


def report_of(result):
    lines = result.stderr.strip().splitlines()
    return json.loads(lines[-1])


def assert_one_line_error(result, code, *fragments):
    assert result.exit_code == code, result.output
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for fragment in fragments:
        assert fragment in lines[0]
    assert "Traceback" not in result.output


# --- what it writes ------------------------------------------------------------------------

def test_clip_writes_the_clipped_document_to_stdout(runner, source):
    result = run(runner, str(source), *WINDOW)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout) == CLIPPED
    assert result.stdout.endswith("}\n")


def test_clip_matches_the_library(runner, source):
    result = run(runner, str(source), *WINDOW)
    expected, stats = rnsca.clip_geojson(DOCUMENT, (0, 0, 10, 10))
    assert json.loads(result.stdout) == json.loads(orjson.dumps(expected))
    assert report_of(result)["stats"] == stats.to_dict()


def test_clip_reports_the_stats_as_json_on_stderr(runner, source):
    result = run(runner, str(source), *WINDOW)
    stats = report_of(result)["stats"]
    assert (stats["geometries_in"], stats["geometries_out"]) == (3, 2)
    assert "verification" not in report_of(result)


@pytest.mark.parametrize("name", [None, "-"])
def test_clip_reads_stdin_when_input_is_dash_or_missing(runner, tmp_path, name):
    out = tmp_path / "out.geojson"
    args = ([] if name is None else [name]) + [*WINDOW, "-o", str(out)]
    result = run(runner, *args, stdin=json.dumps(DOCUMENT))
    assert result.exit_code == 0, result.output
    assert result.stdout == ""
    assert json.loads(out.read_text()) == CLIPPED


def test_clip_writes_stats_to_a_file_with_stats(runner, source, tmp_path):
    stats = tmp_path / "stats.json"
    result = run(runner, str(source), *WINDOW, "--stats", str(stats), "--verify")
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    report = json.loads(stats.read_text())
    assert report["stats"]["geometries_in"] == 3
    assert report["verification"]["passed"] is True


def test_clip_verify_reports_the_comparison_with_shapely(runner, source):
    result = run(runner, str(source), *WINDOW, "--verify")
    assert result.exit_code == 0, result.output
    assert report_of(result)["verification"] == {
        "max_deviation": 0.0, "false_positives": 0, "ratio": 1.0, "passed": True,
        "allowed_deviation": 1e-8, "mode": "exact", "valid": True, "invalid_inputs": 0,
        "inputs": 3, "checked": 3, "sampling": "all", "skipped": 0, "timed_out": False,
        "note": ""}


def test_clip_writes_each_position_of_a_mixed_2d_3d_document_in_its_dimension(
        runner, tmp_path):
    path = tmp_path / "mixed.geojson"
    path.write_bytes(orjson.dumps(MIXED_DIMENSIONS))
    result = run(runner, str(path), *WINDOW, "--verify")
    assert result.exit_code == 0, result.output
    assert [f["geometry"] for f in json.loads(result.stdout)["features"]] == \
        MIXED_DIMENSIONS_CLIPPED
    assert report_of(result)["verification"]["passed"] is True


def test_clip_keep_empty_keeps_features_left_empty(runner, source):
    result = run(runner, str(source), *WINDOW, "--keep-empty", "--verify")
    assert result.exit_code == 0, result.output
    features = json.loads(result.stdout)["features"]
    assert [f["id"] for f in features] == [1, 2, 3]
    assert features[1]["geometry"] == {"type": "Point", "coordinates": []}
    assert report_of(result)["verification"]["passed"] is True


def test_clip_boundary_interior_drops_lines_along_the_edge(runner):
    edge = {"type": "LineString", "coordinates": [[-1, 0], [11, 0]]}
    closed = run(runner, *WINDOW, stdin=json.dumps(edge))
    assert json.loads(closed.stdout)["coordinates"] == [[0.0, 0.0], [10.0, 0.0]]
    interior = run(runner, *WINDOW, "--boundary", "interior", "--verify",
                   stdin=json.dumps(edge))
    assert interior.exit_code == 0, interior.output
    assert json.loads(interior.stdout) == {"type": "LineString", "coordinates": []}
    assert report_of(interior)["verification"]["passed"] is True


def test_clip_takes_negative_bounds(runner):
    line = {"type": "LineString", "coordinates": [[-30, 0], [30, 0]]}
    for window in (["--window", "-10,-10,10,10"], ["--window=-10,-10,10,10"]):
        result = run(runner, *window, stdin=json.dumps(line))
        assert result.exit_code == 0, result.output
        assert json.loads(result.stdout)["coordinates"] == [[-10.0, 0.0], [10.0, 0.0]]


def test_clip_passes_the_clipping_options_on(runner):
    line = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
    result = run(runner, *WINDOW, "--mode", "approx", "--n", "4", "--max-depth", "3",
                 "--tolerance", "0.5", "--verify", "--approx-bound", "1.0",
                 stdin=json.dumps(line))
    assert result.exit_code == 0, result.output
    report = report_of(result)
    assert report["stats"]["dropped"] > 0
    assert report["verification"]["mode"] == "approx"
    assert report["verification"]["passed"] is True
    ((x0, _), (x1, _)) = json.loads(result.stdout)["coordinates"]
    assert 0.0 <= x0 <= 1.0 and 9.0 <= x1 <= 10.0


def test_clip_check_validity_counts_invalid_input_polygons(runner):
    bowtie = {"type": "Polygon", "coordinates": [[[0, 0], [10, 10], [10, 0], [0, 10], [0, 0]]]}
    result = run(runner, "--window", "1,1,9,9", "--check-validity", "--verify",
                 stdin=json.dumps(bowtie))
    assert result.exit_code == 0, result.output
    report = report_of(result)
    assert report["stats"]["invalid_polygons"] == 1
    # No oracle for an invalid input: verify reports it and does not fail on it.
    assert report["verification"]["invalid_inputs"] == 1
    assert report["verification"]["passed"] is True


def test_clip_keeps_z_and_indents_on_request(runner):
    line = {"type": "LineString", "coordinates": [[-5, 5, 0], [15, 5, 20]]}
    result = run(runner, *WINDOW, "--indent", stdin=json.dumps(line))
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith('{\n  "type": "LineString",')
    assert json.loads(result.stdout)["coordinates"] == [[0.0, 5.0, 5.0], [10.0, 5.0, 15.0]]


def test_clip_accepts_a_byte_order_mark_and_a_json_suffix(runner, tmp_path):
    path = tmp_path / "line.JSON"
    path.write_bytes(b"\xef\xbb\xbf \n" + orjson.dumps(LINE))
    result = run(runner, str(path), *WINDOW)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout) == CLIPPED_LINE


@pytest.mark.parametrize("flag", ["--progress", "--no-progress"])
def test_clip_output_is_the_same_with_or_without_a_progress_bar(runner, source, flag):
    result = run(runner, str(source), *WINDOW, flag)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout) == CLIPPED
    assert report_of(result)["stats"]["geometries_out"] == 2


def test_clip_shows_no_progress_bar_when_stderr_is_not_a_terminal(runner, source,
                                                                monkeypatch):
    monkeypatch.setattr("rnsca.cli.PROGRESS_MIN_BYTES", 1)
    result = run(runner, str(source), *WINDOW)
    assert result.exit_code == 0, result.output
    assert result.stderr.strip().startswith('{"stats"')


# --- errors ----------------------------------------------------------------------------------

def test_clip_refuses_input_that_is_not_geojson_by_name(runner, tmp_path):
    path = tmp_path / "drawing.wkt"
    path.write_text("LINESTRING (0 0, 1 1)")
    result = run(runner, str(path), *WINDOW)
    assert_one_line_error(result, 2, "only GeoJSON or SVG input is accepted", ".wkt")


def test_clip_refuses_input_that_is_not_geojson_by_content(runner):
    result = run(runner, *WINDOW, stdin="LINESTRING (0 0, 1 1)")
    assert_one_line_error(result, 2, "only GeoJSON or SVG input is accepted", "<stdin>",
                          "LINESTRING")


@pytest.mark.parametrize("window, message", [
    ("0,0,10", "four comma-separated numbers"),
    ("0,0,ten,10", "four comma-separated numbers"),
    ("0,0,0,10", "window needs xmin < xmax"),
    ("0,nan,10,10", "must be finite"),
])
def test_clip_reports_a_bad_window_and_exits_2(runner, source, window, message):
    assert_one_line_error(run(runner, str(source), "--window", window), 2, message)


@pytest.mark.parametrize("options, message", [
    (["--method", "bogus"], "method must be one of"),
    (["--n", "1"], "n must be in 2..64"),
    (["--max-depth", "99"], "max_depth must be in 0..32"),
    (["--tolerance", "-1"], "tolerance must be > 0"),
    (["--mode", "fast"], "mode must be one of"),
    (["--boundary", "side"], "boundary must be one of"),
    (["--backend", "numpy"], "backend must be one of 'numba', 'opencl'"),
    (["--mode", "approx", "--verify"], "--approx-bound"),
])
def test_clip_reports_a_bad_option_before_reading_and_exits_2(runner, options, message):
    # No input is given: the option is refused before stdin is read.
    assert_one_line_error(run(runner, *WINDOW, *options), 2, message)


def test_clip_reports_approx_mode_on_polygons_and_exits_2(runner, source):
    result = run(runner, str(source), *WINDOW, "--mode", "approx")
    assert_one_line_error(result, 2, "mode='approx' cannot clip polygons")


def test_clip_reports_a_missing_file_and_exits_2(runner, tmp_path):
    result = run(runner, str(tmp_path / "missing.geojson"), *WINDOW)
    assert_one_line_error(result, 2, "missing.geojson: no such file")


def test_clip_reports_text_that_is_not_json_and_exits_1(runner):
    result = run(runner, *WINDOW, stdin='{"type": "LineString",')
    assert_one_line_error(result, 1, "not valid JSON")


def test_clip_reports_invalid_geojson_with_its_path_and_exits_1(runner, tmp_path):
    bad = json.loads(json.dumps(DOCUMENT))
    bad["features"][2]["geometry"]["coordinates"][1][3] = [4, "one"]
    path = tmp_path / "bad.geojson"
    path.write_text(json.dumps(bad))
    result = run(runner, str(path), *WINDOW, "-o", str(tmp_path / "out.geojson"))
    assert_one_line_error(result, 1, "features[2].geometry.coordinates[1][3][1]")
    assert not (tmp_path / "out.geojson").exists()


def test_clip_reports_an_unclosed_ring_and_exits_1(runner):
    ring = {"type": "Polygon", "coordinates": [[[0, 0], [4, 0], [4, 4], [0, 1]]]}
    assert_one_line_error(run(runner, *WINDOW, stdin=json.dumps(ring)), 1, "not closed")


def test_clip_reports_empty_input_and_exits_1(runner):
    assert_one_line_error(run(runner, *WINDOW, stdin=" \n"), 1, "<stdin> is empty")


def test_clip_reports_an_unwritable_output_and_exits_1(runner, source, tmp_path):
    result = run(runner, str(source), *WINDOW, "-o", str(tmp_path / "no" / "out.geojson"))
    assert_one_line_error(result, 1, "No such file or directory", "out.geojson")


def test_clip_exits_1_when_verification_fails(runner, source, monkeypatch):
    clip_geojson = rnsca.clip_geojson

    def overshooting(document, window, **options):
        result = clip_geojson(document, window, **options)
        # The arrays verification reads; the CLI's document (arrays=True) holds views.
        result.outputs["lines"].coords[0, :2] = [-1.0, 1.0]
        return result

    monkeypatch.setattr(rnsca, "clip_geojson", overshooting)
    result = run(runner, str(source), *WINDOW, "--verify")
    assert result.exit_code == 1
    assert json.loads(result.stdout)["features"][0]["geometry"]["coordinates"][0][0] == [
        -1.0, 1.0]
    *_, report_line, error_line = result.stderr.strip().splitlines()
    verification = json.loads(report_line)["verification"]
    assert verification["passed"] is False and verification["false_positives"] == 1
    assert error_line.startswith("error: verification failed: max_deviation=1.0")


def test_no_arguments_lists_the_clip_command(runner):
    assert "clip" in runner.invoke(app, []).output


# --- a real process --------------------------------------------------------------------------
# End to end through a new interpreter (seconds each, mostly importing and loading the
# kernels): slow, so `make check` leaves them to `make test`.

@pytest.mark.slow
def test_clip_as_a_process_pipes_stdin_to_stdout():
    done = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "clip", "--window", "0,0,10,10"],
        input=orjson.dumps(DOCUMENT), capture_output=True, timeout=300)
    assert done.returncode == 0, done.stderr.decode()
    assert json.loads(done.stdout) == CLIPPED
    assert json.loads(done.stderr)["stats"]["geometries_out"] == 2


@pytest.mark.slow
def test_clip_as_a_process_fails_in_one_line_without_a_traceback():
    done = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "clip", "--window", "0,0,10,10"],
        input=b'{"type": "Point", "coordinates": [1, NaN]}', capture_output=True,
        timeout=300)
    assert done.returncode == 1 and done.stdout == b""
    assert done.stderr.decode().count("\n") == 1
    assert done.stderr.startswith(b"error: GeoJSON text is not valid JSON")


# --- GeoJSON text sequences ------------------------------------------------------------------

def _sequence(records, rs: bool) -> bytes:
    return b"".join((b"\x1e" if rs else b"") + orjson.dumps(r) + b"\n" for r in records)


@pytest.mark.parametrize("name, rs", [("roads.geojsons", True), ("roads.geojsonl", False),
                                      ("roads.ndjson", False)])
def test_clip_streams_a_sequence_file_in_its_framing(runner, tmp_path, name, rs):
    path = tmp_path / name
    path.write_bytes(_sequence(DOCUMENT["features"] + [LINE], rs))
    result = run(runner, str(path), *WINDOW)
    assert result.exit_code == 0, result.output
    out = result.stdout_bytes
    assert out.startswith(b"\x1e") == rs and out.count(b"\n") == 3
    texts = out.split(b"\x1e")[1:] if rs else out.splitlines()
    assert [orjson.loads(t) for t in texts] == CLIPPED["features"] + [CLIPPED_LINE]
    report = report_of(result)
    assert (report["records_in"], report["records_out"], report["chunks"]) == (4, 3, 1)
    assert report["stats"]["geometries_in"] == 4


def test_clip_streams_stdin_that_starts_with_rs_or_is_named_by_seq(runner):
    rs = run(runner, *WINDOW, stdin=_sequence([LINE, FAR], True))
    assert rs.exit_code == 0 and rs.stdout_bytes == b"\x1e" + orjson.dumps(CLIPPED_LINE) + b"\n"
    lines = run(runner, "--seq", "lines", *WINDOW, stdin=_sequence([LINE, FAR], False))
    assert lines.exit_code == 0 and lines.stdout_bytes == orjson.dumps(CLIPPED_LINE) + b"\n"


def test_clip_writes_a_sequences_records_before_a_bad_one_then_exits_1(runner):
    stdin = _sequence([LINE, LINE], False) + b'{"type": "Point", "coordinates": [1]}\n'
    result = run(runner, "--seq", "lines", *WINDOW, stdin=stdin)
    assert result.exit_code == 1
    assert result.stdout_bytes == 2 * (orjson.dumps(CLIPPED_LINE) + b"\n")
    assert result.stderr.startswith("error: record 2: invalid GeoJSON at coordinates")


def test_clip_refuses_document_options_and_unknown_framings_for_sequences(runner, tmp_path):
    path = tmp_path / "a.geojsons"
    path.write_bytes(_sequence([LINE], True))
    assert_one_line_error(run(runner, str(path), *WINDOW, "--verify"), 2,
                          "--verify does not apply to GeoJSON text sequences")
    assert_one_line_error(run(runner, str(path), *WINDOW, "--seq", "csv"), 2,
                          "unknown framing 'csv'")
