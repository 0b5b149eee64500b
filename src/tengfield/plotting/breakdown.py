"""breakdown.png: the gap voltages over the stroke against Paschen's curve."""
from __future__ import annotations

import numpy as np

from . import new_figure, save_figure

_COLOURS = {"open": "tab:blue", "open-top": "tab:green", "short": "tab:red"}


def plot_breakdown(result, sigma: float, path, *, title: str | None = None,
                   band=None, ratios=None) -> None:
    """breakdown.png: :func:`breakdown_figure` saved to ``path``."""
    save_figure(breakdown_figure(result, sigma, title=title, band=band, ratios=ratios), path,
                dpi=120)


_EDGE_STYLE = {"lower": ("tab:blue", ":"), "estimate": ("tab:orange", "-"),
               "upper": ("tab:red", "--")}


def _band_panel(ax, band, curves) -> None:
    """Each edge of the band: |V_gap| / V_b of the worst line against the ball position
    over the positions its trajectory visits, V_b at the edge's own γ (``curves``:
    :func:`tengfield.air_breakdown.band.edge_ratios`, computed by the caller): lower
    touches 1 where it binds (the critical gap), upper where the smaller gap is widest,
    the estimate crosses it."""
    z = curves["z"] * 1e3
    empirical = band.paschen_curve == "empirical"
    for edge, sigma in band.edges().items():
        colour, ls = _EDGE_STYLE[edge]
        gamma, ratio = curves[edge]
        at = "" if empirical else f", γ = {gamma:g}"
        ax.plot(z, ratio, color=colour, ls=ls, lw=1.6,
                label=f"{edge}: {sigma * 1e6:.3g} µC/m²{at}")
    ax.axhline(1.0, color="k", lw=1.0)
    for position, edge in ((band.lower_position, "lower"), (band.upper_position, "upper")):
        if np.isfinite(position) and z[0] <= position * 1e3 <= z[-1]:
            ax.plot([position * 1e3], [1.0], "o", color=_EDGE_STYLE[edge][0], mfc="none",
                    ms=7)
    ax.set_xlabel("ball position z along the trajectory [mm]")
    ax.set_ylabel("|V_gap| / V_b (worst line, the edge's γ)")
    ax.set_title("the band: each edge reaches 1 where it binds (○)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)


def breakdown_figure(result, sigma: float, *, title: str | None = None, band=None,
                     ratios=None):
    """Left: |σ ΔV| of the axial gaps (and the binding line) against their length over the
    stroke, with Paschen's curve; right: the largest |σ ΔV| / V_b over the lines against
    the ball position; below (with a ``band`` that has a trajectory): each edge of the
    band along the trajectory (:func:`_band_panel`, ``ratios``: its edges' curves,
    :func:`tengfield.air_breakdown.band.edge_ratios`). ``sigma`` [C/m²]: the scene's (or
    -σ_max). The binding point is marked."""
    third = band is not None and band.track is not None and bool(ratios)
    fig = new_figure((11.0, 8.2 if third else 4.6), layout="constrained")
    if third:
        panels = fig.subplot_mosaic([["left", "right"], ["band", "band"]])
        left, right = panels["left"], panels["right"]
        _band_panel(panels["band"], band, ratios)
    else:
        left, right = fig.subplots(1, 2)
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
        for k, (side, ls) in enumerate((("lower", "-"), ("upper", "--"))):
            if not np.any(np.isfinite(ratio[:, k, :])):   # no gap there (one electrode)
                continue
            right.plot(z * 1e3, np.max(ratio[:, k, :], axis=1), color=colour, ls=ls,
                       label=f"{state}, {side} gap")
    b = result.binding
    v_at = s * abs(b.dv_per_sigma)
    left.plot([b.gap * 1e3], [v_at], "o", color="k", ms=7, mfc="none")
    left.plot([b.gap * 1e3], [b.breakdown_voltage], "*", color="k", ms=11,
              label=f"binds: {b.state}, {b.side} gap, z = {b.position * 1e3:.3g} mm")
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
    from matplotlib.ticker import FuncFormatter
    plain = FuncFormatter(lambda v, _: f"{v:g}")      # 0.2, 0.3, 1: not 2×10⁻¹
    right.yaxis.set_major_formatter(plain)
    right.yaxis.set_minor_formatter(plain)
    right.legend(fontsize=7)
    right.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"air breakdown at σ = {sigma * 1e6:.3g} µC/m²: static limit ".replace("-", "−")
                 +
                 f"σ_max = {result.sigma_max * 1e6:.3g} µC/m²"
                 + ("" if getattr(result.paschen, "curve", "") == "empirical"
                    else f" (γ = {result.paschen.gamma:g})"), fontsize=10)
    return fig
