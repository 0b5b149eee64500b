"""Terminal topologies: how the electrodes are wired to the two terminals (pure, SI).

Conventions (used everywhere in tengfield):

* ``C`` [F]: the Maxwell capacitance matrix of the electrodes (lower, upper) to the
  environment (``C_ll, C_uu > 0 > C_lu``); ``q`` [C]: the charges induced on the
  electrodes by the ball with every electrode grounded (``q_k = -q_ball ψ_k``, ψ_k the
  weighting potential of electrode k, Shockley–Ramo). Electrode charges are
  ``Q = C V + q``.
* Terminal voltage ``V = V_lower - V_upper`` [V]; ``Q_t`` [C] is the charge moved
  through the external circuit from the lower to the upper electrode since the
  reference state. Then ``V = V_OC(z) - Q_t / C_T(z)``.
* ``Q_SC(z) = Q_u0(z) - Q_u0(z_ref)``: charge that flows lower -> upper through a short
  circuit when the ball moves from the reference position (z_ref = 0, ball on the lower
  electrode) to z; ``V_OC = Q_SC / C_T``. A negatively charged ball (PTFE) rising gives
  ``Q_SC > 0, V_OC > 0`` (current flows upward through the external circuit, as in the
  paper).

A topology is one entry of :data:`TOPOLOGIES` (``[circuit] reference``), a small object
answering every question the consumers ask of the wiring: the terminal capacitance
C_T, the upper electrode's short-circuit charge Q_u0, the reference state's electrode
charges, the electrode potentials open and shorted, and the share of a charge put on
the electrodes that the upper one takes (the contact charge, :mod:`tengfield.source`).
Today's two:

* ``"floating"``: the electrode pair floats, its total charge fixed at ``-q_ball`` (the
  reference state: a neutral device);
* ``"grounded-lower"``: the lower electrode is grounded (the paper's COMSOL set-up),
  ``C_T = C_uu``.

A new topology is one class here and one entry in :data:`TOPOLOGIES`;
:class:`LowerToGround` is the single-electrode cell's (one electrode, :func:`wiring`).
"""
from __future__ import annotations

import numpy as np

from .lumped import open_circuit_voltage  # noqa: F401 - V_OC = Q_SC / (C_T + C_p), one definition


def _pair(C, q=None):
    C = np.asarray(C, dtype=float)
    return C if q is None else (C, np.asarray(q, dtype=float))


class _Pair:
    """The matrix form of a two-electrode topology (``C`` (..., 2, 2), ``q`` (..., 2))."""
    electrodes = 2

    def terminal_capacitance(self, C):
        """C_T [F] of the matrices ``C``."""
        C = np.asarray(C, dtype=float)
        return self.capacitance(C[..., 0, 0], C[..., 0, 1], C[..., 1, 1])

    def terminal_charge(self, C, q, ball_charge):
        """The charge on the receiving terminal with the terminals shorted [C] (Q_u0):
        Q_SC(z) is its change from the reference state."""
        C, q = np.asarray(C, dtype=float), np.asarray(q, dtype=float)
        return self.upper_short_charge(C[..., 0, 0], C[..., 0, 1], C[..., 1, 1], q[..., 0],
                                       q[..., 1], ball_charge)

    def contact_share(self, C):
        """k of the matrices ``C`` (:meth:`upper_share`): the share of a charge put on the
        shorted electrodes that the receiving terminal takes."""
        C = np.asarray(C, dtype=float)
        return self.upper_share(C[..., 0, 0], C[..., 0, 1], C[..., 1, 1])

    def contact_transfer(self, lost, from_upper, gained, share):
        """What the ball's contacts have sent through the wire [C] (the contact charge,
        :mod:`tengfield.source.terminal`): ``U − k L`` with L = ``lost`` (to the air),
        U = ``from_upper`` (taken from the upper electrode), k = ``share``; ``gained`` (D,
        every contact's gain) is not needed: a gain from the lower electrode moves no
        charge through the wire of the pair."""
        return from_upper - share * lost


class FloatingPair(_Pair):
    """Both electrodes are the terminals and float together: their total charge stays
    at the reference state's ``-q_ball`` (every charge the ball induces comes from the
    pair itself; the environment supplies none)."""
    name = "floating"
    grounded_lower = False

    def capacitance(self, C_ll, C_lu, C_uu):
        """C_T [F]: the mutual capacitance plus the two self-capacitances in series."""
        c_l = C_ll + C_lu
        c_u = C_lu + C_uu
        return -C_lu + c_l * c_u / (c_l + c_u)

    def upper_short_charge(self, C_ll, C_lu, C_uu, q_l, q_u, ball_charge):
        """Q_u0 [C]: the upper electrode's charge with the terminals shorted."""
        c_l = C_ll + C_lu
        c_u = C_lu + C_uu
        total = -ball_charge  # electrode charge fixed by the reference state
        return q_u + c_u * (total - q_l - q_u) / (c_l + c_u)

    def upper_share(self, C_ll, C_lu, C_uu):
        """k: the share of a charge put on the shorted pair that the upper electrode
        takes, ``c_u / (c_l + c_u)`` (c_l = C_ll + C_lu, c_u = C_lu + C_uu)."""
        c_l = C_ll + C_lu
        c_u = C_lu + C_uu
        return c_u / (c_l + c_u)

    def reference_charges(self, C_ref, q_ref, ball_charge: float) -> np.ndarray:
        """[Q_lower, Q_upper] [C] of the reference state (terminals shorted)."""
        C_ref, q_ref = _pair(C_ref, q_ref)
        common = (-ball_charge - q_ref.sum()) / C_ref.sum()   # shorted pair at one potential
        return C_ref @ np.array([common, common]) + q_ref

    def open_potentials(self, C, q, charges) -> np.ndarray:
        """[V_lower, V_upper] [V] holding the electrode ``charges`` (terminals open)."""
        C, q = _pair(C, q)
        return np.linalg.solve(C, np.asarray(charges, dtype=float) - q)

    def short_potentials(self, C, q, ball_charge) -> np.ndarray:
        """[V_lower, V_upper] [V], shape (n, 2), of the shorted pair at each of n
        positions (``C`` (n, 2, 2), ``q`` (n, 2), ``ball_charge`` [C]): one common
        potential that keeps the total charge."""
        C, q = _pair(C, q)
        common = (-ball_charge - q.sum(axis=1)) / C.sum(axis=(1, 2))
        return np.column_stack([common, common])


class GroundedLower(_Pair):
    """The lower electrode is grounded (V_lower = 0) and is one terminal; the upper is
    the other: the ground supplies every charge the lower electrode takes."""
    name = "grounded-lower"
    grounded_lower = True

    def capacitance(self, C_ll, C_lu, C_uu):
        """C_T [F] = C_uu (the lower electrode is held at 0 V)."""
        return C_uu

    def upper_short_charge(self, C_ll, C_lu, C_uu, q_l, q_u, ball_charge):
        """Q_u0 [C] = q_u: with both at 0 V the upper electrode holds its induced charge."""
        return q_u

    def upper_share(self, C_ll, C_lu, C_uu):
        """k = 0: a charge put on the electrodes is supplied by the ground."""
        return np.zeros_like(np.asarray(C_uu, dtype=float))

    def reference_charges(self, C_ref, q_ref, ball_charge: float) -> np.ndarray:
        """[Q_lower, Q_upper] [C] of the reference state: both at 0 V."""
        return np.asarray(q_ref, dtype=float).copy()

    def open_potentials(self, C, q, charges) -> np.ndarray:
        """[0, V_upper] [V]: the upper electrode keeps its reference charge."""
        C, q = _pair(C, q)
        return np.array([0.0, (np.asarray(charges, dtype=float)[1] - q[1]) / C[1, 1]])

    def short_potentials(self, C, q, ball_charge) -> np.ndarray:
        """Both electrodes at 0 V, shape (n, 2)."""
        return np.zeros((np.asarray(q).shape[0], 2))


class LowerToGround:
    """The single-electrode cell (``[device] electrodes = "lower"``, Niu et al. 2014): the
    terminals are the lower electrode and the ground (the environment: the far field or the
    grounded table). ``V = V_lower`` (the ground at 0 V); Q_t is the charge moved from the
    lower electrode to the ground, so a negative ball rising gives Q_SC > 0 as in the pair.
    Matrices of one electrode: ``C`` (..., 1, 1), ``q`` (..., 1)."""
    name = "lower-to-ground"
    electrodes = 1
    grounded_lower = False

    def terminal_capacitance(self, C):
        """C_T [F] = C_ll, the electrode's capacitance to the ground."""
        return np.asarray(C, dtype=float)[..., 0, 0]

    def terminal_charge(self, C, q, ball_charge):
        """The ground's side with the terminals shorted (the electrode at 0 V holds its
        induced charge q_l): −q_l [C]."""
        return -np.asarray(q, dtype=float)[..., 0]

    def contact_share(self, C):
        """k = 0: a charge lost to the air is the ground's business, not the wire's."""
        return np.zeros_like(np.asarray(C, dtype=float)[..., 0, 0])

    def contact_transfer(self, lost, from_upper, gained, share):
        """−D [C]: every contact's gain is drawn from the one electrode (the bare upper
        plate charges nothing), so the wire has carried it back from the ground."""
        return -gained

    def reference_charges(self, C_ref, q_ref, ball_charge: float) -> np.ndarray:
        """[Q_lower] [C] of the reference state: the electrode at 0 V."""
        return np.asarray(q_ref, dtype=float).copy()

    def open_potentials(self, C, q, charges) -> np.ndarray:
        """[V_lower] [V] holding the electrode's reference charge (terminals open)."""
        C, q = _pair(C, q)
        return np.array([(np.asarray(charges, dtype=float)[0] - q[0]) / C[0, 0]])

    def short_potentials(self, C, q, ball_charge) -> np.ndarray:
        """The electrode at 0 V, shape (n, 1)."""
        return np.zeros((np.asarray(q).shape[0], 1))


#: the terminal topologies of the electrode pair by their ``[circuit] reference`` name
TOPOLOGIES = {t.name: t for t in (FloatingPair(), GroundedLower())}
#: their names, in the order the studies loop over them
REFERENCES = tuple(TOPOLOGIES)
#: the single-electrode cell's one topology
SINGLE_ELECTRODE = LowerToGround()


def wiring(reference: str, electrodes: int = 2):
    """The topology of a cell of ``electrodes`` electrodes: the pair's ``reference``
    (:data:`TOPOLOGIES`), or the single electrode's (:data:`SINGLE_ELECTRODE`, whatever
    the reference: it has one)."""
    if electrodes == 1:
        return SINGLE_ELECTRODE
    return topology(reference)


def of_scene(scene):
    """The topology of ``scene``'s cell (:func:`wiring` of its ``[circuit] reference`` and
    ``[device] electrodes``): what summary.json, the figures and the report name."""
    return wiring(scene.circuit.reference, len(scene.device.electrode_names))


def topology(reference: str):
    """The :data:`TOPOLOGIES` entry named ``reference``; ValueError naming the choices."""
    try:
        return TOPOLOGIES[reference]
    except (KeyError, TypeError):
        raise ValueError(f"reference = {reference!r} is not allowed: choose one of "
                         + ", ".join(repr(r) for r in REFERENCES)) from None


def _check_reference(reference: str) -> None:
    topology(reference)


def terminal_capacitance(C_ll, C_lu, C_uu, reference: str = "floating"):
    """C_T [F] seen between the two terminals."""
    wiring = topology(reference)
    C_ll, C_lu, C_uu = (np.asarray(x, dtype=float) for x in (C_ll, C_lu, C_uu))
    return wiring.capacitance(C_ll, C_lu, C_uu)


def upper_short_circuit_charge(C_ll, C_lu, C_uu, q_l, q_u, ball_charge,
                               reference: str = "floating"):
    """Q_u0(z) [C]: upper-electrode charge with the terminals shorted (V = 0)."""
    wiring = topology(reference)
    C_ll, C_lu, C_uu, q_l, q_u = (np.asarray(x, dtype=float) for x in (C_ll, C_lu, C_uu, q_l, q_u))
    return wiring.upper_short_charge(C_ll, C_lu, C_uu, q_l, q_u, ball_charge)


#: the electrodes' names, in the order of the field's matrices, by their count
ELECTRODE_NAMES = {1: ("lower",), 2: ("lower", "upper")}


def terminal_voltage(potentials) -> float:
    """V = V_lower − V_upper [V] of the electrode ``potentials`` ([V_lower, V_upper]); the
    single-electrode cell's [V_lower]: V_lower − 0 (the ground)."""
    values = np.ravel(np.asarray(potentials, dtype=float))
    return float(values[0] - (values[1] if values.size > 1 else 0.0))
