"""Electrostatics of the BB-TENG at one ball position (dolfinx + gmsh).

Public entry points: :func:`solve_position` returns a
:class:`~tengfield.field.result.PositionResult` (capacitance matrix, induced
charges, error estimate; with ``keep_solution=True`` also ``.solution``, a
:class:`~tengfield.field.result.FieldSolution` with the mesh and potentials),
see that module for the sign conventions; :func:`open_circuit` gives the
open-circuit potentials of a position. Files: :mod:`tengfield.field.io`;
figures: :mod:`tengfield.field.plot`. dolfinx, petsc4py and ufl are imported
only by :mod:`tengfield.field._dolfinx` (the one file that knows their version).

Importing this package loads neither dolfinx nor gmsh: the solvers are
imported lazily, when a solve is asked for.

Example::

    from mpi4py import MPI
    from tengfield.scene import default_scene
    from tengfield.field import solve_position
    res = solve_position(default_scene(), 1.5e-3, comm=MPI.COMM_SELF)
    res.capacitance, res.induced_charge, res.terminal_capacitance("floating")
    open_circuit(default_scene(), 1.5e-3, comm=MPI.COMM_SELF).V_oc
"""
from __future__ import annotations

import math

from pathlib import Path

from ..errors import FieldError, show_number
from .result import FieldSolution, PositionResult

__all__ = ["PositionResult", "FieldSolution", "solve_position", "open_circuit",
           "resolve_method", "check_position", "SOLVER_SOURCES", "solver_source_paths"]

#: The files of this package whose code decides the field numbers (C, q, error
#: estimates). A cache of solves (the surrogate) should fingerprint these and
#: only these: io.py, plot.py, potential.py and result.py write, draw or
#: post-process and may change without invalidating stored solves.
SOLVER_SOURCES = ("__init__.py", "_dolfinx.py", "axisymmetric.py", "breakdown.py", "contact.py",
                  "geometry3d.py", "geometry_axisymmetric.py", "moving.py", "moving3d.py",
                  "solver3d.py",
                  "cells/__init__.py", "cells/_methods.py", "cells/hexagonal.py",
                  "cells/plate_model3d.py",
                  "cells/shell_model.py",
                  "cells/shell_model3d.py", "cells/solve.py",
                  "cells/spherical_shell.py", "cells/tube.py")


def solver_source_paths() -> list[Path]:
    """Absolute paths of :data:`SOLVER_SOURCES`, in that (sorted) order."""
    here = Path(__file__).resolve().parent
    return [here / name for name in SOLVER_SOURCES]


def open_circuit(scene, position: float, *, comm, **kwargs):
    """Open-circuit potentials of one position: see
    :func:`tengfield.field.potential.open_circuit` (returns an ``OpenCircuit``
    with ``potentials`` = [V_lower, V_upper] [V] and ``V_oc``)."""
    from .potential import open_circuit as _open_circuit
    return _open_circuit(scene, position, comm=comm, **kwargs)

#: ``[field]`` scene keys (file-level names) that :func:`solve_position` accepts
#: as keyword overrides, e.g. ``mesh_size_mm=0.3, degree=1, far_field="robin"``.
FIELD_OVERRIDES = ("degree", "mesh_size_mm", "tolerance", "domain_radius_mm", "environment",
                   "far_field")


def check_position(scene, position: float) -> None:
    """Raise :class:`FieldError` unless ``0 <= position <= Δh`` (the free stroke)."""
    stroke = scene.device.stroke
    try:
        value = float(position)
    except (TypeError, ValueError):
        raise FieldError(f"position_mm = {position!r}: expected a number") from None
    if not math.isfinite(value) or value < 0.0 or value > stroke * (1.0 + 1e-12):
        raise FieldError(f"position_mm = {show_number(value * 1e3, 0.0, stroke * 1e3)} is out "
                         "of range: allowed "
                         f"[0, {stroke * 1e3:g}] mm (the free stroke, [device] stroke_mm)")


def resolve_method(scene, method: str | None = None, offset: float = 0.0) -> str:
    """"axisymmetric" or "3d": ``None`` takes ``[field] method``; "auto" picks
    the axisymmetric solver whenever the ball is on the axis (``offset == 0``) of an
    axisymmetric cell, 3D otherwise (``shape = "hexagonal"``: a 3D cell)."""
    from ..scene.shapes import methods, shape_of

    method = scene.field.method if method is None else method
    if method == methods.AUTO:   # kept: "auto" is the one name that is not a method
        return methods.resolve(shape_of(scene.device.shape).field_methods, method, offset)
    if method not in methods.FIELD_METHODS:
        raise FieldError(f"method = {method!r} is not allowed: choose one of "
                         + ", ".join(map(repr, (methods.AUTO, *methods.FIELD_METHODS))))
    if not methods.takes(method, offset):
        raise FieldError(f"method = {method!r} needs offset_mm = 0 (got {offset * 1e3:g}); "
                         "use method = '3d' or 'auto' for an off-axis ball")
    return method


def mapping_group(scene):
    """A hashable key shared by the scenes whose (r, z) reference meshes are mapped from
    the same canonical geometry (:mod:`tengfield.field.moving`: a process meshes that
    geometry's templates once and maps every such scene from them), or None (no
    canonical geometry: the hexagonal cell, an impossible one). Pure: no dolfinx, no
    gmsh. The design search keeps the candidates of one group in one process
    (:func:`tengfield.design_study.search.bundles`): the numbers do not depend on it."""
    from ..errors import TengfieldError
    from .cells import cell_of

    try:
        canonical = cell_of(scene).canonical()
    except (TengfieldError, ValueError):
        return None
    if canonical is None:
        return None
    return (scene.device.shape, repr(getattr(canonical, "device", canonical)))


def solve_position(scene, position: float, *, comm, offset: float | None = None,
                   method: str | None = None, **overrides) -> PositionResult:
    """Capacitance matrix and induced charges with the ball at gap ``position`` [m].

    Parameters
    ----------
    scene:
        A validated :class:`tengfield.scene.Scene`.
    position:
        z [m], gap between the ball's bottom and the lower electrode, in [0, Δh].
    comm:
        MPI communicator of the solve (``MPI.COMM_SELF`` for one serial solve).
    offset:
        Lateral ball offset [m]; ``None`` takes ``[field] ball_offset_mm``.
    method:
        "auto", "axisymmetric" or "3d"; ``None`` takes ``[field] method``.
    overrides:
        ``[field]`` keys in file units (``degree``, ``mesh_size_mm``,
        ``domain_radius_mm``, ``far_field``, ``environment``, ``tolerance``),
        validated like the scene file; any other keyword goes to the
        solver (both: ``estimate_error``, ``keep_solution`` (result.solution);
        axisymmetric also ``source_solve``, ``linear_solver``).
    """
    from .._args import number
    from ..scene.parse import check_scene_argument
    check_scene_argument("tengfield.solve_position", scene)
    position = number("tengfield.solve_position", position, "position")   # [m]; its range below
    offset = number("tengfield.solve_position", offset, "offset", allow_none=True)
    field_values = {k: overrides.pop(k) for k in list(overrides) if k in FIELD_OVERRIDES}
    if offset is not None:
        field_values["ball_offset_mm"] = offset * 1e3
    if field_values:
        scene = scene.with_values(field=field_values)
    offset = scene.field.ball_offset
    check_position(scene, position)
    chosen = resolve_method(scene, method, offset)
    from .cost import check_memory, check_tolerance, solve_cost   # before any meshing (#40)
    try:
        estimate = solve_cost(scene, method=chosen, position=position,
                              estimate_error=overrides.get("estimate_error", True))
    except FieldError:   # a geometry the estimate cannot lay out: the cell's solver says why
        estimate = None
    if estimate is not None:
        check_memory(scene, estimate)
        check_tolerance(scene, estimate)   # a 3D tolerance out of reach (issue #55)
    from .cells import cell_of   # the cell's own solver (field/cells: CELLS)
    result = cell_of(scene).solve_scene(scene, position, comm=comm, method=chosen,
                                        offset=offset, **overrides)
    result.scene = scene
    return result
