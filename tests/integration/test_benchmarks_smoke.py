"""The benchmark harness runs end to end in quick mode and writes well-formed results.

No timing assertions: this only proves `make bench` will not crash and that the JSON of
every suite (segments, geometry, svg) keeps the structure benchmarks/README.md documents.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rnsca import Backend
from rnsca.backends.registry import available_backends
from tests.missing import missing

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
           "second_process", "issue15_throughput", "issue15_vs_shapely", "issue15_copy_floor",
           "issue15_approx", "issue15_peak_memory"}
GEOMETRY_LABELS = {
    "rnsca:clip_ragged", "rnsca:clip_ragged:interior", "shapely:clip_by_rect",
    "shapely:intersection", "objects:shapely:clip_by_rect", "objects:shapely:intersection",
    "objects:rnsca:clip",
}
SEGMENT_LABELS = {"segments:cohen_sutherland", "segments:rnsca"}
# OpenCL contenders run where OpenCL does (the benchmarks record the reason otherwise).
OPENCL_LABELS = ({"opencl:clip_ragged", "opencl:segments:rnsca"}
                 if Backend.OPENCL in available_backends() else set())
GEOMETRY_RUN_KEYS = {"label", "kind", "seconds", "seconds_median", "repeats", "number",
                     "coords_per_s", "stats", "time_ratio", "output"}
OUTPUT_KEYS = {"geometries", "coords", "invalid", "reference", "measure", "reference_measure",
               "relative_difference", "max_abs_difference_per_source", "sources_differing"}
GEOMETRY_TARGETS = {"curves_25_vs_shapely", "curves_10_vs_shapely", "curves_1_vs_shapely",
                    "curves_10_vs_cohen_sutherland", "curves_1_vs_cohen_sutherland",
                    "polygons_vs_shapely", "polygons_valid", "geojson_clip_share",
                    "geojson_clip_share_arrays"}


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    proc = subprocess.run([sys.executable, "-m", "benchmarks.run", "--quick", "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
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
            if r["kind"] == "numba":
                assert r["stats"]["segments_in"] == r["n"]
                assert 0.0 <= r["stats"]["decided_shallow_fraction"] <= 1.0
                assert r["peak_extra_ratio"] is not None
        assert runs["numba:cohen_sutherland"]["time_ratio"]["numba_cohen_sutherland"] == 1.0


def test_n_sweep_compares_every_fixed_n_with_auto(quick_run):
    _, result, _ = quick_run
    assert len(result["n_sweep"]) == 4  # the four families
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


def test_geometry_suite_writes_its_json_and_latest_copy(quick_run):
    out, _, stdout = quick_run
    stamped = list(out.glob("geometry-*.json"))
    assert len(stamped) == 1
    result = json.loads((out / "latest-geometry.json").read_text())
    assert json.loads(stamped[0].read_text()) == result
    assert result["schema"] == "rnsca-bench-geometry/1"
    assert result["quick"] is True
    assert {"cpu_model", "cpu_count", "python", "numba_threads"} <= result["machine"].keys()
    assert "Issue 3 targets" in stdout


@pytest.fixture(scope="module")
def geometry(quick_run):
    out, _, _ = quick_run
    return json.loads((out / "latest-geometry.json").read_text())


def test_curves_run_at_three_centred_windows_with_every_contender(geometry):
    names = [w["workload"]["name"] for w in geometry["curves"]]
    assert names == ["curves-25%", "curves-10%", "curves-1%"]
    assert geometry["curves"][0]["workload"]["window"] == [250.0, 250.0, 750.0, 750.0]
    assert geometry["curves"][2]["workload"]["window"] == [450.0, 450.0, 550.0, 550.0]
    for w in geometry["curves"]:
        info = w["workload"]
        assert info["geometries"] == 6
        assert 2000 <= info["vertices_per_line"][0] <= info["vertices_per_line"][1] <= 5000
        assert info["segments"] == info["coords"] - info["geometries"]
        runs = {r["label"]: r for r in w["runs"]}
        assert runs.keys() == GEOMETRY_LABELS | SEGMENT_LABELS | OPENCL_LABELS
        assert runs["segments:cohen_sutherland"]["time_ratio"]["segments_cohen_sutherland"] == 1
        for label in OPENCL_LABELS:
            assert {"call_seconds", "kernel_seconds", "transfer_seconds",
                    "host_seconds"} <= runs[label]["device"].keys()


def test_polygon_run_checks_validity_of_every_output(geometry):
    info = geometry["polygons"]["workload"]
    assert (info["geometries"], info["rings"], info["coords"]) == (2000, 4000, 2000 * 52)
    assert info["input_invalid"] == 0
    runs = {r["label"]: r for r in geometry["polygons"]["runs"]}
    assert runs.keys() == GEOMETRY_LABELS | (OPENCL_LABELS & {"opencl:clip_ragged"})
    for r in runs.values():
        assert isinstance(r["output"]["invalid"], int)


def test_every_geometry_run_is_timed_compared_and_agrees_with_shapely(geometry):
    for w in [*geometry["curves"], geometry["polygons"]]:
        for r in w["runs"]:
            assert GEOMETRY_RUN_KEYS <= r.keys()
            assert OUTPUT_KEYS <= r["output"].keys()
            assert r["seconds"] > 0
            assert r["time_ratio"]["shapely_clip_by_rect"] > 0
            # Random data never touches the window's edge: every method gives Shapely's
            # length or area, per source geometry.
            assert r["output"]["relative_difference"] < 1e-9
            assert r["output"]["sources_differing"] == 0
            if r["label"].startswith("rnsca:"):
                assert r["stats"]["geometries_in"] == w["workload"]["geometries"]
                assert sum(r["stats"]["runs_decided_per_level"]) > 0


def test_geojson_pipelines_report_parse_clip_and_serialize_separately(geometry):
    g = geometry["geojson"]
    assert g["workload"]["features_in"] > 0
    assert set(g["workload"]["geometry_kinds_in"]) == {"LineString", "MultiLineString",
                                                       "Polygon", "MultiPolygon"}
    assert set(g["pipelines"]) == {"lists", "arrays"}
    for p in g["pipelines"].values():
        assert set(p["stages"]) == {"parse", "clip", "serialize"}
        for stage in p["stages"].values():
            assert stage["seconds"] > 0
        assert p["clip_over_parse_and_serialize"] == (
            p["stages"]["clip"]["seconds"]
            / (p["stages"]["parse"]["seconds"] + p["stages"]["serialize"]["seconds"]))
        assert set(p["clip_steps"]) == {"read", "clip_ragged", "clip_ragged_lines",
                                        "clip_ragged_polygons", "write"}
        assert 0 < p["features_out"] < g["workload"]["features_in"]
        assert p["stats"]["geometries_in"] == g["workload"]["features_in"]
    assert g["pipelines"]["lists"]["bytes_out"] == g["pipelines"]["arrays"]["bytes_out"]


def test_geometry_targets_are_all_evaluated(geometry):
    targets = {t["key"]: t for t in geometry["targets"]}
    assert targets.keys() == GEOMETRY_TARGETS
    for t in targets.values():
        assert t["met"] in (True, False)


def test_svg_suite_times_parse_and_write_and_checks_the_round_trip(quick_run):
    out, _, stdout = quick_run
    stamped = list(out.glob("svg-*.json"))
    assert len(stamped) == 1
    result = json.loads((out / "latest-svg.json").read_text())
    assert json.loads(stamped[0].read_text()) == result
    assert result["schema"] == "rnsca-bench-svg/1"
    assert result["quick"] is True
    info = result["svg"]["workload"]
    assert info["paths"] == 500 and info["bytes"] > 100_000
    assert info["segments"] == sum(info["segments_by_degree"].values()) > 0
    runs = {r["label"]: r for r in result["svg"]["runs"]}
    assert runs.keys() == {"parse:parse_paths", "parse:parse_paths:1thread",
                           "write:precision=6", "write:precision=None"}
    for r in runs.values():
        assert r["seconds"] > 0 and r["mb_per_s"] > 0
    assert runs["write:precision=None"]["reads_back"] is True
    assert runs["write:precision=6"]["reads_back"] is True
    targets = {(t["key"], t.get("workload")): t for t in result["targets"]}
    assert ("parse_throughput", info["name"]) in targets
    assert all(t["met"] in (True, False) for t in targets.values())
    assert "Issue 4 targets" in stdout


def test_svg_suite_times_curve_clipping_against_flatten_then_clip(quick_run):
    out, _, stdout = quick_run
    result = json.loads((out / "latest-svg.json").read_text())
    workloads = {w["workload"]["name"]: w for w in result["curves"]}
    assert len(workloads) == 4 and any(name.startswith("glyphs-") for name in workloads)
    for w in workloads.values():
        labels = {r["label"] for r in w["runs"]}
        assert {"rnsca:preserve", "rnsca:approx", "rnsca:flatten",
                "flatten+rnsca:clip_ragged", "flatten+shapely:intersection"} <= labels
        assert all(r["seconds"] > 0 for r in w["runs"])
        assert w["workload"]["segments"] > 0 and w["workload"]["tolerance"] > 0
    keys = {t["key"] for t in result["targets"]}
    assert {"preserve_vs_flatten+rnsca:clip_ragged",
            "preserve_vs_flatten+shapely:intersection"} <= keys
    assert "Issue 4 curve targets" in stdout


def test_thread_scaling_runs_one_process_per_thread_count(tmp_path):
    subprocess.run([sys.executable, "-m", "benchmarks.threads", "--n", "30000", "--threads",
                    "1,2", "--repeats", "1", "--out", str(tmp_path)],
                   cwd=ROOT, check=True, capture_output=True, timeout=600)
    (path,) = tmp_path.glob("threads-*.json")
    rows = json.loads(path.read_text())["rows"]
    assert [r["threads"] for r in rows] == [1, 2]
    for row in rows:
        assert row["n"] == 30000 and row["segments_per_s"] > 0
        assert all(row[k] > 0 for k in ("call_seconds", "clip_fresh_seconds", "move_seconds",
                                         "check_seconds", "read_seconds", "copy_seconds"))
    assert rows[0]["speedup_over_1"] == 1.0


def test_load_suite_runs_wrk_against_a_real_server(tmp_path):
    """`python -m benchmarks.load --quick`: every case answered, figures parsed from wrk."""
    if shutil.which("wrk") is None:
        missing("wrk is not installed (apt-get install wrk; .ci/run does)")
    subprocess.run([sys.executable, "-m", "benchmarks.load", "--quick", "--out", str(tmp_path)],
                   cwd=ROOT, check=True, capture_output=True, timeout=600)
    (path,) = tmp_path.glob("load-*.json")
    result = json.loads(path.read_text())
    busy = result["cases"].pop("healthz_while_busy")
    assert busy["probes"] > 0 and busy["busy_statuses"] == {"200": 4}
    assert set(busy["latency_s"]) == {"p50", "p99", "max"}
    assert set(result["cases"]) == {"healthz", "geojson_verified", "geojson", "svg",
                                    "segments_binary"}
    for figures in result["cases"].values():
        assert figures["requests"] > 0 and figures["requests_per_s"] > 0
        assert figures["non_2xx"] == 0 and figures["socket_errors"] == 0
        assert set(figures["latency_s"]) == {"p50", "p75", "p90", "p99"}
    assert {t["key"] for t in result["targets"]} == {
        "rate_unverified", "rate_verified", "p99_unverified", "p99_verified"}


def test_memory_suite_measures_every_kind_against_the_admission_table(tmp_path):
    """`python -m benchmarks.memory`: one fresh process per kind, the table's coverage."""
    subprocess.run([sys.executable, "-m", "benchmarks.memory", "--vertices", "20000",
                    "--out", str(tmp_path)], cwd=ROOT, check=True, capture_output=True,
                   timeout=600)
    (path,) = tmp_path.glob("memory-*.json")
    result = json.loads(path.read_text())
    assert [r["kind"] for r in result["rows"]] == [
        "geojson_lines", "geojson_polygons", "svg", "segments_json", "segments_binary",
        "geoarrow_lines", "geoarrow_polygons", "geoarrow_wkb"]
    for row in result["rows"]:
        assert row["body_bytes"] > 0 and row["peak_growth_bytes"] >= 0 and row["seconds"] > 0
    assert set(result["admission_table"]) == {"geojson/json", "svg/json", "segments/json",
                                              "segments/binary", "geoarrow/arrow"}


def test_soak_runs_minutes_of_mixed_load_and_judges_growth(tmp_path):
    """`python -m benchmarks.soak` with 2-second "minutes": figures per minute, a verdict."""
    proc = subprocess.run([sys.executable, "-m", "benchmarks.soak", "--minutes", "3",
                           "--minute-seconds", "2", "--warm-in", "1", "--connections", "4",
                           "--sample-seconds", "0.5", "--out", str(tmp_path)],
                          cwd=ROOT, capture_output=True, text=True, timeout=600, check=False)
    (path,) = tmp_path.glob("soak-*.json")
    result = json.loads(path.read_text())
    # The verdict may fail on a busy machine (p99 over 2 s "minutes" is noise); the exit
    # status says so, and only then.
    assert proc.returncode == (0 if result["verdict"]["passed"] else 1), proc.stderr[-3000:]
    assert result["schema"] == "rnsca-bench-soak/1" and result["quick"] is True
    assert {"cpu_model", "cpu_count", "git"} <= result["machine"].keys()
    assert [m["minute"] for m in result["minutes"]] == [1, 2, 3]
    for m in result["minutes"]:
        assert m["requests"] > 0 and m["requests_per_s"] > 0
        assert set(m["sent"]) == set(result["mix"])
        assert m["answers"]["5xx"] == 0 and m["answers"]["unexpected"] == 0
        assert m["answers"]["expected_4xx"] > 0 and m["answers"]["ok"] > 0
        assert m["socket_errors"] == 0
        assert {"p50", "p90", "p99", "p99.9", "max"} == set(m["latency_s"])
        roles = [p["role"] for p in m["processes"]]
        assert roles[0] == "supervisor" and roles.count("worker") == 2
        assert m["rss_bytes"] >= m["rss_workers_bytes"] > 0
        assert m["rss_peak_bytes"] >= m["rss_bytes"]
        assert len(m["load_average"]) == 3
    verdict = result["verdict"]
    assert {c["key"] for c in verdict["criteria"]} == {
        "rss_max_growth", "rss_trend_growth", "rss_peak_max_growth", "p99_trend_growth",
        "p99_median_last_5_growth", "p99_max_growth", "no_5xx", "no_unexpected_status",
        "no_socket_errors"}
    assert {"first", "baseline", "max", "last", "slope_per_minute",
            "trend_growth"} <= verdict["rss"].keys()
    assert verdict["answers"]["5xx"] == 0
    assert result["server_log"]["lines"] > 0


def _minute(rss_mib: float, p99_ms: float) -> dict:
    answers = {"ok": 100, "expected_4xx": 10, "bad_sent": 10, "5xx": 0, "unexpected": 0}
    return {"rss_bytes": rss_mib * 2**20, "rss_peak_bytes": rss_mib * 2**20,
            "rss_workers_bytes": rss_mib * 2**19, "latency_s": {"p99": p99_ms / 1e3},
            "answers": answers, "socket_errors": 0}


def test_soak_verdict_fails_on_steady_memory_growth_and_passes_on_noise():
    from benchmarks.soak import evaluate_soak

    # 1 MiB a minute on 500 MiB: 5% over minutes 6-30 would pass, so 3 MiB a minute.
    leaking = [_minute(500 + 3 * i, 50) for i in range(30)]
    verdict = evaluate_soak(leaking, warm_in=5)
    met = {c["key"]: c["met"] for c in verdict["criteria"]}
    assert not verdict["passed"]
    assert not met["rss_max_growth"] and not met["rss_trend_growth"]
    assert met["p99_trend_growth"] and met["no_5xx"]
    assert verdict["rss"]["baseline"] == (512 + 515) / 2 * 2**20
    # One slow minute (someone else's build) is reported, not decisive.
    noisy = [_minute(500, 200 if i == 20 else 50) for i in range(30)]
    verdict = evaluate_soak(noisy, warm_in=5)
    met = {c["key"]: c["met"] for c in verdict["criteria"]}
    assert verdict["passed"] and not met["p99_max_growth"]


@pytest.mark.opencl
def test_the_gpu_benchmark_runs_and_checks_every_result(opencl, tmp_path):
    """`python -m benchmarks.gpu --small`: every workload on both backends, equal."""
    run = subprocess.run(
        [sys.executable, "-m", "benchmarks.gpu", "--small", "--skip-cold-start",
         "--repeats", "1", "--out", str(tmp_path)], cwd=ROOT, capture_output=True,
        text=True, timeout=900, env={**os.environ, "OUT": str(tmp_path),
             "RNSCA_CACHE_DIR": str(tmp_path / "cache")})
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads((tmp_path / "gpu.json").read_text())
    # A failing workload is recorded and the rest still run (one lease, minutes long).
    assert report["errors"] == [], report["errors"]
    rows = {row["workload"]: row for row in report["rows"]}
    compared = [row for row in rows.values() if row["equal"] is not None]
    assert len(compared) >= 9 and all(row["equal"] for row in compared)
    assert any(name.startswith("1024 windows") for name in rows)
    assert any("device-resident" in name for name in rows)
    assert any(name.endswith("encode tiles") for name in rows)
    assert set(report["auto_calibration"]["crossover"]) == {"segments", "windows", "lines",
                                                            "polygons"}
    for row in compared:
        assert row["kernel_s"] >= 0 and row["bytes_to_device"] > 0
