"""The ``rnsca`` command line, driven through Typer's test runner on temporary .npy files."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from rnsca.backends.registry import available_backends
from rnsca.cli import app

SEGS = np.array([[-5.0, 5.0, 15.0, 5.0], [20.0, 20.0, 30.0, 30.0], [1.0, 1.0, 2.0, 3.0]])
WINDOW = ["--window", "0", "0", "10", "10"]


@pytest.fixture
def runner():
    return CliRunner()


@pytest.fixture
def source(tmp_path):
    path = tmp_path / "segments.npy"
    np.save(path, SEGS)
    return path


def run_segments(runner, source, output, *options):
    return runner.invoke(app, ["segments", str(source), str(output), *WINDOW, *options])


def test_segments_writes_pieces_source_and_t(runner, source, tmp_path):
    out = tmp_path / "clipped.npz"
    result = run_segments(runner, source, out)
    assert result.exit_code == 0, result.output
    with np.load(out) as data:
        np.testing.assert_array_equal(data["segments"], [[0.0, 5.0, 10.0, 5.0],
                                                         [1.0, 1.0, 2.0, 3.0]])
        np.testing.assert_array_equal(data["source"], [0, 2])
        np.testing.assert_array_equal(data["t"], [[0.25, 0.75], [0.0, 1.0]])


def test_segments_prints_stats_and_what_ran_as_json(runner, source, tmp_path):
    result = run_segments(runner, source, tmp_path / "o.npz", "--method", "liang_barsky",
                          "--mode", "approx")
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert (report["method"], report["mode"], report["backend"]) == (
        "liang_barsky", "approx", "numba")
    assert report["stats"]["segments_in"] == 3 and report["stats"]["pieces_out"] == 2
    assert "verification" not in report


def test_segments_with_verify_reports_the_comparison_with_shapely(runner, source, tmp_path):
    result = run_segments(runner, source, tmp_path / "o.npz", "--verify")
    assert result.exit_code == 0, result.output
    verification = json.loads(result.stdout)["verification"]
    assert verification["passed"] is True and verification["max_deviation"] == 0.0


@pytest.mark.parametrize("n", ["3", "auto"])
def test_segments_accepts_n_as_a_number_or_auto(runner, source, tmp_path, n):
    result = run_segments(runner, source, tmp_path / "o.npz", "--n", n, "--max-depth", "4",
                          "--tolerance", "0.5", "--mode", "approx")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["stats"]["subdivided"] > 0


def test_segments_runs_on_each_backend(runner, source, tmp_path, backend):
    result = run_segments(runner, source, tmp_path / "o.npz", "--backend", backend.value)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["backend"] == backend.value


@pytest.mark.parametrize("options, message", [
    (["--method", "bogus"], "method must be one of"),
    (["--mode", "fast"], "mode must be one of"),
    (["--n", "1"], "n must be in 2..64"),
    (["--n", "-3"], "n must be an integer"),
    (["--max-depth", "99"], "max_depth must be in 0..32"),
    (["--tolerance", "-1"], "tolerance must be > 0"),
    (["--backend", "abacus"], "backend must be one of"),
])
def test_segments_reports_a_bad_option_and_exits_2(runner, source, tmp_path, options, message):
    result = run_segments(runner, source, tmp_path / "o.npz", *options)
    assert result.exit_code == 2
    assert "error:" in result.stderr and message in result.stderr


def test_segments_reports_an_invalid_window_and_exits_2(runner, source, tmp_path):
    result = runner.invoke(app, ["segments", str(source), str(tmp_path / "o.npz"),
                                 "--window", "0", "0", "0", "10"])
    assert result.exit_code == 2 and "xmin < xmax" in result.stderr


def test_segments_reports_a_non_finite_row_and_exits_2(runner, tmp_path):
    path = tmp_path / "nan.npy"
    bad = SEGS.copy()
    bad[1, 3] = np.nan
    np.save(path, bad)
    result = run_segments(runner, path, tmp_path / "o.npz")
    assert result.exit_code == 2 and "segment 1 has a non-finite coordinate" in result.stderr
    assert not (tmp_path / "o.npz").exists()


def test_segments_reports_a_wrong_shape_and_exits_2(runner, tmp_path):
    path = tmp_path / "wide.npy"
    np.save(path, np.zeros((3, 5)))
    result = run_segments(runner, path, tmp_path / "o.npz")
    assert result.exit_code == 2 and "shape (n, 4) or (n, 2, 2)" in result.stderr


def test_segments_reports_a_missing_file_and_exits_2(runner, tmp_path):
    result = run_segments(runner, tmp_path / "missing.npy", tmp_path / "o.npz")
    assert result.exit_code == 2 and "No such file" in result.stderr


def test_segments_refuses_a_pickled_file(runner, tmp_path):
    path = tmp_path / "objects.npy"
    np.save(path, np.array([[1, 2, 3, None]], dtype=object), allow_pickle=True)
    result = run_segments(runner, path, tmp_path / "o.npz")
    assert result.exit_code == 2 and "error:" in result.stderr


def test_segments_clips_an_empty_file_to_an_empty_result(runner, tmp_path):
    path = tmp_path / "empty.npy"
    np.save(path, np.empty((0, 4)))
    out = tmp_path / "o.npz"
    result = run_segments(runner, path, out, "--verify")
    assert result.exit_code == 0, result.output
    with np.load(out) as data:
        assert data["segments"].shape == (0, 4) and data["source"].shape == (0,)
    assert json.loads(result.stdout)["verification"]["passed"] is True


def test_backends_lists_each_available_backend(runner):
    result = runner.invoke(app, ["backends"])
    assert result.exit_code == 0
    lines = [line for line in result.stdout.splitlines() if not line.startswith(" ")]
    assert [line.split(":")[0] for line in lines] == [b.value for b in available_backends()]
    # With what each runs: its capabilities.
    assert lines[0] == ("numba: segments, windows, lines, polygons, paths, flatten, tiles "
                        "(float64)")


@pytest.mark.opencl
def test_backends_lists_the_opencl_devices_and_marks_the_selected_one(runner, opencl):
    result = runner.invoke(app, ["backends"])
    assert result.exit_code == 0, result.output
    devices = [line for line in result.stdout.splitlines() if line.startswith(" ")]
    selected = [line for line in devices if line.startswith(" *")]
    assert len(selected) == 1
    assert selected[0].startswith(f" *{opencl.device['id']} {opencl.name} (")
    assert selected[0].endswith(f", {opencl.precision.value})")


@pytest.mark.opencl
def test_an_opencl_device_matching_nothing_is_explained(runner, opencl):
    try:
        result = runner.invoke(app, ["--opencl-device", "no such device", "backends"])
        assert result.exit_code == 0
        assert not any(line.startswith("opencl") for line in result.stdout.splitlines())
        assert "opencl is not available: no OpenCL device matches 'no such device'" in \
            result.stderr
    finally:
        runner.invoke(app, ["backends"])  # back to the default device


def test_an_unknown_opencl_precision_is_a_usage_error(runner):
    result = runner.invoke(app, ["--opencl-precision", "float16", "backends"])
    assert result.exit_code == 2
    assert "precision must be one of 'auto', 'float64', 'float32'" in result.stderr


def test_warm_up_compiles_the_kernels(runner):
    result = runner.invoke(app, ["warm-up"])
    assert result.exit_code == 0, result.output
    assert result.stdout.strip() == "kernels ready"


def test_no_arguments_prints_help(runner):
    result = runner.invoke(app, [])
    assert "segments" in result.output and "backends" in result.output
