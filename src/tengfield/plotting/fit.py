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


#: fit.png's size [in] (a paper figure's width) and resolution
FIT_SIZE_IN = (7.0, 5.0)
FIT_DPI = 150


def plot_fit(result, path) -> Path:
    """fit.png: :func:`fit_figure` saved to ``path``."""
    return Path(save_figure(fit_figure(result), path, dpi=FIT_DPI))


def fit_figure(result):
    """Measured vs fitted (and residuals) for a trace; per target, the measured value with
    its stated uncertainty (1σ error bar) beside the fitted one."""
    if result.mode == "targets":
        labels = list(result.measured)
        fig = new_figure(FIT_SIZE_IN)
        axes = fig.subplots(1, max(len(labels), 1), squeeze=False)[0]
        for ax, label in zip(axes, labels):
            row = (result.residuals or {}).get(label) or {}
            measured = row.get("measured", result.measured[label])
            fitted = row.get("fitted", result.fitted[label])
            sigma = row.get("uncertainty",
                            abs(measured) * result.noise.get(label, {}).get("relative", 0.0))
            unit = row.get("unit") or label.rpartition("_")[2]
            ax.errorbar([0], [measured], yerr=[sigma], fmt="o", color="0.3", capsize=6,
                        label="measured ± 1σ")
            ax.plot([1], [fitted], "o", color="C3", label="fitted")
            ax.set_xticks([0, 1], ["measured", "fitted"])
            ax.set_xlim(-0.6, 1.6)
            ax.set_ylabel(f"{label.rpartition('_')[0]} [{unit}]")
            ax.grid(alpha=0.3, axis="y")
        axes[0].legend(fontsize=7, loc="best")
        fig.suptitle(_title(result), fontsize=9)
    else:
        quantities = [q for q in result.fitted]
        fig = new_figure((FIT_SIZE_IN[0], max(FIT_SIZE_IN[1], 2.6 * len(quantities) + 0.6)))
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
            axr.set_ylabel(f"residual [{_unit(result, q)}]", fontsize=8)
            ax.grid(alpha=0.3)
            axr.grid(alpha=0.3)
        axes[0].set_title(_title(result), fontsize=8)
        axes[-1].set_xlabel("measured time [s]")
    fig.tight_layout()
    return fig


def _unit(result, q: str) -> str:
    """The shown unit of measured column ``q`` (its panel's, :func:`_axis`)."""
    from ..quantities import quantity

    name = (result.residuals.get(q) or {}).get("tool_key") or _DEFAULT_TOOL[q]
    return quantity(name).display_unit


def _title(result) -> str:
    """``σ = −35.8 ± 0.41 µC/m²; e = 0.62 ± 0.013`` (symbols and units of
    :data:`tengfield.quantities.SCENE_SYMBOLS`), two parameters a line."""
    from ..quantities import scene_symbol

    parts = []
    for name in result.names:
        se = result.standard_errors[name]
        flag = "" if result.identifiable[name] else " (n.i.)"
        symbol, unit, _ = scene_symbol(name) or (name, "", "")
        value = f"{result.values[name]:.3g}".replace("-", "\u2212")
        parts.append(f"{symbol} = {value} ± {se:.2g}" + (f" {unit}" if unit else "") + flag)
    return "\n".join("; ".join(parts[i:i + 2]) for i in range(0, len(parts), 2))
