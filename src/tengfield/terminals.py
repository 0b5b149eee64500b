"""Two-terminal reduction of the electrode system (pure functions, SI).

Conventions (used everywhere in tengfield):

* ``C_ll, C_lu, C_uu`` [F]: Maxwell capacitance matrix of the lower/upper
  electrodes (``C_ll, C_uu > 0 > C_lu``); ``q_l, q_u`` [C]: charges induced
  on the electrodes by the ball with both electrodes grounded. Electrode
  charges are ``Q = C V + q``.
* Terminal voltage ``V = V_lower - V_upper`` [V]; ``Q_t`` [C] is the charge
  moved through the external circuit from the lower to the upper electrode
  since the reference state. Then ``V = V_OC(z) - Q_t / C_T(z)``.
* ``Q_SC(z) = Q_u0(z) - Q_u0(z_ref)``: charge that flows lower -> upper
  through a short circuit when the ball moves from the reference position
  (z_ref = 0, ball on the lower electrode) to z; ``V_OC = Q_SC / C_T``.
  A negatively charged ball (PTFE) rising gives ``Q_SC > 0, V_OC > 0``
  (current flows upward through the external circuit, as in the paper).
* ``reference = "floating"``: the electrode pair floats, total electrode
  charge fixed at ``-q_ball``; ``reference = "grounded-lower"``: the lower
  electrode is grounded (the paper's COMSOL set-up), ``C_T = C_uu``.
"""
from __future__ import annotations

import numpy as np

from .lumped import open_circuit_voltage  # noqa: F401 - V_OC = Q_SC / (C_T + C_p), one definition

REFERENCES = ("floating", "grounded-lower")


def _check_reference(reference: str) -> None:
    if reference not in REFERENCES:
        raise ValueError(f"reference = {reference!r} is not allowed: choose one of "
                         + ", ".join(repr(r) for r in REFERENCES))


def terminal_capacitance(C_ll, C_lu, C_uu, reference: str = "floating"):
    """C_T [F] seen between the two terminals."""
    _check_reference(reference)
    C_ll, C_lu, C_uu = (np.asarray(x, dtype=float) for x in (C_ll, C_lu, C_uu))
    if reference == "grounded-lower":
        return C_uu
    c_l = C_ll + C_lu
    c_u = C_lu + C_uu
    return -C_lu + c_l * c_u / (c_l + c_u)


def upper_short_circuit_charge(C_ll, C_lu, C_uu, q_l, q_u, ball_charge,
                               reference: str = "floating"):
    """Q_u0(z) [C]: upper-electrode charge with the terminals shorted (V = 0)."""
    _check_reference(reference)
    C_ll, C_lu, C_uu, q_l, q_u = (np.asarray(x, dtype=float) for x in (C_ll, C_lu, C_uu, q_l, q_u))
    if reference == "grounded-lower":
        return q_u
    c_l = C_ll + C_lu
    c_u = C_lu + C_uu
    total = -ball_charge  # electrode charge fixed by the reference state
    return q_u + c_u * (total - q_l - q_u) / (c_l + c_u)
