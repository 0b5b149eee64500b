"""``[device] shape = "spherical-shell"``: pure geometry (SI, no dolfinx).

The cavity ``cavity_diameter_mm`` lined by two hemispherical electrodes split by the
band ``electrode_band_mm`` at the equator, the shell ``shell_thickness_mm`` of
``wall_permittivity``. The stroke is ``cavity_diameter - ball_diameter``: ``stroke_mm``
is derived, and refused when written with another value. Its field models (the (r, z)
and the 3D gmsh models): :mod:`tengfield.field.cells.spherical_shell`.
"""
from __future__ import annotations

import math

from ...errors import SceneError
from ._common import around, ball_fits, mm

NAME = "spherical-shell"


def bounding_radius_of(cavity_diameter: float, shell_thickness: float) -> float:
    """The shell's outer radius a + t [m] (the device's and the field cell's)."""
    return 0.5 * cavity_diameter + shell_thickness


class SphericalShell:
    name = NAME
    keys = ("cavity_diameter_mm", "shell_thickness_mm", "electrode_band_mm")
    enclosure = "cavity"
    field_methods = ("axisymmetric", "3d")
    contact_3d = True
    hash_names_shape = True
    stroke_derived = True
    free_space_only = True
    #: the (z, r) table's offsets are scaled to the admissible radius at each height
    #: (tengfield.surrogate.sampling.offset_coordinate)
    offset_coordinate = "scaled"
    #: the two caps, or the lower cap alone (the single-electrode shell, its upper cap
    #: bare: the terminals the lower cap and the ground)
    electrode_sets = ("both", "lower")

    @staticmethod
    def stroke(device_values: dict, given: dict) -> float:
        """cavity - ball diameter; ``stroke_mm`` (or its old name) only if equal."""
        ball_fits(device_values["ball_diameter"], device_values["cavity_diameter"])
        stroke = device_values["cavity_diameter"] - device_values["ball_diameter"]
        for key in ("stroke_mm", "gap_mm"):
            if key in given and not isinstance(given[key], bool) \
                    and isinstance(given[key], (int, float)) \
                    and not math.isclose(float(given[key]) * 1e-3, stroke, rel_tol=1e-9,
                                         abs_tol=1e-15):
                raise SceneError(
                    f"[device] {key} = {given[key]!r} does not apply to shape = "
                    f"'spherical-shell': its stroke is cavity_diameter_mm - ball_diameter_mm "
                    f"= {mm(stroke)} mm (leave {key} out)")
        return stroke

    @staticmethod
    def check(dev) -> None:
        cavity = dev.cavity_diameter
        ball_fits(dev.ball_diameter, cavity)
        if dev.electrode_band >= cavity:
            raise SceneError(
                f"[device] electrode_band_mm = {mm(dev.electrode_band)} is out of range: allowed "
                f"(0, {mm(cavity)}) mm (narrower than cavity_diameter_mm)")

    @staticmethod
    def bounding_radius(dev) -> float:
        """The shell's outer radius a + t [m]."""
        return bounding_radius_of(dev.cavity_diameter, dev.shell_thickness)

    @staticmethod
    def volume(dev) -> float:
        """The outer sphere: 4/3 π (a + t)³."""
        return 4.0 / 3.0 * math.pi * (0.5 * dev.cavity_diameter + dev.shell_thickness) ** 3

    @staticmethod
    def max_offset(dev) -> float:
        return 0.5 * dev.cavity_diameter - dev.ball_radius

    @staticmethod
    def longest_path(dev) -> float:
        """The cavity's diameter (Paschen's low-pressure bound)."""
        return dev.cavity_diameter

    @staticmethod
    def mesh_features(dev) -> dict[str, float]:
        """The features [m] a mesh must resolve, by scene key."""
        features = {"ball_diameter_mm": dev.ball_diameter, "stroke_mm": dev.stroke,
                    "electrode_band_mm": dev.electrode_band}
        if dev.wall_permittivity != 1.0:
            features["shell_thickness_mm"] = dev.shell_thickness
        return features

    @staticmethod
    def followed(base: dict, values: dict) -> dict:
        """``geometry = "follow"`` (file units): a varied ball takes the cavity along,
        the stroke (cavity - ball) kept; the band and the shell's thickness stay. A
        varied cavity never follows."""
        if "ball_diameter_mm" in values and "cavity_diameter_mm" not in values:
            stroke = base["cavity_diameter_mm"] - base["ball_diameter_mm"]
            return {"cavity_diameter_mm": values["ball_diameter_mm"] + stroke}
        return {}

    derived = ("stroke_mm", "stroke = cavity - ball diameter")
    #: why a design does not vary the stroke (``design_vary_problem``)
    stroke_rule = ("its stroke is cavity_diameter_mm - ball_diameter_mm; vary "
                   "cavity_diameter_mm (and ball_diameter_mm)")

    @staticmethod
    def derived_mm(device: dict) -> float:
        return device["cavity_diameter_mm"] - device["ball_diameter_mm"]

    @staticmethod
    def default_design_vary(dev) -> dict:
        """The default design study's ranges: cavity and ball diameter (the stroke is
        derived); a ball that does not fit its cavity is a skipped candidate."""
        return {"cavity_diameter_mm": around(dev.cavity_diameter, (0.8, 1.2)),
                "ball_diameter_mm": around(dev.ball_diameter, (0.7, 1.3))}
