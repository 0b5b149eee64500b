"""fit.png: measured against fitted (and the residuals) for a trace, or the fitted values
against the targets (a :class:`tengfield.fit.FitResult`)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure


#: the tool quantity of V, Q, I when a result names none (tengfield.quantities' names)
_DEFAULT_TOOL = {"V": "V_oc_V", "Q": "Q_sc_C", "I": "I_sc_A"}


def _axis(result, q: str) -> tuple[str, float]:
    """(axis label, SI -> shown factor) of measured column ``q`` (V, Q, I): the tool
    quantity it is compared with (``result.residuals[q]["tool_key"]``), labelled and
    scaled by the quantity table."""
    from ..quantities import axis_label, quantity

    name = (result.residuals.get(q) or {}).get("tool_key") or _DEFAULT_TOOL[q]
    return axis_label(name), quantity(name).display_scale


def plot_fit(result, path) -> Path:
    """fit.png: :func:`fit_figure` saved to ``path``."""
    return Path(save_figure(fit_figure(result), path, dpi=90))


def fit_figure(result):
    """Measured vs fitted (and residuals) for a trace; measured vs fitted bars for targets."""
    if result.mode == "targets":
        labels = list(result.measured)
        fig = new_figure((6.0, 3.2))
        ax = fig.subplots()
        x = np.arange(len(labels))
        ratio = [result.fitted[k] / result.measured[k] for k in labels]
        spread = [result.noise[k].get("relative", 0.0) for k in labels]
        ax.axhline(1.0, color="0.3", lw=0.8)
        ax.errorbar(x, np.ones(len(labels)), yerr=spread, fmt="none", ecolor="C0", capsize=6,
                    label="target ± 1σ")
        ax.plot(x, ratio, "o", color="C3", label="fitted")
        ax.set_xticks(x, labels)
        ax.set_ylabel("value / target")
        ax.legend(fontsize=8)
        ax.set_title(_title(result), fontsize=8)
    else:
        quantities = [q for q in result.fitted]
        fig = new_figure((7.0, 2.6 * len(quantities) + 0.6))
        axes = fig.subplots(2 * len(quantities), 1, sharex=True, squeeze=False,
                            gridspec_kw={"height_ratios": [3, 1] * len(quantities)})
        axes = axes[:, 0]
        t = np.asarray(result.measured["time"])
        for i, q in enumerate(quantities):
            label, scale = _axis(result, q)
            measured = np.asarray(result.measured[q]) * scale
            fitted = np.asarray(result.fitted[q]) * scale
            ax, axr = axes[2 * i], axes[2 * i + 1]
            ax.plot(t, measured, ".", ms=1.5, color="0.5", label="measured")
            ax.plot(t, fitted, lw=1.0, color="C3", label="fitted")
            ax.set_ylabel(label, fontsize=8)
            ax.legend(fontsize=7, loc="upper right")
            axr.plot(t, measured - fitted, lw=0.6, color="C0")
            axr.axhline(0.0, color="0.3", lw=0.5)
            axr.set_ylabel("resid.", fontsize=8)
            ax.grid(alpha=0.3)
            axr.grid(alpha=0.3)
        axes[0].set_title(_title(result), fontsize=8)
        axes[-1].set_xlabel("measured time [s]")
    fig.tight_layout()
    return fig


def _title(result) -> str:
    parts = []
    for name in result.names:
        se = result.standard_errors[name]
        flag = "" if result.identifiable[name] else " (n.i.)"
        parts.append(f"{name} = {result.values[name]:.4g} ± {se:.2g}{flag}")
    return "\n".join("; ".join(parts[i:i + 2]) for i in range(0, len(parts), 2))
