"""design.png: the objective over the varied parameters (or the Pareto plot), best marked."""
from __future__ import annotations

import numpy as np

from . import new_figure


def plot_design(result, path, *, units: dict[str, str]):
    """design.png of a :class:`tengfield.design.DesignResult`; ``units``: objective ->
    its unit (``tengfield.design.spec.OBJECTIVES``, passed in: plotting stays below the
    packages whose results it draws)."""
    spec = result.spec
    rows = result.rows
    keys = list(spec.vary)
    obj = spec.objective
    unit = units[obj]
    ok = [r for r in rows if r["status"] == "ok"]
    infeasible = [r for r in rows if r["status"] == "infeasible"]
    skipped = [r for r in rows if r["status"] == "skipped"]
    best = result.best
    band = f"{spec.aggregate} over {len(spec.band)} band point{'s' * (len(spec.band) > 1)}"
    pareto = len(spec.objectives) > 1
    fig = new_figure((11.0, 4.2) if pareto else (6.4, 4.6))
    axes = fig.subplots(1, 2) if pareto else [fig.subplots()]
    ax = axes[0]
    logx = keys[0] == "load_ohm"
    if len(keys) == 1:
        x = np.array([r["values"][keys[0]] for r in ok])
        y = np.array([r["objective"] for r in ok])
        e = np.array([r["objective_error"] for r in ok])
        order = np.argsort(x)
        ax.errorbar(x[order], y[order], yerr=e[order], fmt="o-", ms=3, lw=0.8, capsize=2,
                    label="feasible")
        for group, marker, label in ((infeasible, "x", spec.require + " not met"),
                                     (skipped, "+", "skipped")):
            if group:
                ax.plot([r["values"][keys[0]] for r in group], [0.0] * len(group), marker,
                        color="0.5" if marker == "x" else "C3", label=label)
        if best is not None:
            ax.plot(best["values"][keys[0]], best["objective"], "*", ms=16, color="C1",
                    mec="k", label="best")
        ax.set_xlabel(keys[0])
        ax.set_ylabel(f"{obj} [{unit}]")
        if logx:
            ax.set_xscale("log")
    else:
        kx, ky = keys[0], keys[1]
        if ok:
            sc = ax.scatter([r["values"][kx] for r in ok], [r["values"][ky] for r in ok],
                            c=[r["objective"] for r in ok], s=22, cmap="viridis",
                            edgecolors="none", label="feasible")
            fig.colorbar(sc, ax=ax, label=f"{obj} [{unit}]")
        for group, marker, label in ((infeasible, "x", spec.require + " not met"),
                                     (skipped, "+", "skipped")):
            if group:
                ax.plot([r["values"][kx] for r in group], [r["values"][ky] for r in group],
                        marker, color="0.55" if marker == "x" else "C3", ms=5, label=label)
        if best is not None:
            ax.plot(best["values"][kx], best["values"][ky], "*", ms=18, color="C1", mec="k",
                    label="best")
        ax.set_xlabel(kx)
        ax.set_ylabel(ky)
        if logx:
            ax.set_xscale("log")
        if ky == "load_ohm":
            ax.set_yscale("log")
    ax.set_title(f"{obj}, {band}" + (f" ({len(keys) - 2} more varied)" if len(keys) > 2 else ""),
                 fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    if pareto:
        a, b = spec.objectives[:2]
        ax2 = axes[1]
        xa = [r["objectives"][a]["value"] for r in ok]
        yb = [r["objectives"][b]["value"] for r in ok]
        ax2.plot(xa, yb, "o", ms=3, color="C0", alpha=0.6, label="feasible")
        front = sorted(result.pareto(), key=lambda i: rows[i]["objectives"][a]["value"])
        ax2.plot([rows[i]["objectives"][a]["value"] for i in front],
                 [rows[i]["objectives"][b]["value"] for i in front], "s-", ms=4, color="C2",
                 label="Pareto front")
        if best is not None:
            ax2.plot(best["objectives"][a]["value"], best["objectives"][b]["value"], "*",
                     ms=16, color="C1", mec="k", label=f"best ({a})")
        ax2.set_xlabel(f"{a} [{units[a]}]")
        ax2.set_ylabel(f"{b} [{units[b]}]")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7)
        ax2.set_title("Pareto plot", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path
