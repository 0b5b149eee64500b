"""Plots of the electrical waveforms and of the surrogate (matplotlib Figure objects, saved as PNG; no pyplot).

``plot_waveforms``: V_OC, Q_SC, I_SC (and the load voltage/power when
present) against time, each with the gap z(t) on a twin axis, in the style
of the paper's Figs. 8c-d and 9b-d. ``plot_surrogate``: V_OC, Q_SC and C_T
against z with the solved positions marked. ``plot_sweep``: peak-to-peak
values over a frequency/amplitude grid, and power against load.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure


def plot_waveforms(waveforms: dict, path: str | Path, *, title: str = "",
                   last_seconds: float | None = None) -> Path:
    """Waveform panels against time [ms] with the gap [mm] in grey (right axis)."""
    t = np.asarray(waveforms["time_s"])
    mask = np.ones_like(t, dtype=bool) if last_seconds is None else t >= t[-1] - last_seconds
    panels = [("V_oc_V", "V_OC [V]", 1.0), ("Q_sc_C", "Q_SC [nC]", 1e9), ("I_sc_A", "I_SC [nA]", 1e9)]
    if "V_load_V" in waveforms:
        panels += [("V_load_V", "V_load [V]", 1.0), ("P_load_W", "P_load [µW]", 1e6)]
    fig = new_figure((8, 2.1 * len(panels)))
    axes = fig.subplots(len(panels), 1, sharex=True)
    for ax, (key, label, factor) in zip(np.atleast_1d(axes), panels):
        ax.plot(t[mask] * 1e3, np.asarray(waveforms[key])[mask] * factor, color="C0", lw=1.0)
        ax.set_ylabel(label, color="C0")
        twin = ax.twinx()
        twin.plot(t[mask] * 1e3, np.asarray(waveforms["gap_m"])[mask] * 1e3, color="0.6", lw=0.8)
        twin.set_ylabel("gap z [mm]", color="0.45")
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel("time [ms]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return Path(path)


def plot_surrogate(table, curves, path: str | Path, *, cells: int = 1) -> Path:
    """V_OC, Q_SC, C_T of ``cells`` cells against z [mm], solved positions as dots."""
    z = np.linspace(0.0, curves.stroke, 400)
    nodes = curves.positions
    panels = [("V_OC [V]", curves.voltage(z), curves.charge_samples / curves.capacitance_samples, 1.0),
              ("Q_SC [nC]", curves.charge(z) * cells, curves.charge_samples * cells, 1e9),
              ("C_T [pF]", curves.capacitance(z) * cells, curves.capacitance_samples * cells, 1e12)]
    fig = new_figure((12, 3.4))
    axes = fig.subplots(1, 3)
    for ax, (label, line, dots, factor) in zip(axes, panels):
        ax.plot(z * 1e3, line * factor, color="C0", lw=1.2, label="cubic spline")
        ax.plot(nodes * 1e3, dots * factor, "o", ms=3.5, color="C3", label="field solves")
        ax.set_xlabel("gap z [mm]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"surrogate ({curves.reference}, {cells} cell(s)): {table.count} positions, "
                 f"error estimate {table.interpolation_error:.2g}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return Path(path)


def plot_sweep(rows: list[dict], path: str | Path) -> Path:
    """Peak-to-peak V_OC, Q_SC, I_SC against frequency (one line per amplitude),
    and mean load power against load resistance when the sweep has loads."""
    freqs = sorted({r["frequency_hz"] for r in rows})
    amps = sorted({r["amplitude_mm"] for r in rows})
    loads = sorted({r["load_ohm"] for r in rows if r.get("load_ohm") is not None})
    panels = [("V_oc_pp_V", "V_OC peak-to-peak [V]", 1.0),
              ("Q_sc_pp_C", "Q_SC peak-to-peak [nC]", 1e9),
              ("I_sc_pp_A", "I_SC peak-to-peak [nA]", 1e9)]
    ncols = len(panels) + (1 if loads else 0)
    fig = new_figure((4 * ncols, 3.4))
    axes = fig.subplots(1, ncols)
    first_load = loads[0] if loads else None
    for ax, (key, label, factor) in zip(axes, panels):
        for amp in amps:
            pts = sorted((r["frequency_hz"], r[key]) for r in rows
                         if r["amplitude_mm"] == amp and r.get("load_ohm") == first_load)
            ax.plot([p[0] for p in pts], [p[1] * factor for p in pts], "o-", ms=3,
                    label=f"A = {amp:g} mm")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    if loads:
        ax = axes[-1]
        for f in freqs:
            for amp in amps:
                pts = sorted((r["load_ohm"], r["P_mean_W"]) for r in rows
                             if r["frequency_hz"] == f and r["amplitude_mm"] == amp
                             and r["P_mean_W"] > 0)   # a ball at rest delivers nothing
                if pts:
                    ax.loglog([p[0] for p in pts], [p[1] * 1e6 for p in pts], "o-", ms=3,
                              label=f"{f:g} Hz, {amp:g} mm")
        ax.set_xlabel("load [Ω]")
        ax.set_ylabel("mean power [µW]")
        ax.grid(alpha=0.3, which="both")
        if len(freqs) * len(amps) <= 8:
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return Path(path)
