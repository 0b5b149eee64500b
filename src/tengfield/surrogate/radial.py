"""Surrogate over (z, r): an off-axis ball (issue #13, DESIGN §8 "Field over (z, r)").

The device is a body of revolution, so the capacitance matrix and the
induced charges of a ball at gap ``z`` [m] and radial offset ``r`` [m]
(distance of its centre from the tube axis) depend on (z, r) only. This
module tabulates 3D field solves (``solve_position(scene, z, comm=...,
offset=r, method="3d")``) on a tensor grid and interpolates:

* **grid**: ``z`` on the nested Chebyshev–Lobatto sets of the 1-D surrogate
  (:mod:`.sampling`); ``r`` on nested Lobatto sets *in s = r²* over
  ``[0, r_max²]`` (``r_max`` = tube inner radius − ball radius), starting
  with ``{0, r_max}``; both clustered at their ends (plates, axis, wall);
* **interpolant**: a tensor-product spline (FITPACK, cubic where the grid
  allows) of ``Q_SC`` and ``C_T`` in ``(z, s)``. Being a smooth function of
  s = r², it has ∂/∂r = 2r ∂/∂s = 0 on the axis exactly, as the symmetry
  demands;
* **refinement**: each round adds the midpoints in z and/or s (held out
  first): the largest relative deviation of the current interpolant from
  those direct solves (Q_SC, C_T, V_OC, both references, as
  :func:`tengfield.surrogate.held_out_error`) is the error estimate, split
  into the points new in z only and new in r only, so that only the
  direction that needs it is refined. It stops below the tolerance (the
  estimate belongs to the coarser grid: conservative);
* **mirror symmetry**: z -> Δh − z swaps lower and upper at any r
  (:func:`tengfield.surrogate.mirrored`): only z <= Δh/2 is solved;
* **MPI**: the solves of a round are spread over ``comm`` by the task farm
  (:func:`tengfield._mpi.farm`), dearest (closest to a plate) first;
* **file and cache**: HDF5 with the 1-D surrogate's rules (per-array
  Fletcher-32 + SHA-256, checksummed scalars, atomic write, structure
  checks, solver fingerprint, rank 0 decides), through
  :mod:`tengfield.surrogate.store`.

The reference state is the ball resting on the lower electrode ON THE AXIS:
``Q_SC(z, r) = Q_u0(z, r) − Q_u0(0, 0)``. :func:`axis_check` compares the
r = 0 column with the axisymmetric surrogate.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import circuit, terminals
from .._mpi import farm, rank_of
from .refinement import FIELD_ERROR_MODES, _accepts_keyword, warn_problems, \
    _field_error_rule, _sampled_field_errors, error_sample_positions
from .sampling import (INITIAL_POSITIONS, contact_first_order, is_lobatto_count,
                       is_mirror_symmetric, lobatto_positions, mirrored, refinement_positions)
from .store import SCALAR_TYPES
from .table import SolveRecord, SurrogateError, SurrogateTable

#: format of the (z, r) HDF5 file
FORMAT_VERSION_ZR = 1
#: first offset set: s = r² in {0, r_max²} (then 3, 5, 9 offsets)
INITIAL_OFFSETS = 2
#: the refinement stops at these counts even if the tolerance is not met
MAX_POSITIONS_ZR = 33
MAX_OFFSETS = 9
#: default 3D discretisation of the (z, r) surrogate (docs/field3d.md: degree 2,
#: 1.5 mm has a field error of ~1e-2, ~10 s of CPU per solve)
DEFAULT_MESH_SIZE_MM = 1.5
DEFAULT_DEGREE = 2
#: default interpolation tolerance: finer than the 3D field error is wasted
DEFAULT_TOLERANCE = 1.0e-2

#: table attribute -> HDF5 dataset name
ARRAYS_ZR = {"positions": "positions_m", "offsets": "offsets_m",
             "capacitance": "capacitance_F", "induced_charge": "induced_charge_C",
             "dofs": "dofs", "cells": "cells", "wall_time": "wall_time_s",
             "solve_time": "solve_time_s", "field_error": "field_relative_error_estimate"}
#: table attribute -> HDF5 file attribute (covered by ``scalars_sha256``)
SCALARS_ZR = {"ball_charge": "ball_charge_C", "stroke": "stroke_m",
              "max_offset": "max_offset_m", "interpolation_error": "interpolation_error_estimate",
              "tolerance": "tolerance", "converged": "converged", "field_hash": "field_hash",
              "method": "method", "degree": "degree", "mesh_size": "mesh_size_m"}
#: table attribute -> type of its value: the 1-D surrogate's and the 3D ones
SCALAR_TYPES_ZR = {**SCALAR_TYPES, "max_offset": float, "mesh_size": float}
#: per-point arrays: trailing shape after (n_z, n_r)
_GRID_TAILS = {"capacitance": (2, 2), "induced_charge": (2,), "dofs": (), "cells": (),
               "wall_time": (), "solve_time": (), "field_error": ()}


# ---------------------------------------------------------------------------
# sampling in r
def max_offset(device) -> float:
    """Largest radial offset of the ball centre [m]: tube inner radius − ball radius."""
    return float(device.tube_inner_radius - device.ball_radius)


def offset_positions(largest: float, count: int) -> np.ndarray:
    """``count`` offsets r [m] in [0, ``largest``], Lobatto-spaced in s = r² (ascending)."""
    if count == 2:
        return np.array([0.0, float(largest)])
    return np.sqrt(lobatto_positions(largest**2, count))


def offset_refinement(largest: float, count: int) -> np.ndarray:
    """The ``count - 1`` offsets that refine :func:`offset_positions` to ``2 count - 1``."""
    return np.sqrt(refinement_positions(largest**2, count))


def _key(z: float, r: float) -> tuple[int, int]:
    return (round(z * 1e13), round(r * 1e13))   # 0.1 pm: exact for the nested sets


# ---------------------------------------------------------------------------
# the table
@dataclass
class RadialTable(SolveRecord):
    """3D field solves on the grid ``positions`` x ``offsets`` (one cell, SI).

    ``capacitance[i, j]`` = [[C_ll, C_lu], [C_lu, C_uu]] [F] and
    ``induced_charge[i, j]`` = [q_lower, q_upper] [C] at gap ``positions[i]``
    [m] and radial offset ``offsets[j]`` [m] (both ascending, from 0).
    ``error_history`` = [(n_z, n_r, estimate), ...]; ``mesh_size`` [m] and
    ``degree`` the 3D discretisation; ``field_hash`` the cache key
    (:func:`radial_hash`). The other fields: :class:`tengfield.surrogate.table.SolveRecord`.
    """
    positions: np.ndarray
    offsets: np.ndarray
    capacitance: np.ndarray
    induced_charge: np.ndarray
    ball_charge: float
    stroke: float
    max_offset: float
    method: str = field(default="3d", kw_only=True)
    mesh_size: float = field(default=math.nan, kw_only=True)

    def __post_init__(self) -> None:
        self.positions = np.asarray(self.positions, dtype=float)
        self.offsets = np.asarray(self.offsets, dtype=float)
        grid = (self.positions.size, self.offsets.size)
        self.capacitance = np.asarray(self.capacitance, dtype=float).reshape(*grid, 2, 2)
        self.induced_charge = np.asarray(self.induced_charge, dtype=float).reshape(*grid, 2)
        for name in ("dofs", "cells"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.int64).reshape(grid))
        for name in ("wall_time", "solve_time", "field_error"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=float).reshape(grid))

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.positions.size), int(self.offsets.size))

    @property
    def count(self) -> int:
        """Number of grid points (mirror images included)."""
        return self.shape[0] * self.shape[1]

    @property
    def total_solve_wall_time(self) -> float:
        """Sum of the per-point wall times [s] over all ranks (mirror images cost 0)."""
        return float(np.sum(self.wall_time))

    def curves(self, reference: str = "floating") -> "RadialTerminalCurves":
        return RadialTerminalCurves(self, reference)

    def column(self, j: int) -> SurrogateTable:
        """The 1-D :class:`SurrogateTable` at offset ``offsets[j]`` (its Q_SC is
        referred to z = 0 at that offset)."""
        return SurrogateTable(
            positions=self.positions, capacitance=self.capacitance[:, j],
            induced_charge=self.induced_charge[:, j], ball_charge=self.ball_charge,
            stroke=self.stroke, dofs=self.dofs[:, j], cells=self.cells[:, j],
            wall_time=self.wall_time[:, j], solve_time=self.solve_time[:, j],
            field_error=self.field_error[:, j], method=self.method, degree=self.degree)

    def subgrid(self, positions, offsets) -> "RadialTable":
        """The points of ``positions`` x ``offsets`` (members of this grid)."""
        iz = _indices(self.positions, positions)
        ir = _indices(self.offsets, offsets)
        pick = {name: getattr(self, name)[np.ix_(iz, ir)] for name in _GRID_TAILS}
        return dataclasses.replace(self, positions=self.positions[iz],
                                   offsets=self.offsets[ir], **pick)


def _indices(values: np.ndarray, wanted) -> np.ndarray:
    index = {round(v * 1e13): i for i, v in enumerate(np.asarray(values, dtype=float))}
    try:
        return np.array([index[round(float(w) * 1e13)] for w in wanted], dtype=int)
    except KeyError as exc:
        raise ValueError(f"{exc.args[0] * 1e-13:g} m is not a grid value") from None


def table_from_grid(solved: dict, positions, offsets, *, stroke: float,
                    largest_offset: float) -> RadialTable:
    """A :class:`RadialTable` from ``solved[(_key(z, r))]`` PositionResults on the grid."""
    positions = np.sort(np.asarray(positions, dtype=float))
    offsets = np.sort(np.asarray(offsets, dtype=float))
    rows = [[solved[_key(z, r)] for r in offsets] for z in positions]
    first = rows[0][0]

    def grid(get, dtype=float):
        return np.array([[get(res) for res in row] for row in rows], dtype=dtype)

    return RadialTable(
        positions=positions, offsets=offsets,
        capacitance=grid(lambda res: np.asarray(res.capacitance, dtype=float)),
        induced_charge=grid(lambda res: np.asarray(res.induced_charge, dtype=float)),
        ball_charge=float(first.ball_charge), stroke=float(stroke),
        max_offset=float(largest_offset),
        dofs=grid(lambda res: res.dofs, np.int64), cells=grid(lambda res: res.cells, np.int64),
        wall_time=grid(lambda res: res.wall_time),
        solve_time=grid(lambda res: getattr(res, "solve_time", math.nan)),
        field_error=grid(lambda res: res.relative_error_estimate),
        method=str(first.method), degree=int(first.degree))


def terminal_grid(table: RadialTable, reference: str = "floating"):
    """``(Q_SC, C_T)`` [C], [F] on the grid, shape (n_z, n_r), one cell, with
    ``Q_SC(z, r) = Q_u0(z, r) − Q_u0(0, 0)`` (the table must contain z = 0 and r = 0)."""
    C, q = table.capacitance, table.induced_charge
    c_t = terminals.terminal_capacitance(C[..., 0, 0], C[..., 0, 1], C[..., 1, 1], reference)
    q_u0 = terminals.upper_short_circuit_charge(C[..., 0, 0], C[..., 0, 1], C[..., 1, 1],
                                                q[..., 0], q[..., 1], table.ball_charge,
                                                reference)
    if table.positions[0] != 0.0 or table.offsets[0] != 0.0:
        raise SurrogateError("the (z, r) table has no point z = 0, r = 0 (the reference state)")
    return np.asarray(q_u0 - q_u0[0, 0], dtype=float), np.asarray(c_t, dtype=float)


class RadialTerminalCurves:
    """Smooth ``Q_SC(z, r)``, ``C_T(z, r)``, ``V_OC(z, r)`` of one cell for one reference.

    The interface of :class:`tengfield.surrogate.TerminalCurves` with two
    arguments: gap ``z`` [m] and radial offset ``r`` [m] (arrays broadcast;
    z is clipped to [0, Δh], |r| to [0, r_max]). Tensor-product splines in
    (z, s = r²), cubic where the grid has 4 or more values (else of degree
    count − 1); the derivatives are those of the splines, and ∂/∂r = 0 at
    r = 0 exactly. Q_SC is referred to the ball on the lower plate on the axis.
    """

    def __init__(self, table: RadialTable, reference: str = "floating"):
        from scipy.interpolate import RectBivariateSpline

        terminals._check_reference(reference)
        nz, nr = table.shape
        if nz < 2 or nr < 2:
            raise SurrogateError(f"a (z, r) surrogate needs at least 2 x 2 points, got {nz} x {nr}")
        self.reference = reference
        self.stroke = float(table.stroke)
        self.max_offset = float(table.max_offset)
        self.positions = table.positions.copy()
        self.offsets = table.offsets.copy()
        self.charge_grid, self.capacitance_grid = terminal_grid(table, reference)
        #: every tabulated value (flat), as ``TerminalCurves`` has (e.g. for C_T's range)
        self.charge_samples = self.charge_grid.ravel()
        self.capacitance_samples = self.capacitance_grid.ravel()
        s = self.offsets**2
        kz, ks = min(3, nz - 1), min(3, nr - 1)
        self._q = RectBivariateSpline(self.positions, s, self.charge_grid, kx=kz, ky=ks, s=0)
        self._c = RectBivariateSpline(self.positions, s, self.capacitance_grid, kx=kz, ky=ks, s=0)

    def _zs(self, z, r):
        z, r = np.broadcast_arrays(np.asarray(z, dtype=float), np.asarray(r, dtype=float))
        z = np.clip(z, 0.0, self.stroke)
        r = np.clip(np.abs(r), 0.0, self.max_offset)
        return z, r

    def _eval(self, spline, z, r, dz=0, ds=0):
        z, r = self._zs(z, r)
        return spline.ev(z, r**2, dx=dz, dy=ds).reshape(z.shape), r

    def _gradient(self, spline, z, r):
        """``(d/dz, d/dr)`` of ``spline`` over (z, s = r²): d/dr = 2 r d/ds (0 on the axis)."""
        d_z = self._eval(spline, z, r, dz=1)[0]
        d_s, r_used = self._eval(spline, z, r, ds=1)
        return d_z, 2.0 * r_used * d_s

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

    def voltage(self, z, r):
        """V_OC(z, r) = Q_SC / C_T [V]."""
        return terminals.open_circuit_voltage(self.charge(z, r), self.capacitance(z, r))


class AnchoredTerminalCurves:
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
        self.zr, self.axis = curves, axis
        self.reference = curves.reference
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

    def voltage(self, z, r):
        """V_OC(z, r) = Q_SC / C_T [V]."""
        return terminals.open_circuit_voltage(self.charge(z, r), self.capacitance(z, r))


def terminal_waveforms_zr(curves, gap, gap_velocity, radial,
                          radial_velocity, *, cells: int = 1,
                          parallel_capacitance: float = 0.0) -> dict[str, np.ndarray]:
    """:func:`tengfield.electrical.terminal_waveforms` for an off-axis trajectory
    (``curves``: :class:`RadialTerminalCurves` or :class:`AnchoredTerminalCurves`).

    ``gap`` z(t), ``radial`` r(t) [m] and their rates [m/s] at the samples;
    ``I_sc = dQ_SC/dz ż + dQ_SC/dr ṙ`` [A], ``dC_T_dt`` likewise; same keys.
    """
    gap, radial = np.asarray(gap, dtype=float), np.asarray(radial, dtype=float)
    z_rate = np.asarray(gap_velocity, dtype=float)
    r_rate = np.asarray(radial_velocity, dtype=float)
    dq_dz, dq_dr = curves.charge_derivative(gap, radial)
    dc_dz, dc_dr = curves.capacitance_derivative(gap, radial)
    q_rate = dq_dz * z_rate + dq_dr * r_rate
    c_rate = dc_dz * z_rate + dc_dr * r_rate
    # scale_cells is linear in each argument: pass the rates as "derivatives" at unit speed
    q_sc, dq_dt, c_t, dc_dt = circuit.scale_cells(curves.charge(gap, radial), q_rate,
                                                  curves.capacitance(gap, radial), c_rate, cells)
    return {"V_oc": circuit.open_circuit_voltage(q_sc, c_t, parallel_capacitance),
            "Q_sc": q_sc, "I_sc": dq_dt, "C_T": c_t, "dC_T_dt": dc_dt}


#: the ball "leaves the axis" when its largest radial offset exceeds this fraction of
#: r_max; below it the change of Q_SC is O((r / r_max)²) x 2e-3 < 1e-8 (docs/surrogate.md)
AXIS_FRACTION = 1e-3


def _radial_rate(x, y, vx, vy) -> tuple[np.ndarray, np.ndarray]:
    r = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = np.where(r > 0.0, (x * vx + y * vy) / np.where(r > 0.0, r, 1.0), 0.0)
    return r, rate


def radial_motion(motion, times=None) -> tuple[np.ndarray, np.ndarray]:
    """``(r, dr/dt)`` [m], [m/s] of a :class:`tengfield.motion3d.Motion3DResult` at its
    output samples, or exactly at ``times`` [s] (``motion.sample3d``); dr/dt = 0 on
    the axis. Anything without lateral motion (a 1-D DynamicsResult) gives zeros."""
    if times is not None:
        t = np.atleast_1d(np.asarray(times, dtype=float))
        if not hasattr(motion, "sample3d"):
            return np.zeros_like(t), np.zeros_like(t)
        state = np.asarray(motion.sample3d(t), dtype=float).reshape(-1, 9)
        return _radial_rate(state[:, 0], state[:, 1], state[:, 3], state[:, 4])
    if not hasattr(motion, "x"):
        n = np.asarray(motion.gap).size
        return np.zeros(n), np.zeros(n)
    velocity = np.asarray(motion.velocity, dtype=float).reshape(-1, 3)
    return _radial_rate(np.asarray(motion.x, dtype=float), np.asarray(motion.y, dtype=float),
                        velocity[:, 0], velocity[:, 1])


def leaves_axis(scene, motion) -> bool:
    """True when ``motion`` takes the ball off the axis by more than ``AXIS_FRACTION``
    of r_max (then the (z, r) surrogate is needed; otherwise the 1-D one is exact
    to far below its own error)."""
    radial = getattr(motion, "radial", None)
    if radial is None or np.asarray(radial).size == 0:
        return False
    return bool(np.max(np.asarray(radial, dtype=float)) > AXIS_FRACTION * max_offset(scene.device))


def held_out_error_zr(coarse: RadialTable, fine: RadialTable) -> tuple[float, float, float]:
    """``(all, along_z, along_r)``: largest relative deviation of ``coarse``'s
    interpolant from the direct solves at the points of ``fine`` not in ``coarse``
    (all of them; those whose offset is a coarse one; those whose gap is a coarse
    one). Over Q_SC, C_T, V_OC and both references, each relative to its largest
    magnitude on ``fine``; NaN where a group is empty."""
    zz, rr = np.meshgrid(fine.positions, fine.offsets, indexing="ij")
    old_z = np.isin(np.round(fine.positions * 1e13), np.round(coarse.positions * 1e13))
    old_r = np.isin(np.round(fine.offsets * 1e13), np.round(coarse.offsets * 1e13))
    old_z, old_r = np.meshgrid(old_z, old_r, indexing="ij")
    held = ~(old_z & old_r)
    groups = {"all": held, "z": held & old_r, "r": held & old_z}
    worst = {name: (0.0 if np.any(mask) else math.nan) for name, mask in groups.items()}
    for reference in terminals.REFERENCES:
        curves = RadialTerminalCurves(coarse, reference)
        q_fine, c_fine = terminal_grid(fine, reference)
        v_fine = q_fine / c_fine
        deviations = [(curves.charge(zz, rr), q_fine), (curves.capacitance(zz, rr), c_fine),
                      (curves.voltage(zz, rr), v_fine)]
        for interpolated, direct in deviations:
            scale = float(np.max(np.abs(direct)))
            if scale <= 0.0:
                continue
            relative = np.abs(interpolated - direct) / scale
            for name, mask in groups.items():
                if np.any(mask):
                    worst[name] = max(worst[name], float(np.max(relative[mask])))
    return worst["all"], worst["z"], worst["r"]


# ---------------------------------------------------------------------------
# the refinement
def radial_hash(scene, *, mesh_size_mm: float = DEFAULT_MESH_SIZE_MM,
                degree: int = DEFAULT_DEGREE, tolerance: float = DEFAULT_TOLERANCE) -> str:
    """SHA-256 of the scene's field inputs plus the (z, r) surrogate's own settings
    (the cache key of :func:`obtain_radial_table`)."""
    inputs = {"field": scene.field_inputs(),
              "zr": {"format": FORMAT_VERSION_ZR, "method": "3d",
                     "mesh_size_mm": float(mesh_size_mm), "degree": int(degree),
                     "tolerance": float(tolerance)}}
    return hashlib.sha256(json.dumps(inputs, sort_keys=True, default=float).encode()).hexdigest()


def _default_solver():
    from ..field import solve_position  # dolfinx/gmsh only load inside the solve
    return solve_position


def precompute_radial(scene, *, comm=None, solve=None, solve_comm=None,
                      mesh_size_mm: float = DEFAULT_MESH_SIZE_MM, degree: int = DEFAULT_DEGREE,
                      tolerance: float = DEFAULT_TOLERANCE,
                      initial_positions: int = INITIAL_POSITIONS,
                      initial_offsets: int = INITIAL_OFFSETS,
                      max_positions: int = MAX_POSITIONS_ZR, max_offsets: int = MAX_OFFSETS,
                      progress: bool = False, command_line: str = "",
                      field_error: str = "sampled") -> RadialTable:
    """Adaptive (z, r) table of 3D field solves for ``scene`` (module docstring).

    ``solve(scene, z, comm=..., offset=r, method="3d", mesh_size_mm=..., degree=...)``
    defaults to :func:`tengfield.field.solve_position` (given ``estimate_error=``
    when it takes it). ``comm`` spreads each round over its ranks (task farm,
    each solve on ``solve_comm``, default ``COMM_SELF``); every rank returns
    the same table. ``field_error``: "sampled" (the solver's own estimate at
    the middle and next to the ends of the stroke, on the axis and at the wall;
    the largest x (1 + FIELD_ERROR_MARGIN) elsewhere) or "every".
    """
    from .provenance import provenance, solver_fingerprint

    if solve is None:
        if scene.field.environment != "free-space":   # before any solve, on every rank
            from ..errors import FieldError
            raise FieldError(f"[field] environment = {scene.field.environment!r} is not "
                             "supported by the 3D solver of the (z, r) surrogate: allowed "
                             "'free-space'")
        solve = _default_solver()
    if solve_comm is None:
        from mpi4py import MPI
        solve_comm = MPI.COMM_SELF
    if field_error not in FIELD_ERROR_MODES:
        raise ValueError(f"field_error = {field_error!r}: choose one of {FIELD_ERROR_MODES}")
    nz, nr = int(initial_positions), int(initial_offsets)
    if not is_lobatto_count(nz):
        raise ValueError(f"initial_positions = {nz}: must be 2^k + 1 >= 3")
    if not (nr == 2 or is_lobatto_count(nr)):
        raise ValueError(f"initial_offsets = {nr}: must be 2 or 2^k + 1")
    if not (math.isfinite(tolerance) and tolerance > 0.0):
        raise ValueError(f"tolerance = {tolerance!r}: must be > 0")
    stroke = scene.device.stroke
    largest = max_offset(scene.device)
    if not largest > 0.0:
        raise SurrogateError(f"the ball fills the tube (tube inner radius - ball radius = "
                             f"{largest * 1e3:g} mm): no radial offset to tabulate")
    symmetric = is_mirror_symmetric(scene)
    sampled = field_error == "sampled" and _accepts_keyword(solve, "estimate_error")
    sample_z = error_sample_positions(stroke, symmetric, nz)
    sample_keys = {_key(z, r) for z in sample_z for r in (0.0, largest)}
    bar = None
    if progress and rank_of(comm) == 0:
        from tqdm import tqdm
        bar = tqdm(total=0, desc="3D field solves (z, r)", unit="solve", file=sys.stderr,
                   disable=not sys.stderr.isatty())

    def work(point):
        z, r = point
        kwargs = dict(comm=solve_comm, offset=float(r), method="3d",
                      mesh_size_mm=mesh_size_mm, degree=degree)
        if sampled:
            kwargs["estimate_error"] = _key(z, r) in sample_keys
        return solve(scene, float(z), **kwargs)

    def advance(n):
        if bar is not None:
            bar.update(n)

    solved: dict = {}
    measured = math.nan

    def solve_grid(positions, offsets) -> None:
        nonlocal measured
        todo_z = positions[positions <= 0.5 * stroke * (1 + 1e-12)] if symmetric else positions
        todo_z = todo_z[contact_first_order(todo_z, stroke)]
        todo = [(z, r) for z in todo_z for r in offsets[::-1] if _key(z, r) not in solved]
        if bar is not None:
            bar.total += len(todo)
            bar.refresh()
        results = farm(comm, todo, work, progress=advance)
        if sampled:
            results, measured = _sampled_field_errors(
                results, [_key(*p) in sample_keys for p in todo], measured)
        for (z, r), res in zip(todo, results):
            solved[_key(z, r)] = res
            if symmetric and not math.isclose(z, 0.5 * stroke, rel_tol=1e-12):
                solved[_key(stroke - z, r)] = mirrored(res, stroke)

    def grid(positions, offsets) -> RadialTable:
        return table_from_grid(solved, positions, offsets, stroke=stroke, largest_offset=largest)

    z_now, r_now = lobatto_positions(stroke, nz), offset_positions(largest, nr)
    z_next = np.sort(np.concatenate([z_now, refinement_positions(stroke, nz)]))
    r_next = np.sort(np.concatenate([r_now, offset_refinement(largest, nr)]))
    solve_grid(z_next, r_next)
    history: list[tuple[int, int, float]] = []
    error_z = error_r = math.inf
    while True:
        estimate, along_z, along_r = held_out_error_zr(grid(z_now, r_now), grid(z_next, r_next))
        error_z = along_z if not math.isnan(along_z) else error_z
        error_r = along_r if not math.isnan(along_r) else error_r
        history.append((z_now.size, r_now.size, estimate))
        z_now, r_now = z_next, r_next
        if estimate <= tolerance:
            break
        refine_z = error_z > tolerance or not error_r > tolerance
        refine_r = error_r > tolerance or not error_z > tolerance
        refine_z &= 2 * z_now.size - 1 <= max_positions
        refine_r &= 2 * r_now.size - 1 <= max_offsets
        if not (refine_z or refine_r):
            break
        if refine_z:
            z_next = np.sort(np.concatenate([z_now, refinement_positions(stroke, z_now.size)]))
        if refine_r:
            r_next = np.sort(np.concatenate([r_now, offset_refinement(largest, r_now.size)]))
        solve_grid(z_next, r_next)
    if bar is not None:
        bar.close()
    rule = (_field_error_rule(sample_z, f" on the axis and at r = {largest:.6g} m", "elsewhere")
            if sampled else "measured at every point")
    table = grid(z_now, r_now)
    table = dataclasses.replace(
        table, interpolation_error=estimate, tolerance=float(tolerance),
        converged=bool(estimate <= tolerance),
        error_history=history, degree=int(degree), mesh_size=float(mesh_size_mm) * 1e-3,
        field_hash=radial_hash(scene, mesh_size_mm=mesh_size_mm, degree=degree,
                               tolerance=tolerance),
        provenance={**provenance(scene, command_line), "mirror_symmetry": symmetric,
                    "field_error_rule": rule, "solver_fingerprint": solver_fingerprint(),
                    "kind": "zr"})
    warn_problems(radial_accuracy_problems(table), comm, stacklevel=2)
    return table


def radial_accuracy_problems(table: RadialTable) -> list[str]:
    """The interpolation error estimate of ``table`` above its tolerance, as one line (the
    (z, r) tolerance is an interpolation target below the 3D field error, so the field
    error is not held to it)."""
    if not table.interpolation_error > table.tolerance:
        return []
    nz, nr = table.shape
    return [f"(z, r) surrogate: interpolation error estimate {table.interpolation_error:.3g} "
            f"is above the tolerance {table.tolerance:g} after {nz} x {nr} points"]


# ---------------------------------------------------------------------------
# checks, file and cache
def _check_grid_shapes(arrays: dict, nz: int, nr: int) -> None:
    """Raise :class:`SurrogateError` unless each per-point array of ``arrays`` (table
    attribute -> array) has the shape ``(nz, nr, *tail)`` of :data:`_GRID_TAILS`."""
    for attr, tail in _GRID_TAILS.items():
        shape = np.shape(arrays[attr])
        if shape != (nz, nr, *tail):
            raise SurrogateError(f"array {ARRAYS_ZR[attr]!r} has shape {shape}, expected "
                                 f"{(nz, nr, *tail)}")


def check_radial_table(table: RadialTable) -> None:
    """Raise :class:`SurrogateError` (reason only) unless ``table`` makes sense:
    shapes, offsets strictly ascending from 0 to ``max_offset``, and every
    offset's column passing :func:`tengfield.surrogate.check_table`."""
    from .store import check_axis, check_table

    nz, nr = table.shape
    _check_grid_shapes({attr: getattr(table, attr) for attr in _GRID_TAILS}, nz, nr)
    r = table.offsets
    check_axis(r, float(table.max_offset), "offset", "max offset")
    z = table.positions
    if z.ndim != 1 or not np.all(np.diff(z) > 0.0):
        raise SurrogateError("positions are not strictly ascending")
    for j in range(nr):
        try:
            check_table(table.column(j))
        except SurrogateError as exc:
            raise SurrogateError(f"at offset r = {r[j]:.6g} m: {exc.reason}") from None


def write_radial_table(path, table: RadialTable) -> Path:
    """Write ``table`` to HDF5 atomically with the 1-D surrogate's checksums
    (:func:`tengfield.surrogate.store.write_checked_file`). Raises ``OSError`` if it
    cannot (nothing is left behind)."""
    from .store import typed_scalars, write_checked_file

    arrays = {name: np.asarray(getattr(table, attr)) for attr, name in ARRAYS_ZR.items()}
    arrays["error_history"] = np.asarray(table.error_history, dtype=float).reshape(-1, 3)
    scalars = typed_scalars(vars(table), SCALAR_TYPES_ZR)
    return write_checked_file(path, arrays, scalars, SCALARS_ZR, {
        "format_version": FORMAT_VERSION_ZR, "kind": "zr",
        "provenance": json.dumps(table.provenance, default=str)})


def _check_format_zr(attrs) -> None:
    version = attrs.get("format_version")
    if str(attrs.get("kind", "")) != "zr" or version is None or int(version) != FORMAT_VERSION_ZR:
        raise SurrogateError(f"is not a (z, r) surrogate of format {FORMAT_VERSION_ZR} "
                             f"(kind {attrs.get('kind')!r}, format {version!r})")


def _build_radial_table(arrays: dict, history, scalars: dict,
                        provenance_data: dict) -> RadialTable:
    _check_grid_shapes(arrays, np.shape(arrays["positions"])[0], np.shape(arrays["offsets"])[0])
    if history.ndim != 2 or history.shape[1] != 3:
        raise SurrogateError(f"error history has shape {history.shape}")
    table = RadialTable(**arrays, **scalars, provenance=provenance_data,
                        error_history=[(int(a), int(b), float(e))
                                       for a, b, e in history.tolist()])
    check_radial_table(table)
    return table


def read_radial_table(path, expected_hash: str | None = None,
                      expected_solver: str | None = None) -> RadialTable:
    """Read a (z, r) surrogate file; raise :class:`SurrogateError` unless it is
    complete, of this format, unchanged (checksums), sensible
    (:func:`check_radial_table`) and (if given) for ``expected_hash``
    (:func:`radial_hash`) and the solver ``expected_solver``
    (:func:`tengfield.surrogate.store.read_checked_file`)."""
    from .store import read_checked_file

    return read_checked_file(path, check_format=_check_format_zr, array_names=ARRAYS_ZR,
                             scalar_names=SCALARS_ZR, scalar_types=SCALAR_TYPES_ZR,
                             build=_build_radial_table, expected_hash=expected_hash,
                             expected_solver=expected_solver, hash_label="hash")


def radial_cache_path(scene, cache_dir=None, **settings) -> Path:
    """Where the (z, r) surrogate of ``scene`` lives in the cache."""
    from .cache import default_cache_dir

    directory = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    return directory / f"surrogate-zr-{radial_hash(scene, **settings)[:24]}.h5"


def obtain_radial_table(scene, *, cache_dir=None, comm=None, solve=None, progress: bool = False,
                        command_line: str = "", write: bool = True,
                        mesh_size_mm: float = DEFAULT_MESH_SIZE_MM, degree: int = DEFAULT_DEGREE,
                        tolerance: float = DEFAULT_TOLERANCE, **refinement):
    """The cached (z, r) surrogate of ``scene`` if trusted, else a new one:
    ``(RadialTable, CacheOutcome)``, the rules of
    :func:`tengfield.surrogate.obtain_table` (rank 0 decides and broadcasts;
    an untrusted file is recomputed with a warning; an unwritable cache costs a
    warning). ``refinement``: further keywords of :func:`precompute_radial`."""
    from .cache import CacheOutcome, load_cached, store_in_cache
    from .provenance import solver_fingerprint

    start = time.perf_counter()
    settings = {"mesh_size_mm": mesh_size_mm, "degree": degree, "tolerance": tolerance}
    path = radial_cache_path(scene, cache_dir, **settings)
    key = radial_hash(scene, **settings)
    table, status, reason = load_cached(
        path, scene, comm,
        read=lambda p: read_radial_table(p, expected_hash=key,
                                         expected_solver=solver_fingerprint()))
    if table is not None:
        warn_problems(radial_accuracy_problems(table), comm, stacklevel=2)
        return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start)
    table = precompute_radial(scene, comm=comm, solve=solve, progress=progress,
                              command_line=command_line, **settings, **refinement)
    stored = store_in_cache(path, table, comm, write=write_radial_table) if write else False
    return table, CacheOutcome(status, reason, str(path), time.perf_counter() - start, stored)


def axis_check(table: RadialTable, axis_table: SurrogateTable) -> dict:
    """Compare the r = 0 column of ``table`` with the axisymmetric surrogate ``axis_table``.

    Returns ``deviation``: the largest relative difference of Q_SC and C_T
    (both references, each relative to its largest magnitude) at the (z, r)
    table's gaps, and ``allowed``: the sum of both tables' largest field error
    estimates and the axisymmetric interpolation error; ``ok`` = deviation <= allowed.
    """
    from .table import TerminalCurves

    z = table.positions
    deviation = 0.0
    for reference in terminals.REFERENCES:
        q_grid, c_grid = terminal_grid(table, reference)
        axis = TerminalCurves(axis_table, reference)
        for ours, theirs in ((q_grid[:, 0], axis.charge(z)), (c_grid[:, 0], axis.capacitance(z))):
            scale = float(np.max(np.abs(theirs)))
            if scale > 0.0:
                deviation = max(deviation, float(np.max(np.abs(ours - theirs)) / scale))
    axis_interp = axis_table.interpolation_error
    allowed = float(np.nanmax(table.field_error[:, 0])) + float(np.nanmax(axis_table.field_error)) \
        + (float(axis_interp) if math.isfinite(axis_interp) else 0.0)
    return {"deviation": deviation, "allowed": allowed, "ok": deviation <= allowed}
