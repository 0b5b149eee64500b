"""breakdown.png: the gap voltages over the stroke against Paschen's curve."""
from __future__ import annotations

import numpy as np

from . import new_figure, save_figure

_COLOURS = {"open": "tab:blue", "open-top": "tab:green", "short": "tab:red"}


def plot_breakdown(result, sigma: float, path, *, title: str | None = None) -> None:
    """breakdown.png: :func:`breakdown_figure` saved to ``path``."""
    save_figure(breakdown_figure(result, sigma, title=title), path, dpi=130)


def breakdown_figure(result, sigma: float, *, title: str | None = None):
    """Left: |σ ΔV| of the axial gaps (and the binding line) against their length over the
    stroke, with Paschen's curve; right: the largest |σ ΔV| / V_b over the lines against
    the ball position. ``sigma`` [C/m²]: the scene's (or -σ_max). The binding point is marked."""
    fig = new_figure((11.0, 4.6), layout="constrained")
    left, right = fig.subplots(1, 2)
    paschen = result.paschen
    d = np.geomspace(1e-6, 2e-2, 400)
    left.loglog(d * 1e3, paschen.voltage(d), color="k", lw=2.0,
                label=f"Paschen, air, {paschen.pressure / 1e3:.4g} kPa")
    landmarks = [(paschen.d_min, "minimum"), (paschen.d_streamer, "streamer above")]
    if np.isfinite(paschen.longest_path):
        landmarks.append((paschen.longest_path, "longest path"))
    for edge, text in landmarks:
        if not d[0] < edge < d[-1]:      # off the plotted range (e.g. at low pressure)
            continue
        left.axvline(edge * 1e3, color="0.7", lw=0.8, ls=":")
        left.text(edge * 1e3, 1.2 * paschen.v_min, f" {text}", fontsize=7, color="0.4",
                  rotation=90, va="bottom", clip_on=True)
    s = abs(sigma)
    for state, curve in result.curves.items():
        colour = _COLOURS.get(state, "tab:purple")
        z = curve["position_m"]
        for k, (side, ls) in enumerate((("lower", "-"), ("upper", "--"))):
            length = curve["length_m"][:, k, 0]
            volts = s * np.abs(curve["dv_per_sigma"][:, k, 0])
            ok = np.isfinite(length) & (length > 0)
            if np.any(ok):
                left.loglog(length[ok] * 1e3, volts[ok], color=colour, ls=ls, lw=1.2,
                            label=f"{state}, {side} gap (axis)")
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = s / curve["limit"]          # |σ ΔV| / V_b per line
        right.plot(z * 1e3, np.max(ratio[:, 0, :], axis=1), color=colour, ls="-",
                   label=f"{state}, lower gap")
        right.plot(z * 1e3, np.max(ratio[:, 1, :], axis=1), color=colour, ls="--",
                   label=f"{state}, upper gap")
    b = result.binding
    v_at = s * abs(b.dv_per_sigma)
    left.plot([b.gap * 1e3], [v_at], "o", color="k", ms=7, mfc="none")
    left.plot([b.gap * 1e3], [b.breakdown_voltage], "*", color="k", ms=11,
              label=f"binds: sigma_max = {result.sigma_max * 1e6:.3g} uC/m2 ({b.state}, {b.side} "
                    f"gap, z = {b.position * 1e3:.3g} mm)")
    left.set_xlabel("gap length along the line [mm]")
    left.set_ylabel("voltage across the gap [V]")
    left.set_xlim(d[0] * 1e3, d[-1] * 1e3)
    left.legend(fontsize=7, loc="upper left")
    left.grid(True, which="both", alpha=0.3)
    right.axhline(1.0, color="k", lw=1.0)
    right.plot([b.position * 1e3], [s / result.sigma_max], "o", color="k", mfc="none", ms=7)
    right.set_xlabel("ball position z [mm]")
    right.set_ylabel("|V_gap| / V_b (worst line)")
    right.set_yscale("log")
    right.legend(fontsize=7)
    right.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"air breakdown at sigma = {sigma * 1e6:.3g} uC/m2: "
                 f"sigma_max = {result.sigma_max * 1e6:.3g} uC/m2", fontsize=10)
    return fig
