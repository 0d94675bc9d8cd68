"""The plots of `benchmarks.paper`: Table 2 times, early decisions by N, intersections."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

__all__ = ["draw_table2", "draw_decided", "draw_intersections"]

_TABLE2_STYLE = {
    "rnsca:exact": dict(color="#d62728", lw=2.2, marker="o"),
    "rnsca:approx": dict(color="#ff7f0e", lw=1.8, marker="o", ls="--"),
    "cohen_sutherland": dict(color="#1f77b4", lw=1.8, marker="s"),
}
_FAMILY_STYLE = {
    "uniform": dict(color="#d62728", marker="o"),
    "mostly_outside": dict(color="#1f77b4", marker="s"),
    "mostly_inside": dict(color="#2ca02c", marker="^"),
    "long_segments": dict(color="#9467bd", marker="v"),
}


def _save(fig, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def draw_table2(table2: list[dict], path: Path, note: str = "") -> Path:
    """Draw time against size (log-log) per contender, and the CS / RNSCA ratio; return `path`."""
    sizes = [w["workload"]["n"] for w in table2]
    fig, (ax_t, ax_r) = plt.subplots(1, 2, figsize=(13, 5.2))
    for label, style in _TABLE2_STYLE.items():
        ax_t.plot(sizes, [w["runs"][label]["seconds"] for w in table2], label=label,
                  markersize=5, **style)
    for label in ("rnsca:exact", "rnsca:approx"):
        ax_r.plot(sizes, [w["cs_over_rnsca"][label] for w in table2],
                  label=f"Cohen–Sutherland / {label}", markersize=5, **_TABLE2_STYLE[label])
    ax_r.axhline(1.0, color="black", lw=0.8)
    ax_t.set(xscale="log", yscale="log", xlabel="segments", ylabel="seconds (best of repeats)",
             title="Time per call")
    ax_r.set(xscale="log", yscale="log", xlabel="segments",
             ylabel="CS time / RNSCA time (> 1: RNSCA faster)",
             title="Cohen–Sutherland time over RNSCA time")
    for ax in (ax_t, ax_r):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("RNSCA against Cohen–Sutherland, uniform segments in [0,1000]², window "
                 "[250,750]² (paper, Table 2; Numba backend)"
                 + (f"\n{note}" if note else ""), fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def draw_decided(decided: list[dict], path: Path, note: str = "",
                 claim: tuple[float, float] | None = None) -> Path:
    """Draw the shallow-decided fraction against N per family, approx and exact; return `path`.

    Fixed N on a log2 axis; ``"auto"`` as a separate hollow marker at the right.
    """
    modes = ("approx", "exact")
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2), sharey=True)
    fixed = sorted({r["n_param"] for d in decided for r in d["runs"]
                    if r["n_param"] != "auto"})
    auto_x = (max(fixed) if fixed else 64) * 2.0
    for ax, mode in zip(axes, modes, strict=True):
        if claim is not None:
            ax.axhspan(claim[0], claim[1], color="#bbbbbb", alpha=0.35,
                       label="paper: 70-80%")
        for d in decided:
            if d["mode"] != mode:
                continue
            family = d["workload"]["family"]
            style = _FAMILY_STYLE.get(family, {})
            runs = [r for r in d["runs"] if r["n_param"] != "auto"]
            auto = [r for r in d["runs"] if r["n_param"] == "auto"]
            ax.plot([r["n_param"] for r in runs],
                    [r["decided_shallow_fraction"] for r in runs], label=family, lw=1.6,
                    markersize=5, **style)
            if auto:
                ax.plot([auto_x], [auto[0]["decided_shallow_fraction"]], ls="none",
                        marker=style.get("marker", "o"), mfc="white",
                        mec=style.get("color"), markersize=9, mew=1.8)
        ax.axvline(auto_x / 1.45, color="black", lw=0.6, ls=":")
        ax.set_xscale("log", base=2)
        ticks = [*fixed, auto_x]
        ax.set_xticks(ticks, [*(str(v) for v in fixed), "auto"])
        ax.minorticks_off()
        n = decided[0]["workload"]["n"] if decided else 0
        ax.set(xlabel="N (pieces per subdivision)", ylim=(-0.02, 1.02),
               title=f"{mode} mode, {n:,} segments per family")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("decided fragments decided at levels 0-1")
    axes[0].legend(fontsize=8, loc="best")
    fig.suptitle("Fragments decided before deep refinement (hollow: n=\"auto\"; default "
                 "tolerance)" + (f"\n{note}" if note else ""), fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def draw_intersections(intersections: list[dict], path: Path, note: str = "") -> Path:
    """Draw intersections per input segment, grouped by family, one bar per method."""
    families = [w["workload"]["family"] for w in intersections]
    methods = list(intersections[0]["runs"]) if intersections else []
    fig, ax = plt.subplots(figsize=(13, 5.2))
    width = 0.8 / max(len(methods), 1)
    x = np.arange(len(families))
    colours = plt.get_cmap("tab10")
    for k, method in enumerate(methods):
        values = [w["runs"][method]["intersections_per_segment"] for w in intersections]
        bars = ax.bar(x + (k - (len(methods) - 1) / 2) * width, values, width, label=method,
                      color=colours(k))
        ax.bar_label(bars, fmt="%.2f", fontsize=6, rotation=90, padding=2)
    n = intersections[0]["workload"]["n"] if intersections else 0
    ax.set_xticks(x, families)
    ax.set(ylabel="intersections computed per input segment",
           title=f"Intersections per method ({n:,} segments per family)")
    ax.margins(y=0.15)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8, ncols=2)
    if note:
        fig.suptitle(note, fontsize=9)
    fig.tight_layout()
    return _save(fig, path)
