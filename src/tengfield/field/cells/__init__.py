"""Cell shapes: one object per shape that knows its geometry for every stage.

A cell is the part of the device around one ball: the electrodes, the
dielectric walls and the cavity the ball moves in. Every stage asks the cell
(never a shape's own attributes), through :class:`Cell`:

==========================  ==================================================
stage                       what it asks
==========================  ==================================================
field (axisymmetric)        ``axisymmetric_layout(position, ...)`` and
                            ``build_axisymmetric_model(gmsh, layout)``: the gmsh
                            model in the (r, z) half-plane with the physical
                            groups of :mod:`tengfield.field.geometry_axisymmetric`
                            (``CELL_TAGS``, ``FACET_TAGS``), which the tube's
                            solver (``axisymmetric.discretise`` and
                            ``solve_discretisation``) assembles and solves as is
field (3D)                  ``placement_3d``, ``contact_rule_3d``, ``extent_3d``,
                            ``occ_parts``, ``rim_distance_expr``,
                            ``gap_refinements_3d`` (the shell; see
                            :func:`tengfield.field.geometry3d.build_model`)
field (default mesh size)   ``mesh_features()``: {scene key: length [m]}
surrogate, dynamics (1-D)   ``stroke``: the ball's travel on the axis [m]
                            (position z = gap below the ball, in [0, stroke]);
                            ``electrode_spacing``: the length the contact rule's
                            minimum gap is a fraction of
dynamics (3D)               ``admissible(centre)``, ``wall_distance(centre)``,
                            ``wall_normal(centre)``: the ball's admissible region
                            and the contact with the wall
breakdown                   ``longest_path()`` (Paschen's low-pressure bound),
                            ``breakdown_feet(ball_centre_z, angles_deg)``
power densities             ``volume()`` [m³]
plots                       ``outline()``: polylines in (r, z) [m]
==========================  ==================================================

Coordinates: the cell's centre at the origin, z up (the drive's axis), SI.
A ball centre is ``(x, y, z)`` [m].

``CELLS`` maps a ``[device] shape`` name to the class of its cell, the field models
of the shape whose pure geometry is the same-named module of
:mod:`tengfield.scene.shapes` (``SHAPES``). Each class has ``from_scene(scene)``
(``cell_of(scene)``), ``field_models`` (``[field] method`` -> its solver, the names of
the shape's ``field_methods``; ``solve_scene`` looks the method up there, the one place
:func:`tengfield.field.solve_position`, and so the surrogate, the run, ``tengfield
field``, dispatches on the shape) and ``contact_walls`` (the 3D contact model's
surfaces, :mod:`.contact_surfaces`). ``"tube"`` (:mod:`.tube`) reads the scene's
device, ``"spherical-shell"`` (:mod:`.spherical_shell`) is the shell with its own
(r, z) and 3D gmsh models, ``"hexagonal"`` (:mod:`.hexagonal`) is built on the
honeycomb's 3D cell. The 3D gmsh model is built by
:func:`tengfield.field.geometry3d.build_model` from the 3D cell's answers
(``placement_3d``, ``contact_rule_3d``, ``extent_3d``, ``occ_parts``,
``rim_distance_expr``, ``gap_refinements_3d``): the tube's and the honeycomb's in
``plate_model3d.py``, the shell's in :mod:`.shell_model3d`. docs/architecture.md ("Where a
new cell shape goes") and docs/spherical_shell.md say what is left.
"""
from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ..._registry import lookup

from .hexagonal import Hexagonal
from .spherical_shell import SphericalShell
from .tube import Tube

__all__ = ["Cell", "CELLS", "Hexagonal", "SphericalShell", "Tube", "cell_class", "cell_of"]


@runtime_checkable
class Cell(Protocol):
    """What a cell shape must know (SI; see the module docstring for who asks)."""

    #: the ``[device] shape`` value
    name: str

    @property
    def stroke(self) -> float:
        """The ball's travel along the axis [m]: z in [0, stroke]."""

    @property
    def electrode_spacing(self) -> float:
        """Distance between the electrodes along the axis [m] (the contact rule's
        minimum gap is ``MIN_GAP_FRACTION`` of it)."""

    def ball_centre_z(self, position: float) -> float:
        """z [m] of the ball centre for the ball at gap ``position`` on the axis."""

    def admissible(self, centre) -> bool:
        """Whether a ball centred at ``centre`` [m] lies inside the cavity."""

    def wall_distance(self, centre) -> float:
        """Gap [m] between the ball surface and the nearest wall (< 0: overlap)."""

    def wall_normal(self, centre) -> np.ndarray:
        """Unit vector from the ball centre toward the nearest wall point."""

    def volume(self) -> float:
        """Volume [m³] the cell occupies (for power densities)."""

    def longest_path(self) -> float:
        """Longest straight discharge path [m] between the ball and an electrode."""

    def breakdown_feet(self, ball_centre_z: float, angles_deg) -> dict:
        """The breakdown lines from the ball surface (points at polar angles from the
        axis, lower and upper side) to the electrodes: ``{"start", "foot"}`` arrays
        (2, n, 3) in (r, z, 0) and ``"length"`` (2, n) [m] (a shape may add its own
        keys)."""

    def mesh_features(self) -> dict[str, float]:
        """The lengths [m] a mesh must resolve, by scene key (default mesh size rule)."""

    def outline(self) -> list[np.ndarray]:
        """Polylines (n, 2) in (r, z) [m]: the cell's outline for plots."""

    def axisymmetric_layout(self, position: float, *, mesh_size: float, degree: int = 2,
                            domain_radius: float | None = None, far_field: str = "kelvin",
                            grading_size: float | None = None):
        """Dimensions of the axisymmetric model with the ball at gap ``position`` (pure)."""

    def build_axisymmetric_model(self, gmsh, layout, *, geometry_order: int = 2) -> str:
        """Create and mesh the (r, z) model of ``layout``; returns its unique name."""

    def canonical(self):
        """This cell with its lengths on the canonical grid (the geometry whose (r, z)
        meshes a candidate's are mapped from, :mod:`tengfield.field.moving`), or None."""

    def check_tabulated_offset(self, offset: float) -> None:
        """Refuse (FieldError, one line) a table of the whole stroke at the lateral
        ``offset`` [m] the cell cannot hold at every height (asked before any solve)."""


    #: ``[field] method`` -> the solver ``(cell, scene, position, *, comm, offset,
    #: **options)`` (the names of the shape's ``field_methods``, scene/shapes/)
    field_models: dict

    #: the walls of the 3D contact model (``contact_surfaces.tube_surfaces``, ...), or
    #: None while the shape's walls are not described
    contact_walls: object

    def solve_scene(self, scene, position: float, *, comm, method: str, offset: float,
                    **options):
        """:func:`tengfield.field.solve_position` of a scene of this shape (``method``
        resolved): ``field_models[method]`` (``_methods.solve_with``)."""


#: ``[device] shape`` -> the class of its cell
CELLS: dict[str, type] = {Tube.name: Tube, Hexagonal.name: Hexagonal,
                          SphericalShell.name: SphericalShell}


def cell_of(scene):
    """The cell of ``scene`` (``[device] shape``, validated by the scene)."""
    return cell_class(scene.device.shape).from_scene(scene)


def cell_class(shape: str) -> type:
    """The class of ``shape``; ``ValueError`` naming the registered shapes otherwise."""
    if shape not in CELLS:
        raise ValueError(f"shape = {shape!r} is not a registered cell: allowed "
                         f"{', '.join(sorted(CELLS))}")
    return lookup(CELLS, shape, "[device] shape")
