"""The paper's tube's field models (``[device] shape = "tube"``): its pure geometry
is :mod:`tengfield.scene.shapes.tube`; this is the :class:`~tengfield.field.cells.Cell`
the field stages ask, with :data:`Tube.field_models`, the table of its field methods
(the (r, z) solver of :mod:`tengfield.field.axisymmetric`, the 3D one of
:mod:`tengfield.field.solver3d` on the :class:`~.plate_model3d.CylindricalCell`,
:func:`solve_position_3d`) that ``[field] method`` resolves through.

Geometry: the electrodes are the discs ``z = ±h/2, r <= a`` (h = plate spacing),
the tube's inner wall is the cylinder ``r = r_i``; the ball moves in
``|z| <= h/2 - r_b``, ``r <= r_i - r_b``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import FieldError
from ...scene.limits import mesh_features
from ...scene.shapes import tube as tube_shape
from ._methods import solve_with
from .contact_surfaces import tube_surfaces
from .plate_model3d import cylindrical_cell


@dataclass(frozen=True)
class Tube:
    """The tube cell of ``scene`` (a validated :class:`tengfield.scene.Scene`)."""

    scene: object

    name = "tube"

    @classmethod
    def from_scene(cls, scene) -> "Tube":
        return cls(scene)

    def _solve_axisymmetric(self, scene, position: float, *, comm, offset: float, **options):
        from ..axisymmetric import solve_position_axisymmetric
        return solve_position_axisymmetric(scene, position, comm=comm, **options)

    def _solve_3d(self, scene, position: float, *, comm, offset: float, **options):
        from ..moving3d import placer
        return solve_position_3d(scene, position, offset=offset, comm=comm,
                                 solve_one=placer(getattr(scene.field, "mesh_motion", "remesh")), **options)

    #: ``[field] method`` -> its solver (the names of ``scene.shapes.tube.Tube.field_methods``)
    field_models = {"axisymmetric": _solve_axisymmetric, "3d": _solve_3d}
    #: the walls of the 3D contact model (:mod:`.contact_surfaces`)
    contact_walls = staticmethod(tube_surfaces)

    def solve_scene(self, scene, position: float, *, comm, method: str, offset: float,
                    **options):
        """:func:`tengfield.field.solve_position` for the tube: ``method``'s solver."""
        return solve_with(self, scene, position, comm=comm, method=method, offset=offset,
                          **options)

    @property
    def device(self):
        return self.scene.device

    # what solve_cell_position asks every cell (the ball and the walls' permittivities)
    @property
    def ball_diameter(self) -> float:
        return self.device.ball_diameter

    @property
    def ball_radius(self) -> float:
        return self.device.ball_radius

    @property
    def ball_permittivity(self) -> float:
        return self.device.ball_permittivity

    @property
    def wall_permittivity(self) -> float:
        return self.device.wall_permittivity

    @property
    def stroke(self) -> float:
        return self.device.stroke

    @property
    def electrode_spacing(self) -> float:
        return self.device.plate_spacing

    def ball_centre_z(self, position: float) -> float:
        return -0.5 * self.device.plate_spacing + float(position) + self.ball_radius

    def _clearances(self, centre) -> np.ndarray:
        """Gaps [m] to the tube wall, the lower and the upper electrode plane."""
        x, y, z = np.asarray(centre, dtype=float).reshape(3)
        dev, rb = self.device, self.ball_radius
        half = 0.5 * dev.plate_spacing
        return np.array([dev.tube_inner_radius - rb - math.hypot(x, y),
                         z + half - rb, half - rb - z])

    def admissible(self, centre) -> bool:
        return bool(np.all(self._clearances(centre) >= -1e-12 * self.device.plate_spacing))

    def wall_distance(self, centre) -> float:
        return float(np.min(self._clearances(centre)))

    def wall_normal(self, centre) -> np.ndarray:
        x, y, _ = np.asarray(centre, dtype=float).reshape(3)
        k = int(np.argmin(self._clearances(centre)))
        if k == 0:
            rho = math.hypot(x, y)
            return np.array([x / rho, y / rho, 0.0]) if rho > 0 else np.array([1.0, 0.0, 0.0])
        return np.array([0.0, 0.0, -1.0 if k == 1 else 1.0])

    def volume(self) -> float:
        return self.device.cell_volume

    def longest_path(self) -> float:
        """The tube's inner diagonal (:mod:`tengfield.scene.shapes.tube`)."""
        return self.device.longest_path

    def breakdown_feet(self, ball_centre_z: float, angles_deg) -> dict:
        """Lines parallel to the axis from the ball surface to the electrode planes
        (:mod:`tengfield.field.breakdown`); ``on_electrode``: the foot within the rim."""
        from ..breakdown import surface_points

        start = surface_points(ball_centre_z, self.ball_radius, angles_deg)
        half = 0.5 * self.device.plate_spacing
        foot = start.copy()
        foot[0, :, 1] = -half
        foot[1, :, 1] = half
        return {"start": start, "foot": foot, "length": np.abs(foot[..., 1] - start[..., 1]),
                "on_electrode": foot[..., 0] <= self.device.electrode_radius}

    def mesh_features(self) -> dict[str, float]:
        return mesh_features(self.device, self.scene.field.environment)

    def outline(self) -> list[np.ndarray]:
        """(r, z) polylines: the electrodes, the plates' and the tube's outlines."""
        return [np.array(line) for line in tube_shape.Tube.outline(self.device)]

    def canonical(self) -> "Tube | None":
        """The tube on the canonical grid of its lengths
        (:func:`tengfield.field.axisymmetric.canonical_device`), or None."""
        from ..axisymmetric import canonical_scene
        scene = canonical_scene(self.scene)
        return None if scene is None else Tube(scene)

    def check_tabulated_offset(self, offset: float) -> None:
        """A table of the whole stroke at the lateral ``offset`` [m]: the tube holds any
        offset its scene admits (the scene refuses one that does not fit the bore)."""

    def axisymmetric_layout(self, position: float, *, mesh_size: float, degree: int = 2,
                            domain_radius: float | None = None, far_field: str = "kelvin",
                            grading_size: float | None = None):
        from ..geometry_axisymmetric import layout
        return layout(self.scene, position, degree=degree, mesh_size=mesh_size,
                      domain_radius=domain_radius, far_field=far_field,
                      grading_size=grading_size)

    def estimated_axisymmetric_cells(self, scene, position: float, mesh_size: float,
                                     grading_size: float | None = None) -> float:
        """Triangles of the (r, z) mesh before meshing (:mod:`tengfield.field.cost`)."""
        from ..geometry_axisymmetric import estimated_cells, layout
        return estimated_cells(layout(scene, position, mesh_size=mesh_size,
                                      grading_size=grading_size))

    def build_axisymmetric_model(self, gmsh, layout, *, geometry_order: int = 2) -> str:
        from ..geometry_axisymmetric import build_model
        return build_model(gmsh, layout, geometry_order=geometry_order)


def solve_position_3d(scene, position: float, *, offset: float | None = None, comm,
                      estimate_error: bool = True, keep_solution: bool = False,
                      solve_one=None) -> PositionResult:
    """3D solve of the scene's tube (:class:`~.plate_model3d.CylindricalCell`) with the
    ball at gap ``position`` [m] (:func:`tengfield.field.solver3d.solve_cell_3d`).

    ``offset`` [m] (lateral, along +x) defaults to ``[field] ball_offset_mm``.
    Discretisation from ``[field]``: ``degree``, ``mesh_size_mm``,
    ``domain_radius_mm``, ``far_field`` ("kelvin" is the low-order exact
    Dirichlet-to-Neumann condition in 3D). ``environment = "grounded-table"``
    is not supported by the 3D path (FieldError).
    """
    fld = scene.field
    if fld.environment != "free-space":
        raise FieldError(f"[field] environment = {fld.environment!r} is not supported by the 3D "
                         "solver: allowed 'free-space' (use method = 'axisymmetric' for "
                         "'grounded-table')")
    offset = fld.ball_offset if offset is None else offset
    from ..geometry_axisymmetric import base_mesh_size
    from ..solver3d import Solve3DSettings, solve_cell_3d

    # mesh_size_mm as written, or the default scaled to the device's features, as in 2D
    settings = Solve3DSettings(degree=fld.degree, mesh_size=base_mesh_size(scene),
                               domain_radius=fld.domain_radius, far_field=fld.far_field,
                               mesh_grading=getattr(fld, "mesh_grading", "uniform"),
                               estimate_error=estimate_error)
    return solve_cell_3d(cylindrical_cell(scene.device), position, offset=offset,
                         surface_charge=scene.device.surface_charge, settings=settings, comm=comm,
                         keep_solution=keep_solution, solve_one=solve_one)
