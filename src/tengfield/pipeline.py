"""End-to-end run: dynamics -> surrogate (cached) -> circuit (DESIGN §1).

:func:`run` returns a :class:`RunResult` (waveforms as arrays, a JSON-ready
summary); :func:`write_outputs` writes ``waveforms.csv``, ``summary.json``
and the plots. Units are SI; sign conventions are those of
:mod:`tengfield.terminals` (V = V_lower - V_upper, Q_SC and currents counted
lower -> upper through the external circuit, reference state z = 0).

Stages a scene does not need are left out, and ``summary["stages"]`` says
why: no field solve (and no dolfinx/gmsh import) when a valid cached
surrogate exists or when Q_SC is identically zero (uncharged ball, or a
ball that never leaves the lower electrode); no load ODE unless
``[circuit] kind = "load"``.
"""
from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import circuit
from ._json import jsonable as _jsonable
from .surrogate import TerminalCurves, SurrogateTable, obtain_table

WAVEFORM_COLUMNS = ["time_s", "gap_m", "gap_velocity_m_per_s", "table_m",
                    "V_oc_V", "Q_sc_C", "I_sc_A"]
LOAD_COLUMNS = ["V_load_V", "I_load_A", "P_load_W"]


# ---------------------------------------------------------------------------
# pure pieces
def terminal_waveforms(curves: TerminalCurves | None, gap, gap_velocity, *, cells: int = 1,
                       parallel_capacitance: float = 0.0) -> dict[str, np.ndarray]:
    """Open-circuit voltage, short-circuit charge and current along a trajectory.

    ``gap`` z(t) [m] and ``gap_velocity`` dz/dt [m/s] are samples of the
    trajectory; ``cells`` identical cells are wired in parallel. Returns
    ``V_oc`` [V] (= Q_SC / (C_T + C_p), the true V_OC when C_p = 0),
    ``Q_sc`` [C], ``I_sc`` = (dQ_SC/dz) dz/dt [A], ``C_T`` [F] and
    ``dC_T_dt`` [F/s]. ``curves = None`` means Q_SC is identically zero
    (then C_T is unknown and reported as NaN).
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


def steady_window(times, scene) -> tuple[np.ndarray, str]:
    """Boolean mask of the samples after ``[run] settle_periods`` excitation periods."""
    t = np.asarray(times, dtype=float)
    start = t[0] + scene.run.settle_periods * scene.excitation.period
    mask = t >= start
    if np.count_nonzero(mask) < 2:
        return np.ones_like(t, dtype=bool), (f"whole run: settle_periods x period = "
                                             f"{start - t[0]:g} s leaves fewer than 2 samples")
    return mask, f"t >= {start:g} s (after settle_periods = {scene.run.settle_periods} periods)"


# ---------------------------------------------------------------------------
# the load ODE along a trajectory with impacts
def _impact_times(dynamics, t0: float, t1: float) -> np.ndarray:
    """Times of the impacts (velocity jumps) strictly inside (t0, t1)."""
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
    return np.unique(times[(times > t0) & (times < t1)])


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


def load_waveforms(scene, dynamics, curves: TerminalCurves | None, waveforms: dict,
                   window_start: float | None = None) -> dict:
    """V_load [V], I_load [A], P_load [W] at the output samples, mean power and energy balance.

    The exponential integrator of :func:`tengfield.circuit.load_response`
    runs on a fine grid: the output times, every impact time twice (pre- and
    post-impact velocity, so the jumps of I_SC are exact) and
    :func:`relaxation_times` after the start and each impact. Energies are
    trapezoidal sums on that grid over the window after ``window_start`` [s]
    (the steady window); ``mean_power_W`` is the dissipated energy divided by
    the window length.
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
    impacts = _impact_times(dynamics, t[0], t[-1])
    output_step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    c_min = float(np.min(curves.capacitance_samples)) * n_cells + c_p
    extra = relaxation_times(np.concatenate([[t[0]], impacts]), load * c_min, output_step, t[-1])
    eps = 1e-9 * scene.excitation.period
    gap_pre, vel_pre, _ = dynamics.sample(impacts - eps) if impacts.size else (np.empty(0),) * 3
    gap_post, vel_post, _ = dynamics.sample(impacts + eps) if impacts.size else (np.empty(0),) * 3
    gap_extra, vel_extra, _ = dynamics.sample(extra) if extra.size else (np.empty(0),) * 3
    grid = np.concatenate([t, impacts, impacts, extra])
    gap = np.concatenate([waveforms["gap_m"], gap_pre, gap_post, gap_extra])
    vel = np.concatenate([waveforms["gap_velocity_m_per_s"], vel_pre, vel_post, vel_extra])
    # equal times: pre-impact (0) before an output sample (1) before post-impact (2)
    tag = np.concatenate([np.ones(t.size), np.zeros(impacts.size), np.full(impacts.size, 2.0),
                          np.full(extra.size, 3.0)])
    order = np.lexsort((tag, grid))
    grid, gap, vel = grid[order], gap[order], vel[order]
    output_index = np.flatnonzero(order < t.size)   # order[...] of outputs is increasing
    fine = terminal_waveforms(curves, gap, vel, cells=n_cells, parallel_capacitance=c_p)
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


# ---------------------------------------------------------------------------
@dataclass
class Stage:
    """What one stage did: ``status`` is "ran", "cached" or "skipped"."""
    status: str
    reason: str = ""
    wall_time_s: float = 0.0
    details: dict = field(default_factory=dict)


@dataclass
class RunResult:
    """Outcome of :func:`run`: waveform columns (SI, see ``WAVEFORM_COLUMNS``),
    the summary (JSON-ready) and the pieces the plots need."""
    scene: Any
    waveforms: dict[str, np.ndarray]
    summary: dict
    dynamics: Any
    table: SurrogateTable | None
    curves: TerminalCurves | None


def _default_simulate():
    from .dynamics import simulate
    return simulate


def run(scene, *, comm=None, cache_dir=None, solve: Callable | None = None,
        simulate: Callable | None = None, progress: bool = False,
        command_line: str = "", write_cache: bool = True) -> RunResult:
    """Dynamics, surrogate and circuit for ``scene``.

    ``simulate(scene)`` defaults to :func:`tengfield.dynamics.simulate`,
    ``solve(scene, z, comm=...)`` to :func:`tengfield.field.solve_position`
    (only called when no valid cached surrogate exists); ``comm`` spreads
    the field solves over its ranks.
    """
    stages: dict[str, Stage] = {}
    simulate = simulate or _default_simulate()

    start = time.perf_counter()
    dynamics = simulate(scene)
    stages["dynamics"] = Stage("ran", getattr(dynamics, "message", "") or "",
                               time.perf_counter() - start,
                               {"status": getattr(dynamics, "status", None),
                                "solver_wall_time_s": getattr(dynamics, "wall_time", None)})
    t = np.asarray(dynamics.t, dtype=float)
    gap = np.asarray(dynamics.gap, dtype=float)
    velocity = np.asarray(dynamics.gap_velocity, dtype=float)
    table_motion = np.asarray(dynamics.table, dtype=float)

    table = curves = None
    needs_field, why_not = _needs_field(scene, gap)
    if needs_field:
        table, outcome = obtain_table(scene, cache_dir=cache_dir, comm=comm, solve=solve,
                                      progress=progress, command_line=command_line,
                                      write=write_cache)
        if outcome.status == "cached":
            stages["field"] = Stage("cached", outcome.reason, outcome.wall_time,
                                    {"path": outcome.path})
        else:
            stages["field"] = Stage("ran", outcome.reason, outcome.wall_time, {
                "path": outcome.path, "positions": table.count,
                "sum_of_solve_wall_times_s": table.total_solve_wall_time})
        stages["field"].details.update({
            "method": table.method, "degree": table.degree,
            "max_relative_error_estimate": float(np.nanmax(table.field_error)),
            "max_dofs": int(table.dofs.max())})
        curves = TerminalCurves(table, scene.circuit.reference)
        stages["surrogate"] = Stage(
            "cached" if outcome.status == "cached" else "ran",
            f"{table.count} positions, cubic splines of Q_SC and C_T",
            0.0, {"interpolation_error_estimate": table.interpolation_error,
                  "tolerance": table.tolerance, "converged": table.converged,
                  "error_history": table.error_history})
    else:
        stages["field"] = Stage("skipped", why_not)
        stages["surrogate"] = Stage("skipped", why_not)

    start = time.perf_counter()
    terminal = terminal_waveforms(curves, gap, velocity, cells=scene.device.cells,
                                  parallel_capacitance=scene.circuit.parallel_capacitance)
    waveforms = {"time_s": t, "gap_m": gap, "gap_velocity_m_per_s": velocity,
                 "table_m": table_motion, "V_oc_V": terminal["V_oc"],
                 "Q_sc_C": terminal["Q_sc"], "I_sc_A": terminal["I_sc"]}
    load = None
    if scene.circuit.kind == "load":
        window, _ = steady_window(t, scene)
        load = load_waveforms(scene, dynamics, curves, waveforms, window_start=t[window][0])
        waveforms.update({"V_load_V": load["V_load"], "I_load_A": load["I_load"],
                          "P_load_W": load["P_load"]})
        delivered = load["delivered_energy_J"]
        residual = delivered - load["dissipated_energy_J"] - load["stored_energy_change_J"]
        stages["circuit"] = Stage("ran", f"load ODE, R = {scene.circuit.load:g} ohm",
                                  time.perf_counter() - start,
                                  {"energy_balance_relative_residual":
                                   abs(residual) / max(abs(delivered), 1e-300)})
    else:
        stages["circuit"] = Stage("ran", f"kind = {scene.circuit.kind!r}: V_OC, Q_SC, I_SC in "
                                  "closed form; load ODE not run (no load)",
                                  time.perf_counter() - start)
    summary = _summary(scene, dynamics, waveforms, load, stages, table,
                       peaks=terminal_peak_to_peak(scene, dynamics, curves, waveforms))
    return RunResult(scene=scene, waveforms=waveforms, summary=summary, dynamics=dynamics,
                     table=table, curves=curves)


def _needs_field(scene, gap) -> tuple[bool, str]:
    if scene.device.ball_charge == 0.0:
        return False, "ball charge is zero ([device] surface_charge_uC_per_m2 = 0): Q_SC = 0"
    if np.all(np.asarray(gap) == 0.0):
        return False, "the ball never leaves the lower electrode: Q_SC = 0 (reference state)"
    return True, ""


def _regime_dict(regime):
    if regime is None:
        return None
    if hasattr(regime, "as_dict"):
        return regime.as_dict()
    return _jsonable(regime)


def terminal_peak_to_peak(scene, dynamics, curves, waveforms) -> dict[str, float]:
    """Peak-to-peak V_OC [V], Q_SC [C], I_SC [A] over the steady window.

    The extremes are taken over the output samples *and* just before and after
    every impact (±1e-9 of a period), where I_SC = (dQ_SC/dz)·ż jumps and takes
    its extremes: the trajectory is exact there, so the peaks do not depend on
    ``[run] sample_rate_hz`` (sampled alone, the I_SC peak of the default scene
    is 3 % low at 20 kHz; docs/report.md).
    """
    names = {"V_oc_V": "V_oc", "Q_sc_C": "Q_sc", "I_sc_A": "I_sc"}
    t = waveforms["time_s"]
    mask, _ = steady_window(t, scene)
    values = {name: [np.asarray(waveforms[name])[mask]] for name in names}
    impacts = _impact_times(dynamics, t[mask][0], t[-1])
    if curves is not None and impacts.size and hasattr(dynamics, "sample"):
        eps = 1e-9 * scene.excitation.period
        gap, velocity, _ = dynamics.sample(np.concatenate([impacts - eps, impacts + eps]))
        extra = terminal_waveforms(curves, gap, velocity, cells=scene.device.cells,
                                   parallel_capacitance=scene.circuit.parallel_capacitance)
        for name, key in names.items():
            values[name].append(extra[key])
    return {name: circuit.peak_to_peak(np.concatenate(v)) for name, v in values.items()}


def _summary(scene, dynamics, waveforms, load, stages, table, *, peaks) -> dict:
    t = waveforms["time_s"]
    mask, window_reason = steady_window(t, scene)
    summary: dict[str, Any] = {
        "scene": scene.source,
        "field_hash": scene.field_hash(),
        "reference": scene.circuit.reference,
        "sign_convention": "V = V_lower - V_upper; Q_SC and currents lower -> upper through "
                           "the external circuit; reference state: ball on the lower electrode",
        "cells": scene.device.cells,
        "circuit": {"kind": scene.circuit.kind, "load_ohm": scene.circuit.load,
                    "parallel_capacitance_F": scene.circuit.parallel_capacitance},
        "window": {"start_s": float(t[mask][0]), "end_s": float(t[mask][-1]),
                   "rule": window_reason},
        "peak_to_peak": peaks,
        "peak_to_peak_rule": "over the output samples of the steady window and just before "
                             "and after every impact (exact extremes of I_SC)",
        "regime": _regime_dict(getattr(dynamics, "regime", None)),
        "load": None,
        "stages": stages,
    }
    if table is not None:
        summary["surrogate_error_estimate"] = table.interpolation_error
    if load is not None:
        volume = scene.device.cell_volume * scene.device.cells
        power = load["mean_power_W"]
        summary["load"] = {
            "mean_power_W": power,
            "device_volume_m3": volume,
            "power_density_W_per_m3": power / volume,
            "V_load_peak_to_peak_V": circuit.peak_to_peak(waveforms["V_load_V"][mask]),
            "I_load_peak_to_peak_A": circuit.peak_to_peak(waveforms["I_load_A"][mask]),
            "energy_balance_J": {k: load[k] for k in ("delivered_energy_J", "dissipated_energy_J",
                                                      "stored_energy_change_J")},
            "integration_points": load["integration_points"],
            "time_constant_s": load["time_constant_s"],
            "settled": bool(5.0 * load["time_constant_s"] <= float(t[mask][0] - t[0])),
            "settled_rule": "5 R (C_T + C_p) <= settle time before the window; otherwise the "
                            "window still holds the load's start-up transient (longer run or "
                            "more settle_periods)",
        }
    else:
        summary["load"] = None
        summary["load_reason"] = f"[circuit] kind = {scene.circuit.kind!r}: no load to report"
    return _jsonable(summary)


# ---------------------------------------------------------------------------
# output files
def write_waveforms_csv(path: str | Path, waveforms: dict) -> Path:
    """CSV with the columns of ``WAVEFORM_COLUMNS`` (+ ``LOAD_COLUMNS`` if present)."""
    columns = WAVEFORM_COLUMNS + [c for c in LOAD_COLUMNS if c in waveforms]
    data = np.column_stack([waveforms[c] for c in columns])
    np.savetxt(path, data, delimiter=",", header=",".join(columns), comments="", fmt="%.10g")
    return Path(path)


def write_outputs(result: RunResult, out_dir: str | Path, *, plots: bool = True) -> list[Path]:
    """Write waveforms.csv, summary.json and, with ``plots``, waveforms.png and
    surrogate.png (the CLI adds the dynamics' own trajectory/impact files)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_waveforms_csv(out / "waveforms.csv", result.waveforms)]
    if plots:
        from .plotting.waveforms import plot_surrogate, plot_waveforms
        shown = 5.0 * result.scene.excitation.period       # the last 5 periods, readable
        written.append(plot_waveforms(result.waveforms, out / "waveforms.png",
                                      title=_title(result) + ", last 5 periods",
                                      last_seconds=shown))
        if result.curves is not None:
            written.append(plot_surrogate(result.table, result.curves, out / "surrogate.png",
                                          cells=result.scene.device.cells))
    (out / "summary.json").write_text(json.dumps(result.summary, indent=2) + "\n")
    written.append(out / "summary.json")
    return written


def _title(result: RunResult) -> str:
    exc = result.scene.excitation
    regime = result.summary.get("regime") or {}
    name = regime.get("regime", regime.get("name", "")) if isinstance(regime, dict) else ""
    return (f"{exc.frequency:g} Hz, A = {exc.amplitude * 1e3:g} mm, "
            f"{result.scene.device.cells} cell(s), {result.scene.circuit.reference}"
            + (f", {name}" if name else ""))


# ---------------------------------------------------------------------------
# parameter sweeps (one surrogate, many excitations and loads)
SWEEP_COLUMNS = ["frequency_hz", "amplitude_mm", "load_ohm", "regime", "period",
                 "V_oc_pp_V", "Q_sc_pp_C", "I_sc_pp_A", "P_mean_W", "power_density_W_per_m3"]


def sweep_point(scene, table: SurrogateTable, frequency: float, amplitude: float,
                loads=(), simulate: Callable | None = None) -> list[dict]:
    """Peak-to-peak V_OC, Q_SC, I_SC at one excitation (frequency [Hz],
    amplitude [m]) and the mean power into each load [ohm] (steady window).

    One row per load (``load_ohm`` None and no power without loads).
    """
    simulate = simulate or _default_simulate()
    point = scene.with_values(excitation={"frequency_hz": float(frequency),
                                          "amplitude_mm": float(amplitude) * 1e3})
    dynamics = simulate(point)
    t = np.asarray(dynamics.t, dtype=float)
    curves = TerminalCurves(table, point.circuit.reference)
    waveforms = {"gap_m": np.asarray(dynamics.gap), "gap_velocity_m_per_s":
                 np.asarray(dynamics.gap_velocity)}
    terminal = terminal_waveforms(curves, waveforms["gap_m"], waveforms["gap_velocity_m_per_s"],
                                  cells=point.device.cells,
                                  parallel_capacitance=point.circuit.parallel_capacitance)
    mask, _ = steady_window(t, point)
    regime = _regime_dict(dynamics.regime) or {}
    base = {"frequency_hz": float(frequency), "amplitude_mm": float(amplitude) * 1e3,
            "regime": regime.get("regime", ""), "period": regime.get("period", 0),
            "V_oc_pp_V": circuit.peak_to_peak(terminal["V_oc"][mask]),
            "Q_sc_pp_C": circuit.peak_to_peak(terminal["Q_sc"][mask]),
            "I_sc_pp_A": circuit.peak_to_peak(terminal["I_sc"][mask])}
    if not len(loads):
        return [{**base, "load_ohm": None, "P_mean_W": None, "power_density_W_per_m3": None}]
    rows = []
    volume = point.device.cell_volume * point.device.cells
    for load in loads:
        loaded = point.with_values(circuit={"kind": "load", "load_ohm": float(load)})
        result = load_waveforms(loaded, dynamics, curves, waveforms, window_start=t[mask][0])
        rows.append({**base, "load_ohm": float(load), "P_mean_W": result["mean_power_W"],
                     "power_density_W_per_m3": result["mean_power_W"] / volume})
    return rows


def _sweep_task(args):
    return sweep_point(*args)


def sweep(scene, table: SurrogateTable, frequencies, amplitudes, loads=(), *,
          jobs: int | None = None, progress: bool = False) -> list[dict]:
    """:func:`sweep_point` over the grid ``frequencies`` [Hz] x ``amplitudes`` [m],
    in ``jobs`` worker processes (default: all cores), with a progress bar."""
    import os
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing

    from tqdm import tqdm

    # validate every grid scene first: a bad point fails before any work starts
    for f in frequencies:
        for a in amplitudes:
            scene.with_values(excitation={"frequency_hz": float(f), "amplitude_mm": float(a) * 1e3})
    tasks = [(scene, table, float(f), float(a), tuple(loads)) for f in frequencies for a in amplitudes]
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(tasks)))
    bar = tqdm(total=len(tasks), desc="sweep", unit="point", file=sys.stderr,
               disable=not (progress and sys.stderr.isatty()))
    rows: list[dict] = []
    if jobs == 1:
        for task in tasks:
            rows.extend(_sweep_task(task))
            bar.update()
    else:
        context = multiprocessing.get_context("spawn")  # safe after MPI/dolfinx initialisation
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            for result in pool.map(_sweep_task, tasks):
                rows.extend(result)
                bar.update()
    bar.close()
    return rows
