"""SVG path data benchmarks (issue 4): parse and write throughput.

The corpus imitates font glyphs and icons, generated deterministically (`glyph_corpus`):
each path has one to four closed contours of lines (``L``, ``H``, ``V``), quadratics
(``Q``, ``T``), cubics (``C``, ``S``) and, in a few paths, arcs, in absolute and
relative form; coordinates are integers or have one or two decimals; some paths are
minified (``M10-5.5.5``), others spelled out (``M 10,-5.5 L .5,...``).

Contenders, each called once before timing (compiles or loads the kernels), then timed
round-robin (best of repeats, see `benchmarks.timing`):

- ``parse:parse_paths``: `rnsca.io.svgpath.parse_paths` on the whole corpus, every
  Numba thread; ``parse:parse_paths:1thread`` the same on one thread;
- ``write:precision=6`` and ``write:precision=None``: `write_paths` of the parsed paths.

Throughput is UTF-8 bytes of path data per second (MB = 10**6 bytes): input bytes for
parsing, output bytes for writing. Outside the timing, the run checks that the written
data reads back: exactly with ``precision=None``.
"""

from __future__ import annotations

import gc
from collections.abc import Callable
from dataclasses import dataclass
from itertools import pairwise

import numba
import numpy as np

from benchmarks.machine import load_average
from benchmarks.timing import Contender, Policy, time_round_robin
from rnsca.io.svgpath import parse_paths, write_paths

__all__ = ["SvgPlan", "FULL_PLAN", "QUICK_PLAN", "PARSE_TARGET_MB_S", "TIMING", "glyph_corpus",
           "run_svg", "evaluate_svg_targets", "print_svg_summary"]

#: Issue 4: parsing at least this many MB/s.
PARSE_TARGET_MB_S = 20.0
SEED = 4
TIMING = ("best (min) of repeats, garbage collector paused; each contender called once "
          "before timing (compiles or loads the kernels); MB/s = 10**6 bytes of path data "
          "per second, input bytes for parse, output bytes for write")


@dataclass(frozen=True)
class SvgPlan:
    """Corpus size and timing of one SVG run (full or quick)."""

    n_paths: int
    policy: Policy


FULL_PLAN = SvgPlan(n_paths=50_000, policy=Policy(min_sample=0.05, budget=3.0,
                                                  min_repeats=3, max_repeats=7))
QUICK_PLAN = SvgPlan(n_paths=500, policy=Policy(min_sample=0.002, budget=0.01,
                                                min_repeats=1, max_repeats=1))


# Command mix of the corpus: letter, number of arguments, cumulative probability.
_COMMANDS = (("L", 2, 0.33), ("H", 1, 0.39), ("V", 1, 0.45), ("Q", 4, 0.63), ("T", 2, 0.68),
             ("C", 6, 0.88), ("S", 4, 1.0))


def _glyph(rng: np.random.Generator) -> str:
    """Return one glyph-like path: closed contours of mixed commands."""
    decimals = int(rng.choice([0, 1, 2], p=[0.6, 0.3, 0.1]))
    minified = rng.random() < 0.5
    n_contours = int(rng.integers(1, 4))
    n_commands = rng.integers(5, 17, n_contours)
    total = int(n_commands.sum())
    kinds = np.searchsorted([c[2] for c in _COMMANDS], rng.random(total), side="right")
    relative = rng.random(total) < 0.5
    arcs = (rng.random(total) < 0.08) & (rng.random() < 0.15)   # arcs in some paths
    deltas = np.round(rng.uniform(-120, 120, (total, 6)), decimals)
    starts = np.round(rng.uniform(0, 1000, (n_contours, 2)), decimals)
    radii = np.round(rng.uniform(5, 120, (total, 2)), decimals)
    angles = np.round(rng.uniform(0, 90, total))
    flags = rng.integers(0, 2, (total, 2))
    numbers = deltas.tolist()

    def fmt(values) -> str:
        texts = []
        for v in values:
            t = f"{v:.{decimals}f}"
            if decimals:
                t = t.rstrip("0").rstrip(".")
            if t == "-0":
                t = "0"
            if minified and t[:2] in ("0.", "-0") and t != "0":
                t = t.replace("0.", ".", 1)
            texts.append(t)
        if not minified:
            return ", ".join(texts)
        out = texts[0]
        for prev, t in pairwise(texts):
            out += t if t[0] == "-" or (t[0] == "." and "." in prev) else " " + t
        return out

    gap = "" if minified else " "
    parts = []
    i = 0
    for c in range(n_contours):
        x, y = starts[c]
        parts.append(f"M{gap}{fmt((x, y))}")
        for _ in range(int(n_commands[c])):
            d = numbers[i]
            if arcs[i]:
                end = d[4:6] if relative[i] else (x + d[4], y + d[5])
                letter = "a" if relative[i] else "A"
                parts.append(f"{letter}{gap}{fmt(radii[i])} {angles[i]:.0f} "
                             f"{flags[i, 0]} {flags[i, 1]} {fmt(end)}")
                x, y = x + d[4], y + d[5]
                i += 1
                continue
            letter, n_args, _ = _COMMANDS[kinds[i]]
            args = d[:n_args]
            if letter == "V":
                args = d[1:2]
            if relative[i]:
                parts.append(f"{letter.lower()}{gap}{fmt(args)}")
            elif letter == "H":
                parts.append(f"H{gap}{fmt((x + args[0],))}")
            elif letter == "V":
                parts.append(f"V{gap}{fmt((y + args[0],))}")
            else:
                absolute = [a + (x if k % 2 == 0 else y) for k, a in enumerate(args)]
                parts.append(f"{letter}{gap}{fmt(absolute)}")
            if letter == "H":
                x += args[0]
            elif letter == "V":
                y += args[0]
            else:
                x, y = x + args[-2], y + args[-1]
            i += 1
        parts.append("Z" if rng.random() < 0.5 else "z")
    return gap.join(parts)


def glyph_corpus(n_paths: int, seed: int = SEED) -> list[str]:
    """Return `n_paths` glyph-like path data strings (about 450 bytes each), seeded."""
    rng = np.random.default_rng(seed)
    return [_glyph(rng) for _ in range(n_paths)]


def _time(label: str, call: Callable[[], object], policy: Policy) -> Contender:
    call()  # compile or load the kernels outside the timing
    contender = Contender(label, call)
    time_round_robin([contender], policy)
    return contender


def _on_one_thread(call: Callable[[], object]) -> Callable[[], object]:
    def run() -> object:
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            return call()
        finally:
            numba.set_num_threads(threads)
    return run


def run_svg(plan: SvgPlan, log: Callable[[str], None] = print) -> dict:
    """Time parsing and writing of the glyph corpus; return the results as a dict."""
    log(f"svg: generating {plan.n_paths} glyph-like paths")
    corpus = glyph_corpus(plan.n_paths)
    n_bytes = sum(len(d) for d in corpus)   # ASCII: characters are bytes
    load_before = load_average()
    runs = []
    parsed = parse_paths(corpus)
    for label, call in (("parse:parse_paths", lambda: parse_paths(corpus)),
                        ("parse:parse_paths:1thread",
                         _on_one_thread(lambda: parse_paths(corpus)))):
        log(f"svg: {label}")
        c = _time(label, call, plan.policy)
        runs.append({"label": label, "seconds": c.best,
                     "seconds_median": float(np.median(c.samples)), "repeats": len(c.samples),
                     "number": c.number, "bytes": n_bytes, "mb_per_s": n_bytes / c.best / 1e6,
                     "segments_per_s": parsed.degree.shape[0] / c.best})
        gc.collect()
    for precision in (6, None):
        label = f"write:precision={precision}"
        log(f"svg: {label}")
        c = _time(label, lambda precision=precision: write_paths(parsed, precision=precision),
                  plan.policy)
        written = c.last
        out_bytes = sum(len(d) for d in written)
        reread = parse_paths(written)
        if precision is None:
            reads_back = reread == parsed
        else:
            scale = max(1.0, float(np.abs(parsed.controls).max(initial=0.0)))
            reads_back = bool(np.allclose(reread.controls, parsed.controls, rtol=0,
                                          atol=10 * scale * 10.0 ** -precision))
        runs.append({"label": label, "seconds": c.best,
                     "seconds_median": float(np.median(c.samples)), "repeats": len(c.samples),
                     "number": c.number, "bytes": out_bytes,
                     "mb_per_s": out_bytes / c.best / 1e6,
                     "segments_per_s": parsed.degree.shape[0] / c.best,
                     "bytes_over_input": out_bytes / n_bytes, "reads_back": reads_back})
        gc.collect()
    degrees = np.bincount(parsed.degree, minlength=4)
    return {
        "workload": {"name": f"glyphs-{plan.n_paths}", "paths": plan.n_paths,
                     "bytes": n_bytes, "subpaths": int(parsed.closed.shape[0]),
                     "segments": int(parsed.degree.shape[0]),
                     "segments_by_degree": {"1": int(degrees[1]), "2": int(degrees[2]),
                                            "3": int(degrees[3])},
                     "seed": SEED, "load_average_before": load_before,
                     "load_average_after": load_average()},
        "runs": runs,
    }


def evaluate_svg_targets(svg: dict) -> list[dict]:
    """Return the issue-4 targets with their value from this run and verdict."""
    runs = {r["label"]: r for r in svg["runs"]}
    value = runs["parse:parse_paths"]["mb_per_s"]
    return [{"key": "parse_throughput", "description": "parse_paths throughput (MB/s)",
             "workload": svg["workload"]["name"], "value": value, "op": ">=",
             "limit": PARSE_TARGET_MB_S, "unit": "MB/s", "met": value >= PARSE_TARGET_MB_S}]


def print_svg_summary(result: dict) -> None:
    """Print the SVG suite: one line per contender, then the targets."""
    w = result["svg"]["workload"]
    m = result["machine"]
    print(f"rnsca svg benchmarks {result['created']}{'  (QUICK)' if result['quick'] else ''}: "
          f"{m['cpu_model']}, {m['cpus_usable']} usable cores; {w['name']}: "
          f"{w['bytes'] / 1e6:.1f} MB, {w['segments']:,} segments")
    for r in result["svg"]["runs"]:
        extra = "" if "reads_back" not in r else (
            f", {r['bytes_over_input']:.2f}x input size, reads back: {r['reads_back']}")
        print(f"  {r['label']:<28} {r['seconds'] * 1e3:9.2f} ms  {r['mb_per_s']:8.1f} MB/s"
              f"  {r['segments_per_s'] / 1e6:6.2f}M segments/s{extra}")
    print("Issue 4 targets")
    for t in result["targets"]:
        print(f"  {t['description']}: {t['value']:.1f} {t['op']} {t['limit']}: "
              f"{'met' if t['met'] else 'NOT met'}")
