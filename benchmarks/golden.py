"""Hashes of every segment output, to show a change leaves the results bit for bit as they were.

Usage::

    python -m benchmarks.golden save before.json    # on the old revision
    python -m benchmarks.golden check before.json   # on the new one: which outputs differ

For ten sets (the benchmark families at 200k-1M segments and adversarial ones: integer
grids on the window's edges, ulp offsets, coordinates from 1e-20 to 1e20, points, segments
1e16 long, subnormal scales), every method, both modes where they differ, and N in
{auto, 2, 8} for RNSCA, it hashes the pieces, sources, intervals and stats of
`rnsca.clip_segments` (SHA-256, first 16 hex digits, with the piece count).
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Iterator

import numpy as np

import rnsca
from benchmarks import datasets as D

__all__ = ["inputs", "hashes", "main"]

METHODS = ("rnsca", "cohen_sutherland", "liang_barsky", "nicholl_lee_nicholl", "midpoint")


def inputs() -> Iterator[tuple[str, np.ndarray, tuple[float, float, float, float]]]:
    """Yield (name, segments, window) for every set, seeded."""
    rng = np.random.default_rng(7)
    grid = (0.0, 0.0, 10.0, 10.0)
    yield "uniform-1M", D.uniform_segments(1_000_000), D.UNIFORM_WINDOW
    yield "outside-200k", D.uniform_segments(200_000), D.OUTSIDE_WINDOW
    yield "inside-200k", D.uniform_segments(200_000), D.INSIDE_WINDOW
    yield "long-200k", D.long_segments(200_000), D.LONG_WINDOW
    yield "grid", rng.integers(-3, 14, (100_000, 4)).astype(float), grid
    near = rng.integers(-3, 14, (100_000, 4)).astype(float)
    yield "grid-eps", near + rng.choice([0.0, 1e-15, -1e-15, 2.0**-40], (100_000, 4)), grid
    normal = rng.standard_normal((100_000, 4))
    yield "scales", normal * 10.0 ** rng.integers(-20, 20, (100_000, 4)), (-1.0, -1.0, 1.0, 1.0)
    yield "points", np.repeat(rng.random((50_000, 2)) * 10, 2, axis=0).reshape(-1, 4), grid
    yield "long-huge", rng.random((100_000, 4)) * 1e16 - 5e15, (0.0, 0.0, 1.0, 1.0)
    yield "tiny", rng.random((100_000, 4)) * 1e-300, (0.0, 0.0, 1e-300, 1e-300)


def hashes() -> dict[str, str]:
    """Return ``{"set/method/mode/n": "<hash> m=<pieces>"}`` for every configuration."""
    out = {}
    for name, segments, window in inputs():
        for method in METHODS:
            modes = ("exact", "approx") if method in ("rnsca", "midpoint") else ("exact",)
            for mode in modes:
                for n in (("auto", 2, 8) if method == "rnsca" else ("auto",)):
                    key = f"{name}/{method}/{mode}/{n}"
                    try:
                        r = rnsca.clip_segments(segments, window, method=method, mode=mode, n=n)
                    except ValueError as exc:
                        out[key] = repr(exc)
                        continue
                    digest = hashlib.sha256()
                    for array in (r.segments, r.source, r.t):
                        digest.update(np.ascontiguousarray(array).tobytes())
                    digest.update(repr(r.stats).encode())
                    out[key] = f"{digest.hexdigest()[:16]} m={len(r.source)}"
    return out


def main(argv: list[str] | None = None) -> int:
    """``save FILE`` or ``check FILE``; exit 1 when a check finds a difference."""
    command, path = argv if argv is not None else sys.argv[1:3]
    found = hashes()
    if command == "save":
        with open(path, "w") as f:
            json.dump(found, f, indent=0)
        print(f"{len(found)} hashes saved")
        return 0
    with open(path) as f:
        saved = json.load(f)
    differ = [key for key in saved if saved[key] != found.get(key)]
    print(f"{len(saved)} compared; {len(differ)} differ")
    for key in differ[:30]:
        print(f"  {key}: {saved[key]} -> {found.get(key)}")
    return 1 if differ else 0


if __name__ == "__main__":
    raise SystemExit(main())
