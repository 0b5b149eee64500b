"""``[device] shape = "hexagonal"``: the honeycomb cell of Fig. 10, pure geometry.

The tube's keys with the hexagon's meaning (``tube_inner_radius_mm`` /
``tube_outer_radius_mm``: the bore's and the outside's apothems, axis to a flat),
electrodes over the whole bore; 3D field solves only (``[field] method = "3d"``), 1-D
dynamics (its walls are not described for the 3D contact model yet). Its field model:
:mod:`tengfield.field.cells.hexagonal` (the gmsh model in ``field/cells/plate_model3d.py``).

This module is the worked example of docs/architecture.md ("A new shape"): one module
here, its field model in field/cells/, one line in each registry.
"""
from __future__ import annotations

import math

from ...errors import SceneError
from ._common import mm
from .tube import Tube

NAME = "hexagonal"
#: corner radius / apothem of a regular hexagon is 1 / COS30
COS30 = math.cos(math.pi / 6)


def bounding_radius_of(outer_apothem: float, half_height: float) -> float:
    """The honeycomb's bounding radius [m]: hypot(outer corner radius, half the spacing +
    a plate); the scene's device and the 3D cell (field/cells/plate_model3d.py) both ask this."""
    return math.hypot(outer_apothem / COS30, half_height)


class Hexagonal:
    """The honeycomb cell (Fig. 10)."""
    name = NAME
    keys = Tube.keys   # the tube's keys, the hexagon's meaning
    enclosure = "hexagonal bore"
    field_methods = ("3d",)
    contact_3d = False
    hash_names_shape = True
    stroke_derived = False
    free_space_only = True
    offset_coordinate = "radial"
    #: its 3D meshes follow ``[field] mesh_grading`` (the tube's rules: field/cost.py); no
    #: measured error against dofs (``error_3d``): no tolerance check before the work
    grades_3d = True
    #: the pair, or the lower electrode alone (the single-electrode cell, the ceiling bare)
    electrode_sets = Tube.electrode_sets
    stroke = Tube.stroke
    followed = Tube.followed   # the apothems follow the ball as the tube's radii
    derived = Tube.derived
    derived_mm = Tube.derived_mm
    default_design_vary = Tube.default_design_vary
    mesh_features = Tube.mesh_features   # the tube's rule

    @staticmethod
    def check(dev) -> None:
        if dev.tube_outer_radius <= dev.tube_inner_radius:
            raise SceneError(
                f"[device] tube_outer_radius_mm = {mm(dev.tube_outer_radius)} must exceed "
                f"tube_inner_radius_mm = {mm(dev.tube_inner_radius)} (the hexagon's apothems)")
        if dev.ball_diameter >= 2.0 * dev.tube_inner_radius:
            raise SceneError(
                f"[device] ball_diameter_mm = {mm(dev.ball_diameter)}: the ball does not fit "
                f"the hexagonal bore; allowed (0, {2e3 * dev.tube_inner_radius:g}) mm (twice "
                "tube_inner_radius_mm, the bore's apothem)")

    @staticmethod
    def bounding_radius(dev) -> float:
        """hypot(outer corner radius, h/2 + plate thickness) [m]."""
        return bounding_radius_of(dev.tube_outer_radius,
                                  0.5 * dev.plate_spacing + dev.plate_thickness)

    @staticmethod
    def volume(dev) -> float:
        """The hexagonal prism: 2√3 b² (h + 2t), b the outer apothem."""
        return 2.0 * math.sqrt(3.0) * dev.tube_outer_radius**2 * (dev.plate_spacing
                                                                  + 2 * dev.plate_thickness)

    @staticmethod
    def max_offset(dev) -> float:
        return dev.tube_inner_radius - dev.ball_radius

    @staticmethod
    def outline(dev) -> list[tuple]:
        """(r, z) polylines [m] of the section through two flats: the electrodes (over the
        whole bore), the outside, the bore."""
        h, t = 0.5 * dev.plate_spacing, dev.plate_thickness
        ri, ro = dev.tube_inner_radius, dev.tube_outer_radius
        return [((0.0, -h), (ri, -h)), ((0.0, h), (ri, h)),
                ((0.0, -h - t), (ro, -h - t), (ro, h + t), (0.0, h + t)),
                ((0.0, -h), (ri, -h), (ri, h), (0.0, h))]

    @staticmethod
    def longest_path(dev) -> float:
        """Hypot of the plate spacing and the bore's corner-to-corner width."""
        return math.hypot(dev.plate_spacing, 2.0 * dev.tube_inner_radius / COS30)
