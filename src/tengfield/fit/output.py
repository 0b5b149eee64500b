"""fit.json, fit.png and fitted.toml (the scene with the fitted values, ready for ``tengfield run``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .._files import scene_toml, write_json, write_text
from .solve import FitResult

#: where each fitted parameter goes in the scene file (time_shift_s has no scene key)
SCENE_KEYS = {
    "surface_charge_uC_per_m2": ("device", "surface_charge_uC_per_m2"),
    "parallel_capacitance_pF": ("circuit", "parallel_capacitance_pF"),
    "restitution": ("contact", "restitution"),
    "load_ohm": ("circuit", "load_ohm"),
}


def fitted_scene_dict(scene, result: FitResult) -> dict:
    """``scene.raw`` with the fitted values (the [fit] section dropped)."""
    data = {sec: dict(values) for sec, values in scene.raw.items() if sec != "fit"}
    for name, value in result.values.items():
        if name in SCENE_KEYS:
            sec, key = SCENE_KEYS[name]
            data.setdefault(sec, {})[key] = float(f"{value:.6g}")
        elif name == "amplitude_scale":
            data.setdefault("excitation", {})["amplitude_mm"] = float(
                f"{scene.excitation.amplitude * 1e3 * value:.6g}")
    return data


def write_fit_outputs(scene, result: FitResult, out_dir, *, plots: bool = True) -> list[Path]:
    """Write fit.json, fitted.toml and (with ``plots``) fit.png to ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary = {"scene": scene.source, **result.as_dict()}
    write_json(out / "fit.json", summary)
    written = [out / "fit.json"]
    lines = [f"fitted by `tengfield fit` from {scene.source} ({result.mode})"]
    for name in result.names:
        se = result.standard_errors[name]
        lines.append(f"{name} = {result.values[name]:.6g} +- {se:.3g}"
                     + ("" if result.identifiable[name] else "  (NOT identifiable)"))
    if "time_shift_s" in result.values:
        lines.append("time_shift_s is the trace's offset after the steady-window start "
                     "(no scene key)")
    write_text(out / "fitted.toml", scene_toml(fitted_scene_dict(scene, result),
                                               "\n".join(lines)))
    written.append(out / "fitted.toml")
    if plots:
        written.append(plot_fit(result, out / "fit.png"))
    return written


_SI_LABEL = {"V": "V", "Q": "C", "I": "A"}
_DISPLAY = {"V": ("V", 1.0), "Q": ("nC", 1e-9), "I": ("nA", 1e-9)}


def plot_fit(result: FitResult, path) -> Path:
    """Measured vs fitted (and residuals) for a trace; measured vs fitted bars for targets."""
    from ..plotting import new_figure

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
            unit, factor = _DISPLAY[q]
            measured = np.asarray(result.measured[q]) / factor
            fitted = np.asarray(result.fitted[q]) / factor
            ax, axr = axes[2 * i], axes[2 * i + 1]
            ax.plot(t, measured, ".", ms=1.5, color="0.5", label="measured")
            ax.plot(t, fitted, lw=1.0, color="C3", label="fitted")
            ax.set_ylabel(f"{q} [{unit}]")
            ax.legend(fontsize=7, loc="upper right")
            axr.plot(t, measured - fitted, lw=0.6, color="C0")
            axr.axhline(0.0, color="0.3", lw=0.5)
            axr.set_ylabel("resid.", fontsize=8)
            ax.grid(alpha=0.3)
            axr.grid(alpha=0.3)
        axes[0].set_title(_title(result), fontsize=8)
        axes[-1].set_xlabel("measured time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    return Path(path)


def _title(result: FitResult) -> str:
    parts = []
    for name in result.names:
        se = result.standard_errors[name]
        flag = "" if result.identifiable[name] else " (n.i.)"
        parts.append(f"{name} = {result.values[name]:.4g} ± {se:.2g}{flag}")
    return "\n".join("; ".join(parts[i:i + 2]) for i in range(0, len(parts), 2))
