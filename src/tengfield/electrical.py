"""Electrical outputs of a trajectory: the one place that turns z(t) into V, Q, I.

Every consumer (:func:`tengfield.pipeline.run`, :mod:`tengfield.sweep`,
:mod:`tengfield.report`, the demos) calls these functions, so ``run``,
``sweep`` and ``report`` give the same numbers for the same scene:

* :func:`terminal_waveforms`: V_OC, Q_SC, I_SC (and C_T) along sampled
  z(t), ż(t) for ``cells`` identical cells in parallel read through a
  parallel capacitance C_p;
* :func:`scene_waveforms`: the same for a dynamics result, with ``cells``
  and C_p taken from the scene, as the ``waveforms.csv`` columns;
* :func:`steady_window`: the samples after ``[run] settle_periods`` periods;
* :func:`terminal_peaks`: peak-to-peak V_OC, Q_SC, I_SC over the steady
  window, over the samples *and* just before/after every impact (where
  I_SC jumps and takes its extremes);
* :func:`load_waveforms`: the load ODE along the trajectory (V_load, I_load,
  P_load, mean power, energy balance).

Units are SI; signs are those of :mod:`tengfield.terminals` (V = V_lower -
V_upper, charges and currents counted lower -> upper through the external
circuit, reference state z = 0).
"""
from __future__ import annotations

import math

import numpy as np

from . import circuit

#: columns of ``waveforms.csv`` (SI units in the names)
WAVEFORM_COLUMNS = ["time_s", "gap_m", "gap_velocity_m_per_s", "table_m",
                    "V_oc_V", "Q_sc_C", "I_sc_A"]
#: extra columns when a load is connected
LOAD_COLUMNS = ["V_load_V", "I_load_A", "P_load_W"]
#: the peak-to-peak quantities and their ``waveforms`` column
PEAK_QUANTITIES = {"V_oc": "V_oc_V", "Q_sc": "Q_sc_C", "I_sc": "I_sc_A"}
#: the pre-/post-impact states are sampled this many excitation periods from an impact
IMPACT_OFFSET_PERIODS = 1e-9


# ---------------------------------------------------------------------------
# waveforms
def terminal_waveforms(curves, gap, gap_velocity, *, cells: int = 1,
                       parallel_capacitance: float = 0.0) -> dict[str, np.ndarray]:
    """Open-circuit voltage, short-circuit charge and current along a trajectory.

    ``curves``: :class:`tengfield.surrogate.TerminalCurves` of ONE cell, or
    None when Q_SC is identically zero (then C_T is unknown and NaN).
    ``gap`` z(t) [m] and ``gap_velocity`` dz/dt [m/s] are samples of the
    trajectory; ``cells`` identical cells are wired in parallel and read
    through ``parallel_capacitance`` C_p [F]. Returns ``V_oc`` [V]
    (= Q_SC / (C_T + C_p), the true V_OC when C_p = 0), ``Q_sc`` [C],
    ``I_sc`` = (dQ_SC/dz) dz/dt [A], ``C_T`` [F] and ``dC_T_dt`` [F/s].
    """
    gap = np.asarray(gap, dtype=float)
    velocity = np.asarray(gap_velocity, dtype=float)
    if curves is None:
        zero = np.zeros_like(gap)
        return {"V_oc": zero, "Q_sc": zero.copy(), "I_sc": zero.copy(),
                "C_T": np.full_like(gap, np.nan), "dC_T_dt": zero.copy()}
    q_sc, dq_dz, c_t, dc_dz = circuit.scale_cells(
        curves.charge(gap), curves.charge_derivative(gap), curves.capacitance(gap),
        curves.capacitance_derivative(gap), cells)
    return {"V_oc": circuit.open_circuit_voltage(q_sc, c_t, parallel_capacitance),
            "Q_sc": q_sc, "I_sc": circuit.short_circuit_current(dq_dz, velocity),
            "C_T": c_t, "dC_T_dt": dc_dz * velocity}


def scene_terminal_waveforms(scene, curves, gap, gap_velocity) -> dict[str, np.ndarray]:
    """:func:`terminal_waveforms` with ``[device] cells`` and ``[circuit]
    parallel_capacitance_pF`` of ``scene``."""
    return terminal_waveforms(curves, gap, gap_velocity, cells=scene.device.cells,
                              parallel_capacitance=scene.circuit.parallel_capacitance)


def scene_waveforms(scene, dynamics, curves) -> dict[str, np.ndarray]:
    """The ``WAVEFORM_COLUMNS`` of ``dynamics`` (a DynamicsResult or anything with
    ``t, gap, gap_velocity, table``) for ``scene``: time, trajectory and the
    terminal waveforms at the output samples."""
    t = np.asarray(dynamics.t, dtype=float)
    gap = np.asarray(dynamics.gap, dtype=float)
    velocity = np.asarray(dynamics.gap_velocity, dtype=float)
    terminal = scene_terminal_waveforms(scene, curves, gap, velocity)
    table = getattr(dynamics, "table", None)
    return {"time_s": t, "gap_m": gap, "gap_velocity_m_per_s": velocity,
            "table_m": np.zeros_like(t) if table is None else np.asarray(table, dtype=float),
            "V_oc_V": terminal["V_oc"], "Q_sc_C": terminal["Q_sc"], "I_sc_A": terminal["I_sc"]}


# ---------------------------------------------------------------------------
# the steady window and the impacts
def steady_window(times, scene) -> tuple[np.ndarray, str]:
    """Boolean mask of the samples after ``[run] settle_periods`` excitation periods,
    and the rule in words (the whole run when that leaves fewer than 2 samples)."""
    t = np.asarray(times, dtype=float)
    start = t[0] + scene.run.settle_periods * scene.excitation.period
    mask = t >= start
    if np.count_nonzero(mask) < 2:
        return np.ones_like(t, dtype=bool), (f"whole run: settle_periods x period = "
                                             f"{start - t[0]:g} s leaves fewer than 2 samples")
    return mask, f"t >= {start:g} s (after settle_periods = {scene.run.settle_periods} periods)"


def impact_times(dynamics, start: float, end: float) -> np.ndarray:
    """Sorted distinct times [s] of the impacts (velocity jumps) strictly inside (start, end).

    ``dynamics.impacts`` may be :class:`tengfield.dynamics.Impacts`, a record
    array with a ``time`` field, an array whose first column is the time, or
    a list of objects with ``time`` (or ``t``); no ``impacts``: none.
    """
    impacts = getattr(dynamics, "impacts", None)
    if impacts is None:
        return np.empty(0)
    if hasattr(impacts, "time"):                      # tengfield.dynamics.Impacts
        times = np.asarray(impacts.time, dtype=float).reshape(-1)
    elif hasattr(impacts, "dtype") and impacts.dtype.names and "time" in impacts.dtype.names:
        times = np.asarray(impacts["time"], dtype=float)
    elif isinstance(impacts, np.ndarray):
        times = np.asarray(impacts, dtype=float).reshape(len(impacts), -1)[:, 0] \
            if impacts.size else np.empty(0)
    else:
        times = np.asarray([getattr(i, "time", getattr(i, "t", math.nan)) for i in impacts],
                           dtype=float)
    times = times[np.isfinite(times)]
    return np.unique(times[(times > start) & (times < end)])


def impact_states(scene, dynamics, impacts) -> tuple[np.ndarray, ...]:
    """``(gap_before, velocity_before, gap_after, velocity_after)`` at the ``impacts``
    [s], sampled ``IMPACT_OFFSET_PERIODS`` periods before and after each one."""
    if not len(impacts) or not hasattr(dynamics, "sample"):
        empty = np.empty(0)
        return empty, empty, empty, empty
    eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
    gap_pre, vel_pre, _ = dynamics.sample(impacts - eps)
    gap_post, vel_post, _ = dynamics.sample(impacts + eps)
    return gap_pre, vel_pre, gap_post, vel_post


# ---------------------------------------------------------------------------
# peaks
def extreme_times(scene, dynamics, start: float) -> np.ndarray:
    """Sorted times [s] at which a waveform's extremes after ``start`` are sought:
    the dynamics' output samples from ``start`` on and just before and after
    every impact there (``IMPACT_OFFSET_PERIODS``), the same instants as
    :func:`terminal_peaks` uses."""
    t = np.asarray(dynamics.t, dtype=float)
    t = t[t >= start]
    impacts = impact_times(dynamics, t[0], t[-1]) if t.size else np.empty(0)
    eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
    return np.sort(np.concatenate([t, impacts - eps, impacts + eps]))


def terminal_peaks(scene, dynamics, curves, waveforms: dict | None = None) -> dict[str, float]:
    """Peak-to-peak ``V_oc`` [V], ``Q_sc`` [C], ``I_sc`` [A] over the steady window.

    The extremes are taken over the output samples of the window *and* just
    before and after every impact in it (``IMPACT_OFFSET_PERIODS``), where
    I_SC = (dQ_SC/dz) ż jumps and takes its extremes: the trajectory is exact
    there, so the peaks do not depend on ``[run] sample_rate_hz`` (sampled
    alone, the I_SC peak of the default scene is 3 % low at 20 kHz;
    docs/report.md). ``cells`` and C_p come from ``scene``; ``waveforms``
    (the :func:`scene_waveforms` of the same scene and dynamics) saves
    recomputing the samples.
    """
    if waveforms is None:
        waveforms = scene_waveforms(scene, dynamics, curves)
    t = np.asarray(waveforms["time_s"], dtype=float)
    mask, _ = steady_window(t, scene)
    values = {name: [np.asarray(waveforms[column])[mask]]
              for name, column in PEAK_QUANTITIES.items()}
    if curves is not None:
        gap_pre, vel_pre, gap_post, vel_post = impact_states(
            scene, dynamics, impact_times(dynamics, t[mask][0], t[-1]))
        if gap_pre.size:
            extra = scene_terminal_waveforms(scene, curves, np.concatenate([gap_pre, gap_post]),
                                             np.concatenate([vel_pre, vel_post]))
            for name in PEAK_QUANTITIES:
                values[name].append(extra[name])
    return {name: circuit.peak_to_peak(np.concatenate(v)) for name, v in values.items()}


# ---------------------------------------------------------------------------
# the load ODE along a trajectory with impacts
def relaxation_times(starts, time_constant: float, output_step: float, end: float) -> np.ndarray:
    """Extra integration times after each jump of I_SC: ``start + τ 2^(k/4)``, k = -16..24.

    The load voltage relaxes in ``τ = R (C_T + C_p)`` after an impact; when τ
    is not resolved by the output step these points let the trapezoidal
    energy sums (mean power, energy balance) see the transient. Only offsets
    below 4 output steps are used (longer transients are already resolved).
    """
    offsets = time_constant * 2.0 ** (np.arange(-16, 25) / 4.0)
    offsets = offsets[offsets < 4.0 * output_step]
    if offsets.size == 0 or len(starts) == 0:
        return np.empty(0)
    extra = (np.asarray(starts, dtype=float)[:, None] + offsets[None, :]).ravel()
    return extra[extra < end]


def load_waveforms(scene, dynamics, curves, *, window_start: float | None = None) -> dict:
    """V_load [V], I_load [A], P_load [W] at the output samples, mean power and energy balance.

    The load is ``[circuit] load_ohm`` with ``cells`` and C_p of ``scene``.
    The exponential integrator of :func:`tengfield.circuit.load_response`
    runs on a fine grid: the output times, every impact time twice (pre- and
    post-impact velocity, so the jumps of I_SC are exact) and
    :func:`relaxation_times` after the start and each impact. Energies are
    trapezoidal sums on that grid over the window after ``window_start`` [s]
    (default: the whole run); ``mean_power_W`` is the dissipated energy
    divided by the window length.
    """
    t = np.asarray(dynamics.t, dtype=float)
    n_cells = scene.device.cells
    c_p = scene.circuit.parallel_capacitance
    load = scene.circuit.load
    window_start = t[0] if window_start is None else window_start
    if curves is None:
        zero = np.zeros_like(t)
        return {"V_load": zero, "I_load": zero.copy(), "P_load": zero.copy(), "mean_power_W": 0.0,
                "delivered_energy_J": 0.0, "dissipated_energy_J": 0.0,
                "stored_energy_change_J": 0.0, "integration_points": int(t.size),
                "time_constant_s": 0.0}
    impacts = impact_times(dynamics, t[0], t[-1])
    output_step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    c_min = float(np.min(curves.capacitance_samples)) * n_cells + c_p
    extra = relaxation_times(np.concatenate([[t[0]], impacts]), load * c_min, output_step, t[-1])
    gap_pre, vel_pre, gap_post, vel_post = impact_states(scene, dynamics, impacts)
    gap_extra, vel_extra, _ = dynamics.sample(extra) if extra.size else (np.empty(0),) * 3
    grid = np.concatenate([t, impacts, impacts, extra])
    gap = np.concatenate([np.asarray(dynamics.gap, dtype=float), gap_pre, gap_post, gap_extra])
    vel = np.concatenate([np.asarray(dynamics.gap_velocity, dtype=float), vel_pre, vel_post,
                          vel_extra])
    # equal times: pre-impact (0) before an output sample (1) before post-impact (2)
    tag = np.concatenate([np.ones(t.size), np.zeros(impacts.size), np.full(impacts.size, 2.0),
                          np.full(extra.size, 3.0)])
    order = np.lexsort((tag, grid))
    grid, gap, vel = grid[order], gap[order], vel[order]
    output_index = np.flatnonzero(order < t.size)   # order[...] of outputs is increasing
    fine = scene_terminal_waveforms(scene, curves, gap, vel)
    response = circuit.load_response(grid, fine["Q_sc"], fine["I_sc"], fine["C_T"], load, c_p)
    delivered = circuit.delivered_power(response.voltage, fine["I_sc"], fine["dC_T_dt"])
    stored = circuit.stored_energy(response.voltage, fine["C_T"], c_p)
    in_window = grid >= window_start
    t_window = grid[in_window]
    window_length = t_window[-1] - t_window[0] if t_window.size > 1 else 0.0
    dissipated = float(np.trapz(response.power[in_window], t_window))
    stored_window = stored[in_window]
    return {"V_load": response.voltage[output_index], "I_load": response.current[output_index],
            "P_load": response.power[output_index],
            "mean_power_W": dissipated / window_length if window_length > 0 else 0.0,
            "delivered_energy_J": float(np.trapz(delivered[in_window], t_window)),
            "dissipated_energy_J": dissipated,
            "stored_energy_change_J": float(stored_window[-1] - stored_window[0]),
            "integration_points": int(grid.size),
            "time_constant_s": load * (float(np.max(curves.capacitance_samples)) * n_cells + c_p)}


def steady_load(scene, dynamics, curves) -> dict:
    """:func:`load_waveforms` with energies over the :func:`steady_window`."""
    t = np.asarray(dynamics.t, dtype=float)
    mask, _ = steady_window(t, scene)
    return load_waveforms(scene, dynamics, curves, window_start=t[mask][0])
