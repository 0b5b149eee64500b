"""The ship case: the honeycomb (455 cells, 0.5 mm, 33 Hz) charging the LTC3588's input.

The paper's Section 3.3 puts the 5 x 91-cell honeycomb on a ship and powers
electronics through an LTC3588 energy-harvesting chip. This demo charges the
chip's input capacitor through one full bridge per cell (``[array] connection
= "rectified-parallel"``: every cell's bridge feeds the same store) and lets
the chip's under-voltage lockout switch a regulated 3.3 V load on and off.
It prints the time to the first UVLO crossing, the chip's duty cycle once it
has started and the energy per burst, and compares the array with N x one
cell (its loss to the cells' phase spread).

What is assumed (each a scene key, change them to study the question):

* the cell: the cylindrical cell of equal cross-section of
  ``electrical_honeycomb.py`` (fast geometry, axisymmetric field; the
  hexagonal 3D cell of the full honeycomb demo costs a 3D surrogate);
* the ball's charge density: the one that reproduces the paper's 153.14 nC
  peak-to-peak for 455 cells (docs/demos.md's calibration rule; the field is
  linear in sigma, so the surrogate is rescaled, not re-solved);
* C_p = 0: the electrometer (321 pF in docs/demos.md) is not part of the
  harvesting circuit; the chip's own input capacitance is inside the store;
* the bridges: ideal diodes with the 0 V default drop (the LTC3588's
  integrated bridge has a few hundred mV; set ``diode_forward_voltage_V``);
* the store: 10 uF at the chip's input, no leakage; the chip: LTC3588-1
  data-sheet UVLO 5.05 V rising / 4.04 V falling, 3.3 V out, 90 % efficiency,
  450 nA quiescent; its load 100 kOhm (33 uA at 3.3 V: a sensor node);
* the array: every cell its own impact-map dynamics with a 60 degree phase
  spread, restitution 0.1 +- 0.01 and launch speeds up to 0.05 m/s (seed 1):
  an illustration of a real array's scatter, not a measured one.

    .venv/bin/python demos/harvest_ship.py [--fast] [-o DIR] [--cache-dir DIR]
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from demo_mpi import is_root, world  # noqa: E402
from electrical_common import demo_arguments, measure, surrogate_curves  # noqa: E402
from electrical_honeycomb import PAPER, honeycomb_scene  # noqa: E402

from tengfield import electrical  # noqa: E402
from tengfield.array import run_array  # noqa: E402
from tengfield.dynamics import simulate  # noqa: E402
from tengfield.plotting.harvest import plot_array, plot_charging  # noqa: E402
from tengfield.surrogate import TerminalCurves  # noqa: E402

CELLS = 455
STORE_UF = 10.0
CHIP_LOAD_OHM = 1e5


def harvest_scene(base, fast: bool):
    """The calibration scene turned into the harvesting one ([array] + rectifier + chip)."""
    freq = base.excitation.frequency
    periods = 330 if fast else 660
    return base.with_values(
        device={"cells": 1},
        run={"duration_s": periods / freq, "settle_periods": 30,
             "sample_rate_hz": (20 if fast else 50) * freq},
        circuit={"kind": "rectifier", "storage_capacitance_uF": STORE_UF, "pmic": "uvlo",
                 "pmic_load_ohm": CHIP_LOAD_OHM, "parallel_capacitance_pF": 0.0},
        array={"cells": CELLS, "connection": "rectified-parallel",
               "initial_phase_spread_deg": 60.0, "restitution_spread": 0.02,
               "initial_velocity_spread_m_per_s": 0.05, "seed": 1})


def main(argv: list[str] | None = None) -> dict:
    args = demo_arguments(__doc__, argv)
    out = Path(args.output)
    _, base = honeycomb_scene(fast=True)       # cylindrical equal-area cell, 455 cells
    if not args.fast:
        base = base.with_values(field={"degree": 2, "mesh_size_mm": 0.4, "tolerance": 1e-3})
    table, curves = surrogate_curves(base, args.cache_dir)
    ideal = measure(curves, simulate(base), base)
    scale = PAPER["Q_sc"] / ideal["Q_sc"]
    sigma = base.device.surface_charge * scale
    curves = TerminalCurves(table, base.circuit.reference, base.device.ball_charge * scale)

    scene = harvest_scene(base, args.fast)
    nominal = simulate(scene)
    arr = run_array(scene, curves, nominal, comm=world())
    fine = arr.fine
    mask, _ = electrical.steady_window(fine.time, scene)
    rect = electrical.rectifier_summary(scene, fine, float(fine.time[mask][0]))
    c = scene.circuit
    first_on = rect["chip_first_on_s"]
    t, on = fine.time, fine.chip_on
    after = t >= first_on if np.isfinite(first_on) else np.zeros_like(t, dtype=bool)
    dt = np.diff(t)
    duty = (float(np.sum(dt[on[1:] & after[1:]]) / np.sum(dt[after[1:]]))
            if after[1:].any() else float("nan"))
    burst = c.pmic_efficiency * 0.5 * c.storage_capacitance * (c.uvlo_rising**2
                                                               - c.uvlo_falling**2)
    load_power = c.pmic_output**2 / c.pmic_load
    result = {
        "cells": CELLS, "sigma_uC_per_m2": sigma * 1e6, "regime": nominal.regime.name,
        "time_to_first_uvlo_rising_s": first_on,
        "time_to_uvlo_falling_level_s": rect["time_to_uvlo_falling_V_s"],
        "chip_bursts": rect["chip_switch_on_count"], "duty_cycle_after_first_on": duty,
        "burst_output_energy_J": burst, "chip_load_power_W": load_power,
        "average_harvested_power_W": rect["average_harvested_power_W"],
        "expected_duty_cycle": rect["average_harvested_power_W"] * c.pmic_efficiency / load_power,
        "array_over_N_cells": arr.summary["array_over_N_cells"],
        "phase_std_deg": arr.summary["phase_std_deg"],
        "energy_residual_max": max(rect["energy_residuals"].values()),
        "wall_time_s": arr.summary["dynamics_wall_time_s"] + arr.summary["electrical_wall_time_s"],
    }
    print(f"honeycomb on the ship: {CELLS} cells, 0.5 mm, 33 Hz, regime {result['regime']}; "
          f"sigma = {sigma * 1e6:.4g} uC/m^2 (153.14 nC pp)")
    print(f"per-cell bridges into {STORE_UF:g} uF, LTC3588-1 UVLO {c.uvlo_rising:g}/"
          f"{c.uvlo_falling:g} V, {c.pmic_output:g} V into {CHIP_LOAD_OHM / 1e3:g} kOhm")
    print(f"store reaches {c.uvlo_falling:g} V at {result['time_to_uvlo_falling_level_s']:.4g} s; "
          f"first UVLO crossing ({c.uvlo_rising:g} V) at {first_on:.4g} s")
    print(f"chip bursts: {result['chip_bursts']}, duty cycle after the first: {duty:.4g} "
          f"(harvested power x efficiency / load power = {result['expected_duty_cycle']:.4g}); "
          f"{burst * 1e6:.4g} uJ out per burst")
    print(f"average harvested power {result['average_harvested_power_W'] * 1e6:.4g} uW; array / "
          f"(N x one cell) = {result['array_over_N_cells']:.4g} (phase std "
          f"{result['phase_std_deg']:.3g} deg); energy books residual "
          f"{result['energy_residual_max']:.2g}")
    title = f"ship: {CELLS} cells, 0.5 mm, 33 Hz, per-cell bridges"
    if is_root():
        plot_charging(fine, scene, out / "harvest_ship.png", title=title)
        plot_array(arr, {**arr.summary, "connection": "rectified-parallel"},
                   out / "harvest_ship_array.png", title=title)
    print(f"wrote {out / 'harvest_ship.png'}, {out / 'harvest_ship_array.png'}")
    return result


if __name__ == "__main__":
    main()
