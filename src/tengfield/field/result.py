"""What a field solve at one ball position returns (pure Python, no dolfinx).

Sign conventions are those of :mod:`tengfield.terminals`: the Maxwell
capacitance matrix ``C = [[C_ll, C_lu], [C_lu, C_uu]]`` [F] of the lower and
upper electrodes (``C_ll, C_uu > 0 > C_lu``), and the charges
``q = [q_lower, q_upper]`` [C] induced on the electrodes by the charged ball
with both electrodes grounded, ``q_k = -∮_ball σ ψ_k dS`` (ψ_k the weighting
potential of electrode k). Electrode charges at potentials V are
``Q = C V + q``.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._args import checked_write
from .. import terminals
from .._json import jsonable as _jsonable
from ..scene.shapes.methods import FIELD_METHODS

#: the resolved ``[field] method`` names (scene/shapes/methods.py's table)
METHODS = tuple(FIELD_METHODS)


@dataclass
class FieldSolution:
    """Mesh and potentials behind a :class:`PositionResult` (in memory only; ask
    for it with ``solve_position(..., keep_solution=True)``). The same type for
    both methods; the axisymmetric one lives on one process (COMM_SELF), the 3D
    one is distributed over the solve's communicator.

    Attributes
    ----------
    method:
        "axisymmetric" (coordinates (r, z), metres) or "3d" (x, y, z).
    mesh, cell_tags, facet_tags:
        The dolfinx mesh and its physical-group tags.
    space:
        The Lagrange space of the potentials.
    weighting:
        (ψ_lower, ψ_upper): dolfinx Functions on ``space``, the potential [V]
        for 1 V on that electrode and 0 V on the other, uncharged ball.
    ball_centre:
        [m], shape (3,), in the mesh's coordinates.
    geometry:
        The layout the mesh was built from (axisymmetric
        :class:`~tengfield.field.geometry_axisymmetric.AxisymmetricLayout`, 3D cell).
    source:
        φ_σ [V]: potential of the ball charge with both electrodes grounded
        (axisymmetric with ``source_solve``), else ``None``.
    hidden_cells:
        Local cells outside the physical domain (the Kelvin image), left out of
        files and plots.
    degree:
        Lagrange degree of ``space``.
    """
    method: str
    mesh: Any
    cell_tags: Any
    facet_tags: Any
    space: Any
    weighting: tuple
    ball_centre: np.ndarray
    geometry: Any
    source: Any = None
    hidden_cells: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    degree: int = 1

    def potential_values(self, potentials=(0.0, 0.0)) -> np.ndarray:
        """Local dof values of φ = φ_σ + V_lower ψ_lower + V_upper ψ_upper [V]
        (``potentials`` = [V_lower, V_upper]; φ_σ = 0 when there is no source)."""
        phi = sum(v * psi.x.array for v, psi in zip(potentials, self.weighting))
        if self.source is not None:
            phi = phi + self.source.x.array
        return np.asarray(phi, dtype=float)


@dataclass
class PositionResult:
    """Electrostatics of the device with the ball at one position (SI).

    Attributes
    ----------
    position:
        z [m], the gap between the ball's bottom and the lower electrode.
    offset:
        Lateral distance of the ball centre from the tube axis [m].
    capacitance:
        2x2 Maxwell capacitance matrix [[C_ll, C_lu], [C_lu, C_uu]] [F].
    induced_charge:
        [q_lower, q_upper] [C], both electrodes grounded.
    ball_charge:
        Total free charge on the ball, σ π d² [C].
    dofs, cells:
        Size of the discrete problem (global, all ranks).
    method:
        "axisymmetric" or "3d".
    degree:
        Lagrange degree of the potential.
    wall_time:
        Wall-clock time of the whole position (mesh + assembly + solves) [s].
    relative_error_estimate:
        A-posteriori estimate of the relative error of C and q (max over the
        entries), see ``docs/field.md`` for how each method obtains it.
    solve_time:
        Time of the linear algebra only (factorisation + solves) [s].
    info:
        Free-form provenance (mesh size, far-field treatment, domain radius...).
    induced_fraction:
        [q_lower, q_upper] / q_ball (σ-independent; defined for an uncharged ball).
    solution:
        The :class:`FieldSolution` (mesh, potentials) with ``keep_solution=True``,
        else ``None``; never written to JSON.
    """
    position: float
    offset: float
    capacitance: np.ndarray
    induced_charge: np.ndarray
    ball_charge: float
    dofs: int
    cells: int
    method: str
    degree: int
    wall_time: float
    relative_error_estimate: float
    solve_time: float = math.nan
    info: dict[str, Any] = field(default_factory=dict)
    induced_fraction: np.ndarray | None = None
    solution: FieldSolution | None = field(default=None, repr=False, compare=False)
    #: the scene solved (set by :func:`tengfield.field.solve_position`), else None
    scene: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.induced_charge = np.asarray(self.induced_charge, dtype=float).reshape(-1)
        n = self.induced_charge.size            # the electrodes: 2 (the pair) or 1
        if n not in terminals.ELECTRODE_NAMES:
            raise ValueError(f"{n} electrodes: allowed 1 or 2")
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(n, n)
        if self.induced_fraction is None:
            with np.errstate(invalid="ignore", divide="ignore"):
                self.induced_fraction = self.induced_charge / self.ball_charge
        self.induced_fraction = np.asarray(self.induced_fraction, dtype=float).reshape(n)
        if self.method not in METHODS:
            raise ValueError(f"method = {self.method!r}: choose one of {METHODS}")

    # -- named entries ----------------------------------------------------
    @property
    def electrodes(self) -> tuple[str, ...]:
        """The electrodes' names, in the order of the matrices: ("lower", "upper"), or
        ("lower",) for the single-electrode cell."""
        return terminals.ELECTRODE_NAMES[self.induced_charge.size]

    def _upper(self, value):
        if self.induced_charge.size < 2:
            raise AttributeError("the single-electrode cell has no upper electrode "
                                 "([device] electrodes = 'lower')")
        return float(value())

    @property
    def C_ll(self) -> float:
        return float(self.capacitance[0, 0])

    @property
    def C_lu(self) -> float:
        return self._upper(lambda: self.capacitance[0, 1])

    @property
    def C_uu(self) -> float:
        return self._upper(lambda: self.capacitance[1, 1])

    @property
    def q_lower(self) -> float:
        return float(self.induced_charge[0])

    @property
    def q_upper(self) -> float:
        return self._upper(lambda: self.induced_charge[1])

    # -- derived ----------------------------------------------------------
    def wiring(self, reference: str = "floating"):
        """The topology of the terminals (:func:`tengfield.terminals.wiring`): the pair's
        ``reference``, or the single electrode's to the ground."""
        return terminals.wiring(reference, self.induced_charge.size)

    def terminal_capacitance(self, reference: str = "floating") -> float:
        """C_T [F] between the terminals for ``reference`` ("floating" or "grounded-lower";
        the single-electrode cell: the electrode to the ground)."""
        return float(self.wiring(reference).terminal_capacitance(self.capacitance))

    def induced_fractions(self) -> np.ndarray:
        """[q_lower, q_upper] / q_ball: each in [-1, 0] by the maximum principle."""
        return self.induced_fraction.copy()

    @property
    def summary(self) -> dict:
        """JSON-ready: field.json's content for the floating reference (``to_json`` gives
        another reference's)."""
        return self.to_json()

    @checked_write
    def write(self, out_dir, plots: bool = True, *, reference: str = "floating",
              potentials=None) -> list:
        """Write what ``tengfield field`` writes for this position to ``out_dir``: field.json
        (``reference``'s C_T; the open-circuit ``potentials`` [V] when given, as
        :meth:`OpenCircuit.write <tengfield.field.potential.OpenCircuit.write>` gives them)
        and, with ``plots``, potential.xdmf and field.png (they need the solution:
        ``keep_solution=True``); returns the paths."""
        from .io import write_position_files

        return write_position_files(self, out_dir, reference=reference, potentials=potentials,
                                    plots=plots)

    def to_json(self, reference: str = "floating") -> dict:
        """The content of ``field.json`` (SI, keys carry the unit)."""
        return {
            "position_m": self.position,
            "offset_m": self.offset,
            "capacitance_F": {f"{a}_{b}": float(self.capacitance[j, k])
                              for j, a in enumerate(self.electrodes)
                              for k, b in enumerate(self.electrodes) if k >= j},
            "induced_charge_C": {name: float(self.induced_charge[k])
                                 for k, name in enumerate(self.electrodes)},
            "ball_charge_C": self.ball_charge,
            "reference": self.wiring(reference).name,
            "C_T_F": self.terminal_capacitance(reference),
            "dofs": int(self.dofs),
            "cells": int(self.cells),
            "method": self.method,
            "degree": int(self.degree),
            "wall_time_s": self.wall_time,
            "solve_time_s": self.solve_time,
            "relative_error_estimate": self.relative_error_estimate,
            "info": _jsonable(self.info),
        }

    def dumps(self, reference: str = "floating") -> str:
        return json.dumps(self.to_json(reference), indent=2)


