"""``[field] method``: the field methods a shape can offer, and what each needs.

The table a shape's ``field_methods`` names its entries from (the shape module says
which ones it has; the field layer, :mod:`tengfield.field.cells`, holds the solvers of
each shape's methods under the same names). ``"auto"`` is not a method: it resolves to
the first of the shape's methods that takes the ball's offset (:func:`resolve`).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..._registry import lookup


@dataclass(frozen=True)
class FieldMethod:
    """One ``[field] method``."""

    name: str
    #: only a ball on the axis (offset 0): the (r, z) half-plane's solve
    on_axis_only: bool


#: ``[field] method`` -> its entry (the scene file's names)
FIELD_METHODS = {"axisymmetric": FieldMethod("axisymmetric", on_axis_only=True),
                 "3d": FieldMethod("3d", on_axis_only=False)}

AUTO = "auto"


def takes(method: str, offset: float) -> bool:
    """Whether ``method`` solves a ball at ``offset`` [m] from the axis."""
    return offset == 0.0 or not FIELD_METHODS[method].on_axis_only


def resolve(offered: tuple, method: str, offset: float = 0.0) -> str:
    """``method`` of a shape offering ``offered`` (its ``field_methods``, in order of
    preference) for a ball at ``offset`` [m]: ``"auto"`` -> the first that takes the
    offset; a named one is looked up (``SceneError`` naming the allowed ones)."""
    if method == AUTO:   # kept: "auto" is the one name that is not a method
        return next(m for m in offered if takes(m, offset))
    return lookup({m: m for m in offered}, method, "[field] method")
