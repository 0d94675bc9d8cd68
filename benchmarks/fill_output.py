"""Time ``fill_output="clean"`` against ``"raw"``: what the clean rings cost a fill clip.

Workloads: the curve benchmark's glyph page (`bench_curves.glyph_page`: glyph-like cubic
outlines, the window cutting through many of them), and, where the fonts are installed,
a line of real glyphs (DejaVu Sans, TrueType quadratics; tests/fonts.py) cut by a band
through their middle and by the issue's window. Each contender is called once (compiles
or loads the kernels), then timed round-robin, best of the repeats, on the threads Numba
has (``NUMBA_NUM_THREADS``).

Run: ``python -m benchmarks.fill_output [--glyphs N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import time

import numba

from benchmarks.bench_curves import glyph_page
from rnsca import clip_paths, parse_paths


def _best(calls: dict, repeats: int) -> dict[str, float]:
    for call in calls.values():
        call()  # compile, or load from the cache
    best = {name: float("inf") for name in calls}
    for _ in range(repeats):
        for name, call in calls.items():
            start = time.perf_counter()
            call()
            best[name] = min(best[name], time.perf_counter() - start)
    return best


def _font_line():
    try:
        from tests.fonts import load_glyph
    except ImportError:
        return None
    try:
        glyphs = [load_glyph("dejavu-sans", c) for c in "aegoBS&@8éçÅ" * 10]
    except Exception:  # no font or no fontTools here: that workload is left out
        return None
    return parse_paths([g.d for g in glyphs])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--glyphs", type=int, default=3000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    workloads = []
    page, window = glyph_page(args.glyphs)
    workloads.append((f"glyph page ({args.glyphs} glyphs, {page.degree.shape[0]:,} cubics)",
                      page, window))
    line = _font_line()
    if line is not None:
        workloads.append(("DejaVu Sans x120, band y 500..1100 (the issue's window)", line,
                          (0.0, 500.0, 2000.0, 1100.0)))
        workloads.append(("DejaVu Sans x120, band y 600..640", line, (0.0, 600.0, 2000.0, 640.0)))
    print(f"threads: {numba.get_num_threads()}")
    for name, paths, win in workloads:
        for rule in ("nonzero", "evenodd"):
            calls = {output: (lambda output=output, paths=paths, win=win, rule=rule:
                              clip_paths(paths, win, fill=rule, fill_output=output))
                     for output in ("raw", "clean")}
            best = _best(calls, args.repeats)
            raw, clean = best["raw"], best["clean"]
            out = clip_paths(paths, win, fill=rule).paths
            print(f"{name}, {rule}: raw {raw * 1e3:8.2f} ms, clean {clean * 1e3:8.2f} ms "
                  f"(x{clean / raw:.2f}, +{(clean - raw) * 1e3:.2f} ms; "
                  f"{out.closed.shape[0]:,} rings)")


if __name__ == "__main__":
    main()
