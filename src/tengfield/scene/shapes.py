"""The scene's side of ``[device] shape`` (issue #32): each shape's own rules, the
quantities the base layer needs (stroke, volume, bounding radius, mesh features) and
its part of the field hash. The cells' full geometry (meshes, breakdown lines,
outlines, 3D contact) is :mod:`tengfield.field.cells` (``CELLS``); the scene layer
cannot import it (it is a layer up), so the few formulas the scene itself needs are
here, one entry per shape in :data:`SHAPES`.

* ``"tube"``: the paper's tube (``stroke_mm``, ``electrode_radius_mm``,
  ``tube_*_radius_mm``, ``plate_thickness_mm``), unchanged.
* ``"spherical-shell"``: the cavity ``cavity_diameter_mm`` lined by two hemispherical
  electrodes split by the band ``electrode_band_mm`` at the equator, the shell
  ``shell_thickness_mm`` of ``wall_permittivity``. The stroke is ``cavity_diameter -
  ball_diameter``: ``stroke_mm`` is derived, and refused when written with another
  value.
* ``"hexagonal"``: the honeycomb cell of Fig. 10 (``tengfield.field.geometry3d.
  HexagonalCell``): the tube's keys with the hexagon's meaning (apothems), 3D field
  solves only (``[field] method = "3d"``), 1-D dynamics.
"""
from __future__ import annotations

import math

from ..errors import SceneError


#: the ``[device]`` keys of each shape besides the shared ones (ball, permittivities,
#: charge, density): a shape's field hash holds its own keys and not the others'
SHAPE_KEYS = {"tube": ("stroke_mm", "electrode_radius_mm", "tube_inner_radius_mm",
                       "tube_outer_radius_mm", "plate_thickness_mm"),
              "spherical-shell": ("cavity_diameter_mm", "shell_thickness_mm",
                                  "electrode_band_mm")}
SHAPE_KEYS["hexagonal"] = SHAPE_KEYS["tube"]   # the tube's keys, the hexagon's meaning


def _mm(x: float) -> str:
    return f"{x * 1e3:g}"


class _Tube:
    name = "tube"
    #: what holds the ball, in messages ("the ball must stay inside the tube")
    enclosure = "tube"

    @staticmethod
    def stroke(device_values: dict, given: dict) -> float:
        return device_values["stroke"]

    @staticmethod
    def check(dev) -> None:
        if dev.tube_outer_radius <= dev.tube_inner_radius:
            raise SceneError(
                f"[device] tube_outer_radius_mm = {_mm(dev.tube_outer_radius)} must exceed "
                f"tube_inner_radius_mm = {_mm(dev.tube_inner_radius)}")
        if dev.ball_diameter >= 2.0 * dev.tube_inner_radius:
            raise SceneError(
                f"[device] ball_diameter_mm = {_mm(dev.ball_diameter)}: the ball does not fit "
                f"the tube; allowed (0, {2e3 * dev.tube_inner_radius:g}) mm (twice "
                "tube_inner_radius_mm)")
        if dev.electrode_radius > dev.tube_outer_radius:
            raise SceneError(
                f"[device] electrode_radius_mm = {_mm(dev.electrode_radius)} is larger than "
                f"the plate: allowed (0, {_mm(dev.tube_outer_radius)}] mm "
                "(tube_outer_radius_mm)")

    @staticmethod
    def bounding_radius(dev) -> float:
        return math.hypot(dev.tube_outer_radius, 0.5 * dev.plate_spacing + dev.plate_thickness)

    @staticmethod
    def volume(dev) -> float:
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
    def followed(base: dict, values: dict) -> dict:
        return _tube_followed(base, values)

    #: the length ``tengfield design`` states beside the varied keys: (key, words)
    derived = ("plate_spacing_mm", "plate spacing h = stroke + ball diameter")

    @staticmethod
    def derived_mm(device: dict) -> float:
        return device["stroke_mm"] + device["ball_diameter_mm"]

    @staticmethod
    def default_design_vary(dev) -> dict:
        """The default design study's ranges (file units): stroke and ball diameter."""
        return {"stroke_mm": _around(dev.stroke, (0.5, 1.5)),
                "ball_diameter_mm": _around(dev.ball_diameter, (0.7, 1.3))}


def _around(x: float, factors) -> list[float]:
    """[x f_lo, x f_hi] in mm, 3 significant digits."""
    return [float(f"{x * 1e3 * f:.3g}") for f in factors]


def _tube_followed(base: dict, values: dict) -> dict:
    """The tube's ``geometry = "follow"`` rule (file units): the base scene's radial
    clearance (bore - ball radius), wall (outer - inner radius) and electrode inset (bore -
    electrode radius) are kept, so a bigger ball gets a bigger bore and the wall and the
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


def _ball_fits(ball: float, cavity: float) -> None:
    if ball >= cavity:
        raise SceneError(f"[device] ball_diameter_mm = {_mm(ball)} is out of range: allowed "
                         f"(0, {_mm(cavity)}) mm (smaller than cavity_diameter_mm: the ball "
                         "must fit the cavity)")


class _SphericalShell:
    name = "spherical-shell"
    enclosure = "cavity"
    #: the (z, r) table's offsets are scaled to the admissible radius at each height
    #: (tengfield.surrogate.sampling.offset_coordinate)
    offset_coordinate = "scaled"

    @staticmethod
    def stroke(device_values: dict, given: dict) -> float:
        """cavity - ball diameter; ``stroke_mm`` (or its old name) only if equal."""
        _ball_fits(device_values["ball_diameter"], device_values["cavity_diameter"])
        stroke = device_values["cavity_diameter"] - device_values["ball_diameter"]
        for key in ("stroke_mm", "gap_mm"):
            if key in given and not isinstance(given[key], bool) \
                    and isinstance(given[key], (int, float)) \
                    and not math.isclose(float(given[key]) * 1e-3, stroke, rel_tol=1e-9,
                                         abs_tol=1e-15):
                raise SceneError(
                    f"[device] {key} = {given[key]!r} does not apply to shape = "
                    f"'spherical-shell': its stroke is cavity_diameter_mm - ball_diameter_mm "
                    f"= {_mm(stroke)} mm (leave {key} out)")
        return stroke

    @staticmethod
    def check(dev) -> None:
        cavity = dev.cavity_diameter
        _ball_fits(dev.ball_diameter, cavity)
        if dev.electrode_band >= cavity:
            raise SceneError(
                f"[device] electrode_band_mm = {_mm(dev.electrode_band)} is out of range: allowed "
                f"(0, {_mm(cavity)}) mm (narrower than cavity_diameter_mm)")

    @staticmethod
    def bounding_radius(dev) -> float:
        return 0.5 * dev.cavity_diameter + dev.shell_thickness

    @staticmethod
    def volume(dev) -> float:
        """The outer sphere: 4/3 π (a + t)³."""
        return 4.0 / 3.0 * math.pi * (0.5 * dev.cavity_diameter + dev.shell_thickness) ** 3

    @staticmethod
    def max_offset(dev) -> float:
        return 0.5 * dev.cavity_diameter - dev.ball_radius

    @staticmethod
    def longest_path(dev) -> float:
        """The cavity's diameter (Paschen's low-pressure bound; ``SphericalShell``'s)."""
        return dev.cavity_diameter

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

    @staticmethod
    def derived_mm(device: dict) -> float:
        return device["cavity_diameter_mm"] - device["ball_diameter_mm"]

    @staticmethod
    def default_design_vary(dev) -> dict:
        """The default design study's ranges: cavity and ball diameter (the stroke is
        derived); a ball that does not fit its cavity is a skipped candidate."""
        return {"cavity_diameter_mm": _around(dev.cavity_diameter, (0.8, 1.2)),
                "ball_diameter_mm": _around(dev.ball_diameter, (0.7, 1.3))}


class _Hexagonal:
    """The honeycomb cell (Fig. 10): the tube's keys with the hexagon's meaning
    (``tube_inner_radius_mm``/``tube_outer_radius_mm``: the bore's and the outside's
    apothems, axis to a flat), electrodes over the whole bore."""
    name = "hexagonal"
    enclosure = "hexagonal bore"
    stroke = _Tube.stroke
    followed = _Tube.followed   # the apothems follow the ball as the tube's radii
    derived = _Tube.derived
    derived_mm = _Tube.derived_mm
    default_design_vary = _Tube.default_design_vary

    @staticmethod
    def check(dev) -> None:
        if dev.tube_outer_radius <= dev.tube_inner_radius:
            raise SceneError(
                f"[device] tube_outer_radius_mm = {_mm(dev.tube_outer_radius)} must exceed "
                f"tube_inner_radius_mm = {_mm(dev.tube_inner_radius)} (the hexagon's apothems)")
        if dev.ball_diameter >= 2.0 * dev.tube_inner_radius:
            raise SceneError(
                f"[device] ball_diameter_mm = {_mm(dev.ball_diameter)}: the ball does not fit "
                f"the hexagonal bore; allowed (0, {2e3 * dev.tube_inner_radius:g}) mm (twice "
                "tube_inner_radius_mm, the bore's apothem)")

    @staticmethod
    def bounding_radius(dev) -> float:
        corner = dev.tube_outer_radius / math.cos(math.pi / 6)
        return math.hypot(corner, 0.5 * dev.plate_spacing + dev.plate_thickness)

    @staticmethod
    def volume(dev) -> float:
        """The hexagonal prism: 2√3 b² (h + 2t), b the outer apothem."""
        return 2.0 * math.sqrt(3.0) * dev.tube_outer_radius**2 * (dev.plate_spacing
                                                                  + 2 * dev.plate_thickness)

    @staticmethod
    def max_offset(dev) -> float:
        return dev.tube_inner_radius - dev.ball_radius

    @staticmethod
    def longest_path(dev) -> float:
        """Hypot of the plate spacing and the bore's corner-to-corner width."""
        return math.hypot(dev.plate_spacing, 2.0 * dev.tube_inner_radius / math.cos(math.pi / 6))


#: ``[device] shape`` -> its scene-level rules (the shapes a scene can run)
SHAPES = {_Tube.name: _Tube, _Hexagonal.name: _Hexagonal, _SphericalShell.name: _SphericalShell}

#: shapes the schema names that a scene cannot run yet -> why (one line)
NOT_RUNNABLE: dict[str, str] = {}


def shape_of(shape: str):
    """The rules of ``shape``; SceneError for a shape a scene cannot run."""
    if shape in NOT_RUNNABLE:
        raise SceneError(f"[device] shape = {shape!r}: {NOT_RUNNABLE[shape]}")
    return SHAPES[shape]


def design_vary_problem(shape: str, key: str) -> str | None:
    """Why ``[design.vary] key`` does not apply to ``shape`` (None: it does): the keys of
    another shape, and for the shell the stroke (derived: cavity - ball)."""
    if shape == "spherical-shell" and key in ("stroke_mm", "gap_mm"):
        return (f"[design.vary] {key} does not apply to shape = 'spherical-shell': its stroke "
                "is cavity_diameter_mm - ball_diameter_mm; vary cavity_diameter_mm (and "
                "ball_diameter_mm)")
    own = SHAPE_KEYS.get(shape, ())
    for other, keys in SHAPE_KEYS.items():
        if key in keys and key not in own and other != shape:
            return (f"[design.vary] {key} does not apply to shape = {shape!r} (a key of "
                    f"shape = {other!r}); allowed for it: " + ", ".join(
                        k for k in own if k not in ("stroke_mm",)
                        or shape != "spherical-shell") + " and the shared [device] keys")
    return None


def followed_keys(shape: str, base: dict, values: dict) -> dict:
    """``[device]`` keys (file units) that follow the varied ``values`` of a design
    candidate under ``geometry = "follow"`` (the shape's rule, :data:`SHAPES`), rounded
    to 12 digits. ``base``: the base scene's ``[device]`` (``to_dict``)."""
    out = shape_of(shape).followed(base, values)
    return {k: float(f"{v:.12g}") for k, v in out.items()}


def derived_stroke(shape: str, raw_device: dict, device: dict) -> dict:
    """A shape whose stroke is derived (the shell), written with ``stroke_mm`` (or its old
    name) in the base scene: that key at the candidate's derived value (``device``: the
    candidate's ``[device]``, file units), so a varied cavity or ball is not refused."""
    if shape != "spherical-shell":
        return {}
    stroke = _SphericalShell.derived_mm(device)
    return {k: float(f"{stroke:.12g}") for k in ("stroke_mm", "gap_mm") if k in raw_device}


def check_shape_scene(scene) -> None:
    """Rules between the shape and other sections: what a shape does not support yet
    (the honeycomb's 3D contact)."""
    dev = scene.device
    if dev.shape == "hexagonal" and scene.contact.model == "3d":
        raise SceneError(f"[contact] model = '3d' is not available for shape = {dev.shape!r} "
                         "yet (the contact on the hexagonal wall is not done): use 'impact' "
                         "or 'soft'")


def shape_field_problems(dev, fld) -> list[str]:
    """Field-only problems of a non-tube shape: the honeycomb has 3D solves only; the
    shell has both solvers (an off-axis ball's offset is checked against its height by
    the cell, field/cells/shell_model3d.py); both are free-space cells."""
    if dev.shape == "tube":
        return []
    problems = []
    if dev.shape == "hexagonal":
        if fld.method == "axisymmetric":     # "auto" chooses 3D (resolve_method)
            problems.append(f"[field] method = {fld.method!r}: shape = 'hexagonal' is a 3D "
                            "cell; use method = '3d'")
    if fld.environment != "free-space":
        problems.append(f"[field] environment = {fld.environment!r} is not available for "
                        f"shape = {dev.shape!r}: allowed 'free-space'")
    return problems


def enclosure(shape: str) -> str:
    """What holds the ball in ``shape``, as messages name it (tube, cavity, ...)."""
    return getattr(SHAPES.get(shape), "enclosure", "tube")


def keys_of_other_shapes(shape: str, given) -> list[str]:
    """The keys among ``given`` ([device] keys as written) that belong to another shape
    only (a tube's ``cavity_diameter_mm``): the scene leaves them out."""
    own = set(SHAPE_KEYS.get(shape, ())) | {"gap_mm"}
    return [key for key in given if key not in own
            and any(key in keys for keys in SHAPE_KEYS.values())]


def switched_shape(device: dict, previous: str, shape: str, kept) -> dict:
    """``[device]`` (file keys) after ``--set device.shape`` switched ``previous`` to
    ``shape``: the keys of the previous shape that the new one does not have are dropped
    (and the shell's derived ``stroke_mm``), except those set in the same command
    (``kept``)."""
    if previous == shape:
        return device
    drop = set(SHAPE_KEYS.get(previous, ())) - set(SHAPE_KEYS.get(shape, ()))
    if shape == "spherical-shell":
        drop |= {"stroke_mm", "gap_mm"}
    return {k: v for k, v in device.items() if k not in drop or k in kept}


def shape_mesh_features(dev) -> dict[str, float] | None:
    """The features [m] a mesh of a non-tube shape must resolve (None: the tube's rule)."""
    if dev.shape != "spherical-shell":
        return None
    features = {"ball_diameter_mm": dev.ball_diameter, "stroke_mm": dev.stroke,
                "electrode_band_mm": dev.electrode_band}
    if dev.wall_permittivity != 1.0:
        features["shell_thickness_mm"] = dev.shell_thickness
    return features


def shape_field_inputs(device_inputs: dict, shape: str, full_device: dict,
                       hash_names: dict) -> dict:
    """The ``[device]`` part of the field hash for ``shape``: a tube's exactly as before
    the shape key existed (no ``shape``, no shell keys); another shape's names it, holds
    its own keys (:data:`SHAPE_KEYS`) and drops the tube's (``hash_names``: the schema's
    ``HASH_NAMES``, a renamed key's name in the hash)."""
    out = dict(device_inputs)
    if shape == "tube":
        out.pop("shape", None)
        return out
    for key in SHAPE_KEYS["tube"]:
        out.pop(hash_names.get(("device", key), key), None)
    for key in SHAPE_KEYS.get(shape, ()):
        out[key] = full_device[key]
    return out
