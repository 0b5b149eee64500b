"""``[circuit] kind = "rectifier"``: a full bridge into a store with leakage and an
optional UVLO chip (:mod:`tengfield.harvest`), along a trajectory.

:func:`rectifier_waveforms` runs the bridge on the output samples and every impact
instant; :func:`rectifier_summary` the store, chip and energy books over the steady
window; the entry adds the bridge's V-Q loop, charging.png's
record, and the array's three connections (one bridge, a bridge per cell into one
store, a bridge and store per cell).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..cycle import last_period, loop_area
from ...source import Source
from ..waveforms import (elapsed_times, impact_elapsed, sample_elapsed, steady_window,
                         on_axis, time_origin)
from . import Circuit, CircuitRun, SpreadCircuit
from .rectifier_store import (check_store_resolution, first_crossing, harvester_options,
                              warn_numerical_dissipation)

#: extra columns of ``waveforms.csv`` for ``[circuit] kind = "rectifier"``
RECTIFIER_COLUMNS = ["V_store_V", "I_store_A", "E_store_J", "pmic_on"]
#: rows per chunk of a rectifier run (times x cells), bounds its memory
CHUNK_VALUES = 2_000_000


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
    from ...harvest import Harvester

    check_store_resolution(scene)
    grid, output_index = rectifier_grid(scene, dynamics)
    source = Source.of_scene(scene, curves, dynamics)
    run = Harvester(1, time_origin=time_origin(dynamics), **harvester_options(scene))
    rows = max(2, CHUNK_VALUES)
    parts = []
    for start in range(0, grid.size, rows):
        times = grid[start:start + rows]
        gap, _, _ = sample_elapsed(dynamics, times)
        if source.charged:
            q, c = source.state(times, gap)
        else:
            q, c = np.zeros_like(gap), np.full_like(gap, 1e-12)
        parts.append(run.advance(times, q, c))
    fine = concat_results(parts)
    return {"V_store_V": fine.store_voltage[output_index],
            "I_store_A": fine.store_current[output_index],
            "E_store_J": fine.stored_energy[output_index],
            "pmic_on": fine.chip_on[output_index].astype(float),
            "fine": fine, "output_index": output_index}


def concat_results(parts):
    """One :class:`tengfield.harvest.HarvestResult` of consecutive chunks.

    The chunks are taken out of the list ``parts`` (a list: emptied) as they are
    copied into the whole arrays, so memory peaks at the whole result plus one chunk
    (a 500 s rectifier run held every chunk and its concatenation: twice the record)."""
    if len(parts) == 1:
        return parts[0]
    first, last = parts[0], parts[-1]
    kind = type(first)
    names = [f.name for f in dataclasses.fields(first)
             if isinstance(getattr(first, f.name), np.ndarray)]
    total = sum(len(p.time) for p in parts)
    whole = {name: np.empty((total, *getattr(first, name).shape[1:]),
                            dtype=getattr(first, name).dtype) for name in names}
    fields = {f.name: getattr(last, f.name) for f in dataclasses.fields(first)
              if f.name not in whole}
    fields["initial_terminal_energy"] = first.initial_terminal_energy
    fields["initial_stored_energy"] = first.initial_stored_energy
    del first, last
    start = 0
    if not isinstance(parts, list):
        parts = list(parts)
    while parts:
        part = parts.pop(0)
        n = len(part.time)
        for name in names:
            whole[name][start:start + n] = getattr(part, name)
        start += n
        del part
    return kind(**fields, **whole)


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
    return summary_block(scene, record_numbers(scene, fine, window_start), curves, max_gap)


def record_numbers(scene, fine, window_start: float) -> dict:
    """What :func:`summary_block` reads of a whole record ``fine`` (a
    :class:`tengfield.harvest.HarvestResult`); :class:`RectifierChunks` takes the same
    numbers a chunk at a time."""
    from ...harvest import mean_bridge_current

    c = scene.circuit
    t = fine.time
    inside = t >= window_start
    k0 = int(np.flatnonzero(inside)[0]) if inside.any() else 0
    on = fine.chip_on
    dt = np.diff(t)
    return {
        "t0": float(t[0]), "t_end": float(t[-1]), "t_k0": float(t[k0]),
        "store_input_k0": float(fine.store_input[k0]),
        "bridge_energy_k0": float(fine.bridge_energy[k0]),
        "switch_on": int(np.count_nonzero(on[1:] & ~on[:-1])),
        "switch_off": int(np.count_nonzero(~on[1:] & on[:-1])),
        "on_time": float(np.sum(dt[on[1:]])),
        "max_store_voltage": float(np.max(fine.store_voltage)),
        "max_store_voltage_window": float(np.max(fine.store_voltage[k0:])),
        "mean_bridge_current_window": mean_bridge_current(fine, k0),
        "crossing_falling": first_crossing(t, fine.store_voltage, c.uvlo_falling),
        "crossing_rising": first_crossing(t, fine.store_voltage, c.uvlo_rising),
        "last": fine, "origin": float(getattr(fine, "time_origin", 0.0))}


def summary_block(scene, numbers: dict, curves=None, max_gap=None) -> dict:
    """summary.json's ``rectifier`` block from :func:`record_numbers` (or the streamed
    :meth:`RectifierChunks.numbers`): ``numbers["last"]`` is the record (or its last
    chunk) whose final values and threshold times it reads."""
    from ...harvest import saturation_voltage, warn_starved_store

    c = scene.circuit
    n_ = numbers
    last = n_["last"]
    origin = n_["origin"]
    period = scene.excitation.period
    length = n_["t_end"] - n_["t_k0"]
    into_store = float(last.store_input[-1] - n_["store_input_k0"])
    bridge = float(last.bridge_energy[-1] - n_["bridge_energy_k0"])
    books = last.balance()
    warn_numerical_dissipation(books)
    if c.pmic == "uvlo":
        warn_starved_store(n_["max_store_voltage_window"], n_["mean_bridge_current_window"],
                           c.pmic_quiescent_current)
    span = n_["t_end"] - n_["t0"]
    out = {
        "diode": c.diode, "storage_capacitance_F": c.storage_capacitance, "pmic": c.pmic,
        "final_store_voltage_V": float(last.store_voltage[-1]),
        "final_stored_energy_J": float(last.stored_energy[-1]),
        "max_store_voltage_V": n_["max_store_voltage"],
        "time_to_uvlo_falling_V_s": origin + n_["crossing_falling"],
        "time_to_uvlo_rising_V_s": origin + _first_of(
            n_["crossing_rising"], last.threshold_times["uvlo_rising_s"]),
        "uvlo_levels_V": [c.uvlo_falling, c.uvlo_rising],
        "record_length_s": span,
        "chip_first_on_s": origin + last.threshold_times["uvlo_rising_s"],
        "chip_first_lockout_s": origin + last.threshold_times["uvlo_falling_s"],
        "chip_switch_on_count": n_["switch_on"], "chip_switch_off_count": n_["switch_off"],
        "chip_duty_cycle": n_["on_time"] / span if span > 0 else 0.0,
        "chip_output_energy_J": float(last.chip_input_energy[-1]) * c.pmic_efficiency,
        "average_harvested_power_W": into_store / length if length > 0 else 0.0,
        "energy_per_cycle_J": bridge * period / length if length > 0 else 0.0,
        "window_start_s": origin + n_["t_k0"],
        "energy_books_J": {k: v for k, v in books.items() if k.endswith("_J")},
        "energy_residuals": {k: v for k, v in books.items() if k.endswith("_residual")},
        "energy_residuals_rule": "relative to the energy delivered into the bridges; the "
                                 "backward-Euler step's own dissipation is booked as "
                                 "numerical_dissipation_J",
    }
    if curves is not None and max_gap is not None:
        n = scene.device.cells
        axis = on_axis(curves)           # the bound of the ball on the axis
        q_max = float(curves.charge(max_gap, *axis)) * n
        c_max = float(curves.capacitance(max_gap, *axis)) * n + c.parallel_capacitance
        c_0 = float(curves.capacitance(0.0, *axis)) * n + c.parallel_capacitance
        out["saturation_voltage_V"] = saturation_voltage(abs(q_max), c_max, c_0,
                                                         c.diode_forward_voltage)
    return out


class Rectifier(Circuit):
    name = "rectifier"
    fills_store = True
    linear_in_charge = False     # its diodes
    columns = tuple(RECTIFIER_COLUMNS)
    keys = ("diode", "diode_forward_voltage_V", "diode_saturation_current_A",
            "diode_emission_coefficient", "diode_series_resistance_ohm",
            "storage_capacitance_uF", "storage_leakage_ohm", "pmic", "uvlo_rising_V",
            "uvlo_falling_V", "pmic_output_V", "pmic_load_ohm", "pmic_efficiency",
            "pmic_quiescent_current_A", "pmic_shunt_V")

    def check(self, scene) -> None:
        check_store_resolution(scene)

    def start(self, scene, source, window_start, chunk_rows):
        from .rectifier_stream import RectifierChunks
        return RectifierChunks(scene, source, window_start) if source.charged else None

    def finish(self, scene, source, state, record, note) -> CircuitRun:
        if state is None:                  # the loop's zero columns
            return CircuitRun({}, f"Q_SC = 0: nothing to rectify{note}", status="skipped")
        books = state.last.balance()
        c = scene.circuit
        if record.get("columns") is not None:   # a whole run: its whole record, one step
            data = {"fine": state.last}
        else:                                   # a chunked one: the reductions
            data = {"fine": state.last_period(), "numbers": state.numbers(),
                    "charging": state.charging()}
        return CircuitRun(
            {}, f"full bridge ({c.diode}) into {c.storage_capacitance * 1e6:g} uF, "
                f"pmic = {c.pmic!r}{note}",
            {"integration_points": int(state.points),
             "energy_balance_relative_residual": max(
                 books["terminal_residual"], books["bridge_residual"], books["store_residual"])},
            data=data)

    def cycle(self, scene, source, run, t, mask, max_gap) -> dict:
        """The bridge's V-Q loop, summary.json's ``rectifier`` block and charging.png's
        record (no resistive-load loop: a rectifier run has no load to compare)."""
        period = scene.excitation.period
        fine = run.data["fine"]
        fine_last = last_period(fine.time, period)
        v = fine.voltage[fine_last, 0]
        q = fine.bridge_charge[fine_last, 0]
        vq = {"rectifier": (q - q[0], v, loop_area(v, q))}
        numbers = run.data.get("numbers")       # a streamed run's reductions
        if numbers is None:
            numbers = record_numbers(scene, fine, float(t[mask][0]))
        return {"energy_per_cycle": {"rectifier_loop_area_J": vq["rectifier"][2]},
                "rectifier": summary_block(scene, numbers, source.curves, max_gap),
                "_fine": run.data.get("charging", fine), "_vq": vq}

    def array_identical(self, scaled, dynamics, curves, waves) -> dict:
        if curves is None:
            return super().array_identical(scaled, dynamics, curves, waves)
        rect = rectifier_waveforms(scaled, dynamics, curves)
        waves.update({c: rect[c] for c in RECTIFIER_COLUMNS})
        fine = rect["fine"]
        energy = float(fine.store_input[-1])
        t = elapsed_times(dynamics)
        mask, _ = steady_window(t, scaled)
        return dict(value=energy, reference_value=energy,
                    compared="energy into the store(s) [J]", output=rect["E_store_J"],
                    reference=rect["E_store_J"], label="E_store [J]", fine=fine,
                    summary={"rectifier": rectifier_summary(scaled, fine, float(t[mask][0]))})

    def spread(self, scene, t, weights, origin):
        return _SpreadRectifier(scene, t, weights, origin)


class _SpreadRectifier(SpreadCircuit):
    """``[array] connection``: "parallel" (the cells' terminals in parallel, one bridge),
    "rectified-parallel" (a bridge per cell into one store), "rectified-per-cell" (a
    bridge and store per cell; energies add, V_store is the cells' mean); the reference
    is N x the nominal cell wired the same way."""

    def __init__(self, scene, t, weights, origin):
        from ...harvest import Harvester

        super().__init__(scene, t, weights)
        check_store_resolution(scene)
        self.connection = connection = scene.array.connection
        self.g = g = len(weights)
        self.n = float(np.sum(weights))
        bare = dict(harvester_options(scene), parallel_capacitance=0.0, time_origin=origin)
        if connection == "rectified-per-cell":
            self.harvesters = [Harvester(1, **bare) for _ in range(g)]
        else:
            self.harvesters = [Harvester(g if connection == "rectified-parallel" else 1, **bare)]
        self.ref_harvester = Harvester(1, **bare)
        self.columns = {c: np.empty(t.size) for c in RECTIFIER_COLUMNS}
        self.parts, self.ref_parts = [], []

    def chunk(self, block, times, q, c, sums, ref_q, ref_c) -> None:
        connection, weights, n = self.connection, self.weights, self.n
        c_p = self.scene.circuit.parallel_capacitance
        harvesters, parts = self.harvesters, self.parts
        if connection == "parallel":
            res = harvesters[0].advance(times, sums["Q"][block], sums["C"][block] + c_p)
            store = (res.store_voltage, res.store_current, res.stored_energy,
                     res.chip_on.astype(float))
            parts.append(_store_only(res))
        elif connection == "rectified-parallel":
            res = harvesters[0].advance(times, q * weights, c * weights + c_p * weights)
            store = (res.store_voltage, res.store_current, res.stored_energy,
                     res.chip_on.astype(float))
            parts.append(_store_only(res))
        else:
            results = [h.advance(times, q[:, j], c[:, j] + c_p) for j, h in enumerate(harvesters)]
            w = weights / n
            store = (sum(r.store_voltage * wj for r, wj in zip(results, w)),
                     sum(r.store_current * wj for r, wj in zip(results, weights)),
                     sum(r.stored_energy * wj for r, wj in zip(results, weights)),
                     sum(r.chip_on * wj for r, wj in zip(results, w)))
            parts[:] = [results]             # only the last chunk's ends are used
        for col, value in zip(RECTIFIER_COLUMNS, store):
            self.columns[col][block] = value
        if connection == "parallel":            # N x one cell, C_p once across them
            ref_q, ref_c = ref_q * n, ref_c * n + c_p
        elif connection == "rectified-parallel":  # N cells with C_p each, one store
            ref_q, ref_c = ref_q * n, (ref_c + c_p) * n
        else:                                     # one cell into its own store (x N below)
            ref_c = ref_c + c_p
        self.ref_parts.append(self.ref_harvester.advance(times, ref_q, ref_c))

    def finish(self, sums, ref, columns, mask) -> dict:
        connection, weights, n, parts = self.connection, self.weights, self.n, self.parts
        columns.update(self.columns)
        ref_fine = concat_results(self.ref_parts)
        ref_energy = float(ref_fine.store_input[-1]) * (n if connection == "rectified-per-cell"
                                                        else 1.0)
        summary = {}
        if connection == "rectified-per-cell":
            energy = float(sum(parts[-1][j].store_input[-1] * weights[j]
                               for j in range(self.g)))
            books = [r.balance() for r in parts[-1]]
            warn_numerical_dissipation(
                {k: float(sum(b[k] * w for b, w in zip(books, weights)))
                 for k in ("delivered_J", "numerical_dissipation_J")})
            fine = None
            ref_curve = ref_fine.stored_energy * n
        else:
            fine = concat_results(parts)
            energy = float(fine.store_input[-1])
            ref_curve = ref_fine.stored_energy
            summary["rectifier"] = rectifier_summary(self.scene, fine, float(self.t[mask][0]))
        return dict(value=energy, reference_value=ref_energy,
                    compared="energy into the store(s) [J]", output=self.columns["E_store_J"],
                    reference=ref_curve, label="E_store [J]", fine=fine, summary=summary)


def _store_only(res):
    """A chunk's HarvestResult without its (rows, cells) arrays: an array run keeps only
    the store's 1-D record, never N x samples."""
    empty = np.empty((res.time.size, 0))        # not a view: the chunk's memory is freed
    return dataclasses.replace(res, voltage=empty, bridge_charge=empty.copy())


CIRCUIT = Rectifier()
