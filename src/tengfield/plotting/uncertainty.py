"""uncertainty.png: each main output's distribution over the study with its 5-95 % band
and the scene's nominal value (left), and its Sobol indices S1 and ST with their
bootstrap 95 % intervals as bars per input (right)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure

#: display unit of an output by its name's unit suffix: (suffix, unit text, scale)
_UNITS = (("_V", "V", 1.0), ("_C", "nC", 1e9), ("_A", "µA", 1e6), ("_W", "µW", 1e6),
          ("_J", "µJ", 1e6))


def display_unit(name: str) -> tuple[str, float]:
    """(unit text, scale) to show output ``name`` in."""
    for suffix, unit, scale in _UNITS:
        if name.endswith(suffix):
            return unit, scale
    return "", 1.0


def output_axis(name: str) -> tuple[str, float]:
    """(axis label, SI -> shown factor) of output ``name``: a quantity-table output
    (``peak_to_peak.Q_sc_C``) as ``"Q_SC peak-to-peak [nC]"``; others by unit suffix."""
    from ..quantities import QUANTITIES, axis_label

    stat, _, leaf = name.rpartition(".")
    if leaf in QUANTITIES:          # a statistic's or a block's (energy_per_cycle) output
        q = QUANTITIES[leaf]
        if q.display_unit in ("", "1"):                  # dimensionless: FOM_S
            return q.symbol, q.display_scale
        return axis_label(leaf, statistic=stat), q.display_scale
    unit, scale = display_unit(name)
    return (f"{name} [{unit}]" if unit else name), scale


def plot_uncertainty(rows: list[dict], summary: dict, path: str | Path) -> Path:
    """uncertainty.png: :func:`uncertainty_figure` saved to ``path``."""
    return Path(save_figure(uncertainty_figure(rows, summary), path, dpi=110))


def uncertainty_figure(rows: list[dict], summary: dict):
    """One row of panels per main output (``summary["main_outputs"]``; ``rows``: each
    evaluation's outputs): its distribution with the 5-95 % band, the median and the
    nominal value, and (Sobol) its S1 / ST bars per input. A matplotlib Figure
    (``Study.plot()`` in a notebook)."""
    shown = summary["main_outputs"] or summary["output_keys"][:3]
    sobol = summary["method"] == "sobol"
    height = 2.6 * max(len(shown), 1) + 1.0
    fig = new_figure((11.0 if sobol else 6.5, height), layout="constrained")   # ticks kept in
    axes = fig.subplots(max(len(shown), 1), 2 if sobol else 1, squeeze=False)
    from ..quantities import scene_label

    inputs = list(summary["distributions"])
    for row_axes, name in zip(axes, shown):
        block = summary["outputs"][name]
        label, scale = output_axis(name)
        values = np.array([np.nan if r.get(name) is None else r[name] for r in rows], float)
        values = values[np.isfinite(values)] * scale
        ax = row_axes[0]
        if values.size:
            ax.hist(values, bins=min(40, max(8, values.size // 8)), color="C0", alpha=0.6)
        p = block["percentiles"]
        if p:
            ax.axvspan(p["5"] * scale, p["95"] * scale, color="C1", alpha=0.15,
                       label="5-95 %")
            ax.axvline(p["50"] * scale, color="C1", lw=1.2, label="median")
        if block.get("nominal") is not None:
            ax.axvline(block["nominal"] * scale, color="k", ls="--", lw=1.2, label="nominal")
        ax.set_xlabel(label, fontsize=8)
        ax.set_ylabel("evaluations", fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        if sobol:
            ax = row_axes[1]
            indices = block.get("sobol")
            if indices:
                x = np.arange(len(inputs))
                for offset, which, colour in ((-0.2, "S1", "C2"), (0.2, "ST", "C3")):
                    ax.bar(x + offset, [indices[k][which] for k in inputs], width=0.4,
                           yerr=[indices[k][which + "_conf"] for k in inputs], capsize=3,
                           color=colour, alpha=0.75, label=which)
                ax.set_xticks(x)
                ax.set_xticklabels([scene_label(k) for k in inputs], fontsize=7, rotation=15 if len(inputs) > 2 else 0,
                                   ha="right" if len(inputs) > 2 else "center")
                ax.set_ylim(min(0.0, ax.get_ylim()[0]), max(1.05, ax.get_ylim()[1]))
                ax.legend(fontsize=7, loc="best")
            else:
                ax.text(0.5, 0.5, summary.get("notes", {}).get(name, "no Sobol indices"),
                        ha="center", va="center", fontsize=8, transform=ax.transAxes)
            ax.set_ylabel("share of variance", fontsize=8)
            ax.grid(alpha=0.3, axis="y")
    bars = "; bars: Sobol S1 / ST with bootstrap 95 % intervals" if sobol else ""
    fig.suptitle(f"uncertainty: {summary['evaluations']} evaluations ({summary['method']}, "
                 f"N = {summary['samples']}){bars}", fontsize=9)
    return fig
