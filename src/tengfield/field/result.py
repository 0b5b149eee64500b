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

from .. import terminals
from .._json import jsonable as _jsonable

METHODS = ("axisymmetric", "3d")


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
        Free-form provenance (mesh size, far-field treatment, domain radius...);
        keys starting with "_" hold in-memory objects and are left out of JSON.
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

    def __post_init__(self) -> None:
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(2, 2)
        self.induced_charge = np.asarray(self.induced_charge, dtype=float).reshape(2)
        if self.method not in METHODS:
            raise ValueError(f"method = {self.method!r}: choose one of {METHODS}")

    # -- named entries ----------------------------------------------------
    @property
    def C_ll(self) -> float:
        return float(self.capacitance[0, 0])

    @property
    def C_lu(self) -> float:
        return float(self.capacitance[0, 1])

    @property
    def C_uu(self) -> float:
        return float(self.capacitance[1, 1])

    @property
    def q_lower(self) -> float:
        return float(self.induced_charge[0])

    @property
    def q_upper(self) -> float:
        return float(self.induced_charge[1])

    # -- derived ----------------------------------------------------------
    def terminal_capacitance(self, reference: str = "floating") -> float:
        """C_T [F] between the terminals for ``reference`` ("floating" or "grounded-lower")."""
        return float(terminals.terminal_capacitance(self.C_ll, self.C_lu, self.C_uu, reference))

    def induced_fractions(self) -> np.ndarray:
        """[q_lower, q_upper] / q_ball: each in [-1, 0] by the maximum principle."""
        return self.induced_charge / self.ball_charge

    def to_json(self, reference: str = "floating") -> dict:
        """The content of ``field.json`` (SI, keys carry the unit)."""
        return {
            "position_m": self.position,
            "offset_m": self.offset,
            "capacitance_F": {"lower_lower": self.C_ll, "lower_upper": self.C_lu,
                              "upper_upper": self.C_uu},
            "induced_charge_C": {"lower": self.q_lower, "upper": self.q_upper},
            "ball_charge_C": self.ball_charge,
            "reference": reference,
            "C_T_F": self.terminal_capacitance(reference),
            "dofs": int(self.dofs),
            "cells": int(self.cells),
            "method": self.method,
            "degree": int(self.degree),
            "wall_time_s": self.wall_time,
            "solve_time_s": self.solve_time,
            "relative_error_estimate": self.relative_error_estimate,
            "info": _jsonable({k: v for k, v in self.info.items() if not k.startswith("_")}),
        }

    def dumps(self, reference: str = "floating") -> str:
        return json.dumps(self.to_json(reference), indent=2)


