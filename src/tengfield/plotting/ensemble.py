"""Ensemble figure: each output over the realisations, its running mean with the
95 % confidence interval shrinking as 1/sqrt(N), and the regime fractions."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure


def _shown() -> tuple:
    """(ensemble.csv column, axis label, SI -> shown factor) of the outputs drawn, named
    by the one table of output quantities (tengfield.quantities)."""
    from ..quantities import TERMINAL, axis_label, column_name, quantity

    shown = [(column_name(n, "peak_to_peak"), axis_label(n, statistic="peak_to_peak"),
              quantity(n).display_scale) for n in TERMINAL]
    shown += [(n, axis_label(n), quantity(n).display_scale)
              for n in ("mean_power_W", "average_harvested_power_W")]
    return tuple(shown)


def _running_interval(values: np.ndarray):
    """(realisations 1..N, running mean, running 95 % half-width) over the values so far;
    a missing value (NaN) is left out (the statistics of summary.json do the same)."""
    from scipy.stats import t as student_t

    values = np.asarray(values, dtype=float)
    n = np.arange(1, values.size + 1)
    finite = np.isfinite(values)
    count = np.cumsum(finite)
    ref = values[finite][0] if finite.any() else 0.0
    shifted = np.where(finite, values - ref, 0.0)   # sums of squares without cancellation
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_shifted = np.cumsum(shifted) / count
        sq = np.cumsum(shifted**2)
        var = np.where(count > 1, (sq - count * mean_shifted**2) / np.maximum(count - 1, 1),
                       np.nan)
        half = np.where(count > 1, student_t.ppf(0.975, np.maximum(count - 1, 1))
                        * np.sqrt(np.maximum(var, 0.0) / np.maximum(count, 1)), np.nan)
    mean = np.where(count > 0, ref + mean_shifted, np.nan)
    return n, mean, half


def plot_ensemble(rows: list[dict], block: dict, path: str | Path) -> Path:
    """ensemble.png: :func:`ensemble_figure` saved to ``path``."""
    return Path(save_figure(ensemble_figure(rows, block), path, dpi=110))


def ensemble_figure(rows: list[dict], block: dict):
    """One row of panels per output (realisations and running mean +- CI) and the regime
    fractions; ``rows``: ensemble.csv's, ``block``: summary.json's ``ensemble``. A
    matplotlib Figure (``result.ensemble.plot()`` in a notebook)."""
    from matplotlib.ticker import MaxNLocator

    items = _shown() + (("array_value", f"array: {block.get('array_quantity', '')}", 1.0),)
    shown = [(k, label, scale) for k, label, scale in items
             if k in block["quantities"] and block["quantities"][k]["mean"] is not None]
    fig = new_figure((9.0, 2.3 * len(shown) + 2.0))
    axes = fig.subplots(len(shown) + 1, 1, squeeze=False)[:, 0]
    for ax, (key, label, scale) in zip(axes, shown):
        values = np.array([np.nan if r[key] is None else r[key] for r in rows], float) * scale
        n, mean, half = _running_interval(values)
        ax.plot(n, values, "o", ms=3, color="0.55", label="realisation")
        ax.plot(n, mean, color="C0", lw=1.4, label="running mean")
        ax.fill_between(n, mean - half, mean + half, color="C0", alpha=0.2,
                        label="95 % CI of the mean")
        ax.set_ylabel(label, fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)
        if block["quantities"][key].get("equal_within_round_off"):
            # one value up to round-off: an axis of +-5 % around it, not its last bits
            centre = float(block["quantities"][key]["mean"]) * scale
            width = 0.05 * abs(centre) or 1.0
            ax.set_ylim(centre - width, centre + width)
            ax.set_title(f"{label.split(' [')[0]}: the same in every realisation "
                         "(spread below round-off)", fontsize=8)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))   # N is a count
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="best")
    axes[len(shown) - 1].set_xlabel("realisations N")
    ax = axes[-1]
    fractions = block["regime_fractions"]
    labels = list(fractions)
    means = [fractions[k]["mean"] for k in labels]
    # the exact binomial interval is not symmetric about the fraction
    errs = [[m - fractions[k]["ci95_low"] for k, m in zip(labels, means)],
            [fractions[k]["ci95_high"] - m for k, m in zip(labels, means)]]
    ax.bar(labels, means, yerr=errs, color="C2", alpha=0.7, capsize=4)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("fraction of realisations", fontsize=8)
    ax.set_title("regime (exact binomial 95 % interval)", fontsize=9)
    fig.suptitle(f"ensemble of {block['realisations']} realisations "
                 "(95 % confidence intervals, Student t)", fontsize=10)
    fig.tight_layout()
    return fig
