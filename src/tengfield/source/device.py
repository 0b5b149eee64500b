"""The device as a two-terminal source along one run (issue #51, DESIGN §7).

A :class:`Source` is built from the run's trajectory (a dynamics result, or none for a
model sampled elsewhere), the surrogate curves of one cell (which carry the ball's charge
history, :class:`~tengfield.source.terminal.ContactCurves`, and the terminal topology,
:mod:`tengfield.terminals`), the number of identical cells wired in parallel and the
capacitance C_p an instrument puts across the terminals. It is the one place that turns
the ball's motion into the terminal quantities; every consumer (the whole and the
streamed electrical stage, the loads' and the rectifier's integration grids, the peaks
at the impacts, SPICE, fit, arrays) asks it:

* :meth:`Source.terminal`: V_OC, V_read, Q_SC, I_SC = dQ_SC/dt, C_T, dC_T/dt at given
  times and trajectory states (the impacts' pre- and post-impact states, a load's
  relaxation points);
* :meth:`Source.rows` / :meth:`Source.chunks`: the same at the run's output samples, a
  span of rows at a time (memory bounded by the chunk; the values are those of the whole
  record, bit for bit: every quantity is pointwise in time);
* :meth:`Source.state`: ``(Q_SC, C_T)`` of all the cells at given times (what a circuit
  that integrates its own state needs, the rectifier's).

Units SI; times on the run's own axis (seconds after ``[initial] time_s``); signs those of
:mod:`tengfield.terminals` (V = V_lower - V_upper, charges and currents counted lower ->
upper through the external circuit, reference state z = 0). Without curves (no field:
nothing charged) Q_SC = I_SC = 0 and C_T is unknown (NaN).
"""
from __future__ import annotations

import numpy as np

from .. import lumped

#: the keys of :meth:`Source.terminal` (SI: V, V, C, A, F, F/s)
QUANTITIES = ("V_oc", "V_read", "Q_sc", "I_sc", "C_T", "dC_T_dt")


def terminal_quantities(curves, gap, gap_velocity, *, cells: int = 1,
                        parallel_capacitance: float = 0.0, radial=None,
                        radial_velocity=None, times=None) -> dict[str, np.ndarray]:
    """The terminal quantities (:data:`QUANTITIES`) of ``cells`` identical cells in
    parallel, read through ``parallel_capacitance`` C_p [F], along samples of a
    trajectory: ``gap`` z [m], ``gap_velocity`` dz/dt [m/s]; for (z, r) curves
    ``radial`` r [m] and ``radial_velocity`` dr/dt [m/s] (default 0); ``times`` [s] on
    the run's axis where the ball's charge follows its contacts (``curves.contact``).

    V_oc = Q_SC / C_T (the ideal open-circuit voltage, whatever C_p); V_read =
    Q_SC / (C_T + C_p) (what an instrument of capacitance C_p reads; V_oc itself when
    C_p = 0); I_sc = dQ_SC/dz ż (+ dQ_SC/dr ṙ). ``curves`` None: nothing charged."""
    gap = np.asarray(gap, dtype=float)
    if curves is None:
        zero = np.zeros_like(gap)
        return {"V_oc": zero, "V_read": zero.copy(), "Q_sc": zero.copy(), "I_sc": zero.copy(),
                "C_T": np.full_like(gap, np.nan), "dC_T_dt": zero.copy()}
    if getattr(curves, "contact", False):   # the charge follows the contacts: q(t)
        q_sc, i_sc, c_t, dc_dt = curves.evaluate_many(gap, gap_velocity, radial,
                                                      radial_velocity, cells=cells,
                                                      times=times)
    else:
        q_sc, i_sc, c_t, dc_dt = curves.evaluate_many(gap, gap_velocity, radial,
                                                      radial_velocity, cells=cells)
    v_oc = lumped.open_circuit_voltage(q_sc, c_t)
    v_read = v_oc if parallel_capacitance == 0.0 else \
        lumped.open_circuit_voltage(q_sc, c_t, parallel_capacitance)
    return {"V_oc": v_oc, "V_read": v_read,
            "Q_sc": q_sc, "I_sc": i_sc, "C_T": c_t, "dC_T_dt": dc_dt}


def _time_origin(dynamics) -> float:
    return float(getattr(dynamics, "time_origin", 0.0) or 0.0)


class Source:
    """The device as a two-terminal source along one run (module docstring).

    ``curves``: the :class:`~tengfield.surrogate.Curves` of ONE cell (None: nothing
    charged); ``dynamics``: the run's trajectory (a dynamics result: ``t``, ``gap``,
    ``gap_velocity``, maybe ``elapsed``, ``time_origin`` and the 3D motion's ``x``,
    ``y``, ``sample3d``), needed by :meth:`rows`, :meth:`chunks` and by (z, r) curves;
    ``cells`` identical cells in parallel; ``parallel_capacitance`` C_p [F]."""

    def __init__(self, curves, dynamics=None, *, cells: int = 1,
                 parallel_capacitance: float = 0.0):
        self.curves, self.dynamics = curves, dynamics
        self.cells = int(cells)
        self.parallel_capacitance = float(parallel_capacitance)
        self._radial_rows = None

    @classmethod
    def of_scene(cls, scene, curves, dynamics=None) -> "Source":
        """The source of ``scene``'s device (``[device] cells``, ``[circuit]
        parallel_capacitance_pF``) with ``curves`` along ``dynamics``."""
        return cls(curves, dynamics, cells=scene.device.cells,
                   parallel_capacitance=scene.circuit.parallel_capacitance)

    # -- what the source is ----------------------------------------------------
    @property
    def charged(self) -> bool:
        """Whether the ball moves any charge (False without curves: Q_SC = 0)."""
        return self.curves is not None

    @property
    def radial(self) -> bool:
        """Whether the terminal depends on the ball's offset r from the axis too."""
        return self.curves is not None and bool(self.curves.radial)

    @property
    def contact(self) -> bool:
        """Whether the ball's charge follows its contacts (it depends on the time)."""
        return bool(getattr(self.curves, "contact", False))

    def ball_charge(self, times):
        """The ball's charge q(t) [C] at ``times`` [s] on the run's axis, for a ball
        charged by its contacts (the history's; None for a constant charge)."""
        if not self.contact:
            return None
        return self.curves.terminal.ball_charge(np.asarray(times, dtype=float))

    # -- the terminal ------------------------------------------------------------
    def terminal(self, times, gap, gap_velocity, radial=None,
                 radial_velocity=None) -> dict[str, np.ndarray]:
        """:data:`QUANTITIES` at ``times`` [s] (the run's axis) where the ball is at
        ``gap`` [m] moving at ``gap_velocity`` [m/s]. For (z, r) curves the offset r and
        dr/dt are the trajectory's at ``times`` unless given."""
        if self.radial and radial is None and self.dynamics is not None:
            from ..surrogate.offaxis import radial_motion
            radial, radial_velocity = radial_motion(
                self.dynamics, _time_origin(self.dynamics) + np.asarray(times, dtype=float))
        return terminal_quantities(self.curves, gap, gap_velocity, cells=self.cells,
                                   parallel_capacitance=self.parallel_capacitance,
                                   radial=radial, radial_velocity=radial_velocity,
                                   times=times)

    def each_cell(self, times, gap, gap_velocity) -> tuple[np.ndarray, ...]:
        """``(Q_SC [C], C_T [F], I_SC [A])`` of ONE cell at each column of ``gap`` [m] and
        ``gap_velocity`` [m/s] ((rows, k) arrays: k cells with their own motion, an
        ``[array]``'s) at ``times`` [s] (rows, the run's axis). A constant charge on the
        axis: the surrogate's cubic splines (``curves.pieces()``) in one compiled pass over
        every cell, the same splines as :meth:`terminal`; a ball charged by its contacts:
        its history's curves, column by column."""
        gap = np.asarray(gap, dtype=float)
        gap_velocity = np.asarray(gap_velocity, dtype=float)
        if self.contact:
            q, c, i = np.empty_like(gap), np.empty_like(gap), np.empty_like(gap)
            for j in range(gap.shape[1]):
                one = terminal_quantities(self.curves, gap[:, j], gap_velocity[:, j],
                                          times=times)
                q[:, j], c[:, j], i[:, j] = one["Q_sc"], one["C_T"], one["I_sc"]
            return q, c, i
        from ._kernel import spline_terminal
        q, c, i = spline_terminal(gap.reshape(-1), gap_velocity.reshape(-1),
                                  *self.curves.pieces(), self.curves.stroke)
        return q.reshape(gap.shape), c.reshape(gap.shape), i.reshape(gap.shape)

    def state(self, times, gap) -> tuple[np.ndarray, np.ndarray]:
        """``(Q_SC [C], C_T [F])`` of all the cells at ``times`` [s] (the run's axis) and
        gaps ``gap`` [m]: at the ball's offset r(t) for (z, r) curves, with the charge
        history's charge for a ball charged by its contacts."""
        curves, gap = self.curves, np.asarray(gap, dtype=float)
        if curves is None:
            return np.zeros_like(gap), np.full_like(gap, np.nan)
        offset = ()
        if curves.radial:
            from ..surrogate.offaxis import radial_motion
            offset = (radial_motion(self.dynamics, _time_origin(self.dynamics)
                                    + np.asarray(times, dtype=float))[0],)
        if self.contact:
            charge = curves.charge_at(times, gap, *offset)
        else:
            charge = curves.charge(gap, *offset)
        return charge * self.cells, curves.capacitance(gap, *offset) * self.cells

    # -- the run's output samples --------------------------------------------------
    @property
    def samples(self) -> int:
        """The number of the run's output samples."""
        return len(self.dynamics.t)

    def elapsed(self, i0: int = 0, i1: int | None = None) -> np.ndarray:
        """The output times of rows ``i0:i1`` on the run's own axis [s] (exact: the
        dynamics' ``elapsed`` where it has one)."""
        dyn = self.dynamics
        elapsed = getattr(dyn, "elapsed", None)
        if elapsed is not None:
            return np.asarray(elapsed[i0:i1], dtype=float)
        return np.asarray(dyn.t[i0:i1], dtype=float) - _time_origin(dyn)

    def _radial_at_rows(self, i0, i1):
        if not self.radial:
            return None, None
        if self._radial_rows is None:       # the 3D motion's own samples, once
            from ..surrogate.offaxis import radial_motion
            self._radial_rows = radial_motion(self.dynamics)
        r, rate = self._radial_rows
        return r[i0:i1], rate[i0:i1]

    def rows(self, i0: int = 0, i1: int | None = None) -> dict[str, np.ndarray]:
        """:data:`QUANTITIES` at the output rows ``i0:i1`` (all by default), with the
        rows' ``gap`` [m] and ``gap_velocity`` [m/s]."""
        dyn = self.dynamics
        gap = np.asarray(dyn.gap[i0:i1], dtype=float)
        velocity = np.asarray(dyn.gap_velocity[i0:i1], dtype=float)
        radial, radial_velocity = self._radial_at_rows(i0, i1)
        out = terminal_quantities(self.curves, gap, velocity, cells=self.cells,
                                  parallel_capacitance=self.parallel_capacitance,
                                  radial=radial, radial_velocity=radial_velocity,
                                  times=self.elapsed(i0, i1))
        out["gap"], out["gap_velocity"] = gap, velocity
        return out

    def chunks(self, size: int):
        """Yield ``(i0, i1, rows)`` for consecutive spans of ``size`` output rows
        (:meth:`rows`), in order."""
        n = self.samples
        for i0 in range(0, n, int(size)):
            i1 = min(i0 + int(size), n)
            yield i0, i1, self.rows(i0, i1)
