"""uncertainty.png: each main output's distribution over the study with its 5-95 % band
and the scene's nominal value (left), and its Sobol indices S1 and ST with their
bootstrap 95 % intervals as bars per input (right)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure

#: display unit of an output the quantity table leaves in SI (or does not hold), by its
#: name's unit suffix: (suffix, unit text, scale); I_SC as the run prints it (nA)
_UNITS = (("_V", "V", 1.0), ("_C", "nC", 1e9), ("_A", "nA", 1e9), ("_W", "µW", 1e6),
          ("_J", "µJ", 1e6))


def display_unit(name: str) -> tuple[str, float]:
    """(unit text, scale) output ``name`` is shown in, on the terminal and on
    uncertainty.png alike: the quantity table's display unit (``peak.I_sc_A``: nA, as
    ``tengfield run`` prints it), else by the unit suffix (an SI energy in µJ)."""
    from ..quantities import QUANTITIES

    leaf = name.rpartition(".")[2]
    q = QUANTITIES.get(leaf)
    if q is not None and q.display_unit not in ("", "1") and q.display_scale != 1.0:
        return q.display_unit, q.display_scale
    for suffix, unit, scale in _UNITS:
        if name.endswith(suffix):
            return unit, scale
    return "", 1.0


def output_axis(name: str) -> tuple[str, float]:
    """(axis label, SI -> shown factor) of output ``name``, in :func:`display_unit`'s
    unit: a quantity-table output (``peak_to_peak.Q_sc_C``) as
    ``"Q_SC peak-to-peak [nC]"``; others by unit suffix."""
    from ..quantities import QUANTITIES

    from ..quantities import CHARGE_LABELS

    if name in CHARGE_LABELS:       # the contact charge's: units as named, shown as SI
        return CHARGE_LABELS[name], 1.0
    stat, _, leaf = name.rpartition(".")
    unit, scale = display_unit(name)
    if leaf in QUANTITIES:          # a statistic's or a block's (energy_per_cycle) output
        q = QUANTITIES[leaf]
        if q.display_unit in ("", "1"):                  # dimensionless: FOM_S
            return q.symbol, q.display_scale
        words = {"peak_to_peak": " peak-to-peak", "peak": " peak"}.get(stat, "")
        return f"{q.symbol}{words} [{unit}]", scale
    return (f"{name} [{unit}]" if unit else name), scale


#: a Sobol index is a share of variance: its bootstrap interval is drawn within [0, 1]
#: (a bootstrap of a few samples can reach past either end; the JSON keeps it whole)
SHARE_RANGE = (0.0, 1.0)


def share_error_bars(value: float, half_width: float) -> tuple[float, float]:
    """(below, above) of a Sobol index's 95 % interval ``value ± half_width`` clipped
    to :data:`SHARE_RANGE` (the value itself clipped too: an estimate of 1.19 is drawn
    at 1)."""
    shown = min(max(value, SHARE_RANGE[0]), SHARE_RANGE[1])
    low = min(max(value - half_width, SHARE_RANGE[0]), shown)
    high = max(min(value + half_width, SHARE_RANGE[1]), shown)
    return shown - low, high - shown


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
                    raw = [indices[k][which] for k in inputs]
                    bars = [share_error_bars(v, indices[k][which + "_conf"])
                            for k, v in zip(inputs, raw)]
                    ax.bar(x + offset, [min(max(v, 0.0), 1.0) for v in raw], width=0.4,
                           yerr=np.array(bars).T, capsize=3, color=colour, alpha=0.75,
                           label=which)
                ax.set_xticks(x)
                ax.set_xticklabels([scene_label(k) for k in inputs], fontsize=7, rotation=15 if len(inputs) > 2 else 0,
                                   ha="right" if len(inputs) > 2 else "center")
                ax.set_ylim(0.0, 1.05)
                ax.legend(fontsize=7, loc="best")
            else:
                ax.text(0.5, 0.5, summary.get("notes", {}).get(name, "no Sobol indices"),
                        ha="center", va="center", fontsize=8, transform=ax.transAxes)
            ax.set_ylabel("share of variance", fontsize=8)
            ax.grid(alpha=0.3, axis="y")
    bars = ("; bars: Sobol S1 / ST with bootstrap 95 % intervals (within [0, 1])"
            if sobol else "")
    fig.suptitle(f"uncertainty: {summary['evaluations']} evaluations ({summary['method']}, "
                 f"N = {summary['samples']}){bars}", fontsize=9)
    return fig
