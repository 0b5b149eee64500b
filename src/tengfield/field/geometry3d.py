"""The 3D gmsh model of one BB-TENG cell (OCC kernel), SI units: the builder, the
placement rules and the mesh settings every 3D cell shares.

:func:`build_model` asks the cell for its parts (``placement_3d``, ``contact_rule_3d``,
``extent_3d``, ``occ_parts``, ``rim_distance_expr``, ``gap_refinements_3d``): each
shape answers in its own module of :mod:`tengfield.field.cells` (the tube's and the
honeycomb's :class:`~tengfield.field.cells.plate_model3d.CylindricalCell` and
:class:`~tengfield.field.cells.plate_model3d.HexagonalCell` in ``plate_model3d.py``,
the spherical shell's in ``shell_model3d.py``); nothing here names a shape.

Coordinates: the origin is the centre of the cell, z is the tube axis, the
lower electrode lies in the plane ``z = -h/2`` and the upper one in
``z = +h/2`` (``h = d + Δh``, the electrode spacing). The ball centre is at
``(offset cos φ, offset sin φ, -h/2 + z_gap + d/2)`` (φ = ``offset_angle``,
0 by default); ``z_gap`` is the gap between the ball's bottom and the lower
electrode, clamped to ``[g_min, Δh - g_min]`` by :func:`meshed_gap` (the
z → 0 / z → Δh rule shared with the axisymmetric builder; the solver
extrapolates positions closer than ``g_min``, see :func:`contact_anchors`).
The air fills a sphere of radius ``domain_radius``
centred at the origin; the far-field condition lives on that sphere.

Electrodes are zero-thickness conductor surfaces embedded in the mesh
(the copper foil is thin compared with everything else). Physical groups
(names, never point groups): volumes ``ball``, ``walls`` (absent when the
walls have εr = 1), ``air``; surfaces ``ball_surface``,
``electrode_<name>`` for each of the cell's electrodes (``electrode_lower``,
``electrode_upper``; the single-electrode cell has no upper one: its upper plate is
bare dielectric), ``far_boundary``.

gmsh is imported inside the functions that need it.
"""
from __future__ import annotations

import contextlib
import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import FieldError, show_number
from ..scene.shapes import enclosure

# The z → 0 / z → Δh rule is :mod:`tengfield.field.contact` (one rule for both
# solvers): no mesh has a ball-electrode gap below ``MIN_GAP_FRACTION · h``.
from . import contact  # noqa: E402  (no gmsh)
from .geometry_axisymmetric import RIM_EXPONENT  # noqa: E402  (no gmsh)

VOLUME_GROUPS = ("ball", "walls", "air")
SURFACE_GROUPS = ("ball_surface", "electrode_lower", "electrode_upper", "far_boundary")

_model_counter = itertools.count()

#: gmsh's ``Mesh.OptimizeThreshold`` for the 3D meshes: tets of lower quality (gamma)
#: are optimised after meshing (gmsh's default is 0.3; see :func:`build_model`)
OPTIMIZE_THRESHOLD = 0.2

#: ``[field] mesh_grading``: the allowed values (:class:`MeshSettings` ``grading``)
MESH_GRADINGS = ("uniform", "graded")


@dataclass(frozen=True)
class MeshSettings:
    """Element sizes [m] and order of a 3D mesh.

    ``size`` is the characteristic size inside the device. Refined zones:

    * electrode rims: radical grading ``s = size · (ρ/L)^(1-μ)`` (ρ the
      distance to the rim, L = h/4, μ = α/p with α = RIM_EXPONENT the
      strongest singular exponent, p = ``order``, the FE degree), floored
      at ``rim_floor · size``; this is the axisymmetric builder's rule and
      restores the smooth convergence rate under uniform refinement;
    * the ball surface: ``ball_factor · size``;
    * the contact gaps: half the gap at the ball's poles, growing linearly.

    Outside the device the size grows by ``growth`` per unit distance up
    to the far-field sphere.

    ``grading`` (``[field] mesh_grading``): ``"uniform"`` keeps ``size`` everywhere
    inside the device's bounding sphere (the zones above only refine). ``"graded"``
    puts the dofs where the error of C and q is (measured, docs/field3d.md "Graded
    meshes": at fine meshes the elements at the rims' floor decide it): the rims'
    floor is ``graded_rim_floor · size``, the zones above are sized from
    ``feature_factor · size`` instead of ``size``, and away from them the size grows up
    to ``bulk_factor · feature_factor · size`` in the rest of the device and from there
    by ``growth`` per unit distance to the far sphere (see :func:`_size_fields`).

    Study knobs (``Solve3DSettings.mesh_options``; no scene key): ``rim_factor`` scales
    the rims' grading (``rim_factor · size · (ρ/L)^…``), ``rim_power`` replaces its
    exponent ``1 - α/p`` when > 0 (docs/field3d.md, "Graded meshes").
    """
    size: float
    domain_radius: float
    order: int = 1
    rim_floor: float = 0.05
    ball_factor: float = 0.5
    growth: float = 0.3
    grading: str = "uniform"
    bulk_factor: float = 4.0
    feature_factor: float = 1.7
    graded_rim_floor: float = 0.02
    rim_factor: float = 1.0
    rim_power: float = 0.0

    def __post_init__(self):
        # plain floats: gmsh MathEval strings use repr(), and numpy 2 writes np.float64(...)
        for name in ("size", "domain_radius", "rim_floor", "ball_factor", "growth", "bulk_factor",
                     "feature_factor", "graded_rim_floor", "rim_factor", "rim_power"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if not (self.size > 0 and math.isfinite(self.size)):
            raise FieldError(f"mesh_size_mm = {self.size * 1e3!r} is out of range: allowed (0, 100] mm")
        if self.order not in (1, 2):
            raise FieldError(f"degree = {self.order!r}: the 3D mesh order must be 1 or 2")
        if self.grading not in MESH_GRADINGS:
            raise FieldError(f"[field] mesh_grading = {self.grading!r} is not allowed: choose one of "
                             + ", ".join(repr(g) for g in MESH_GRADINGS))


def minimum_gap(cell) -> float:
    """Smallest ball-electrode (and ball-tube) gap that is meshed [m]: ``MIN_GAP_FRACTION · h``."""
    return contact.minimum_gap(cell.electrode_spacing)


def check_position(cell, position: float) -> None:
    """Raise :class:`FieldError` unless ``0 <= position <= Δh``."""
    stroke = cell.stroke
    if not (math.isfinite(position) and 0.0 <= position <= stroke * (1 + 1e-12)):
        raise FieldError(f"position_mm = {show_number(position * 1e3, 0.0, stroke * 1e3)} is "
                         "out of range: allowed "
                         f"[0, {stroke * 1e3:g}] mm (the free stroke, [device] stroke_mm)")


def meshed_gap(cell, position: float) -> float:
    """The ball-lower-electrode gap [m] that is meshed for ``position`` z [m]:
    z clamped to ``[g_min, Δh - g_min]`` (:func:`minimum_gap`)."""
    check_position(cell, position)
    g_min = minimum_gap(cell)
    if cell.stroke < 4 * g_min:
        raise FieldError(f"[device] stroke_mm = {cell.stroke * 1e3:g} is too small for the 3D mesh: "
                         f"allowed > {4e3 * g_min:g} mm (4 x the minimum meshed gap)")
    return min(max(position, g_min), cell.stroke - g_min)


def contact_anchors(cell, position: float) -> tuple[float, float, float] | None:
    """The anchors of :func:`tengfield.field.contact.contact_anchors` for ``cell``
    (after checking ``0 <= position <= Δh``)."""
    check_position(cell, position)
    return contact.contact_anchors(position, cell.stroke, cell.electrode_spacing)


def meshed_offset(cell, offset: float) -> float:
    """The lateral offset [m] that is meshed: at most ``max_offset - g_min``
    (the ball never touches the tube wall in the mesh)."""
    max_offset = cell.max_offset
    if not (math.isfinite(offset) and 0.0 <= offset <= max_offset * (1 + 1e-12) + 1e-15):
        raise FieldError(f"offset_mm = {show_number(offset * 1e3, 0.0, max_offset * 1e3)} is "
                         "out of range: allowed "
                         f"[0, {max_offset * 1e3:g}] mm (the ball must stay inside the "
                         f"{enclosure(getattr(cell, 'name', 'tube'))})")
    return min(offset, max(max_offset - minimum_gap(cell), 0.0))


def ball_centre(cell, position: float, offset: float, offset_angle: float = 0.0) -> np.ndarray:
    """Ball centre [m] for the meshed gap and offset; the offset points at
    ``offset_angle`` [rad] from the +x axis (see module docstring)."""
    z_gap = meshed_gap(cell, position)
    off = meshed_offset(cell, offset)
    return np.array([off * math.cos(offset_angle), off * math.sin(offset_angle),
                     -0.5 * cell.electrode_spacing + z_gap + 0.5 * cell.ball_diameter])


# ---------------------------------------------------------------------------
# gmsh model construction (rank 0 only)

def unique_model_name(prefix: str) -> str:
    """A gmsh model name that no other model in this process uses."""
    return f"{prefix}-{next(_model_counter)}"


def build_model(cell, position: float, offset: float, settings: MeshSettings, *,
                offset_angle: float = 0.0) -> dict:
    """Build and mesh ``cell`` in the current gmsh model.

    The caller owns the gmsh session and the model (see
    :func:`tengfield.field.solver3d.gmsh_model`). Returns a dict with the
    physical group tags by name, the meshed gap and offset [m], and the
    ball centre [m].
    """
    import gmsh

    occ = gmsh.model.occ
    extent = cell.extent_3d(offset)
    if settings.domain_radius <= 1.2 * extent:
        raise FieldError(
            f"domain_radius_mm = {settings.domain_radius * 1e3:g} is too small: it must exceed "
            f"{1.2e3 * extent:.3g} mm (1.2 x the device's bounding radius)")
    centre, gap = cell.placement_3d(position, offset, offset_angle)
    radius = 0.5 * cell.ball_diameter

    domain = occ.addSphere(0, 0, 0, settings.domain_radius)
    ball = occ.addSphere(*centre, radius)
    electrodes, walls = cell.occ_parts(occ)

    objects = [(3, domain)]
    tools = [(3, ball)] + [(3, w) for w in walls] + [(2, e) for e in electrodes]
    _, piece_map = occ.fragment(objects, tools)
    occ.synchronize()
    # piece_map follows the order objects + tools
    ball_vols = [tag for _, tag in piece_map[1]]
    wall_vols = sorted({tag for pieces in piece_map[2:2 + len(walls)] for _, tag in pieces})
    # one surface per electrode the cell lists (``cell.electrodes``, the order of occ_parts)
    electrode_surfs = {f"electrode_{name}": [tag for _, tag in piece_map[2 + len(walls) + i]]
                       for i, name in enumerate(cell.electrodes)}
    all_vols = [tag for _, tag in gmsh.model.getEntities(3)]
    air_vols = [v for v in all_vols if v not in ball_vols and v not in wall_vols]
    ball_surfs = [tag for _, tag in gmsh.model.getBoundary([(3, v) for v in ball_vols],
                                                           combined=True, oriented=False)]
    far_surfs = [tag for _, tag in gmsh.model.getBoundary([(3, v) for v in all_vols],
                                                          combined=True, oriented=False)]

    groups = {}
    for name, dim, tags in (("ball", 3, ball_vols), ("walls", 3, wall_vols), ("air", 3, air_vols),
                            ("ball_surface", 2, ball_surfs),
                            *((group, 2, tags) for group, tags in electrode_surfs.items()),
                            ("far_boundary", 2, far_surfs)):
        if tags:
            groups[name] = gmsh.model.addPhysicalGroup(dim, tags, name=name)
    missing = [n for n in ("ball", "air", "ball_surface", *electrode_surfs, "far_boundary")
               if n not in groups]
    if missing:  # pragma: no cover - would be a gmsh/OCC regression
        raise FieldError(f"3D geometry: gmsh produced no entities for {', '.join(missing)}")

    _size_fields(cell, centre, settings, ball_surfs,
                 [c for tags in electrode_surfs.values() for s in tags
                  for _, c in gmsh.model.getBoundary([(2, s)], oriented=False)])
    # OPTIMIZE_THRESHOLD: gmsh's tet optimiser after HXT works on every tet of quality
    # below it; at the default 0.3 it spends most of the meshing on the few tets along the
    # graded electrode rims that it cannot improve (tube at 2 mm: 3D meshing 2.47 s ->
    # 0.33 s; 10 mm shell at 1.5 mm: 1.06 s -> 0.29 s; the worst tet the same within 0.02)
    with _gmsh_options({"Mesh.MeshSizeFromPoints": 0, "Mesh.MeshSizeFromCurvature": 0,
                        "Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.Algorithm3D": 10,
                        "Mesh.OptimizeThreshold": OPTIMIZE_THRESHOLD,
                        "Mesh.HighOrderOptimize": 2}):
        gmsh.model.mesh.generate(3)
        if settings.order == 2:
            gmsh.model.mesh.setOrder(2)
            _untangle_curved_elements()
    return {"groups": groups, "ball_centre": centre,
            "meshed_gap": gap,
            "meshed_offset": float(math.hypot(centre[0], centre[1]))}


@contextlib.contextmanager
def _gmsh_options(values: dict):
    """Set gmsh numeric options for a block and restore them after (gmsh options are
    global: other models in the same process must not inherit ours)."""
    import gmsh

    saved = {name: gmsh.option.getNumber(name) for name in values}
    try:
        for name, value in values.items():
            gmsh.option.setNumber(name, value)
        yield
    finally:
        for name, value in saved.items():
            gmsh.option.setNumber(name, value)


def _untangle_curved_elements() -> None:
    """Curving a second-order mesh onto the sphere can invert a few thin tets
    (negative Jacobian); gmsh's high-order optimiser fixes those locally."""
    import gmsh

    _, tags, _ = gmsh.model.mesh.getElements(3)
    quality = np.concatenate([gmsh.model.mesh.getElementQualities(t, "minSJ") for t in tags])
    if quality.min() <= 0.0:
        gmsh.model.mesh.optimize("HighOrder")


def eval_number(value) -> str:
    """A number in a gmsh MathEval expression: the shortest round-trip decimal of a
    plain float (numpy 2's repr writes ``np.float64(...)``, which gmsh's parser rejects
    by aborting the process)."""
    return repr(float(value))


def _gap_size(s_min, point) -> str:
    """MathEval size [m] growing from ``s_min`` at ``point`` (x, y, z) [m] with slope 0.35."""
    x, y, z = (eval_number(c) for c in point)
    return f"{eval_number(s_min)} + 0.35*sqrt((x-({x}))^2+(y-({y}))^2+(z-({z}))^2)"


#: ``grading = "graded"``: growth of the size per unit distance away from the ball surface
#: (the ball's Threshold field) up to the bulk size
GRADED_BALL_SLOPE = 0.4


def _size_fields(cell, centre, settings: MeshSettings, ball_surfs, rim_curves) -> None:
    """Background size [m]: the Min of the rim, ball-surface, gap and bulk/far-field
    gradings. ``"uniform"``: the zones are sized from ``size``, the rims floored at
    ``rim_floor · size``, the bulk is ``size`` inside the device's bounding sphere.
    ``"graded"``: the zones are sized from ``h = feature_factor · size``, the rims
    floored at ``graded_rim_floor · size``, the bulk is ``bulk_factor · h``, and the
    ball's Threshold grows from ``ball_factor · h`` to it with slope
    :data:`GRADED_BALL_SLOPE` (the rims' radical grading and the gaps' linear growth
    reach it by themselves)."""
    import gmsh

    fld = gmsh.model.mesh.field
    graded = settings.grading == "graded"
    h = settings.size * (settings.feature_factor if graded else 1.0)
    floor = settings.size * (settings.graded_rim_floor if graded else settings.rim_floor)
    bulk = settings.bulk_factor * h if graded else h
    fields = []

    power = settings.rim_power or 1.0 - RIM_EXPONENT / settings.order
    reach = 0.25 * cell.electrode_spacing
    rim = fld.add("MathEval")
    rho = f"({cell.rim_distance_expr()})"
    grading = (f"{eval_number(settings.rim_factor * h)}*({rho}/{eval_number(reach)})"
               f"^{eval_number(power)}")
    fld.setString(rim, "F", f"max({eval_number(floor)}, {grading})")
    fields.append(rim)

    ball_dist = fld.add("Distance")
    fld.setNumbers(ball_dist, "SurfacesList", ball_surfs)
    fld.setNumber(ball_dist, "Sampling", 60)
    ball = fld.add("Threshold")
    fld.setNumber(ball, "InField", ball_dist)
    fld.setNumber(ball, "SizeMin", settings.ball_factor * h)
    fld.setNumber(ball, "SizeMax", bulk)
    fld.setNumber(ball, "DistMin", 0.25 * h)
    fld.setNumber(ball, "DistMax", (0.25 * h + (bulk - settings.ball_factor * h) / GRADED_BALL_SLOPE)
                  if graded else 2.0 * h)
    fld.setNumber(ball, "StopAtDistMax", 1)
    fields.append(ball)

    # contact gaps: size grows linearly with the distance from the gap's midpoint (from at
    # least 0.02 size at the closest point, at most the ball's surface size)
    ball_factor = settings.ball_factor * (settings.feature_factor if graded else 1.0)
    for s_min, point in cell.gap_refinements_3d(centre, settings.size, ball_factor):
        gap_field = fld.add("MathEval")
        fld.setString(gap_field, "F", _gap_size(s_min, point))
        fields.append(gap_field)

    device_r = cell.bounding_radius
    far = fld.add("MathEval")
    fld.setString(far, "F", f"max({eval_number(bulk)}, {eval_number(bulk)} + {eval_number(settings.growth)}"
                            f"*(sqrt(x^2+y^2+z^2) - {eval_number(device_r)}))")
    fields.append(far)

    total = fld.add("Min")
    fld.setNumbers(total, "FieldsList", fields)
    fld.setAsBackgroundMesh(total)


def mesh_statistics() -> dict:
    """Statistics of the current (first-order) gmsh mesh: node count, and per
    physical group the element count and measure (volume [m³] or area [m²])."""
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = np.zeros((int(tags.max()) + 1, 3))
    xyz[tags.astype(int)] = coords.reshape(-1, 3)
    stats = {"nodes": int(len(tags)), "groups": {}}
    for dim, tag in gmsh.model.getPhysicalGroups():
        count, measure = 0, 0.0
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            etypes, _, enodes = gmsh.model.mesh.getElements(dim, entity)
            for etype, nodes in zip(etypes, enodes):
                corners = dim + 1
                per = gmsh.model.mesh.getElementProperties(etype)[3]
                p = xyz[nodes.astype(int).reshape(-1, per)[:, :corners]]
                edges = p[:, 1:] - p[:, :1]
                if dim == 3:
                    measure += float(np.abs(np.linalg.det(edges)).sum() / 6.0)
                else:
                    measure += float(np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1).sum() / 2)
                count += len(p)
        stats["groups"][gmsh.model.getPhysicalName(dim, tag)] = {"elements": count, "measure": measure}
    return stats
