"""Plots of the electrical waveforms and of the surrogate (matplotlib Figure objects, saved as PNG; no pyplot).

``plot_waveforms``: V_OC, Q_SC, I_SC (and the load voltage/power when
present) against time, with the gap z(t) on its own panel below, in the style
of the paper's Figs. 8c-d and 9b-d. ``plot_surrogate``: V_OC, Q_SC and C_T
against z with the solved positions marked (a (z, r) surrogate: at r = 0 and at the
offsets the ball reached, plus the change of Q_SC with r). ``plot_sweep``: peak-to-peak
values over a frequency/amplitude grid, and power against load.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..terminals import of_scene
from . import new_figure, save_figure


#: a terminal panel -> the [instrument]'s reading drawn over it (issue #39)
READ_OVERLAYS = {"Q_sc_C": "Q_read_C", "I_sc_A": "I_read_A"}


def waveform_panels(waveforms: dict, parallel_capacitance_pF: float = 0.0) -> list:
    """``(column, axis label, factor)`` of each panel of :func:`plot_waveforms`, names and
    units from :mod:`tengfield.quantities`: V_OC (ideal), the voltage read through C_p
    when the waveforms have it (short label "V_read [V]"; C_p is named in its legend), Q_SC, I_SC, and a load's V_load and P_load."""
    from ..quantities import QUANTITIES, axis_label

    names = ["V_oc_V"]
    if "V_read_V" in waveforms:
        names.append("V_read_V")
    names += ["Q_sc_C", "I_sc_A"]
    if "V_load_V" in waveforms:
        names += ["V_load_V", "P_load_W"]
    panels = []
    for name in names:
        label = axis_label(name)
        if name == "V_read_V":   # short: the instrument is named in the panel's legend
            label = "V_read [V]"
        elif name == "V_oc_V":
            label = "V_OC (ideal) [V]" if "V_read_V" in waveforms else label
        panels.append((name, label, QUANTITIES[name].display_scale))
    return panels


def plot_waveforms(waveforms: dict, path: str | Path, *, title: str = "",
                   last_seconds: float | None = None,
                   parallel_capacitance_pF: float = 0.0) -> Path:
    """waveforms.png: :func:`waveforms_figure` saved to ``path``."""
    save_figure(waveforms_figure(waveforms, title=title, last_seconds=last_seconds,
                                 parallel_capacitance_pF=parallel_capacitance_pF), path, dpi=120)
    return Path(path)


def waveforms_figure(waveforms: dict, *, title: str = "", last_seconds: float | None = None,
                     parallel_capacitance_pF: float = 0.0):
    """Waveform panels against time [ms] and, below them, the gap z [mm] on its own panel
    (:func:`waveform_panels`; ``parallel_capacitance_pF``: the instrument's C_p, named
    on the V_read panel)."""
    t = np.asarray(waveforms["time_s"])
    mask = np.ones_like(t, dtype=bool) if last_seconds is None else t >= t[-1] - last_seconds
    panels = waveform_panels(waveforms, parallel_capacitance_pF)
    heights = [1.0] * len(panels) + [0.6]       # the gap: its own, lower panel
    fig = new_figure((8, 2.1 * len(panels) + 1.3))
    axes = fig.subplots(len(panels) + 1, 1, sharex=True, gridspec_kw={"height_ratios": heights})
    for ax, (key, label, factor) in zip(axes, panels):
        ax.plot(t[mask] * 1e3, np.asarray(waveforms[key])[mask] * factor, color="C0", lw=1.0,
                label=(f"V read through C_p = {parallel_capacitance_pF:.3g} pF"
                       if key == "V_read_V" else None))
        if key == "V_read_V":
            ax.legend(loc="upper right", fontsize=7)
        read = READ_OVERLAYS.get(key)
        if read in waveforms:     # what the [instrument] records, over the terminal's own
            ax.plot(t[mask] * 1e3, np.asarray(waveforms[read])[mask] * factor, color="C3",
                    lw=1.0, label="read by the instrument")
            ax.legend(loc="upper right", fontsize=7)
        ax.set_ylabel(label, color="C0")
        ax.grid(alpha=0.3)
    gap_ax = axes[-1]
    gap_ax.plot(t[mask] * 1e3, np.asarray(waveforms["gap_m"])[mask] * 1e3, color="0.4", lw=0.9)
    gap_ax.set_ylabel("gap z [mm]")
    gap_ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel("time [ms]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


#: trajectory points sent to the surrogate figure (the (z, r) places the ball went)
VISITED_POINTS = 4000


def visited_positions(dynamics) -> tuple[np.ndarray, np.ndarray] | None:
    """``(gap, radial offset)`` [m] of a 3D trajectory (at most ``VISITED_POINTS``
    evenly spaced samples: small to send to the figure process), or None for a
    trajectory on the axis (no ``radial``)."""
    r = getattr(dynamics, "radial", None)
    if r is None or np.asarray(r).size == 0:
        return None
    gap, r = np.asarray(dynamics.gap, dtype=float), np.asarray(r, dtype=float)
    step = max(1, -(-gap.size // VISITED_POINTS))
    return gap[::step].copy(), r[::step].copy()


def surrogate_lines(curves, *, cells: int = 1, visited=None, points: int = 400) -> list:
    """The curves of :func:`plot_surrogate`: ``[(r [m], {"V_OC", "Q_SC", "C_T"}), ...]``
    over ``z = linspace(0, Δh, points)`` (``cells`` cells in parallel: Q_SC and C_T
    scale, V_OC does not).

    A 1-D :class:`tengfield.surrogate.TerminalCurves` gives one line (r = 0); (z, r)
    curves give r = 0 and, up to the largest offset ``visited`` (``(gap, r)`` of the
    trajectory; None: the surrogate's r_max), its half and itself."""
    z = np.linspace(0.0, curves.stroke, points)
    if not curves.radial:
        return [(0.0, {"V_OC": curves.voltage(z), "Q_SC": curves.charge(z) * cells,
                       "C_T": curves.capacitance(z) * cells})]
    top = curves.max_offset if visited is None else float(np.max(visited[1], initial=0.0))
    top = min(max(top, 0.0), curves.max_offset)
    offsets = [0.0] if top == 0.0 else [0.0, 0.5 * top, top]
    return [(r, {"V_OC": curves.voltage(z, r), "Q_SC": curves.charge(z, r) * cells,
                 "C_T": curves.capacitance(z, r) * cells}) for r in offsets]


def plot_surrogate(table, curves, path: str | Path, *, cells: int = 1, visited=None,
                   error_estimate: float | None = None) -> Path:
    """surrogate.png: :func:`surrogate_figure` saved to ``path``."""
    save_figure(surrogate_figure(table, curves, cells=cells, visited=visited,
                                 error_estimate=error_estimate), path, 120)
    return Path(path)


def surrogate_figure(table, curves, *, cells: int = 1, visited=None,
                     error_estimate: float | None = None):
    """V_OC, Q_SC, C_T of ``cells`` cells against z [mm], solved positions as dots.

    ``curves``: the 1-D surrogate, or the (z, r) one of a ball off the axis
    (:class:`tengfield.surrogate.AnchoredTerminalCurves`): then the lines are
    those of :func:`surrogate_lines` (r = 0 and the offsets the ball reached, the band
    between shaded) and a fourth panel maps the change of Q_SC with r over (z, r)
    with the field solves of the grid and the trajectory's (z, r) samples
    (``visited``: ``(gap, r)`` [m], :func:`visited_positions`). ``error_estimate``: the
    one the title gives (summary.json's ``surrogate_error_estimate``: off the axis the
    (z, r) table's, which governs); None: the axis table's interpolation estimate."""
    radial = curves.radial
    lines = surrogate_lines(curves, cells=cells, visited=visited)
    z = np.linspace(0.0, curves.stroke, 400)
    if curves.axis is None:                       # bare (z, r) curves: the grid's r = 0
        q0, c0 = curves.charge_grid[:, 0], curves.capacitance_grid[:, 0]
        axis_dots = (curves.positions, q0 / c0, q0 * cells, c0 * cells)
    else:                                         # the 1-D solves, on the axis
        axis = curves.axis
        axis_dots = (axis.positions, axis.charge_samples / axis.capacitance_samples,
                     axis.charge_samples * cells, axis.capacitance_samples * cells)
    panels = [("V_OC", "V_OC [V]", 1.0), ("Q_SC", "Q_SC [nC]", 1e9), ("C_T", "C_T [pF]", 1e12)]
    fig = new_figure((16 if radial else 12, 3.6 if radial else 3.4))
    axes = fig.subplots(1, 4 if radial else 3)
    colours = ["C0", "C2", "C1"]
    for k, (ax, (key, label, factor)) in enumerate(zip(axes, panels)):
        for (r, values), colour in zip(lines, colours):
            name = "cubic spline" if not radial else f"r = {r * 1e3:.3g} mm"
            ax.plot(z * 1e3, values[key] * factor, color=colour, lw=1.2, label=name)
        if len(lines) > 1:
            stacked = np.array([values[key] for _, values in lines]) * factor
            ax.fill_between(z * 1e3, stacked.min(axis=0), stacked.max(axis=0), color="C1",
                            alpha=0.15, lw=0, label="r reached")
        ax.plot(axis_dots[0] * 1e3, axis_dots[k + 1] * factor, "o", ms=3.5, color="C3",
                label="field solves (r = 0)" if radial else "field solves")
        ax.set_xlabel("gap z [mm]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    title = (f"surrogate ({', '.join(p for p in (curves.reference, cells_phrase(cells)) if p)}): "
             f"{table.count} positions, "
             f"error estimate {table.interpolation_error if error_estimate is None else error_estimate:.2g}")
    if radial:
        _plot_radial_change(axes[3], curves, cells, visited)
        title += (f"; (z, r): {len(curves.positions)} x {len(curves.offsets)} 3D solves "
                  f"up to r = {curves.max_offset * 1e3:.3g} mm")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def _plot_radial_change(ax, curves, cells: int, visited) -> None:
    """Q_SC(z, r) − Q_SC(z, 0) [pC] over (z, r) (filled contours), the grid's solves,
    and where the ball went. A table whose offsets are scaled to the admissible radius at
    each height (the spherical shell: r_max(z) = sqrt(R² − (z − Δh/2)²)) is drawn inside
    r <= r_max(z) only, its solves at their real offsets, the wall as a line."""
    scaled = bool(getattr(getattr(curves, "zr", curves), "scaled", False))
    stroke, largest = curves.stroke, curves.max_offset
    z = np.linspace(0.0, stroke, 120)
    r = np.linspace(0.0, largest, 60)
    zz, rr = np.meshgrid(z, r, indexing="ij")
    change = (curves.charge(zz, rr) - curves.charge(zz, np.zeros_like(rr))) * cells * 1e12
    gz, gu = np.meshgrid(curves.positions, curves.offsets, indexing="ij")
    gr = gu
    if scaled:
        def wall(height):
            return np.sqrt(np.maximum(largest**2 - (height - 0.5 * stroke) ** 2, 0.0))
        change = np.where(rr <= wall(zz) * (1 + 1e-9), change, np.nan)
        gr = gu * wall(gz) / largest
    finite = change[np.isfinite(change)]
    levels = 21 if finite.size and np.ptp(finite) > 0 else 2
    filled = ax.contourf(zz * 1e3, rr * 1e3, change, levels=levels, cmap="RdBu_r")
    ax.figure.colorbar(filled, ax=ax, label="Q_SC(z, r) − Q_SC(z, 0) [pC]")
    if scaled:
        ax.plot(z * 1e3, wall(z) * 1e3, "-", color="0.3", lw=1, label="cavity wall r_max(z)")
    ax.plot(gz.ravel() * 1e3, gr.ravel() * 1e3, "+", ms=4, color="0.2", label="3D solves")
    if visited is not None:
        ax.plot(np.asarray(visited[0]) * 1e3, np.asarray(visited[1]) * 1e3, ".", ms=1.5,
                color="C1", alpha=0.5, label="trajectory")
    ax.set_xlim(0.0, stroke * 1e3)
    ax.set_ylim(0.0, largest * 1e3 * 1.04)   # the outer solves stay visible
    ax.set_xlabel("gap z [mm]")
    ax.set_ylabel("radial offset r [mm]")
    ax.legend(fontsize=7, loc="upper right")


def plot_sweep(rows: list[dict], path: str | Path) -> Path:
    """sweep.png: :func:`sweep_figure` saved to ``path``."""
    save_figure(sweep_figure(rows), path, dpi=120)
    return Path(path)


def sweep_figure(rows: list[dict]):
    """Peak-to-peak V_OC, Q_SC, I_SC against frequency (one line per amplitude; left out
    when the sweep has one frequency: a single dot on no axis), and with loads the load's
    peak-to-peak voltage and current and its mean power against the resistance R (log
    axes; one line per excitation)."""
    freqs = sorted({r["frequency_hz"] for r in rows})
    amps = sorted({r["amplitude_mm"] for r in rows})
    loads = sorted({r["load_ohm"] for r in rows if r.get("load_ohm") is not None})
    from ..quantities import QUANTITIES, TERMINAL, axis_label, column_name
    panels = [(column_name(n, "peak_to_peak"), axis_label(n, statistic="peak_to_peak"),
               QUANTITIES[n].display_scale) for n in TERMINAL]
    if loads and len(freqs) == 1:
        panels = []                   # against R only: one frequency is no axis
    panels_r = load_panels() if loads else []
    ncols = len(panels) + len(panels_r)
    fig = new_figure((4 * ncols, 3.4))
    axes = list(np.atleast_1d(fig.subplots(1, ncols)))
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
    if panels:
        axes[0].legend(fontsize=7)
    for ax, (key, label, factor) in zip(axes[len(panels):], panels_r):
        for f in freqs:
            for amp in amps:
                pts = sorted((r["load_ohm"], r[key]) for r in rows
                             if r["frequency_hz"] == f and r["amplitude_mm"] == amp
                             and r.get("load_ohm") is not None
                             and (r.get(key) or 0.0) > 0)   # a ball at rest: nothing
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] * factor for p in pts], "o-", ms=3,
                            label=f"{f:g} Hz, A = {amp:g} mm")
        ax.set_xscale("log")
        y = [v for line in ax.get_lines() for v in line.get_ydata()]
        if y and max(y) > 10.0 * min(y):    # a decade or more: log; less: plain ticks
            ax.set_yscale("log")
        ax.set_xlabel("load R [Ω]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
    if panels_r and len(freqs) * len(amps) <= 8 and axes[len(panels)].get_lines():
        axes[len(panels)].legend(fontsize=7)
    fig.tight_layout()
    return fig


#: the panels of a load sweep, against R: (sweep.csv column, the quantity, its statistic)
_LOAD_PANELS = [("V_load_pp_V", "V_load_V", "peak_to_peak"),
                ("I_load_pp_A", "I_load_A", "peak_to_peak"), ("P_mean_W", "mean_power_W", None)]


def load_panels() -> list[tuple[str, str, float]]:
    """(sweep.csv column, axis label, display scale) of a load sweep's panels, names and
    units from :mod:`tengfield.quantities` (the terminal's)."""
    from ..quantities import QUANTITIES, axis_label
    return [(column, axis_label(name, statistic=stat) if stat else axis_label(name),
             QUANTITIES[name].display_scale) for column, name, stat in _LOAD_PANELS]


def cells_phrase(cells: int) -> str:
    """``"4 cells"`` for more than one cell, ``""`` for one (a title says nothing then)."""
    return f"{int(cells)} cells" if int(cells) > 1 else ""


def _signed(value: float) -> str:
    """``value`` with ``{:g}`` and a typographic minus (−8, not -8)."""
    return f"{value:g}".replace("-", "−")


def circuit_words(scene) -> list[str]:
    """The circuit's and the instrument's numbers a run's waveforms depend on: the load
    R (Ω, kΩ, MΩ, GΩ), the circuit's parallel C_p and the instrument's C_p [pF]."""
    circuit = scene.circuit
    words = []
    if getattr(circuit, "kind", "") in ("load", "series-rc") and getattr(circuit, "load", 0.0) > 0:
        words.append(f"R = {_ohms(circuit.load)}")
    instrument = getattr(scene, "instrument", None)
    c_p = getattr(instrument, "capacitance", 0.0) or getattr(circuit, "parallel_capacitance", 0.0)
    if c_p > 0:
        words.append(f"C_p = {c_p * 1e12:.3g} pF")
    return words


def _ohms(value: float) -> str:
    """A resistance with its SI prefix: 10 MΩ, 4.7 kΩ, 50 Ω."""
    for factor, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if value >= factor:
            return f"{value / factor:.3g} {prefix}Ω"
    return f"{value:.3g} Ω"


def run_title(result) -> str:
    """The title of a run's figures: the device (σ [µC/m²], stroke Δh [mm]), the
    excitation, the cell count when > 1, the load R and C_p (:func:`circuit_words`),
    the reference and the regime."""
    exc, dev = result.scene.excitation, result.scene.device
    regime = result.summary.get("regime") or {}
    name = regime.get("regime", regime.get("name", "")) if isinstance(regime, dict) else ""
    charge = result.summary.get("charge") if isinstance(result.summary, dict) else None
    sigma = (f"σ from contacts (steady {charge['steady_uC_per_m2']:.3g} µC/m²)"
             if isinstance(charge, dict) and charge.get("model") == "contact"
             else f"σ = {_signed(dev.surface_charge * 1e6)} µC/m²")
    parts = [sigma,
             f"Δh = {dev.stroke * 1e3:g} mm", f"{exc.frequency:g} Hz",
             f"A = {exc.amplitude * 1e3:g} mm",
             cells_phrase(result.summary.get("cells", dev.cells)),
             *circuit_words(result.scene), of_scene(result.scene).name, name]
    return ", ".join(p for p in parts if p)

