"""The honeycomb cell of Fig. 10 as a :class:`~tengfield.field.cells.Cell`
(``[device] shape = "hexagonal"``): an adapter over
:class:`tengfield.field.cells.plate_model3d.HexagonalCell` and the 3D solver (nothing of the
honeycomb is re-implemented here).

The tube's keys are read with the hexagon's meaning: ``tube_inner_radius_mm`` is the
inner apothem (axis to a flat of the hexagonal bore), ``tube_outer_radius_mm`` the
outer one (wall thickness = outer - inner), ``plate_thickness_mm``, ``stroke_mm``,
the ball and the permittivities as for the tube; the electrodes cover the inner
hexagon (``electrode_radius_mm`` is not used). Hexagons have two flats parallel to x.

Field: 3D solves only (``[field] method = "3d"``; no breakdown lines), the scene's
``[field]`` discretisation, as ``solve_position_3d`` does for the tube.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import FieldError
from ...quantities import SURFACE_CHARGE_KEY
from ...scene.limits import mesh_features
from ...scene.shapes import hexagonal as hexagonal_shape
from ._methods import solve_with
from .tube import Tube

#: unit normals of the hexagon's six flats (two parallel to x)
_NORMALS = np.array([[math.cos(math.pi / 2 + k * math.pi / 3),
                      math.sin(math.pi / 2 + k * math.pi / 3), 0.0] for k in range(6)])


@dataclass(frozen=True)
class Hexagonal:
    """The honeycomb cell of ``scene`` (a validated scene with ``shape = "hexagonal"``)."""

    scene: object

    name = "hexagonal"

    @classmethod
    def from_scene(cls, scene) -> "Hexagonal":
        return cls(scene)

    @property
    def cell(self):
        """The :class:`~tengfield.field.cells.plate_model3d.HexagonalCell` of the scene."""
        from .plate_model3d import HexagonalCell

        dev = self.scene.device
        return HexagonalCell(ball_diameter=dev.ball_diameter, stroke=dev.stroke,
                             inner_apothem=dev.tube_inner_radius,
                             wall_thickness=dev.tube_outer_radius - dev.tube_inner_radius,
                             plate_thickness=dev.plate_thickness,
                             ball_permittivity=dev.ball_permittivity,
                             wall_permittivity=dev.wall_permittivity,
                             electrodes=dev.electrode_names)

    def _solve_3d(self, scene, position: float, *, comm, offset: float, **options):
        """The 3D solve (:func:`tengfield.field.solver3d.solve_cell_3d`) at the scene's σ
        and ``[field]`` settings; options ``estimate_error``, ``keep_solution``."""
        unknown = set(options) - {"estimate_error", "keep_solution"}
        if unknown:
            raise FieldError(f"unknown 3D solver option(s) {sorted(unknown)}; allowed: "
                             "estimate_error, keep_solution")
        from ..geometry_axisymmetric import base_mesh_size
        from ..moving3d import placer
        from ..solver3d import Solve3DSettings, solve_cell_3d

        fld = scene.field
        settings = Solve3DSettings(degree=fld.degree, mesh_size=base_mesh_size(scene),
                                   domain_radius=fld.domain_radius, far_field=fld.far_field,
                                   mesh_grading=getattr(fld, "mesh_grading", "uniform"),
                                   estimate_error=options.get("estimate_error", True))
        return solve_cell_3d(self.cell, position, offset=offset,
                             surface_charge=scene.device.surface_charge, settings=settings,
                             comm=comm, keep_solution=options.get("keep_solution", False),
                             solve_one=placer(getattr(fld, "mesh_motion", "remesh")))

    #: ``[field] method`` -> its solver: a 3D cell (the shape's ``field_methods``)
    field_models = {"3d": _solve_3d}
    #: the hexagonal bore is not described for the 3D contact model yet
    contact_walls = None

    def solve_scene(self, scene, position: float, *, comm, method: str, offset: float,
                    **options):
        """:func:`tengfield.field.solve_position` for the honeycomb: ``method``'s solver."""
        return solve_with(self, scene, position, comm=comm, method=method, offset=offset,
                          **options)

    # -- geometry ----------------------------------------------------------------
    @property
    def ball_radius(self) -> float:
        return self.scene.device.ball_radius

    @property
    def stroke(self) -> float:
        return self.scene.device.stroke

    @property
    def electrode_spacing(self) -> float:
        return self.scene.device.plate_spacing

    def ball_centre_z(self, position: float) -> float:
        return -0.5 * self.electrode_spacing + float(position) + self.ball_radius

    def _clearances(self, centre) -> np.ndarray:
        """Gaps [m] to the nearest flat of the bore, the lower and the upper electrode."""
        c = np.asarray(centre, dtype=float).reshape(3)
        half, rb = 0.5 * self.electrode_spacing, self.ball_radius
        lateral = self.scene.device.tube_inner_radius - rb - float(np.max(_NORMALS @ c))
        return np.array([lateral, c[2] + half - rb, half - rb - c[2]])

    def admissible(self, centre) -> bool:
        return bool(np.all(self._clearances(centre) >= -1e-12 * self.electrode_spacing))

    def wall_distance(self, centre) -> float:
        return float(np.min(self._clearances(centre)))

    def wall_normal(self, centre) -> np.ndarray:
        c = np.asarray(centre, dtype=float).reshape(3)
        k = int(np.argmin(self._clearances(c)))
        if k == 0:
            return _NORMALS[int(np.argmax(_NORMALS @ c))].copy()
        return np.array([0.0, 0.0, -1.0 if k == 1 else 1.0])

    def volume(self) -> float:
        """The hexagonal prism, walls and both plates: 2√3 b² (h + 2t) (b: outer apothem)."""
        return self.scene.device.cell_volume

    def longest_path(self) -> float:
        """Hypot of the plate spacing and the bore's corner-to-corner width."""
        return self.scene.device.longest_path

    def breakdown_feet(self, ball_centre_z: float, angles_deg) -> dict:
        raise FieldError("shape = 'hexagonal' has no breakdown lines (3D solves): give "
                         f"[device] {SURFACE_CHARGE_KEY} as a number")

    def mesh_features(self) -> dict[str, float]:
        return mesh_features(self.scene.device, self.scene.field.environment)

    def axisymmetric_layout(self, position: float, **settings):
        raise FieldError("shape = 'hexagonal' has no axisymmetric model (a 3D cell)")

    def canonical(self) -> None:
        """No (r, z) mesh to map: a 3D cell."""
        return None

    def check_tabulated_offset(self, offset: float) -> None:
        """A table of the whole stroke at the lateral ``offset`` [m]: the honeycomb's
        cell holds any offset its scene admits."""

    #: the cost estimate's (r, z) count is the tube's rule on the same keys (a 3D cell
    #: has no (r, z) model; asked only for an explicit "axisymmetric" estimate)
    estimated_axisymmetric_cells = Tube.estimated_axisymmetric_cells

    def build_axisymmetric_model(self, gmsh, layout, *, geometry_order: int = 2) -> str:
        raise FieldError("shape = 'hexagonal' has no axisymmetric model (a 3D cell)")

    def outline(self) -> list[np.ndarray]:
        """(r, z) polylines of the section through two flats: electrodes, bore, outside
        (:mod:`tengfield.scene.shapes.hexagonal`)."""
        return [np.array(line) for line in hexagonal_shape.Hexagonal.outline(self.scene.device)]
