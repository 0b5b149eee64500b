"""The contact-charged ball off the axis (``[contact] model = "3d"``, issue #52).

The bookkeeping of :mod:`tengfield.source.terminal` holds at every ball position, on the
axis or off it: the field is linear in the ball's charge q and in the electrodes' total
charge, so with the (z, r) curves of the tables (per unit ball charge) at the reference
charge q_ref (1 C, as on the axis),

    Q_SC(t) = (q/q_ref) Q_ref(z, r) + (q − q0) b(0, 0) − k(z, r) L(t) + U(t),

b(0, 0) the upper electrode's short-circuit charge per unit ball charge in the reference
state (the ball on the lower plate, on the axis), k(z, r) the share of a charge put on the
electrodes that the upper one takes (:meth:`tengfield.terminals.FloatingPair.upper_share`)
and L, U what the ball has lost to the air and taken from the upper electrode. The
currents follow with ż and ṙ. k(z, r) is the (z, r) table's, anchored to the axis table
as the curves are (:class:`tengfield.surrogate.table.AnchoredTerminalCurves`):
k_axis(z) + k_zr(z, r) − k_zr(z, 0).

Only the impacts on the electrodes charge the ball (:func:`tengfield.source.contacts.
contacts_of`: the 3D model's impacts are its plate contacts); the tube wall's and the
shell's insulating band's contacts are left out (an assumption, docs/charge.md).
"""
from __future__ import annotations

import numpy as np

from .. import terminals
from ..surrogate.table import AnchoredTerminalCurves, OffAxisCurves, RadialTerminalCurves
from .terminal import ContactCurves, ContactTerminal


class _RadialShare(RadialTerminalCurves):
    """k(z, r) of a (z, r) table through the interpolation of its terminal curves (the
    same splines in (z, s = u²), clipping and chain rule): :meth:`charge` is k and
    :meth:`charge_derivative` its gradient (dk/dz [1/m], dk/dr [1/m]); one spline, no
    capacitance methods."""

    def __init__(self, table, reference: str):
        self._axes(table, reference)
        self._q = self._spline(np.asarray(terminals.wiring(
            reference, table.electrodes).contact_share(table.capacitance), dtype=float))


class OffAxisContactTerminal(ContactTerminal):
    """:class:`ContactTerminal` with the ball off the axis: its (z, r) curves at the
    reference charge q_ref are :class:`AnchoredTerminalCurves` (the axis ``table``'s
    curves plus the (z, r) ``radial_table``'s change with r, as a run's)."""

    def __init__(self, table, radial_table, history, upper, reference: str = "floating"):
        super().__init__(table, history, upper, reference)
        self.offaxis = AnchoredTerminalCurves(
            RadialTerminalCurves(radial_table, reference, self.q_ref), self.curves)
        self._share_zr = _RadialShare(radial_table, reference)

    def share(self, z, r) -> tuple:
        """``(k, dk/dz [1/m], dk/dr [1/m])`` at gaps ``z`` and offsets ``r`` [m]."""
        on_axis = self._k(z)
        k = on_axis + self._share_zr.charge(z, r) - self._share_zr.charge(z, 0.0)
        d_z, d_r = self._share_zr.charge_derivative(z, r)
        d_z = self._dk(z) + d_z - self._share_zr.charge_derivative(z, 0.0)[0]
        return k, d_z, d_r

    def evaluate(self, t, z, z_rate, r=None, r_rate=None, cells: int = 1) -> tuple:
        """``(Q_SC [C], I_SC [A], C_T [F], dC_T/dt [F/s])`` of ``cells`` cells at times
        ``t`` [s], gaps ``z`` [m], offsets ``r`` [m] and their rates [m/s] (r None: on
        the axis; r_rate None: 0)."""
        t = np.asarray(t, dtype=float)
        z = np.clip(np.asarray(z, dtype=float), 0.0, self.curves.stroke)
        r = np.zeros_like(z) if r is None else np.asarray(r, dtype=float)
        z_rate = np.asarray(z_rate, dtype=float)
        r_rate = np.zeros_like(z) if r_rate is None else np.asarray(r_rate, dtype=float)
        q, lost, scale = self.charge_state(t)
        q_ref_curve = self.offaxis.charge(z, r)
        dq_dz, dq_dr = self.offaxis.charge_derivative(z, r)
        k, dk_dz, dk_dr = self.share(z, r)
        q_sc = self.short_circuit_charge(t, q, lost, scale, q_ref_curve, k)
        i_sc = scale * (dq_dz * z_rate + dq_dr * r_rate) \
            - lost * (dk_dz * z_rate + dk_dr * r_rate) \
            + self.leakage_current(q, q_ref_curve, k)
        c_t = self.offaxis.capacitance(z, r)
        dc_dz, dc_dr = self.offaxis.capacitance_derivative(z, r)
        return q_sc * cells, i_sc * cells, c_t * cells, (dc_dz * z_rate + dc_dr * r_rate) * cells


class OffAxisContactCurves(OffAxisCurves):
    """The (z, r) counterpart of :class:`~tengfield.source.terminal.ContactCurves`: its
    functions of (z, r) alone (figures) are the run's (z, r) curves at the ``steady``
    charge [C]; the time-resolved terminal quantities come from :meth:`evaluate_many`
    with ``times``, which follows the charge history."""
    contact = True

    def __init__(self, terminal: OffAxisContactTerminal, steady: float):
        self.terminal = terminal
        base = terminal.offaxis
        self._base = base
        self.reference, self.stroke = base.reference, base.stroke
        self.max_offset = base.max_offset
        self.positions, self.offsets = base.positions, base.offsets
        self.axis = ContactCurves(terminal, steady)   # on the axis at the steady charge too
        self.ball_charge = float(steady)
        self.factor = steady / terminal.q_ref
        self.charge_grid = base.charge_grid * self.factor
        self.capacitance_grid = base.capacitance_grid
        self.charge_samples = self.charge_grid.ravel()
        self.capacitance_samples = self.capacitance_grid.ravel()

    def charge(self, z, r):
        return self._base.charge(z, r) * self.factor

    def charge_derivative(self, z, r):
        d_z, d_r = self._base.charge_derivative(z, r)
        return d_z * self.factor, d_r * self.factor

    def capacitance(self, z, r):
        return self._base.capacitance(z, r)

    def capacitance_derivative(self, z, r):
        return self._base.capacitance_derivative(z, r)

    def charge_at(self, times, z, r=None):
        """Q_SC [C] of one cell at the run's ``times`` [s], gaps ``z`` and offsets ``r`` [m]."""
        z = np.asarray(z, dtype=float)
        return self.terminal.evaluate(times, z, np.zeros_like(z), r)[0]

    def evaluate_many(self, z, z_rate, r=None, r_rate=None, *, cells: int = 1,
                      times=None) -> tuple:
        if times is None:
            raise TypeError("OffAxisContactCurves.evaluate_many needs the times of the "
                            "samples (the charge changes contact by contact)")
        return self.terminal.evaluate(times, z, z_rate, r, r_rate, cells)
