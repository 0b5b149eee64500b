"""Energy per cycle: V-Q loops and the CMEO bound (Zi et al. 2015), whatever the circuit."""
from __future__ import annotations

import math

import numpy as np


def loop_area(voltage, charge) -> float:
    """∮ V dQ [J] of a sampled loop (trapezoidal; positive when energy leaves the TENG)."""
    v = np.asarray(voltage, dtype=float)
    q = np.asarray(charge, dtype=float)
    return float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(q)))


def cumulative(t, current):
    """∫ I dt [C] from the first sample (trapezoidal)."""
    q = np.zeros_like(t)
    q[1:] = np.cumsum(0.5 * (current[1:] + current[:-1]) * np.diff(t))
    return q


def last_period(times, period: float) -> np.ndarray:
    """Mask of the samples in the last full excitation period."""
    t = np.asarray(times, dtype=float)
    return t >= t[-1] - period


def cmeo(scene, curves, max_gap: float) -> dict:
    """Cycles for maximised energy output (Zi et al. 2015) for a stroke 0 -> ``max_gap``
    [m] of ``[device] cells`` identical cells, and the structural figure of merit
    (area = the ball's surface pi d^2 per cell, x_max = ``max_gap``), on the axis.

    Both are the device's own: the instrument's capacitance C_p (``[circuit]
    parallel_capacitance_pF``) does not enter them. With C_p > 0 the CMEO of the
    device read through the instrument is the separately named
    ``max_energy_per_cycle_with_instrument_J`` (C_T + C_p in both states)."""
    from ..harvest import max_energy_per_cycle, structural_figure_of_merit

    curves = curves.axis   # a (z, r) surrogate: the stroke on the axis
    n = scene.device.cells
    c_p = scene.circuit.parallel_capacitance
    q_max = abs(float(curves.charge(max_gap)) - float(curves.charge(0.0))) * n
    c_max = float(curves.capacitance(max_gap)) * n
    c_0 = float(curves.capacitance(0.0)) * n
    energy = max_energy_per_cycle(q_max, c_max, c_0)
    dev = scene.device
    area = math.pi * dev.ball_diameter**2 * n
    fom = structural_figure_of_merit(energy, dev.surface_charge, area, max_gap) \
        if dev.surface_charge != 0 and max_gap > 0 else math.nan
    out = {"max_energy_per_cycle_J": energy, "Q_sc_max_C": q_max,
           "V_oc_max_V": q_max / c_max, "V_return_max_V": q_max / c_0,
           "C_at_max_gap_F": c_max, "C_at_zero_F": c_0, "max_gap_m": max_gap,
           "figure_of_merit_structural": fom, "fom_area_m2": area,
           "fom_rule": "FOM_S = 2 eps0 E_m / (sigma^2 A x_max), A = pi d^2 x cells (the "
                       "charged ball surface), x_max = the largest gap reached; E_m = "
                       "Q_SC,max (V_OC,max + |V'_max|) / 2 (Zi et al., Nat. Commun. 6:8376, "
                       "2015); the device's own: the instrument's C_p does not enter"}
    if c_p > 0.0:
        out["max_energy_per_cycle_with_instrument_J"] = max_energy_per_cycle(
            q_max, c_max + c_p, c_0 + c_p)
        out["instrument_capacitance_F"] = c_p
    return out
