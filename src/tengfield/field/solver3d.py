"""3D electrostatics of one BB-TENG cell (dolfinx via :mod:`._dolfinx`, gmsh OCC), SI units.

For a ball position the weighting potential ψ_k of each of the cell's electrodes
(ψ_lower, ψ_upper of the pair; ψ_lower alone for the single-electrode cell, whose
upper plate is bare dielectric) solves

    ∇·(εr ∇ψ_k) = 0,   ψ_k = 1 on electrode k, 0 on every other electrode,

with ε0 scaled out of the matrix (it multiplies the results). They share one
operator: it is assembled once and preconditioned once (CG + hypre
BoomerAMG); the right-hand sides differ only in the Dirichlet values.

Far field (the air is a sphere of radius R centred on the cell):

* ``"robin"``: the asymptotic condition ∂ψ/∂n + ψ/R = 0, exact for the
  monopole part of the exterior field. Its weak form adds ``(1/R)∮ψ v dS``,
  and the same term (the energy of the monopole exterior field) enters C.
* ``"kelvin"`` (the scene default): in 3D this is the exact
  Dirichlet-to-Neumann map of the exterior for the spherical harmonics of
  degree l ≤ ``DTN_DEGREE`` (∂ψ_l/∂n = -(l+1)/R ψ_l), i.e. the Robin term
  plus the rank-8 term ``Σ_{l=1,2} Σ_m (l/R) (∮Y_lm ψ)(∮Y_lm v) / ∮Y_lm²``.
  It is what the Kelvin inversion gives for those modes; the remaining
  truncation error falls as (device size / R)^7 (measured in
  docs/field3d.md). The low-rank term is applied matrix-free on top of the
  assembled Robin matrix, which also preconditions (BoomerAMG).
* ``"dirichlet"``: ψ = 0 on the sphere (a grounded enclosure).

Results (sign conventions of :mod:`tengfield.terminals`):

* ``C_jk = ε0 [∫ εr ∇ψ_j·∇ψ_k dΩ + ∮ ψ_j DtN ψ_k dS]`` [F], the field
  energy including the exterior (symmetric by construction, positive definite).
* ``q_k = -∮_ball σ ψ_k dS`` [C]: evaluated as ``-q_ball · <ψ_k>_ball``,
  the mean of ψ_k over the meshed ball surface times the exact ball charge
  ``q_ball = σ π d²`` (the meshed sphere's area error cancels).
* ``relative_error_estimate``: the same position is also solved on a mesh
  twice as coarse; the estimate is the largest relative change of C_ll,
  C_lu, C_uu, q_lower/q_ball, q_upper/q_ball
  (:func:`tengfield.field.contact.relative_change`) divided by ``2^p - 1`` with ``p`` the
  observed convergence order (1 for degree 1, 1.5 for degree 2, measured in
  docs/field3d.md; the electrode rims limit the rate).

Every function takes the MPI communicator explicitly; the gmsh model is
built on rank 0 of that communicator and distributed by dolfinx.
"""
from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import FieldError
from ..scene.constants import EPS0
from . import contact
from .geometry3d import MeshSettings, build_model, unique_model_name
from .result import FieldSolution, PositionResult

#: Observed convergence order of C and q under uniform refinement, by degree
#: (used to turn the coarse/fine difference into an error estimate).
OBSERVED_ORDER = {1: 1.0, 2: 1.5}

FAR_FIELDS = ("robin", "dirichlet", "kelvin")
#: Highest spherical-harmonic degree whose exterior field is exact for far_field = "kelvin".
DTN_DEGREE = 2


@dataclass
class CellMesh:
    """A distributed dolfinx mesh of one cell with its physical groups."""
    mesh: Any
    cell_tags: Any
    facet_tags: Any
    groups: dict[str, int]        # physical group name -> tag
    ball_centre: np.ndarray       # [m]
    meshed_gap: float             # [m]
    meshed_offset: float          # [m]
    mesh_time: float              # [s]

    @property
    def electrodes(self) -> tuple[str, ...]:
        """The meshed electrodes' names, in the order of the field's matrices."""
        return tuple(name for name in ("lower", "upper") if f"electrode_{name}" in self.groups)


@dataclass
class WeightingPotentials:
    """Every electrode's weighting potential on one mesh (``functions``, in the order of
    the field's matrices: ψ_lower, ψ_upper; ψ_lower alone for the single electrode), plus
    what the solve cost."""
    functions: tuple
    dofs: int
    cells: int
    iterations: tuple[int, int]
    assembly_time: float          # [s]
    solve_time: float             # [s] (preconditioner setup + both solves)
    #: far_field = "kelvin": ∮Y_m ψ_k dS (shape 2 x M) and the weights l/(R ∮Y_m²) [1/m],
    #: so that the exterior energy beyond Robin is Σ_m w_m moment_jm moment_km.
    harmonic_moments: np.ndarray = None
    harmonic_weights: np.ndarray = None

    @property
    def lower(self):
        """ψ_lower."""
        return self.functions[0]


def sphere_harmonics(x, max_degree: int = DTN_DEGREE):
    """Real solid harmonics of degree 1..max_degree (unnormalised UFL polynomials of
    the spatial coordinate ``x``; on an origin-centred sphere they are the real
    spherical harmonics up to a constant), as (degree, expression) pairs."""
    n = [x[i] for i in range(3)]
    out = [(1, n[0]), (1, n[1]), (1, n[2])]
    if max_degree >= 2:
        out += [(2, n[0] * n[1]), (2, n[1] * n[2]), (2, n[0] * n[2]),
                (2, n[0] * n[0] - n[1] * n[1]), (2, 2 * n[2] * n[2] - n[0] * n[0] - n[1] * n[1])]
    if max_degree > 2:
        raise ValueError("sphere_harmonics: max_degree <= 2")
    return out


class _LowRankUpdate:
    """PETSc python matrix ``y = A x + Σ_m w_m (u_m·x) u_m`` (symmetric, A assembled)."""

    def __init__(self, matrix, vectors, weights):
        self.matrix, self.vectors, self.weights = matrix, vectors, weights

    def mult(self, mat, x, y):
        self.matrix.mult(x, y)
        for u, w in zip(self.vectors, self.weights):
            y.axpy(w * u.dot(x), u)


# ---------------------------------------------------------------------------
@contextlib.contextmanager
def gmsh_model(name: str):
    """A fresh gmsh model named ``name`` (gmsh initialised if needed, removed after)."""
    import gmsh

    from ._gmsh import initialize

    started = not gmsh.isInitialized()
    if started:
        initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    try:
        yield gmsh.model
    finally:
        gmsh.model.setCurrent(name)
        gmsh.model.remove()
        if started:
            gmsh.finalize()


def mesh_cell(cell, position: float, offset: float, settings: MeshSettings, *, comm,
              offset_angle: float = 0.0) -> CellMesh:
    """Mesh ``cell`` with gmsh on rank 0 of ``comm`` and distribute it with dolfinx.

    ``position`` z [m], ``offset`` [m] and ``offset_angle`` [rad] place the
    ball (see :mod:`tengfield.field.geometry3d`)."""
    from . import _dolfinx as dx_api

    start = time.perf_counter()
    meta = None
    error = None
    if comm.rank == 0:
        with gmsh_model(unique_model_name("tengfield-3d")) as model:
            try:
                meta = build_model(cell, position, offset, settings, offset_angle=offset_angle)
            except Exception as exc:  # noqa: BLE001 - re-raised on every rank below
                error = exc
            comm.bcast(None if error is None else str(error), root=0)
            if error is None:
                mesh, cell_tags, facet_tags = dx_api.mesh_from_gmsh(model, comm, rank=0, gdim=3)
    else:
        message = comm.bcast(None, root=0)
        if message is not None:
            error = FieldError(f"3D meshing failed on rank 0: {message}")
        else:
            mesh, cell_tags, facet_tags = dx_api.mesh_from_gmsh(None, comm, rank=0, gdim=3)
    if error is not None:
        raise error
    meta = comm.bcast(meta, root=0)
    return CellMesh(mesh=mesh, cell_tags=cell_tags, facet_tags=facet_tags, groups=meta["groups"],
                    ball_centre=np.asarray(meta["ball_centre"]), meshed_gap=meta["meshed_gap"],
                    meshed_offset=meta["meshed_offset"], mesh_time=time.perf_counter() - start)


def permittivity_function(cell_mesh: CellMesh, permittivity: dict[str, float]):
    """Piecewise-constant εr (DG0) from the volume groups (``{"ball": 2.1, ...}``; air is 1)."""
    from . import _dolfinx as dx_api

    return dx_api.cellwise_constant(
        cell_mesh.mesh, cell_mesh.cell_tags,
        {cell_mesh.groups[name]: value for name, value in permittivity.items()
         if name in cell_mesh.groups}, name="relative_permittivity")


#: PETSc options of the 3D solve (CG + BoomerAMG tuned for the 3D Laplacian)
AMG_OPTIONS = {"pc_hypre_boomeramg_strong_threshold": 0.6,
               "pc_hypre_boomeramg_coarsen_type": "HMIS",
               "pc_hypre_boomeramg_interp_type": "ext+i", "pc_hypre_boomeramg_P_max": 4,
               "pc_hypre_boomeramg_agg_nl": 1, "ksp_atol": 1e-30}


def solve_weighting_potentials(cell_mesh: CellMesh, permittivity: dict[str, float], *,
                               degree: int, far_field: str, domain_radius: float,
                               rtol: float = 1e-10) -> WeightingPotentials:
    """Both weighting potentials with one assembled, once-preconditioned operator."""
    from . import _dolfinx as dx_api

    ufl, PETSc = dx_api.ufl, dx_api.PETSc
    if far_field not in FAR_FIELDS:
        raise FieldError(f"far_field = {far_field!r} is not allowed: choose one of "
                         + ", ".join(repr(f) for f in FAR_FIELDS))
    mesh = cell_mesh.mesh
    comm = mesh.comm
    start = time.perf_counter()
    space = dx_api.lagrange_space(mesh, degree)
    eps_r = permittivity_function(cell_mesh, permittivity)
    u, v = ufl.TrialFunction(space), ufl.TestFunction(space)
    _, ds, _ = dx_api.measures(mesh, cell_mesh.cell_tags, cell_mesh.facet_tags)
    far_tag = cell_mesh.groups["far_boundary"]
    a = eps_r * ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    if far_field in ("robin", "kelvin"):
        a = a + dx_api.constant(mesh, 1.0 / domain_radius) * u * v * ds(far_tag)
    rhs = dx_api.form(ufl.inner(dx_api.constant(mesh, 0.0), v) * ufl.dx)
    bilinear = dx_api.form(a)

    conductors = [f"electrode_{name}" for name in cell_mesh.electrodes]
    dofs = {name: dx_api.facet_dofs(space, cell_mesh.facet_tags, cell_mesh.groups[name])
            for name in conductors}
    if far_field == "dirichlet":
        dofs["far_boundary"] = dx_api.facet_dofs(space, cell_mesh.facet_tags, far_tag)

    def bcs_for(active: str):
        return [dx_api.dirichlet_bc(space, 1.0 if name == active else 0.0, d)
                for name, d in dofs.items()]

    matrix = dx_api.assemble_matrix(bilinear, bcs=bcs_for(conductors[0]))
    operator, harmonic_vectors, weights = matrix, [], np.empty(0)
    if far_field == "kelvin":
        # exact exterior for the harmonics l = 1..DTN_DEGREE: a low-rank term on the far sphere
        x = ufl.SpatialCoordinate(mesh)
        weights = []
        for degree_l, harmonic in sphere_harmonics(x):
            harmonic_vectors.append(dx_api.assemble_vector(dx_api.form(harmonic * v * ds(far_tag))))
            norm = dx_api.assemble_scalar(dx_api.form(harmonic * harmonic * ds(far_tag)), comm)
            weights.append(degree_l / (domain_radius * norm))
        weights = np.array(weights)
        operator = dx_api.python_matrix(comm, matrix.getSizes(),
                                        _LowRankUpdate(matrix, harmonic_vectors, weights))
    assembly_time = time.perf_counter() - start

    start = time.perf_counter()
    prefix = dx_api.unique_prefix("3d")
    ksp = dx_api.create_ksp(comm, operator, prefix=prefix, kind="cg-amg", rtol=rtol,
                            preconditioner_matrix=matrix, options=AMG_OPTIONS)
    potentials, iterations, moments = [], [], []
    try:
        for active in conductors:
            b = dx_api.assemble_vector(rhs, bilinear, bcs_for(active))
            psi = dx_api.function(space, name=f"psi_{active.split('_')[1]}")
            try:
                dx_api.solve(ksp, b, dx_api.petsc_vector(psi))
            except PETSc.Error as exc:
                raise FieldError(f"3D solve for {active} did not converge "
                                 f"(reason {ksp.getConvergedReason()}): {exc}") from None
            psi.x.scatter_forward()
            potentials.append(psi)
            moments.append([u.dot(dx_api.petsc_vector(psi)) for u in harmonic_vectors])
            iterations.append(ksp.getIterationNumber())
            b.destroy()
    finally:
        ksp.destroy()
        if operator is not matrix:
            operator.destroy()
        matrix.destroy()
        for vec in harmonic_vectors:
            vec.destroy()
        dx_api.clear_options(prefix)
    solve_time = time.perf_counter() - start
    return WeightingPotentials(functions=tuple(potentials),
                               dofs=dx_api.num_dofs(space), cells=dx_api.num_cells(mesh),
                               iterations=tuple(iterations),
                               assembly_time=assembly_time, solve_time=solve_time,
                               harmonic_moments=np.array(moments).reshape(len(potentials), -1),
                               harmonic_weights=np.asarray(weights))


def capacitance_matrix(cell_mesh: CellMesh, potentials: WeightingPotentials,
                       permittivity: dict[str, float], *, far_field: str,
                       domain_radius: float) -> np.ndarray:
    """Maxwell capacitance matrix [F] of the electrodes from the field energy: [[C_ll,
    C_lu], [C_lu, C_uu]] for the pair, [[C_ll]] for the single electrode."""
    from . import _dolfinx as dx_api

    ufl = dx_api.ufl
    mesh = cell_mesh.mesh
    eps_r = permittivity_function(cell_mesh, permittivity)
    _, ds, _ = dx_api.measures(mesh, cell_mesh.cell_tags, cell_mesh.facet_tags)
    psi = potentials.functions

    def energy(a, b):
        form = eps_r * ufl.inner(ufl.grad(a), ufl.grad(b)) * ufl.dx
        if far_field in ("robin", "kelvin"):
            form = form + (dx_api.constant(mesh, 1.0 / domain_radius) * a * b
                           * ds(cell_mesh.groups["far_boundary"]))
        return dx_api.assemble_scalar(dx_api.form(form), mesh.comm)

    n = len(psi)
    c = np.empty((n, n))
    moments, weights = potentials.harmonic_moments, potentials.harmonic_weights
    for j, k in ((j, k) for j in range(n) for k in range(j, n)):
        exterior = float(np.sum(weights * moments[j] * moments[k])) if weights is not None else 0.0
        c[j, k] = c[k, j] = EPS0 * (energy(psi[j], psi[k]) + exterior)
    return c


def ball_surface_means(cell_mesh: CellMesh, potentials: WeightingPotentials) -> np.ndarray:
    """[<ψ_k>]: means of the electrodes' weighting potentials over the ball surface
    ([<ψ_lower>, <ψ_upper>] for the pair)."""
    from . import _dolfinx as dx_api

    mesh = cell_mesh.mesh
    _, _, dS = dx_api.measures(mesh, cell_mesh.cell_tags, cell_mesh.facet_tags)
    dS = dS(cell_mesh.groups["ball_surface"])

    def integral(expr):
        return dx_api.assemble_scalar(dx_api.form(expr * dS), mesh.comm)

    area = integral(dx_api.constant(mesh, 1.0))
    return np.array([integral(psi("+")) / area for psi in potentials.functions])


def evaluate_at(function, point, comm=None) -> float:
    """Value of a dolfinx Function at one point [m] (collective over the mesh's communicator)."""
    from . import _dolfinx as dx_api

    mesh = function.function_space.mesh
    comm = mesh.comm if comm is None else comm
    point = np.asarray(point, dtype=float).reshape(1, 3)
    cells = dx_api.colliding_cells(mesh, point)
    local = function.eval(point, cells[:1])[0] if cells[0] >= 0 else math.nan
    values = [v for v in comm.allgather(local) if not math.isnan(v)]
    if not values:
        raise FieldError(f"point {point.ravel().tolist()} m is outside the mesh")
    return float(values[0])


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Solve3DSettings:
    """Discretisation of one 3D solve (SI)."""
    degree: int = 2
    mesh_size: float = 0.5e-3           # [m]
    domain_radius: float = 20.0e-3      # [m]
    far_field: str = "robin"
    estimate_error: bool = True
    mesh_options: tuple = ()            # extra MeshSettings fields, (("rim_factor", 0.2),)
    mesh_grading: str = "uniform"       # [field] mesh_grading: "uniform" or "graded"

    def mesh_settings(self, coarsen: float = 1.0) -> MeshSettings:
        return MeshSettings(size=self.mesh_size * coarsen, domain_radius=self.domain_radius,
                            order=2 if self.degree >= 2 else 1, grading=self.mesh_grading,
                            **dict(self.mesh_options))


@dataclass
class CellSolution:
    """Raw result of :func:`solve_cell`: numbers plus the mesh and potentials."""
    capacitance: np.ndarray
    induced_fraction: np.ndarray     # [q_k] / q_ball = -<ψ_k>_ball, one per electrode
    cell_mesh: CellMesh
    potentials: WeightingPotentials
    estimate: float = math.nan       # relative error estimate (set by solve_cell_3d)


def solve_cell(cell, position: float, offset: float, settings: Solve3DSettings, *, comm,
               coarsen: float = 1.0, offset_angle: float = 0.0) -> CellSolution:
    """Mesh and solve one cell at gap ``position`` [m] and lateral ``offset`` [m]
    (direction ``offset_angle`` [rad] from +x); ``coarsen`` scales the mesh size."""
    if settings.degree not in (1, 2):
        raise FieldError(f"degree = {settings.degree!r} is out of range: the 3D solver allows 1 or 2")
    cell_mesh = mesh_cell(cell, position, offset, settings.mesh_settings(coarsen), comm=comm,
                          offset_angle=offset_angle)
    return solve_on_mesh(cell_mesh, cell_permittivity(cell), settings)


def cell_permittivity(cell) -> dict[str, float]:
    """Relative permittivity by volume group (the air is 1)."""
    return {"ball": cell.ball_permittivity, "walls": cell.wall_permittivity}


def solve_on_mesh(cell_mesh: CellMesh, permittivity: dict[str, float],
                  settings: Solve3DSettings) -> CellSolution:
    """C and q/q_ball on an existing mesh (e.g. one of ``meshes/``, see :func:`load_cell_mesh`)."""
    potentials = solve_weighting_potentials(cell_mesh, permittivity, degree=settings.degree,
                                            far_field=settings.far_field,
                                            domain_radius=settings.domain_radius)
    cap = capacitance_matrix(cell_mesh, potentials, permittivity, far_field=settings.far_field,
                             domain_radius=settings.domain_radius)
    return CellSolution(capacitance=cap, induced_fraction=-ball_surface_means(cell_mesh, potentials),
                        cell_mesh=cell_mesh, potentials=potentials)


def solve_reference_mesh(path, case: dict, *, comm) -> CellSolution:
    """Degree-1, Robin, no error estimate: how ``meshes/generate.py`` solves a stored
    reference mesh ``path`` (``.msh``), from the case's entry in ``meshes/reference.json``
    (``ball_centre_m``, ``mesh_settings``, ``cell`` permittivities)."""
    cell_mesh = load_cell_mesh(path, comm=comm, ball_centre=case["ball_centre_m"])
    settings = Solve3DSettings(degree=1, mesh_size=case["mesh_settings"]["size"],
                               domain_radius=case["mesh_settings"]["domain_radius"],
                               far_field="robin", estimate_error=False)
    cell = case["cell"]
    return solve_on_mesh(cell_mesh, {"ball": cell["ball_permittivity"],
                                     "walls": cell["wall_permittivity"]}, settings)


def load_cell_mesh(path, *, comm, ball_centre=(0.0, 0.0, 0.0), meshed_gap: float = math.nan,
                   meshed_offset: float = math.nan) -> CellMesh:
    """Read a ``.msh`` file written by ``meshes/generate.py`` (named physical groups)
    on rank 0 of ``comm`` and distribute it."""
    from . import _dolfinx as dx_api

    start = time.perf_counter()
    groups = None
    if comm.rank == 0:
        with gmsh_model(unique_model_name("tengfield-3d-read")):
            import gmsh
            gmsh.merge(str(path))
            groups = {gmsh.model.getPhysicalName(dim, tag): tag
                      for dim, tag in gmsh.model.getPhysicalGroups() if dim >= 2}
            groups = comm.bcast(groups, root=0)
            mesh, cell_tags, facet_tags = dx_api.mesh_from_gmsh(gmsh.model, comm, rank=0, gdim=3)
    else:
        groups = comm.bcast(None, root=0)
        mesh, cell_tags, facet_tags = dx_api.mesh_from_gmsh(None, comm, rank=0, gdim=3)
    return CellMesh(mesh=mesh, cell_tags=cell_tags, facet_tags=facet_tags, groups=groups,
                    ball_centre=np.asarray(ball_centre, dtype=float), meshed_gap=meshed_gap,
                    meshed_offset=meshed_offset, mesh_time=time.perf_counter() - start)


def solve_cell_3d(cell, position: float, *, offset: float = 0.0, offset_angle: float = 0.0,
                  surface_charge: float, settings: Solve3DSettings, comm,
                  keep_solution: bool = False, solve_one=None) -> PositionResult:
    """A :class:`PositionResult` for ``cell`` (a :class:`CylindricalCell`, a :class:`HexagonalCell`
    or a :class:`~tengfield.field.cells.SphericalShell`: any cell with the 3D model's
    methods ``placement_3d``, ``contact_rule_3d``, ``extent_3d``, ``occ_parts``,
    ``rim_distance_expr``, ``gap_refinements_3d``, see :func:`geometry3d.build_model`).

    ``surface_charge`` σ [C/m²] on the ball; ``position`` z [m] in [0, Δh];
    ``offset`` [m] lateral, at ``offset_angle`` [rad] from +x. A position
    closer than ``g_min`` to an electrode follows the contact rule of
    :mod:`tengfield.field.contact` (the axisymmetric solver's). With
    ``keep_solution``, ``result.solution`` is the :class:`FieldSolution`
    (mesh and ψ functions) of the (nearest) meshed position. ``solve_one``: a
    :func:`solve_cell` of the same signature that places each mesh otherwise
    (:func:`tengfield.field.moving3d.solve_cell`, ``[field] mesh_motion = "move"``:
    ``info["mesh_placements"]`` says how); None meshes every position with gmsh.
    """
    start = time.perf_counter()
    # [field] mesh_motion = "move": the caller passes field/moving3d.py's solve_cell, which
    # places the ball by moving a reference mesh (a kept solution is always meshed)
    moving = solve_one is not None and not keep_solution
    solve_one = solve_one if moving else solve_cell
    placed = []

    def solve_here(z: float, with_estimate: bool, r: float = offset):
        sol = solve_one(cell, z, r, settings, comm=comm, offset_angle=offset_angle)
        placed.append(getattr(sol, "placement", None))
        sol.estimate = math.nan
        if with_estimate:
            coarse = solve_one(cell, z, r, settings, comm=comm, coarsen=2.0,
                               offset_angle=offset_angle)
            placed.append(getattr(coarse, "placement", None))
            sol.estimate = (contact.relative_change(coarse, sol)
                            / (2.0 ** OBSERVED_ORDER[settings.degree] - 1.0))
        return sol

    # the cell's contact rule: None, or the anchors along its own coordinate (the gap
    # along z for the tube, the gap to the spherical wall for the shell) and where
    # each anchor puts the ball (place(x) -> (position, offset))
    rule_at = cell.contact_rule_3d(position, offset, offset_angle)
    info: dict[str, Any] = {}
    if rule_at is None:
        fine = solve_here(position, settings.estimate_error)
        capacitance, fraction = fine.capacitance, fine.induced_fraction
        solve_time, estimate = fine.potentials.solve_time, fine.estimate
    else:
        anchors = rule_at["anchors"]

        def solve_anchor(x: float):
            z, r = rule_at["place"](x)
            return solve_here(z, settings.estimate_error and x == anchors[0], r)

        rule = contact.extrapolate_to_contact(rule_at["coordinate"], anchors, rule_at["span"],
                                              solve_anchor)
        fine = rule["solves"][0]
        capacitance, fraction = rule["capacitance"], rule["induced_fraction"]
        solve_time = sum(s.potentials.solve_time for s in rule["solves"])
        estimate = max(fine.estimate, rule["error"]) if settings.estimate_error else math.nan
        info["contact_rule"] = ("power-law extrapolation from gaps "
                                + ", ".join(f"{d:.6g}" for d in rule["distances"]) + " m")
        info["contact_extrapolation_error"] = rule["error"]
        info["contact_exponent"] = rule["exponent"]
    ball_charge = surface_charge * math.pi * cell.ball_diameter**2
    pot = fine.potentials
    info.update({
        "geometry": type(cell).__name__,
        "mesh_size_m": settings.mesh_size,
        "domain_radius_m": settings.domain_radius,
        "far_field": (f"dtn-{DTN_DEGREE} (exact exterior for harmonics l <= {DTN_DEGREE})"
                      if settings.far_field == "kelvin" else settings.far_field),
        "meshed_gap_m": fine.cell_mesh.meshed_gap,
        "meshed_offset_m": fine.cell_mesh.meshed_offset,
        "ball_centre_m": fine.cell_mesh.ball_centre.tolist(),
        "ksp_iterations": list(pot.iterations),
        "mesh_time_s": fine.cell_mesh.mesh_time,
        "assembly_time_s": pot.assembly_time,
        "mpi_size": comm.size,
    })
    if moving:
        info["mesh_motion"] = "move"
        info["mesh_placements"] = {key: sum(p[key] for p in placed if p)
                                   for key in ("moved", "meshed")}
    solution = None
    if keep_solution:
        cm = fine.cell_mesh
        solution = FieldSolution(method="3d", mesh=cm.mesh, cell_tags=cm.cell_tags,
                                 facet_tags=cm.facet_tags, space=pot.lower.function_space,
                                 weighting=pot.functions, ball_centre=cm.ball_centre,
                                 geometry=cell, degree=settings.degree)
    return PositionResult(
        position=position, offset=offset, capacitance=capacitance,
        induced_charge=fraction * ball_charge, ball_charge=ball_charge,
        dofs=pot.dofs, cells=pot.cells, method="3d", degree=settings.degree,
        wall_time=time.perf_counter() - start, relative_error_estimate=estimate,
        solve_time=solve_time, info=info, induced_fraction=fraction, solution=solution)
