"""The table of field solves and the smooth terminal curves through it.

Per position: the Maxwell capacitance matrix ``C_ll, C_lu, C_uu`` [F] and
the induced charges ``q_l, q_u`` [C] (sign conventions of
:mod:`tengfield.terminals`). Cubic splines through the derived ``Q_SC(z)``
[C] and ``C_T(z)`` [F] (for the chosen reference) give ``V_OC = Q_SC / C_T``
[V] and the exact derivatives ``dQ_SC/dz`` [C/m] and ``dC_T/dz`` [F/m] of
the interpolant (never finite differences). :func:`held_out_error` is the
surrogate's error estimate (see :mod:`tengfield.surrogate.refinement`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from .. import terminals
from ..errors import TengfieldError


class SurrogateError(TengfieldError, RuntimeError):
    """A surrogate file is missing, partial, corrupt or for another scene.

    ``path`` (if any) names the file and ``reason`` says what is wrong with it
    (the message without the path).
    """

    def __init__(self, message: str, *, path=None, reason: str | None = None):
        super().__init__(message)
        self.path = None if path is None else str(path)
        self.reason = reason if reason is not None else message


#: the per-position arrays of a table (all of length ``count``)
PER_POSITION = ("positions", "capacitance", "induced_charge", "dofs", "cells", "wall_time",
                "solve_time", "field_error")
#: optional per-position arrays (None when the solver did not give them): the basis
#: potentials of the breakdown lines (tengfield.field.breakdown), shape (n, 2, lines, 3),
#: and the same on the error estimate's half-size mesh (NaN where not estimated)
OPTIONAL_PER_POSITION = ("line_potential", "line_check")


@dataclass(kw_only=True)
class SolveRecord:
    """What the field solves behind a surrogate cost and how it was refined (keywords only;
    :class:`SurrogateTable` per position, :class:`tengfield.surrogate.radial.RadialTable`
    per grid point): ``dofs``, ``cells``, ``wall_time`` [s] (per solve, all ranks),
    ``solve_time`` [s], ``field_error`` (relative), the interpolation error estimate,
    its ``tolerance``, whether it ``converged``, the ``error_history`` of the refinement,
    the cache key ``field_hash``, the solver ``method`` and ``degree``, and ``provenance``."""
    dofs: np.ndarray
    cells: np.ndarray
    wall_time: np.ndarray
    solve_time: np.ndarray
    field_error: np.ndarray
    interpolation_error: float = math.nan
    tolerance: float = math.nan
    converged: bool = False
    error_history: list = field(default_factory=list)
    field_hash: str = ""
    method: str = ""
    degree: int = 0
    provenance: dict = field(default_factory=dict)


@dataclass
class SurrogateTable(SolveRecord):
    """Field solves at sampled positions (one cell, SI) and their provenance.

    ``capacitance[i]`` = [[C_ll, C_lu], [C_lu, C_uu]] [F] and
    ``induced_charge[i]`` = [q_lower, q_upper] [C] at ``positions[i]`` [m]
    (ascending). ``interpolation_error`` is the held-out relative error
    estimate (see :mod:`tengfield.surrogate.refinement`), ``field_error`` the
    field solver's per-position estimate (measured at a few positions and
    carried over to the others, see ``provenance["field_error_rule"]``);
    ``error_history`` = [(positions, estimate), ...]. The other fields: :class:`SolveRecord`.
    """
    positions: np.ndarray
    capacitance: np.ndarray
    induced_charge: np.ndarray
    ball_charge: float
    stroke: float
    line_potential: np.ndarray | None = None
    line_check: np.ndarray | None = None

    def __post_init__(self) -> None:
        order = np.argsort(self.positions, kind="stable")
        for name in OPTIONAL_PER_POSITION:
            if getattr(self, name) is not None:
                setattr(self, name, np.asarray(getattr(self, name), dtype=float)[order])
        self.positions = np.asarray(self.positions, dtype=float)[order]
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(-1, 2, 2)[order]
        self.induced_charge = np.asarray(self.induced_charge, dtype=float).reshape(-1, 2)[order]
        for name in ("dofs", "cells"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.int64)[order])
        for name in ("wall_time", "solve_time", "field_error"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=float)[order])

    @property
    def count(self) -> int:
        return int(self.positions.size)

    @property
    def total_solve_wall_time(self) -> float:
        """Sum of the per-position wall times [s] over all ranks (mirror images cost 0)."""
        return float(np.sum(self.wall_time))

    def curves(self, reference: str = "floating") -> "TerminalCurves":
        return TerminalCurves(self, reference)

    def subset(self, mask) -> "SurrogateTable":
        """The positions selected by the boolean ``mask``."""
        return dataclasses.replace(self, **{name: getattr(self, name)[mask] for name in PER_POSITION
                                            + self._optional()})

    def _optional(self) -> tuple:
        return tuple(n for n in OPTIONAL_PER_POSITION if getattr(self, n) is not None)

    def merged(self, other: "SurrogateTable") -> "SurrogateTable":
        """This table plus the positions of ``other`` (same scene)."""
        cat = {name: np.concatenate([getattr(self, name), getattr(other, name)])
               for name in PER_POSITION}
        for name in OPTIONAL_PER_POSITION:
            mine, theirs = getattr(self, name), getattr(other, name)
            cat[name] = (None if mine is None or theirs is None
                         else np.concatenate([mine, theirs]))
        return dataclasses.replace(self, **cat)


def table_from_results(results: list, *, stroke: float) -> SurrogateTable:
    """A :class:`SurrogateTable` from :class:`~tengfield.field.PositionResult` s."""
    if not results:
        raise ValueError("no field results")
    return SurrogateTable(
        positions=[r.position for r in results],
        capacitance=[r.capacitance for r in results],
        induced_charge=[r.induced_charge for r in results],
        ball_charge=float(results[0].ball_charge),
        stroke=stroke,
        dofs=[r.dofs for r in results], cells=[r.cells for r in results],
        wall_time=[r.wall_time for r in results],
        solve_time=[getattr(r, "solve_time", math.nan) for r in results],
        field_error=[r.relative_error_estimate for r in results],
        method=str(results[0].method), degree=int(results[0].degree),
        **_line_arrays(results))


def _line_arrays(results: list) -> dict:
    """``line_potential`` and ``line_check`` from the results' ``info`` (breakdown lines),
    or nothing when a result has none."""
    lines = [getattr(r, "info", {}).get("breakdown_lines") for r in results]
    if any(v is None for v in lines):
        return {}
    lines = [np.asarray(v, dtype=float) for v in lines]
    check = [np.asarray(getattr(r, "info", {}).get("breakdown_lines_check", np.full_like(v, np.nan)),
                        dtype=float) for r, v in zip(results, lines)]
    return {"line_potential": np.stack(lines), "line_check": np.stack(check)}


def terminal_samples(table: SurrogateTable, reference: str = "floating"):
    """``(Q_SC, C_T)`` [C], [F] at the table's positions, one cell.

    ``Q_SC(z) = Q_u0(z) - Q_u0(0)``: the table must contain z = 0.
    """
    C = table.capacitance
    q = table.induced_charge
    c_t = terminals.terminal_capacitance(C[:, 0, 0], C[:, 0, 1], C[:, 1, 1], reference)
    q_u0 = terminals.upper_short_circuit_charge(C[:, 0, 0], C[:, 0, 1], C[:, 1, 1],
                                                q[:, 0], q[:, 1], table.ball_charge, reference)
    if table.positions[0] != 0.0:
        raise SurrogateError("the surrogate table has no position z = 0 (the reference state)")
    return q_u0 - q_u0[0], np.asarray(c_t, dtype=float)


class TerminalCurves:
    """Smooth ``Q_SC(z)``, ``C_T(z)``, ``V_OC(z)`` of one cell for one reference.

    Cubic splines (not-a-knot) through the tabulated values; derivatives are
    those of the splines. ``z`` [m] outside [0, Δh] is clipped to the stroke.
    """

    def __init__(self, table: SurrogateTable, reference: str = "floating"):
        from scipy.interpolate import CubicSpline   # not at import: keeps `tengfield --help` fast

        terminals._check_reference(reference)
        self.reference = reference
        self.stroke = float(table.stroke)
        self.positions = table.positions.copy()
        self.charge_samples, self.capacitance_samples = terminal_samples(table, reference)
        if self.positions.size < 2:
            raise SurrogateError("a surrogate needs at least 2 positions")
        kind = "not-a-knot" if self.positions.size >= 4 else "natural"
        self._q = CubicSpline(self.positions, self.charge_samples, bc_type=kind)
        self._c = CubicSpline(self.positions, self.capacitance_samples, bc_type=kind)
        self._dq = self._q.derivative()
        self._dc = self._c.derivative()

    def _z(self, z):
        return np.clip(np.asarray(z, dtype=float), 0.0, self.stroke)

    def charge(self, z):
        """Q_SC(z) [C]."""
        return self._q(self._z(z))

    def charge_derivative(self, z):
        """dQ_SC/dz [C/m] (exact derivative of the interpolant)."""
        return self._dq(self._z(z))

    def capacitance(self, z):
        """C_T(z) [F]."""
        return self._c(self._z(z))

    def capacitance_derivative(self, z):
        """dC_T/dz [F/m]."""
        return self._dc(self._z(z))

    def voltage(self, z):
        """V_OC(z) = Q_SC / C_T [V]."""
        return terminals.open_circuit_voltage(self.charge(z), self.capacitance(z))


def held_out_error(coarse: SurrogateTable, held_out: SurrogateTable) -> float:
    """Largest relative deviation of ``coarse``'s interpolants from direct solves.

    Over both references and the quantities Q_SC, C_T and V_OC, each relative
    to its largest magnitude on the union of both position sets.
    """
    union = coarse.merged(held_out)
    worst = 0.0
    for reference in terminals.REFERENCES:
        curves = TerminalCurves(coarse, reference)
        q_all, c_all = terminal_samples(union, reference)
        inside = np.isin(union.positions, held_out.positions)
        z = union.positions[inside]
        q_direct, c_direct = q_all[inside], c_all[inside]
        v_all = q_all / c_all
        pairs = [(curves.charge(z), q_direct, np.max(np.abs(q_all))),
                 (curves.capacitance(z), c_direct, np.max(np.abs(c_all))),
                 (curves.voltage(z), q_direct / c_direct, np.max(np.abs(v_all)))]
        for interpolated, direct, scale in pairs:
            if scale > 0.0:
                worst = max(worst, float(np.max(np.abs(interpolated - direct)) / scale))
    return worst
