"""Open-circuit potential of one ball position (library function + pure physics).

With the ball at z the electrodes float at potentials V = [V_lower, V_upper]
that keep the charges of the reference state (:mod:`tengfield.terminals`):
ball on the lower electrode (z = 0), the terminals shorted, and

* ``reference = "floating"``: the pair holds total charge ``-q_ball``;
* ``reference = "grounded-lower"``: the lower electrode stays grounded
  (V_lower = 0) and the upper one keeps its reference charge.

The physical potential is then ``φ = φ_σ + V_lower ψ_lower + V_upper ψ_upper``
(φ_σ: potential of the ball charge with both electrodes grounded), see
:meth:`tengfield.field.result.FieldSolution.potential_values`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._args import checked_write
from .. import terminals
from .result import PositionResult


def reference_charges(C_ref, q_ref, ball_charge: float, reference: str = "floating") -> np.ndarray:
    """Electrode charges [Q_lower, Q_upper] [C] of the reference state (terminals shorted):
    the topology's (:func:`tengfield.terminals.wiring`)."""
    return terminals.wiring(reference, np.asarray(q_ref).size).reference_charges(
        C_ref, q_ref, ball_charge)


def open_circuit_potentials(C, q, C_ref, q_ref, ball_charge: float,
                            reference: str = "floating") -> np.ndarray:
    """[V_lower, V_upper] [V] with the terminals open, charges fixed at the reference state
    (one potential, [V_lower], for the single-electrode cell)."""
    wiring = terminals.wiring(reference, np.asarray(q).size)
    return wiring.open_potentials(C, q, wiring.reference_charges(C_ref, q_ref, ball_charge))


@dataclass
class OpenCircuit:
    """The open-circuit state of one position (SI)."""
    result: PositionResult          # the position (``result.solution`` with keep_solution)
    reference_result: PositionResult  # the reference state, ball at z = 0
    potentials: np.ndarray          # [V_lower, V_upper] [V]
    reference: str                  # "floating" or "grounded-lower"

    @property
    def V_oc(self) -> float:
        """V_OC = V_lower - V_upper [V]."""
        return terminals.terminal_voltage(self.potentials)

    @property
    def summary(self) -> dict:
        """JSON-ready: field.json's content (the position, C_T for ``reference``, the
        open-circuit potentials)."""
        from .io import field_json

        return field_json(self.result, self.reference, self.potentials)

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield field`` writes (field.json with the open-circuit potentials,
        potential.xdmf and field.png of φ); returns the paths."""
        return self.result.write(out_dir, plots, reference=self.reference,
                                 potentials=self.potentials)

    def potential_values(self) -> np.ndarray:
        """Local dof values of φ [V] on ``result.solution.space`` (needs keep_solution)."""
        if self.result.solution is None:
            raise ValueError("open_circuit(..., keep_solution=True) keeps the potentials")
        return self.result.solution.potential_values(self.potentials)


def open_circuit(scene, position: float, *, comm, reference: str | None = None,
                 keep_solution: bool = False, method: str | None = None,
                 offset: float | None = None, **overrides) -> OpenCircuit:
    """Open-circuit potentials [V_lower, V_upper] with the ball at gap ``position`` [m].

    Solves the position and the reference state (z = 0, no error estimate);
    ``reference`` defaults to ``[circuit] reference``. ``keep_solution`` keeps
    the mesh and potentials (axisymmetric: also the ball charge's own potential
    φ_σ, so :meth:`OpenCircuit.potential_values` is the full φ; 3D: φ_σ is not
    computed). ``method``, ``offset`` and ``overrides`` as in
    :func:`tengfield.field.solve_position`.
    """
    from ..scene.shapes.methods import field_method
    from . import FIELD_OVERRIDES, resolve_method, solve_position

    reference = reference or scene.circuit.reference
    terminals._check_reference(reference)
    field_keys = {k: v for k, v in overrides.items() if k in FIELD_OVERRIDES}
    options = dict(overrides)
    chosen = resolve_method(scene, method, scene.field.ball_offset if offset is None else offset)
    if keep_solution and field_method(chosen).dimension == 2:   # the (r, z) solver's σ solve
        options["source_solve"] = True
    result = solve_position(scene, position, comm=comm, method=chosen, offset=offset,
                            keep_solution=keep_solution, **options)
    ref = solve_position(scene, 0.0, comm=comm, method=chosen, offset=offset,
                         estimate_error=False, **field_keys)
    potentials = open_circuit_potentials(result.capacitance, result.induced_charge,
                                         ref.capacitance, ref.induced_charge,
                                         result.ball_charge, reference)
    return OpenCircuit(result, ref, potentials, reference)
