"""``[field] method`` -> a cell's solver: each cell class's ``field_models`` table (the
names of its shape's ``field_methods``, :mod:`tengfield.scene.shapes`), looked up
through :func:`tengfield._registry.lookup` like every other registry."""
from __future__ import annotations

from ..._registry import lookup


def solve_with(cell, scene, position: float, *, comm, method: str, offset: float, **options):
    """``cell``'s solver of ``method`` ("axisymmetric", "3d"; resolved) at gap ``position``
    [m], lateral ``offset`` [m]; a method the shape does not offer is a SceneError
    naming the ones it has."""
    model = lookup(type(cell).field_models, method, f"[field] method (shape = {cell.name!r})")
    return model(cell, scene, position, comm=comm, offset=offset, **options)
