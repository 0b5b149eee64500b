"""Plots of the harvesting electronics (matplotlib Figure objects, saved as PNG; no pyplot).

``plot_charging``: the store voltage against time with the UVLO levels and the
chip's on intervals. ``plot_vq``: the V-Q cycles of the last excitation
period (resistive load, rectifier) and the CMEO bound; the areas are the
energies per cycle. ``plot_array``: per-cell phases and the array's output
against N x one cell.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save_figure


def plot_charging(fine, scene, path: str | Path, *, title: str = "") -> Path:
    """U(t) [V] of a :class:`tengfield.harvest.HarvestResult` with the UVLO levels (only
    when there is a chip: ``[circuit] pmic`` not "none")."""
    c = scene.circuit
    t = np.asarray(fine.time)
    fig = new_figure((8, 3.6))
    ax = fig.subplots()
    ax.plot(t, fine.store_voltage, color="C0", lw=1.0, label="store U")
    levels = () if c.pmic == "none" else ((c.uvlo_rising, "UVLO rising"),
                                          (c.uvlo_falling, "UVLO falling"))
    for level, name in levels:
        ax.axhline(level, color="C3" if "rising" in name else "C1", ls="--", lw=0.8,
                   label=f"{name} {level:g} V")
    on = np.asarray(fine.chip_on, dtype=bool)
    if on.any():
        top = max(float(np.max(fine.store_voltage)), c.uvlo_rising if levels else 0.0) * 1.05
        ax.fill_between(t, 0, top, where=on, color="C2", alpha=0.15, step="post",
                        label="chip on")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("store voltage U [V]")
    ax.set_title(f"{title}\n{c.storage_capacitance * 1e6:g} µF, {c.diode} bridge, "
                 f"pmic = {c.pmic}", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    save_figure(fig, path, 120)
    return Path(path)


def plot_vq(loops: dict, energy: dict, path: str | Path, *, title: str = "") -> Path:
    """vq.png: :func:`vq_figure` saved to ``path``."""
    save_figure(vq_figure(loops, energy, title=title), path, 120)
    return Path(path)


def _draw_loops(ax, loops: dict, energy: dict) -> None:
    """Each loop's V [V] against Q [nC], labelled with its ∮V dQ."""
    for k, (name, (q, v, area)) in enumerate(loops.items()):
        label = (f"resistive load {energy.get('load_ohm', float('nan')):.3g} Ω"
                 if name == "load" else "rectifier (bridge terminal)")
        ax.plot(np.asarray(q) * 1e9, v, color=f"C{k}", lw=1.2,
                label=f"{label}: ∮V dQ = {area:.4g} J")


def _label_vq(ax, title: str) -> None:
    ax.axhline(0, color="0.7", lw=0.6)
    ax.set_xlabel("charge through the circuit Q [nC]")
    ax.set_ylabel("terminal voltage V [V]")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def vq_figure(loops: dict, energy: dict, *, title: str = ""):
    """V [V] against transferred charge Q [nC] over the last period; legend: ∮V dQ. With
    the CMEO bound (``energy["max_energy_per_cycle_J"]``) two panels: the loops under the
    bound's triangle (left), and the loops alone on their own limits (right), since a
    loop far inside the bound would be a flat line at the triangle's scale."""
    cmeo = bool(energy.get("max_energy_per_cycle_J"))
    fig = new_figure((11.5, 4.8) if cmeo else (6.4, 4.8))
    axes = fig.subplots(1, 2 if cmeo else 1, squeeze=False)[0]
    _draw_loops(axes[0], loops, energy)
    if cmeo:
        q_max = energy["Q_sc_max_C"] * 1e9
        v_up, v_down = energy["V_oc_max_V"], energy["V_return_max_V"]
        axes[0].plot([0, 0, q_max, q_max, 0], [0, v_up, 0, -v_down, 0], color="0.4", ls=":",
                     label=f"CMEO bound: {energy['max_energy_per_cycle_J']:.4g} J")
        _draw_loops(axes[1], loops, energy)     # autoscaled on the loops alone
        _label_vq(axes[0], "with the CMEO bound")
        _label_vq(axes[1], "the run's V-Q loop, zoomed")
    else:
        _label_vq(axes[0], "")
    fig.suptitle(f"{title}\nV-Q cycle of the last period (area = energy per cycle)",
                 fontsize=9)
    fig.tight_layout()
    return fig


def plot_array(array, summary: dict, path: str | Path, *, title: str = "") -> Path:
    """array.png: :func:`array_figure` saved to ``path``."""
    save_figure(array_figure(array, summary, title=title), path, 120)
    return Path(path)


def array_figure(array, summary: dict, *, title: str = ""):
    """Histogram of the per-cell phases and the array's output against N x one cell."""
    fig = new_figure((10, 4))
    ax_h, ax_t = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.6]})
    phases = np.asarray(array.phases_deg)
    ax_h.hist(phases[np.isfinite(phases)], bins=min(36, max(6, phases.size // 4)), color="C0")
    ax_h.set_xlabel("cell phase - array mean phase [deg]")
    ax_h.set_ylabel("cells")
    ax_h.set_title(f"{phases.size} cells, coherence |<e^iφ>| = "
                   f"{summary.get('phase_coherence', float('nan')):.3f}", fontsize=9)
    t = np.asarray(array.time)
    shown = t >= t[-1] - 5.0 * array.period
    ax_t.plot(t[shown] * 1e3, np.asarray(array.output)[shown], color="C0", lw=1.0,
              label=f"array ({summary.get('connection', '')})")
    ax_t.plot(t[shown] * 1e3, np.asarray(array.reference)[shown], color="C3", lw=1.0, ls="--",
              label="N x one cell (no spread)")
    ax_t.set_xlabel("time [ms]")
    ax_t.set_ylabel(array.output_label)
    ratio = summary.get("array_over_N_cells", float("nan"))
    ax_t.set_title(f"{summary.get('compared', '')}: array / (N x one cell) = {ratio:.4g}",
                   fontsize=9)
    ax_t.grid(alpha=0.3)
    ax_t.legend(fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig
