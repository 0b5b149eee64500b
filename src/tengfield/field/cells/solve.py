"""The axisymmetric solve of any :class:`~tengfield.field.cells.Cell` with the ball on
its axis: the cell builds the gmsh model, the tube's solver does the rest.

The cell's model carries the tube's physical groups, so this module reuses
:func:`tengfield.field.axisymmetric.discretise` (floating-potential weighting
solves ψ_lower, ψ_upper, the ball's σ source, the far field: ``kelvin``,
``robin`` or ``dirichlet``) and ``solve_discretisation`` (one LDLᵀ factorisation
per mesh under its own PETSc options prefix) unchanged, and the contact rule of
:mod:`tengfield.field.contact` (positions closer than g to the wall are
extrapolated from gaps g, 2g, 4g). The result is the tube's
:class:`~tengfield.field.result.PositionResult`: C_ll, C_lu, C_uu, q_lower,
q_upper, with the Richardson error estimate of a half-size mesh of the same
family (``estimate_error``).

Settings are passed explicitly (the scene has no cell shapes yet):
``sigma`` [C/m²] the ball's surface charge, ``mesh_size`` [m], ``degree``,
``far_field``, ``domain_radius`` [m] (default: the cell's).

As the tube's solve, it runs on rank 0 of ``comm`` (on COMM_SELF) and the
result is broadcast to every rank.
"""
from __future__ import annotations

import math
import time

from ...errors import FieldError, show_number
from ...scene.constants import EPS0
from .. import contact
from ..axisymmetric import (discretise, field_solution, mesh_model, richardson_error,
                            solve_by_contact_rule, solve_discretisation, solved_on_rank_zero)
from ..geometry_axisymmetric import FACET_TAGS
from ..result import PositionResult

#: options of :func:`solve_cell_position` besides the cell and the position
SOLVER_OPTIONS = ("sigma", "mesh_size", "degree", "far_field", "domain_radius",
                  "estimate_error", "source_solve", "linear_solver", "grading_size",
                  "breakdown_lines", "keep_solution", "mesh_motion")


def build_mesh(cell, position: float, comm, *, mesh_size: float, degree: int,
               far_field: str, domain_radius: float | None, grading_size: float | None = None):
    """(layout, mesh, cell_tags, facet_tags) of ``cell`` with the ball at ``position``."""
    lay = cell.axisymmetric_layout(position, mesh_size=mesh_size, degree=degree,
                                   domain_radius=domain_radius, far_field=far_field,
                                   grading_size=grading_size)

    def failure(exc) -> str:
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:160]
        return (f"gmsh could not mesh the {cell.name} cell ({first}): check its dimensions "
                f"and [field] mesh_size_mm = {mesh_size * 1e3:g}")

    mesh, cell_tags, facet_tags = mesh_model(
        lambda gmsh: cell.build_axisymmetric_model(gmsh, lay, geometry_order=2), comm, failure)
    return lay, mesh, cell_tags, facet_tags


def far_field_charge(dx_api, disc, potential, lay, far_field: str) -> float:
    """Charge [C] that the field of ``potential`` (a full dof vector [V]) carries to
    infinity, ``-ε0 ∮_{|x|=R} ∂φ/∂n dA``, with the Robin condition ``∂φ/∂n = -κφ/R``
    (κ = 1, the monopole far field): ``ε0 (κ/R) ∮ φ dA``. Only for ``far_field =
    "robin"`` (Kelvin's exterior flux is not a boundary integral)."""
    if far_field != "robin":
        raise FieldError("far_field_charge needs far_field = 'robin'")
    ufl = dx_api.ufl
    phi = dx_api.function(disc.V, potential)
    _, ds, _ = dx_api.measures(disc.mesh, disc.cell_tags, disc.facet_tags)
    r = ufl.SpatialCoordinate(disc.mesh)[0]
    flux = dx_api.assemble_scalar(dx_api.form(phi * r * ds(FACET_TAGS["far_boundary"])),
                                  disc.mesh.comm)
    return 2.0 * math.pi * EPS0 * flux / lay.domain_radius


def _solve_meshed(cell, position: float, comm, *, sigma: float, mesh_size: float, degree: int,
                  far_field: str, domain_radius: float | None, estimate_error: bool,
                  source_solve: bool, linear_solver: str, grading_size: float | None,
                  breakdown_lines: bool = False, keep_solution: bool = False,
                  mesh_motion: str = "remesh") -> PositionResult:
    """One solve of the meshable ``position`` (one process)."""
    from .. import _dolfinx as dx_api

    t0 = time.perf_counter()
    eps = {"ball": cell.ball_permittivity, "walls": cell.wall_permittivity, "air": 1.0,
           "exterior": 1.0}
    common = dict(degree=degree, far_field=far_field, domain_radius=domain_radius)
    moving = mesh_motion == "move" and not keep_solution

    def discretised(size, grading):
        """(layout, Discretisation): meshed, or a reference mesh moved (field/moving.py)."""
        def meshed(z):
            lay, *mesh = build_mesh(cell, z, comm, mesh_size=size, grading_size=grading,
                                    **common)
            return lay, discretise(dx_api, *mesh, lay, eps, degree, far_field)

        def layout_at(z):
            return cell.axisymmetric_layout(z, mesh_size=size, grading_size=grading, **common)
        if not moving:
            return meshed(position)
        from .. import moving as motion
        from ..axisymmetric import reassemble
        key = (repr(cell), size, grading, degree, far_field, domain_radius)
        lay = layout_at(position)
        settings = dict(cell=type(cell).__name__, degree=degree, far_field=far_field,
                        grading_size=grading)
        family = motion.geometry_family(lay, permittivity=eps, **settings)

        def canonical(rung):
            """The canonical cell at ``rung``: (key, layout, family, mesh()) or None."""
            other = cell.canonical()
            if other is None:
                return None
            z = motion.rung_gap(other.stroke, contact.minimum_gap(other.electrode_spacing),
                                rung)
            if z is None:
                return None
            options = dict(common, domain_radius=motion.canonical_domain_radius(
                lay.domain_radius, far_field))
            try:
                lay_c = other.axisymmetric_layout(z, mesh_size=size, grading_size=grading,
                                                  **options)
            except FieldError:
                return None

            def mesh():
                lay_m, *mesh_c = build_mesh(other, z, comm, mesh_size=size,
                                            grading_size=grading, **options)
                return discretise(dx_api, *mesh_c, lay_m, eps, degree, far_field)
            return ((repr(other), size, grading, tuple(sorted(options.items())), z), lay_c,
                    motion.geometry_family(lay_c, permittivity=eps, **settings), mesh)
        return motion.placed(key, lay, layout_at, lambda z: meshed(z)[1],
                             lambda disc: reassemble(dx_api, disc), dx_api,
                             minimum_gap=contact.minimum_gap(cell.electrode_spacing),
                             family=family, canonical=canonical)

    lay, disc = discretised(mesh_size, grading_size)
    mesh = disc.mesh
    sol = solve_discretisation(dx_api, disc, sigma, cell.ball_diameter,
                               source_solve=source_solve, linear_solver=linear_solver,
                               unit_source=breakdown_lines)
    estimate = math.nan
    lines_check = None
    finer = None
    if estimate_error:   # half the size, the coarse mesh's grading lengths: one family
        lay_half, finer = discretised(0.5 * mesh_size, grading_size or mesh_size)
        fine = solve_discretisation(dx_api, finer, sigma, cell.ball_diameter,
                                    source_solve=False, linear_solver=linear_solver,
                                    unit_source=breakdown_lines)
        estimate = richardson_error(contact.relative_change(sol, fine), degree)
        if breakdown_lines:   # the lines on the half-size mesh: their error estimate
            from ..breakdown import line_basis
            lines_check = line_basis(dx_api, finer, fine.unit_source, fine.weighting, lay_half)
    from ..axisymmetric import placements
    info = {"shape": cell.name, "mesh_size_m": lay.mesh_size,
            "mesh_placements": placements(disc, finer),
            "domain_radius_m": lay.domain_radius, "far_field": far_field,
            "meshed_gap_m": lay.effective_gap,
            "minimum_gap_m": contact.minimum_gap(cell.electrode_spacing),
            "ball_area_quadrature_m2": sol.ball_area,
            "error_estimate": "Richardson, mesh_size/2, rate h^(2p)"}
    if sol.source_charge is not None:
        info["source_electrode_charge_C"] = sol.source_charge
        if far_field == "robin":
            info["far_field_charge_C"] = far_field_charge(dx_api, disc, sol.source, lay,
                                                          far_field)
    if breakdown_lines:   # [φ_1, ψ_lower, ψ_upper] at the ball's surface points
        from ..breakdown import line_basis
        info["breakdown_lines"] = line_basis(dx_api, disc, sol.unit_source, sol.weighting, lay)
        if lines_check is not None:
            info["breakdown_lines_check"] = lines_check
    ball_charge = sigma * math.pi * cell.ball_diameter**2
    result = PositionResult(
        position=position, offset=0.0, capacitance=sol.capacitance,
        induced_charge=sol.induced_fraction * ball_charge, ball_charge=ball_charge,
        dofs=dx_api.num_dofs(disc.V), cells=dx_api.num_cells(mesh), method="axisymmetric",
        degree=degree, wall_time=time.perf_counter() - t0, relative_error_estimate=estimate,
        solve_time=sol.solve_time, info=info, induced_fraction=sol.induced_fraction)
    if keep_solution:
        result.solution = field_solution(dx_api, disc, sol, lay)
    from ..moving import done_with
    done_with(dx_api, disc, finer, moving=moving)   # PETSc frees nothing by itself
    return result


def _solve_serial(cell, position: float, comm, **options) -> PositionResult:
    """With the contact rule: near the wall, extrapolated from three meshable gaps (the
    tube's :func:`~tengfield.field.axisymmetric.solve_by_contact_rule`)."""
    anchors = contact.contact_anchors(position, cell.stroke, cell.electrode_spacing)
    if anchors is None:
        return _solve_meshed(cell, position, comm, **options)
    return solve_by_contact_rule(position, anchors, cell.stroke,
                                 lambda z, **opts: _solve_meshed(cell, z, comm, **opts), options)


def solve_cell_position(cell, position: float, *, comm, sigma: float = 0.0,
                        mesh_size: float, degree: int = 2, far_field: str = "kelvin",
                        domain_radius: float | None = None, estimate_error: bool = True,
                        source_solve: bool = False, linear_solver: str = "direct",
                        grading_size: float | None = None, breakdown_lines: bool = False,
                        keep_solution: bool = False, mesh_motion: str = "remesh"
                        ) -> PositionResult:
    """:class:`PositionResult` of ``cell`` with the ball on the axis at gap ``position``
    [m] in [0, cell.stroke] (computed on rank 0 of ``comm``, broadcast).

    ``source_solve`` adds ``info["source_electrode_charge_C"]`` (the electrode charges
    as reactions of the σ source solve, Gauss's law on the electrodes) and, with
    ``far_field = "robin"``, ``info["far_field_charge_C"]`` (the charge the field
    carries to infinity). ``breakdown_lines`` adds ``info["breakdown_lines"]``: the
    basis values [φ_1 (V per C/m²), ψ_lower, ψ_upper] at the ball's surface points of
    :data:`tengfield.field.breakdown.LINE_ANGLES_DEG` (2 sides, n, 3), as the tube's
    (the lines' lengths: ``cell.breakdown_feet``). ``keep_solution`` (a communicator
    of size 1): ``result.solution``, the tube's :class:`FieldSolution` (mesh, ψ_lower,
    ψ_upper, with ``source_solve`` φ_σ). ``mesh_motion = "move"``: a reference mesh of
    this cell and mesh size moved to the position (:mod:`tengfield.field.moving`)."""
    from .. import _dolfinx  # noqa: F401 - on every rank: PETSc initialises collectively

    if not (0.0 <= position <= cell.stroke):
        raise FieldError(f"position = {show_number(position * 1e3, 0.0, cell.stroke * 1e3)} mm "
                         "is out of range: allowed "
                         f"[0, {cell.stroke * 1e3:g}] mm (the {cell.name}'s stroke)")
    if degree not in (1, 2, 3):
        raise FieldError(f"[field] degree = {degree} is out of range: allowed 1, 2, 3")
    options = dict(sigma=float(sigma), mesh_size=float(mesh_size), degree=int(degree),
                   far_field=far_field, domain_radius=domain_radius,
                   estimate_error=estimate_error, source_solve=source_solve,
                   linear_solver=linear_solver, grading_size=grading_size,
                   breakdown_lines=breakdown_lines, keep_solution=keep_solution,
                   mesh_motion=mesh_motion)
    return solved_on_rank_zero(comm, lambda here: _solve_serial(cell, position, here, **options),
                               keep_solution=keep_solution)


__all__ = ["solve_cell_position", "far_field_charge", "build_mesh", "SOLVER_OPTIONS"]
