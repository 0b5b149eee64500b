"""``[circuit] kind = "open"`` and ``"short"``: the terminal's closed forms.

V_OC = Q_SC / (C_T + C_p) (what an instrument of capacitance C_p reads), Q_SC and
I_SC come from :mod:`tengfield.electrical.waveforms` for every kind; these two add
no columns and integrate nothing (:class:`~tengfield.electrical.circuits.Circuit`'s
defaults)."""
from __future__ import annotations

from . import Circuit


class Open(Circuit):
    name = "open"
    breakdown_states = ("open",)

    def states(self, scene) -> tuple[str, ...]:
        """Read through an instrument (``parallel_capacitance_pF`` > 0) the open circuit
        moves charge between 0 and Q_SC through it: open and short circuit bound it."""
        return ("open", "short") if scene.circuit.parallel_capacitance > 0.0 \
            else self.breakdown_states


class Short(Circuit):
    name = "short"
    breakdown_states = ("short",)


CIRCUITS = (Open(), Short())
