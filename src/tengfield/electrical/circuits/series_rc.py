"""``[circuit] kind = "series-rc"``: R (``load_ohm``) in series with C_s
(``series_capacitance_pF``) across the terminal and C_p.

The terminal is Q_SC behind C = C_T + C_p; the branch carries Q (the charge on C_s,
zero at the start). With the deficit D = Q_SC - Q = C V on the terminal:

    R dQ/dt = V - Q / C_s = Q_SC / C - Q / C_eff,   1 / C_eff = 1 / C + 1 / C_s,

the load's ODE (for its deficit, here Q) with C_eff for C and Q_SC / (R C) for I_SC,
so the load's exponential integrator (:func:`tengfield.lumped.load_response`)
solves it on the load's grid (:func:`.load.fine_terminal`). C_s -> inf is the plain load; C_s -> 0
passes no charge. Columns: ``V_load_V`` the branch's voltage (the terminal's),
``I_load_A`` its current, ``P_load_W`` = I^2 R, ``V_series_C_V`` = Q / C_s. Energy
books: delivered = V I_SC - V^2/2 dC_T/dt = I^2 R + d/dt[C V^2/2 + Q^2/(2 C_s)].
"""
from __future__ import annotations

import numpy as np

from ... import lumped
from . import Circuit, CircuitRun, SpreadCircuit
from .load import (Load, LoadChunks, fine_terminal, load_block, no_charge, streamed_load,
                   window_energies)
from ..waveforms import elapsed_times, steady_window, trapezoid

COLUMNS = ("V_load_V", "I_load_A", "P_load_W", "V_series_C_V")


#: C_s above this multiple of the largest C_T + C_p: integrate the terminal's deficit
#: D = Q_SC - Q (driven by I_SC, as the load: exact load limit for C_s -> inf); below
#: it the charge Q on C_s (driven by Q_SC / (R C): Q and the small current stay
#: accurate as C_s -> 0, where D's lag would swamp them)
DEFICIT_FORM_RATIO = 1e3


def series_response(times, q_sc, i_sc, c_t, load: float, c_p: float, c_s: float) -> dict:
    """V [V] across the branch, its current I [A], P = I^2 R [W], Q [C] on C_s and
    V_Cs [V] along ``times`` (terminal ``q_sc``, ``i_sc``, ``c_t`` there)."""
    c = np.asarray(c_t, dtype=float) + c_p
    q_sc = np.asarray(q_sc, dtype=float)
    c_eff = c * c_s / (c + c_s)
    if c_s >= DEFICIT_FORM_RATIO * float(np.max(c)):
        # dD/dt = I_SC + Q_SC / (R C_s) - D / (R C_eff), D(0) = Q_SC(0)
        res = lumped.load_response(times, q_sc,
                                    np.asarray(i_sc, dtype=float) + q_sc / (load * c_s),
                                    c_eff, load, 0.0)
        q = res.charge
    else:
        # R dQ/dt = Q_SC / C - Q / C_eff, Q(0) = 0
        res = lumped.load_response(times, np.zeros_like(q_sc), q_sc / (load * c), c_eff,
                                    load, 0.0)
        q = res.voltage * c_eff
    voltage = (q_sc - q) / c
    v_cs = q / c_s
    current = (voltage - v_cs) / load
    return {"V": voltage, "I": current, "P": current * current * load, "Q": q, "V_Cs": v_cs,
            "C": c}


def series_waveforms(scene, dynamics, curves, window_start=None) -> dict:
    """The ``COLUMNS`` at the output samples, mean power and energy books over the window
    after ``window_start`` (the run's own axis; None: the whole run)."""
    c = scene.circuit
    if curves is None:
        out = no_charge(dynamics)
        return {**out, "V_series_C": out["V_load"].copy()}
    n_cells = scene.device.cells
    c_min = float(np.min(curves.capacitance_samples)) * n_cells + c.parallel_capacitance
    c_max = float(np.max(curves.capacitance_samples)) * n_cells + c.parallel_capacitance
    grid, fine, index = fine_terminal(scene, dynamics, curves,
                                      c.load * c_min * c.series_capacitance
                                      / (c_min + c.series_capacitance))
    r = series_response(grid, fine["Q_sc"], fine["I_sc"], fine["C_T"], c.load,
                        c.parallel_capacitance, c.series_capacitance)
    delivered = lumped.delivered_power(r["V"], fine["I_sc"], fine["dC_T_dt"])
    stored = 0.5 * r["C"] * r["V"] ** 2 + 0.5 * r["Q"] ** 2 / c.series_capacitance
    return {"V_load": r["V"][index], "I_load": r["I"][index], "P_load": r["P"][index],
            "V_series_C": r["V_Cs"][index],
            **window_energies(dynamics, grid, window_start, r["P"], delivered, stored),
            "integration_points": int(grid.size),
            "time_constant_s": c.load * c_max * c.series_capacitance
            / (c_max + c.series_capacitance)}


def steady_series(scene, dynamics, curves) -> dict:
    """:func:`series_waveforms` with energies over the steady window."""
    t = elapsed_times(dynamics)
    mask, _ = steady_window(t, scene)
    return series_waveforms(scene, dynamics, curves, t[mask][0])


def _columns(result) -> dict:
    return {"V_load_V": result["V_load"], "I_load_A": result["I_load"],
            "P_load_W": result["P_load"], "V_series_C_V": result["V_series_C"]}


class SeriesChunks(LoadChunks):
    """:func:`series_waveforms` a chunk of output rows at a time (the streamed stage,
    :class:`.load.LoadChunks`' grid): a first pass takes the largest C_T + C_p of the
    grid (it chooses the form, as :func:`series_response` does on the whole grid), then
    the chosen form's state (D or Q) is carried from chunk to chunk."""

    def __init__(self, scene, source, window_start, first_rows):
        c, curves = scene.circuit, source.curves
        c_min = float(np.min(curves.capacitance_samples)) * scene.device.cells \
            + c.parallel_capacitance
        c_max = float(np.max(curves.capacitance_samples)) * scene.device.cells \
            + c.parallel_capacitance
        super().__init__(scene, source, window_start, first_rows,
                         time_constant=c.load * c_min * c.series_capacitance
                         / (c_min + c.series_capacitance))
        self.time_constant = c.load * c_max * c.series_capacitance / (
            c_max + c.series_capacitance)
        from ..loop import chunk_bounds
        bounds = chunk_bounds(self.t.size, first_rows)
        largest = -np.inf
        self._kept = None           # a whole run's one grid, not evaluated twice
        for i0, i1 in bounds:
            fine = self.fine(i0, i1)
            largest = max(largest, float(np.max(fine[1]["C_T"])))
            if len(bounds) == 1:
                self._kept = ((i0, i1), fine)
        self.deficit_form = c.series_capacitance >= DEFICIT_FORM_RATIO * (
            largest + c.parallel_capacitance)

    def chunk(self, i0: int, i1: int) -> dict:
        kept = self._kept
        grid, fine, output_index = kept[1] if kept is not None and kept[0] == (i0, i1) \
            else self.fine(i0, i1)
        c = self.scene.circuit
        load, c_s = c.load, c.series_capacitance
        cap = np.asarray(fine["C_T"], dtype=float) + c.parallel_capacitance
        q_sc = np.asarray(fine["Q_sc"], dtype=float)
        c_eff = cap * c_s / (cap + c_s)
        zero = np.zeros_like(q_sc)
        if self.deficit_form:     # D = Q_SC - Q carried; series_response's first branch
            d0 = q_sc[0] if self.deficit is None else self.deficit
            res = lumped.load_response(grid, zero, np.asarray(fine["I_sc"], dtype=float)
                                        + q_sc / (load * c_s), c_eff, load, 0.0,
                                        initial_load_charge=-d0)
            q = q_sc - (-res.charge)
        else:                     # Q on C_s carried; its second branch
            d0 = 0.0 if self.deficit is None else self.deficit
            res = lumped.load_response(grid, zero, q_sc / (load * cap), c_eff, load, 0.0,
                                        initial_load_charge=-d0)
            q = res.voltage * c_eff
        self.deficit = -res.charge[-1]
        voltage = (q_sc - q) / cap
        v_cs = q / c_s
        current = (voltage - v_cs) / load
        power = current * current * load
        delivered = lumped.delivered_power(voltage, fine["I_sc"], fine["dC_T_dt"])
        stored = 0.5 * cap * voltage ** 2 + 0.5 * q ** 2 / c_s
        self.add(grid, i0, power, delivered, stored)
        keep = output_index[:i1 - i0]
        return {"V_load_V": voltage[keep], "I_load_A": current[keep], "P_load_W": power[keep],
                "V_series_C_V": v_cs[keep]}


class SeriesRC(Load):
    """The load's summary, V-Q loop and array comparison, with C_s in the branch."""
    name = "series-rc"
    columns = COLUMNS
    keys = ("load_ohm", "series_capacitance_pF")
    fit_load = False             # fit's forward model is the R ∥ C_p load, not R + C_s
    fit_columns = Circuit.fit_columns

    def start(self, scene, source, window_start, chunk_rows):
        return SeriesChunks(scene, source, window_start, chunk_rows) if source.charged \
            else None

    def finish(self, scene, source, state, record, note) -> CircuitRun:
        c = scene.circuit
        details, data = streamed_load(source.dynamics, state, record)
        return CircuitRun({}, f"series R + C ODE, R = {c.load:g} ohm, "
                              f"C_s = {c.series_capacitance * 1e12:g} pF{note}", details,
                          data=data)

    def summary(self, scene, run, waveforms, mask) -> dict:
        return {"load": load_block(scene, run.data, waveforms, mask,
                                   series_capacitance_F=scene.circuit.series_capacitance)}

    def array_identical(self, scaled, dynamics, curves, waves) -> dict:
        if curves is None:
            return super(Load, self).array_identical(scaled, dynamics, curves, waves)
        result = steady_series(scaled, dynamics, curves)
        waves.update(_columns(result))
        return dict(value=result["mean_power_W"], reference_value=result["mean_power_W"],
                    compared="mean load power [W]", output=result["P_load"],
                    reference=result["P_load"], label="P_load [W]", load=result)

    def spread(self, scene, t, weights, origin):
        return _SpreadSeries(scene, t, weights)


class _SpreadSeries(SpreadCircuit):
    """The cells' terminals in parallel into one R + C_s, on the output samples."""

    def finish(self, sums, ref, columns, mask) -> dict:
        t, c = self.t, self.scene.circuit
        args = (c.load, c.parallel_capacitance, c.series_capacitance)
        r = series_response(t, sums["Q"], sums["I"], sums["C"], *args)
        rr = series_response(t, ref["Q"], ref["I"], ref["C"], *args)
        columns.update({"V_load_V": r["V"], "I_load_A": r["I"], "P_load_W": r["P"],
                        "V_series_C_V": r["V_Cs"]})
        length = t[mask][-1] - t[mask][0]
        power = float(trapezoid(r["P"][mask], t[mask]) / length)
        ref_power = float(trapezoid(rr["P"][mask], t[mask]) / length)
        return dict(value=power, reference_value=ref_power, compared="mean load power [W]",
                    output=r["P"], reference=rr["P"], label="P_load [W]",
                    load={"mean_power_W": power, "V_load": r["V"], "I_load": r["I"]},
                    summary={"mean_load_power_W": power})


CIRCUIT = SeriesRC()
