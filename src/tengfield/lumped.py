"""The device as a lumped element with its load (pure numerics, SI, DESIGN §6): the
terminal quantities Q_SC(z), C_T(z) across R || C_p. (Was ``tengfield.circuit``; the
circuit kinds of ``[circuit] kind`` are :mod:`tengfield.electrical.circuits`.)

Conventions follow :mod:`tengfield.terminals`: the terminal voltage is
``V = V_lower - V_upper`` [V]; ``Q_SC(z)`` [C] is the charge that moves from the
lower to the upper electrode through a short circuit since the reference
state (ball on the lower electrode, z = 0); currents [A] are positive from
lower to upper through the external circuit.

The instrument/cable capacitance ``C_p`` [F] sits across the terminals, in
parallel with the load resistance ``R`` [ohm]. With ``Q_R`` the charge that
has passed through ``R`` (lower -> upper), the terminal relation
``V = (Q_SC - Q_t) / C_T`` with ``Q_t = Q_R + C_p V`` gives

    V = (Q_SC(z) - Q_R) / (C_T(z) + C_p),      dQ_R/dt = V / R,

which is DESIGN §6's ``(C_T + C_p) dV/dt = dQ_SC/dt - V dC_T/dt - V/R``.
:func:`load_response` integrates it for the *deficit* ``D = Q_SC - Q_R =
(C_T + C_p) V``, ``dD/dt = I_SC(t) - D / (R (C_T + C_p))``, with an
exponential integrator that is exact in both limits (R -> 0: ``V -> R I_SC``;
R -> inf: ``V -> Q_SC / (C_T + C_p)``) and stable for any ``R``.

``cells = N`` identical cells wired in parallel: Q_SC, I_SC and C_T scale
with N (:func:`scale_cells`), V_OC does not.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def scale_cells(q_sc, dq_sc_dz, c_t, dc_t_dz, cells: int):
    """One cell's terminal quantities -> ``cells`` identical cells in parallel.

    Charges [C], their z-derivatives [C/m], capacitances [F] and their
    derivatives [F/m] are multiplied by ``cells``.
    """
    n = float(cells)
    return (np.asarray(q_sc) * n, np.asarray(dq_sc_dz) * n,
            np.asarray(c_t) * n, np.asarray(dc_t_dz) * n)


def open_circuit_voltage(q_sc, c_t, parallel_capacitance: float = 0.0):
    """Voltage [V] across the terminals with no load: ``Q_SC / (C_T + C_p)``.

    With ``C_p = 0`` this is the true V_OC; an instrument of capacitance
    ``C_p`` [F] reads the smaller value.
    """
    return np.asarray(q_sc, dtype=float) / (np.asarray(c_t, dtype=float) + parallel_capacitance)


def short_circuit_current(dq_sc_dz, gap_velocity):
    """I_SC = (dQ_SC/dz) * dz/dt [A] (lower -> upper through the short)."""
    return np.asarray(dq_sc_dz, dtype=float) * np.asarray(gap_velocity, dtype=float)


def _phi1(x):
    """(1 - e^-x) / x, accurate for small x >= 0."""
    x = np.asarray(x, dtype=float)
    small = x < 1e-8
    safe = np.where(small, 1.0, x)
    return np.where(small, 1.0 - 0.5 * x, -np.expm1(-safe) / safe)


def _psi(x):
    """(1 - e^-x (1 + x)) / x^2, accurate for small x >= 0 (series below 1e-3)."""
    x = np.asarray(x, dtype=float)
    small = x < 1e-3
    safe = np.where(small, 1.0, x)
    series = 0.5 - x / 3.0 + x * x / 8.0 - x**3 / 30.0
    exact = (-np.expm1(-safe) - safe * np.exp(-safe)) / (safe * safe)
    return np.where(small, series, exact)


@dataclass(frozen=True)
class LoadResponse:
    """Waveforms of a resistive load (arrays on the input time grid, SI).

    ``voltage`` V = V_lower - V_upper [V]; ``current`` through R [A]
    (lower -> upper outside the device); ``power`` V^2/R [W] dissipated in R;
    ``charge`` Q_R [C] passed through R since the start.
    """
    voltage: np.ndarray
    current: np.ndarray
    power: np.ndarray
    charge: np.ndarray


def load_response(times, q_sc, i_sc, c_t, load_ohm: float, parallel_capacitance: float = 0.0,
                  initial_load_charge: float = 0.0) -> LoadResponse:
    """Integrate the load circuit along a sampled trajectory.

    Parameters
    ----------
    times:
        Non-decreasing sample times [s]. A repeated time marks a jump of
        ``i_sc`` (an impact): the step of zero length carries no charge and
        the next step starts from the value after the jump.
    q_sc, i_sc, c_t:
        Q_SC(z(t)) [C], I_SC = dQ_SC/dt [A] and C_T(z(t)) [F] at ``times``
        (already scaled for the number of cells).
    load_ohm:
        R [ohm], any value in (0, inf).
    parallel_capacitance:
        C_p [F] across the terminals.
    initial_load_charge:
        Q_R at ``times[0]`` [C]; the default 0 means no charge has passed
        through R since the reference state, so the run starts at the
        open-circuit voltage (the R -> inf solution).

    Method: with ``Λ(t) = ∫ dt / (R (C_T + C_p))`` the deficit
    ``D = (C_T + C_p) V`` obeys ``dD/dΛ = f - D``, ``f = R (C_T + C_p) I_SC``.
    Over each step ``Λ`` is integrated by the trapezoidal rule and ``f`` is
    taken linear in ``Λ``; the step is then solved exactly (exponential
    integrator, second order, unconditionally stable, exact quasi-static
    limit ``D = f`` for R C -> 0 and exact ``ΔD = ∫ I_SC dt`` for R -> inf).
    """
    t = np.asarray(times, dtype=float)
    q_sc = np.asarray(q_sc, dtype=float)
    i_sc = np.asarray(i_sc, dtype=float)
    c_total = np.asarray(c_t, dtype=float) + parallel_capacitance
    if not (load_ohm > 0.0 and np.isfinite(load_ohm)):
        raise ValueError(f"load_ohm = {load_ohm!r} is out of range: allowed (0, inf)")
    if np.any(np.diff(t) < 0):
        raise ValueError("times must be non-decreasing")
    rate = 1.0 / (load_ohm * c_total)            # 1 / (R C) [1/s]
    forcing = i_sc / rate                        # f = R C I_SC [C]
    dt = np.diff(t)
    x = 0.5 * (rate[:-1] + rate[1:]) * dt        # ΔΛ per step (>= 0)
    decay = np.exp(-x)
    phi1 = _phi1(x)
    psi = _psi(x)
    # D1 = e^-x D0 + x [f0 phi1 + (f1 - f0)(phi1 - psi)]
    gain_start = x * psi                    # weight of f0
    gain_end = x * (phi1 - psi)             # weight of f1
    source = gain_start * forcing[:-1] + gain_end * forcing[1:]
    from ._lumped_kernel import deficit_recurrence   # numba: loaded when a load is solved

    deficit = deficit_recurrence(decay, source, float(q_sc[0] - initial_load_charge))
    voltage = deficit / c_total
    current = voltage / load_ohm
    return LoadResponse(voltage=voltage, current=current, power=voltage * current,
                        charge=q_sc - deficit)


def delivered_power(voltage, q_sc_rate, c_t_rate):
    """Electrical power the mechanics puts into the circuit [W].

    ``P_in = V dQ_SC/dt - V^2/2 dC_T/dt``; it balances
    ``d/dt [(C_T + C_p) V^2 / 2] + V^2 / R`` (stored + dissipated).
    """
    v = np.asarray(voltage, dtype=float)
    return v * np.asarray(q_sc_rate, dtype=float) - 0.5 * v * v * np.asarray(c_t_rate, dtype=float)


def stored_energy(voltage, c_t, parallel_capacitance: float = 0.0):
    """Energy (C_T + C_p) V^2 / 2 [J] of the terminal capacitance."""
    v = np.asarray(voltage, dtype=float)
    return 0.5 * (np.asarray(c_t, dtype=float) + parallel_capacitance) * v * v


def peak_to_peak(values) -> float:
    """max - min of a waveform (0 for an empty one)."""
    v = np.asarray(values, dtype=float)
    return float(v.max() - v.min()) if v.size else 0.0
