"""The measurements of each stage: field, surrogate, dynamics, circuit.

:class:`_Solver` does every field solve once (farmed over the ranks by
:meth:`_Solver.prefetch`); :func:`field_rows`, :func:`surrogate_rows`,
:func:`dynamics_rows` and :func:`circuit_rows` measure each stage's error
against its reference (see :mod:`tengfield.accuracy_report.study`).
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from .. import electrical, lumped
from ..scene.shapes.methods import field_method
from .plan import (QUANTITIES, FieldSetting, Plan, Row, max_relative_deviation, peak_errors,
                   relative_error, richardson, solves_needed)


class _Solver:
    """Field solves at (setting, position), each done once (mirror images are free)."""

    def __init__(self, scene, comm, solve=None, progress=None):
        self.scene = scene
        self.comm = comm
        self.stroke = scene.device.stroke
        from ..surrogate.sampling import is_mirror_symmetric
        # a grounded table, or the single-electrode cell's one electrode, breaks the mirror
        self.symmetric = is_mirror_symmetric(scene)
        self.cache: dict = {}
        self._solve = solve
        self.progress = progress

    def key(self, setting: FieldSetting, z: float):
        return (setting, round(z / self.stroke, 12))

    def compute(self, setting: FieldSetting, z: float):
        """One field solve, not cached (what a rank of the farm runs)."""
        if self._solve is None:
            from ..field import solve_position
            self._solve = solve_position
        return self._solve(self.scene, float(z), comm=self.comm, estimate_error=False,
                           **setting.overrides())

    def solve(self, setting: FieldSetting, z: float):
        key = self.key(setting, z)
        if key not in self.cache:
            self.cache[key] = self.compute(setting, z)
            if self.progress is not None:
                self.progress(1)
        return self.cache[key]

    def solved_positions(self, count: int) -> list[float]:
        """The positions a table of ``count`` Lobatto positions solves (mirror images are free)."""
        from ..surrogate import lobatto_positions

        return [float(self.stroke - z) if self._mirror(z) else float(z)
                for z in lobatto_positions(self.stroke, count)]

    def _mirror(self, z: float) -> bool:
        return self.symmetric and z > 0.5 * self.stroke * (1 + 1e-12)

    def prefetch(self, pairs, farm_comm) -> None:
        """Solve every (setting, z) of ``pairs`` not yet cached, farmed over the ranks of
        ``farm_comm`` (:func:`tengfield._mpi.farm`, dearest first); every rank then holds
        every result, so the stages that follow run the same on every rank."""
        from .._mpi import farm, rank_of

        todo = {}
        for setting, z in pairs:
            key = self.key(setting, z)
            if key not in self.cache and key not in todo:
                todo[key] = (setting, float(z))
        # dearest first (3D, then the most cells x degree^2), so the dynamic schedule balances;
        items = sorted(todo.values(), key=lambda p: (field_method(p[0].method).dimension,
                                                     p[0].degree**2 / p[0].mesh_size_mm**2),
                       reverse=True)
        progress = self.progress if rank_of(farm_comm) == 0 else None
        results = farm(farm_comm, items, lambda item: self.compute(*item), progress=progress)
        for (setting, z), result in zip(items, results):
            self.cache[self.key(setting, z)] = result

    def table(self, setting: FieldSetting, count: int):
        """Surrogate table of ``count`` Lobatto positions and its solve wall time [s]."""
        from ..surrogate import lobatto_positions, mirrored, table_from_results

        positions = lobatto_positions(self.stroke, count)
        results, wall = [], 0.0
        for z in positions:
            if self._mirror(z):
                results.append(mirrored(self.solve(setting, self.stroke - z), self.stroke))
            else:
                res = self.solve(setting, z)
                wall += res.wall_time
                results.append(res)
        return table_from_results(results, stroke=self.stroke), wall


def planned_solves(solver: _Solver, plan: Plan) -> list:
    """Every (setting, position) the field and surrogate stages solve
    (for :meth:`_Solver.prefetch`)."""
    pairs = []
    for setting in dict.fromkeys(plan.field_settings + plan.far_field_settings):
        pairs += [(setting, z) for z in solver.solved_positions(plan.field_positions)]
    mid = 0.5 * solver.stroke
    pairs += [(setting, mid) for setting in plan.reference_pair + tuple(plan.settings_3d)]
    finest = plan.reference_pair[1]
    for count in {plan.reference_count, *plan.surrogate_counts,
                  *(2 * c - 1 for c in plan.surrogate_counts)}:
        pairs += [(finest, z) for z in solver.solved_positions(count)]
    return pairs


def _curves(table, scene):
    from ..surrogate import TerminalCurves
    return TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge)


def _trajectory(scene, sample_rate: float | None = None, **contact):
    """Simulate ``scene`` (optionally at another sampling rate / contact model);
    returns (dynamics result, wall time [s], the scene that was simulated)."""
    from ..dynamics import simulate

    changes = {}
    if sample_rate is not None:
        changes["run"] = {"sample_rate_hz": float(sample_rate)}
    if contact:
        changes["contact"] = contact
    run_scene = scene.with_values(**changes) if changes else scene
    start = time.perf_counter()
    dyn = simulate(run_scene)
    return dyn, time.perf_counter() - start, run_scene


def field_rows(solver: _Solver, plan: Plan, scene, trajectory, progress=None) -> tuple[list, dict]:
    """The field stage: every setting at the same Lobatto positions (see the module docstring)."""
    rows = []
    n = plan.field_positions
    tables = {}
    for setting in dict.fromkeys(plan.field_settings + plan.far_field_settings):
        tables[setting] = solver.table(setting, n)
    coarse, fine = plan.reference_pair
    ratio = coarse.mesh_size_mm / fine.mesh_size_mm
    t_coarse, t_fine = tables[coarse][0], tables[fine][0]
    ref_table = dataclasses.replace(
        t_fine, capacitance=richardson(t_coarse.capacitance, t_fine.capacitance, ratio, 4),
        induced_fraction=richardson(t_coarse.induced_fraction, t_fine.induced_fraction, ratio, 4))
    ref_peaks = electrical.terminal_peaks(scene, trajectory, _curves(ref_table, scene))
    reference = (f"Richardson extrapolation (h^4) of {coarse.label} and {fine.label} "
                 f"at the same {n} Lobatto positions")
    for setting, (table, wall) in tables.items():
        peaks = electrical.terminal_peaks(scene, trajectory, _curves(table, scene))
        pos_err = max(max_relative_deviation(table.capacitance, ref_table.capacitance),
                      max_relative_deviation(table.induced_fraction, ref_table.induced_fraction))
        rows.append(Row("field", setting.label,
                        {**setting.field_block(), "positions": n,
                         "solves": solves_needed(n, solver.symmetric),
                         "dofs": int(np.max(table.dofs))},
                        wall, peak_errors(peaks, ref_peaks), reference, pos_err))
    # 3D: C and q at mid-stroke against the Richardson reference of the axisymmetric solves
    mid = 0.5 * scene.device.stroke
    ref_mid = [solver.solve(s, mid) for s in plan.reference_pair]
    ref_C = richardson(ref_mid[0].capacitance, ref_mid[1].capacitance, ratio, 4)
    ref_q = richardson(ref_mid[0].induced_charge, ref_mid[1].induced_charge, ratio, 4)
    for setting in plan.settings_3d:
        res = solver.solve(setting, mid)
        err = max(max_relative_deviation(res.capacitance, ref_C),
                  max_relative_deviation(res.induced_charge, ref_q))
        rows.append(Row("field", setting.label, {**setting.field_block(), "positions": 1,
                                                  "solves": 1, "dofs": int(res.dofs)},
                        res.wall_time, {k: math.nan for k in QUANTITIES},
                        "Richardson axisymmetric reference at mid-stroke (C and q only)", err,
                        note="3D: position-level error only"))
    return rows, {"field": reference, "field_peaks": ref_peaks}


def surrogate_rows(solver: _Solver, plan: Plan, scene, trajectory) -> tuple[list, Any]:
    """The surrogate stage: nested Lobatto sets at the finest field setting."""
    setting = plan.reference_pair[1]
    ref_table, _ = solver.table(setting, plan.reference_count)
    ref_curves = _curves(ref_table, scene)
    ref_peaks = electrical.terminal_peaks(scene, trajectory, ref_curves)
    reference = f"{plan.reference_count} Lobatto positions, {setting.label}"
    rows = []
    from ..surrogate import held_out_error, lobatto_positions
    for count in plan.surrogate_counts:
        table, wall = solver.table(setting, count)
        finer = lobatto_positions(scene.device.stroke, 2 * count - 1)[1::2]
        held = solver.table(setting, 2 * count - 1)[0]
        held_out = held.subset(np.isin(np.round(held.positions / scene.device.stroke, 12),
                                       np.round(finer / scene.device.stroke, 12)))
        estimate = held_out_error(table, held_out)
        peaks = electrical.terminal_peaks(scene, trajectory, _curves(table, scene))
        rows.append(Row("surrogate", f"{count} positions",
                        {"positions": count, "solves": solves_needed(count, solver.symmetric),
                         "held_out_estimate": estimate, **setting.field_block()},
                        wall, peak_errors(peaks, ref_peaks), reference))
    return rows, ref_curves


def _peaks_task(scene, curves, sample_rate, contact):
    """Peak-to-peak values of one trajectory and its wall time [s] (one farm task)."""
    dyn, wall, run_scene = _trajectory(scene, sample_rate, **contact)
    return electrical.terminal_peaks(run_scene, dyn, curves), wall


def _tasks(farm_comm, tasks, work, progress):
    """``[work(*t) for t in tasks]``, farmed over ``farm_comm``'s ranks (if any);
    ``progress(n)`` on rank 0 only."""
    from .._mpi import farm, rank_of

    if rank_of(farm_comm) != 0:
        progress = None
    return farm(farm_comm, list(tasks), lambda task: work(*task), progress=progress)


def dynamics_rows(plan: Plan, scene, curves, progress=None, farm_comm=None) -> tuple[list, Any]:
    """Output sampling of the impact map, and soft contact against the impact map.

    Returns the rows and ``(None, reference scene, reference peaks)``; the
    trajectories are farmed over ``farm_comm``'s ranks (every rank gets every row).
    """
    rate = scene.run.sample_rate
    tasks = ([(scene, curves, plan.reference_sample_rate, {})]
             + [(scene, curves, r, {}) for r in plan.sample_rates]
             + [(scene, curves, rate, {})]
             + [(scene, curves, rate, {"model": "soft", "stiffness_N_per_m": k})
                for k in plan.stiffnesses])
    done = _tasks(farm_comm, tasks, _peaks_task, progress)
    ref_peaks = done[0][0]
    sampled = done[1:1 + len(plan.sample_rates)]
    impact_peaks = done[1 + len(plan.sample_rates)][0]
    soft = done[2 + len(plan.sample_rates):]
    rows = []
    for r, (peaks, wall) in zip(plan.sample_rates, sampled):
        rows.append(Row("dynamics", f"impact map, {r:g} Hz sampling",
                        {"model": "impact", "sample_rate_hz": r}, wall,
                        peak_errors(peaks, ref_peaks),
                        f"impact map sampled at {plan.reference_sample_rate:g} Hz plus the "
                        "impact instants (exact extremes)"))
    for k, (peaks, wall) in zip(plan.stiffnesses, soft):
        rows.append(Row("dynamics", f"soft contact k={k:.0e} N/m",
                        {"model": "soft", "stiffness_N_per_m": k, "contact_sample_rate_hz": rate},
                        wall, peak_errors(peaks, impact_peaks),
                        f"impact map (rigid limit), same sampling {rate:g} Hz"))
    ref_scene = scene.with_values(run={"sample_rate_hz": float(plan.reference_sample_rate)})
    return rows, (None, ref_scene, ref_peaks)


def _load_task(scene, curves, load, rate):
    """Mean load power [W], peak-to-peak load voltage [V] and the integrator's wall
    time [s] for one load [ohm] at one step (sampling rate [Hz]); one farm task."""
    loaded = scene.with_values(circuit={"kind": "load", "load_ohm": float(load)})
    dyn, _, run_scene = _trajectory(loaded, rate)
    mask = electrical.steady_window(dyn.t, run_scene)[0]
    start = time.perf_counter()
    out = electrical.steady_load(run_scene, dyn, curves)
    wall = time.perf_counter() - start
    return out["mean_power_W"], lumped.peak_to_peak(out["V_load"][mask]), wall


def circuit_rows(plan: Plan, scene, curves, progress=None, farm_comm=None) -> list:
    """Step of the load integrator (output sampling) for stiff to slow loads
    (the runs farmed over ``farm_comm``'s ranks; every rank gets every row)."""
    ref_rate = plan.circuit_rates[-1] * plan.circuit_refinement
    rates = (ref_rate, *plan.circuit_rates)
    tasks = [(scene, curves, load, rate) for load in plan.loads for rate in rates]
    done = iter(_tasks(farm_comm, tasks, _load_task, progress))
    rows = []
    for load in plan.loads:
        ref_power, ref_v, _ = next(done)
        tau = load * float(np.max(curves.capacitance_samples))
        for rate in plan.circuit_rates:
            power, v, wall = next(done)
            rows.append(Row("circuit", f"R={load:.0e} ohm, {rate:g} Hz step",
                            {"load_ohm": load, "sample_rate_hz": rate,
                             "time_constant_s": tau},
                            wall, {"P_load": relative_error(power, ref_power),
                                   "V_load": relative_error(v, ref_v)},
                            f"exponential integrator at {ref_rate:g} Hz"))
    return rows
