"""The terminal quantities of a ball whose charge changes contact by contact (issue #52).

The field is linear in the ball's charge q and in the electrode pair's total charge Q_e,
so one surrogate table, per unit ball charge, gives every charge state (docs/charge.md,
"Conservation"); its curves are taken at the reference charge q_ref = 1 C
(:data:`~tengfield.surrogate.table.UNIT_CHARGE`: Q_ref per unit ball charge):

* the upper electrode's short-circuit charge is Q_u0(z; q, Q_e) = q b(z) + k(z)(Q_e + q),
  with b(z) = Q_u0(z; q_ref, -q_ref)/q_ref (today's curve per unit charge) and k(z) the
  share of a charge put on the floating pair that the upper electrode takes,
  k = c_u/(c_l + c_u) (c_l = C_ll + C_lu, c_u = C_lu + C_uu); with the lower electrode
  grounded k = 0 (the ground supplies it);
* the contacts: the ball's gain at a contact comes from the electrode it touches, not
  through the wire; what the ball loses to the air (leakage, breakdown) leaves Q_e
  unchanged. With L(t) = q0 + D(t) - q(t) the charge lost to the air (D: the sum of the
  contacts' gains) and U(t) the sum of the gains taken from the upper electrode, the
  charge the wire has carried from the lower to the upper electrode since the reference
  state (ball at rest on the lower electrode with q0, Q_e = -q0) is

      Q_SC(t) = (q(t)/q_ref) Q_ref(z) + (q(t) - q0) b(0) - k(z) L(t) + U(t),

  Q_ref(z) = q_ref (b(z) - b(0)) the constant-charge curve of the table at q_ref.

With q = q0 = q_ref and nothing lost this is the constant model's Q_SC(z) exactly; C_T(z)
does not depend on the charge. Between contacts
I_SC = (q/q_ref) Q_ref'(z) z' - L k'(z) z' + q' (b(z) + k(z)), q' = -q/tau (leakage);
the jump of Q_SC at a contact (one contact's gain times b + k at the ball, or the gain
itself at the upper electrode) is a charge moved in an instant, seen in Q_SC and in the
circuits' response, not as a finite I_SC sample.

The single-electrode cell (one electrode, the terminals the electrode and the ground): the
electrode shorted (at 0 V) holds q f_l(z) (f_l its induced fraction), and every contact
gain is drawn from it (the bare upper plate charges nothing), so the charge the wire has
carried from the electrode to the ground is

    Q_SC(t) = (q(t)/q_ref) Q_ref(z) + (q(t) - q0) b(0) - D(t),   b(0) = -f_l(0),

and between contacts I_SC = (q/q_ref) Q_ref'(z) z' + q' (Q_ref(z)/q_ref + b(0)).
"""
from __future__ import annotations

import numpy as np

from .. import lumped, terminals
from ..surrogate.table import UNIT_CHARGE, OnAxisCurves, TerminalCurves


class ContactTerminal:
    """The contact-charged ball's terminal quantities over time, for one cell on the axis.

    ``table``: the surrogate table (per unit ball charge: its curves at q_ref = 1 C,
    :data:`~tengfield.surrogate.table.UNIT_CHARGE`); ``history``: the ball's
    :class:`~tengfield.source.charge.ChargeHistory` on the run's own time axis (seconds after its start); ``upper``: a boolean per contact of
    the history, true where the ball touched the upper electrode; ``reference``: the
    terminal topology ("floating" or "grounded-lower")."""

    def __init__(self, table, history, upper, reference: str = "floating"):
        from scipy.interpolate import CubicSpline

        self.reference = reference
        self.q_ref = UNIT_CHARGE
        self.curves = TerminalCurves(table, reference, self.q_ref)
        self.history = history
        C, f = table.capacitance, table.induced_fraction
        #: the terminal topology: its ``contact_transfer`` says what the contacts send
        #: through the wire (the pair: U − k L; the single electrode: −D)
        self.wiring = terminals.wiring(reference, f.shape[1])
        self.b0 = float(self.wiring.terminal_charge(C[0], f[0], 1.0))   # per unit charge
        share = self.wiring.contact_share(C)
        kind = "not-a-knot" if table.positions.size >= 4 else "natural"
        self._k = CubicSpline(table.positions, share, bc_type=kind)
        self._dk = self._k.derivative()
        gains = history.gains
        upper = np.asarray(upper, dtype=bool)
        if upper.shape != gains.shape:
            raise ValueError(f"upper: one flag per contact ({gains.shape}), got {upper.shape}")
        self._gained = np.cumsum(gains)                 # D after contact n
        self._upper_gained = np.cumsum(np.where(upper, gains, 0.0))   # U after contact n

    def _counted(self, cumulative, t):
        i = np.searchsorted(self.history.times, t, side="right") - 1
        return np.where(i >= 0, cumulative[np.maximum(i, 0)] if cumulative.size else 0.0, 0.0)

    def ball_charge(self, t):
        """q(t) [C] at the run's times ``t`` [s] (after a contact at that instant)."""
        return self.history.at(t)

    def lost_to_air(self, t):
        """L(t) [C]: what the ball has lost to the air (leakage, breakdown) by ``t``."""
        return self.history.start + self._counted(self._gained, t) - self.history.at(t)

    def upper_gains(self, t):
        """U(t) [C]: the charge the ball has taken from the upper electrode by ``t``."""
        return self._counted(self._upper_gained, t)

    def charge_state(self, t) -> tuple:
        """``(q, L, q/q_ref)`` at the run's times ``t`` [s]: the ball's charge [C], what it
        has lost to the air [C], and the scale of the table's curves."""
        q = self.ball_charge(t)
        return q, self.lost_to_air(t), q / self.q_ref

    def short_circuit_charge(self, t, q, lost, scale, q_ref_curve, k):
        """Q_SC [C] at times ``t`` from the :meth:`charge_state` and the table's curve
        Q_ref and share k at the ball (module docstring: the pair, the single electrode;
        the topology's ``contact_transfer``)."""
        return scale * q_ref_curve + (q - self.history.start) * self.b0 \
            + self.wiring.contact_transfer(lost, self.upper_gains(t),
                                           self._counted(self._gained, t), k)

    def leakage_current(self, q, q_ref_curve, k):
        """The part of I_SC [A] the ball's leakage drives, q' (Q_ref/q_ref + b(0) + k)."""
        tau = self.history.leakage_time
        q_rate = -q / tau if tau > 0.0 else np.zeros_like(q)
        return q_rate * (q_ref_curve / self.q_ref + self.b0 + k)

    def evaluate(self, t, z, z_rate, cells: int = 1) -> tuple:
        """``(Q_SC [C], I_SC [A], C_T [F], dC_T/dt [F/s])`` of ``cells`` cells in parallel
        at times ``t`` [s] (the run's axis), gaps ``z`` [m] and rates ``z_rate`` [m/s]."""
        t = np.asarray(t, dtype=float)
        z = np.asarray(z, dtype=float)
        z_rate = np.asarray(z_rate, dtype=float)
        zc = np.clip(z, 0.0, self.curves.stroke)
        q, lost, scale = self.charge_state(t)
        q_ref_curve = self.curves.charge(zc)
        k, dk = self._k(zc), self._dk(zc)
        q_sc = self.short_circuit_charge(t, q, lost, scale, q_ref_curve, k)
        dq_dt_z = scale * self.curves.charge_derivative(zc) - lost * dk
        i_sc = lumped.short_circuit_current(dq_dt_z, z_rate) \
            + self.leakage_current(q, q_ref_curve, k)
        c_t = self.curves.capacitance(zc)
        dc = self.curves.capacitance_derivative(zc) * z_rate
        return q_sc * cells, i_sc * cells, c_t * cells, dc * cells


class ContactCurves(OnAxisCurves):
    """The :class:`~tengfield.surrogate.Curves` a run with ``[charge] model = "contact"``
    hands to the electrical stage: its functions of z alone (the figures, the CMEO bound)
    are the constant-charge curves at the ``steady`` charge [C]; the time-resolved
    terminal quantities come from :meth:`evaluate_many` with ``times`` (every electrical
    path passes them, :func:`tengfield.electrical.terminal_waveforms`), which follows the
    charge history (:class:`ContactTerminal`)."""
    contact = True

    def __init__(self, terminal: ContactTerminal, steady: float):
        self.terminal = terminal
        base = terminal.curves
        self.reference, self.stroke = base.reference, base.stroke
        self.positions = base.positions
        self.ball_charge = float(steady)
        self.factor = steady / terminal.q_ref
        self.charge_samples = base.charge_samples * self.factor
        self.capacitance_samples = base.capacitance_samples
        self._base = base

    def charge(self, z):
        return self._base.charge(z) * self.factor

    def charge_derivative(self, z):
        return self._base.charge_derivative(z) * self.factor

    def capacitance(self, z):
        return self._base.capacitance(z)

    def capacitance_derivative(self, z):
        return self._base.capacitance_derivative(z)

    def charge_at(self, times, z):
        """Q_SC [C] of one cell at the run's ``times`` [s] and gaps ``z`` [m]."""
        z = np.asarray(z, dtype=float)
        return self.terminal.evaluate(times, z, np.zeros_like(z))[0]

    def evaluate_many(self, z, z_rate, r=None, r_rate=None, *, cells: int = 1,
                      times=None) -> tuple:
        if times is None:
            raise TypeError("ContactCurves.evaluate_many needs the times of the samples "
                            "(the charge changes contact by contact)")
        return self.terminal.evaluate(times, z, z_rate, cells=cells)
