"""The printed summaries of the benchmark suites (rich tables)."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from benchmarks.bench_segments import SWEEP_N

__all__ = ["make_console", "print_summary", "print_geometry_summary"]


def make_console() -> Console:
    """Return a console that does not squash tables when output is not a terminal."""
    console = Console()
    if not console.is_terminal:
        console = Console(width=160)
    return console


def _seconds(v: float | None) -> str:
    if v is None:
        return "-"
    if v < 1e-3:
        return f"{v * 1e6:.1f} µs"
    if v < 1.0:
        return f"{v * 1e3:.2f} ms"
    return f"{v:.3f} s"


def _x(v: float | None, digits: int = 2) -> str:
    return "-" if v is None else f"{v:.{digits}f}x"


def _rate(v: float | None) -> str:
    return "-" if v is None else f"{v / 1e6:.2f}"


def _size(n: int) -> str:
    return f"{n // 1_000_000}M" if n >= 1_000_000 and n % 1_000_000 == 0 else (
        f"{n // 1000}k" if n >= 1000 and n % 1000 == 0 else str(n))


def _figure5_table(workloads: list[dict]) -> Table:
    uniform = [w for w in workloads if w["workload"]["family"] == "uniform"]
    sizes = [w["workload"]["n"] for w in uniform]
    labels: list[str] = []
    for w in uniform:
        for r in w["runs"]:
            if r["label"] not in labels:
                labels.append(r["label"])
    table = Table(title="Uniform sets (paper, Table 2 / Figure 5): best time per call")
    table.add_column("contender")
    for n in sizes:
        table.add_column(_size(n), justify="right")
    for label in labels:
        cells = []
        for w in uniform:
            run = next((r for r in w["runs"] if r["label"] == label), None)
            if run is None:
                cells.append("")
            else:
                cells.append(_seconds(run["seconds"]) + ("" if run["measured"] else " (ext)"))
        table.add_row(label, *cells)
    return table


def _workload_table(w: dict) -> Table:
    info = w["workload"]
    level0 = info.get("level0", {})
    table = Table(title=(f"{info['name']}: window {info['window']}; level 0: "
                         f"{level0.get('inside', 0):.0%} inside, "
                         f"{level0.get('rejected', 0):.0%} rejected, "
                         f"{level0.get('ambiguous', 0):.0%} ambiguous; load "
                         f"{info.get('load_average_before')} -> {info.get('load_average_after')}"))
    for col in ("contender", "time", "Mseg/s", "t/shapely", "t/CS", "t/floor", "peak mem",
                "intersections", "decided L0-1", "pieces"):
        table.add_column(col, justify="left" if col == "contender" else "right")
    for r in w["runs"]:
        ratio = r["time_ratio"]
        stats = r["stats"] or {}
        table.add_row(
            r["label"] + ("" if r["measured"] else " (extrapolated)"),
            _seconds(r["seconds"]), _rate(r["segments_per_s"]),
            _x(ratio["shapely_clip_by_rect"], 3), _x(ratio["numba_cohen_sutherland"]),
            _x(ratio["copy_floor"]), _x(r["peak_extra_ratio"]),
            "-" if not stats else f"{stats['intersections']:,}",
            "-" if not stats else f"{stats['decided_shallow_fraction']:.1%}",
            "-" if r["pieces_out"] is None else f"{r['pieces_out']:,}")
    for s in w.get("skipped", []):
        table.add_row(s["label"], f"skipped: {s['reason']}", *[""] * 8)
    return table


def _numba_twin(label: str) -> str:
    return "numba:" + label.split(":", 1)[1]


def _device_table(workloads: list[dict], twin_of=_numba_twin) -> Table | None:
    """Return the OpenCL runs' split: kernels, host-device transfers, host (or None).

    `twin_of` names the Numba run each OpenCL run is compared with.
    """
    rows = [(w["workload"]["name"], r) for w in workloads for r in w["runs"]
            if r.get("device")]
    if not rows:
        return None
    device = rows[0][1]["device"]
    table = Table(title=f"OpenCL on {device['device']} ({device['precision']}): where the "
                        "time of one more (profiled) call goes")
    for col in ("workload", "contender", "best time", "t/numba", "profiled call", "kernels",
                "transfers", "host", "MB up", "MB down"):
        table.add_column(col, justify="left" if col in ("workload", "contender") else "right")
    by_label = {(w["workload"]["name"], r["label"]): r for w in workloads for r in w["runs"]}
    for name, r in rows:
        d = r["device"]
        twin = by_label.get((name, twin_of(r["label"])))
        table.add_row(name, r["label"], _seconds(r["seconds"]),
                      _x(r["seconds"] / twin["seconds"] if twin else None),
                      _seconds(d["call_seconds"]), _seconds(d["kernel_seconds"]),
                      _seconds(d["transfer_seconds"]), _seconds(d["host_seconds"]),
                      f"{d['bytes_to_device'] / 1e6:.1f}", f"{d['bytes_from_device'] / 1e6:.1f}")
    return table


def _sweep_table(sweeps: list[dict]) -> Table:
    table = Table(title='n sweep: rnsca on numba, fixed N vs n="auto" (time / auto time)')
    table.add_column("workload")
    table.add_column("mode")
    table.add_column("auto", justify="right")
    for n in SWEEP_N:
        table.add_column(f"N={n}", justify="right")
    table.add_column("best fixed", justify="right")
    for s in sweeps:
        for mode, summary in s["summary"].items():
            rows = {r["n_param"]: r for r in s["runs"] if r["mode"] == mode}
            table.add_row(s["workload"]["name"], mode, _seconds(summary["auto_seconds"]),
                          *[_x(rows[n]["ratio_to_auto"]) for n in SWEEP_N],
                          f"N={summary['best_fixed_n']}: auto is "
                          f"{summary['auto_over_best_fixed']:.2f}x")
    return table


def _startup_table(startup: dict) -> Table:
    table = Table(title="A fresh process reaches its first result (from spawn)")
    table.add_column("case")
    table.add_column("first result", justify="right")
    table.add_column("of which import", justify="right")
    table.add_column("note")
    pc = startup["project_cache"]
    table.add_row("first child (project cache)", _seconds(pc["first_result_seconds"]),
                  _seconds(pc["import_seconds"]),
                  f"{pc['cache_index_files_before']} cache index files seen before")
    for k, s in enumerate(startup["warm"]["samples"]):
        table.add_row(f"warm #{k + 1}", _seconds(s["first_result_seconds"]),
                      _seconds(s["import_seconds"]), "")
    if startup.get("empty_cache"):
        for key in ("cold", "second"):
            s = startup["empty_cache"][key]
            table.add_row(f"empty NUMBA_CACHE_DIR: {key}", _seconds(s["first_result_seconds"]),
                          _seconds(s["import_seconds"]),
                          "compiles every kernel" if key == "cold" else "loads that cache")
    table.add_row("python -c pass", _seconds(startup["interpreter"]["process_seconds"]), "-",
                  "whole process")
    return table


def _targets_table(targets: list[dict], title: str = "Issue targets (exact rnsca, numba)"
                   ) -> Table:
    table = Table(title=title)
    for col in ("target", "workload", "value", "limit", "met"):
        table.add_column(col, justify="left" if col in ("target", "workload") else "right")
    for t in targets:
        value = t["value"]
        if value is None:
            shown = "-"
        elif t["unit"] == "segments/s":
            shown = f"{value / 1e6:.1f}M/s"
        elif t["unit"] == "s":
            shown = f"{value:.2f} s"
        elif t["unit"] == "count":
            shown = f"{value:,}"
        else:
            shown = f"{value:.2f}x"
        if t["unit"] == "segments/s":
            limit = f"{t['op']} {t['limit'] / 1e6:.0f}M/s"
        elif t["unit"] == "count":
            limit = f"{t['op']} {t['limit']}"
        else:
            limit = f"{t['op']} {t['limit']:g}{' s' if t['unit'] == 's' else 'x'}"
        met = {True: "[green]met[/]", False: "[red]NOT met[/]", None: "n/a"}[t["met"]]
        table.add_row(t["description"] + (" *" if t.get("note") else ""), t["workload"],
                      shown, limit, met)
    return table


def print_summary(result: dict, console: Console | None = None) -> None:
    """Print the run's tables: Figure 5 matrix, large and shaped sets, sweep, startup, targets."""
    console = console or make_console()
    m = result["machine"]
    console.print(f"[bold]rnsca segment benchmarks[/] {result['created']}"
                  f"{'  (QUICK)' if result['quick'] else ''}: {m['cpu_model']}, "
                  f"{m['cpus_usable']} usable cores, numba {m['versions']['numba']} "
                  f"({m['numba_threads']} threads, {m['numba_threading_layer']}), "
                  f"load {m['load_average_at_start']} -> {result['load_average_at_end']}")
    if result.get("rnsca_changed_during_run"):
        console.print("[bold red]rnsca/ was edited during this run; the children of the "
                      "startup measurement may have run other code than this process.[/]")
    workloads = result["workloads"]
    console.print(_figure5_table(workloads))
    largest_uniform = max((w["workload"]["n"] for w in workloads
                           if w["workload"]["family"] == "uniform"), default=0)
    for w in workloads:
        info = w["workload"]
        if info["family"] != "uniform" or info["n"] >= min(1_000_000, largest_uniform):
            console.print(_workload_table(w))
    device = _device_table(workloads)
    if device is not None:
        console.print(device)
    if result["n_sweep"]:
        console.print(_sweep_table(result["n_sweep"]))
    console.print(_startup_table(result["startup"]))
    console.print(_targets_table(result["targets"]))
    for t in result["targets"]:
        if t.get("note"):
            console.print(f"* {t['key']}: {t['note']}")
    console.print(f"Results: {result['paths']['json']}\nFigure:  {result['paths']['figure']}")


# --------------------------------------------------------------------------- geometry suite


def _faster(ratio: float | None) -> str:
    """Return a speed-up (reference time / this time) from a time ratio (this / reference)."""
    return "-" if not ratio else f"{1.0 / ratio:.2f}x"


def _per_level(stats: dict | None) -> str:
    levels = list((stats or {}).get("runs_decided_per_level") or ())
    while levels and levels[-1] == 0:
        levels.pop()
    if not levels:
        return "-"
    shown = " ".join(f"{v:,}" for v in levels[:6])
    return shown + (" ..." if len(levels) > 6 else "")


def _geometry_table(w: dict, title: str) -> Table:
    table = Table(title=title)
    for col in ("contender", "time", "Mcoord/s", "vs clip_by_rect", "vs CS", "geoms out",
                "coords out", "invalid", "measure vs ref", "runs decided per level"):
        table.add_column(col, justify="left" if col in ("contender", "runs decided per level")
                         else "right")
    for r in w["runs"]:
        out = r["output"]
        rel = out["relative_difference"]
        table.add_row(
            r["label"], _seconds(r["seconds"]), _rate(r["coords_per_s"]),
            _faster(r["time_ratio"]["shapely_clip_by_rect"]),
            _faster(r["time_ratio"]["segments_cohen_sutherland"]),
            f"{out['geometries']:,}", f"{out['coords']:,}",
            "-" if out["invalid"] is None else f"{out['invalid']:,}",
            "-" if rel is None else f"{rel:.1e} ({out['sources_differing']} differ)",
            _per_level(r["stats"]))
    return table


def _geojson_table(g: dict) -> Table:
    info = g["workload"]
    table = Table(title=(f"{info['name']}: {info['bytes_in'] / 1e6:.1f} MB, "
                         f"{info['features_in']:,} features, window {info['window']}; load "
                         f"{info.get('load_average_before')} -> "
                         f"{info.get('load_average_after')}"))
    labels = list(g["pipelines"])
    table.add_column("stage")
    for label in labels:
        table.add_column(f"{label}: time", justify="right")
        table.add_column("MB/s", justify="right")
        table.add_column("share", justify="right")
    for stage in ("parse", "clip", "serialize"):
        cells = []
        for label in labels:
            p = g["pipelines"][label]
            s = p["stages"][stage]
            cells += [_seconds(s["seconds"]), f"{s['mb_per_s']:.1f}",
                      f"{s['seconds'] / p['total_seconds']:.0%}"]
        table.add_row(stage, *cells)
    steps = list(g["pipelines"][labels[0]]["clip_steps"])  # in the order they ran
    for step in steps:
        cells = []
        for label in labels:
            value = g["pipelines"][label]["clip_steps"].get(step)
            cells += [_seconds(value), "", ""]
        table.add_row(f"  clip step: {step}", *cells)
    cells = []
    for label in labels:
        p = g["pipelines"][label]
        cells += [_x(p["clip_over_parse_and_serialize"]),
                  f"{p['features_out']:,} features out", f"{p['bytes_out'] / 1e6:.1f} MB"]
    table.add_row("clip / (parse + serialize)", *cells)
    return table


def print_geometry_summary(result: dict, console: Console | None = None) -> None:
    """Print the geometry suite: curves per window, polygons, GeoJSON stages, targets."""
    console = console or make_console()
    m = result["machine"]
    console.print(f"[bold]rnsca geometry benchmarks[/] {result['created']}"
                  f"{'  (QUICK)' if result['quick'] else ''}: {m['cpu_model']}, "
                  f"{m['cpus_usable']} usable cores, numba {m['versions']['numba']} "
                  f"({m['numba_threads']} threads, {m['numba_threading_layer']}), "
                  f"load {m['load_average_at_start']} -> {result['load_average_at_end']}")
    if result.get("rnsca_changed_during_run"):
        console.print("[bold red]rnsca/ was edited during this run.[/]")
    for w in result["curves"]:
        info = w["workload"]
        level0 = info["segments_level0"]
        console.print(_geometry_table(w, (
            f"{info['name']}: {info['geometries']} lines, {info['coords']:,} vertices, window "
            f"{[round(v, 2) for v in info['window']]}; {info['vertices_inside']:.1%} of "
            f"vertices inside; segments at level 0: {level0['inside']:.1%} inside, "
            f"{level0['rejected']:.1%} rejected, {level0['ambiguous']:.1%} ambiguous; load "
            f"{info.get('load_average_before')} -> {info.get('load_average_after')}")))
    info = result["polygons"]["workload"]
    bbox = info["bbox_level0"]
    console.print(_geometry_table(result["polygons"], (
        f"{info['name']}: {info['coords']:,} vertices in {info['rings']:,} rings, window "
        f"{info['window']}; bounding boxes {bbox['inside']:.0%} inside, "
        f"{bbox['outside']:.0%} outside, {bbox['crossing']:.0%} crossing; "
        f"{info['input_invalid']} invalid inputs; load {info.get('load_average_before')} -> "
        f"{info.get('load_average_after')}")))
    device = _device_table([*result["curves"], result["polygons"]],
                           {"opencl:clip_ragged": "rnsca:clip_ragged",
                            "opencl:segments:rnsca": "segments:rnsca"}.get)
    if device is not None:
        console.print(device)
    console.print(_geojson_table(result["geojson"]))
    console.print(_targets_table(result["targets"], "Issue 3 targets (rnsca.clip_ragged, "
                                 "defaults; ratios from this run)"))
    console.print(f"Results: {result['paths']['json']}")
