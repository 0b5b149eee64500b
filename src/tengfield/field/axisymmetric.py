"""Axisymmetric (r, z) electrostatics of the BB-TENG at one ball position.

Formulation (SI, ε0 scaled out of every matrix): the weighting potential ψ_k
of electrode k solves ``∇·(εr ∇ψ) = 0`` with ψ_k = 1 on electrode k, 0 on the
other electrode (and on a grounded table) and ψ → 0 at infinity. In (r, z)
with volume element ``2π r dr dz`` the bilinear form is

    a(u, v) = ∫ εr ∇u·∇v r dr dz  +  κ/R ∮_{|x|=R} u v r ds   (+ Kelvin image part)

where the last term comes from the far field (see :func:`far_field_weight`).
``C_jk = 2π ε0 a(ψ_j, ψ_k)``, ``q_k = -2π σ ∫_ball ψ_k r ds`` and the ball
charge is ``σ π d²``.

Far field, for the sphere of radius R around the inversion centre:

* ``kelvin``: the exterior |x| > R is mapped by x' = R² x/|x|² onto a second
  half-disk meshed in the same model; there u* = (R/|x'|) u is harmonic and
  needs no condition at the inverted origin (u → 0 at infinity makes u*
  bounded there). On the sphere ``∂_ρ u = -u*/R - ∂_ρ' u*``, so the exterior
  energy ``∫_{|x|>R} ∇u·∇v = ∫_{|x'|<R} ∇u*·∇v* + (1/R) ∮ u* v*``: the image
  domain enters with weight r' (the map preserves the azimuth) plus the
  boundary term with κ = 1. The two arcs are glued by a restriction P
  (one unknown per pair of coincident nodes); we solve Pᵀ A P x = Pᵀ b.
  With a grounded table the inversion centre lies on the table plane,
  which the inversion maps onto itself (ψ* = 0 there too).
* ``robin``: ∂ψ/∂n + κψ/R = 0, exact for a monopole (κ = 1) or, with a
  grounded table, for the image dipole (κ = 2) far field.
* ``dirichlet``: ψ = 0 on the sphere (naive truncation, for comparison).

Dirichlet values and gluing are both expressed through P: the full vector is
``ψ = P x + g`` (g: electrode values), so one operator ``K = Pᵀ A P`` is
factored once (CHOLMOD on one process, else MUMPS) and reused for every right-hand side.

Error estimate: the geometry is meshed again with half the mesh size (all
graded sizes halve too) and solved with the same degree; with the measured
asymptotic rate h^(2p) of C and q (radical grading restores it), the error of
the returned (coarse) values is ``max_i |X_i(h) - X_i(h/2)| / |X_i(h/2)| /
(1 - 2^(-2p))`` over X = C_ll, C_lu, C_uu, q_lower, q_upper.

The problem is small: it is solved on rank 0 of ``comm`` (on COMM_SELF) and
the result broadcast to every rank.
"""
from __future__ import annotations

import math
import time
import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import FieldError, TengfieldError
from ..scene.constants import EPS0
from . import contact
from . import geometry_axisymmetric as geometry
from .result import FieldSolution, PositionResult

#: info keys of the breakdown lines (coarse mesh, half-size mesh where estimated)
LINE_KEYS = ("breakdown_lines", "breakdown_lines_check")
#: options the solver accepts besides the scene (see solve_position_axisymmetric)
SOLVER_OPTIONS = ("estimate_error", "keep_solution", "source_solve", "linear_solver",
                  "breakdown_lines")


def far_field_weight(far_field: str, table: bool) -> float:
    """κ in the boundary term κ/R ∮ u v of the far-field treatment (0 for Dirichlet)."""
    if far_field == "dirichlet":
        return 0.0
    if far_field == "kelvin":
        return 1.0
    return 2.0 if table else 1.0


def restriction(n_full: int, fixed: np.ndarray, image_pairs: np.ndarray):
    """Restriction (prolongation) P: reduced unknowns -> full dof vector.

    ``fixed``: dofs with prescribed values (removed); ``image_pairs``: rows
    (image dof, master dof) whose values are identical. Returns
    (indptr, indices, data, n_reduced) of the CSR matrix P (n_full × n_reduced).
    """
    is_fixed = np.zeros(n_full, dtype=bool)
    is_fixed[fixed] = True
    slave = np.zeros(n_full, dtype=bool)
    if len(image_pairs):
        slave[image_pairs[:, 0]] = True
    free = np.flatnonzero(~is_fixed & ~slave)
    column = np.full(n_full, -1, dtype=np.int64)
    column[free] = np.arange(free.size)
    if len(image_pairs):
        column[image_pairs[:, 0]] = column[image_pairs[:, 1]]  # -1 if the master is fixed
    rows_with_entry = column >= 0
    indptr = np.concatenate([[0], np.cumsum(rows_with_entry)]).astype(np.int32)
    indices = column[rows_with_entry].astype(np.int32)
    data = np.ones(indices.size)
    return indptr, indices, data, int(free.size)


def match_image_dofs(coords: np.ndarray, image_dofs: np.ndarray, master_dofs: np.ndarray,
                     shift: float, scale: float) -> np.ndarray:
    """Pairs (image dof, master dof) of nodes that coincide after shifting by -shift in z."""
    from scipy.spatial import cKDTree

    image_dofs = np.unique(image_dofs)
    master_dofs = np.unique(master_dofs)
    tree = cKDTree(coords[master_dofs, :2])
    shifted = coords[image_dofs, :2] - np.array([0.0, shift])
    dist, idx = tree.query(shifted)
    if image_dofs.size != master_dofs.size or np.max(dist, initial=0.0) > 1e-8 * scale:
        raise FieldError(f"Kelvin gluing: {image_dofs.size} image nodes vs {master_dofs.size} "
                         f"sphere nodes, worst mismatch {np.max(dist, initial=0.0):.3g} m")
    return np.column_stack([image_dofs, master_dofs[idx]])


@dataclass
class Discretisation:
    """Mesh, space and assembled operators of one (geometry, degree) pair (rank-local)."""
    mesh: object
    cell_tags: object
    facet_tags: object
    V: object
    A: object            # full operator a(u, v), ε0 and 2π scaled out
    ball_load: np.ndarray  # ∫_ball v r ds per dof (2π scaled out)
    P: object            # restriction, PETSc
    n_reduced: int
    electrodes: tuple    # each electrode's dofs, in the layout's order (lower, upper)
    grounded: np.ndarray  # table / Dirichlet far boundary dofs
    degree: int = 1
    forms: tuple = ()    # compiled (operator, ball load): assembled again on a moved mesh
    solver: dict | None = None  # a reference mesh's {kind: (K, KSP, prefix)}, set up once
    placement: str = "meshed"   # "moved": a reference mesh moved here (field/moving.py)
    meshings: int = 1           # gmsh meshings the last placement of this mesh took
    mappings: int = 0           # references mapped from another geometry's (moving.py)
    far_weight: tuple | None = None  # (Constant κ/R of the far boundary term, κ)


def placements(*discs) -> dict:
    """``{"moved": n, "meshed": m, "mapped": k}`` over the meshes of one solve
    (info["mesh_placements"]): how many were reference meshes moved there, how many gmsh
    meshings it took, how many references were mapped from another geometry's."""
    discs = [d for d in discs if d is not None]
    return {"moved": sum(1 for d in discs if d.placement == "moved"),
            "meshed": sum(int(d.meshings) for d in discs),
            "mapped": sum(int(d.mappings) for d in discs)}



def discretise(dx_api, mesh, cell_tags, facet_tags, lay, permittivity: dict[str, float],
               degree: int, far_field: str) -> Discretisation:
    """Assemble the operator and the ball-surface load for Lagrange degree ``degree``."""
    ufl = dx_api.ufl
    comm = mesh.comm
    V = dx_api.lagrange_space(mesh, degree)
    eps_r = dx_api.cellwise_constant(mesh, cell_tags, {
        geometry.CELL_TAGS[name]: value for name, value in permittivity.items()})
    dx, ds, dS = dx_api.measures(mesh, cell_tags, facet_tags)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    r = ufl.SpatialCoordinate(mesh)[0]
    a = eps_r * ufl.inner(ufl.grad(u), ufl.grad(v)) * r * dx
    kappa = far_field_weight(far_field, lay.table)
    far_weight = None
    if kappa:   # κ/R a constant of the form: a mapped geometry (moving.py) sets its R
        far_weight = (dx_api.constant(mesh, kappa / lay.domain_radius), kappa)
        a += far_weight[0] * u * v * r * ds(geometry.FACET_TAGS["far_boundary"])
    a_form = dx_api.form(a)
    load_form = dx_api.form(v("+") * r("+") * dS(geometry.FACET_TAGS["ball_surface"]))
    A = dx_api.assemble_matrix(a_form)
    ball_load = dx_api.assemble_vector(load_form).array.copy()

    def dofs(name):
        tags = facet_tags.values
        if geometry.FACET_TAGS[name] not in tags:
            return np.zeros(0, dtype=np.int32)
        return dx_api.facet_dofs(V, facet_tags, geometry.FACET_TAGS[name])

    names = getattr(lay, "electrodes", ("lower", "upper"))
    electrodes = tuple(dofs(f"electrode_{name}").astype(np.int64) for name in names)
    grounded = [dofs("table"), dofs("table_image")]
    if far_field == "dirichlet":
        grounded.append(dofs("far_boundary"))
    grounded = np.unique(np.concatenate(grounded)).astype(np.int64)
    n_full = dx_api.num_dofs(V)
    pairs = np.zeros((0, 2), dtype=np.int64)
    if lay.kelvin:
        pairs = match_image_dofs(dx_api.dof_coordinates(V), dofs("far_boundary_image"),
                                 dofs("far_boundary"), lay.shift, lay.domain_radius)
    fixed = np.unique(np.concatenate([*electrodes, grounded])).astype(np.int64)
    indptr, indices, data, n_red = restriction(n_full, fixed, pairs)
    P = dx_api.matrix_from_csr(comm, (n_full, n_red), indptr, indices, data)
    return Discretisation(mesh, cell_tags, facet_tags, V, A, ball_load, P, n_red,
                          electrodes, grounded, degree, (a_form, load_form),
                          far_weight=far_weight)


def reassemble(dx_api, disc: Discretisation) -> None:
    """The operator and the ball's load of ``disc`` assembled again (its mesh moved:
    :mod:`tengfield.field.moving`), with the same compiled forms, dofs and sparsity."""
    a_form, load_form = disc.forms
    dx_api.assemble_matrix_into(disc.A, a_form)
    disc.ball_load = dx_api.assemble_vector(load_form).array.copy()


@dataclass
class Solution:
    """Potentials (full dof vectors) and the quantities derived from them (SI)."""
    capacitance: np.ndarray
    induced_fraction: np.ndarray  # [q_lower, q_upper] / q_ball (one per electrode)
    weighting: list          # [ψ_lower, ψ_upper] as numpy arrays (one per electrode)
    source: np.ndarray | None  # potential of the ball charge, electrodes grounded [V]
    source_charge: np.ndarray | None  # electrode charges of the source solve (reactions) [C]
    solve_time: float
    ball_area: float
    unit_source: np.ndarray | None = None  # potential of σ = 1 C/m², electrodes grounded


def solve_discretisation(dx_api, disc: Discretisation, sigma: float, ball_diameter: float, *,
                         source_solve: bool, linear_solver: str = "direct",
                         unit_source: bool = False) -> Solution:
    """Every electrode's weighting potential (and optionally the σ source) with one
    factorisation; the capacitance matrix and the induced fractions over the electrodes."""
    comm = disc.mesh.comm
    t0 = time.perf_counter()
    kept = disc.solver.get(linear_solver) if disc.solver is not None else None
    if kept is not None:   # a moved mesh: same sparsity, the factorisation's analysis kept
        K, ksp, prefix = kept
        disc.A.ptap(disc.P, K)
        dx_api.refactor(ksp, K, kind=linear_solver, symmetric=True)
    else:
        K = disc.A.ptap(disc.P)
        prefix = dx_api.unique_prefix("axisym")
        ksp = dx_api.create_ksp(comm, K, prefix=prefix, kind=linear_solver, symmetric=True)
    n_full = disc.ball_load.size

    def full(x, lift):
        y = disc.P.createVecLeft()
        disc.P.mult(x, y)
        return y.array + lift

    psis = []
    for electrode in disc.electrodes:
        g = np.zeros(n_full)
        g[electrode] = 1.0
        Ag = disc.A.createVecLeft()
        disc.A.mult(dx_api.vector(comm, g), Ag)
        rhs = disc.P.createVecRight()
        disc.P.multTranspose(Ag, rhs)
        rhs.scale(-1.0)
        psis.append(full(dx_api.solve(ksp, rhs), g))
    source = source_charge = None
    if source_solve:
        rhs = disc.P.createVecRight()
        disc.P.multTranspose(dx_api.vector(comm, (sigma / EPS0) * disc.ball_load), rhs)
        source = full(dx_api.solve(ksp, rhs), np.zeros(n_full))
    unit = None
    if unit_source:   # breakdown lines: the same back-substitution with σ = 1 C/m²
        rhs = disc.P.createVecRight()
        disc.P.multTranspose(dx_api.vector(comm, disc.ball_load / EPS0), rhs)
        unit = full(dx_api.solve(ksp, rhs), np.zeros(n_full))
    solve_time = time.perf_counter() - t0
    if disc.solver is not None:   # a reference mesh (field/moving.py) keeps its solver
        disc.solver[linear_solver] = (K, ksp, prefix)
    else:
        ksp.destroy()
        K.destroy()
        dx_api.clear_options(prefix)

    def apply_A(x):
        y = disc.A.createVecLeft()
        disc.A.mult(dx_api.vector(comm, x), y)
        return y.array.copy()

    A_psi = [apply_A(p) for p in psis]
    n = len(psis)
    C = 2.0 * math.pi * EPS0 * np.array([[psis[j] @ A_psi[k] for k in range(n)] for j in range(n)])
    C = 0.5 * (C + C.T)
    # q_k = -2π σ ∫_ball ψ_k r ds and q_ball = σ π d²: the fraction does not need σ
    fraction = -2.0 * np.array([disc.ball_load @ p for p in psis]) / ball_diameter**2
    if source is not None:
        # electrode charge = reaction of the source solve: 2π (ε0 A φ - σ b) on the electrode dofs
        residual = 2.0 * math.pi * (EPS0 * apply_A(source) - sigma * disc.ball_load)
        source_charge = np.array([residual[dofs].sum() for dofs in disc.electrodes])
    ball_area = 2.0 * math.pi * float(disc.ball_load.sum())
    return Solution(C, fraction, psis, source, source_charge, solve_time, ball_area, unit)


def richardson_error(change: float, degree: int) -> float:
    """Error of the coarse value from its change when the mesh size h is halved (same
    degree p), for functionals converging as h^(2p) (measured, see docs/field.md):
    change / (1 - 2^(-2p))."""
    return change / (1.0 - 2.0 ** (-2 * degree))


def permittivities(device, lay) -> dict[str, float]:
    return {"ball": device.ball_permittivity, "walls": device.wall_permittivity,
            "air": 1.0, "exterior": 1.0}


def mesh_model(build, comm, failure):
    """(mesh, cell_tags, facet_tags): ``build(gmsh)`` creates and meshes the current gmsh
    model (gmsh initialised here unless it is), distributed on ``comm`` from rank 0; a
    gmsh/OpenCASCADE failure is the one :class:`FieldError` line ``failure(exc)``. Shared
    by the tube (:func:`build_mesh`) and the cells (``field/cells/solve.py``)."""
    import gmsh

    from . import _dolfinx as dx_api
    from ._gmsh import initialize as initialize_gmsh

    initialised_here = not gmsh.isInitialized()
    if initialised_here:
        # interruptible=False: gmsh leaves Python's SIGINT handler alone (Ctrl-C
        # raises KeyboardInterrupt instead of killing the process)
        initialize_gmsh(["-nt", "1"], readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        try:
            build(gmsh)
        except FieldError:
            raise
        except Exception as exc:  # noqa: BLE001 - gmsh/OpenCASCADE: one line naming the keys
            raise FieldError(failure(exc)) from None
        mesh, cell_tags, facet_tags = dx_api.mesh_from_gmsh(gmsh.model, comm, rank=0, gdim=2)
        gmsh.model.remove()
    finally:
        if initialised_here:
            gmsh.finalize()
    return mesh, cell_tags, facet_tags


def build_mesh(scene, position: float, comm, **layout_overrides):
    """(layout, mesh, cell_tags, facet_tags) for the ball at ``position`` (on ``comm``)."""
    lay = geometry.layout(scene, position, **layout_overrides)
    geometry.check_mesh_budget(lay, scene.field.degree,
                               mesh_size_mm=geometry.base_mesh_size(scene) * 1e3)
    return (lay, *mesh_layout(lay, comm, scene))


def mesh_layout(lay, comm, scene):
    """(mesh, cell_tags, facet_tags) of the layout ``lay`` (on ``comm``); a gmsh failure
    is one line naming ``scene``'s keys."""
    return mesh_model(lambda gmsh: geometry.build_model(gmsh, lay, geometry_order=2), comm,
                      lambda exc: geometry.meshing_failure(scene, exc))


def solve_serial(scene, position: float, comm, **options) -> PositionResult:
    """The axisymmetric solve on one process (``comm`` of size 1), with the contact
    rule of :mod:`tengfield.field.contact` (the one the 3D solver uses too): its
    extrapolation error enters ``relative_error_estimate`` (and
    ``info['contact_extrapolation_error']``). The potentials kept for plots are
    those at the nearest anchor gap g.
    """
    dev = scene.device
    anchors = contact.contact_anchors(position, dev.stroke, dev.plate_spacing)
    if anchors is None:
        return solve_meshed(scene, position, comm, **options)
    return solve_by_contact_rule(position, anchors, dev.stroke,
                                 lambda z, **opts: solve_meshed(scene, z, comm, **opts), options)


#: ``info`` entries of a solve that the contact rule extrapolates like C and q (the
#: electrode charges of the source solve, the charge to infinity, the breakdown lines)
EXTRAPOLATED_INFO = ("source_electrode_charge_C", "far_field_charge_C", *LINE_KEYS)


def solve_by_contact_rule(position: float, anchors, stroke: float, solve_at_gap,
                          options: dict) -> PositionResult:
    """The contact rule (:func:`tengfield.field.contact.extrapolate_to_contact`) over an
    axisymmetric solver ``solve_at_gap(z, **options)`` -> PositionResult: C, q and the
    :data:`EXTRAPOLATED_INFO` entries extrapolated from the ``anchors``; the potentials
    kept (``keep_solution``) are those of the nearest anchor. Shared by the tube and the
    cells (``field/cells/solve.py``)."""
    t0 = time.perf_counter()
    later = {**options, "keep_solution": False}

    def solve_at(z):
        res = solve_at_gap(z, **(options if z == anchors[0] else later))
        if "source_electrode_charge_C" in res.info:
            res.extras = {"source": np.asarray(res.info["source_electrode_charge_C"])}
        for key in EXTRAPOLATED_INFO[1:]:   # the charge to infinity, the breakdown lines
            if key in res.info:
                res.extras = {**getattr(res, "extras", {}), key: np.asarray(res.info[key])}
        return res

    rule = contact.extrapolate_to_contact(position, anchors, stroke, solve_at)
    solves = rule["solves"]
    result = solves[0]
    if "source" in rule["extras"]:
        result.info["source_electrode_charge_C"] = rule["extras"]["source"]
    for key in EXTRAPOLATED_INFO[1:]:
        if key in rule["extras"]:
            result.info[key] = rule["extras"][key]
    result.capacitance = rule["capacitance"]
    result.induced_fraction = rule["induced_fraction"]
    result.induced_charge = rule["induced_fraction"] * result.ball_charge
    result.relative_error_estimate = max(max(r.relative_error_estimate for r in solves),
                                         rule["error"])
    result.position = position
    result.solve_time = sum(r.solve_time for r in solves)
    result.wall_time = time.perf_counter() - t0
    result.info["contact_rule"] = ("power-law extrapolation from gaps "
                                   + ", ".join(f"{d:.6g}" for d in rule["distances"]) + " m")
    result.info["contact_extrapolation_error"] = rule["error"]
    if all("mesh_placements" in r.info for r in solves):   # every anchor's meshes
        result.info["mesh_placements"] = {
            key: sum(r.info["mesh_placements"].get(key, 0) for r in solves)
            for key in ("moved", "meshed", "mapped")}
    result.info["contact_exponent"] = rule["exponent"]
    for r in solves:
        r.__dict__.pop("extras", None)
    return result


def canonical_device(device):
    """The tube ``device`` on the canonical grid (:func:`tengfield.field.moving.canonical_length`)
    of its independent lengths: the ball's diameter, the stroke, the radial clearance
    (bore - ball radius), the wall (outer - inner radius), the electrode's inset (bore -
    electrode radius, signed) and the plates' thickness; None when that device is
    impossible. The geometry a candidate's meshes are mapped from (docs/field.md)."""
    from .moving import canonical_length as grid

    d = grid(device.ball_diameter)
    bore = 0.5 * d + grid(device.tube_inner_radius - device.ball_radius)
    try:
        return dataclasses.replace(
            device, ball_diameter=d, stroke=grid(device.stroke), tube_inner_radius=bore,
            tube_outer_radius=bore + grid(device.tube_outer_radius - device.tube_inner_radius),
            electrode_radius=bore - grid(device.tube_inner_radius - device.electrode_radius),
            plate_thickness=grid(device.plate_thickness))
    except (TengfieldError, ValueError):
        return None


def canonical_scene(scene):
    """What :func:`geometry_axisymmetric.layout` reads of ``scene`` (its ``device`` and
    ``field``) with the device on the canonical grid (:func:`canonical_device`), or None."""
    device = canonical_device(scene.device)
    return None if device is None else _Canonical(device, scene.field)


def discretised(dx_api, scene, position: float, comm, eps: dict, *, moving: bool,
                grading_size: float | None = None):
    """``(layout, Discretisation)`` of ``scene`` with the ball at ``position``: meshed
    (gmsh), or with ``moving`` a reference mesh of the same scene and mesh size moved
    there (:func:`tengfield.field.moving.placed`, which meshes when the move would
    spoil the mesh), a missing reference mapped from the mesh of the scene's canonical
    geometry (:func:`canonical_device`)."""
    fld = scene.field
    extra = {} if grading_size is None else {"grading_size": grading_size}

    def mesh_and_discretise(z):
        lay, *meshed = build_mesh(scene, z, comm, **extra)
        return lay, discretise(dx_api, *meshed, lay, eps, fld.degree, fld.far_field)

    if not moving:
        return mesh_and_discretise(position)
    from . import moving as motion

    key = (scene.field_hash(), geometry.base_mesh_size(scene), grading_size)
    lay = geometry.layout(scene, position, **extra)
    settings = dict(degree=fld.degree, far_field=fld.far_field, grading_size=grading_size)
    family = motion.geometry_family(lay, permittivity=eps, **settings)

    def canonical(rung):
        """The canonical geometry at ``rung``: (key, layout, family, mesh()) or None."""
        canon = canonical_scene(scene)
        if canon is None:
            return None
        device = canon.device
        z = motion.rung_gap(device.stroke, contact.minimum_gap(device.plate_spacing), rung)
        if z is None:
            return None
        options = dict(extra, mesh_size=lay.mesh_size,
                       domain_radius=motion.canonical_domain_radius(lay.domain_radius,
                                                                    fld.far_field))
        try:
            lay_c = geometry.layout(canon, z, **options)
        except FieldError:
            return None
        eps_c = permittivities(device, lay_c)

        def mesh():
            return discretise(dx_api, *mesh_layout(lay_c, comm, scene), lay_c, eps_c,
                              fld.degree, fld.far_field)
        lengths = (device.ball_diameter, device.stroke, device.tube_inner_radius,
                   device.tube_outer_radius, device.electrode_radius, device.plate_thickness)
        return ((lengths, z, tuple(sorted(options.items()))), lay_c,
                motion.geometry_family(lay_c, permittivity=eps_c, **settings), mesh)

    return motion.placed(key, lay, lambda z: geometry.layout(scene, z, **extra),
                         lambda z: mesh_and_discretise(z)[1],
                         lambda disc: reassemble(dx_api, disc), dx_api,
                         minimum_gap=contact.minimum_gap(scene.device.plate_spacing),
                         family=family, canonical=canonical)


@dataclass(frozen=True)
class _Canonical:
    """What :func:`geometry_axisymmetric.layout` reads of a scene, for a canonical device."""
    device: object
    field: object


def solve_meshed(scene, position: float, comm, *, estimate_error: bool = True,
                 keep_solution: bool = False, source_solve: bool = False,
                 linear_solver: str = "direct", breakdown_lines: bool = False) -> PositionResult:
    """One axisymmetric solve of the geometry with the ball at gap ``position`` (one process)."""
    from . import _dolfinx as dx_api

    t0 = time.perf_counter()
    fld = scene.field
    # the scene's mesh_size_mm as written, or its default scaled to the device's features
    size = geometry.base_mesh_size(scene)
    if estimate_error:   # refuse before any meshing if the finer mesh would not fit
        half = scene.with_values(field={"mesh_size_mm": 0.5e3 * size})
        geometry.check_mesh_budget(geometry.layout(half, position, grading_size=size),
                                   fld.degree, mesh_size_mm=size * 1e3, refinement=2.0)
    moving = getattr(fld, "mesh_motion", "remesh") == "move" and not keep_solution
    eps = permittivities(scene.device, geometry.layout(scene, position))
    lay, disc = discretised(dx_api, scene, position, comm, eps, moving=moving)
    mesh = disc.mesh
    sigma = scene.device.surface_charge
    diameter = scene.device.ball_diameter
    sol = solve_discretisation(dx_api, disc, sigma, diameter, source_solve=source_solve,
                               linear_solver=linear_solver, unit_source=breakdown_lines)
    estimate = math.nan
    finer = None
    if estimate_error:
        # same grading lengths as the coarse mesh: a uniform halving of one mesh family
        lay_half, finer = discretised(dx_api, half, position, comm, eps, moving=moving,
                                      grading_size=size)
        fine = solve_discretisation(dx_api, finer, sigma, diameter, source_solve=False,
                                    linear_solver=linear_solver, unit_source=breakdown_lines)
        estimate = richardson_error(contact.relative_change(sol, fine), fld.degree)
        if breakdown_lines:
            from .breakdown import line_basis
            lines_check = line_basis(dx_api, finer, fine.unit_source, fine.weighting, lay_half)
    info = {"mesh_size_m": lay.mesh_size, "domain_radius_m": lay.domain_radius,
            "mesh_motion": "move" if moving else "remesh",
            "mesh_placements": placements(disc, finer),
            "far_field": fld.far_field, "environment": fld.environment,
            "meshed_gap_m": lay.effective_gap,
            "minimum_gap_m": contact.minimum_gap(scene.device.plate_spacing),
            "ball_area_quadrature_m2": sol.ball_area, "error_estimate": "Richardson, mesh_size/2, rate h^(2p)"}
    if sol.source_charge is not None:
        info["source_electrode_charge_C"] = sol.source_charge
    if breakdown_lines:   # basis potentials on the ball surface (tengfield.field.breakdown)
        from .breakdown import line_basis
        info["breakdown_lines"] = line_basis(dx_api, disc, sol.unit_source, sol.weighting, lay)
        if estimate_error:
            info["breakdown_lines_check"] = lines_check
    ball_charge = scene.device.ball_charge
    result = PositionResult(
        position=position, offset=0.0, capacitance=sol.capacitance,
        induced_charge=sol.induced_fraction * ball_charge, ball_charge=ball_charge,
        dofs=dx_api.num_dofs(disc.V), cells=dx_api.num_cells(mesh), method="axisymmetric",
        degree=fld.degree, wall_time=time.perf_counter() - t0,
        relative_error_estimate=estimate, solve_time=sol.solve_time, info=info,
        induced_fraction=sol.induced_fraction)
    if keep_solution:
        result.solution = field_solution(dx_api, disc, sol, lay)
    from .moving import done_with
    done_with(dx_api, disc, finer, moving=moving)   # PETSc frees nothing by itself
    return result


def field_solution(dx_api, disc: Discretisation, sol: Solution, lay) -> FieldSolution:
    """The public :class:`FieldSolution` of one axisymmetric discretisation."""
    weighting = tuple(dx_api.function(disc.V, psi, name=f"psi_{name}")
                      for psi, name in zip(sol.weighting,
                                           getattr(lay, "electrodes", ("lower", "upper"))))
    source = None if sol.source is None else dx_api.function(disc.V, sol.source,
                                                             name="phi_source_V")
    return FieldSolution(
        method="axisymmetric", mesh=disc.mesh, cell_tags=disc.cell_tags,
        facet_tags=disc.facet_tags, space=disc.V, weighting=weighting,
        ball_centre=np.array([0.0, lay.ball_centre_z, 0.0]), geometry=lay, source=source,
        hidden_cells=np.asarray(disc.cell_tags.find(geometry.CELL_TAGS["exterior"]),
                                dtype=np.int32), degree=disc.degree)


def solve_position_axisymmetric(scene, position: float, *, comm, **options) -> PositionResult:
    """:class:`PositionResult` of the axisymmetric problem; computed on rank 0 of ``comm``
    and broadcast (an exception on rank 0 is re-raised on every rank).

    Options: ``estimate_error`` (default True: solve again with half the mesh
    size), ``source_solve`` (also solve for the potential of the ball charge,
    needed for plots), ``keep_solution`` (serial only: keep mesh and potentials
    in ``result.solution``), ``linear_solver`` ("direct": CHOLMOD / MUMPS, or "cg-amg").
    """
    from . import _dolfinx  # noqa: F401 - on every rank: PETSc initialises collectively

    unknown = set(options) - set(SOLVER_OPTIONS)
    if unknown:
        raise FieldError(f"unknown axisymmetric solver option(s) {sorted(unknown)}; "
                         f"allowed: {', '.join(SOLVER_OPTIONS)}")
    return solved_on_rank_zero(comm, lambda here: solve_serial(scene, position, here, **options),
                               keep_solution=bool(options.get("keep_solution")))


def solved_on_rank_zero(comm, solve, *, keep_solution: bool = False):
    """``solve(here)`` on ``comm`` itself when it has one rank, else on rank 0 (``here`` =
    ``COMM_SELF``) with its result (or exception) broadcast to every rank; the tube's and
    the cells' axisymmetric solves."""
    from mpi4py import MPI

    if comm.size == 1:
        return solve(comm)
    if keep_solution:
        raise FieldError("keep_solution needs a communicator of size 1")
    outcome = None
    if comm.rank == 0:
        try:
            outcome = solve(MPI.COMM_SELF)
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank below
            outcome = exc
    outcome = comm.bcast(outcome, root=0)
    if isinstance(outcome, Exception):
        raise outcome
    return outcome
