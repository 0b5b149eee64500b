"""3D gmsh geometries of one BB-TENG cell (OCC kernel), SI units.

Two cells are built here:

* :class:`CylindricalCell`: the paper's device (Table 1): a dielectric ball
  between two thin disk electrodes on the inner faces of two PMMA end
  plates, inside a PMMA tube. Built from ``scene.device`` with
  :func:`cylindrical_cell`.
* :class:`HexagonalCell`: one cell of the Fig. 10 honeycomb (PLA walls,
  hexagonal tube and plates, hexagonal electrodes covering the cell floor,
  a 5 mm ball and Δh = 2 mm).

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
``electrode_lower``, ``electrode_upper``, ``far_boundary``.

:func:`build_model` asks the cell for its parts (``placement_3d``,
``contact_rule_3d``, ``extent_3d``, ``occ_parts``, ``rim_distance_expr``,
``gap_refinements_3d``), so another cell shape brings its own: the spherical shell's
are in :mod:`tengfield.field.cells.shell_model3d`.

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
from ..scene.shapes import hexagonal as hexagonal_shape
from ..scene.shapes import tube as tube_shape

# The z → 0 / z → Δh rule is :mod:`tengfield.field.contact` (one rule for both
# solvers): no mesh has a ball-electrode gap below ``MIN_GAP_FRACTION · h``.
from . import contact  # noqa: E402  (no gmsh)
from .geometry_axisymmetric import RIM_EXPONENT  # noqa: E402  (no gmsh)

VOLUME_GROUPS = ("ball", "walls", "air")
SURFACE_GROUPS = ("ball_surface", "electrode_lower", "electrode_upper", "far_boundary")

_model_counter = itertools.count()


# -- what build_model asks a cell between two plates (the tube and the honeycomb);
# -- the spherical shell answers the same questions in field/cells/shell_model3d.py
def _plate_cell_placement(cell, position: float, offset: float,
                          offset_angle: float = 0.0) -> tuple[np.ndarray, float]:
    """(ball centre [m], meshed gap [m]) for gap ``position`` and lateral ``offset`` [m]."""
    return ball_centre(cell, position, offset, offset_angle), meshed_gap(cell, position)


def _plate_cell_contact_rule(cell, position: float, offset: float,
                             offset_angle: float = 0.0) -> dict | None:
    """The contact rule of :func:`contact_anchors` (along z, at the same offset):
    ``None`` when ``position`` is meshable, else ``{"coordinate", "anchors", "span",
    "place"}`` for :func:`tengfield.field.contact.extrapolate_to_contact`
    (``place(z) -> (position, offset)``)."""
    anchors = contact_anchors(cell, position)
    if anchors is None:
        return None
    return {"coordinate": position, "anchors": anchors, "span": cell.stroke,
            "place": lambda z: (z, offset)}


def _plate_cell_extent(cell, offset: float) -> float:
    """Radius [m] around the origin the device and an offset ball fit in."""
    return cell.bounding_radius + offset


def _plate_cell_gap_refinements(cell, centre, size: float, ball_factor: float) -> list:
    """``[(s_min [m], point [m])]``: the gaps the mesh refines (the ball's poles to the
    plates, the lateral gap to the wall when smaller than ``ball_factor · size``)."""
    h = size
    radius = 0.5 * cell.ball_diameter
    half = 0.5 * cell.electrode_spacing
    x0, y0, zc = (float(c) for c in centre)
    out = []
    for z_pole, z_plane in ((zc - radius, -half), (zc + radius, half)):
        gap = abs(z_pole - z_plane)
        s_min = min(max(0.5 * gap, 0.02 * h), ball_factor * h)
        z_mid = 0.5 * (z_pole + z_plane)
        out.append((s_min, (x0, y0, z_mid)))
    lateral = _lateral_gap(cell, centre)
    if lateral is not None and lateral[0] < ball_factor * h:
        gap, mid = lateral
        out.append((max(0.5 * gap, 0.02 * h), mid))
    return out


def _plates_and_bore(cell, occ, solid, outer: float, inner: float) -> list[int]:
    """The wall volumes of a cell between two plates (none when εr = 1): the two plates
    and the tube, ``solid(size, z0, height)`` a prism of the cross-section (a cylinder
    of radius ``size``, a hexagonal prism of apothem ``size``) from ``z0`` up."""
    if cell.wall_permittivity == 1.0:
        return []
    half, t = 0.5 * cell.electrode_spacing, cell.plate_thickness
    walls = [solid(outer, -half - t, t), solid(outer, half, t)]
    tube, _ = occ.cut([(3, solid(outer, -half, 2 * half))], [(3, solid(inner, -half, 2 * half))])
    return walls + [tag for _, tag in tube]


def _plane_rims(cell, lateral: str) -> str:
    """Distance to the nearest rim of two plane electrodes at z = ±h/2 whose in-plane
    distance to the rim is the MathEval expression ``lateral``."""
    half = 0.5 * cell.electrode_spacing
    axial = f"min(abs(z-{_num(half)}),abs(z+{_num(half)}))"
    return f"sqrt({lateral}^2+{axial}^2)"


class _PlateCell:
    """What the tube and the honeycomb share: the ball between two plane electrodes
    h = d + Δh apart; the 3D model's placement, contact rule, extent and gap sizes."""
    placement_3d = _plate_cell_placement
    contact_rule_3d = _plate_cell_contact_rule
    extent_3d = _plate_cell_extent
    gap_refinements_3d = _plate_cell_gap_refinements

    @property
    def electrode_spacing(self) -> float:
        """h = d + Δh [m]."""
        return self.ball_diameter + self.stroke

    def outline(self) -> list[np.ndarray]:
        """(r, z) polylines [m] for plots, r >= 0 (mirrored by the plot): the lower and the
        upper electrode, then the plates' and the bore's outline (``outline_radii``)."""
        h, t = 0.5 * self.electrode_spacing, self.plate_thickness
        electrode, inner, outer = self.outline_radii
        return [np.array([[0.0, -h], [electrode, -h]]), np.array([[0.0, h], [electrode, h]]),
                np.array([[0.0, -h - t], [outer, -h - t], [outer, h + t], [0.0, h + t]]),
                np.array([[0.0, -h], [inner, -h], [inner, h], [0.0, h]])]


@dataclass(frozen=True)
class CylindricalCell(_PlateCell):
    """The paper's device: round tube, round plates, disk electrodes (SI)."""
    ball_diameter: float        # d [m]
    stroke: float               # Δh = h - d [m]
    electrode_radius: float     # [m]
    tube_inner_radius: float    # [m]
    tube_outer_radius: float    # [m], also the plates' radius
    plate_thickness: float      # [m]
    ball_permittivity: float    # relative
    wall_permittivity: float    # relative; 1 leaves tube and plates out

    @property
    def bounding_radius(self) -> float:
        """Radius of the smallest origin-centred sphere holding the device [m]."""
        return tube_shape.bounding_radius_of(self.tube_outer_radius,
                                             0.5 * self.electrode_spacing + self.plate_thickness)

    @property
    def max_offset(self) -> float:
        """Largest lateral ball offset that keeps the ball inside the tube [m]."""
        return self.tube_inner_radius - 0.5 * self.ball_diameter

    def occ_parts(self, occ) -> tuple[list[int], list[int]]:
        """Add the electrodes (two disks) and, unless εr = 1, the plates and the tube
        to the OCC model: ``([lower, upper] surface tags, wall volume tags)``."""
        half = 0.5 * self.electrode_spacing
        rim = self.electrode_radius
        electrodes = [occ.addDisk(0, 0, z, rim, rim) for z in (-half, half)]
        def cylinder(radius, z0, height):
            return occ.addCylinder(0, 0, z0, 0, 0, height, radius)

        return electrodes, _plates_and_bore(self, occ, cylinder, self.tube_outer_radius,
                                            self.tube_inner_radius)

    def rim_distance_expr(self) -> str:
        """gmsh MathEval expression of the distance [m] to the nearest disk rim (exact)."""
        lateral = f"(sqrt(x*x+y*y)-{_num(self.electrode_radius)})"
        return _plane_rims(self, lateral)

    def lateral_wall(self, direction) -> float:
        """Distance [m] from the axis to the tube's inner wall along ``direction`` (unit, xy)."""
        return self.tube_inner_radius

    @property
    def outline_radii(self) -> tuple[float, float, float]:
        """(electrode, bore, outside) radii [m] of the plot's outline."""
        return self.electrode_radius, self.tube_inner_radius, self.tube_outer_radius


@dataclass(frozen=True)
class HexagonalCell(_PlateCell):
    """One cell of the Fig. 10 honeycomb (SI).

    Hexagons have two flats parallel to the x axis; "apothem" is the
    distance from the axis to a flat. The electrodes cover the cell floor
    and ceiling (the inner hexagon). Defaults: the paper's shipboard
    honeycomb (5 mm PTFE ball, Δh = 2 mm, 3D-printed PLA, εr ≈ 3); the
    cell's lateral size and wall/plate thickness are not given in the paper
    and are chosen here (0.5 mm lateral clearance, 1 mm walls, 2 mm plates).
    """
    ball_diameter: float = 5.0e-3
    stroke: float = 2.0e-3
    inner_apothem: float = 3.0e-3
    wall_thickness: float = 1.0e-3
    plate_thickness: float = 2.0e-3
    ball_permittivity: float = 2.1
    wall_permittivity: float = 3.0

    @property
    def outer_apothem(self) -> float:
        return self.inner_apothem + self.wall_thickness

    @property
    def outline_radii(self) -> tuple[float, float, float]:
        """(electrode, bore, outside) of the plot's outline [m]: the section through two
        flats (the electrodes cover the bore)."""
        return self.inner_apothem, self.inner_apothem, self.outer_apothem

    @property
    def bounding_radius(self) -> float:
        return hexagonal_shape.bounding_radius_of(
            self.outer_apothem, 0.5 * self.electrode_spacing + self.plate_thickness)

    @property
    def max_offset(self) -> float:
        return self.inner_apothem - 0.5 * self.ball_diameter

    def occ_parts(self, occ) -> tuple[list[int], list[int]]:
        """Add the hexagonal electrodes and, unless εr = 1, the plates and the hexagonal
        tube: ``([lower, upper] surface tags, wall volume tags)``."""
        half = 0.5 * self.electrode_spacing
        electrodes = [_hexagon(occ, self.inner_apothem, z) for z in (-half, half)]
        def prism(apothem, z0, height):
            return _hex_prism(occ, apothem, z0, height)

        return electrodes, _plates_and_bore(self, occ, prism, self.outer_apothem,
                                            self.inner_apothem)

    def rim_distance_expr(self) -> str:
        """gmsh MathEval distance [m] to the nearest hexagon rim (exact off the corners)."""
        c = _num(math.cos(math.pi / 6))
        lateral = (f"(max(abs(y),max(abs(0.5*y+{c}*x),abs(0.5*y-{c}*x)))"
                   f"-{_num(self.inner_apothem)})")
        return _plane_rims(self, lateral)

    def lateral_wall(self, direction) -> float:
        """Distance [m] from the axis to the hexagonal bore along ``direction`` (unit, xy)."""
        normals = [(0.0, 1.0), (math.cos(math.pi / 6), 0.5), (-math.cos(math.pi / 6), 0.5)]
        return self.inner_apothem / max(abs(direction @ np.array(n)) for n in normals)


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
    """
    size: float
    domain_radius: float
    order: int = 1
    rim_floor: float = 0.05
    ball_factor: float = 0.5
    growth: float = 0.3

    def __post_init__(self):
        # plain floats: gmsh MathEval strings use repr(), and numpy 2 writes np.float64(...)
        for name in ("size", "domain_radius", "rim_floor", "ball_factor", "growth"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if not (self.size > 0 and math.isfinite(self.size)):
            raise FieldError(f"mesh_size_mm = {self.size * 1e3!r} is out of range: allowed (0, 100] mm")
        if self.order not in (1, 2):
            raise FieldError(f"degree = {self.order!r}: the 3D mesh order must be 1 or 2")


def cylindrical_cell(device) -> CylindricalCell:
    """The paper's device from a scene's ``[device]`` section (:class:`tengfield.scene.Device`)."""
    return CylindricalCell(
        ball_diameter=device.ball_diameter, stroke=device.stroke,
        electrode_radius=device.electrode_radius, tube_inner_radius=device.tube_inner_radius,
        tube_outer_radius=device.tube_outer_radius, plate_thickness=device.plate_thickness,
        ball_permittivity=device.ball_permittivity, wall_permittivity=device.wall_permittivity)


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
    lower_surfs = [tag for _, tag in piece_map[2 + len(walls)]]
    upper_surfs = [tag for _, tag in piece_map[3 + len(walls)]]
    all_vols = [tag for _, tag in gmsh.model.getEntities(3)]
    air_vols = [v for v in all_vols if v not in ball_vols and v not in wall_vols]
    ball_surfs = [tag for _, tag in gmsh.model.getBoundary([(3, v) for v in ball_vols],
                                                           combined=True, oriented=False)]
    far_surfs = [tag for _, tag in gmsh.model.getBoundary([(3, v) for v in all_vols],
                                                          combined=True, oriented=False)]

    groups = {}
    for name, dim, tags in (("ball", 3, ball_vols), ("walls", 3, wall_vols), ("air", 3, air_vols),
                            ("ball_surface", 2, ball_surfs), ("electrode_lower", 2, lower_surfs),
                            ("electrode_upper", 2, upper_surfs), ("far_boundary", 2, far_surfs)):
        if tags:
            groups[name] = gmsh.model.addPhysicalGroup(dim, tags, name=name)
    missing = [n for n in ("ball", "air", "ball_surface", "electrode_lower", "electrode_upper",
                           "far_boundary") if n not in groups]
    if missing:  # pragma: no cover - would be a gmsh/OCC regression
        raise FieldError(f"3D geometry: gmsh produced no entities for {', '.join(missing)}")

    _size_fields(cell, centre, settings, ball_surfs,
                 [c for s in lower_surfs + upper_surfs
                  for _, c in gmsh.model.getBoundary([(2, s)], oriented=False)])
    with _gmsh_options({"Mesh.MeshSizeFromPoints": 0, "Mesh.MeshSizeFromCurvature": 0,
                        "Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.Algorithm3D": 10,
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


def _hexagon(occ, apothem: float, z: float) -> int:
    """A plane hexagonal surface in the plane ``z`` (flats parallel to x)."""
    corner = apothem / math.cos(math.pi / 6)
    pts = [occ.addPoint(corner * math.cos(a), corner * math.sin(a), z)
           for a in np.arange(6) * math.pi / 3]
    lines = [occ.addLine(pts[i], pts[(i + 1) % 6]) for i in range(6)]
    return occ.addPlaneSurface([occ.addCurveLoop(lines)])


def _hex_prism(occ, apothem: float, z0: float, height: float) -> int:
    out = occ.extrude([(2, _hexagon(occ, apothem, z0))], 0, 0, height)
    return next(tag for dim, tag in out if dim == 3)


def _lateral_gap(cell, centre):
    """(gap [m], midpoint [m]) between an off-axis ball and the tube wall it
    approaches, or None for an on-axis ball or a cell without walls."""
    offset = math.hypot(centre[0], centre[1])
    if offset == 0.0 or cell.wall_permittivity == 1.0:
        return None
    direction = np.array([centre[0], centre[1]]) / offset
    wall = cell.lateral_wall(direction)
    radius = 0.5 * cell.ball_diameter
    gap = wall - offset - radius
    mid = offset + radius + 0.5 * gap
    return gap, (float(mid * direction[0]), float(mid * direction[1]), float(centre[2]))


def _num(value) -> str:
    """A number in a gmsh MathEval expression: the shortest round-trip decimal of a
    plain float (numpy 2's repr writes ``np.float64(...)``, which gmsh's parser rejects
    by aborting the process)."""
    return repr(float(value))


def _gap_size(s_min, point) -> str:
    """MathEval size [m] growing from ``s_min`` at ``point`` (x, y, z) [m] with slope 0.35."""
    x, y, z = (_num(c) for c in point)
    return f"{_num(s_min)} + 0.35*sqrt((x-({x}))^2+(y-({y}))^2+(z-({z}))^2)"


def _size_fields(cell, centre, settings: MeshSettings, ball_surfs, rim_curves) -> None:
    """Background size: min of rim, ball-surface, gap and far-field gradings."""
    import gmsh

    fld = gmsh.model.mesh.field
    h = settings.size
    fields = []

    power = 1.0 - RIM_EXPONENT / settings.order
    reach = 0.25 * cell.electrode_spacing
    rim = fld.add("MathEval")
    fld.setString(rim, "F", f"max({_num(settings.rim_floor * h)}, "
                            f"{_num(h)}*({cell.rim_distance_expr()}/{_num(reach)})^{_num(power)})")
    fields.append(rim)

    ball_dist = fld.add("Distance")
    fld.setNumbers(ball_dist, "SurfacesList", ball_surfs)
    fld.setNumber(ball_dist, "Sampling", 60)
    ball = fld.add("Threshold")
    fld.setNumber(ball, "InField", ball_dist)
    fld.setNumber(ball, "SizeMin", settings.ball_factor * h)
    fld.setNumber(ball, "SizeMax", h)
    fld.setNumber(ball, "DistMin", 0.25 * h)
    fld.setNumber(ball, "DistMax", 2.0 * h)
    fld.setNumber(ball, "StopAtDistMax", 1)
    fields.append(ball)

    # contact gaps: size grows linearly with the distance from the gap's midpoint
    for s_min, point in cell.gap_refinements_3d(centre, h, settings.ball_factor):
        gap_field = fld.add("MathEval")
        fld.setString(gap_field, "F", _gap_size(s_min, point))
        fields.append(gap_field)

    device_r = cell.bounding_radius
    far = fld.add("MathEval")
    fld.setString(far, "F", f"max({_num(h)}, {_num(h)} + {_num(settings.growth)}"
                            f"*(sqrt(x^2+y^2+z^2) - {_num(device_r)}))")
    fields.append(far)

    total = fld.add("Min")
    fld.setNumbers(total, "FieldsList", fields)
    fld.setAsBackgroundMesh(total)


# ---------------------------------------------------------------------------
# reference cases (meshes/ holds their meshes and statistics)

@dataclass(frozen=True)
class ReferenceCase:
    """A geometry, a ball placement and mesh settings whose mesh lives in ``meshes/``."""
    name: str
    cell: CylindricalCell | HexagonalCell
    position: float                 # z [m]
    offset: float                   # [m], along +x
    settings: MeshSettings
    surface_charge: float = -8.0e-6  # σ [C/m²]


def reference_cases() -> dict[str, ReferenceCase]:
    """The reference geometries: the paper's device with an off-axis ball
    (Table 1, z = 1.5 mm, offset 0.3 mm) and one honeycomb cell (Fig. 10,
    z = 1 mm, on axis); coarse first-order meshes (size 2 mm, R = 20 mm)."""
    paper = CylindricalCell(ball_diameter=7e-3, stroke=3e-3, electrode_radius=4e-3,
                            tube_inner_radius=4e-3, tube_outer_radius=5.5e-3, plate_thickness=2e-3,
                            ball_permittivity=2.1, wall_permittivity=2.6)
    coarse = MeshSettings(size=2e-3, domain_radius=20e-3, order=1)
    return {
        "paper_device": ReferenceCase("paper_device", paper, 1.5e-3, 0.3e-3, coarse),
        "honeycomb_cell": ReferenceCase("honeycomb_cell", HexagonalCell(), 1.0e-3, 0.0, coarse),
    }


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
