"""The paper's tube as a :class:`~tengfield.field.cells.Cell`: an adapter over the
scene's ``[device]`` and the existing tube modules (nothing of the tube is
re-implemented here; the stages still read the tube directly until they are
moved onto ``CELLS``).

Geometry: the electrodes are the discs ``z = ±h/2, r <= a`` (h = plate spacing),
the tube's inner wall is the cylinder ``r = r_i``; the ball moves in
``|z| <= h/2 - r_b``, ``r <= r_i - r_b``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...scene.limits import mesh_features


@dataclass(frozen=True)
class Tube:
    """The tube cell of ``scene`` (a validated :class:`tengfield.scene.Scene`)."""

    scene: object

    name = "tube"

    @classmethod
    def from_scene(cls, scene) -> "Tube":
        return cls(scene)

    def solve_scene(self, scene, position: float, *, comm, method: str, offset: float,
                    **options):
        """:func:`tengfield.field.solve_position` for the tube: the tube's own solvers."""
        if method == "axisymmetric":
            from ..axisymmetric import solve_position_axisymmetric
            return solve_position_axisymmetric(scene, position, comm=comm, **options)
        from ..solver3d import solve_position_3d
        return solve_position_3d(scene, position, offset=offset, comm=comm, **options)

    @property
    def device(self):
        return self.scene.device

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

    @property
    def bounding_radius(self) -> float:
        return self.device.bounding_radius

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
        """The tube's inner diagonal (``scene.device.longest_path`` of a tube)."""
        return math.hypot(self.device.plate_spacing, 2.0 * self.device.tube_inner_radius)

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
        dev = self.device
        h, t = 0.5 * dev.plate_spacing, dev.plate_thickness
        ri, ro, a = dev.tube_inner_radius, dev.tube_outer_radius, dev.electrode_radius
        return [np.array([[0.0, -h], [a, -h]]), np.array([[0.0, h], [a, h]]),
                np.array([[0.0, -h - t], [ro, -h - t], [ro, h + t], [0.0, h + t]]),
                np.array([[0.0, -h], [ri, -h], [ri, h], [0.0, h]])]

    def axisymmetric_layout(self, position: float, *, mesh_size: float, degree: int = 2,
                            domain_radius: float | None = None, far_field: str = "kelvin",
                            grading_size: float | None = None):
        from ..geometry_axisymmetric import layout
        return layout(self.scene, position, degree=degree, mesh_size=mesh_size,
                      domain_radius=domain_radius, far_field=far_field,
                      grading_size=grading_size)

    def build_axisymmetric_model(self, gmsh, layout, *, geometry_order: int = 2) -> str:
        from ..geometry_axisymmetric import build_model
        return build_model(gmsh, layout, geometry_order=geometry_order)
