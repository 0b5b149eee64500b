"""The tables of field solves and the smooth terminal curves through them, for a ball
on the axis (z) and off it (z, r).

Per position: the Maxwell capacitance matrix ``C_ll, C_lu, C_uu`` [F] and
the induced fractions ``f_l, f_u`` (dimensionless: the charge each grounded electrode
carries per unit ball charge, ``q_k = f_k q_ball``, ``f_k = -ψ_k`` averaged over the ball,
Shockley–Ramo; sign conventions of :mod:`tengfield.terminals`). A table holds no ball
charge: the field is linear in it, so the curves take it as an argument
(``TerminalCurves(table, reference, ball_charge)``), and tables of one geometry serve
every σ. Cubic splines through the derived ``Q_SC(z)``
[C] and ``C_T(z)`` [F] (for the chosen reference and ball charge) give ``V_OC = Q_SC / C_T``
[V] and the exact derivatives ``dQ_SC/dz`` [C/m] and ``dC_T/dz`` [F/m] of
the interpolant (never finite differences). :class:`SurrogateTable` and
:class:`TerminalCurves` on the axis; :class:`RadialTable`,
:class:`RadialTerminalCurves` and :class:`AnchoredTerminalCurves` over (z, r)
(the device is a body of revolution, so an off-axis ball's quantities depend on
its gap z and radial offset r only). How well they interpolate:
:mod:`tengfield.surrogate.refinement`.
"""
from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np
from .._args import checked_write
from .. import lumped, terminals
from ..errors import SurrogateError, TengfieldError  # noqa: F401 - its home was here
from .sampling import grid_key, scaled_offset, scaled_offset_jacobian


#: the ball charge [C] of curves per unit ball charge (Q_SC in C per C of the ball: the
#: accuracy estimates, which are relative, and the contact-charge bookkeeping use them)
UNIT_CHARGE = 1.0
#: the per-position arrays of a table (all of length ``count``)
PER_POSITION = ("positions", "capacitance", "induced_fraction", "dofs", "cells", "wall_time",
                "solve_time", "field_error")
#: optional per-position arrays (None when the solver did not give them): the basis
#: potentials of the breakdown lines (tengfield.field.breakdown), shape (n, 2, lines, 3),
#: and the same on the error estimate's half-size mesh (NaN where not estimated)
OPTIONAL_PER_POSITION = ("line_potential", "line_check")
#: per-point arrays: trailing shape after (n_z, n_r), for the pair's two electrodes
#: (:func:`grid_tails` for any count)
GRID_TAILS = {"capacitance": (2, 2), "induced_fraction": (2,), "dofs": (), "cells": (),
               "wall_time": (), "solve_time": (), "field_error": ()}


def grid_tails(electrodes: int = 2) -> dict:
    """:data:`GRID_TAILS` of a cell with ``electrodes`` electrodes (2: the pair, 1: the
    single-electrode cell)."""
    return {**GRID_TAILS, "capacitance": (electrodes, electrodes),
            "induced_fraction": (electrodes,)}


@dataclass(kw_only=True)
class SolveRecord:
    """What the field solves behind a surrogate cost and how it was refined (keywords only;
    :class:`SurrogateTable` per position, :class:`RadialTable`
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
    ``induced_fraction[i]`` = [q_lower, q_upper] / q_ball (dimensionless, each in
    [-1, 0]) at ``positions[i]`` [m] (ascending); no ball charge (:meth:`induced_charges`
    gives the charges [C] at one). ``interpolation_error`` is the held-out relative error
    estimate (see :mod:`tengfield.surrogate.refinement`), ``field_error`` the
    field solver's per-position estimate (measured at a few positions and
    carried over to the others, see ``provenance["field_error_rule"]``);
    ``error_history`` = [(positions, estimate), ...]. The other fields: :class:`SolveRecord`.
    """
    positions: np.ndarray
    capacitance: np.ndarray
    induced_fraction: np.ndarray
    stroke: float
    line_potential: np.ndarray | None = None
    line_check: np.ndarray | None = None
    #: the scene solved (set by ``precompute`` and ``obtain_table``), else None
    scene: object = field(default=None, repr=False, compare=False)

    @property
    def summary(self) -> dict:
        """JSON-ready: the solved positions [m], the capacitance matrices [F], the induced
        fractions (charge per unit ball charge, dimensionless), the stroke [m] and the
        accuracy figures."""
        return {"positions_m": self.positions.tolist(),
                "capacitance_F": self.capacitance.tolist(),
                "induced_fraction": self.induced_fraction.tolist(),
                "stroke_m": float(self.stroke),
                "method": self.method, "degree": int(self.degree),
                "field_hash": self.field_hash, "converged": bool(self.converged),
                "interpolation_error": float(self.interpolation_error),
                "tolerance": float(self.tolerance)}

    def induced_charges(self, ball_charge: float) -> np.ndarray:
        """[q_lower, q_upper] [C] per position for a ball carrying ``ball_charge`` [C]."""
        return self.induced_fraction * float(ball_charge)

    def plot(self, reference: str = "floating", ball_charge: float | None = None):
        """surrogate.png's figure: V_OC, Q_SC, C_T against z, solved positions as dots, for
        a ball carrying ``ball_charge`` [C] (None: the charge of the scene it was obtained
        for, ``scene``)."""
        from ..plotting.waveforms import surrogate_figure

        return surrogate_figure(self, TerminalCurves(self, reference,
                                                     scene_ball_charge(self, ball_charge)))

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write surrogate.h5 (what ``tengfield precompute -o`` writes) and, with ``plots``,
        surrogate.png (what ``tengfield run`` draws) to ``out_dir``; returns the paths."""
        from .output import write_surrogate_files

        # the figure's ball charge: the scene's (refused before anything is written)
        return write_surrogate_files(self, out_dir, plots=plots,
                                     ball_charge=scene_ball_charge(self) if plots else None)

    def __post_init__(self) -> None:
        order = np.argsort(self.positions, kind="stable")
        for name in OPTIONAL_PER_POSITION:
            if getattr(self, name) is not None:
                setattr(self, name, np.asarray(getattr(self, name), dtype=float)[order])
        self.positions = np.asarray(self.positions, dtype=float)[order]
        count = self.positions.size            # the electrodes: 2 (the pair) or 1
        electrodes = np.asarray(self.induced_fraction).size // count if count else 2
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(
            -1, electrodes, electrodes)[order]
        self.induced_fraction = np.asarray(self.induced_fraction, dtype=float).reshape(
            -1, electrodes)[order]
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

    def curves(self, reference: str, ball_charge: float) -> "TerminalCurves":
        """:class:`TerminalCurves` for ``reference`` and a ball of ``ball_charge`` [C]."""
        return TerminalCurves(self, reference, ball_charge)

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


def scene_ball_charge(table, ball_charge: float | None = None) -> float:
    """``ball_charge`` [C], or (None) the ball charge of the scene ``table`` was obtained
    for (``table.scene``, set by :func:`tengfield.surrogate.obtain_table` and
    ``precompute``); :class:`SurrogateError` when it knows none."""
    if ball_charge is not None:
        return float(ball_charge)
    scene = getattr(table, "scene", None)
    if scene is None:
        raise SurrogateError("the surrogate table holds no ball charge (it is per unit "
                             "charge) and knows no scene: give ball_charge [C]")
    return float(scene.device.ball_charge)


def table_from_results(results: list, *, stroke: float) -> SurrogateTable:
    """A :class:`SurrogateTable` from :class:`~tengfield.field.PositionResult` s."""
    if not results:
        raise ValueError("no field results")
    return SurrogateTable(
        positions=[r.position for r in results],
        capacitance=[r.capacitance for r in results],
        induced_fraction=[r.induced_fraction for r in results],
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


def terminal_samples(table: SurrogateTable, reference: str, ball_charge: float):
    """``(Q_SC, C_T)`` [C], [F] at the table's positions, one cell, the ball carrying
    ``ball_charge`` [C] (1.0: Q_SC per unit ball charge).

    ``Q_SC(z) = Q_u0(z) - Q_u0(0)``: the table must contain z = 0 (Q_u0: the charge on
    the receiving terminal shorted, :meth:`tengfield.terminals.FloatingPair.terminal_charge`;
    the single-electrode cell's ground side), linear in the ball's charge: per unit
    charge from the fractions, times ``ball_charge``.
    """
    C = table.capacitance
    f = table.induced_fraction
    wiring = terminals.wiring(reference, f.shape[1])   # the pair's reference, or one electrode
    c_t = wiring.terminal_capacitance(C)
    q_u0 = wiring.terminal_charge(C, f, 1.0) * float(ball_charge)
    if table.positions[0] != 0.0:
        raise SurrogateError("the surrogate table has no position z = 0 (the reference state)")
    return q_u0 - q_u0[0], np.asarray(c_t, dtype=float)


class Curves(ABC):
    """The terminal curves of one cell for one reference, as every caller uses them (the
    electrical stage, the arrays, the figures, the fit).

    :class:`TerminalCurves` for a ball on the axis (of :class:`OnAxisCurves`),
    :class:`RadialTerminalCurves` and :class:`AnchoredTerminalCurves` off it (of
    :class:`OffAxisCurves`). When ``radial`` is true the values depend on the radial
    offset ``r`` [m] as well as the gap ``z`` [m], and the methods take ``(z, r)``,
    else ``(z)``; ``axis`` is the 1-D curves on the axis (None for bare (z, r) curves).
    ``positions`` [m] are the tabulated gaps; ``charge_samples`` [C] and
    ``capacitance_samples`` [F] every tabulated value (e.g. for C_T's range);
    ``ball_charge`` [C] the ball's charge the charges are for.
    """
    reference: str
    ball_charge: float
    stroke: float
    positions: np.ndarray
    charge_samples: np.ndarray
    capacitance_samples: np.ndarray
    #: the values depend on the radial offset r (the methods take (z, r))
    radial: bool = False
    #: the curves of the ball on the axis (None: bare (z, r) curves have none)
    axis: "TerminalCurves | None" = None

    @abstractmethod
    def charge(self, z, *r):
        """Q_SC [C]."""

    @abstractmethod
    def charge_derivative(self, z, *r):
        """dQ_SC/dz [C/m] (with r: the pair (dQ_SC/dz, dQ_SC/dr))."""

    @abstractmethod
    def capacitance(self, z, *r):
        """C_T [F]."""

    @abstractmethod
    def capacitance_derivative(self, z, *r):
        """dC_T/dz [F/m] (with r: the pair (dC_T/dz, dC_T/dr))."""

    def voltage(self, z, *r):
        """V_OC = Q_SC / C_T [V]."""
        return terminals.open_circuit_voltage(self.charge(z, *r), self.capacitance(z, *r))

    @abstractmethod
    def evaluate_many(self, z, z_rate, r=None, r_rate=None, *, cells: int = 1) -> tuple:
        """``(Q_SC [C], I_SC [A], C_T [F], dC_T/dt [F/s])`` of ``cells`` identical cells in
        parallel along sampled gaps ``z`` [m] with rates ``z_rate`` [m/s] (and, where
        ``radial``, offsets ``r`` [m] with rates ``r_rate`` [m/s], default 0): the arrays of
        :func:`tengfield.electrical.terminal_waveforms`."""


class OnAxisCurves(Curves):
    """Curves of a ball on the axis: everything follows from ``charge(z)``,
    ``capacitance(z)`` and their derivatives."""
    radial = False

    @property
    def axis(self) -> "OnAxisCurves":
        return self

    def evaluate_many(self, z, z_rate, r=None, r_rate=None, *, cells: int = 1) -> tuple:
        """:meth:`Curves.evaluate_many`; ``r`` and ``r_rate`` play no part on the axis.
        ``I_SC = (dQ_SC/dz) ż`` and ``dC_T/dt = (dC_T/dz) ż`` of the scaled cells."""
        z = np.asarray(z, dtype=float)
        z_rate = np.asarray(z_rate, dtype=float)
        q_sc, dq_dz, c_t, dc_dz = lumped.scale_cells(
            self.charge(z), self.charge_derivative(z), self.capacitance(z),
            self.capacitance_derivative(z), cells)
        return q_sc, lumped.short_circuit_current(dq_dz, z_rate), c_t, dc_dz * z_rate


class TerminalCurves(OnAxisCurves):
    """Smooth ``Q_SC(z)``, ``C_T(z)``, ``V_OC(z)`` of one cell for one reference and a
    ball carrying ``ball_charge`` [C] (σ π d²; Q_SC and V_OC are proportional to it, C_T
    does not depend on it).

    Cubic splines (not-a-knot) through the tabulated values; derivatives are
    those of the splines. ``z`` [m] outside [0, Δh] is clipped to the stroke.
    """

    def __init__(self, table: SurrogateTable, reference: str, ball_charge: float):
        from scipy.interpolate import CubicSpline   # not at import: keeps `tengfield --help` fast

        terminals._check_reference(reference)
        self.reference = reference
        self.ball_charge = float(ball_charge)
        self.stroke = float(table.stroke)
        self.positions = table.positions.copy()
        self.charge_samples, self.capacitance_samples = terminal_samples(
            table, reference, self.ball_charge)
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

    def pieces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(knots, charge, capacitance)``: the splines' breakpoints [m] (the positions)
        and the piecewise cubic coefficients of Q_SC and C_T, shape (4, knots - 1),
        highest power first, in powers of ``z - knots[j]`` on interval j: for compiled
        evaluation (:mod:`tengfield.array`). Read only."""
        return self._q.x, self._q.c, self._c.c


# ---------------------------------------------------------------------------
# over (z, r): an off-axis ball (issue #13)
@dataclass
class RadialTable(SolveRecord):
    """3D field solves on the grid ``positions`` x ``offsets`` (one cell, SI).

    ``capacitance[i, j]`` = [[C_ll, C_lu], [C_lu, C_uu]] [F] and
    ``induced_fraction[i, j]`` = [q_lower, q_upper] / q_ball (dimensionless) at gap
    ``positions[i]`` [m] and radial offset ``offsets[j]`` [m] (both ascending, from 0);
    no ball charge, as :class:`SurrogateTable`.
    ``error_history`` = [(n_z, n_r, estimate), ...]; ``mesh_size`` [m] and
    ``degree`` the 3D discretisation; ``field_hash`` the cache key
    (:func:`tengfield.surrogate.provenance.radial_hash`). The other fields: :class:`SolveRecord`.
    """
    positions: np.ndarray
    offsets: np.ndarray
    capacitance: np.ndarray
    induced_fraction: np.ndarray
    stroke: float
    max_offset: float
    method: str = field(default="3d", kw_only=True)
    mesh_size: float = field(default=math.nan, kw_only=True)
    #: "radial": offsets r [m]; "scaled": u = R r / r_max(z) [m] (sampling.offset_coordinate)
    offset_coordinate: str = field(default="radial", kw_only=True)

    def __post_init__(self) -> None:
        if self.offset_coordinate not in ("radial", "scaled"):
            raise SurrogateError(f"offset_coordinate {self.offset_coordinate!r}: not radial/scaled")
        self.positions = np.asarray(self.positions, dtype=float)
        self.offsets = np.asarray(self.offsets, dtype=float)
        grid = (self.positions.size, self.offsets.size)
        points = grid[0] * grid[1]     # the electrodes: 2 (the pair) or 1
        electrodes = np.asarray(self.induced_fraction).size // points if points else 2
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(
            *grid, electrodes, electrodes)
        self.induced_fraction = np.asarray(self.induced_fraction, dtype=float).reshape(
            *grid, electrodes)
        for name in ("dofs", "cells"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.int64).reshape(grid))
        for name in ("wall_time", "solve_time", "field_error"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=float).reshape(grid))

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.positions.size), int(self.offsets.size))

    @property
    def electrodes(self) -> int:
        """The cell's electrode count (2: the pair, 1: the single-electrode cell)."""
        return int(self.induced_fraction.shape[-1])

    @property
    def count(self) -> int:
        """Number of grid points (mirror images included)."""
        return self.shape[0] * self.shape[1]

    @property
    def total_solve_wall_time(self) -> float:
        """Sum of the per-point wall times [s] over all ranks (mirror images cost 0)."""
        return float(np.sum(self.wall_time))

    def induced_charges(self, ball_charge: float) -> np.ndarray:
        """[q_lower, q_upper] [C] per grid point for a ball carrying ``ball_charge`` [C]."""
        return self.induced_fraction * float(ball_charge)

    def curves(self, reference: str, ball_charge: float) -> "RadialTerminalCurves":
        """:class:`RadialTerminalCurves` for ``reference`` and a ball of ``ball_charge`` [C]."""
        return RadialTerminalCurves(self, reference, ball_charge)

    def column(self, j: int) -> SurrogateTable:
        """The 1-D :class:`SurrogateTable` at offset ``offsets[j]`` (its Q_SC is
        referred to z = 0 at that offset)."""
        return SurrogateTable(
            positions=self.positions, capacitance=self.capacitance[:, j],
            induced_fraction=self.induced_fraction[:, j], stroke=self.stroke,
            dofs=self.dofs[:, j], cells=self.cells[:, j],
            wall_time=self.wall_time[:, j], solve_time=self.solve_time[:, j],
            field_error=self.field_error[:, j], method=self.method, degree=self.degree)

    def subgrid(self, positions, offsets) -> "RadialTable":
        """The points of ``positions`` x ``offsets`` (members of this grid)."""
        iz = _indices(self.positions, positions)
        ir = _indices(self.offsets, offsets)
        pick = {name: getattr(self, name)[np.ix_(iz, ir)] for name in GRID_TAILS}
        return dataclasses.replace(self, positions=self.positions[iz],
                                   offsets=self.offsets[ir], **pick)


def _indices(values: np.ndarray, wanted) -> np.ndarray:
    index = {round(v * 1e13): i for i, v in enumerate(np.asarray(values, dtype=float))}
    try:
        return np.array([index[round(float(w) * 1e13)] for w in wanted], dtype=int)
    except KeyError as exc:
        raise ValueError(f"{exc.args[0] * 1e-13:g} m is not a grid value") from None


def table_from_grid(solved: dict, positions, offsets, *, stroke: float,
                    largest_offset: float, offset_coordinate: str = "radial") -> RadialTable:
    """A :class:`RadialTable` from ``solved[grid_key(z, r)]`` PositionResults on the grid."""
    positions = np.sort(np.asarray(positions, dtype=float))
    offsets = np.sort(np.asarray(offsets, dtype=float))
    rows = [[solved[grid_key(z, r)] for r in offsets] for z in positions]
    first = rows[0][0]

    def grid(get, dtype=float):
        return np.array([[get(res) for res in row] for row in rows], dtype=dtype)

    return RadialTable(
        positions=positions, offsets=offsets,
        capacitance=grid(lambda res: np.asarray(res.capacitance, dtype=float)),
        induced_fraction=grid(lambda res: np.asarray(res.induced_fraction, dtype=float)),
        stroke=float(stroke),
        max_offset=float(largest_offset),
        dofs=grid(lambda res: res.dofs, np.int64), cells=grid(lambda res: res.cells, np.int64),
        wall_time=grid(lambda res: res.wall_time),
        solve_time=grid(lambda res: getattr(res, "solve_time", math.nan)),
        field_error=grid(lambda res: res.relative_error_estimate),
        method=str(first.method), degree=int(first.degree), offset_coordinate=offset_coordinate)


def terminal_grid(table: RadialTable, reference: str, ball_charge: float):
    """``(Q_SC, C_T)`` [C], [F] on the grid, shape (n_z, n_r), one cell, the ball carrying
    ``ball_charge`` [C], with ``Q_SC(z, r) = Q_u0(z, r) − Q_u0(0, 0)`` (the table must
    contain z = 0 and r = 0)."""
    C, f = table.capacitance, table.induced_fraction
    wiring = terminals.wiring(reference, f.shape[-1])
    c_t = wiring.terminal_capacitance(C)
    q_u0 = wiring.terminal_charge(C, f, 1.0) * float(ball_charge)
    if table.positions[0] != 0.0 or table.offsets[0] != 0.0:
        raise SurrogateError("the (z, r) table has no point z = 0, r = 0 (the reference state)")
    return np.asarray(q_u0 - q_u0[0, 0], dtype=float), np.asarray(c_t, dtype=float)


class OffAxisCurves(Curves):
    """Curves of a ball off the axis: ``charge(z, r)``, ``capacitance(z, r)`` and their
    gradients ``(d/dz, d/dr)``; ``positions`` x ``offsets`` [m] is the grid of solves up
    to ``max_offset`` [m], ``charge_grid`` and ``capacitance_grid`` the values on it."""
    radial = True
    offsets: np.ndarray
    max_offset: float
    charge_grid: np.ndarray
    capacitance_grid: np.ndarray

    def evaluate_many(self, z, z_rate, r=None, r_rate=None, *, cells: int = 1) -> tuple:
        """:meth:`Curves.evaluate_many` with ``I_SC = dQ_SC/dz ż + dQ_SC/dr ṙ``, ``dC_T/dt``
        likewise (no ``r``: on the axis; no ``r_rate``: 0)."""
        z = np.asarray(z, dtype=float)
        zero = np.zeros_like(z)
        radial = np.asarray(zero if r is None else r, dtype=float)
        z_rate = np.asarray(z_rate, dtype=float)
        r_rate = np.asarray(zero if r_rate is None else r_rate, dtype=float)
        dq_dz, dq_dr = self.charge_derivative(z, radial)
        dc_dz, dc_dr = self.capacitance_derivative(z, radial)
        q_rate = dq_dz * z_rate + dq_dr * r_rate
        c_rate = dc_dz * z_rate + dc_dr * r_rate
        # scale_cells is linear in each argument: pass the rates as "derivatives" at unit speed
        q_sc, dq_dt, c_t, dc_dt = lumped.scale_cells(self.charge(z, radial), q_rate,
                                                      self.capacitance(z, radial), c_rate, cells)
        return q_sc, dq_dt, c_t, dc_dt


class RadialTerminalCurves(OffAxisCurves):
    """Smooth ``Q_SC(z, r)``, ``C_T(z, r)``, ``V_OC(z, r)`` of one cell for one reference.

    The interface of :class:`tengfield.surrogate.TerminalCurves` (a ball of
    ``ball_charge`` [C]) with two arguments: gap ``z`` [m] and radial offset ``r`` [m]
    (arrays broadcast; z is clipped to [0, Δh], |r| to [0, r_max]). Tensor-product splines in
    (z, s = r²), cubic where the grid has 4 or more values (else of degree
    count − 1); the derivatives are those of the splines, and ∂/∂r = 0 at
    r = 0 exactly. Q_SC is referred to the ball on the lower plate on the axis.
    A ``"scaled"`` table (the spherical shell): splines in (z, u²), u = R r / r_max(z), r
    clipped to r_max(z), the chain rule (:func:`scaled_offset_jacobian`); see :meth:`grid_values`.
    """

    def __init__(self, table: RadialTable, reference: str, ball_charge: float):
        self._axes(table, reference)
        self.ball_charge = float(ball_charge)
        self.charge_grid, self.capacitance_grid = terminal_grid(table, reference,
                                                                self.ball_charge)
        #: every tabulated value (flat), as ``TerminalCurves`` has (e.g. for C_T's range)
        self.charge_samples = self.charge_grid.ravel()
        self.capacitance_samples = self.capacitance_grid.ravel()
        self._q = self._spline(self.charge_grid)
        self._c = self._spline(self.capacitance_grid)

    def _axes(self, table: RadialTable, reference: str) -> None:
        """The grid of ``table`` (gaps, offsets, their coordinate) and the reference."""
        terminals._check_reference(reference)
        nz, nr = table.shape
        if nz < 2 or nr < 2:
            raise SurrogateError(f"a (z, r) surrogate needs at least 2 x 2 points, got {nz} x {nr}")
        self.reference = reference
        self.table = table       # its capacitance grid: the contact charge's share k(z, r)
        self.stroke = float(table.stroke)
        self.max_offset = float(table.max_offset)
        self.scaled = table.offset_coordinate == "scaled"
        self.positions = table.positions.copy()
        self.offsets = table.offsets.copy()

    def _spline(self, grid):
        """The tensor-product spline of ``grid`` (gaps x offsets) in (z, s = u²)."""
        from scipy.interpolate import RectBivariateSpline

        nz, nr = grid.shape
        return RectBivariateSpline(self.positions, self.offsets**2, grid,
                                   kx=min(3, nz - 1), ky=min(3, nr - 1), s=0)

    def _zs(self, z, r):
        z, r = np.broadcast_arrays(np.asarray(z, dtype=float), np.asarray(r, dtype=float))
        z = np.clip(z, 0.0, self.stroke)
        if self.scaled:
            return z, scaled_offset(z, r, self.stroke, self.max_offset)
        return z, np.clip(np.abs(r), 0.0, self.max_offset)

    def _eval(self, spline, z, r, dz=0, ds=0):
        z, r = self._zs(z, r)
        return spline.ev(z, r**2, dx=dz, dy=ds).reshape(z.shape), r

    def _gradient(self, spline, z, r):
        """``(d/dz, d/dr)`` of ``spline`` over (z, s = u²); d/dr = 2u d/ds du/dr, 0 on the axis."""
        d_z = self._eval(spline, z, r, dz=1)[0]
        d_s, u = self._eval(spline, z, r, ds=1)
        if not self.scaled:
            return d_z, 2.0 * u * d_s
        du_dz, du_dr = scaled_offset_jacobian(z, r, u, self.stroke, self.max_offset)
        return d_z + 2.0 * u * d_s * du_dz, 2.0 * u * d_s * du_dr

    def grid_values(self, z, u):
        """``(Q_SC [C], C_T [F])`` at gap ``z`` and table coordinate ``u`` [m] (= r if radial)."""
        z, u = np.broadcast_arrays(np.asarray(z, dtype=float), np.asarray(u, dtype=float))
        return self._q.ev(z, u**2).reshape(z.shape), self._c.ev(z, u**2).reshape(z.shape)

    def charge(self, z, r):
        """Q_SC(z, r) [C]."""
        return self._eval(self._q, z, r)[0]

    def charge_derivative(self, z, r):
        """``(dQ_SC/dz [C/m], dQ_SC/dr [C/m])`` of the interpolant."""
        return self._gradient(self._q, z, r)

    def capacitance(self, z, r):
        """C_T(z, r) [F]."""
        return self._eval(self._c, z, r)[0]

    def capacitance_derivative(self, z, r):
        """``(dC_T/dz [F/m], dC_T/dr [F/m])`` of the interpolant."""
        return self._gradient(self._c, z, r)


class AnchoredTerminalCurves(OffAxisCurves):
    """The (z, r) curves anchored to the axisymmetric surrogate:
    ``F(z, r) = F_axis(z) + [F_zr(z, r) − F_zr(z, 0)]`` for F = Q_SC and C_T.

    On the axis this is the 1-D surrogate exactly (its field error ~1e-4, not
    the coarse 3D mesh's ~1e-2), and off the axis the 3D solves contribute
    only the change with r, in which most of their discretisation error
    cancels. So a run switches from the 1-D to the (z, r) surrogate without a
    jump as the ball leaves the axis. Same interface as
    :class:`RadialTerminalCurves`; ``axis`` is a
    :class:`tengfield.surrogate.TerminalCurves` of the same reference.
    """

    def __init__(self, curves: RadialTerminalCurves, axis):
        if axis.reference != curves.reference:
            raise ValueError(f"references differ: {axis.reference!r} (axis) and "
                             f"{curves.reference!r} (z, r)")
        if not math.isclose(axis.stroke, curves.stroke, rel_tol=1e-12):
            raise ValueError("the axisymmetric and (z, r) surrogates have different strokes")
        if axis.ball_charge != curves.ball_charge:
            raise ValueError(f"ball charges differ: {axis.ball_charge:g} C (axis) and "
                             f"{curves.ball_charge:g} C (z, r)")
        self.zr, self.axis = curves, axis
        self.reference, self.ball_charge = curves.reference, curves.ball_charge
        self.stroke, self.max_offset = curves.stroke, curves.max_offset
        self.positions, self.offsets = curves.positions, curves.offsets
        z = curves.positions[:, None]
        shift_q = curves.charge_grid - curves.charge_grid[:, :1]
        shift_c = curves.capacitance_grid - curves.capacitance_grid[:, :1]
        self.charge_grid = axis.charge(z) + shift_q
        self.capacitance_grid = axis.capacitance(z) + shift_c
        self.charge_samples = self.charge_grid.ravel()
        self.capacitance_samples = self.capacitance_grid.ravel()

    def charge(self, z, r):
        """Q_SC(z, r) [C]."""
        return self.axis.charge(z) + self.zr.charge(z, r) - self.zr.charge(z, 0.0)

    def charge_derivative(self, z, r):
        """``(dQ_SC/dz, dQ_SC/dr)`` [C/m]."""
        d_z, d_r = self.zr.charge_derivative(z, r)
        return self.axis.charge_derivative(z) + d_z - self.zr.charge_derivative(z, 0.0)[0], d_r

    def capacitance(self, z, r):
        """C_T(z, r) [F]."""
        return self.axis.capacitance(z) + self.zr.capacitance(z, r) - self.zr.capacitance(z, 0.0)

    def capacitance_derivative(self, z, r):
        """``(dC_T/dz, dC_T/dr)`` [F/m]."""
        d_z, d_r = self.zr.capacitance_derivative(z, r)
        return (self.axis.capacitance_derivative(z) + d_z
                - self.zr.capacitance_derivative(z, 0.0)[0], d_r)
