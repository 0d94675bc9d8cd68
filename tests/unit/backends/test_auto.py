"""``backend="auto"``: the measured choice, its cache, and no fallback for "opencl"."""

import json

import numpy as np
import pytest

import rnsca
from rnsca.backends import auto
from rnsca.options import Backend


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RNSCA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(auto, "_CACHE", {})
    return tmp_path


def test_auto_is_numba_where_opencl_is_missing(monkeypatch):
    monkeypatch.setattr(auto, "opencl_available", lambda: False)
    assert auto.choose("segments", 10**9) is Backend.NUMBA
    assert auto.backend_for("auto", "segments", 10**9).kind is Backend.NUMBA


def test_curves_stay_on_numba(opencl):
    assert auto.choose("paths", 10**9) is Backend.NUMBA
    assert auto.choose("flatten", 10**9) is Backend.NUMBA


def test_the_calibration_is_measured_once_and_cached_on_disk(opencl, fresh_cache,
                                                             monkeypatch):
    sizes = {"segments": (256, 1024), "lines": (1024,)}
    monkeypatch.setattr(auto, "CALIBRATED", sizes)
    crossover = auto.calibration()
    assert set(crossover) == {"segments", "lines"}
    files = list(fresh_cache.glob("auto-*.json"))
    assert len(files) == 1
    stored = json.loads(files[0].read_text())
    assert stored["crossover"] == crossover
    assert [row[0] for row in stored["seconds"]["segments"]] == [256, 1024]
    # A new process reads the file: nothing is measured again.
    monkeypatch.setattr(auto, "_CACHE", {})
    monkeypatch.setattr(auto, "calibrate", lambda *a: pytest.fail("measured again"))
    assert auto.calibration() == crossover


@pytest.mark.parametrize("rows, expected", [
    ([[10, 1.0, 2.0], [100, 1.0, 0.5], [1000, 1.0, 0.1]], 100),
    ([[10, 1.0, 0.5], [100, 1.0, 2.0], [1000, 1.0, 0.1]], 1000),  # won, lost, won
    ([[10, 1.0, 2.0], [100, 1.0, 2.0]], None),
    ([[10, 1.0, 0.5], [100, 1.0, 0.5]], 10)])
def test_the_crossover_is_where_opencl_wins_at_every_larger_size(opencl, monkeypatch, rows,
                                                                 expected):
    times = {(size, backend): seconds for size, numba_s, opencl_s in rows
             for backend, seconds in ((Backend.NUMBA, numba_s), (Backend.OPENCL, opencl_s))}
    monkeypatch.setattr(auto, "_calls", lambda operation, size, backend: (size, backend))
    monkeypatch.setattr(auto, "_best", lambda call: times[call])
    result = auto.calibrate({"segments": tuple(row[0] for row in rows)})
    assert result["crossover"]["segments"] == expected


def test_auto_picks_by_size_and_gives_the_same_result(opencl, monkeypatch):
    name = opencl.name
    monkeypatch.setattr(auto, "_CACHE", {name: {"crossover": {
        "segments": 1000, "windows": None, "lines": 10, "polygons": None}}})
    assert auto.choose("segments", 999) is Backend.NUMBA
    assert auto.choose("segments", 1000) is Backend.OPENCL
    assert auto.choose("windows", 10**9) is Backend.NUMBA
    segs = np.random.default_rng(0).uniform(0.0, 10.0, size=(1500, 4))
    result = rnsca.clip_segments(segs, (2.0, 2.0, 8.0, 8.0), backend="auto")
    assert result.backend is Backend.OPENCL
    expected = rnsca.clip_segments(segs, (2.0, 2.0, 8.0, 8.0))
    np.testing.assert_array_equal(result.segments, expected.segments)
    small = rnsca.clip_segments(segs[:10], (2.0, 2.0, 8.0, 8.0), backend="auto")
    assert small.backend is Backend.NUMBA
    coords = np.array([[0.0, 0.0], [10.0, 10.0], [10.0, 0.0]])
    lines = rnsca.clip_ragged("linestring", coords, (np.array([0, 3]),), (2, 2, 8, 8),
                              backend="auto")
    assert lines.stats.device is None  # 3 vertices: below the crossover of 10


def test_opencl_by_name_is_never_replaced(monkeypatch):
    from rnsca.backends import registry
    from rnsca.errors import BackendUnavailableError

    def missing():
        raise BackendUnavailableError("no OpenCL here")

    monkeypatch.setattr(registry, "_opencl_module", missing)
    monkeypatch.setattr(registry, "_BUILT", {})
    with pytest.raises(BackendUnavailableError, match="no OpenCL here"):
        rnsca.clip_segments([[0.0, 0.0, 1.0, 1.0]], (0, 0, 1, 1), backend="opencl")


def test_auto_runs_curves_on_numba(opencl):
    path = ["M -5 5 C 0 15 10 -5 15 5"]
    assert rnsca.clip_svg(path, (0, 0, 10, 10), backend="auto")[1].device is None
    assert rnsca.clip_svg(path, (0, 0, 10, 10), backend="opencl")[1].device is not None
