"""The spherical shell: a ball inside a spherical cavity whose two hemispheres are
the electrodes (the rolling/bouncing-ball shells of full-space vibration and
blue-energy harvesters).

Geometry (SI, centre of the cavity at the origin, z up): the cavity of radius
``a = cavity_diameter/2`` is lined by two zero-thickness electrodes on its
surface, the lower one where ``z <= -w/2`` and the upper one where
``z >= +w/2`` (``w = electrode_band``, the height of the insulating band at the
equator; the band's arc length is ``2a·asin(w/2a)``, = w to first order). The
shell, of permittivity ``wall_permittivity``, fills ``a <= |x| <= a + t``
(``t = shell_thickness``) behind the electrodes. The ball (diameter d, its own
permittivity, surface charge σ given to the solver) moves in the cavity: on
the axis its centre is at ``z_c = -a + position + d/2`` with the gap
``position`` in ``[0, stroke]``, ``stroke = cavity_diameter - ball_diameter``;
anywhere, its centre must satisfy ``|c| <= a - d/2``.

This module is pure geometry (numpy); the gmsh model is in
:mod:`tengfield.field.cells.shell_model`, loaded on first use.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import FieldError
from ...scene.limits import DOMAIN_AUTO_FACTOR, DOMAIN_MIN_FACTOR
from ...scene.shapes import spherical_shell as shell_shape
from ._methods import solve_with
from .contact_surfaces import shell_surfaces

#: allowed ranges (open below, closed above) of the lengths [mm]
_RANGES_MM = {"cavity_diameter_mm": (0.0, 1000.0), "shell_thickness_mm": (0.0, 100.0),
              "electrode_band_mm": (0.0, 1000.0), "ball_diameter_mm": (0.0, 1000.0)}


@dataclass(frozen=True)
class SphericalShell:
    """A spherical-shell cell (SI). ``domain_radius`` [m]: the far-field sphere of the
    field solve (``None``: ``DOMAIN_AUTO_FACTOR`` x the shell's outer radius)."""

    cavity_diameter: float
    shell_thickness: float
    electrode_band: float
    ball_diameter: float
    wall_permittivity: float = 1.0
    ball_permittivity: float = 2.1
    domain_radius: float | None = None
    #: the conductors, in the order of the field's matrices (``[device] electrodes``):
    #: the two caps ("lower", "upper"), or the lower cap alone ("lower",: the
    #: single-electrode shell, its upper cap bare cavity wall)
    electrodes: tuple = ("lower", "upper")

    name = "spherical-shell"

    #: the ``[device]`` keys of the shell (file units) -> the dataclass field and factor
    KEYS = {"cavity_diameter_mm": ("cavity_diameter", 1e-3),
            "shell_thickness_mm": ("shell_thickness", 1e-3),
            "electrode_band_mm": ("electrode_band", 1e-3),
            "ball_diameter_mm": ("ball_diameter", 1e-3),
            "wall_permittivity": ("wall_permittivity", 1.0),
            "ball_permittivity": ("ball_permittivity", 1.0)}

    @classmethod
    def from_keys(cls, device: dict, domain_radius_mm: float | None = None
                  ) -> "SphericalShell":
        """The shell of a ``[device]`` table in file units (mm; ``shape`` and keys of
        other shapes are ignored); a missing key names itself."""
        values = {}
        for key, (attribute, factor) in cls.KEYS.items():
            if key in device:
                values[attribute] = float(device[key]) * factor
            elif attribute not in ("wall_permittivity", "ball_permittivity"):
                raise FieldError(f"[device] {key} is missing: shape = 'spherical-shell' "
                                 f"needs {', '.join(k for k in cls.KEYS if k.endswith('_mm'))}")
        if domain_radius_mm is not None:
            values["domain_radius"] = float(domain_radius_mm) * 1e-3
        return cls(**values)

    @classmethod
    def from_scene(cls, scene) -> "SphericalShell":
        """The shell of ``scene`` (``[device] shape = "spherical-shell"``, validated by
        the scene) with its far-field sphere ``[field] domain_radius_mm``."""
        dev = scene.device
        return cls(cavity_diameter=dev.cavity_diameter, shell_thickness=dev.shell_thickness,
                   electrode_band=dev.electrode_band, ball_diameter=dev.ball_diameter,
                   wall_permittivity=dev.wall_permittivity,
                   ball_permittivity=dev.ball_permittivity,
                   domain_radius=scene.field.domain_radius, electrodes=dev.electrode_names)

    def _solve_axisymmetric(self, scene, position: float, *, comm, offset: float,
                            **options):
        """The axisymmetric solve (:func:`~tengfield.field.cells.solve.solve_cell_position`)
        at the scene's σ and ``[field]`` discretisation (the default mesh size scaled as
        the tube's)."""
        from ..geometry_axisymmetric import base_mesh_size

        fld = scene.field
        if offset != 0.0:
            raise FieldError(f"method = 'axisymmetric' needs offset_mm = 0 (got "
                             f"{offset * 1e3:g}); use method = '3d' for an off-axis ball")
        from .solve import solve_cell_position

        return solve_cell_position(self, position, comm=comm,
                                   sigma=scene.device.surface_charge,
                                   mesh_size=base_mesh_size(scene), degree=fld.degree,
                                   far_field=fld.far_field, domain_radius=fld.domain_radius,
                                   **{"mesh_motion": getattr(fld, "mesh_motion", "remesh"),
                                      **options})

    def _solve_scene_3d(self, scene, position: float, *, comm, offset: float, **options):
        """The 3D solve (:meth:`solve_3d`) at the scene's σ and ``[field]`` settings."""
        from ..geometry_axisymmetric import base_mesh_size

        fld = scene.field
        return self.solve_3d(position, offset=offset, sigma=scene.device.surface_charge,
                             mesh_size=base_mesh_size(scene), degree=fld.degree,
                             far_field=fld.far_field, comm=comm,
                             **{"mesh_motion": getattr(fld, "mesh_motion", "remesh"),
                                **options})

    #: ``[field] method`` -> its solver (the names of the shape's ``field_methods``)
    field_models = {"axisymmetric": _solve_axisymmetric, "3d": _solve_scene_3d}
    #: the walls of the 3D contact model (:mod:`.contact_surfaces`)
    contact_walls = staticmethod(shell_surfaces)

    def solve_scene(self, scene, position: float, *, comm, method: str, offset: float,
                    **options):
        """:func:`tengfield.field.solve_position` for this cell: ``method``'s solver."""
        return solve_with(self, scene, position, comm=comm, method=method, offset=offset,
                          **options)

    def solve_3d(self, position: float, *, offset: float = 0.0, offset_angle: float = 0.0,
                 sigma: float, mesh_size: float, degree: int = 2, far_field: str = "kelvin",
                 comm, estimate_error: bool = True, keep_solution: bool = False,
                 mesh_motion: str = "remesh"):
        """A 3D solve (:func:`tengfield.field.solver3d.solve_cell_3d`, the tube's solver on
        :mod:`.shell_model3d`'s model) with the ball at gap ``position`` [m] and lateral
        ``offset`` [m] (at most :meth:`admissible_offset`), at angle ``offset_angle``
        [rad] from +x; the far-field sphere :attr:`far_radius`; ``mesh_motion = "move"``:
        reference meshes moved to the position (:mod:`tengfield.field.moving3d`)."""
        from ..moving3d import placer
        from ..solver3d import Solve3DSettings, solve_cell_3d

        settings = Solve3DSettings(degree=degree, mesh_size=mesh_size,
                                   domain_radius=self.far_radius, far_field=far_field,
                                   estimate_error=estimate_error)
        return solve_cell_3d(self, position, offset=offset, offset_angle=offset_angle,
                             surface_charge=sigma, settings=settings, comm=comm,
                             keep_solution=keep_solution,
                             solve_one=placer(mesh_motion))

    def __post_init__(self) -> None:
        for key, value in (("cavity_diameter_mm", self.cavity_diameter),
                           ("shell_thickness_mm", self.shell_thickness),
                           ("electrode_band_mm", self.electrode_band),
                           ("ball_diameter_mm", self.ball_diameter)):
            lo, hi = _RANGES_MM[key]
            if not (math.isfinite(value) and lo * 1e-3 < value <= hi * 1e-3):
                raise FieldError(f"[device] {key} = {value * 1e3:g} is out of range: "
                                 f"allowed ({lo:g}, {hi:g}] mm")
        if self.ball_diameter >= self.cavity_diameter:
            raise FieldError(f"[device] ball_diameter_mm = {self.ball_diameter * 1e3:g} is out "
                             f"of range: allowed (0, {self.cavity_diameter * 1e3:g}) mm "
                             "(smaller than cavity_diameter_mm)")
        if self.electrode_band >= self.cavity_diameter:
            raise FieldError(f"[device] electrode_band_mm = {self.electrode_band * 1e3:g} is out "
                             f"of range: allowed (0, {self.cavity_diameter * 1e3:g}) mm "
                             "(narrower than cavity_diameter_mm)")
        for key, value in (("wall_permittivity", self.wall_permittivity),
                           ("ball_permittivity", self.ball_permittivity)):
            if not (math.isfinite(value) and 1.0 <= value <= 1000.0):
                raise FieldError(f"[device] {key} = {value:g} is out of range: allowed [1, 1000]")
        if self.domain_radius is not None:
            lowest = DOMAIN_MIN_FACTOR * self.outer_radius
            if not (math.isfinite(self.domain_radius) and self.domain_radius > lowest):
                raise FieldError(f"[field] domain_radius_mm = {self.domain_radius * 1e3:g} is too "
                                 f"small: it must exceed {lowest * 1e3:.3g} mm "
                                 f"({DOMAIN_MIN_FACTOR:g} x the shell's outer radius)")

    # -- dimensions ----------------------------------------------------------
    @property
    def cavity_radius(self) -> float:
        return 0.5 * self.cavity_diameter

    @property
    def outer_radius(self) -> float:
        return self.cavity_radius + self.shell_thickness

    @property
    def ball_radius(self) -> float:
        return 0.5 * self.ball_diameter

    @property
    def stroke(self) -> float:
        """Travel of the ball along the axis [m]: cavity - ball diameter."""
        return self.cavity_diameter - self.ball_diameter

    @property
    def electrode_spacing(self) -> float:
        """The electrodes' distance along the axis [m]: the cavity diameter."""
        return self.cavity_diameter

    @property
    def bounding_radius(self) -> float:
        return shell_shape.bounding_radius_of(self.cavity_diameter, self.shell_thickness)

    @property
    def far_radius(self) -> float:
        """The field solve's far-field sphere [m] (``domain_radius`` or its default)."""
        if self.domain_radius is not None:
            return self.domain_radius
        return DOMAIN_AUTO_FACTOR * self.outer_radius

    @property
    def rim_angle(self) -> float:
        """Elevation [rad] of the electrodes' rims above the equator: asin(w / 2a)."""
        return math.asin(0.5 * self.electrode_band / self.cavity_radius)

    # -- the ball's region -------------------------------------------------------
    def ball_centre_z(self, position: float) -> float:
        """z [m] of the ball centre at gap ``position`` above the cavity's bottom."""
        return -self.cavity_radius + float(position) + self.ball_radius

    def admissible(self, centre) -> bool:
        """Ball centred at ``centre`` inside the cavity: |c| <= a - d/2."""
        return bool(np.linalg.norm(np.asarray(centre, dtype=float)) <=
                    self.cavity_radius - self.ball_radius * (1.0 - 1e-12))

    def wall_distance(self, centre) -> float:
        """Gap [m] between the ball and the spherical wall: a - d/2 - |c| (< 0: overlap)."""
        return self.cavity_radius - self.ball_radius - float(
            np.linalg.norm(np.asarray(centre, dtype=float)))

    def wall_normal(self, centre) -> np.ndarray:
        """Unit vector from the ball centre to the nearest wall point: the outward radial
        c/|c| (the contact force on the ball points along its opposite). At the centre
        every direction is as near; -z (down) is returned."""
        c = np.asarray(centre, dtype=float).reshape(3)
        norm = float(np.linalg.norm(c))
        if norm <= 1e-15 * self.cavity_radius:
            return np.array([0.0, 0.0, -1.0])
        return c / norm

    def electrode_at(self, z: float) -> str | None:
        """"lower", "upper" or None (the band) for the point at height ``z`` [m] on the
        cavity surface."""
        if z <= -0.5 * self.electrode_band:
            return "lower"
        if z >= 0.5 * self.electrode_band:
            return "upper"
        return None

    # -- breakdown, volume, plots ---------------------------------------------------
    def volume(self) -> float:
        """The shell's volume [m³]: the sphere of its outer radius (the shape's)."""
        return shell_shape.SphericalShell.volume(self)

    def longest_path(self) -> float:
        """Longest straight path [m] inside the cavity: its diameter (a bound on every
        line and field line from the ball to an electrode; the shape's)."""
        return shell_shape.SphericalShell.longest_path(self)

    def breakdown_feet(self, ball_centre_z: float, angles_deg) -> dict:
        """Lines from the ball surface to each electrode: from the surface point at polar
        angle θ from the axis (lower side: θ from the bottom, upper side: from the top)
        to the nearest point of that side's electrode, so no field line from there to
        the electrode is shorter (with a breakdown curve that does not fall with the
        gap, pairing the voltage with this length errs on the safe side, as the
        tube's lines do). The nearest point is the radial projection ``a p/|p|`` when
        it lies on the electrode (``radial`` True), else the electrode's rim in the
        point's meridian (the distance to the sphere grows with the angle from the
        projection). ``{"start", "foot"}`` (2, n, 3) in (r, z, 0), ``"length"`` and
        ``"radial"`` (2, n)."""
        theta = np.radians(np.asarray(angles_deg, dtype=float))
        rb, a = self.ball_radius, self.cavity_radius
        edge = 0.5 * self.electrode_band
        rim_r = math.sqrt(a * a - edge * edge)
        r = rb * np.sin(theta)
        dz = rb * np.cos(theta)
        out = {"start": [], "foot": [], "length": [], "radial": []}
        for sign in (-1.0, 1.0):   # lower side, upper side
            start = np.column_stack([r, ball_centre_z + sign * dz, np.zeros_like(r)])
            rho = np.linalg.norm(start, axis=1)
            safe = np.maximum(rho, 1e-300)[:, None]
            radial_foot = np.where(rho[:, None] > 1e-12 * a, a * start / safe,
                                   np.array([0.0, sign * a, 0.0]))
            radial = sign * radial_foot[:, 1] >= edge
            rim = np.array([rim_r, sign * edge, 0.0])
            foot = np.where(radial[:, None], radial_foot, rim)
            out["start"].append(start)
            out["foot"].append(foot)
            out["length"].append(np.linalg.norm(foot - start, axis=1))
            out["radial"].append(radial)
        return {key: np.array(value) for key, value in out.items()}

    def line_lengths(self, positions, angles) -> np.ndarray:
        """Breakdown line lengths [m] (len(positions), 2, lines) for the ball at gaps
        ``positions`` [m] and lines at polar ``angles`` [rad] (:meth:`breakdown_feet`;
        :class:`tengfield.breakdown.Lines` reads them)."""
        degrees = np.degrees(np.asarray(angles, dtype=float))
        return np.array([self.breakdown_feet(self.ball_centre_z(z), degrees)["length"]
                         for z in np.atleast_1d(np.asarray(positions, dtype=float))])

    def mesh_features(self) -> dict[str, float]:
        """Lengths [m] the default mesh must resolve, by scene key (the shape's)."""
        return shell_shape.SphericalShell.mesh_features(self)

    def outline(self, points: int = 91) -> list[np.ndarray]:
        """(r, z) polylines [m]: the electrodes (``electrodes``' order: the lower and the
        upper cap of the cavity surface), then the band (with a bare upper cap: the band
        and that cap), the shell's outer surface."""
        a, b, phi0 = self.cavity_radius, self.outer_radius, self.rim_angle

        def arc(radius, lo, hi):
            phi = np.linspace(lo, hi, points)
            return np.column_stack([radius * np.cos(phi), radius * np.sin(phi)])

        caps = {"lower": arc(a, -0.5 * math.pi, -phi0), "upper": arc(a, phi0, 0.5 * math.pi)}
        bare = arc(a, -phi0, 0.5 * math.pi if "upper" not in self.electrodes else phi0)
        return [*(caps[name] for name in self.electrodes), bare,
                arc(b, -0.5 * math.pi, 0.5 * math.pi)]

    # -- field ---------------------------------------------------------------------
    def canonical(self) -> "SphericalShell | None":
        """This shell on the canonical grid (:func:`tengfield.field.moving.canonical_length`)
        of its independent lengths: the cavity, the stroke (cavity - ball), the shell's
        thickness and the band; None when that shell is impossible. The geometry a
        candidate's meshes are mapped from (docs/field.md)."""
        from dataclasses import replace

        from ..moving import canonical_length as grid

        cavity = grid(self.cavity_diameter)
        try:
            return replace(self, cavity_diameter=cavity, domain_radius=None,
                           ball_diameter=cavity - grid(self.stroke),
                           shell_thickness=grid(self.shell_thickness),
                           electrode_band=grid(self.electrode_band))
        except (FieldError, ValueError):
            return None

    def axisymmetric_layout(self, position: float, *, mesh_size: float, degree: int = 2,
                            domain_radius: float | None = None, far_field: str = "kelvin",
                            grading_size: float | None = None):
        from .shell_model import layout
        return layout(self, position, mesh_size=mesh_size, degree=degree,
                      domain_radius=domain_radius, far_field=far_field,
                      grading_size=grading_size)

    def estimated_axisymmetric_cells(self, scene, position: float, mesh_size: float,
                                     grading_size: float | None = None) -> float:
        """Triangles of the (r, z) mesh before meshing (:mod:`tengfield.field.cost`)."""
        from .shell_model import shell_cells
        lay = self.axisymmetric_layout(position, mesh_size=mesh_size, degree=scene.field.degree,
                                       far_field=scene.field.far_field,
                                       domain_radius=scene.field.domain_radius,
                                       grading_size=grading_size)
        return shell_cells(lay)

    def build_axisymmetric_model(self, gmsh, layout, *, geometry_order: int = 2) -> str:
        from .shell_model import build_model
        return build_model(gmsh, layout, geometry_order=geometry_order)

    # -- the 3D model (field/cells/shell_model3d.py; geometry3d.build_model asks these) --
    def admissible_offset(self, position: float) -> float:
        """Largest lateral offset [m] of the ball at gap ``position`` [m]: sqrt(z (stroke - z))."""
        from .shell_model3d import admissible_offset
        return admissible_offset(self, position)

    def placement_3d(self, position: float, offset: float, offset_angle: float = 0.0):
        from .shell_model3d import placement
        return placement(self, position, offset, offset_angle)

    def check_tabulated_offset(self, offset: float) -> None:
        """Refuse (:class:`FieldError`, one line naming the allowed range) a table of the
        whole stroke at the fixed lateral ``offset`` [m]: the cavity holds only the axis
        at the ends of the stroke (asked by :func:`tengfield.surrogate.precompute` before
        any solve)."""
        for position in (0.0, self.stroke):
            self.placement_3d(position, offset)

    def contact_rule_3d(self, position: float, offset: float, offset_angle: float = 0.0):
        from .shell_model3d import contact_rule
        return contact_rule(self, position, offset, offset_angle)

    def extent_3d(self, offset: float) -> float:
        """The shell holds the ball wherever it is: its outer radius [m]."""
        return self.outer_radius

    def occ_parts(self, occ):
        from .shell_model3d import occ_parts
        return occ_parts(self, occ)

    def rim_distance_expr(self) -> str:
        from .shell_model3d import rim_distance_expr
        return rim_distance_expr(self)

    def gap_refinements_3d(self, centre, size: float, ball_factor: float) -> list:
        from .shell_model3d import gap_refinements
        return gap_refinements(self, centre, size, ball_factor)
