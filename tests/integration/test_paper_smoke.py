"""`python -m benchmarks.paper --quick` runs end to end and its figures hang together.

No timing assertions: the run is tiny (Table 2 sizes 100 and 500, families at 500) and
only its structure and internal consistency are checked, plus one independent count:
Cohen–Sutherland's intersections, recounted here with a textbook loop in plain Python.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import rnsca
from benchmarks import datasets

ROOT = Path(__file__).resolve().parents[2]
MAX_SIZE = 500
FAMILIES = {"uniform", "mostly_outside", "mostly_inside", "long_segments"}
CONTENDERS = {"rnsca:exact", "rnsca:approx", "cohen_sutherland"}
METHODS = {"rnsca:exact", "rnsca:approx", "cohen_sutherland", "liang_barsky",
           "nicholl_lee_nicholl", "midpoint:exact", "midpoint:approx"}
SWEEP_N = [2, 3, 4, 8, 16, 32, 64, "auto"]
SHARES = {"accepted", "rejected", "subdivided", "clipped", "dropped"}


@pytest.fixture(scope="module")
def quick_paper(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks.paper", "--quick", "--max-size", str(MAX_SIZE),
         "--out", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out, json.loads((out / "latest-paper.json").read_text()), proc.stdout


def test_quick_run_writes_json_plots_and_latest_copies(quick_paper):
    out, result, _ = quick_paper
    stamped = list(out.glob("paper-*.json"))
    assert len(stamped) == 1
    assert json.loads(stamped[0].read_text()) == result
    for key in ("table2", "decided", "intersections"):
        assert Path(result["paths"]["figures"][key]).stat().st_size > 0
        assert (out / f"latest-paper-{key}.png").stat().st_size > 0


def test_result_describes_the_machine_and_the_run(quick_paper):
    _, result, _ = quick_paper
    assert result["schema"] == "rnsca-bench-paper/1"
    assert result["quick"] is True
    assert {"cpu_model", "numba_threads", "versions", "git"} <= result["machine"].keys()
    assert result["config"]["table2_sizes"] == [100, 500]
    assert result["config"]["family_n"] == MAX_SIZE
    assert {"decided_shallow_fraction", "trivially_decided_fraction", "shares",
            "intersections_per_segment"} <= result["definitions"].keys()


def test_table2_times_each_contender_and_gives_the_cohen_sutherland_ratio(quick_paper):
    _, result, _ = quick_paper
    assert [w["workload"]["n"] for w in result["table2"]] == [100, 500]
    for w in result["table2"]:
        runs = w["runs"]
        assert runs.keys() == CONTENDERS
        for r in runs.values():
            assert r["seconds"] > 0 and r["segments_per_s"] > 0
            assert r["stats"]["segments_in"] == w["workload"]["n"]
        # Every exact method leaves the same pieces.
        assert runs["rnsca:exact"]["pieces_out"] == runs["cohen_sutherland"]["pieces_out"]
        cs = runs["cohen_sutherland"]["seconds"]
        for label in ("rnsca:exact", "rnsca:approx"):
            assert w["cs_over_rnsca"][label] == pytest.approx(cs / runs[label]["seconds"])


def _default_approx_tolerance(window) -> float:
    return rnsca.clip_segments([[0.0, 0.0, 1.0, 1.0]], window, mode="approx").options.tolerance


def test_approx_mode_runs_with_the_library_default_tolerance(quick_paper):
    _, result, _ = quick_paper
    for w in result["table2"]:
        expected = _default_approx_tolerance(w["workload"]["window"])
        assert w["runs"]["rnsca:approx"]["tolerance"] == expected
    for d in result["decided"]:
        if d["mode"] == "approx":
            expected = _default_approx_tolerance(d["workload"]["window"])
            assert all(r["tolerance"] == expected for r in d["runs"])


def test_decided_sweeps_every_n_in_both_modes_on_every_family(quick_paper):
    _, result, _ = quick_paper
    seen = {(d["workload"]["family"], d["mode"]) for d in result["decided"]}
    assert seen == {(f, m) for f in FAMILIES for m in ("approx", "exact")}
    for d in result["decided"]:
        assert [r["n_param"] for r in d["runs"]] == SWEEP_N
        assert d["workload"]["n"] == MAX_SIZE


def test_decided_fractions_follow_from_the_stats(quick_paper):
    _, result, _ = quick_paper
    for d in result["decided"]:
        n = d["workload"]["n"]
        for r in d["runs"]:
            s = r["stats"]
            levels = s["decided_per_level"]
            assert r["seconds"] > 0
            assert r["shares"].keys() == SHARES
            assert sum(r["shares"].values()) == pytest.approx(1.0)
            assert r["fragments_per_segment"] == pytest.approx(s["fragments_evaluated"] / n)
            assert r["fragments_per_segment"] >= 1.0
            decided = s["accepted"] + s["rejected"] + s["clipped"] + s["dropped"]
            assert r["decided"] == decided == sum(levels)
            assert decided == s["fragments_evaluated"] - s["subdivided"]
            assert r["decided_shallow_fraction"] == pytest.approx(sum(levels[:2]) / sum(levels))
            assert r["trivially_decided_fraction"] == pytest.approx(
                (s["accepted"] + s["rejected"]) / decided)
            assert r["deepest_level"] == max(k for k, v in enumerate(levels) if v)
            if d["mode"] == "approx":
                assert s["clipped"] == 0 and s["intersections"] == 0  # nothing is cut


def _textbook_cohen_sutherland_intersections(segment, window) -> int:
    """Cut one segment with the textbook loop (Foley et al.): top, bottom, right, left."""
    xmin, ymin, xmax, ymax = window

    def code(x, y):
        return ((x < xmin) * 1) | ((x > xmax) * 2) | ((y < ymin) * 4) | ((y > ymax) * 8)

    x0, y0, x1, y1 = (float(v) for v in segment)
    c0, c1 = code(x0, y0), code(x1, y1)
    cuts = 0
    while (c0 | c1) and not (c0 & c1):
        c = c0 or c1
        cuts += 1
        if c & 8:
            x, y = x0 + (x1 - x0) * (ymax - y0) / (y1 - y0), ymax
        elif c & 4:
            x, y = x0 + (x1 - x0) * (ymin - y0) / (y1 - y0), ymin
        elif c & 2:
            x, y = xmax, y0 + (y1 - y0) * (xmax - x0) / (x1 - x0)
        else:
            x, y = xmin, y0 + (y1 - y0) * (xmin - x0) / (x1 - x0)
        if c == c0:
            x0, y0, c0 = x, y, code(x, y)
        else:
            x1, y1, c1 = x, y, code(x, y)
    return cuts


def test_cohen_sutherland_intersections_match_an_independent_count(quick_paper):
    _, result, _ = quick_paper
    workloads = {w.family: w for w in [*datasets.table2([MAX_SIZE]), *datasets.shaped(MAX_SIZE)]}
    for w in result["intersections"]:
        workload = workloads[w["workload"]["family"]]
        expected = sum(_textbook_cohen_sutherland_intersections(s, workload.window)
                       for s in workload.segments())
        cs = w["runs"]["cohen_sutherland"]
        assert cs["intersections"] == expected
        assert cs["intersections_per_segment"] == pytest.approx(expected / MAX_SIZE)


def test_intersections_are_counted_for_every_method_on_every_family(quick_paper):
    _, result, _ = quick_paper
    assert {w["workload"]["family"] for w in result["intersections"]} == FAMILIES
    for w in result["intersections"]:
        assert w["runs"].keys() == METHODS
        for r in w["runs"].values():
            assert r["intersections"] == r["stats"]["intersections"] >= 0
        # Approx modes drop undecided leaves: they never compute an intersection.
        assert w["runs"]["rnsca:approx"]["intersections"] == 0
        assert w["runs"]["midpoint:approx"]["intersections"] == 0


def test_claims_and_the_markdown_summary_are_reported(quick_paper):
    _, result, stdout = quick_paper
    keys = {c["key"] for c in result["claims"]}
    assert keys == {"faster_than_cohen_sutherland:exact", "faster_than_cohen_sutherland:approx",
                    "decided_shallow:approx", "decided_shallow:exact"}
    for c in result["claims"]:
        assert c["holds"] in (True, False, "partly")
    assert "**Table 2 sets" in stdout and "| uniform |" in stdout


def test_summary_reprints_the_tables_of_a_result_file(quick_paper, capsys):
    from benchmarks.paper import main, markdown_summary

    out, result, stdout = quick_paper
    assert main(["--summary", str(out / "latest-paper.json")]) == 0
    printed = capsys.readouterr().out
    assert printed.strip() == markdown_summary(result).strip()
    assert markdown_summary(result).strip() in stdout
