"""How a cold start's warm-up is scheduled: children start beside the first step, in order.

The child processes are stood in for by threads (`compile_step` recorded, not run), so the
test sees the order the runner starts and loads steps in, which a real cold start (minutes
of compiling, `benchmarks.coldstart`) shows only in its log.
"""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

from service import runner as runner_module
from service.runner import ClipRunner
from service.warmup import Step


def _cold_warm_up(monkeypatch, steps, endpoints, processes, child_seconds):
    """Warm up with `steps`, the first one slow (a cold cache); return the event log."""
    events: list[tuple[str, str]] = []
    lock = threading.Lock()

    def record(kind: str, name: str) -> None:
        with lock:
            events.append((kind, name))

    def compile_step(name: str) -> str:  # what a child process does, in a thread
        record("child starts", name)
        time.sleep(child_seconds[name])
        record("child done", name)
        return name

    def run(name: str):
        def step() -> None:
            if name == steps[0]:
                time.sleep(1.0)  # compiling: longer than COLD_SECONDS below
            record("loaded" if name != steps[0] else "first done", name)
        return step

    monkeypatch.setattr(runner_module, "COLD_SECONDS", 0.2)
    monkeypatch.setattr(runner_module, "_jit_disabled", lambda: False)
    monkeypatch.setattr(runner_module, "compile_step", compile_step)
    monkeypatch.setattr(runner_module, "ProcessPoolExecutor",
                        lambda max_workers, mp_context: ThreadPoolExecutor(max_workers))
    made = [Step(name, run(name), NEEDS.get(name, ())) for name in steps]
    clip_runner = ClipRunner(threads=1, time_limit=5.0)
    clip_runner.warm_up(made, endpoints, processes)
    assert clip_runner.ready.is_set()
    return events, clip_runner


NEEDS = {"geojson": ("lines", "polygons")}
ORDER = ["segments", "lines", "polygons", "geojson", "svg"]


def test_children_start_beside_the_first_step_and_take_steps_whose_needs_are_compiled(
        monkeypatch):
    endpoints = {"segments": ("segments",), "geojson": ("lines", "polygons", "geojson"),
                 "svg": ("svg",)}
    events, clip_runner = _cold_warm_up(
        monkeypatch, ORDER, endpoints, processes=2,
        child_seconds={"lines": 0.3, "polygons": 1.2, "geojson": 0.1, "svg": 0.3})
    started = [name for kind, name in events if kind == "child starts"]
    # The first two children start while the first step still compiles.
    assert started[:2] == ["lines", "polygons"]
    assert events.index(("child starts", "lines")) < events.index(("first done", "segments"))
    # When lines is done, polygons is not: geojson cannot start, so svg does (no child
    # waits on another's lock while a step it could compile is left).
    assert started[2] == "svg"
    assert events.index(("child starts", "geojson")) > events.index(("child done", "polygons"))
    # Each step is loaded here once its child is done, never before the first step.
    for name in ORDER[1:]:
        assert events.index(("loaded", name)) > events.index(("child done", name))
        assert events.index(("loaded", name)) > events.index(("first done", "segments"))
    assert clip_runner.served == frozenset(endpoints)


def test_a_warm_cache_runs_every_step_here_in_order(monkeypatch):
    monkeypatch.setattr(runner_module, "COLD_SECONDS", 5.0)
    order: list[str] = []
    steps = [Step(name, lambda name=name: order.append(name), NEEDS.get(name, ()))
             for name in ORDER]
    monkeypatch.setattr(runner_module, "compile_step", lambda name: 1 / 0)  # never called
    clip_runner = ClipRunner(threads=1, time_limit=5.0)
    clip_runner.warm_up(steps, {"svg": ("svg",)}, processes=2)
    assert order == ORDER and clip_runner.ready.is_set()
