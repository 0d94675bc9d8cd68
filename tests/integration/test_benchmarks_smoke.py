"""The benchmark harness runs end to end in quick mode and writes well-formed results.

No timing assertions: this only proves `make bench` will not crash and that the JSON
keeps the structure benchmarks/README.md documents.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LABELS = {
    "numba:rnsca:exact", "numba:rnsca:approx", "numba:cohen_sutherland", "numba:liang_barsky",
    "numba:nicholl_lee_nicholl", "numba:midpoint:exact", "numba:midpoint:approx",
    "shapely:clip_by_rect", "shapely:intersection", "floor:copy",
    "part:validate",
}
RUN_KEYS = {
    "workload", "family", "n", "label", "kind", "backend", "method", "mode", "n_param",
    "seconds", "seconds_median", "repeats", "number", "segments_per_s", "pieces_out",
    "measured", "note", "stats", "peak_extra_bytes", "peak_extra_ratio", "time_ratio",
    "pieces_match_reference",
}
TARGETS = {"throughput", "copy_floor", "vs_shapely", "vs_cohen_sutherland", "peak_memory",
           "second_process"}


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    proc = subprocess.run([sys.executable, "-m", "benchmarks.run", "--quick", "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out, json.loads((out / "latest.json").read_text()), proc.stdout


def test_quick_run_writes_json_plot_and_latest_copies(quick_run):
    out, result, _ = quick_run
    stamped = list(out.glob("segments-*.json"))
    assert len(stamped) == 1
    assert stamped[0].with_suffix(".png").stat().st_size > 0
    assert (out / "latest.png").stat().st_size > 0
    assert json.loads(stamped[0].read_text()) == result


def test_result_describes_the_machine_and_the_run(quick_run):
    _, result, _ = quick_run
    assert result["schema"] == "rnsca-bench-segments/1"
    assert result["quick"] is True
    machine = result["machine"]
    assert {"cpu_model", "cpu_count", "python", "numba_threads"} <= machine.keys()
    assert {"numba", "numpy", "shapely"} <= machine["versions"].keys()


def test_every_workload_times_every_contender_with_ratios_and_stats(quick_run):
    _, result, _ = quick_run
    families = {w["workload"]["family"] for w in result["workloads"]}
    assert families == {"uniform", "mostly_outside", "mostly_inside", "long_segments"}
    for w in result["workloads"]:
        assert {"inside", "rejected", "ambiguous"} == w["workload"]["level0"].keys()
        runs = {r["label"]: r for r in w["runs"]}
        assert LABELS <= runs.keys()
        for r in w["runs"]:
            assert RUN_KEYS <= r.keys()
            assert r["seconds"] > 0
            assert set(r["time_ratio"]) == {"shapely_clip_by_rect", "numba_cohen_sutherland",
                                            "copy_floor"}
            if r["kind"] in ("numba", "numpy"):
                assert r["stats"]["segments_in"] == r["n"]
                assert 0.0 <= r["stats"]["decided_shallow_fraction"] <= 1.0
                assert r["peak_extra_ratio"] is not None
        assert runs["numba:cohen_sutherland"]["time_ratio"]["numba_cohen_sutherland"] == 1.0
        numpy_ran = any(r["kind"] == "numpy" for r in w["runs"])
        assert numpy_ran or any(s["label"] == "numpy:*" for s in w["skipped"])


def test_n_sweep_compares_every_fixed_n_with_auto(quick_run):
    _, result, _ = quick_run
    assert len(result["n_sweep"]) == 2
    for sweep in result["n_sweep"]:
        assert set(sweep["summary"]) == {"exact", "approx"}
        assert {r["n_param"] for r in sweep["runs"]} == {"auto", 2, 3, 4, 8, 16, 32, 64}


def test_startup_and_targets_are_reported(quick_run):
    _, result, stdout = quick_run
    startup = result["startup"]
    assert startup["project_cache"]["first_result_seconds"] > 0
    assert startup["warm"]["first_result_seconds_median"] > 0
    targets = {t["key"]: t for t in result["targets"]}
    assert targets.keys() == TARGETS
    for t in targets.values():
        assert t["met"] in (True, False)
    assert "Issue targets" in stdout
