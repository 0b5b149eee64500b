"""breakdown.png: the gap voltages over the stroke against Paschen's curve."""
from __future__ import annotations

import numpy as np

from . import new_figure, save_figure

_COLOURS = {"open": "tab:blue", "open-top": "tab:green", "short": "tab:red"}


def plot_breakdown(result, sigma: float, path, *, title: str | None = None,
                   band=None) -> None:
    """breakdown.png: :func:`breakdown_figure` saved to ``path``."""
    save_figure(breakdown_figure(result, sigma, title=title, band=band), path, dpi=130)


_EDGE_STYLE = {"lower": ("tab:blue", ":"), "estimate": ("tab:orange", "-"),
               "upper": ("tab:red", "--")}


def _band_panel(ax, band) -> None:
    """|V_gap| / V_b of the worst line along the trajectory (the scene's γ) against the
    ball's smaller gap, with σ at each of the band's three levels."""
    track = band.track
    smaller = track.smaller_gap
    for edge, sigma in band.edges().items():
        colour, ls = _EDGE_STYLE[edge]
        ax.plot(smaller * 1e3, track.ratio(sigma), color=colour, ls=ls, lw=1.0,
                label=f"{edge}: {sigma * 1e6:.3g} µC/m²")
    ax.axhline(1.0, color="k", lw=1.0)
    for gap_m, text in ((band.lower_gap, "lower binds"), (band.upper_gap, "upper binds")):
        if np.isfinite(gap_m):
            ax.axvline(gap_m * 1e3, color="0.6", lw=0.8, ls=":")
            ax.text(gap_m * 1e3, 1.0, f" {text}", fontsize=7, color="0.4", rotation=90,
                    va="bottom")
    ax.set_xlabel("ball's smaller gap along the trajectory [mm]")
    ax.set_ylabel("|V_gap| / V_b (worst line, scene's gamma)")
    ax.set_title("the band along the trajectory", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)


def breakdown_figure(result, sigma: float, *, title: str | None = None, band=None):
    """Left: |σ ΔV| of the axial gaps (and the binding line) against their length over the
    stroke, with Paschen's curve; middle: the largest |σ ΔV| / V_b over the lines against
    the ball position; right (with a ``band`` that has a trajectory): |V_gap|/V_b along the
    trajectory at the band's three σ. ``sigma`` [C/m²]: the scene's (or -σ_max). The
    binding point is marked."""
    third = band is not None and band.track is not None
    fig = new_figure((16.0 if third else 11.0, 4.6), layout="constrained")
    axes = fig.subplots(1, 3 if third else 2)
    left, right = axes[0], axes[1]
    if third:
        _band_panel(axes[2], band)
    paschen = result.paschen
    d = np.geomspace(1e-6, 2e-2, 400)
    left.loglog(d * 1e3, paschen.voltage(d), color="k", lw=2.0,
                label=f"Paschen, air, {paschen.pressure / 1e3:.4g} kPa"
                + (" (measured, Dakin 1974)" if getattr(paschen, "curve", "") == "empirical"
                   else ""))
    landmarks = [(paschen.d_min, "minimum")]
    if getattr(paschen, "curve", "townsend") == "townsend":   # the measured curve has no switch
        landmarks.append((paschen.d_streamer, "streamer above"))
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
              label=f"binds: σ_max = {result.sigma_max * 1e6:.3g} µC/m² ({b.state}, {b.side} "
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
    fig.suptitle(title or f"air breakdown at σ = {sigma * 1e6:.3g} µC/m²: "
                 f"σ_max = {result.sigma_max * 1e6:.3g} µC/m²", fontsize=10)
    return fig
