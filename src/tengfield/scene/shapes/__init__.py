"""``[device] shape``: the shape registry (issues #32, #41).

Each shape is ONE module here, pure geometry the scene can import without dolfinx
(:mod:`.tube`, :mod:`.spherical_shell`, :mod:`.hexagonal`): its ``[device]`` keys,
checks, stroke, volume, bounding radius, longest path, mesh features, its part of the
field hash, its design rules, and the names of the field methods it offers
(``field_methods``, entries of :data:`.methods.FIELD_METHODS`). Its field models (gmsh
and dolfinx) are the same-named module of :mod:`tengfield.field.cells`, whose table
``FIELD_MODELS`` maps each of those names to a solver. :data:`SHAPES` is looked up
through :func:`tengfield._registry.lookup` like every other registry; callers ask the
entry (``shape_of(dev.shape).contact_3d``), never compare a shape's name.
"""
from __future__ import annotations

from ..._registry import lookup
from ...errors import SceneError
from ...quantities import SURFACE_CHARGE_KEY
from . import methods
from .hexagonal import Hexagonal
from .spherical_shell import SphericalShell
from .tube import Tube

#: ``[device] shape`` -> its module's entry (the shapes a scene can run)
SHAPES = {Tube.name: Tube, Hexagonal.name: Hexagonal, SphericalShell.name: SphericalShell}

#: the ``[device]`` keys of each shape besides the shared ones (ball, permittivities,
#: charge, density): a shape's field hash holds its own keys and not the others'
SHAPE_KEYS = {name: shape.keys for name, shape in SHAPES.items()}

#: shapes the schema names that a scene cannot run yet -> why (one line)
NOT_RUNNABLE: dict[str, str] = {}

#: the shape whose field hash predates the shape key (its keys are dropped from the
#: hash of every other shape)
_LEGACY = Tube


def shape_of(shape: str):
    """The entry of ``shape``; SceneError for a shape a scene cannot run."""
    if shape in NOT_RUNNABLE:
        raise SceneError(f"[device] shape = {shape!r}: {NOT_RUNNABLE[shape]}")
    return lookup(SHAPES, shape, "[device] shape")


def field_method(shape: str, method: str, offset: float = 0.0) -> str:
    """``[field] method`` of a scene of ``shape`` resolved: "auto" -> the first of the
    shape's methods that takes a ball at ``offset`` [m]; a method the shape does not
    offer raises ``SceneError`` naming the ones it has."""
    return methods.resolve(shape_of(shape).field_methods, method, offset)


def design_vary_problem(shape: str, key: str) -> str | None:
    """Why ``[design.vary] key`` does not apply to ``shape`` (None: it does): the keys of
    another shape, and for a derived stroke (the shell's) the stroke."""
    entry = SHAPES.get(shape)
    derived = entry is not None and entry.stroke_derived
    if derived and key in ("stroke_mm", "gap_mm"):
        return (f"[design.vary] {key} does not apply to shape = {shape!r}: "
                f"{entry.stroke_rule}")
    own = SHAPE_KEYS.get(shape, ())
    for other, keys in SHAPE_KEYS.items():
        if key in keys and key not in own and other != shape:
            return (f"[design.vary] {key} does not apply to shape = {shape!r} (a key of "
                    f"shape = {other!r}); allowed for it: " + ", ".join(
                        k for k in own if k not in ("stroke_mm",) or not derived)
                    + " and the shared [device] keys")
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
    entry = shape_of(shape)
    if not entry.stroke_derived:
        return {}
    stroke = entry.derived_mm(device)
    return {k: float(f"{stroke:.12g}") for k in ("stroke_mm", "gap_mm") if k in raw_device}


def check_shape_scene(scene) -> None:
    """Rules between the shape and other sections: what a shape does not support yet
    (the honeycomb's 3D contact)."""
    dev = scene.device
    # kept: the dynamics' MODELS registry is a layer up; its lateral model is "3d"
    if scene.contact.model == "3d" and not shape_of(dev.shape).contact_3d:
        raise SceneError(f"[contact] model = '3d' is not available for shape = {dev.shape!r} "
                         "yet (the contact on the hexagonal wall is not done): use 'impact' "
                         "or 'soft'")


def gap_lines_problem(dev, fld, alternative: str = "") -> str | None:
    """Why a field solve of ``dev`` with ``fld`` (``[field]``) samples no breakdown gap
    lines (None: it does): the resolved method's entry says (``"auto"`` through the
    shape's ``field_methods``: the honeycomb's is "3d"). The one rule every user of the
    lines asks before its first solve (a run's σ = "breakdown", ``tengfield breakdown``,
    ``design``, ``uncertainty``'s breakdown-band draws); ``alternative``: what else the
    asker can do (e.g. give σ as a number), said after the fix."""
    try:
        method = field_method(dev.shape, fld.method, fld.ball_offset)
    except SceneError as exc:
        return str(exc)
    if methods.FIELD_METHODS[method].gap_lines and fld.ball_offset == 0.0:
        return None
    offered = [m for m in shape_of(dev.shape).field_methods if methods.FIELD_METHODS[m].gap_lines]
    if offered:
        fix = f'use [field] method = "{offered[0]}" with ball_offset_mm = 0' + (
            f", or {alternative}" if alternative else "")
    else:
        fix = f"shape = {dev.shape!r} has 3D solves only" + (
            f": {alternative}" if alternative else "")
    return (f"the breakdown gap lines come from the axisymmetric field solver (the ball on "
            f"the axis): shape = {dev.shape!r}, [field] method = {fld.method!r}, "
            f"ball_offset_mm = {fld.ball_offset * 1e3:g} has none; {fix}")


#: what an asker of the lines that states σ can do instead (gap_lines_problem's alternative)
NUMERIC_SIGMA = f"give [device] {SURFACE_CHARGE_KEY} as a number"


def has_gap_lines(dev, fld) -> bool:
    """Whether a field solve of ``dev`` with ``fld`` samples the breakdown gap lines
    (:func:`gap_lines_problem` is None)."""
    return gap_lines_problem(dev, fld) is None


def shape_field_problems(dev, fld) -> list[str]:
    """Field-only problems of the shape: a method it does not offer (the honeycomb has 3D
    solves only); a free-space cell in another environment."""
    entry = shape_of(dev.shape)
    problems = []
    offered = entry.field_methods
    if fld.method != methods.AUTO and fld.method not in offered:
        what = f"is a {offered[0].upper()} cell" if len(offered) == 1 else \
            "offers " + ", ".join(map(repr, offered))
        problems.append(f"[field] method = {fld.method!r}: shape = {dev.shape!r} {what}; "
                        f"use method = {offered[0]!r}")
    if entry.free_space_only and fld.environment != "free-space":
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
    (and a derived ``stroke_mm``), except those set in the same command (``kept``)."""
    if previous == shape:
        return device
    drop = set(SHAPE_KEYS.get(previous, ())) - set(SHAPE_KEYS.get(shape, ()))
    if getattr(SHAPES.get(shape), "stroke_derived", False):
        drop |= {"stroke_mm", "gap_mm"}
    return {k: v for k, v in device.items() if k not in drop or k in kept}


def shape_mesh_features(dev) -> dict[str, float] | None:
    """The features [m] a mesh of the shape must resolve (None: the tube's rule)."""
    return shape_of(dev.shape).mesh_features(dev)


def shape_field_inputs(device_inputs: dict, shape: str, full_device: dict,
                       hash_names: dict) -> dict:
    """The ``[device]`` part of the field hash for ``shape``: a tube's exactly as before
    the shape key existed (no ``shape``, no shell keys); another shape's names it, holds
    its own keys (:data:`SHAPE_KEYS`) and drops the tube's (``hash_names``: the schema's
    ``HASH_NAMES``, a renamed key's name in the hash)."""
    out = dict(device_inputs)
    if not shape_of(shape).hash_names_shape:
        out.pop("shape", None)
        return out
    for key in _LEGACY.keys:
        out.pop(hash_names.get(("device", key), key), None)
    for key in SHAPE_KEYS[shape]:
        out[key] = full_device[key]
    return out
