"""``[circuit] kind = "open"`` and ``"short"``: the terminal's closed forms.

V_OC = Q_SC / (C_T + C_p) (what an instrument of capacitance C_p reads), Q_SC and
I_SC come from :mod:`tengfield.electrical.waveforms` for every kind; these two add
no columns and integrate nothing (:class:`~tengfield.electrical.circuits.Circuit`'s
defaults)."""
from __future__ import annotations

from . import Circuit


class Open(Circuit):
    name = "open"


class Short(Circuit):
    name = "short"


CIRCUITS = (Open(), Short())
