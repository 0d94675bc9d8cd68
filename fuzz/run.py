"""Run the fuzz targets under atheris, one process per target, one after the other.

Usage::

    python -m fuzz.run [--seconds N] [TARGET ...]     # fuzz (default: every target, 600 s)
    python -m fuzz.run --merge [TARGET ...]           # minimize new inputs into the corpus
    python -m fuzz.run --replay TARGET FILE ...       # rerun inputs without atheris

Each target runs in its own process with Numba's bounds checking on
(``NUMBA_BOUNDSCHECK=1``, its own kernel cache under ``.fuzz/numba-cache`` so the normal
cache is left alone), libFuzzer's ``-timeout=1`` (an input taking over a second is a
hang; one that does not reproduce in a fresh process is set aside as the machine's
doing, and fuzzing goes on) and ``-max_total_time``. It reads the committed corpus
``fuzz/corpus/<target>`` and writes the inputs it finds to ``.fuzz/corpus/<target>``;
a crash, hang or disagreement is written to ``.fuzz/findings/<target>/`` and the log
to ``.fuzz/logs/<target>.log`` (``.fuzz`` is ignored by git). The exit status is 1 if
any target had a finding. ``--merge`` keeps, of the committed and the new inputs, the
smallest set that reaches the same coverage (libFuzzer's ``-merge=1``), in
``fuzz/corpus/<target>``.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

from fuzz import TARGETS

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "fuzz" / "corpus"
DICTIONARIES = ROOT / "fuzz" / "dictionaries"
WORK = ROOT / ".fuzz"

#: Modules atheris must not instrument: Numba compiles their functions from the
#: bytecode, which instrumentation would change. Their coverage is not measured.
#: atheris excludes modules by exact name, so every kernel module is listed.
COMPILED = ["rnsca.kernels", "rnsca.io.svgparse", "rnsca.io.svgwrite",
            "rnsca.io.msgpack_decode"] + sorted(
    f"rnsca.kernels.{path.stem}" for path in (ROOT / "rnsca" / "kernels").glob("*.py")
    if path.stem != "__init__")
#: Modules whose coverage guides the fuzzer (the references' included: their
#: branches are the grammar's states).
INSTRUMENTED = ["rnsca", "service", "fuzz"]
#: libFuzzer's memory limit; a process with Numba, Shapely and the app uses about 500.
RSS_LIMIT_MB = 3072
#: Seconds an input may take (libFuzzer's -timeout): more is a hang.
TIMEOUT = 1


def environment() -> dict[str, str]:
    """Return the environment of a target process: bounds checks, their own cache."""
    env = dict(os.environ)
    env["NUMBA_BOUNDSCHECK"] = "1"
    # One thread: the fuzzer uses one core, and the parallel kernels' hand-off to a
    # thread pool costs more than these small inputs on a busy machine.
    env["NUMBA_NUM_THREADS"] = "1"
    env["NUMBA_CACHE_DIR"] = str(WORK / "numba-cache")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return env


def libfuzzer_flags(target: str, module_max_len: int) -> list[str]:
    """Return the libFuzzer flags every run of `target` takes."""
    flags = [f"-max_len={module_max_len}", f"-timeout={TIMEOUT}", f"-rss_limit_mb={RSS_LIMIT_MB}",
             f"-artifact_prefix={WORK / 'findings' / target}{os.sep}"]
    dictionary = DICTIONARIES / f"{target}.dict"
    if dictionary.exists():
        flags.append(f"-dict={dictionary}")
    return flags


def _max_len(target: str) -> int:
    """Return the target's MAX_LEN without importing rnsca (read from its source)."""
    source = (ROOT / "fuzz" / f"{target}.py").read_text()
    return int(re.search(r"^MAX_LEN = ([0-9_]+)", source, re.M).group(1))


def _child(target: str, flags: list[str]) -> None:
    """Fuzz `target` in this process (the parent set the environment)."""
    import atheris

    with atheris.instrument_imports(include=INSTRUMENTED, exclude=COMPILED):
        module = importlib.import_module(f"fuzz.{target}")
    started = time.perf_counter()
    module.setup()
    # Each input's first run of a code path loads compiled code (Numba's cache, lazily
    # unpickled constants): replay the committed corpus once so that this is not timed.
    for path in sorted((CORPUS / target).glob("*")):
        try:
            module.test_one_input(path.read_bytes())
        except Exception:   # noqa: BLE001 -- libFuzzer runs it again and reports it
            pass
    print(f"fuzz.run: {target} set up in {time.perf_counter() - started:.1f} s", flush=True)
    # libFuzzer reruns argv[0] for -merge=1: the wrapper `_run_child` wrote.
    atheris.Setup([str(_wrapper(target)), *flags],
                  _keeping_findings(target, module.test_one_input))
    atheris.Fuzz()


def _keeping_findings(target: str, test_one_input):
    """Return `test_one_input`, writing an input that raises to the findings first.

    libFuzzer writes the input of a crash too, but not when its timer's SIGALRM ends the
    process while the crash is being reported (seen with the app's threads running).
    """
    findings = WORK / "findings" / target

    def test(data: bytes) -> None:
        try:
            test_one_input(data)
        except BaseException:
            findings.mkdir(parents=True, exist_ok=True)
            (findings / f"raised-{hashlib.sha1(data).hexdigest()}").write_bytes(data)
            raise

    return test


def _wrapper(target: str) -> Path:
    """Return the path of the script that starts a child process of `target`."""
    return WORK / "bin" / target


def _run_child(target: str, arguments: list[str], log: Path) -> int:
    """Run `target` in a new process with libFuzzer `arguments`; return its status.

    The process is started through a small script (`_wrapper`), which libFuzzer also
    runs for the inner processes of a merge (it reruns its own ``argv[0]``).
    """
    (WORK / "findings" / target).mkdir(parents=True, exist_ok=True)
    log.parent.mkdir(parents=True, exist_ok=True)
    wrapper = _wrapper(target)
    wrapper.parent.mkdir(parents=True, exist_ok=True)
    wrapper.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m fuzz.run --child {target} '
                       f'-- "$@"\n')
    wrapper.chmod(0o755)
    command = [str(wrapper), *arguments, *libfuzzer_flags(target, _max_len(target))]
    with log.open("w") as out:
        out.write(" ".join(command) + "\n")
        out.flush()
        return subprocess.call(command, cwd=ROOT, env=environment(), stdout=out,
                               stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)


def _summary(log: Path) -> dict[str, str]:
    """Return the figures of a libFuzzer log: executions, speed, coverage, corpus."""
    text = log.read_text(errors="replace")
    figures = dict(re.findall(r"^stat::(\w+):\s*(\S+)", text, re.M))
    progress = re.findall(r"^#(\d+)\s+\w+\s+cov: (\d+) ft: (\d+) corp: (\S+)", text, re.M)
    if progress:
        figures.update(zip(("inputs", "cov", "ft", "corpus"), progress[-1], strict=True))
    return figures


def _reproducible_timeouts(target: str, files: list[Path]) -> list[Path]:
    """Return the timeout inputs that take over `TIMEOUT` s again, in a fresh process.

    Each is run three times after the target is set up; one that finishes in time every
    time was slowed by the machine (other processes), not by the input.
    """
    code = (f"import sys, time; from fuzz import {target} as t; t.setup()\n"
            "for name in sys.argv[1:]:\n"
            "    data = open(name, 'rb').read(); t.test_one_input(data); worst = 0.0\n"
            "    for _ in range(3):\n"
            "        s = time.perf_counter(); t.test_one_input(data)\n"
            "        worst = max(worst, time.perf_counter() - s)\n"
            "    print(name, worst)")
    out = subprocess.run([sys.executable, "-c", code, *map(str, files)], cwd=ROOT,
                         env=environment(), capture_output=True, text=True)
    if out.returncode != 0:   # it raised, or hung for good: a finding
        return files
    worst = dict(line.rsplit(" ", 1) for line in out.stdout.splitlines())
    return [path for path in files if float(worst.get(str(path), "inf")) > TIMEOUT]


def fuzz(targets: list[str], seconds: int) -> int:
    """Fuzz each target for `seconds`; return 1 if any had a finding, else 0.

    A timeout that does not reproduce (see `_reproducible_timeouts`) is set aside in
    ``.fuzz/findings/<target>/slowed/`` and fuzzing goes on for the time left.
    """
    failed = []
    for target in targets:
        work = WORK / "corpus" / target
        work.mkdir(parents=True, exist_ok=True)
        findings = WORK / "findings" / target
        print(f"fuzz.run: {target} for {seconds} s (logs: {WORK / 'logs'})", flush=True)
        started = time.perf_counter()
        left, round_ = seconds, 0
        while True:
            log = WORK / "logs" / f"{target}.log" if round_ == 0 else \
                WORK / "logs" / f"{target}.{round_}.log"
            before = set(findings.glob("*")) if findings.exists() else set()
            began = time.perf_counter()
            status = _run_child(target, [str(work), str(CORPUS / target),
                                         f"-max_total_time={left}", "-print_final_stats=1"],
                                log)
            figures = _summary(log)
            print(f"fuzz.run: {target}: status {status}, "
                  f"{time.perf_counter() - began:.0f} s, "
                  f"{figures.get('number_of_executed_units', '?')} executions, "
                  f"{figures.get('average_exec_per_sec', '?')} exec/s, "
                  f"cov {figures.get('cov', '?')} ft {figures.get('ft', '?')}, "
                  f"corpus {figures.get('corpus', '?')}", flush=True)
            new = sorted(set(findings.glob("*")) - before - {findings / "slowed"})
            left = seconds - int(time.perf_counter() - started)
            timeouts = [p for p in new if p.name.startswith("timeout-")]
            if status == 0 or not new or len(timeouts) < len(new) or \
                    _reproducible_timeouts(target, timeouts):
                break
            (findings / "slowed").mkdir(exist_ok=True)
            for path in timeouts:
                path.rename(findings / "slowed" / path.name)
            print(f"fuzz.run: {target}: timeout did not reproduce (a busy machine); "
                  f"set aside, {left} s left", flush=True)
            status = 0
            if left < 10:
                break
            round_ += 1
        if status != 0:
            failed.append(target)
            lines = log.read_text(errors="replace").splitlines()
            print("\n".join(lines[-80:]), flush=True)
            print(f"fuzz.run: {target}: FINDING; inputs in {WORK / 'findings' / target}; "
                  f"reproduce: python -m fuzz.run --replay {target} FILE", flush=True)
    if failed:
        print(f"fuzz.run: findings in {', '.join(failed)}", flush=True)
        return 1
    print(f"fuzz.run: no findings in {', '.join(targets)}", flush=True)
    return 0


def merge(targets: list[str]) -> int:
    """Minimize the committed and the new inputs of each target into its corpus."""
    for target in targets:
        committed = CORPUS / target
        committed.mkdir(parents=True, exist_ok=True)
        found = WORK / "corpus" / target
        found.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as merged:
            status = _run_child(target, ["-merge=1", merged, str(committed), str(found)],
                                WORK / "logs" / f"{target}-merge.log")
            if status != 0 or not any(Path(merged).iterdir()):
                print(f"fuzz.run: merging {target} failed (status {status}); corpus kept")
                return 1
            shutil.rmtree(committed)
            shutil.copytree(merged, committed)
        size = sum(p.stat().st_size for p in committed.iterdir())
        print(f"fuzz.run: {target}: {len(list(committed.iterdir()))} inputs, {size} bytes")
    return 0


def replay(target: str, files: list[str]) -> int:
    """Run `files` through the target without atheris, printing each finding."""
    module = importlib.import_module(f"fuzz.{target}")
    module.setup()
    status = 0
    for name in files:
        data = Path(name).read_bytes()
        started = time.perf_counter()
        try:
            module.test_one_input(data)
        except Exception:
            status = 1
            print(f"{name}: {data[:200]!r}")
            traceback.print_exc()
        else:
            print(f"{name}: passed in {time.perf_counter() - started:.3f} s")
    return status


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--child"]:
        _child(argv[1], argv[3:])   # --child TARGET -- FLAGS...
        return 0
    parser = argparse.ArgumentParser(prog="python -m fuzz.run", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=int, default=600, help="per target (600)")
    parser.add_argument("--merge", action="store_true", help="minimize into the corpus")
    parser.add_argument("--replay", nargs="+", metavar=("TARGET", "FILE"),
                        help="run files through a target without atheris")
    parser.add_argument("targets", nargs="*", metavar="TARGET",
                        help=f"any of {', '.join(TARGETS)} (default: all)")
    args = parser.parse_args(argv)
    named = args.targets + args.replay[:1] if args.replay else args.targets
    unknown = sorted(set(named) - set(TARGETS))
    if unknown:
        parser.error(f"unknown target {unknown[0]!r}; the targets are {', '.join(TARGETS)}")
    if args.replay:
        return replay(args.replay[0], args.replay[1:])
    targets = args.targets or list(TARGETS)
    return merge(targets) if args.merge else fuzz(targets, args.seconds)


if __name__ == "__main__":
    sys.exit(main())
