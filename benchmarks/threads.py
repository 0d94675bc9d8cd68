"""Thread scaling of the segment core: one process per thread count, the call in stages.

Usage::

    python -m benchmarks.threads                     # 10M uniform, 1, 2, 4, ... cores
    python -m benchmarks.threads --n 1000000 --threads 1,2 --out /tmp/t

Each thread count runs in a fresh process with ``NUMBA_NUM_THREADS`` set (Numba reads it
once, at start), times `rnsca.clip_segments` (exact RNSCA, the paper's Table 2 set,
window [250, 750]^2) end to end, and then the stages of the Numba backend's one pass
one by one, each the best of `--repeats`:

``clip_fresh``
    The clipping kernel (`segments.clip_segment_blocks`), writing into fresh output
    arrays, as the call does: their pages are faulted in by the writes.
``clip_prefaulted``
    The same kernel into arrays already touched: the difference is the page faults.
``move``
    Moving the later chunks' rows up behind the first chunk's (`segments.move_rows`).
``check``
    The input check as a pass of its own (`rnsca.arrays.check_segment_values`), which
    the call no longer makes (it is fused into the clip): what fusing saved.
``read`` and ``copy``
    Memory references: summing the input once (one read of its bytes, in parallel), and
    copying the input into a preallocated array (NumPy, one thread).

The JSON (``threads-<UTC timestamp>.json`` in `--out`) holds the machine, the figures
per thread count and the speed-up over one thread.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.machine import describe_machine, load_average

__all__ = ["measure", "child"]

ROOT = Path(__file__).resolve().parent.parent


def _best(call, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def child(n: int, repeats: int) -> dict:
    """Time the call and its stages in this process (NUMBA_NUM_THREADS set by the parent)."""
    import numba
    import numpy as np
    from numba import prange

    import rnsca
    from benchmarks.datasets import UNIFORM_WINDOW, uniform_segments
    from rnsca.arrays import check_segment_values
    from rnsca.backends.numba_cpu import BLOCK_SIZE, core_options
    from rnsca.kernels import counters as C
    from rnsca.kernels import records as R
    from rnsca.kernels import segments as K
    from rnsca.options import SegmentOptions
    from rnsca.window import Window

    @numba.njit(parallel=True, cache=False)
    def read_all(a):
        total = 0.0
        for i in prange(a.shape[0]):
            total += a[i, 0] + a[i, 1] + a[i, 2] + a[i, 3]
        return total

    segments = uniform_segments(n)
    window = Window(*UNIFORM_WINDOW)
    bounds = R.Window(*UNIFORM_WINDOW)
    settings = core_options(SegmentOptions.resolve(window))
    n_blocks = -(-n // BLOCK_SIZE)
    threads = numba.get_num_threads()
    n_chunks = min(threads, n_blocks)

    def output():
        return K.SegmentOutput(
            np.empty((n, 4)), np.empty(n, dtype=np.int64), np.empty((n, 2)),
            np.empty(n_blocks, dtype=np.int64), np.empty(n_blocks, dtype=np.int64),
            np.zeros((n_blocks, C.WIDTH), dtype=np.int64))

    def clip(out):
        K.clip_segment_blocks(segments, bounds, settings, BLOCK_SIZE, n_chunks, out)

    def moves(out):
        plan, m = [], 0
        for chunk in range(n_chunks):
            first, last = K.chunk_blocks(chunk, n_chunks, n_blocks)
            count = int(out.block_count[first:last].sum())
            start = int(out.block_start[first]) if count else m
            plan.append((start, m, count))
            m += count
        return plan

    rnsca.clip_segments(segments, UNIFORM_WINDOW)  # compile or load everything first
    read_all(segments)
    call = _best(lambda: rnsca.clip_segments(segments, UNIFORM_WINDOW), repeats)
    clip_fresh = _best(lambda: clip(output()), repeats)
    touched = output()
    for array in (touched.pieces, touched.source, touched.t):
        array.fill(0)
    clip_prefaulted = _best(lambda: clip(touched), repeats)
    move = float("inf")
    for _ in range(repeats):
        out = output()
        clip(out)
        start = time.perf_counter()
        for source, to, count in moves(out):
            if source != to:
                K.move_rows(out, source, to, count)
        move = min(move, time.perf_counter() - start)
    check = _best(lambda: check_segment_values(segments), repeats)
    read = _best(lambda: read_all(segments), repeats)
    scratch = np.empty_like(segments)
    copy = _best(lambda: np.copyto(scratch, segments), repeats)
    return {"threads": threads, "n": n, "call_seconds": call, "clip_fresh_seconds": clip_fresh,
            "clip_prefaulted_seconds": clip_prefaulted, "move_seconds": move,
            "check_seconds": check, "read_seconds": read, "copy_seconds": copy,
            "segments_per_s": n / call}


def measure(n: int, thread_counts: list[int], repeats: int) -> list[dict]:
    """Run `child` in one fresh process per thread count; return their figures."""
    rows = []
    for threads in thread_counts:
        env = dict(os.environ, NUMBA_NUM_THREADS=str(threads))
        code = (f"import json; from benchmarks.threads import child; "
                f"print(json.dumps(child({n}, {repeats})))")
        done = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT,
                              capture_output=True, text=True, check=True)
        row = json.loads(done.stdout.strip().splitlines()[-1])
        rows.append(row)
        ms = {key: row[key] * 1e3 for key in row if key.endswith("_seconds")}
        print(f"{threads:3d} threads: call {ms['call_seconds']:8.1f} ms "
              f"({row['segments_per_s'] / 1e6:5.1f} M/s); clip {ms['clip_fresh_seconds']:7.1f}"
              f" (prefaulted {ms['clip_prefaulted_seconds']:.1f}), move "
              f"{ms['move_seconds']:.1f}, separate check {ms['check_seconds']:.1f}, "
              f"read {ms['read_seconds']:.1f}, copy {ms['copy_seconds']:.1f} ms", flush=True)
    one = next((r for r in rows if r["threads"] == 1), None)
    for row in rows:
        row["speedup_over_1"] = one["call_seconds"] / row["call_seconds"] if one else None
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=10_000_000)
    parser.add_argument("--threads", default=None,
                        help="comma-separated thread counts (default 1, 2, 4, ... up to the "
                             "cores)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    cores = os.cpu_count() or 1
    counts = ([int(t) for t in args.threads.split(",")] if args.threads else
              sorted({min(2 ** k, cores) for k in range(cores.bit_length() + 1)}))
    rows = measure(args.n, counts, args.repeats)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"threads-{stamp}.json"
    path.write_text(json.dumps({"machine": describe_machine(ROOT), "rows": rows,
                                "load_average_at_end": load_average()}, indent=2))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
