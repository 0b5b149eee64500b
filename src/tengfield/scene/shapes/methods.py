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
    #: the mesh's dimension: 2 (the (r, z) half-plane) or 3 (the volume)
    dimension: int
    #: small enough to solve (and draw) on one rank, the outcome shared
    #: (``tengfield field``); else collective over the communicator
    serial: bool
    #: its solve samples the breakdown gap lines (tengfield.field.breakdown): the ball's
    #: charge limit and band (``[device] σ = "breakdown"``, ``tengfield breakdown``)
    gap_lines: bool = False


#: ``[field] method`` -> its entry (the scene file's names)
FIELD_METHODS = {"axisymmetric": FieldMethod("axisymmetric", on_axis_only=True, dimension=2,
                                             serial=True, gap_lines=True),
                 "3d": FieldMethod("3d", on_axis_only=False, dimension=3, serial=False)}

AUTO = "auto"


def field_method(method: str) -> FieldMethod:
    """The entry of a resolved ``method`` (not "auto"); ``SceneError`` naming the
    allowed ones."""
    return lookup(FIELD_METHODS, method, "[field] method")


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
