"""design.png: the objective over the varied parameters (readable units, error bars), the
best marked (and named when it sits on a bound of its range); with several objectives
also the Pareto plot of the first two."""
from __future__ import annotations

import numpy as np

from . import new_figure, save_figure
from ..scene.schema import SURFACE_CHARGE_KEY

#: [design.vary] key -> axis label (others: the key's name with its unit suffix)
KEY_LABELS = {
    "stroke_mm": "stroke Δh [mm]",
    "gap_mm": "stroke Δh [mm]",
    "ball_diameter_mm": "ball diameter d [mm]",
    "electrode_radius_mm": "electrode radius [mm]",
    "tube_inner_radius_mm": "tube inner radius [mm]",
    "tube_outer_radius_mm": "tube outer radius [mm]",
    "plate_thickness_mm": "plate thickness [mm]",
    SURFACE_CHARGE_KEY: "σ [µC/m²]",
    "ball_density_kg_per_m3": "ball density [kg/m³]",
    "load_ohm": "load R [Ω]",
}
_SUFFIXES = (("_uC_per_m2", "µC/m²"), ("_kg_per_m3", "kg/m³"), ("_mm", "mm"), ("_ohm", "Ω"))

def key_label(key: str) -> str:
    if key in KEY_LABELS:
        return KEY_LABELS[key]
    for suffix, unit in _SUFFIXES:
        if key.endswith(suffix):
            return f"{key[:-len(suffix)].replace('_', ' ')} [{unit}]"
    return key.replace("_", " ")


def plot_design(result, path, **options):
    """design.png: :func:`design_figure` saved to ``path``; returns the Figure."""
    fig = design_figure(result, **options)
    save_figure(fig, path, 110)
    return fig


def design_figure(result, *, units: dict[str, str], names: dict[str, str] | None = None,
                  scales: dict | None = None, on_bound=()):
    """The figure of a :class:`tengfield.design_study.DesignResult` (design.png). ``units``:
    objective -> its SI unit; ``names``: objective -> its words (the quantity table's); ``scales``: objective -> (label, factor) of the readable unit (value x factor;
    default the SI unit); ``on_bound``: [(key, "lower" | "upper", bound)] the best sits on
    (passed in: plotting stays below the packages whose results it draws)."""
    spec = result.spec
    rows = result.rows
    keys = list(spec.vary)
    obj = spec.objective
    scales = scales or {}
    names = names or {}
    from ..quantities import figure_unit

    label, factor = scales.get(obj, (units[obj], 1.0))
    label = figure_unit(label)                      # µW/cm³ on the figure (µW/cm^3 printed)
    ylabel = f"{names.get(obj, obj)} [{label}]"
    ok = [r for r in rows if r["status"] == "ok"]
    infeasible = [r for r in rows if r["status"] == "infeasible"]
    skipped = [r for r in rows if r["status"] == "skipped"]
    best = result.best
    over = (f"{spec.aggregate} over [uncertainty.vary], mean over"
            if getattr(spec, "percentile", None) is not None else f"{spec.aggregate} over")
    band = f"{over} {len(spec.band)} band point{'s' * (len(spec.band) > 1)}"
    values = np.array([r["objective"] for r in ok]) * factor
    tie = len(values) > 1 and float(np.ptp(values)) == 0.0
    pareto = len(spec.objectives) > 1
    panels = (1 if len(keys) == 1 else 2) + pareto
    fig = new_figure((5.6 * panels, 4.4))
    axes = list(np.atleast_1d(fig.subplots(1, panels)))
    bound_text = "; ".join(f"best on the {side} bound of {key} ({b:g}): widen the range"
                           for key, side, b in on_bound)

    def against_first_key(ax):
        k = keys[0]
        x = np.array([r["values"][k] for r in ok])
        e = np.array([r["objective_error"] for r in ok]) * factor
        order = np.argsort(x)
        ax.errorbar(x[order], values[order], yerr=e[order], fmt="o" + ("-" if len(keys) == 1
                                                                      else ""),
                    ms=3, lw=0.8, capsize=2, label="feasible (± error bar)")
        for group, marker, text in ((infeasible, "x", spec.require + " not met"),
                                    (skipped, "+", "skipped")):
            if group:
                ax.plot([r["values"][k] for r in group], [0.0] * len(group), marker,
                        color="0.5" if marker == "x" else "C3", label=text)
        if best is not None:
            ax.errorbar(best["values"][k], best["objective"] * factor,
                        yerr=best["objective_error"] * factor, fmt="*", ms=16, color="C1",
                        mec="k", capsize=3, label="best")
        lo, hi = spec.vary[k]
        for b in (lo, hi):
            ax.axvline(b, color="0.6", ls=":", lw=0.8)
        for key, side, b in on_bound:
            if key == k:
                ax.axvline(b, color="C3", ls="--", lw=1.2, label="best on a bound")
        ax.set_xlabel(key_label(k))
        ax.set_ylabel(ylabel)
        if k == "load_ohm":
            ax.set_xscale("log")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")

    ax = axes[0]
    if len(keys) == 1:
        against_first_key(ax)
    else:
        kx, ky = keys[0], keys[1]
        if ok:
            vmin, vmax = (values[0] - 1.0, values[0] + 1.0) if tie else (None, None)
            if tie and values[0] == 0:
                vmin, vmax = 0.0, 1.0
            sc = ax.scatter([r["values"][kx] for r in ok], [r["values"][ky] for r in ok],
                            c=values, s=22, cmap="viridis", edgecolors="none",
                            vmin=vmin, vmax=vmax, label="feasible")
            fig.colorbar(sc, ax=ax, label=ylabel)
        for group, marker, text in ((infeasible, "x", spec.require + " not met"),
                                    (skipped, "+", "skipped")):
            if group:
                ax.plot([r["values"][kx] for r in group], [r["values"][ky] for r in group],
                        marker, color="0.55" if marker == "x" else "C3", ms=5, label=text)
        if best is not None:
            ax.plot(best["values"][kx], best["values"][ky], "*", ms=18, color="C1", mec="k",
                    label="best")
            if any(key in (kx, ky) for key, _, _ in on_bound):
                ax.plot(best["values"][kx], best["values"][ky], "o", ms=22, mfc="none",
                        mec="C3", mew=1.5, label="best on a bound")
        for b in spec.vary[kx]:   # the search box
            ax.axvline(b, color="0.6", ls=":", lw=0.8)
        for b in spec.vary[ky]:
            ax.axhline(b, color="0.6", ls=":", lw=0.8)
        ax.set_xlabel(key_label(kx))
        ax.set_ylabel(key_label(ky))
        if kx == "load_ohm":
            ax.set_xscale("log")
        if ky == "load_ohm":
            ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        against_first_key(axes[1])
    title = f"{names.get(obj, obj)}, {band}" + (
        f" ({len(keys) - 2} more varied)" if len(keys) > 2 else "")
    if best is not None:
        title += (f"\nbest {best['objective'] * factor:.4g} ± "
                  f"{best['objective_error'] * factor:.2g} {label}")
    if tie:
        title += " - all candidates equal (a tie)"
    if bound_text and len(keys) == 1:
        title += "\n" + bound_text
    axes[0].set_title(title, fontsize=9)
    if bound_text and len(keys) > 1:
        axes[1].set_title(bound_text, fontsize=8, color="C3")
    if pareto:
        a, b = spec.objectives[:2]
        (la, fa), (lb, fb) = scales.get(a, (units[a], 1.0)), scales.get(b, (units[b], 1.0))
        la, lb = figure_unit(la), figure_unit(lb)
        ax2 = axes[-1]
        xa = [r["objectives"][a]["value"] * fa for r in ok]
        yb = [r["objectives"][b]["value"] * fb for r in ok]
        ax2.plot(xa, yb, "o", ms=3, color="C0", alpha=0.6, label="feasible")
        front = sorted(result.pareto(), key=lambda i: rows[i]["objectives"][a]["value"])
        ax2.plot([rows[i]["objectives"][a]["value"] * fa for i in front],
                 [rows[i]["objectives"][b]["value"] * fb for i in front], "s-", ms=4,
                 color="C2", label="Pareto front")
        if best is not None:
            ax2.plot(best["objectives"][a]["value"] * fa, best["objectives"][b]["value"] * fb,
                     "*", ms=16, color="C1", mec="k", label=f"best ({a})")
        ax2.set_xlabel(f"{names.get(a, a)} [{la}]")
        ax2.set_ylabel(f"{names.get(b, b)} [{lb}]")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7)
        ax2.set_title("Pareto plot", fontsize=9)
    for a in axes:   # readable numbers: no 1e-6 offset on an axis
        for axis in (a.xaxis, a.yaxis):
            fmt = axis.get_major_formatter()
            if hasattr(fmt, "set_useOffset"):
                fmt.set_useOffset(False)
    fig.tight_layout()
    return fig
