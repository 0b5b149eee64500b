"""One 3D mesh per geometry, moved with the ball (issue #40; ``[field] mesh_motion = "move"``
for the 3D solves: the spherical shell's (z, r) table, the tube's and the honeycomb's).

The 3D positions of one table share reference meshes: the ball is placed at centre ``c``
by moving the mesh nodes by ``δ · w(x)`` with ``δ = c - c_ref`` (the ball's displacement
from the reference's centre) and the blending weight of :mod:`.moving`, in 3D

    w = d_fixed / (d_fixed + d_ball)   inside the cavity, 0 outside it,

``d_ball`` the distance to the ball (0 in it: the ball moves rigidly), ``d_fixed`` the
distance to the cavity's walls (the shell's cavity sphere ``|x| = a``; the tube's and the
honeycomb's electrode planes ``z = ±h/2`` and bore), so the electrodes, the walls, the
shell, the far sphere (and with it the Kelvin/DtN harmonics) do not move. The same
compiled forms, dofs and sparsity are reused: on a move only the operator (into the same
matrix, :func:`~tengfield.field._dolfinx.assemble_matrix_into`) and the lifted right-hand
sides are assembled again, and the reference's CG + BoomerAMG solver (its own options
prefix, created once) sets its preconditioner up on the new values (0.09 s of a 3.8 s
solve of the 10 mm shell: docs/field3d.md; every solve starts from zero, so the numbers
do not depend on the order of the solves).

The reference of a position is a function of the position alone (so a table's numbers do
not depend on the order of its solves or on the ranks):

* spherical shell: the ball-wall gap ``g = R - |c|`` (R = a - d/2) on a ladder
  (:func:`shell_rung`: g_min, 4 g_min, 16 g_min, ... below R/2, and R, the ball at the
  cavity's centre), and the direction of ``c`` (its polar angle from -z) on steps of
  about ``g_rung / R`` rad (a step of the rung's gap along the wall; one direction at the
  centre; the position's own direction at the contact anchors' rungs g_min and 4 g_min,
  so the anchors are meshed or stretched along their radius, never slid), at the
  position's own azimuth;
* tube and honeycomb: the nearer plate's gap on the ladder of
  :func:`tengfield.field.moving.reference_position`, at the position's own
  offset and angle (one reference per offset r, per rung).

A move is accepted only if every tetrahedron keeps its orientation, its volume changes by
at most :data:`~tengfield.field.moving.QUALITY_BOUND` (either way) and its shape quality
(the mean ratio, 1 for a regular tetrahedron) falls by at most that factor against the
reference mesh; otherwise the position is meshed on its own (gmsh, as ``"remesh"``).
Each solve says how its meshes were placed (``info["mesh_placements"]``), a table sums
them; :data:`COUNTS` says how often each happened in this process.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, replace
from types import SimpleNamespace
from typing import Any

import numpy as np

from . import contact
from .moving import LADDER_FACTOR, QUALITY_BOUND, reference_position

#: reference meshes (with their solvers) kept in this process, the least recently used
#: released first (a 10 mm shell at P2 / 1.5 mm: ~54k dofs each)
MAX_REFERENCES = 12
#: the direction step of the shell's references, in units of the rung's gap over R
DIRECTION_STEP = 1.0
#: the shell's rungs up to this many g_min (the contact anchors' scale) sit at the
#: position's own direction: the contact rule's anchors are never slid along the wall
CONTACT_RUNGS = 4.0
#: positions placed by moving a reference mesh, and gmsh meshings (references and the
#: positions a move would have spoilt)
COUNTS = {"moved": 0, "meshed": 0}

_references: OrderedDict = OrderedDict()


# -- geometry ---------------------------------------------------------------------------
def _is_shell(cell) -> bool:
    return hasattr(cell, "cavity_radius")


def fixed_distance(cell, x: np.ndarray) -> np.ndarray:
    """Distance [m] of the points ``x`` (n, 3) to the cavity's walls, <= 0 outside the
    cavity: the shell's sphere ``|x| = a``; a plate cell's electrode planes and bore
    (round: ``tube_inner_radius``; hexagonal: ``inner_apothem`` to the flats)."""
    if _is_shell(cell):
        return cell.cavity_radius - np.linalg.norm(x, axis=1)
    half = 0.5 * cell.electrode_spacing
    if hasattr(cell, "inner_apothem"):
        c = math.cos(math.pi / 6)
        across = np.maximum.reduce([np.abs(x[:, 1]), np.abs(0.5 * x[:, 1] + c * x[:, 0]),
                                    np.abs(0.5 * x[:, 1] - c * x[:, 0])])
        lateral = cell.inner_apothem - across
    else:
        lateral = cell.tube_inner_radius - np.hypot(x[:, 0], x[:, 1])
    return np.minimum.reduce([x[:, 2] + half, half - x[:, 2], lateral])


def blending_weight(cell, x: np.ndarray, centre) -> np.ndarray:
    """w(x) for the geometry nodes ``x`` (n, 3) [m] of ``cell`` with the ball at ``centre``:
    1 in the ball, 0 on and beyond the cavity's walls (within 1e-9 of the electrode
    spacing: a wall node meshed off the sphere by rounding does not move either),
    ``d_fixed / (d_fixed + d_ball)`` between."""
    d_fixed = fixed_distance(cell, x)
    d_ball = np.maximum(np.linalg.norm(x - np.asarray(centre, dtype=float), axis=1)
                        - 0.5 * cell.ball_diameter, 0.0)
    w = np.zeros(len(x))
    inside = d_fixed > 1e-9 * cell.electrode_spacing   # nodes on a wall (to rounding) stay
    w[inside] = d_fixed[inside] / (d_fixed[inside] + d_ball[inside])
    return w


def tetrahedron_measures(x: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(signed volumes [m³], mean-ratio shape quality in (0, 1]) of the tetrahedra ``tets``
    (cells, 4) with vertex coordinates in ``x``."""
    p = [x[tets[:, k]] for k in range(4)]
    e1, e2, e3 = p[1] - p[0], p[2] - p[0], p[3] - p[0]
    volume = np.einsum("ij,ij->i", e1, np.cross(e2, e3)) / 6.0
    edges = (e1, e2, e3, p[2] - p[1], p[3] - p[1], p[3] - p[2])
    squares = sum(np.einsum("ij,ij->i", e, e) for e in edges)
    quality = 12.0 * np.cbrt(3.0 * np.abs(volume)) ** 2 / squares
    return volume, quality


def shell_rung(gap: float, minimum_gap: float, top: float) -> float:
    """The shell's reference gap [m] for a ball-wall ``gap``: the ladder
    ``g_min · LADDER_FACTOR^k`` below ``top / 2`` and ``top`` (R: the ball at the cavity's
    centre), the rung nearest in ratio."""
    ladder, rung = [], minimum_gap
    while rung < 0.5 * top:
        ladder.append(rung)
        rung *= LADDER_FACTOR
    ladder.append(top)
    near = max(gap, minimum_gap)
    return min(ladder, key=lambda rung: abs(math.log(near / rung)))


def reference_centre(cell, centre: np.ndarray, offset_angle: float) -> tuple[tuple, np.ndarray]:
    """``(key, c_ref)``: the reference a ball at (meshed) ``centre`` [m] is moved from (the
    module docstring's rule; a function of the position alone)."""
    g_min = contact.minimum_gap(cell.electrode_spacing)
    c = np.asarray(centre, dtype=float)
    if _is_shell(cell):
        big_r = cell.cavity_radius - cell.ball_radius
        gap = big_r - float(np.linalg.norm(c))
        rung = shell_rung(gap, g_min, big_r)
        if rung >= big_r * (1 - 1e-9):
            return ("shell", round(rung / g_min, 6)), np.zeros(3)
        theta = math.atan2(math.hypot(c[0], c[1]), -c[2])
        if rung <= CONTACT_RUNGS * g_min * (1 + 1e-9):
            # the contact rule's anchors (g_min, 2 g_min, 4 g_min along one radius): their
            # references at the anchors' own direction, the middle one stretched radially
            k, steps, theta_ref = round(theta, 12), 0, theta
        else:
            steps = math.ceil(math.pi / min(0.5 * math.pi, DIRECTION_STEP * rung / big_r))
            k = int(round(theta / (math.pi / steps)))
            theta_ref = k * math.pi / steps
        phi = math.atan2(c[1], c[0]) if math.hypot(c[0], c[1]) > 0.0 else offset_angle
        rho = big_r - rung
        ref = np.array([rho * math.sin(theta_ref) * math.cos(phi),
                        rho * math.sin(theta_ref) * math.sin(phi), -rho * math.cos(theta_ref)])
        return ("shell", round(rung / g_min, 6), k, steps, round(phi, 9)), ref
    half = 0.5 * cell.electrode_spacing
    z_gap = c[2] + half - 0.5 * cell.ball_diameter
    z_ref = reference_position(SimpleNamespace(gap_lower=z_gap, gap_upper=cell.stroke - z_gap),
                               g_min)
    ref = np.array([c[0], c[1], -half + z_ref + 0.5 * cell.ball_diameter])
    return ("plates", round(z_ref / g_min, 6), round(float(c[0]), 12),
            round(float(c[1]), 12)), ref


def _position_of(cell, centre: np.ndarray) -> tuple[float, float, float]:
    """(position z [m], offset [m], offset angle [rad]) that put the ball at ``centre``."""
    offset = math.hypot(centre[0], centre[1])
    angle = math.atan2(centre[1], centre[0]) if offset > 0.0 else 0.0
    if _is_shell(cell):
        return float(centre[2] + cell.cavity_radius - cell.ball_radius), offset, angle
    return float(centre[2] + 0.5 * cell.electrode_spacing - 0.5 * cell.ball_diameter), \
        offset, angle


# -- the discretised problem kept with a reference ---------------------------------------
class Problem:
    """The weighting-potential problem of one mesh, set up once: function space, compiled
    forms, Dirichlet dofs, the matrix (the far field's harmonic vectors for "kelvin") and
    a CG + BoomerAMG solver under its own options prefix. :meth:`solve` assembles the
    operator into the same matrix and solves both potentials on the mesh as it is now."""

    def __init__(self, cell_mesh, permittivity: dict, settings):
        from . import _dolfinx as dx_api
        from .solver3d import AMG_OPTIONS, _LowRankUpdate, permittivity_function, \
            sphere_harmonics

        ufl = dx_api.ufl
        self.cell_mesh, self.settings = cell_mesh, settings
        mesh = cell_mesh.mesh
        self.space = dx_api.lagrange_space(mesh, settings.degree)
        eps_r = permittivity_function(cell_mesh, permittivity)
        u, v = ufl.TrialFunction(self.space), ufl.TestFunction(self.space)
        _, ds, _ = dx_api.measures(mesh, cell_mesh.cell_tags, cell_mesh.facet_tags)
        far_tag = cell_mesh.groups["far_boundary"]
        a = eps_r * ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
        if settings.far_field in ("robin", "kelvin"):
            a = a + dx_api.constant(mesh, 1.0 / settings.domain_radius) * u * v * ds(far_tag)
        self.rhs = dx_api.form(ufl.inner(dx_api.constant(mesh, 0.0), v) * ufl.dx)
        self.bilinear = dx_api.form(a)
        self.conductors = [f"electrode_{name}" for name in cell_mesh.electrodes]
        dofs = {name: dx_api.facet_dofs(self.space, cell_mesh.facet_tags, cell_mesh.groups[name])
                for name in self.conductors}
        if settings.far_field == "dirichlet":
            dofs["far_boundary"] = dx_api.facet_dofs(self.space, cell_mesh.facet_tags, far_tag)
        self.bcs = {active: [dx_api.dirichlet_bc(self.space, 1.0 if name == active else 0.0, d)
                             for name, d in dofs.items()]
                    for active in self.conductors}
        self.matrix = dx_api.assemble_matrix(self.bilinear, bcs=self.bcs[self.conductors[0]])
        self.operator, self.harmonics, self.weights = self.matrix, [], np.empty(0)
        if settings.far_field == "kelvin":   # the far sphere does not move: assembled once
            x = ufl.SpatialCoordinate(mesh)
            weights = []
            for degree_l, harmonic in sphere_harmonics(x):
                self.harmonics.append(dx_api.assemble_vector(dx_api.form(harmonic * v
                                                                         * ds(far_tag))))
                norm = dx_api.assemble_scalar(dx_api.form(harmonic * harmonic * ds(far_tag)),
                                              mesh.comm)
                weights.append(degree_l / (settings.domain_radius * norm))
            self.weights = np.array(weights)
            self.operator = dx_api.python_matrix(
                mesh.comm, self.matrix.getSizes(),
                _LowRankUpdate(self.matrix, self.harmonics, self.weights))
        self.prefix = dx_api.unique_prefix("3d_moving")
        self.ksp = dx_api.create_ksp(mesh.comm, self.operator, prefix=self.prefix,
                                     kind="cg-amg", rtol=1e-10,
                                     preconditioner_matrix=self.matrix, options=AMG_OPTIONS)
        self.assembled = True

    def reassemble(self) -> None:
        """The operator on the mesh as it is now (same matrix, same sparsity); the solver's
        preconditioner is set up again at the next solve."""
        from . import _dolfinx as dx_api

        dx_api.assemble_matrix_into(self.matrix, self.bilinear, self.bcs[self.conductors[0]])
        self.assembled = False

    def solve(self):
        """:class:`~tengfield.field.solver3d.WeightingPotentials` on the mesh as it is now."""
        import time

        from . import _dolfinx as dx_api
        from ..errors import FieldError
        from .solver3d import WeightingPotentials

        start = time.perf_counter()
        if not self.assembled:   # the preconditioner on the new values
            self.ksp.setOperators(self.operator, self.matrix)
            self.ksp.setUp()
            self.assembled = True
        potentials, iterations, moments = [], [], []
        for active in self.conductors:
            b = dx_api.assemble_vector(self.rhs, self.bilinear, self.bcs[active])
            psi = dx_api.function(self.space, name=f"psi_{active.split('_')[1]}")
            try:
                dx_api.solve(self.ksp, b, dx_api.petsc_vector(psi))
            except dx_api.PETSc.Error as exc:
                raise FieldError(f"3D solve for {active} did not converge (reason "
                                 f"{self.ksp.getConvergedReason()}): {exc}") from None
            finally:
                b.destroy()
            psi.x.scatter_forward()
            potentials.append(psi)
            moments.append([u.dot(dx_api.petsc_vector(psi)) for u in self.harmonics])
            iterations.append(self.ksp.getIterationNumber())
        return WeightingPotentials(
            functions=tuple(potentials), dofs=dx_api.num_dofs(self.space),
            cells=dx_api.num_cells(self.cell_mesh.mesh), iterations=tuple(iterations),
            assembly_time=0.0, solve_time=time.perf_counter() - start,
            harmonic_moments=np.array(moments).reshape(len(potentials), -1),
            harmonic_weights=np.asarray(self.weights))

    def release(self) -> None:
        """Destroy the solver, the matrices and vectors (and the solver's PETSc options)."""
        from . import _dolfinx as dx_api

        self.ksp.destroy()
        if self.operator is not self.matrix:
            self.operator.destroy()
        self.matrix.destroy()
        for vec in self.harmonics:
            vec.destroy()
        dx_api.clear_options(self.prefix)


@dataclass
class Reference:
    """A meshed 3D cell, its problem and what moving it needs."""
    cell_mesh: Any           # solver3d.CellMesh (its mesh is moved in place)
    problem: Problem
    x0: np.ndarray           # the geometry nodes as meshed [m]
    weight: np.ndarray       # blending weight per geometry node
    tets: np.ndarray         # (local cells, 4) vertex nodes
    volume0: np.ndarray      # signed volumes as meshed [m³]
    quality0: np.ndarray     # mean-ratio quality as meshed
    centre: np.ndarray       # the ball centre as meshed [m]
    placed_at: np.ndarray    # the ball centre now [m]


def quality_ok(ref: Reference, shift: np.ndarray, comm) -> bool:
    """Whether moving ``ref``'s ball by ``shift`` (3,) [m] keeps every tetrahedron's
    orientation, its volume within :data:`QUALITY_BOUND` of the reference's either way
    and its mean-ratio quality above the reference's / :data:`QUALITY_BOUND` (collective
    over ``comm``)."""
    x = ref.x0 + ref.weight[:, None] * np.asarray(shift, dtype=float)[None, :]
    volume, quality = tetrahedron_measures(x, ref.tets)
    ratio = volume / ref.volume0
    local = bool(np.all(ratio > 1.0 / QUALITY_BOUND) and np.all(ratio < QUALITY_BOUND)
                 and np.all(quality * QUALITY_BOUND > ref.quality0))
    from mpi4py import MPI
    return bool(comm.allreduce(local, op=MPI.LAND))


def _new_reference(cell, centre_ref, offset_angle, settings, coarsen, comm) -> Reference:
    from . import _dolfinx as dx_api
    from .solver3d import cell_permittivity, mesh_cell

    position, offset, angle = _position_of(cell, centre_ref)
    cell_mesh = mesh_cell(cell, position, offset, settings.mesh_settings(coarsen), comm=comm,
                          offset_angle=angle if offset > 0.0 else offset_angle)
    problem = Problem(cell_mesh, cell_permittivity(cell), settings)
    x0 = np.array(cell_mesh.mesh.geometry.x[:, :3], copy=True)
    tets = dx_api.cell_vertex_nodes(cell_mesh.mesh, 4)
    volume0, quality0 = tetrahedron_measures(x0, tets)
    centre = np.asarray(cell_mesh.ball_centre, dtype=float)
    return Reference(cell_mesh=cell_mesh, problem=problem, x0=x0,
                     weight=blending_weight(cell, x0, centre), tets=tets, volume0=volume0,
                     quality0=quality0, centre=centre, placed_at=centre.copy())


def solve_cell(cell, position: float, offset: float, settings, *, comm, coarsen: float = 1.0,
               offset_angle: float = 0.0):
    """:func:`tengfield.field.solver3d.solve_cell` on a reference mesh moved to the
    position (meshed on first use), or on a mesh of its own when the move would spoil the
    reference's quality; the result's ``placement`` is ``{"moved": n, "meshed": m}``."""
    from .solver3d import (CellSolution, ball_surface_means, capacitance_matrix,
                           cell_permittivity, solve_cell as remeshed)

    centre, gap = cell.placement_3d(position, offset, offset_angle)
    centre = np.asarray(centre, dtype=float)
    slot, centre_ref = reference_centre(cell, centre, offset_angle)
    key = (cell, settings.mesh_settings(coarsen), settings.degree, settings.far_field,
           comm.py2f(), comm.size) + slot
    ref = _references.get(key)
    fresh = ref is None
    if fresh:
        ref = _new_reference(cell, centre_ref, offset_angle, settings, coarsen, comm)
        _references[key] = ref
        while len(_references) > MAX_REFERENCES:
            _references.popitem(last=False)[1].problem.release()
    _references.move_to_end(key)
    shift = centre - ref.centre
    moved = bool(np.any(shift != 0.0))
    if moved and not quality_ok(ref, shift, comm):   # the move would spoil the mesh
        COUNTS["meshed"] += 1 + int(fresh)
        sol = remeshed(cell, position, offset, settings, comm=comm, coarsen=coarsen,
                       offset_angle=offset_angle)
        sol.placement = {"moved": 0, "meshed": 1 + int(fresh)}
        return sol
    if np.any(ref.placed_at != centre):
        x = ref.cell_mesh.mesh.geometry.x
        x[:, :3] = ref.x0 + ref.weight[:, None] * shift[None, :]
        ref.problem.reassemble()
        ref.placed_at = centre.copy()
    COUNTS["meshed"] += int(fresh)
    COUNTS["moved"] += int(moved)
    cell_mesh = replace(ref.cell_mesh, ball_centre=centre, meshed_gap=float(gap),
                        mesh_time=ref.cell_mesh.mesh_time if fresh else 0.0,
                        meshed_offset=float(math.hypot(centre[0], centre[1])))
    permittivity = cell_permittivity(cell)
    potentials = ref.problem.solve()
    cap = capacitance_matrix(cell_mesh, potentials, permittivity,
                             far_field=settings.far_field, domain_radius=settings.domain_radius)
    sol = CellSolution(capacitance=cap, induced_fraction=-ball_surface_means(cell_mesh, potentials),
                       cell_mesh=cell_mesh, potentials=potentials)
    sol.placement = {"moved": int(moved), "meshed": int(fresh)}
    return sol


def placer(mesh_motion: str):
    """The ``solve_one`` of :func:`tengfield.field.solver3d.solve_cell_3d` for ``[field]
    mesh_motion``: :func:`solve_cell` for "move", None (gmsh at every position) for
    "remesh"."""
    return solve_cell if mesh_motion == "move" else None


def release_references() -> None:
    """Forget every reference mesh, their solvers destroyed (a table is done)."""
    while _references:
        _references.popitem(last=False)[1].problem.release()


def clear() -> None:
    """Forget every reference mesh (their solvers destroyed) and the counts."""
    release_references()
    COUNTS.update(moved=0, meshed=0)
