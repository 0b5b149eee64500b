"""``[circuit] kind = "load"``: a resistor R (``load_ohm``) across the terminal and C_p.

The load ODE along a trajectory with impacts (:func:`load_waveforms`: the
exponential integrator of :func:`tengfield.lumped.load_response` on a grid
refined at every impact), its summary block (mean power, energy balance), the
resistive V-Q loop of vq.png (also drawn beside a rectifier's) and the array's
load (the cells' terminals in parallel into one R).
"""
from __future__ import annotations

import numpy as np

from ... import lumped
from ..cycle import cumulative, last_period, loop_area
from ...source import Source
from ..waveforms import (IMPACT_OFFSET_PERIODS, _impact_states, elapsed_times,
                         impact_elapsed, sample_elapsed, steady_window, time_origin, trapezoid)
from . import Circuit, CircuitRun, SpreadCircuit

#: extra columns of ``waveforms.csv`` when a load is connected
LOAD_COLUMNS = ["V_load_V", "I_load_A", "P_load_W"]


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
    The exponential integrator of :func:`tengfield.lumped.load_response`
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


def _load_waveforms(scene, dynamics, curves, window_start, grid: "LoadGrid | None" = None
                    ) -> dict:
    """:func:`load_waveforms` on the run's own axis (``window_start`` after the origin);
    ``grid``: a :class:`LoadGrid` of the same run kept for a scan over loads."""
    n_cells = scene.device.cells
    c_p = scene.circuit.parallel_capacitance
    load = scene.circuit.load
    if curves is None:
        return no_charge(dynamics)
    c_min = float(np.min(curves.capacitance_samples)) * n_cells + c_p
    grid, fine, output_index = (LoadGrid(scene, dynamics, curves) if grid is None
                                else grid).fine(load * c_min)
    response = lumped.load_response(grid, fine["Q_sc"], fine["I_sc"], fine["C_T"], load, c_p)
    delivered = lumped.delivered_power(response.voltage, fine["I_sc"], fine["dC_T_dt"])
    stored = lumped.stored_energy(response.voltage, fine["C_T"], c_p)
    return {"V_load": response.voltage[output_index], "I_load": response.current[output_index],
            "P_load": response.power[output_index],
            **window_energies(dynamics, grid, window_start, response.power, delivered, stored),
            "integration_points": int(grid.size),
            "time_constant_s": load * (float(np.max(curves.capacitance_samples)) * n_cells + c_p)}


def no_charge(dynamics) -> dict:
    """The load numbers of a run with Q_SC = 0: nothing moves."""
    zero = np.zeros_like(elapsed_times(dynamics))
    return {"V_load": zero, "I_load": zero.copy(), "P_load": zero.copy(), "mean_power_W": 0.0,
            "delivered_energy_J": 0.0, "dissipated_energy_J": 0.0,
            "stored_energy_change_J": 0.0, "integration_points": int(zero.size),
            "time_constant_s": 0.0}


def fine_terminal(scene, dynamics, curves, time_constant: float):
    """``(grid, terminal, output_index)``: the integration grid of a load on the run's own
    axis (the output times, every impact twice with its pre- and post-impact velocity,
    :func:`relaxation_times` of ``time_constant`` [s] after the start and each impact),
    the terminal waveforms there (:meth:`tengfield.source.Source.terminal`) and the indices of
    the output samples in it."""
    return LoadGrid(scene, dynamics, curves).fine(time_constant)


class LoadGrid:
    """The part of :func:`fine_terminal`'s grid that no load changes (the output times and
    every impact twice, with their terminal waveforms), kept for a scan over loads:
    :meth:`fine` adds one time constant's :func:`relaxation_times` and gives
    :func:`fine_terminal`'s arrays, bitwise (the waveforms are pointwise in time).
    ``scene`` gives ``[device] cells`` and ``[circuit] parallel_capacitance_pF``, which
    every load of the scan shares."""

    def __init__(self, scene, dynamics, curves):
        self.scene, self.dynamics, self.curves = scene, dynamics, curves
        t = elapsed_times(dynamics)
        self.t = t
        self.origin = time_origin(dynamics)
        impacts = impact_elapsed(dynamics, t[0], t[-1])
        self.starts = np.concatenate([[t[0]], impacts])
        self.output_step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
        gap_pre, vel_pre, gap_post, vel_post = _impact_states(scene, dynamics, impacts)
        self.grid = np.concatenate([t, impacts, impacts])
        gap = np.concatenate([np.asarray(dynamics.gap, dtype=float), gap_pre, gap_post])
        vel = np.concatenate([np.asarray(dynamics.gap_velocity, dtype=float), vel_pre,
                              vel_post])
        # equal times: pre-impact (0) before an output sample (1) before post-impact (2)
        self.tag = np.concatenate([np.ones(t.size), np.zeros(impacts.size),
                                   np.full(impacts.size, 2.0)])
        self.terminal = self._terminal(self.grid, gap, vel)
        self._no_extra = None     # fine() of a time constant that adds no point

    def _terminal(self, grid, gap, vel) -> dict:
        return Source.of_scene(self.scene, self.curves, self.dynamics).terminal(grid, gap, vel)

    def fine(self, time_constant: float):
        """:func:`fine_terminal`'s ``(grid, terminal, output_index)`` for ``time_constant``
        [s]."""
        t = self.t
        extra = relaxation_times(self.starts, time_constant, self.output_step, t[-1])
        if extra.size == 0 and self._no_extra is not None:
            grid, fine, output_index = self._no_extra
            return grid.copy(), {k: v.copy() for k, v in fine.items()}, output_index.copy()
        gap_extra, vel_extra, _ = (sample_elapsed(self.dynamics, extra) if extra.size
                                   else (np.empty(0),) * 3)
        grid = np.concatenate([self.grid, extra])
        tag = np.concatenate([self.tag, np.full(extra.size, 3.0)])
        order = np.lexsort((tag, grid))
        output_index = np.flatnonzero(order < t.size)   # order[...] of outputs is increasing
        terminal = self.terminal
        if extra.size:
            more = self._terminal(extra, gap_extra, vel_extra)
            terminal = {k: np.concatenate([v, more[k]]) for k, v in terminal.items()}
        fine = {k: v[order] for k, v in terminal.items()}
        grid = grid[order]
        if extra.size == 0:
            self._no_extra = (grid, fine, output_index)
            return grid.copy(), {k: v.copy() for k, v in fine.items()}, output_index.copy()
        return grid, fine, output_index


def window_energies(dynamics, grid, window_start, dissipated_power, delivered_power,
                    stored_energy) -> dict:
    """Mean power and the energy books of a load over the window after ``window_start``
    (the run's own axis; None: the whole run): trapezoidal sums on ``grid``."""
    window_start = elapsed_times(dynamics)[0] if window_start is None else window_start
    in_window = grid >= window_start
    t_window = grid[in_window]
    window_length = t_window[-1] - t_window[0] if t_window.size > 1 else 0.0
    dissipated = float(trapezoid(dissipated_power[in_window], t_window))
    stored_window = stored_energy[in_window]
    return {"mean_power_W": dissipated / window_length if window_length > 0 else 0.0,
            "delivered_energy_J": float(trapezoid(delivered_power[in_window], t_window)),
            "dissipated_energy_J": dissipated,
            "stored_energy_change_J": float(stored_window[-1] - stored_window[0])}


class LoadChunks:
    """The load ODE a chunk of output rows at a time (the streamed stage of a long run,
    :mod:`tengfield.electrical.stream`): the same grid, terminal and exponential integrator
    as :func:`load_waveforms`, the load's deficit carried exactly from one chunk to the
    next (the chunks share their boundary sample), the energy sums accumulated over the
    window after ``window_start`` (the run's own axis). Feed every chunk in order to
    :meth:`chunk`; :meth:`numbers` then gives :func:`load_waveforms`' numbers."""

    def __init__(self, scene, source: Source, window_start: float, first_rows: int,
                 time_constant: float | None = None):
        dynamics, curves = source.dynamics, source.curves
        self.scene, self.dynamics, self.curves = scene, dynamics, curves
        self.source = source
        self.window_start = window_start
        self.t = elapsed_times(dynamics)                  # the dynamics' own array, no copy
        n_cells, c_p = scene.device.cells, scene.circuit.parallel_capacitance
        c_min = float(np.min(curves.capacitance_samples)) * n_cells + c_p
        # the relaxation points' time constant (fine_terminal's): R (C_min + C_p) here
        self.tau = scene.circuit.load * c_min if time_constant is None else time_constant
        t = self.t
        self.impacts = impact_elapsed(dynamics, t[0], t[-1])
        head = t[:first_rows + 1]    # (a median over the whole run would copy it)
        self.step = float(np.median(np.diff(head))) if head.size > 1 else 0.0
        self.deficit = None
        self.sums = {"delivered": 0.0, "dissipated": 0.0}
        self.window = None           # (first time, its stored energy, last time, stored)
        self.points = 0
        self.time_constant = scene.circuit.load * (
            float(np.max(curves.capacitance_samples)) * n_cells + c_p)

    def chunk(self, i0: int, i1: int) -> dict:
        """V_load [V], I_load [A], P_load [W] at the output rows ``i0:i1``."""
        grid, fine, output_index = self.fine(i0, i1)
        scene = self.scene
        c_p, load = scene.circuit.parallel_capacitance, scene.circuit.load
        # Q_SC = 0 and Q_R(0) = -D: the integrator starts from the carried deficit D
        # exactly and returns -D as its charge (every step as load_waveforms' own)
        d0 = fine["Q_sc"][0] if self.deficit is None else self.deficit
        response = lumped.load_response(grid, np.zeros_like(grid), fine["I_sc"], fine["C_T"],
                                         load, c_p, initial_load_charge=-d0)
        self.deficit = -response.charge[-1]
        delivered = lumped.delivered_power(response.voltage, fine["I_sc"], fine["dC_T_dt"])
        stored = lumped.stored_energy(response.voltage, fine["C_T"], c_p)
        self.add(grid, i0, response.power, delivered, stored)
        keep = output_index[:i1 - i0]
        return {"V_load_V": response.voltage[keep], "I_load_A": response.current[keep],
                "P_load_W": response.power[keep]}

    def add(self, grid, i0: int, dissipated, delivered, stored) -> None:
        """The chunk's grid points and energy sums over the window (trapezoidal)."""
        self.points += grid.size - (1 if i0 > 0 else 0)
        in_window = grid >= self.window_start
        if in_window.any():
            g = grid[in_window]
            stored = stored[in_window]
            self.sums["dissipated"] += float(trapezoid(dissipated[in_window], g))
            self.sums["delivered"] += float(trapezoid(delivered[in_window], g))
            first = self.window or (g[0], stored[0])
            self.window = (first[0], first[1], g[-1], stored[-1])

    def fine(self, i0: int, i1: int):
        """``(grid, terminal, output_index)`` of :func:`fine_terminal` over the output rows
        ``i0:i1`` and the next chunk's first sample (which closes the last step)."""
        scene, dynamics, t_all = self.scene, self.dynamics, self.t
        n = t_all.size
        j1 = min(i1 + 1, n)                     # the next chunk's first sample closes it
        t = t_all[i0:j1]
        lo, hi = t[0], t[-1]
        imp = self.impacts
        pre = imp[(imp > lo) & (imp <= hi)]     # pre-impact states sort before a sample
        post = imp[(imp >= lo) & (imp < hi)]    # at the same time, post-impact after it
        starts = np.concatenate([t_all[:1], imp])
        starts = starts[(starts > lo - 5.0 * self.step) & (starts <= hi)]   # offsets < 4 steps
        extra = relaxation_times(starts, self.tau, self.step, t_all[-1])
        extra = extra[(extra >= lo) & (extra < hi)]
        eps = IMPACT_OFFSET_PERIODS * scene.excitation.period
        gap_pre, vel_pre, _ = (sample_elapsed(dynamics, pre - eps) if pre.size
                               else (np.empty(0),) * 3)
        gap_post, vel_post, _ = (sample_elapsed(dynamics, post + eps) if post.size
                                 else (np.empty(0),) * 3)
        gap_extra, vel_extra, _ = (sample_elapsed(dynamics, extra) if extra.size
                                   else (np.empty(0),) * 3)
        grid = np.concatenate([t, pre, post, extra])
        gap = np.concatenate([np.asarray(dynamics.gap[i0:j1], dtype=float), gap_pre, gap_post,
                              gap_extra])
        vel = np.concatenate([np.asarray(dynamics.gap_velocity[i0:j1], dtype=float), vel_pre,
                              vel_post, vel_extra])
        tag = np.concatenate([np.ones(t.size), np.zeros(pre.size), np.full(post.size, 2.0),
                              np.full(extra.size, 3.0)])
        order = np.lexsort((tag, grid))
        grid, gap, vel = grid[order], gap[order], vel[order]
        output_index = np.flatnonzero(order < t.size)
        return grid, self.source.terminal(grid, gap, vel), output_index

    def numbers(self) -> dict:
        """Mean power [W], the energy books [J] over the window, integration points,
        time constant [s]: :func:`load_waveforms`' numbers."""
        t0, s0, t1, s1 = self.window or (0.0, 0.0, 0.0, 0.0)
        length = t1 - t0
        return {"mean_power_W": self.sums["dissipated"] / length if length > 0 else 0.0,
                "delivered_energy_J": self.sums["delivered"],
                "dissipated_energy_J": self.sums["dissipated"],
                "stored_energy_change_J": float(s1 - s0),
                "integration_points": int(self.points), "time_constant_s": self.time_constant}


def streamed_load(dynamics, chunked, reduced) -> tuple[dict, dict]:
    """``(details, data)`` of a load-like run after the loop's last chunk
    (:mod:`tengfield.electrical.loop`): the numbers of ``chunked`` (:class:`LoadChunks`;
    None: Q_SC = 0), the window's peak-to-peak of its columns and the columns of its last
    periods (every row of a whole run: the V-Q loop) from ``reduced``."""
    if chunked is None:                      # Q_SC = 0: nothing moves
        load = {k: v for k, v in no_charge(dynamics).items() if not isinstance(v, np.ndarray)}
    else:
        load = chunked.numbers()
    tail = reduced["tail"]
    data = dict(load, V_load=tail["V_load_V"], I_load=tail["I_load_A"], P_load=tail["P_load_W"],
                peak_to_peak=reduced["column_peak_to_peak"])
    return {"energy_balance_relative_residual": balance_residual(load)}, data


def steady_load(scene, dynamics, curves, *, grid: "LoadGrid | None" = None) -> dict:
    """:func:`load_waveforms` with energies over the :func:`steady_window`. ``grid``: a
    :class:`LoadGrid` of ``dynamics`` kept for a scan over loads (its scene's cells and
    C_p are ``scene``'s), the same numbers sooner."""
    t = elapsed_times(dynamics)
    mask, _ = steady_window(t, scene)
    return _load_waveforms(scene, dynamics, curves, t[mask][0], grid)


def resistive_loop(scene, load: dict, t, period: float) -> tuple[dict, tuple]:
    """The energy-per-cycle numbers of the resistive load ``load`` (a :func:`steady_load`)
    and its V-Q loop over the last period of ``t`` (the run's own axis)."""
    last = last_period(t, period)
    v_load = np.asarray(load["V_load"])[last]
    q_load = cumulative(t[last], np.asarray(load["I_load"])[last])
    loop = (q_load, v_load, loop_area(v_load, q_load))
    return {"load_ohm": scene.circuit.load, "load_loop_area_J": loop[2],
            "load_mean_power_times_period_J": load["mean_power_W"] * period}, loop


def load_block(scene, load: dict, waveforms, mask, **extra) -> dict:
    """summary.json's ``load`` block of a load run (``waveforms``: with the
    ``LOAD_COLUMNS``; ``mask``: the steady window over its ``time_s``; ``load``'s
    ``peak_to_peak``, if given, the V_load and I_load ones over that window)."""
    t = waveforms["time_s"]
    pp = load.get("peak_to_peak")          # a streamed run's, taken while it streamed
    v_pp, i_pp = (pp["V_load_V"], pp["I_load_A"]) if pp is not None else (
        lumped.peak_to_peak(waveforms["V_load_V"][mask]),
        lumped.peak_to_peak(waveforms["I_load_A"][mask]))
    return load_block_of(scene, load, v_pp, i_pp, float(t[mask][0] - t[0]), **extra)


def load_block_of(scene, load: dict, v_pp: float, i_pp: float, settle_time: float,
                  **extra) -> dict:
    """:func:`load_block` from its numbers: V_load and I_load peak-to-peak over the window
    [V], [A], ``settle_time`` [s] from the start to the window (the streamed stage)."""
    volume = scene.device.cell_volume * scene.device.cells
    power = load["mean_power_W"]
    return {
        "mean_power_W": power,
        "device_volume_m3": volume,
        "power_density_W_per_m3": power / volume,
        "V_load_peak_to_peak_V": v_pp,
        "I_load_peak_to_peak_A": i_pp,
        "energy_balance_J": {k: load[k] for k in ("delivered_energy_J", "dissipated_energy_J",
                                                  "stored_energy_change_J")},
        "integration_points": load["integration_points"],
        "time_constant_s": load["time_constant_s"],
        "settled": bool(5.0 * load["time_constant_s"] <= settle_time),
        "settled_rule": "5 R (C_T + C_p) <= settle time before the window; otherwise the "
                        "window still holds the load's start-up transient (longer run or "
                        "more settle_periods)",
        **extra,
    }


def balance_residual(load: dict) -> float:
    """|delivered - dissipated - stored change| / |delivered| of a load run."""
    delivered = load["delivered_energy_J"]
    residual = delivered - load["dissipated_energy_J"] - load["stored_energy_change_J"]
    return abs(residual) / max(abs(delivered), 1e-300)


class Load(Circuit):
    name = "load"
    columns = tuple(LOAD_COLUMNS)
    keys = ("load_ohm",)
    read_column = "V_load_V"     # the instrument reads the load's R || C_p
    has_load = True
    fit_load = True
    fit_columns = {"V": ("V_load_V", "V"), "Q": ("Q_sc_C", "C"), "I": ("I_load_A", "A")}

    def summary(self, scene, run, waveforms, mask) -> dict:
        return {"load": load_block(scene, run.data, waveforms, mask)}

    def cycle(self, scene, source, run, t, mask, max_gap) -> dict:
        numbers, loop = resistive_loop(scene, run.data, t, scene.excitation.period)
        return {"energy_per_cycle": numbers, "_vq": {"load": loop}}

    def start(self, scene, source, window_start, chunk_rows):
        return LoadChunks(scene, source, window_start, chunk_rows) if source.charged else None

    def finish(self, scene, source, state, record, note) -> CircuitRun:
        details, data = streamed_load(source.dynamics, state, record)
        return CircuitRun({}, f"load ODE, R = {scene.circuit.load:g} ohm{note}", details,
                          data=data)

    def array_identical(self, scaled, dynamics, curves, waves) -> dict:
        if curves is None:
            return super().array_identical(scaled, dynamics, curves, waves)
        load = steady_load(scaled, dynamics, curves)
        waves.update({"V_load_V": load["V_load"], "I_load_A": load["I_load"],
                      "P_load_W": load["P_load"]})
        return dict(value=load["mean_power_W"], reference_value=load["mean_power_W"],
                    compared="mean load power [W]", output=load["P_load"],
                    reference=load["P_load"], label="P_load [W]", load=load)

    def spread(self, scene, t, weights, origin):
        return _SpreadLoad(scene, t, weights)


class _SpreadLoad(SpreadCircuit):
    """The cells' terminals in parallel into one R, on the output samples."""

    def finish(self, sums, ref, columns, mask) -> dict:
        t = self.t
        load = self.scene.circuit.load
        c_p = self.scene.circuit.parallel_capacitance
        resp = lumped.load_response(t, sums["Q"], sums["I"], sums["C"], load, c_p)
        ref_resp = lumped.load_response(t, ref["Q"], ref["I"], ref["C"], load, c_p)
        columns.update({"V_load_V": resp.voltage, "I_load_A": resp.current,
                        "P_load_W": resp.power})
        length = t[mask][-1] - t[mask][0]
        power = float(trapezoid(resp.power[mask], t[mask]) / length)
        ref_power = float(trapezoid(ref_resp.power[mask], t[mask]) / length)
        return dict(value=power, reference_value=ref_power, compared="mean load power [W]",
                    output=resp.power, reference=ref_resp.power, label="P_load [W]",
                    load={"mean_power_W": power, "V_load": resp.voltage, "I_load": resp.current},
                    summary={"mean_load_power_W": power})


CIRCUIT = Load()
