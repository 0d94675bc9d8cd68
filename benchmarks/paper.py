"""The paper's claims, reproduced: RNSCA against Cohen–Sutherland, early decisions, intersections.

Usage::

    python -m benchmarks.paper                     # full run: Table 2 sizes up to 10M
    python -m benchmarks.paper --quick             # Table 2 up to 10k, the families at 10k
    python -m benchmarks.paper --max-size 1000000  # no workload above 1M segments
    python -m benchmarks.run --suite paper         # the same, as a suite of benchmarks.run
    python -m benchmarks.paper --summary benchmarks/results/latest-paper.json  # tables only

Three measurements, each on the Numba backend (see benchmarks/README.md, "The paper's
claims, reproduced"):

1. ``table2``: `rnsca.clip_segments` with method ``rnsca`` (exact, and approx with the
   library's default tolerance; ``n="auto"``) and ``cohen_sutherland`` on the uniform
   sets of the paper's Table 2 (100 to 10k segments) and 100k, 1M, 10M, timed
   round-robin (`benchmarks.timing`); the ratio Cohen–Sutherland time / RNSCA time.
2. ``decided``: for N = 2, 3, 4, 8, 16, 32, 64 and ``"auto"``, in approx and exact mode
   (default settings otherwise), on the four segment families at one size (100k; 10k
   with ``--quick``): how many fragments are evaluated and how each ends (`ClipStats`),
   the share decided at levels 0 and 1 (the paper claims 70-80%), and the time per call.
3. ``intersections``: `ClipStats.intersections` per input segment for every method on
   the four families (one untimed call each).

Writes ``<out>/paper-<UTC timestamp>.json`` and three plots
``paper-<stamp>-{table2,decided,intersections}.png``, copied to ``latest-paper.json``
and ``latest-paper-*.png``; a run that is not ``--quick``, into the default directory,
also copies the plots to ``benchmarks/paper-*.png`` (the copies the README shows). The
markdown tables of the README (`markdown_summary`) are printed on stdout.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import shutil
import statistics
import sys
import time
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path

import numba
import numpy as np

import rnsca
from benchmarks import datasets
from benchmarks.machine import describe_machine, load_average, run_header
from benchmarks.plot_paper import draw_decided, draw_intersections, draw_table2
from benchmarks.timing import Contender, Policy, full_policy, time_round_robin
from rnsca.backends.numba_cpu import BLOCK_SIZE, SERIAL_BLOCKS
from rnsca.runtime import configure_process

__all__ = [
    "SCHEMA",
    "CONTENDERS",
    "SWEEP_N",
    "METHODS",
    "DEFINITIONS",
    "fragment_figures",
    "run_table2",
    "run_decided",
    "run_intersections",
    "evaluate_claims",
    "run",
    "markdown_summary",
    "main",
]

SCHEMA = "rnsca-bench-paper/1"
HERE = Path(__file__).resolve().parent
PROJECT_ROOT = HERE.parent
DEFAULT_OUT = HERE / "results"
#: The plots, by key; ``benchmarks/paper-<key>.png`` is the committed copy of each.
PLOTS = ("table2", "decided", "intersections")
#: The environment variables that change how Numba's parallel kernels run.
THREADING_ENV = ("NUMBA_NUM_THREADS", "NUMBA_THREADING_LAYER", "OMP_NUM_THREADS",
                 "OMP_WAIT_POLICY")

#: label -> clip_segments keywords. Approx mode takes the library's default tolerance.
CONTENDERS: dict[str, dict] = {
    "rnsca:exact": {"method": "rnsca", "mode": "exact", "n": "auto"},
    "rnsca:approx": {"method": "rnsca", "mode": "approx", "n": "auto"},
    "cohen_sutherland": {"method": "cohen_sutherland"},
}
#: The N values of the early-decision sweep ("auto" last).
SWEEP_N: tuple[int | str, ...] = (2, 3, 4, 8, 16, 32, 64, "auto")
#: Every method (label -> clip_segments keywords) for the intersection count.
METHODS: dict[str, dict] = {
    "rnsca:exact": {"method": "rnsca", "mode": "exact"},
    "rnsca:approx": {"method": "rnsca", "mode": "approx"},
    "cohen_sutherland": {"method": "cohen_sutherland"},
    "liang_barsky": {"method": "liang_barsky"},
    "nicholl_lee_nicholl": {"method": "nicholl_lee_nicholl"},
    "midpoint:exact": {"method": "midpoint", "mode": "exact"},
    "midpoint:approx": {"method": "midpoint", "mode": "approx"},
}
FAMILIES = ("uniform", "mostly_outside", "mostly_inside", "long_segments")
#: The paper's claim on early decisions: this share of fragments decided at levels 0-1.
PAPER_SHALLOW = (0.70, 0.80)

DEFINITIONS = {
    "fragment": ("a whole input segment or a piece of one made by subdivision; each "
                 "evaluated fragment ends exactly one way: accepted, rejected, "
                 "subdivided, clipped or dropped (ClipStats)"),
    "decided": "accepted + rejected + clipped + dropped (every evaluated fragment not "
               "subdivided) == sum(decided_per_level)",
    "fragments_per_segment": "fragments_evaluated / input segments",
    "shares": ("accepted, rejected, subdivided, clipped, dropped, each / "
               "fragments_evaluated (they sum to 1)"),
    "decided_shallow_fraction": ("sum(decided_per_level[:2]) / sum(decided_per_level): "
                                 "decided fragments decided at subdivision level 0 (the "
                                 "whole segment) or 1 (a piece of its first split)"),
    "trivially_decided_fraction": ("(accepted + rejected) / decided: decided fragments "
                                   "settled by their end points' outcodes alone, with no "
                                   "intersection computed and nothing dropped"),
    "intersections_per_segment": ("ClipStats.intersections / input segments: intersection "
                                  "parameters computed against an edge line, one division "
                                  "each, counted the same way for every method"),
    "cs_over_rnsca": ("Cohen-Sutherland seconds / the RNSCA contender's seconds, same "
                      "workload, same run; above 1 means RNSCA is faster"),
    "seconds": "best (minimum) seconds per call over the repeats (benchmarks.timing)",
}


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _warm_up(segments: np.ndarray, window, options: dict) -> None:
    """Compile (or load) the kernels of one configuration on rows of the input.

    The Numba backend clips up to `SERIAL_BLOCKS` blocks on the calling thread and more
    in parallel: both drivers are loaded here, or the first timed call of a large input
    would include loading the parallel one (about 0.1 s, measured).
    """
    rnsca.clip_segments(segments[:64], window, **options)
    if segments.shape[0] > SERIAL_BLOCKS * BLOCK_SIZE:
        rnsca.clip_segments(segments[:(SERIAL_BLOCKS + 1) * BLOCK_SIZE], window, **options)


def _call(segments: np.ndarray, window, options: dict) -> Callable[[], object]:
    def call():
        return rnsca.clip_segments(segments, window, **options)
    return call


def _resolved(result: rnsca.SegmentClipResult) -> dict:
    """Return the options a call ran with (the library's defaults filled in)."""
    options = result.options
    tolerance = float(options.tolerance)
    return {"tolerance": None if math.isinf(tolerance) else tolerance,
            "max_depth": int(options.max_depth)}


def fragment_figures(stats: dict, n: int) -> dict:
    """Return the derived figures of one call's `ClipStats.to_dict()` (see DEFINITIONS)."""
    evaluated = stats["fragments_evaluated"]
    decided = stats["accepted"] + stats["rejected"] + stats["clipped"] + stats["dropped"]
    return {
        "fragments_per_segment": evaluated / n if n else 0.0,
        "shares": {key: (stats[key] / evaluated if evaluated else 0.0)
                   for key in ("accepted", "rejected", "subdivided", "clipped", "dropped")},
        "decided": decided,
        "decided_shallow_fraction": stats["decided_shallow_fraction"],
        "trivially_decided_fraction": ((stats["accepted"] + stats["rejected"]) / decided
                                       if decided else 1.0),
        "deepest_level": stats["deepest_level"],
        "intersections_per_segment": stats["intersections"] / n if n else 0.0,
    }


def _timed_record(c: Contender, n: int) -> dict:
    return {"seconds": c.best, "seconds_median": statistics.median(c.samples),
            "repeats": len(c.samples), "number": c.number,
            "segments_per_s": n / c.best if c.best > 0 else None}


# --------------------------------------------------------------------------- 1. Table 2


def run_table2(sizes: list[int], policy_for: Callable[[int], Policy],
               log: Callable[[str], None] = _log) -> list[dict]:
    """Time `CONTENDERS` round-robin on the uniform set of each size; one dict per size."""
    out = []
    for workload in datasets.table2(sizes):
        segments = workload.segments()
        contenders = []
        for label, options in CONTENDERS.items():
            _warm_up(segments, workload.window, options)
            contenders.append(Contender(label, _call(segments, workload.window, options)))
        policy = policy_for(workload.n)
        log(f"  table2 {workload.name}: {len(contenders)} contenders "
            f"(best of up to {policy.max_repeats})")
        before = load_average()
        time_round_robin(contenders, policy)
        runs = {}
        for c in contenders:
            result = c.last
            assert isinstance(result, rnsca.SegmentClipResult)
            runs[c.label] = {**_timed_record(c, workload.n), **_resolved(result),
                             **CONTENDERS[c.label], "pieces_out": len(result),
                             "stats": result.stats.to_dict()}
        cs = runs["cohen_sutherland"]["seconds"]
        out.append({"workload": workload.describe(), "load_average_before": before,
                    "load_average_after": load_average(), "runs": runs,
                    "cs_over_rnsca": {label: cs / runs[label]["seconds"]
                                      for label in ("rnsca:exact", "rnsca:approx")}})
        del segments
        gc.collect()
    return out


# --------------------------------------------------------------------------- 2. decided


def _families(n: int) -> list[datasets.Workload]:
    return [*datasets.table2([n]), *datasets.shaped(n)]


def run_decided(n: int, policy: Policy, log: Callable[[str], None] = _log) -> list[dict]:
    """Sweep `SWEEP_N` in approx and exact mode on the four families of `n` segments.

    For each family and mode, the eight configurations are timed round-robin; each
    record holds the time, the call's stats and the figures of `fragment_figures`.
    """
    out = []
    for workload in _families(n):
        segments = workload.segments()
        for mode in ("approx", "exact"):
            contenders = []
            for n_value in SWEEP_N:
                options = {"method": "rnsca", "mode": mode, "n": n_value}
                _warm_up(segments, workload.window, options)
                contenders.append(Contender(str(n_value),
                                            _call(segments, workload.window, options)))
            log(f"  decided {workload.name} {mode}: {len(contenders)} values of N")
            time_round_robin(contenders, policy)
            runs = []
            for c, n_value in zip(contenders, SWEEP_N, strict=True):
                result = c.last
                assert isinstance(result, rnsca.SegmentClipResult)
                stats = result.stats.to_dict()
                runs.append({"n_param": n_value, **_timed_record(c, workload.n),
                             **_resolved(result), "pieces_out": len(result),
                             **fragment_figures(stats, workload.n), "stats": stats})
            out.append({"workload": workload.describe(), "mode": mode, "runs": runs})
        del segments
        gc.collect()
    return out


# --------------------------------------------------------------------------- 3. intersections


def run_intersections(n: int, log: Callable[[str], None] = _log) -> list[dict]:
    """Count intersections per input segment for every method of `METHODS`, per family."""
    out = []
    for workload in _families(n):
        segments = workload.segments()
        log(f"  intersections {workload.name}: {len(METHODS)} methods")
        runs = {}
        for label, options in METHODS.items():
            result = rnsca.clip_segments(segments, workload.window, **options)
            stats = result.stats.to_dict()
            runs[label] = {**options, **_resolved(result), "pieces_out": len(result),
                           "intersections": stats["intersections"],
                           "intersections_per_segment": stats["intersections"] / workload.n,
                           "fragments_per_segment": stats["fragments_evaluated"] / workload.n,
                           "stats": stats}
        out.append({"workload": workload.describe(), "runs": runs})
    return out


# --------------------------------------------------------------------------- claims


def evaluate_claims(table2: list[dict], decided: list[dict]) -> list[dict]:
    """Return each claim of the paper measured here, with its values and whether it holds.

    ``holds`` is True where the claim holds on every workload measured, False where it
    fails on every one, and ``"partly"`` in between.
    """
    def verdict(flags: list[bool]):
        if flags and all(flags):
            return True
        return "partly" if any(flags) else False

    claims = []
    for label in ("rnsca:exact", "rnsca:approx"):
        values = {str(w["workload"]["n"]): w["cs_over_rnsca"][label] for w in table2}
        claims.append({
            "key": f"faster_than_cohen_sutherland:{label.split(':')[1]}",
            "claim": f"{label} clips the Table 2 sets faster than Cohen-Sutherland",
            "measure": "cs_over_rnsca per size (> 1: RNSCA faster)",
            "values": values, "holds": verdict([v > 1.0 for v in values.values()])})
    for mode in ("approx", "exact"):
        values = {}
        for d in decided:
            if d["mode"] == mode:
                auto = next(r for r in d["runs"] if r["n_param"] == "auto")
                values[d["workload"]["family"]] = auto["decided_shallow_fraction"]
        claims.append({
            "key": f"decided_shallow:{mode}",
            "claim": (f"70-80% of fragments are decided at levels 0-1 ({mode} mode, "
                      "n='auto', default tolerance)"),
            "measure": "decided_shallow_fraction per family (holds if >= 0.70)",
            "values": values,
            "holds": verdict([v >= PAPER_SHALLOW[0] for v in values.values()])})
    return claims


# --------------------------------------------------------------------------- the run


_QUICK_POLICY = Policy(min_sample=0.002, budget=0.01, min_repeats=1, max_repeats=1)
_SWEEP_POLICY = Policy(min_sample=0.05, budget=1.0, min_repeats=2, max_repeats=5)


def build_config(quick: bool, max_size: int | None) -> dict:
    """Return the Table 2 sizes and the family size of a run."""
    sizes = list(datasets.PAPER_SIZES) if quick else [*datasets.PAPER_SIZES,
                                                      *datasets.LARGE_SIZES]
    family_n = 10_000 if quick else 100_000
    if max_size is not None:
        sizes = [n for n in sizes if n <= max_size] or [max_size]
        family_n = min(family_n, max_size)
    return {"sizes": sizes, "family_n": family_n, "max_size": max_size}


def _json_default(obj):
    if hasattr(obj, "item"):
        return obj.item()
    raise TypeError(f"cannot serialise {type(obj).__name__}")


def run(quick: bool = False, out_dir: Path = DEFAULT_OUT, max_size: int | None = None,
        copy_figures: bool = True, log: Callable[[str], None] = _log) -> dict:
    """Run the three measurements; write the JSON and the plots into `out_dir`; return it.

    `copy_figures`: also copy the plots to ``benchmarks/paper-*.png`` (ignored in quick
    mode).
    """
    started = time.monotonic()
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    config = build_config(quick, max_size)
    machine = describe_machine(PROJECT_ROOT)
    log(f"paper: Table 2 sizes {config['sizes']}, families at {config['family_n']}")
    table2 = run_table2(config["sizes"], (lambda n: _QUICK_POLICY) if quick else full_policy,
                        log=log)
    decided = run_decided(config["family_n"], _QUICK_POLICY if quick else _SWEEP_POLICY, log=log)
    intersections = run_intersections(config["family_n"], log=log)
    machine["numba_threading_layer"] = numba.threading_layer()

    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = out_dir / f"paper-{stamp}.json"
    plots = {key: out_dir / f"paper-{stamp}-{key}.png" for key in PLOTS}
    result = {
        **run_header(SCHEMA, stamp, quick, machine, PROJECT_ROOT),
        "config": {
            "table2_sizes": config["sizes"],
            "family_n": config["family_n"],
            "max_size": config["max_size"],
            "backend": "numba",
            "contenders": CONTENDERS,
            "sweep_n": list(SWEEP_N),
            "methods": METHODS,
            "paper_shallow_claim": list(PAPER_SHALLOW),
            "environment": {name: os.environ.get(name) for name in THREADING_ENV},
            "policies": ({"all": vars(_QUICK_POLICY)} if quick else
                         {"table2": {str(n): vars(full_policy(n)) for n in config["sizes"]},
                          "decided": vars(_SWEEP_POLICY)}),
            "timing": ("best (min) of repeats; the contenders of a workload (table2) or the "
                       "values of N of one family and mode (decided) timed round-robin; "
                       "kernels compiled before timing; intersections untimed"),
        },
        "definitions": DEFINITIONS,
        "table2": table2,
        "decided": decided,
        "intersections": intersections,
        "claims": evaluate_claims(table2, decided),
        "elapsed_seconds": None,
        "paths": {"json": str(json_path), "figures": {k: str(p) for k, p in plots.items()}},
    }
    note = (f"{machine['cpu_model']}, {machine['numba_threads']} Numba thread(s), {stamp}"
            + (" (QUICK)" if quick else ""))
    draw_table2(table2, plots["table2"], note)
    draw_decided(decided, plots["decided"], note, PAPER_SHALLOW)
    draw_intersections(intersections, plots["intersections"], note)
    result["elapsed_seconds"] = time.monotonic() - started
    text = json.dumps(result, indent=1, default=_json_default)
    json_path.write_text(text)
    (out_dir / "latest-paper.json").write_text(text)
    for key, path in plots.items():
        shutil.copyfile(path, out_dir / f"latest-paper-{key}.png")
        if copy_figures and not quick:
            shutil.copyfile(path, HERE / f"paper-{key}.png")
    return result


# --------------------------------------------------------------------------- summary


def _ms(seconds: float) -> str:
    ms = seconds * 1e3
    return f"{ms:.3f}" if ms < 1 else f"{ms:.2f}" if ms < 100 else f"{ms:.0f}"


def _size(n: int) -> str:
    if n >= 1_000_000 and n % 1_000_000 == 0:
        return f"{n // 1_000_000}M"
    return f"{n // 1000}k" if n >= 1000 and n % 1000 == 0 else str(n)


def _pct(v: float) -> str:
    return f"{100 * v:.1f}%"


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return lines


def markdown_summary(result: dict) -> str:
    """Return the README's tables of a run (markdown), to paste under its run line."""
    m = result["machine"]
    first = result["table2"][0]
    approx_tol = first["runs"]["rnsca:approx"]["tolerance"]
    xmin, ymin, xmax, ymax = first["workload"]["window"]
    lines = [f"Run `{result['created']}`{' (quick)' if result['quick'] else ''}: "
             f"{m['cpu_model']}, {m['numba_threads']} Numba thread(s), load "
             f"{m['load_average_at_start']} -> {result['load_average_at_end']}; approx mode "
             f"with the library's default tolerance ({approx_tol:g} on the Table 2 window, "
             f"{approx_tol / max(xmax - xmin, ymax - ymin):.3g} of its side), `n=\"auto\"` "
             "unless N is given.", ""]

    lines += ["**Table 2 sets (uniform, window [250,750]²): ms per call, best of repeats**",
              ""]
    rows = []
    for w in result["table2"]:
        r = w["runs"]
        rows.append([_size(w["workload"]["n"]), _ms(r["rnsca:exact"]["seconds"]),
                     _ms(r["rnsca:approx"]["seconds"]), _ms(r["cohen_sutherland"]["seconds"]),
                     f"{w['cs_over_rnsca']['rnsca:exact']:.2f}",
                     f"{w['cs_over_rnsca']['rnsca:approx']:.2f}",
                     f"{r['rnsca:exact']['segments_per_s'] / 1e6:.1f}"])
    lines += _table(["segments", "rnsca exact", "rnsca approx", "Cohen–Sutherland",
                     "CS / exact", "CS / approx", "exact Mseg/s"], rows)

    family_n = result["config"]["family_n"]
    for mode in ("approx", "exact"):
        sweeps = [d for d in result["decided"] if d["mode"] == mode]
        lines += ["", f"**Decided at levels 0-1, {mode} mode, {_size(family_n)} segments, "
                      "by N** (`decided_shallow_fraction`)", ""]
        header = ["family", *[str(v) for v in SWEEP_N]]
        rows = [[d["workload"]["family"],
                 *[_pct(r["decided_shallow_fraction"]) for r in d["runs"]]] for d in sweeps]
        lines += _table(header, rows)
        lines += ["", f"**{mode} mode, `n=\"auto\"`: how fragments end**", ""]
        rows = []
        for d in sweeps:
            a = next(r for r in d["runs"] if r["n_param"] == "auto")
            s = a["shares"]
            rows.append([d["workload"]["family"], f"{a['fragments_per_segment']:.2f}",
                         _pct(s["accepted"]), _pct(s["rejected"]), _pct(s["subdivided"]),
                         _pct(s["clipped"]), _pct(s["dropped"]),
                         _pct(a["decided_shallow_fraction"]),
                         _pct(a["trivially_decided_fraction"]), str(a["deepest_level"]),
                         _ms(a["seconds"])])
        lines += _table(["family", "fragments / segment", "accepted", "rejected", "subdivided",
                         "clipped", "dropped", "decided at 0-1", "decided by outcodes",
                         "deepest", "ms"], rows)

    lines += ["", f"**Intersections per input segment, {_size(family_n)} segments**", ""]
    rows = [[w["workload"]["family"],
             *[f"{w['runs'][label]['intersections_per_segment']:.3f}" for label in METHODS]]
            for w in result["intersections"]]
    lines += _table(["family", *METHODS], rows)

    lines += ["", "**Claims**", ""]
    rows = [[c["key"], c["measure"],
             ", ".join(f"{k}: {v:.2f}" for k, v in c["values"].items()), str(c["holds"])]
            for c in result["claims"]]
    lines += _table(["claim", "measure", "values", "holds"], rows)
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Parse the command line, run, print the markdown summary."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.paper", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="Table 2 sizes up to 10k, families at 10k, one sample each")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"directory for the JSON and PNGs (default {DEFAULT_OUT})")
    parser.add_argument("--max-size", type=int, default=None,
                        help="no workload larger than this many segments")
    parser.add_argument("--no-figure-copy", action="store_true",
                        help="do not update benchmarks/paper-*.png")
    parser.add_argument("--summary", type=Path, metavar="JSON",
                        help="run nothing: print the markdown tables of this result file")
    args = parser.parse_args(argv)
    if args.summary is not None:
        print(markdown_summary(json.loads(args.summary.read_text())))
        return 0
    configure_process()  # as the CLI, the service and benchmarks.run do
    copy_figures = not args.no_figure_copy and args.out.resolve() == DEFAULT_OUT
    result = run(args.quick, args.out, args.max_size, copy_figures)
    print(markdown_summary(result))
    print(f"Results: {result['paths']['json']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
