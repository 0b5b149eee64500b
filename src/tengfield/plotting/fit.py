"""fit.png: measured against fitted (and the residuals) for a trace, or the fitted values
against the targets (a :class:`tengfield.fit.FitResult`)."""
from __future__ import annotations

import math
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


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
#: SI prefixes a time in seconds is shown with (t_0 = 0 ± 2.6 µs, not 2.6e-06 s)
_TIME_PREFIXES = ((1.0, "s"), (1e-3, "ms"), (1e-6, "µs"), (1e-9, "ns"))


def _two_digits(x: float) -> str:
    """``x`` to 2 significant digits, a power of ten as ×10⁻⁶ (no "e-06")."""
    text = f"{x:.2g}"
    if 1e-4 <= abs(x) < 1e5:         # fixed point, its second digit kept (0.20, not 0.2)
        text = f"{x:.{max(1 - math.floor(math.log10(abs(x))), 0)}f}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}×10{str(int(exponent)).translate(_SUPERSCRIPT)}"
    return text.replace("-", "\u2212")


def value_with_error(value: float, error: float, unit: str = "") -> str:
    """``"−35.80 ± 0.41 µC/m²"``: ``value`` rounded to the digits its standard ``error``
    carries (2 significant digits of the error; past 6 digits of the value, 4: ``−8 ±
    1.1×10⁻⁶``), a value within a hundredth of its error shown as 0 (a t_0 of 2.5e-19 s
    ± 2.6 µs is 0); a time in seconds with the SI prefix of its error."""
    if unit == "s" and math.isfinite(error) and error > 0:
        size = max(abs(value), error)
        for factor, prefix in _TIME_PREFIXES:
            if size >= factor or factor == _TIME_PREFIXES[-1][0]:
                value, error, unit = value / factor, error / factor, prefix
                break
    if not (math.isfinite(error) and error > 0):
        shown = f"{value:.3g}"
        spread = ""
    else:
        if abs(value) < 0.01 * error:
            shown = "0"
        else:
            decimals = 1 - math.floor(math.log10(error))
            digits = (math.floor(math.log10(abs(value))) + 1 + decimals) if value else 0
            shown = (f"{value:.{max(decimals, 0)}f}" if 0 < digits <= 6 or decimals <= 0
                     else f"{value:.4g}")
        spread = f" ± {_two_digits(error)}"
    shown = shown.replace("-", "\u2212")
    return f"{shown}{spread}" + (f" {unit}" if unit else "")


def _title(result) -> str:
    """The fitted values: ``σ = −35.80 ± 0.41 µC/m²; restitution e = 0.620 ± 0.013``
    (symbols and units of :data:`tengfield.quantities.SCENE_SYMBOLS`, each value rounded
    to its standard error: :func:`value_with_error`), two parameters a line."""
    from ..quantities import scene_symbol

    parts = []
    for name in result.names:
        se = result.standard_errors[name]
        flag = "" if result.identifiable[name] else " (n.i.)"
        symbol, unit, words = scene_symbol(name) or (name, "", "")
        if not unit and words and len(symbol) == 1:     # e: "restitution e"
            symbol = f"{words} {symbol}"
        parts.append(f"{symbol} = {value_with_error(result.values[name], se, unit)}" + flag)
    return "\n".join("; ".join(parts[i:i + 2]) for i in range(0, len(parts), 2))
