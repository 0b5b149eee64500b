"""The honeycomb array of Fig. 10: 5 layers x 91 cells in parallel, 0.5 mm at 33 Hz, load sweep.

The shipboard harvester of the paper's Section 3.3 stacks five 3D-printed
PLA honeycomb layers of 91 hexagonal cells, each with a 5 mm PTFE ball and
a stroke Δh = 2 mm, all 455 cells wired in parallel. The paper measures
peaks of 342.56 V, 153.14 nC and 26.72 µA and, over a load sweep (Fig.
S13), a maximum instantaneous power density of 59.78 W/m³ at 11 MΩ.

The field of one cell:

* full mode: the hexagonal 3D cell of ``tengfield.field.geometry3d``
  (``HexagonalCell``: inner apothem 3 mm, 1 mm PLA walls, 2 mm plates,
  hexagonal electrodes covering floor and ceiling, εr = 3), solved by the
  3D solver at Lobatto positions (an isolated cell: neighbours are not
  modelled);
* fast mode: a cylindrical cell of equal cross-section (bore and outer
  radius giving the hexagons' areas), axisymmetric.

N identical cells in parallel multiply Q_SC, I_SC and C_T by N and leave
V_OC unchanged. The ball's charge density σ and the instrument capacitance
C_p that reproduce the paper's 153.14 nC and 342.56 V are derived; the
load sweep is run with them (the electrometer across the load).

    .venv/bin/python demos/electrical_honeycomb.py [--fast] [-o DIR] [--cache-dir DIR]
"""
from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from demo_mpi import is_root, world  # noqa: E402
from electrical_common import (demo_arguments, measure, pyplot,  # noqa: E402
                               reconciling_capacitance, save_small_png, surrogate_curves)

from tengfield import electrical  # noqa: E402
from tengfield.dynamics import simulate  # noqa: E402
from tengfield.scene import default_scene  # noqa: E402

LAYERS, CELLS_PER_LAYER = 5, 91
PAPER = {"V_oc": 342.56, "Q_sc": 153.14e-9, "I_sc": 26.72e-6, "power_density": 59.78,
         "optimal_load": 11e6}


def equal_area_radius(apothem: float) -> float:
    """Radius [m] of the circle with the area of the regular hexagon of ``apothem`` [m]."""
    return math.sqrt(2.0 * math.sqrt(3.0) * apothem**2 / math.pi)


def honeycomb_scene(fast: bool):
    from tengfield.field.cells.plate_model3d import HexagonalCell

    cell = HexagonalCell()
    bore = equal_area_radius(cell.inner_apothem)
    outer = equal_area_radius(cell.outer_apothem)
    periods = 40 if fast else 120
    return cell, default_scene().with_values(
        device={"ball_diameter_mm": cell.ball_diameter * 1e3, "stroke_mm": cell.stroke * 1e3,
                "tube_inner_radius_mm": bore * 1e3, "electrode_radius_mm": bore * 1e3,
                "tube_outer_radius_mm": outer * 1e3,
                "plate_thickness_mm": cell.plate_thickness * 1e3,
                "ball_permittivity": cell.ball_permittivity,
                "wall_permittivity": cell.wall_permittivity,
                "cells": LAYERS * CELLS_PER_LAYER},
        excitation={"frequency_hz": 33.0, "amplitude_mm": 0.5},
        run={"duration_s": periods / 33.0, "settle_periods": periods // 2,
             "sample_rate_hz": 20000.0 if fast else 50000.0},
        field={"degree": 1, "mesh_size_mm": 0.7, "tolerance": 0.03} if fast else
              {"degree": 2, "mesh_size_mm": 0.4, "tolerance": 1e-3})


def hexagonal_table(cell, scene, cache_dir):
    """Surrogate of the hexagonal 3D cell (degree 1, 1.2 mm, Robin far field, 1e-2),
    cached next to tengfield's surrogates under its own name."""
    from tengfield.field.solver3d import Solve3DSettings, solve_cell_3d
    from tengfield.surrogate import (SurrogateError, cache_path, precompute, read_table,
                                     solver_fingerprint, write_table)

    settings = Solve3DSettings(degree=1, mesh_size=1.2e-3, domain_radius=20e-3,
                               far_field="robin", estimate_error=False)
    hex_scene = scene.with_values(field={"method": "3d", "tolerance": 1e-2, "degree": 1,
                                         "mesh_size_mm": 1.2, "far_field": "robin"})
    path = cache_path(hex_scene, cache_dir).with_name(
        "honeycomb-hexagonal-" + cache_path(hex_scene, cache_dir).name)
    try:
        table = read_table(path, expected_hash=hex_scene.field_hash(),
                           expected_solver=solver_fingerprint())
        print(f"  hexagonal 3D surrogate: {table.count} positions (cached)", file=sys.stderr)
        return table
    except (SurrogateError, OSError):
        pass

    def solve(_scene, z, comm):
        return solve_cell_3d(cell, z, surface_charge=scene.device.surface_charge,
                             settings=settings, comm=comm)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        table = precompute(hex_scene, solve=solve, comm=world(), progress=True)
    if is_root():
        path.parent.mkdir(parents=True, exist_ok=True)
        write_table(path, table)
    print(f"  hexagonal 3D surrogate: {table.count} positions, estimate "
          f"{table.interpolation_error:.2g}", file=sys.stderr)
    return table


def load_sweep(scene, dynamics, table, loads, scale, c_p):
    """Mean and peak instantaneous power density [W/m³] into each load [ohm].

    The ball's charge is scaled by ``scale`` (σ_fit/σ): the induced charges
    are linear in σ, the capacitances do not depend on it."""
    from tengfield.surrogate import TerminalCurves

    scaled = TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge * scale)
    mask, _ = electrical.steady_window(dynamics.t, scene)
    volume = scene.device.cell_volume * scene.device.cells
    mean, peak = [], []
    for load in loads:
        loaded = scene.with_values(circuit={"kind": "load", "load_ohm": float(load),
                                            "parallel_capacitance_pF": c_p * 1e12})
        res = electrical.steady_load(loaded, dynamics, scaled)
        mean.append(res["mean_power_W"] / volume)
        peak.append(float(np.max(res["P_load"][mask])) / volume)
    return np.array(mean), np.array(peak), volume


def main(argv: list[str] | None = None) -> dict:
    args = demo_arguments(__doc__, argv)
    out = Path(args.output)
    cell, scene = honeycomb_scene(args.fast)
    n_cells = scene.device.cells
    if args.fast:
        geometry = "cylindrical cell of equal cross-section (axisymmetric)"
        table, curves = surrogate_curves(scene, args.cache_dir)
    else:
        from tengfield.surrogate import TerminalCurves
        geometry = "hexagonal 3D cell (isolated, degree 1, 1.2 mm)"
        table = hexagonal_table(cell, scene, args.cache_dir)
        curves = TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge)
    dynamics = simulate(scene)
    ideal = measure(curves, dynamics, scene)
    i_peak = float(np.max(np.abs(ideal["waveforms"]["I_sc"][ideal["mask"]])))
    scale = PAPER["Q_sc"] / ideal["Q_sc"]
    c_p = reconciling_capacitance(ideal["Q_sc"] * scale, PAPER["V_oc"], ideal["C_T_max"])
    read = measure(curves, dynamics, scene, parallel_capacitance=c_p)
    sigma = scene.device.surface_charge
    regime = dynamics.regime

    loads = np.logspace(5, 10, 11 if args.fast else 31)
    mean, peak, volume = load_sweep(scene, dynamics, table, loads, scale, c_p)
    best = int(np.argmax(peak))
    best_mean = int(np.argmax(mean))

    print(f"honeycomb: {LAYERS} x {CELLS_PER_LAYER} = {n_cells} cells in parallel; field: {geometry}; "
          f"{table.count} positions")
    print(f"0.5 mm, 33 Hz: regime {regime.name} (period {regime.period}), upper contacts per "
          f"period {regime.upper_contacts_per_period:.2f}, max gap {regime.max_gap * 1e3:.3f} mm "
          f"of {scene.device.stroke * 1e3:g} mm")
    print("quantity                                  paper          tengfield")
    print(f"V_OC pp, ideal (sigma = {sigma*1e6:g} uC/m^2)      -              {ideal['V_oc']:.4g} V")
    print(f"Q_SC pp, {n_cells} cells (sigma = {sigma*1e6:g})       -              "
          f"{ideal['Q_sc'] * 1e9:.4g} nC")
    print(f"|I_SC| peak, {n_cells} cells (sigma = {sigma*1e6:g})   -              {i_peak * 1e6:.4g} uA")
    print(f"sigma reproducing Q_SC = 153.14 nC         -              {sigma * scale * 1e6:.4g} uC/m^2")
    print(f"Q_SC pp at that sigma                     153.14 nC      {ideal['Q_sc'] * scale * 1e9:.4g} nC")
    print(f"|I_SC| peak at that sigma                 26.72 uA       {i_peak * scale * 1e6:.4g} uA")
    print(f"C_T of the array (max)                    -              {ideal['C_T_max'] * 1e12:.4g} pF")
    print(f"C_p reconciling 342.56 V                  -              {c_p * 1e12:.4g} pF")
    print(f"V read with that C_p                      342.56 V       {read['V_oc'] * scale:.4g} V")
    print(f"device volume (455 hexagonal prisms)      -              {volume * 1e6:.4g} cm^3")
    print(f"max instantaneous power density           59.78 W/m^3    {peak[best]:.4g} W/m^3")
    print(f"  at load                                 11 MOhm        {loads[best] / 1e6:.3g} MOhm")
    print(f"max mean power density                    -              {mean[best_mean]:.4g} W/m^3 "
          f"at {loads[best_mean] / 1e6:.3g} MOhm")
    r_match = 1.0 / (2 * math.pi * scene.excitation.frequency * (ideal["C_T_max"] + c_p))
    print(f"1/(2 pi f (C_T + C_p))                    -              {r_match / 1e6:.3g} MOhm")

    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    t = np.asarray(dynamics.t)
    show = t >= t[-1] - 3.0 / scene.excitation.frequency
    tm = (t[show] - t[show][0]) * 1e3
    ax1.plot(tm, read["waveforms"]["V_oc"][show] * scale, label=f"V read (C_p = {c_p*1e12:.0f} pF)")
    ax1.set_ylabel("V [V]")
    ax1.set_xlabel("time [ms]")
    twin = ax1.twinx()
    twin.plot(tm, ideal["waveforms"]["I_sc"][show] * scale * 1e6, color="C1", lw=0.8,
              label="I_SC")
    twin.set_ylabel("I_SC [µA]", color="C1")
    ax1.axhline(PAPER["V_oc"], color="C3", ls="--", lw=0.8, label="paper 342.56 V")
    ax1.legend(fontsize=7, loc="upper left")
    ax1.set_title(f"Fig. 10b: {n_cells} cells, 0.5 mm, 33 Hz", fontsize=10)
    ax2.loglog(loads, peak, "o-", ms=3, label="peak instantaneous")
    ax2.loglog(loads, mean, "s-", ms=3, label="mean")
    ax2.plot([PAPER["optimal_load"]], [PAPER["power_density"]], "r*", ms=10,
             label="paper: 59.78 W/m³ at 11 MΩ")
    ax2.set_xlabel("load [Ω]")
    ax2.set_ylabel("power density [W/m³]")
    ax2.set_title("Fig. S13: load sweep", fontsize=10)
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7)
    fig.tight_layout()
    path = save_small_png(fig, out / "electrical_honeycomb.png")
    plt.close(fig)
    print(f"wrote {path}")

    return {"cells": n_cells, "C_p_pF": c_p * 1e12, "V_read_V": read["V_oc"] * scale,
            "peak_power_density_W_per_m3": float(peak[best]),
            "peak_power_load_MOhm": float(loads[best] / 1e6),
            "mean_power_density_W_per_m3": float(mean[best_mean]),
            "mean_power_load_MOhm": float(loads[best_mean] / 1e6),
            "matched_load_MOhm": r_match / 1e6}


if __name__ == "__main__":
    main()
