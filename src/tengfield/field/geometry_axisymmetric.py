"""gmsh model of the BB-TENG in the axisymmetric (r, z) half-plane.

Coordinates: x = r ≥ 0 (radius), y = z (tube axis), origin midway between
the electrode faces, SI (metres). The lower electrode is the segment
``z = -h/2, 0 ≤ r ≤ a``, the upper one ``z = +h/2`` (h = plate spacing,
a = electrode radius; zero-thickness conductors on the inner faces of the
PMMA plates). The ball (radius d/2) sits on the axis with its bottom at gap
``z_gap`` above the lower electrode.

Far field: the computational domain is the half-disk of radius R
(``domain_radius``) around the *inversion centre* (device centre, or the
table point below it for a grounded table). For ``far_field = "kelvin"`` a
second half-disk, the Kelvin image of the exterior ``|x| > R`` under
``x' = R² x/|x|²``, is meshed in the same model, translated by ``shift``
along z, with its arc periodic (node-for-node identical, up to the shift) to
the domain's arc.

Contact rule (z → 0, z → Δh): the layout clamps the gap to
``[min_gap, Δh - min_gap]``; positions closer to a plate are extrapolated by
the solver, see :mod:`tengfield.field.contact` (one rule for both solvers).

Mesh grading (all sizes scale with the base size ``mesh_size``):

* radical grading toward the electrode rims and the tube corners,
  ``s = mesh_size · (ρ/L)^(1-μ)`` (ρ = distance to the rim, L = h/4,
  μ = α/p with α = 0.43 the strongest singular exponent observed, at the
  rim/tube corner), which restores the optimal convergence rate of a
  smooth problem under uniform refinement;
* ``s = 0.4 · mesh_size`` on the ball surface, growing linearly away;
* in the ball-electrode gaps, ``s = (mesh_size/ℓ) · w(ρ)`` where
  ``w(ρ) ≈ g + ρ²/d`` is the local gap width and ``ℓ = 1 mm · d / 7 mm`` (the paper's
  ball: 1 mm exactly), so the rule is scale-free: the paper's device divided by k with
  its mesh size divided by k is the paper's mesh divided by k (it used ℓ = 1 mm for
  every device, and a device /30 meshed its gaps 30x finer than the paper's, in
  ~900x the cells: gmsh ran for minutes at 11 GB);
* far away the size grows with the distance to the device.

Physical groups (no point groups): surfaces ``ball``, ``walls``, ``air``,
``exterior`` (Kelvin image); curves ``ball_surface``, ``electrode_lower``,
``electrode_upper``, ``far_boundary``, ``far_boundary_image``, ``table``,
``table_image``.
"""
from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass, field

from ..errors import FieldError
from ..scene.limits import PAPER_FEATURES, default_mesh_scale
from . import contact

#: strongest singular exponent of the field (rim of an electrode meeting the tube corner)
RIM_EXPONENT = 0.43
#: The mesh grades away from the features (ball, rims, gaps, dielectric interfaces)
#: over lengths of at most GRADING_REACH x the base mesh size, so a large device
#: costs what its features cost, not what its box costs. For the paper's device
#: (h = 10 mm, extent 8.6 mm) at mesh sizes >= 0.125 mm the lengths are the
#: device's own (h/4 and the extent) and the mesh is the one of earlier versions.
GRADING_REACH = 20.0
# The default mesh size is scaled to the device's smallest features (PAPER_FEATURES,
# mesh_features, default_mesh_scale): a rule of tengfield.scene.limits, since the
# scene's own "too fine" check needs the same rule.
#: relative precision of gmsh's integral of 1/size along the curves (its default,
#: 1e-9, spends half of the meshing time of the steeply graded rims there)
LC_INTEGRATION_PRECISION = 1e-6
#: growth of the element size per unit distance from a dielectric interface
INTERFACE_GROWTH = 0.3
#: refuse to mesh beyond this many estimated dofs (MUMPS needs ~1-2 kB per dof in 2D;
#: the paper's device at default settings: 13k, its error-estimate mesh ~50k)
MAX_DOFS_2D = 1_000_000
#: names of the physical groups and their tags
CELL_TAGS = {"ball": 1, "walls": 2, "air": 3, "exterior": 4}
FACET_TAGS = {"ball_surface": 11, "electrode_lower": 12, "electrode_upper": 13,
              "far_boundary": 14, "far_boundary_image": 15, "table": 16, "table_image": 17}

_model_counter = itertools.count()


@dataclass(frozen=True)
class AxisymmetricLayout:
    """Dimensions of one axisymmetric geometry (SI) and where its parts are."""
    ball_radius: float
    ball_centre_z: float
    plate_spacing: float
    plate_thickness: float
    electrode_radius: float
    tube_inner_radius: float
    tube_outer_radius: float
    walls: bool
    table: bool
    domain_radius: float
    inversion_centre_z: float
    kelvin: bool
    shift: float
    gap_lower: float
    gap_upper: float
    requested_gap: float
    effective_gap: float
    mesh_size: float
    grading_exponent: float
    info: dict = field(default_factory=dict)
    #: the conductors, in the order of the field's matrices (``[device] electrodes``):
    #: ("lower", "upper"), or ("lower",) for the single-electrode cell (the upper plate bare)
    electrodes: tuple = ("lower", "upper")

    @property
    def z_lower(self) -> float:
        return -0.5 * self.plate_spacing

    @property
    def z_upper(self) -> float:
        return 0.5 * self.plate_spacing

    @property
    def z_table(self) -> float:
        return self.z_lower - self.plate_thickness

    def plot_outline(self) -> dict:
        """What field.png draws (SI, (r, z) polylines for r >= 0, mirrored by the plot):
        ``electrodes`` (the two disks), ``walls`` (the plates and the tube, with walls),
        ``half_width`` and ``z_range`` of the frame, ``on_electrode(r, z, tol)`` where
        field lines stop, ``height_label``, ``table_z`` (the grounded table's face, or
        None): the keys of every cell's ``plot_outline``."""
        import numpy as np

        zl, zu, t = self.z_lower, self.z_upper, self.plate_thickness
        a, ri, ro = self.electrode_radius, self.tube_inner_radius, self.tube_outer_radius
        walls = []
        if self.walls:
            walls = [np.array([[0.0, zl - t], [ro, zl - t], [ro, zl], [0.0, zl]]),
                     np.array([[0.0, zu], [ro, zu], [ro, zu + t], [0.0, zu + t]]),
                     np.array([[ri, zl], [ro, zl], [ro, zu], [ri, zu], [ri, zl]])]

        heights = [z for name, z in (("lower", zl), ("upper", zu)) if name in self.electrodes]

        def on_electrode(r, z, tol):
            near = np.zeros(np.shape(z), dtype=bool)
            for height in heights:
                near |= np.abs(z - height) < tol
            return near & (np.abs(r) <= a)

        return {"electrodes": [np.array([[0.0, z], [a, z]]) for z in heights],
                "walls": walls, "half_width": ro + 2e-3, "z_range": (zl - t - 1.5e-3, zu + t + 1.5e-3),
                "on_electrode": on_electrode, "height_label": "the lower electrode",
                "table_z": zl - t if self.table else None}


def mesh_size_written(scene) -> bool:
    """Whether ``[field] mesh_size_mm`` is in the scene (its file or an override)."""
    return "mesh_size_mm" in ((scene.raw or {}).get("field") or {})


def base_mesh_size(scene) -> float:
    """The base mesh size [m] of ``scene``: ``[field] mesh_size_mm`` as written, or,
    when the scene does not give it, the default scaled by :func:`default_mesh_scale`."""
    size = scene.field.mesh_size
    if mesh_size_written(scene):
        return size
    return size * default_mesh_scale(scene.device, scene.field)


def mesh_size_text(scene) -> str:
    """``mesh_size_mm = X`` for messages, saying when X is the scaled default."""
    size_mm = base_mesh_size(scene) * 1e3
    if mesh_size_written(scene):
        return f"mesh_size_mm = {size_mm:g}"
    return (f"mesh_size_mm = {size_mm:.3g} (the default {scene.field.mesh_size * 1e3:g} "
            f"scaled by the device's smallest feature)")


def minimum_gap(device) -> float:
    """Smallest ball–electrode gap meshed [m] (:func:`tengfield.field.contact.minimum_gap`)."""
    return contact.minimum_gap(device.plate_spacing)


def effective_gap(device, position: float) -> float:
    """The gap actually meshed: ``position`` clamped to [min_gap, Δh - min_gap]."""
    return contact.clamp_gap(position, device.stroke, device.plate_spacing)


def layout(scene, position: float, *, degree: int | None = None, mesh_size: float | None = None,
           domain_radius: float | None = None, far_field: str | None = None,
           environment: str | None = None, grading_size: float | None = None
           ) -> AxisymmetricLayout:
    """Dimensions for ``scene`` with the ball at gap ``position`` [m] (pure, no gmsh).

    ``mesh_size`` [m] (default: :func:`base_mesh_size`, the scene's ``mesh_size_mm``
    as written or its scaled default) is used as given.

    ``grading_size`` [m] (default: the mesh size) sets the grading lengths
    (:data:`GRADING_REACH` times it); the error estimate's half-size mesh
    passes the coarse mesh's size, so both meshes belong to one family."""
    dev, fld = scene.device, scene.field
    position = float(position)
    degree = fld.degree if degree is None else degree
    mesh_size = base_mesh_size(scene) if mesh_size is None else mesh_size
    domain_radius = fld.domain_radius if domain_radius is None else domain_radius
    far_field = fld.far_field if far_field is None else far_field
    environment = fld.environment if environment is None else environment
    if not (mesh_size > 0 and math.isfinite(mesh_size)):
        raise FieldError(f"mesh_size_mm = {mesh_size * 1e3:g} is out of range: allowed (0, 100] mm")
    if dev.electrode_radius > dev.tube_outer_radius:
        raise FieldError(f"electrode_radius_mm = {dev.electrode_radius * 1e3:g} is larger than the "
                         f"plate: allowed (0, {dev.tube_outer_radius * 1e3:g}] mm")
    h = dev.plate_spacing
    z_gap = effective_gap(dev, position)
    table = environment == "grounded-table"
    z_lower = -0.5 * h
    centre = z_lower - dev.plate_thickness if table else 0.0
    extent = max(math.hypot(dev.tube_outer_radius, zz - centre)
                 for zz in (z_lower - dev.plate_thickness, -z_lower + dev.plate_thickness))
    grading_size = mesh_size if grading_size is None else grading_size
    # plain floats: gmsh MathEval strings use repr(), and numpy 2 writes np.float64(...)
    mesh_size, grading_size, domain_radius = float(mesh_size), float(grading_size), \
        float(domain_radius)
    if domain_radius <= 1.05 * extent:
        raise FieldError(f"domain_radius_mm = {domain_radius * 1e3:g} is too small: it must exceed "
                         f"{1.05e3 * extent:.3g} mm (the device seen from the inversion centre)")
    return AxisymmetricLayout(
        ball_radius=dev.ball_radius, ball_centre_z=z_lower + z_gap + dev.ball_radius,
        plate_spacing=h, plate_thickness=dev.plate_thickness,
        electrode_radius=dev.electrode_radius, tube_inner_radius=dev.tube_inner_radius,
        tube_outer_radius=dev.tube_outer_radius, walls=dev.wall_permittivity != 1.0,
        table=table, domain_radius=domain_radius, inversion_centre_z=centre,
        kelvin=far_field == "kelvin", shift=2.5 * domain_radius,
        gap_lower=z_gap, gap_upper=dev.stroke - z_gap, requested_gap=position, effective_gap=z_gap,
        mesh_size=mesh_size, grading_exponent=RIM_EXPONENT / max(degree, 1),
        info={"device_extent_m": extent,
              "rim_reach_m": min(0.25 * h, GRADING_REACH * grading_size),
              "bulk_length_m": min(extent, GRADING_REACH * grading_size)},
        electrodes=dev.electrode_names)


# ---------------------------------------------------------------------------
def build_model(gmsh, lay: AxisymmetricLayout, *, geometry_order: int = 2) -> str:
    """Create and mesh the gmsh model of ``lay``; returns the (unique) model name.

    ``gmsh`` is the initialised gmsh module; the new model is left current.
    """
    name = f"tengfield_axisym_{os.getpid()}_{next(_model_counter)}"
    gmsh.model.add(name)
    occ = gmsh.model.occ
    R, zK = lay.domain_radius, lay.inversion_centre_z
    rb, zb = lay.ball_radius, lay.ball_centre_z
    zl, zu, t = lay.z_lower, lay.z_upper, lay.plate_thickness
    a, ri, ro = lay.electrode_radius, lay.tube_inner_radius, lay.tube_outer_radius

    def half_disk(zc, radius, quarter):
        disk = occ.addDisk(0.0, zc, 0.0, radius, radius)
        zmin = zc if quarter else zc - radius
        box = occ.addRectangle(0.0, zmin, 0.0, radius, zc + radius - zmin)
        out, _ = occ.intersect([(2, disk)], [(2, box)])
        return out[0][1]

    domain = half_disk(zK, R, lay.table)
    ball = half_disk(zb, rb, False)
    tools = [(2, ball)]
    if lay.walls:
        tools += [(2, occ.addRectangle(0.0, zl - t, 0.0, ro, t)),
                  (2, occ.addRectangle(0.0, zu, 0.0, ro, t)),
                  (2, occ.addRectangle(ri, zl, 0.0, ro - ri, zu - zl))]
    electrodes = [(1, occ.addLine(occ.addPoint(0.0, z, 0.0), occ.addPoint(a, z, 0.0)))
                  for name, z in (("lower", zl), ("upper", zu)) if name in lay.electrodes]
    _, children = occ.fragment([(2, domain)], tools + electrodes)
    # children[i]: the pieces of input i (domain, ball, walls..., electrodes)
    ball_parts = {tag for _, tag in children[1]}
    wall_parts = {tag for parts in children[2:2 + len(tools) - 1] for _, tag in parts}
    image = half_disk(zK + lay.shift, R, lay.table) if lay.kelvin else None
    occ.synchronize()

    groups = surface_groups(gmsh, image, ball_parts, wall_parts)

    # -- classify curves by a point in their parametric middle -------------
    tol = 1e-9 * R
    pad = 2e-7 + 1e-6 * R  # gmsh pads bounding boxes by its tolerance (1e-7 m)
    mids: dict[int, float] = {}
    for _, c in gmsh.model.getEntities(1):
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        x, y, _ = gmsh.model.getValue(1, c, [0.5 * (lo[0] + hi[0])])
        bb = gmsh.model.getBoundingBox(1, c)
        mids[c] = y
        if x < tol and bb[3] < pad:
            continue  # the symmetry axis: natural condition (weight r)
        if image is not None and y > zK + R + tol:
            if abs(math.hypot(x, y - zK - lay.shift) - R) < 1e3 * tol:
                groups["far_boundary_image"].append(c)
            elif lay.table and abs(y - zK - lay.shift) < tol:
                groups["table_image"].append(c)
        elif abs(math.hypot(x, y - zb) - rb) < 1e3 * tol and x > tol:
            groups["ball_surface"].append(c)
        elif abs(math.hypot(x, y - zK) - R) < 1e3 * tol:
            groups["far_boundary"].append(c)
        elif lay.table and abs(y - zK) < tol:
            groups["table"].append(c)
        elif abs(y - zl) < tol and bb[3] <= a + pad and "lower" in lay.electrodes:
            groups["electrode_lower"].append(c)
        elif abs(y - zu) < tol and bb[3] <= a + pad and "upper" in lay.electrodes:
            groups["electrode_upper"].append(c)   # (a bare plate's face is no electrode)

    register_groups(gmsh, groups, mids, kelvin_shift=None if image is None else lay.shift,
                    what="axisymmetric", name=name, electrodes=lay.electrodes)

    interfaces = []
    if wall_parts:
        for _, c in gmsh.model.getBoundary([(2, s) for s in wall_parts], combined=False,
                                           oriented=False):
            x, y, _ = gmsh.model.getValue(1, abs(c), [0.5 * sum(
                gmsh.model.getParametrizationBounds(1, abs(c))[i][0] for i in (0, 1))])
            if x > tol:          # not the symmetry axis
                interfaces.append(abs(c))
    _size_fields(gmsh, lay, sorted(set(interfaces)))
    gmsh.model.mesh.generate(2)
    if geometry_order > 1:
        gmsh.model.mesh.setOrder(geometry_order)
    return name


def surface_groups(gmsh, image, ball_parts, wall_parts) -> dict[str, list[int]]:
    """Every group name of :data:`CELL_TAGS` and :data:`FACET_TAGS` -> [] but the
    surfaces: the Kelvin image (``exterior``), the ball, the walls, the rest air."""
    groups: dict[str, list[int]] = {k: [] for k in (*CELL_TAGS, *FACET_TAGS)}
    for _, s in gmsh.model.getEntities(2):
        if s == image:
            groups["exterior"].append(s)
        elif s in ball_parts:
            groups["ball"].append(s)
        elif s in wall_parts:
            groups["walls"].append(s)
        else:
            groups["air"].append(s)
    return groups


def register_groups(gmsh, groups: dict, mids: dict, *, kelvin_shift: float | None, what: str,
                    name: str, electrodes: tuple = ("lower", "upper")) -> None:
    """Check that the model has its required groups, pair the Kelvin image's arcs with the
    far boundary's (periodic, shifted by ``kelvin_shift``; None: no image) by their
    middles' heights ``mids``, and add the physical groups (:data:`CELL_TAGS`,
    :data:`FACET_TAGS`); ``what`` names the geometry in the messages (the tube's and the
    spherical shell's models); ``electrodes``: the conductors the model has."""
    required = ("ball", "air", "ball_surface", *(f"electrode_{e}" for e in electrodes),
                "far_boundary")
    for key in required:
        if not groups[key]:
            raise FieldError(f"{what} geometry: no {key!r} entity found (gmsh model {name})")
    if kelvin_shift is not None:
        masters = sorted(groups["far_boundary"], key=mids.get)
        slaves = sorted(groups["far_boundary_image"], key=mids.get)
        if len(masters) != len(slaves):
            raise FieldError(f"{what} geometry: the Kelvin arcs do not pair up")
        translation = [1, 0, 0, 0, 0, 1, 0, kelvin_shift, 0, 0, 1, 0, 0, 0, 0, 1]
        gmsh.model.mesh.setPeriodic(1, slaves, masters, translation)
    for key, tag in CELL_TAGS.items():
        if groups[key]:
            gmsh.model.addPhysicalGroup(2, groups[key], tag)
            gmsh.model.setPhysicalName(2, tag, key)
    for key, tag in FACET_TAGS.items():
        if groups[key]:
            gmsh.model.addPhysicalGroup(1, groups[key], tag)
            gmsh.model.setPhysicalName(1, tag, key)


def _size_fields(gmsh, lay: AxisymmetricLayout, interface_curves=()) -> None:
    """Background mesh size: radical grading at rims, ball surface, gaps, dielectric
    interfaces, bulk and far field (the Min of all)."""
    fld = gmsh.model.mesh.field
    h = lay.mesh_size
    zl, zu = lay.z_lower, lay.z_upper
    mu = lay.grading_exponent
    fields = []

    def distance_to_points(points):
        """Expression: distance to the nearest of ``points``."""
        terms = [f"Sqrt((x - ({x!r}))^2 + (y - ({y!r}))^2)" for x, y in points]
        expr = terms[0]
        for term in terms[1:]:
            expr = f"Min({expr}, {term})"
        return f"({expr})"

    sizes = []   # MathEval expressions, evaluated as one (their Min)

    def math_eval(expr):
        sizes.append(expr)

    L = lay.info["rim_reach_m"]
    # rims (and tube corners when the walls are present)
    rims = [(lay.electrode_radius, zl), (lay.electrode_radius, zu)]
    if lay.walls and abs(lay.tube_inner_radius - lay.electrode_radius) > 1e-12:
        rims += [(lay.tube_inner_radius, zl), (lay.tube_inner_radius, zu)]
    d_rim = distance_to_points(rims)
    rho_min = L * (h / L) ** (1.0 / mu) if h < L else L
    math_eval(f"({h!r}) * (Max({d_rim}, ({rho_min!r})) / ({L!r}))^({1.0 - mu!r})")

    # ball surface
    d_ball = f"Abs(Sqrt(x^2 + (y - ({lay.ball_centre_z!r}))^2) - ({lay.ball_radius!r}))"
    math_eval(f"({0.4 * h!r}) + 0.3 * {d_ball}")

    # ball-electrode gaps: local width g + rho^2/d (rho = distance to the axis point)
    for gap, z0 in ((lay.gap_lower, zl), (lay.gap_upper, zu)):
        if gap < 2.0 * h:
            d_gap = distance_to_points([(0.0, z0)])
            math_eval(f"({gap_size_factor(lay)!r}) * (({gap!r}) + {d_gap}^2 / "
                      f"({2.0 * lay.ball_radius!r}))")

    # dielectric interfaces: h on them, growing linearly away
    if interface_curves:
        dist = fld.add("Distance")
        fld.setNumbers(dist, "CurvesList", interface_curves)
        fld.setNumber(dist, "Sampling", 200)
        math_eval(f"({h!r}) + {INTERFACE_GROWTH!r} * F{dist}")

    # bulk and far field: h within bulk_length of the inversion centre, then growing
    extent = lay.info["bulk_length_m"]
    zK = lay.inversion_centre_z
    math_eval(f"({h!r}) * Max(1, Sqrt(x^2 + (y - ({zK!r}))^2) / ({extent!r}))")
    finish_size_fields(gmsh, lay, sizes, fields, centre_z=zK)


def finish_size_fields(gmsh, lay, sizes: list, fields: list, *, centre_z: float = 0.0) -> None:
    """The end of a (r, z) model's size fields (the tube's and the spherical shell's,
    ``field/cells/shell_model.py``): with ``lay.kelvin`` the Kelvin image's box (size
    h R / bulk_length around ``centre_z + lay.shift``) joins ``fields``; the Min of the
    MathEval expressions ``sizes`` and of ``fields`` is the background mesh; the
    mesher's options."""
    fld = gmsh.model.mesh.field
    h, extent = lay.mesh_size, lay.info["bulk_length_m"]
    if lay.kelvin:
        arc_size = h * lay.domain_radius / extent
        box = fld.add("Box")
        fld.setNumber(box, "VIn", arc_size)
        fld.setNumber(box, "VOut", 1e22)
        fld.setNumber(box, "XMin", -1.0)
        fld.setNumber(box, "XMax", 1.0)
        fld.setNumber(box, "YMin", centre_z + lay.shift - 1.5 * lay.domain_radius)
        fld.setNumber(box, "YMax", centre_z + lay.shift + 1.5 * lay.domain_radius)
        fields.append(box)
    # one MathEval for the Min of all the expressions: the same sizes to the bit (the
    # same arithmetic) as one field each, and 20 % less meshing time (gmsh evaluates
    # the size ~16 times per triangle, and each field evaluation has its overhead)
    combined = sizes[0]
    for expr in sizes[1:]:
        combined = f"Min({combined}, {expr})"
    size = fld.add("MathEval")
    fld.setString(size, "F", combined)
    fmin = fld.add("Min")
    fld.setNumbers(fmin, "FieldsList", [size, *fields])
    fld.setAsBackgroundMesh(fmin)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25 * lay.domain_radius)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.LcIntegrationPrecision", LC_INTEGRATION_PRECISION)
    # no Laplacian smoothing pass after the frontal-Delaunay mesher: 25 % less meshing
    # time, and on the default device a smaller error (estimate 2.43e-4 instead of
    # 2.53e-4 at z = 1.5 mm, same dofs)
    gmsh.option.setNumber("Mesh.Smoothing", 0)


def gap_size_factor(lay: AxisymmetricLayout) -> float:
    """``c`` of the gap rule ``s = c · (g + ρ²/d)``: mesh_size / ℓ, ℓ = 1 mm · d / 7 mm
    (exactly ``mesh_size / 1e-3`` for the paper's 7 mm ball)."""
    scale = 2.0 * lay.ball_radius / PAPER_FEATURES["ball_diameter_mm"]
    return lay.mesh_size / (1e-3 * scale)


def _gap_cells(lay: AxisymmetricLayout) -> float:
    """Triangles of the gap rule where it is finer than the base size: the half-disk
    around the axis point of each gap, ∫ π ρ dρ / (0.433 s²) with s = c (g + ρ²/d), is
    π d / (0.866 c²) (1/g - 1/g_max), g_max = h / c the width where s reaches h."""
    h, c, d = lay.mesh_size, gap_size_factor(lay), 2.0 * lay.ball_radius
    cells = 0.0
    for gap in (lay.gap_lower, lay.gap_upper):
        if 0.0 < gap < 2.0 * h and gap < h / c:
            cells += math.pi * d / (0.866 * c * c) * (1.0 / gap - c / h)
    return cells


def estimated_cells(lay: AxisymmetricLayout) -> float:
    """Rough number of triangles of the mesh of ``lay`` (before meshing, from the
    size fields of :func:`_size_fields`: bulk and far field, rims, ball surface,
    ball-electrode gaps, dielectric interfaces; a triangle of size s covers ~0.433 s²)."""
    h = lay.mesh_size
    area = 0.433 * h * h
    B, R = lay.info["bulk_length_m"], lay.domain_radius
    bulk = 0.5 * math.pi * B * B / area * (1.0 + 2.0 * math.log(max(R / B, 1.0)))
    L, mu = lay.info["rim_reach_m"], lay.grading_exponent
    rims = (4 if lay.walls else 2) * math.pi * L * L / (2.0 * mu * area)
    ball = math.pi * lay.ball_radius / (0.433 * 0.3 * 0.4 * h)
    interfaces = 0.0
    if lay.walls:
        length = 2.0 * lay.tube_outer_radius + 4.0 * lay.plate_thickness + 2.0 * lay.plate_spacing \
            + 2.0 * (lay.tube_outer_radius - lay.tube_inner_radius)
        interfaces = length / (0.433 * INTERFACE_GROWTH * h)
    image = bulk * 0.5 if lay.kelvin else 0.0
    return bulk + rims + ball + interfaces + image + _gap_cells(lay)


def estimated_dofs(lay: AxisymmetricLayout, degree: int) -> float:
    """Rough number of dofs: ~cells/2 vertices, plus ~1.5 cells edge midpoints for P2."""
    cells = estimated_cells(lay)
    return cells * (0.5 + (1.5 if degree >= 2 else 0.0))


def check_mesh_budget(lay: AxisymmetricLayout, degree: int = 2, *,
                      mesh_size_mm: float | None = None, refinement: float = 1.0) -> None:
    """Raise :class:`FieldError` (one line, naming ``mesh_size_mm``) before meshing
    when the estimated dofs exceed :data:`MAX_DOFS_2D`. ``lay`` may be the error
    estimate's finer mesh (``refinement`` = 2): the message names the scene's
    ``mesh_size_mm`` all the same."""
    dofs = estimated_dofs(lay, degree)
    if dofs > MAX_DOFS_2D:
        named = lay.mesh_size * refinement * 1e3 if mesh_size_mm is None else mesh_size_mm
        smallest = named * math.sqrt(dofs / MAX_DOFS_2D)
        what = " (the error estimate's half-size mesh)" if refinement != 1.0 else ""
        raise FieldError(f"mesh_size_mm = {named:g} needs about {dofs:.2g} dofs{what}: "
                         f"allowed <= {MAX_DOFS_2D:.0e}, use mesh_size_mm >= {smallest:.2g} "
                         "for this device")


def meshing_failure(scene, exc: BaseException) -> str:
    """One line for a gmsh/OpenCASCADE failure, naming the keys that shape the mesh."""
    dev, fld = scene.device, scene.field
    first = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:160]
    return (f"gmsh could not mesh the device ({first}): check [device] stroke_mm = "
            f"{dev.stroke * 1e3:g}, ball_diameter_mm = {dev.ball_diameter * 1e3:g} and "
            f"[field] {mesh_size_text(scene)}, domain_radius_mm = "
            f"{fld.domain_radius * 1e3:g}")
