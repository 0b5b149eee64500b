"""The 3D gmsh models of the two cells between two plane electrodes: what
:func:`tengfield.field.geometry3d.build_model` asks a cell (``placement_3d``,
``contact_rule_3d``, ``extent_3d``, ``occ_parts``, ``rim_distance_expr``,
``gap_refinements_3d``), answered for

* :class:`CylindricalCell`: the paper's device (Table 1, the tube,
  :class:`~tengfield.field.cells.Tube`): a dielectric ball between two thin disk
  electrodes on the inner faces of two PMMA end plates, inside a PMMA tube. Built from
  ``scene.device`` with :func:`cylindrical_cell`.
* :class:`HexagonalCell`: one cell of the Fig. 10 honeycomb
  (:class:`~tengfield.field.cells.Hexagonal`; PLA walls, hexagonal tube and plates,
  hexagonal electrodes covering the cell floor, a 5 mm ball and Δh = 2 mm).

The spherical shell answers the same questions in :mod:`.shell_model3d`; the generic
model builder, the placement rules (``meshed_gap``, ``contact_anchors``,
``ball_centre``) and the mesh settings are :mod:`tengfield.field.geometry3d`'s.
Coordinates as there (SI, origin at the cell's centre, z the axis). gmsh is imported by
the caller (``occ`` is passed in); this module is numpy only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...scene.shapes import hexagonal as hexagonal_shape
from ...scene.shapes import tube as tube_shape
from ..geometry3d import (MeshSettings, ball_centre, contact_anchors, eval_number,
                          meshed_gap)


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
    axial = f"min(abs(z-{eval_number(half)}),abs(z+{eval_number(half)}))"
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
        """(r, z) polylines [m] for plots, r >= 0 (mirrored by the plot): the electrodes
        (``electrodes``' order), then the plates' and the bore's outline (``outline_radii``)."""
        h, t = 0.5 * self.electrode_spacing, self.plate_thickness
        electrode, inner, outer = self.outline_radii
        return [*(np.array([[0.0, z], [electrode, z]]) for z in _electrode_planes(self)),
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
    #: the conductors, in the order of the field's matrices (``[device] electrodes``):
    #: ("lower", "upper"), or ("lower",) for the single-electrode cell (the upper plate bare)
    electrodes: tuple = ("lower", "upper")

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
        """Add the electrodes (a disk per name of ``electrodes``) and, unless εr = 1, the
        plates and the tube to the OCC model: ``(electrode surface tags in the order of
        electrodes, wall volume tags)``."""
        rim = self.electrode_radius
        electrodes = [occ.addDisk(0, 0, z, rim, rim) for z in _electrode_planes(self)]
        def cylinder(radius, z0, height):
            return occ.addCylinder(0, 0, z0, 0, 0, height, radius)

        return electrodes, _plates_and_bore(self, occ, cylinder, self.tube_outer_radius,
                                            self.tube_inner_radius)

    def rim_distance_expr(self) -> str:
        """gmsh MathEval expression of the distance [m] to the nearest disk rim (exact)."""
        lateral = f"(sqrt(x*x+y*y)-{eval_number(self.electrode_radius)})"
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
    #: the conductors, in the order of the field's matrices (as :class:`CylindricalCell`)
    electrodes: tuple = ("lower", "upper")

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
        """Add the hexagonal electrodes (one per name of ``electrodes``) and, unless
        εr = 1, the plates and the hexagonal tube: ``(electrode surface tags in the order
        of electrodes, wall volume tags)``."""
        electrodes = [_hexagon(occ, self.inner_apothem, z) for z in _electrode_planes(self)]
        def prism(apothem, z0, height):
            return _hex_prism(occ, apothem, z0, height)

        return electrodes, _plates_and_bore(self, occ, prism, self.outer_apothem,
                                            self.inner_apothem)

    def rim_distance_expr(self) -> str:
        """gmsh MathEval distance [m] to the nearest hexagon rim (exact off the corners)."""
        c = eval_number(math.cos(math.pi / 6))
        lateral = (f"(max(abs(y),max(abs(0.5*y+{c}*x),abs(0.5*y-{c}*x)))"
                   f"-{eval_number(self.inner_apothem)})")
        return _plane_rims(self, lateral)

    def lateral_wall(self, direction) -> float:
        """Distance [m] from the axis to the hexagonal bore along ``direction`` (unit, xy)."""
        normals = [(0.0, 1.0), (math.cos(math.pi / 6), 0.5), (-math.cos(math.pi / 6), 0.5)]
        return self.inner_apothem / max(abs(direction @ np.array(n)) for n in normals)


def _electrode_planes(cell) -> list[float]:
    """The planes z [m] of the cell's electrodes, in the order of ``cell.electrodes``: the
    lower one at -h/2, the upper one at +h/2 (a bare plate has none)."""
    half = 0.5 * cell.electrode_spacing
    return [{"lower": -half, "upper": half}[name] for name in cell.electrodes]


def cylindrical_cell(device) -> CylindricalCell:
    """The paper's device from a scene's ``[device]`` section (:class:`tengfield.scene.Device`)."""
    return CylindricalCell(
        ball_diameter=device.ball_diameter, stroke=device.stroke,
        electrode_radius=device.electrode_radius, tube_inner_radius=device.tube_inner_radius,
        tube_outer_radius=device.tube_outer_radius, plate_thickness=device.plate_thickness,
        ball_permittivity=device.ball_permittivity, wall_permittivity=device.wall_permittivity,
        electrodes=device.electrode_names)


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
