"""Figure 5 of the paper, redrawn: clipping time against input size, log-log."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

__all__ = ["draw_figure5"]

_STYLE = {
    "numba:rnsca:exact": dict(color="#d62728", lw=2.4, marker="o"),
    "numba:rnsca:approx": dict(color="#ff7f0e", lw=1.8, marker="o", ls="--"),
    "numba:cohen_sutherland": dict(color="#1f77b4", marker="s"),
    "numba:liang_barsky": dict(color="#2ca02c", marker="^"),
    "numba:nicholl_lee_nicholl": dict(color="#9467bd", marker="v"),
    "numba:midpoint:exact": dict(color="#8c564b", marker="D"),
    "numba:midpoint:approx": dict(color="#8c564b", marker="D", ls="--"),
    "shapely:clip_by_rect": dict(color="black", marker="x"),
    "shapely:intersection": dict(color="gray", marker="+"),
    "floor:copy": dict(color="#17becf", ls=":", lw=2.0),
    "part:validate": dict(color="#7f7f7f", ls="-.", lw=1.2),
}


def draw_figure5(workload_results: list[dict], path: Path, title_note: str = "") -> Path:
    """Draw time and throughput against input size for the uniform sets; return `path`.

    One line per contender. NumPy-backend lines are thin, dotted, in the colour of their
    Numba twin (they stop at the NumPy size limit), OpenCL lines dashed in the same
    colour; extrapolated points are drawn hollow.
    """
    series: dict[str, list[tuple[int, float, bool]]] = {}
    for wr in workload_results:
        if wr["workload"]["family"] != "uniform":
            continue
        for r in wr["runs"]:
            series.setdefault(r["label"], []).append((r["n"], r["seconds"], r["measured"]))
    fig, (ax_t, ax_r) = plt.subplots(1, 2, figsize=(15, 6))
    for label, points in sorted(series.items()):
        points.sort()
        xs = [p[0] for p in points]
        ts = [p[1] for p in points]
        style = dict(_STYLE.get(label, {}))
        if label.startswith("opencl:"):  # dashed, in the colour of the Numba twin
            twin = _STYLE.get("numba:" + label.split(":", 1)[1], {})
            style = dict(color=twin.get("color"), lw=1.2, ls="--", marker="x", alpha=0.8)
        style.setdefault("lw", 1.3)
        style.setdefault("markersize", 4)
        for ax, ys in ((ax_t, ts), (ax_r, [x / t for x, t in zip(xs, ts, strict=True)])):
            (line,) = ax.plot(xs, ys, label=label, **style)
            hollow = [(x, y) for (x, _, measured), y in zip(points, ys, strict=True)
                      if not measured]
            if hollow:
                ax.plot(*zip(*hollow, strict=True), ls="none", marker="o", mfc="white",
                        mec=line.get_color(), markersize=8)
    ax_t.set(xscale="log", yscale="log", xlabel="segments", ylabel="seconds (best of repeats)",
             title="Clipping time vs input size")
    ax_r.set(xscale="log", yscale="log", xlabel="segments", ylabel="segments per second",
             title="Throughput")
    for ax in (ax_t, ax_r):
        ax.grid(True, which="both", alpha=0.3)
    handles, labels = ax_t.get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="center right")
    fig.suptitle("Uniform random segments in [0,1000]², window [250,750]² (paper, Figure 5)"
                 + (f"\n{title_note}" if title_note else ""), fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.85, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
