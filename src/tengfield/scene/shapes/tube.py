"""``[device] shape = "tube"``: the paper's tube, pure geometry (SI, no dolfinx).

Keys: ``stroke_mm``, ``electrode_radius_mm``, ``tube_inner_radius_mm``,
``tube_outer_radius_mm``, ``plate_thickness_mm``. The electrodes are the discs
``z = ±h/2, r <= a`` (h = plate spacing = stroke + ball diameter), the tube's inner
wall the cylinder ``r = r_i``. Its field models: :mod:`tengfield.field.cells.tube`.
"""
from __future__ import annotations

import math

from ...errors import SceneError
from ._common import around, mm

NAME = "tube"


def bounding_radius_of(outer_radius: float, half_height: float) -> float:
    """The tube's bounding radius [m]: hypot(outer radius, half the spacing + a plate);
    the scene's device and the 3D cell (field/cells/plate_model3d.py) both ask this one formula."""
    return math.hypot(outer_radius, half_height)


class Tube:
    name = NAME
    #: the ``[device]`` keys of this shape besides the shared ones (ball, permittivities,
    #: charge, density)
    keys = ("stroke_mm", "electrode_radius_mm", "tube_inner_radius_mm",
            "tube_outer_radius_mm", "plate_thickness_mm")
    #: what holds the ball, in messages ("the ball must stay inside the tube")
    enclosure = "tube"
    #: the field methods it offers, in the order "auto" prefers them
    field_methods = ("axisymmetric", "3d")
    #: its walls are described for the 3D contact model ([contact] model = "3d")
    contact_3d = True
    #: the field hash names the shape (False: the tube's hash from before shapes existed)
    hash_names_shape = False
    #: the stroke is derived from other keys (``stroke_mm`` refused unless equal)
    stroke_derived = False
    #: free-space cell only ([field] environment)
    free_space_only = False
    #: the ``[device] electrodes`` it offers: the pair, or the lower electrode alone (the
    #: single-electrode cell; both field methods, on and off the axis)
    electrode_sets = ("both", "lower")
    #: the (z, r) table's offsets: the radius itself
    #: (tengfield.surrogate.sampling.offset_coordinate)
    offset_coordinate = "radial"
    #: the measured relative error of its 3D solves against their dofs, per ``[field]
    #: mesh_grading``: ``(error, dofs, rate)``, error(N) = error (N / dofs)^-rate (P2, the
    #: paper's tube, ball on the axis at z = 1.5 mm, against the axisymmetric reference:
    #: docs/field3d.md, "Graded meshes"; rate fitted between 0.7 and 0.5 mm). What the
    #: tolerance check before the work reads (tengfield.field.cost.tolerance_problem); a
    #: shape without it is not checked
    error_3d = {"uniform": (3.2e-3, 1_126_226, 0.37), "graded": (2.5e-3, 548_271, 0.99)}
    #: its 3D meshes follow ``[field] mesh_grading`` ("graded": fewer dofs, field/cost.py)
    grades_3d = True

    @staticmethod
    def stroke(device_values: dict, given: dict) -> float:
        return device_values["stroke"]

    @staticmethod
    def check(dev) -> None:
        if dev.tube_outer_radius <= dev.tube_inner_radius:
            raise SceneError(
                f"[device] tube_outer_radius_mm = {mm(dev.tube_outer_radius)} must exceed "
                f"tube_inner_radius_mm = {mm(dev.tube_inner_radius)}")
        if dev.ball_diameter >= 2.0 * dev.tube_inner_radius:
            raise SceneError(
                f"[device] ball_diameter_mm = {mm(dev.ball_diameter)}: the ball does not fit "
                f"the tube; allowed (0, {2e3 * dev.tube_inner_radius:g}) mm (twice "
                "tube_inner_radius_mm)")
        if dev.electrode_radius > dev.tube_outer_radius:
            raise SceneError(
                f"[device] electrode_radius_mm = {mm(dev.electrode_radius)} is larger than "
                f"the plate: allowed (0, {mm(dev.tube_outer_radius)}] mm "
                "(tube_outer_radius_mm)")

    @staticmethod
    def bounding_radius(dev) -> float:
        """Radius [m] of the smallest sphere about the centre holding the cell."""
        return bounding_radius_of(dev.tube_outer_radius,
                                  0.5 * dev.plate_spacing + dev.plate_thickness)

    @staticmethod
    def volume(dev) -> float:
        """The tube and both plates: π r_o² (h + 2t) [m³]."""
        return math.pi * dev.tube_outer_radius**2 * (dev.plate_spacing + 2 * dev.plate_thickness)

    @staticmethod
    def longest_path(dev) -> float:
        """The tube's inner diagonal, hypot(plate spacing, inner diameter): every line and
        field line from the ball to an electrode is shorter (Paschen's low-pressure bound)."""
        return math.hypot(dev.plate_spacing, 2.0 * dev.tube_inner_radius)

    @staticmethod
    def max_offset(dev) -> float:
        return dev.tube_inner_radius - dev.ball_radius

    @staticmethod
    def mesh_features(dev) -> dict[str, float] | None:
        """The features a mesh must resolve: None, the tube's rule
        (:func:`tengfield.scene.limits.mesh_features`)."""
        return None

    @staticmethod
    def outline(dev) -> list[tuple]:
        """(r, z) polylines [m]: the electrodes, the plates' and the tube's outlines."""
        h, t = 0.5 * dev.plate_spacing, dev.plate_thickness
        ri, ro, a = dev.tube_inner_radius, dev.tube_outer_radius, dev.electrode_radius
        return [((0.0, -h), (a, -h)), ((0.0, h), (a, h)),
                ((0.0, -h - t), (ro, -h - t), (ro, h + t), (0.0, h + t)),
                ((0.0, -h), (ri, -h), (ri, h), (0.0, h))]

    @staticmethod
    def followed(base: dict, values: dict) -> dict:
        """``geometry = "follow"`` (file units): the base scene's radial clearance (bore -
        ball radius), wall (outer - inner radius) and electrode inset (bore - electrode
        radius) are kept, so a bigger ball gets a bigger bore and the wall and the
        electrode follow the bore. A varied key never follows."""
        b, out = base, {}
        bore = b["tube_inner_radius_mm"]
        if "ball_diameter_mm" in values and "tube_inner_radius_mm" not in values:
            clearance = b["tube_inner_radius_mm"] - 0.5 * b["ball_diameter_mm"]
            bore = 0.5 * values["ball_diameter_mm"] + clearance
            out["tube_inner_radius_mm"] = bore
        elif "tube_inner_radius_mm" in values:
            bore = values["tube_inner_radius_mm"]
        if bore != b["tube_inner_radius_mm"]:
            if "electrode_radius_mm" not in values:
                out["electrode_radius_mm"] = bore - (b["tube_inner_radius_mm"]
                                                     - b["electrode_radius_mm"])
            if "tube_outer_radius_mm" not in values:
                out["tube_outer_radius_mm"] = bore + (b["tube_outer_radius_mm"]
                                                      - b["tube_inner_radius_mm"])
        return out

    #: the length ``tengfield design`` states beside the varied keys: (key, words)
    derived = ("plate_spacing_mm", "plate spacing h = stroke + ball diameter")

    @staticmethod
    def derived_mm(device: dict) -> float:
        return device["stroke_mm"] + device["ball_diameter_mm"]

    @staticmethod
    def default_design_vary(dev) -> dict:
        """The default design study's ranges (file units): stroke and ball diameter."""
        return {"stroke_mm": around(dev.stroke, (0.5, 1.5)),
                "ball_diameter_mm": around(dev.ball_diameter, (0.7, 1.3))}
