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

#: ∫ y dx by the trapezoidal rule: numpy 2's name (numpy 1 has only ``trapz``, which
#: numpy 2 deprecates)
trapezoid = np.trapezoid if hasattr(np, "trapezoid") else np.trapz

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
# the run's own time axis
def time_origin(dynamics) -> float:
    """``[initial] time_s`` of ``dynamics`` [s] (its ``time_origin``; 0 without one)."""
    return float(getattr(dynamics, "time_origin", 0.0) or 0.0)


def elapsed_times(dynamics) -> np.ndarray:
    """The output times of ``dynamics`` on the run's own axis, ``t - time_origin`` [s]
    (exact: ``dynamics.elapsed`` when it has one). Every circuit is integrated on this
    axis, so its precision does not depend on the absolute time (at t ~ 1.7e9 s the
    doubles are 2.4e-7 s apart, far coarser than the impact offsets)."""
    elapsed = getattr(dynamics, "elapsed", None)
    if elapsed is not None:
        return np.asarray(elapsed, dtype=float)
    return np.asarray(dynamics.t, dtype=float) - time_origin(dynamics)


def sample_elapsed(dynamics, elapsed):
    """(gap, gap velocity, table) of ``dynamics`` at ``elapsed`` times [s] after its origin."""
    sampler = getattr(dynamics, "sample_elapsed", None)
    if sampler is not None:
        return sampler(elapsed)
    return dynamics.sample(np.asarray(elapsed, dtype=float) + time_origin(dynamics))


def impact_elapsed(dynamics, start: float, end: float) -> np.ndarray:
    """:func:`impact_times` on the run's own axis (``start``, ``end`` and the result in
    seconds after ``time_origin``). The stored impact times are absolute (rounded to the
    doubles near ``time_origin``); with a non-zero origin each one is put back on the
    exact velocity jump of the trajectory by bisection over those few ulp."""
    origin = time_origin(dynamics)
    if origin == 0.0:
        return impact_times(dynamics, start, end)
    absolute = impact_times(dynamics, -math.inf, math.inf)
    if absolute.size == 0 or not (hasattr(dynamics, "sample")
                                  or hasattr(dynamics, "sample_elapsed")):
        return np.empty(0)
    approx = absolute - origin
    ulp = np.spacing(np.abs(absolute))
    lo, hi = np.maximum(approx - ulp, 0.0), approx + ulp
    _, v_lo, _ = sample_elapsed(dynamics, lo)
    _, v_hi, _ = sample_elapsed(dynamics, hi)
    v_lo, v_hi = np.array(v_lo, dtype=float), np.array(v_hi, dtype=float)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        active = (mid > lo) & (mid < hi)
        if not active.any():
            break
        _, v_mid, _ = sample_elapsed(dynamics, mid)
        before = np.abs(v_mid - v_lo) <= np.abs(v_mid - v_hi)   # mid is before the jump
        lo = np.where(active & before, mid, lo)
        v_lo = np.where(active & before, v_mid, v_lo)
        hi = np.where(active & ~before, mid, hi)
        v_hi = np.where(active & ~before, v_mid, v_hi)
    times = np.unique(hi)
    return times[(times > start) & (times < end)]


# ---------------------------------------------------------------------------
# waveforms
def terminal_waveforms(curves, gap, gap_velocity, *, cells: int = 1,
                       parallel_capacitance: float = 0.0, radial=None,
                       radial_velocity=None) -> dict[str, np.ndarray]:
    """Open-circuit voltage, short-circuit charge and current along a trajectory.

    ``curves``: the :class:`tengfield.surrogate.Curves` of ONE cell, or None when
    Q_SC is identically zero (then C_T is unknown and NaN). ``gap`` z(t) [m] and
    ``gap_velocity`` dz/dt [m/s] are samples of the trajectory; ``cells``
    identical cells are wired in parallel and read through
    ``parallel_capacitance`` C_p [F]. Returns ``V_oc`` [V] (= Q_SC / (C_T + C_p),
    the true V_OC when C_p = 0), ``Q_sc`` [C], ``I_sc`` = (dQ_SC/dz) dz/dt [A],
    ``C_T`` [F] and ``dC_T_dt`` [F/s]. For (z, r) curves (``curves.radial``)
    ``radial`` r(t) [m] and ``radial_velocity`` dr/dt [m/s] (default 0) enter, and
    ``I_sc = dQ_SC/dz ż + dQ_SC/dr ṙ`` (:meth:`tengfield.surrogate.Curves.evaluate_many`).
    """
    gap = np.asarray(gap, dtype=float)
    if curves is None:
        zero = np.zeros_like(gap)
        return {"V_oc": zero, "Q_sc": zero.copy(), "I_sc": zero.copy(),
                "C_T": np.full_like(gap, np.nan), "dC_T_dt": zero.copy()}
    q_sc, i_sc, c_t, dc_dt = curves.evaluate_many(gap, gap_velocity, radial, radial_velocity,
                                                  cells=cells)
    return {"V_oc": circuit.open_circuit_voltage(q_sc, c_t, parallel_capacitance),
            "Q_sc": q_sc, "I_sc": i_sc, "C_T": c_t, "dC_T_dt": dc_dt}


def terminal_waveforms_zr(curves, gap, gap_velocity, radial, radial_velocity, *,
                          cells: int = 1, parallel_capacitance: float = 0.0) -> dict:
    """:func:`terminal_waveforms` for an off-axis trajectory: ``radial`` r(t) [m] and
    ``radial_velocity`` dr/dt [m/s] at the samples (the name the (z, r) docs use)."""
    return terminal_waveforms(curves, gap, gap_velocity, cells=cells,
                              parallel_capacitance=parallel_capacitance, radial=radial,
                              radial_velocity=radial_velocity)


def scene_terminal_waveforms(scene, curves, gap, gap_velocity, radial=None,
                             radial_velocity=None) -> dict[str, np.ndarray]:
    """:func:`terminal_waveforms` with ``[device] cells`` and ``[circuit]
    parallel_capacitance_pF`` of ``scene``."""
    return terminal_waveforms(curves, gap, gap_velocity, cells=scene.device.cells,
                              parallel_capacitance=scene.circuit.parallel_capacitance,
                              radial=radial, radial_velocity=radial_velocity)


def _radial(dynamics, curves, times=None):
    """``(r, dr/dt)`` of ``dynamics`` (at its samples or at ``times``) when ``curves``
    is a (z, r) surrogate, else ``(None, None)``."""
    if curves is None or not curves.radial:
        return None, None
    from .surrogate.offaxis import radial_motion
    return radial_motion(dynamics, times)


def scene_waveforms(scene, dynamics, curves) -> dict[str, np.ndarray]:
    """The ``WAVEFORM_COLUMNS`` of ``dynamics`` (a DynamicsResult or anything with
    ``t, gap, gap_velocity, table``) for ``scene``: time, trajectory and the
    terminal waveforms at the output samples."""
    t = np.asarray(dynamics.t, dtype=float)
    gap = np.asarray(dynamics.gap, dtype=float)
    velocity = np.asarray(dynamics.gap_velocity, dtype=float)
    terminal = scene_terminal_waveforms(scene, curves, gap, velocity,
                                        *_radial(dynamics, curves))
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
    return _impact_states(scene, dynamics, np.asarray(impacts, dtype=float)
                          - time_origin(dynamics))


def _impact_states(scene, dynamics, impacts) -> tuple[np.ndarray, ...]:
    """:func:`impact_states` at ``impacts`` on the run's own axis (:func:`elapsed_times`)."""
    if not len(impacts) or not (hasattr(dynamics, "sample")
                                or hasattr(dynamics, "sample_elapsed")):
        empty = np.empty(0)
        return empty, empty, empty, empty
    eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
    gap_pre, vel_pre, _ = sample_elapsed(dynamics, impacts - eps)
    gap_post, vel_post, _ = sample_elapsed(dynamics, impacts + eps)
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
    t = elapsed_times(dynamics)          # the rows of waveforms, on the run's own axis
    mask, _ = steady_window(t, scene)
    values = {name: [np.asarray(waveforms[column])[mask]]
              for name, column in PEAK_QUANTITIES.items()}
    if curves is not None:
        impacts = impact_elapsed(dynamics, t[mask][0], t[-1])
        gap_pre, vel_pre, gap_post, vel_post = _impact_states(scene, dynamics, impacts)
        if gap_pre.size:
            eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
            extra = scene_terminal_waveforms(
                scene, curves, np.concatenate([gap_pre, gap_post]),
                np.concatenate([vel_pre, vel_post]),
                *_radial(dynamics, curves, time_origin(dynamics)
                         + np.concatenate([impacts - eps, impacts + eps])))
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
    origin = time_origin(dynamics)
    return _load_waveforms(scene, dynamics, curves,
                           None if window_start is None else window_start - origin)


def _load_waveforms(scene, dynamics, curves, window_start) -> dict:
    """:func:`load_waveforms` on the run's own axis (``window_start`` after the origin)."""
    t = elapsed_times(dynamics)
    origin = time_origin(dynamics)
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
    impacts = impact_elapsed(dynamics, t[0], t[-1])
    output_step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    c_min = float(np.min(curves.capacitance_samples)) * n_cells + c_p
    extra = relaxation_times(np.concatenate([[t[0]], impacts]), load * c_min, output_step, t[-1])
    gap_pre, vel_pre, gap_post, vel_post = _impact_states(scene, dynamics, impacts)
    gap_extra, vel_extra, _ = (sample_elapsed(dynamics, extra) if extra.size
                               else (np.empty(0),) * 3)
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
    fine = scene_terminal_waveforms(scene, curves, gap, vel,
                                    *_radial(dynamics, curves, origin + grid))
    response = circuit.load_response(grid, fine["Q_sc"], fine["I_sc"], fine["C_T"], load, c_p)
    delivered = circuit.delivered_power(response.voltage, fine["I_sc"], fine["dC_T_dt"])
    stored = circuit.stored_energy(response.voltage, fine["C_T"], c_p)
    in_window = grid >= window_start
    t_window = grid[in_window]
    window_length = t_window[-1] - t_window[0] if t_window.size > 1 else 0.0
    dissipated = float(trapezoid(response.power[in_window], t_window))
    stored_window = stored[in_window]
    return {"V_load": response.voltage[output_index], "I_load": response.current[output_index],
            "P_load": response.power[output_index],
            "mean_power_W": dissipated / window_length if window_length > 0 else 0.0,
            "delivered_energy_J": float(trapezoid(delivered[in_window], t_window)),
            "dissipated_energy_J": dissipated,
            "stored_energy_change_J": float(stored_window[-1] - stored_window[0]),
            "integration_points": int(grid.size),
            "time_constant_s": load * (float(np.max(curves.capacitance_samples)) * n_cells + c_p)}


def steady_load(scene, dynamics, curves) -> dict:
    """:func:`load_waveforms` with energies over the :func:`steady_window`."""
    t = elapsed_times(dynamics)
    mask, _ = steady_window(t, scene)
    return _load_waveforms(scene, dynamics, curves, t[mask][0])


# ---------------------------------------------------------------------------
# rectifier into a store (tengfield.harvest) along a trajectory
#: extra columns of ``waveforms.csv`` for ``[circuit] kind = "rectifier"``
RECTIFIER_COLUMNS = ["V_store_V", "I_store_A", "E_store_J", "pmic_on"]
#: rows per chunk of a rectifier run (times x cells), bounds its memory
CHUNK_VALUES = 2_000_000


def harvester_options(scene) -> dict:
    """Keyword arguments of :class:`tengfield.harvest.Harvester` from ``[circuit]``
    (SI): diode, store, leakage (0 in the file: none), the UVLO chip (``pmic``)."""
    from .harvest import Diode, PowerChip

    c = scene.circuit
    diode = Diode(model=c.diode, forward_voltage=c.diode_forward_voltage,
                  saturation_current=c.diode_saturation_current,
                  emission_coefficient=c.diode_emission_coefficient,
                  series_resistance=c.diode_series_resistance)
    chip = None
    if c.pmic == "uvlo":
        chip = PowerChip(uvlo_rising=c.uvlo_rising, uvlo_falling=c.uvlo_falling,
                         output_voltage=c.pmic_output, load=c.pmic_load,
                         efficiency=c.pmic_efficiency, quiescent_current=c.pmic_quiescent_current,
                         shunt_voltage=c.pmic_shunt)
    return {"storage_capacitance": c.storage_capacitance, "diode": diode,
            "parallel_capacitance": c.parallel_capacitance,
            "leakage": c.storage_leakage if c.storage_leakage > 0 else math.inf, "chip": chip}


#: numerical_dissipation_J above this fraction of the energy delivered into the bridges
#: gets a warning (the backward-Euler step moved the store too far per step)
NUMERICAL_DISSIPATION_WARN = 0.01


def smallest_resolved_store(scene) -> float:
    """Smallest ``[circuit] storage_capacitance_uF`` [F] whose chip bursts the output
    step resolves (0 without a chip): the energy between the UVLO levels,
    ``C_L (uvlo_rising^2 - uvlo_falling^2) / 2``, must last at least one step
    ``1 / sample_rate_hz`` at the chip's largest draw (input power + quiescent current
    at the shunt voltage). Below it a burst (the chip on, then locked out again) fits
    inside one step: the store is at 0 at every grid point while the books show shunt
    and chip energy, and the step's own dissipation is half of what is delivered."""
    c = scene.circuit
    if c.kind != "rectifier" or c.pmic != "uvlo":
        return 0.0
    step = 1.0 / scene.run.sample_rate
    draw = c.pmic_output**2 / (c.pmic_load * c.pmic_efficiency) \
        + c.pmic_quiescent_current * c.pmic_shunt
    return 2.0 * step * draw / (c.uvlo_rising**2 - c.uvlo_falling**2)


def check_store_resolution(scene) -> None:
    """One-line SceneError when the store is too small for the output step to resolve
    its chip (:func:`smallest_resolved_store`)."""
    from .errors import SceneError

    smallest = smallest_resolved_store(scene)
    c = scene.circuit
    if c.storage_capacitance < smallest:
        raise SceneError(
            f"[circuit] storage_capacitance_uF = {c.storage_capacitance * 1e6:g} is out of "
            f"range: with pmic = 'uvlo' at [run] sample_rate_hz = {scene.run.sample_rate:g} "
            f"allowed >= {smallest * 1e6:.3g} (a chip burst, C_L (uvlo_rising_V^2 - "
            f"uvlo_falling_V^2)/2 of energy, must last at least one output step; or raise "
            f"[run] sample_rate_hz)")


def warn_numerical_dissipation(books: dict) -> None:
    """One ``tengfield: warning:`` line when the backward-Euler step's own dissipation
    (``numerical_dissipation_J`` of ``HarvestResult.balance()``, or the same keys summed
    over stores) exceeds ``NUMERICAL_DISSIPATION_WARN`` of the delivered energy."""
    import warnings

    delivered = books.get("delivered_J", 0.0)
    lost = books.get("numerical_dissipation_J", 0.0)
    if delivered > 0 and lost > NUMERICAL_DISSIPATION_WARN * delivered:
        warnings.warn(
            f"rectifier: numerical_dissipation_J = {lost:.3g} J is {lost / delivered:.1%} of "
            f"the {delivered:.3g} J delivered into the bridges (> "
            f"{NUMERICAL_DISSIPATION_WARN:.0%}): the store moves too far per step; raise "
            f"[run] sample_rate_hz or [circuit] storage_capacitance_uF", RuntimeWarning,
            stacklevel=3)


def rectifier_grid(scene, dynamics) -> tuple[np.ndarray, np.ndarray]:
    """(grid [s], indices of the output samples in it): the output times and every
    impact instant (Q_SC(z(t)) has a kink there; the bridge steps end on it), on the
    run's own axis (:func:`elapsed_times`)."""
    t = elapsed_times(dynamics)
    impacts = impact_elapsed(dynamics, t[0], t[-1])
    impacts = impacts[~np.isin(impacts, t)]
    grid = np.concatenate([t, impacts])
    order = np.argsort(grid, kind="stable")
    return grid[order], np.flatnonzero(order < t.size)


def rectifier_waveforms(scene, dynamics, curves) -> dict:
    """``[device] cells`` identical cells (one bridge for them all: identical cells
    give the same as one bridge each) charging ``[circuit]``'s store along
    ``dynamics``. Returns the ``RECTIFIER_COLUMNS`` at the output samples, the
    :class:`tengfield.harvest.HarvestResult` ``fine`` on the whole grid and the
    grid's output indices ``output_index``."""
    from .harvest import Harvester

    check_store_resolution(scene)
    grid, output_index = rectifier_grid(scene, dynamics)
    n = scene.device.cells
    run = Harvester(1, time_origin=time_origin(dynamics), **harvester_options(scene))
    rows = max(2, CHUNK_VALUES)
    parts = []
    for start in range(0, grid.size, rows):
        times = grid[start:start + rows]
        gap, _, _ = sample_elapsed(dynamics, times)
        q = curves.charge(gap) * n if curves is not None else np.zeros_like(gap)
        c = curves.capacitance(gap) * n if curves is not None else np.full_like(gap, 1e-12)
        parts.append(run.advance(times, q, c))
    fine = concat_results(parts)
    return {"V_store_V": fine.store_voltage[output_index],
            "I_store_A": fine.store_current[output_index],
            "E_store_J": fine.stored_energy[output_index],
            "pmic_on": fine.chip_on[output_index].astype(float),
            "fine": fine, "output_index": output_index}


def concat_results(parts):
    """One :class:`tengfield.harvest.HarvestResult` of consecutive chunks."""
    import dataclasses

    if len(parts) == 1:
        return parts[0]
    fields = {}
    for f in dataclasses.fields(parts[0]):
        values = [getattr(p, f.name) for p in parts]
        fields[f.name] = (np.concatenate(values) if isinstance(values[0], np.ndarray)
                          else getattr(parts[-1], f.name))
    fields["initial_terminal_energy"] = parts[0].initial_terminal_energy
    fields["initial_stored_energy"] = parts[0].initial_stored_energy
    return type(parts[0])(**fields)


def first_crossing(times, values, level: float) -> float:
    """First time [s] ``values`` reach ``level`` (linear between samples); NaN if never."""
    v = np.asarray(values, dtype=float)
    hit = np.flatnonzero(v >= level)
    if hit.size == 0:
        return math.nan
    k = int(hit[0])
    if k == 0:
        return float(times[0])
    v0, v1 = v[k - 1], v[k]
    return float(times[k - 1] + (level - v0) / (v1 - v0) * (times[k] - times[k - 1]))


def _first_of(*times) -> float:
    """Earliest of the finite ``times`` (a chip that switches on within the step it
    reached the level may pull the sampled U back below it), NaN if none."""
    finite = [x for x in times if math.isfinite(x)]
    return min(finite) if finite else math.nan


def rectifier_summary(scene, fine, window_start: float, curves=None, max_gap=None) -> dict:
    """Numbers of a rectifier run (SI): store, time to each UVLO level, chip
    switching, average harvested power and energy per cycle over the steady
    window (from ``window_start`` [s] on ``fine.time``, the run's own axis), the
    energy books and their residuals, and the ideal bridge's saturation voltage
    (docs/harvest.md). Instants are reported as absolute times (``fine.time_origin``
    + the time on the run's axis), as in ``waveforms.csv``."""
    from .harvest import saturation_voltage

    c = scene.circuit
    t = fine.time
    origin = float(getattr(fine, "time_origin", 0.0))
    period = scene.excitation.period
    inside = t >= window_start
    k0 = int(np.flatnonzero(inside)[0]) if inside.any() else 0
    length = float(t[-1] - t[k0])
    into_store = float(fine.store_input[-1] - fine.store_input[k0])
    bridge = float(fine.bridge_energy[-1] - fine.bridge_energy[k0])
    on = fine.chip_on
    switch_on = int(np.count_nonzero(on[1:] & ~on[:-1]))
    switch_off = int(np.count_nonzero(~on[1:] & on[:-1]))
    dt = np.diff(t)
    on_time = float(np.sum(dt[on[1:]]))
    books = fine.balance()
    warn_numerical_dissipation(books)
    out = {
        "diode": c.diode, "storage_capacitance_F": c.storage_capacitance, "pmic": c.pmic,
        "final_store_voltage_V": float(fine.store_voltage[-1]),
        "final_stored_energy_J": float(fine.stored_energy[-1]),
        "max_store_voltage_V": float(np.max(fine.store_voltage)),
        "time_to_uvlo_falling_V_s": origin + first_crossing(t, fine.store_voltage,
                                                            c.uvlo_falling),
        "time_to_uvlo_rising_V_s": origin + _first_of(
            first_crossing(t, fine.store_voltage, c.uvlo_rising),
            fine.threshold_times["uvlo_rising_s"]),
        "uvlo_levels_V": [c.uvlo_falling, c.uvlo_rising],
        "chip_first_on_s": origin + fine.threshold_times["uvlo_rising_s"],
        "chip_first_lockout_s": origin + fine.threshold_times["uvlo_falling_s"],
        "chip_switch_on_count": switch_on, "chip_switch_off_count": switch_off,
        "chip_duty_cycle": on_time / float(t[-1] - t[0]) if t[-1] > t[0] else 0.0,
        "chip_output_energy_J": float(fine.chip_input_energy[-1]) * c.pmic_efficiency,
        "average_harvested_power_W": into_store / length if length > 0 else 0.0,
        "energy_per_cycle_J": bridge * period / length if length > 0 else 0.0,
        "window_start_s": origin + float(t[k0]),
        "energy_books_J": {k: v for k, v in books.items() if k.endswith("_J")},
        "energy_residuals": {k: v for k, v in books.items() if k.endswith("_residual")},
        "energy_residuals_rule": "relative to the energy delivered into the bridges; the "
                                 "backward-Euler step's own dissipation is booked as "
                                 "numerical_dissipation_J",
    }
    if curves is not None and max_gap is not None:
        n = scene.device.cells
        q_max = float(curves.charge(max_gap)) * n
        c_max = float(curves.capacitance(max_gap)) * n + c.parallel_capacitance
        c_0 = float(curves.capacitance(0.0)) * n + c.parallel_capacitance
        out["saturation_voltage_V"] = saturation_voltage(abs(q_max), c_max, c_0,
                                                         c.diode_forward_voltage)
    return out


# ---------------------------------------------------------------------------
# energy per cycle: V-Q loops and the CMEO bound
def loop_area(voltage, charge) -> float:
    """∮ V dQ [J] of a sampled loop (trapezoidal; positive when energy leaves the TENG)."""
    v = np.asarray(voltage, dtype=float)
    q = np.asarray(charge, dtype=float)
    return float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(q)))


def last_period(times, period: float) -> np.ndarray:
    """Mask of the samples in the last full excitation period."""
    t = np.asarray(times, dtype=float)
    return t >= t[-1] - period


def cmeo(scene, curves, max_gap: float) -> dict:
    """Cycles for maximised energy output (Zi et al. 2015) for a stroke 0 -> ``max_gap``
    [m] of ``[device] cells`` identical cells, and the structural figure of merit
    (area = the ball's surface pi d^2 per cell, x_max = ``max_gap``), on the axis."""
    from .harvest import max_energy_per_cycle, structural_figure_of_merit

    curves = curves.axis   # a (z, r) surrogate: the stroke on the axis
    n = scene.device.cells
    c_p = scene.circuit.parallel_capacitance
    q_max = abs(float(curves.charge(max_gap)) - float(curves.charge(0.0))) * n
    c_max = float(curves.capacitance(max_gap)) * n + c_p
    c_0 = float(curves.capacitance(0.0)) * n + c_p
    energy = max_energy_per_cycle(q_max, c_max, c_0)
    dev = scene.device
    area = math.pi * dev.ball_diameter**2 * n
    fom = structural_figure_of_merit(energy, dev.surface_charge, area, max_gap) \
        if dev.surface_charge != 0 and max_gap > 0 else math.nan
    return {"max_energy_per_cycle_J": energy, "Q_sc_max_C": q_max,
            "V_oc_max_V": q_max / c_max, "V_return_max_V": q_max / c_0,
            "C_at_max_gap_F": c_max, "C_at_zero_F": c_0, "max_gap_m": max_gap,
            "figure_of_merit_structural": fom, "fom_area_m2": area,
            "fom_rule": "FOM_S = 2 eps0 E_m / (sigma^2 A x_max), A = pi d^2 x cells (the "
                        "charged ball surface), x_max = the largest gap reached; E_m = "
                        "Q_SC,max (V_OC,max + |V'_max|) / 2 (Zi et al., Nat. Commun. 6:8376, 2015)"}
