"""What a field solve costs, known before any meshing (issue #40): dofs, memory, time.

The estimate comes from the mesh rule itself (the size fields of
:mod:`.geometry_axisymmetric` and :mod:`.cells.shell_model`, integrated in closed
form: :func:`~tengfield.field.geometry_axisymmetric.estimated_cells`) for the
axisymmetric solver, and from a fit to measured 3D meshes for the 3D solver; memory
and time are per-dof rates measured on this project's machine (docs/field.md, "The
cost before the work"). They are rough (a factor ~2) and are said so; they exist so
that a run that cannot fit is refused in one line before it starts, and a long one
says how long before it starts.

``[field] max_memory_gb`` bounds the estimated peak of one solve (its error-estimate
mesh included); 0 (the default) means 80 % of the machine's memory.

Importing this module loads neither dolfinx nor gmsh.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import FieldError
from ..scene.shapes.methods import field_method

#: the process before its first mesh: Python, dolfinx, PETSc, gmsh (measured 0.25-0.30 GB)
BASE_MEMORY_BYTES = 0.25e9
#: peak bytes per dof of an axisymmetric solve (mesh, P2 space, MUMPS LDLᵀ factors, gmsh's
#: own mesh): 1.05 GB for the thin shell's 72k + 290k dofs (its error-estimate mesh)
BYTES_PER_DOF_2D = 2.2e3
#: ... of a 3D solve (CG + BoomerAMG): 0.46 GB for the tube's 172k + 33k dofs (1 mm)
BYTES_PER_DOF_3D = 1.3e3
#: wall seconds per dof, meshing included (quiet machine; a loaded one: 2-3 x):
#: the default tube's 13k + 50k dofs in 0.8 s; the 3D tube's 172k + 33k dofs in ~50 s
SECONDS_PER_DOF_2D = 1.5e-5
SECONDS_PER_DOF_3D = 2.5e-4
#: 3D dofs of the paper's tube (P2) at mesh size 2 mm, and how they grow as the size
#: falls (measured: 32.5k at 2 mm, 172k at 1 mm, 1.11M at 0.5 mm: exponent 2.4-2.7)
DOFS_3D_REFERENCE = 32.5e3
MESH_SIZE_3D_REFERENCE = 2.0e-3
DOFS_3D_EXPONENT = 2.55
#: the dofs of a ``[field] mesh_grading = "graded"`` 3D mesh against the uniform one of
#: the same size (the tube, P2: 0.49 at 0.5 mm, 0.54 at 0.7 mm, 0.60 at 1.0 mm;
#: docs/field3d.md), for the shapes that grade their 3D meshes (``grades_3d``)
GRADED_DOFS_SHARE = 0.49
#: the paper's tube seen from its centre [m] (the 3D fit's device size)
BOUNDING_RADIUS_REFERENCE = 8.9e-3
#: share of the machine's memory that ``max_memory_gb = 0`` allows
MACHINE_SHARE = 0.8


@dataclass(frozen=True)
class SolveCost:
    """Estimated cost of one field solve: ``dofs`` of its mesh, ``check_dofs`` of its
    error-estimate mesh (0 without), ``memory_bytes`` peak, ``seconds`` wall."""
    method: str
    dofs: float
    check_dofs: float
    memory_bytes: float
    seconds: float

    @property
    def memory_gb(self) -> float:
        return self.memory_bytes / 1e9


def machine_memory_bytes() -> float:
    """Physical memory of this machine [bytes] (``os.sysconf``; 8 GB when it cannot say)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        return 8e9


def memory_limit_bytes(scene) -> float:
    """``[field] max_memory_gb`` in bytes; 0: :data:`MACHINE_SHARE` of the machine."""
    limit = float(getattr(scene.field, "max_memory_gb", 0.0) or 0.0)
    return limit * 1e9 if limit > 0 else MACHINE_SHARE * machine_memory_bytes()


def _axisymmetric_dofs(scene, position: float, mesh_size: float, grading_size=None) -> float:
    from .cells import cell_of

    degree = scene.field.degree
    cells = cell_of(scene).estimated_axisymmetric_cells(scene, position, mesh_size,
                                                        grading_size)
    return cells * (0.5 + (1.5 if degree >= 2 else 0.0))


def _dofs_3d(scene, mesh_size: float, degree: int) -> float:
    from ..scene.shapes import shape_of

    radius = max(float(scene.device.bounding_radius), 1e-9)
    scale = radius / BOUNDING_RADIUS_REFERENCE
    dofs = DOFS_3D_REFERENCE * (MESH_SIZE_3D_REFERENCE * scale / mesh_size) ** DOFS_3D_EXPONENT
    if scene.field.mesh_grading == "graded" and getattr(shape_of(scene.device.shape),
                                                         "grades_3d", False):
        dofs *= GRADED_DOFS_SHARE
    return dofs if degree >= 2 else dofs / 7.5


def solve_cost(scene, *, method: str = "axisymmetric", position: float | None = None,
               estimate_error: bool = True, mesh_size: float | None = None,
               degree: int | None = None) -> SolveCost:
    """Estimated :class:`SolveCost` of one solve of ``scene`` with the ball at gap
    ``position`` [m] (default: the smallest meshed gap, the dearest solve), before any
    meshing. ``mesh_size`` [m] and ``degree`` default to the scene's (3D: the (z, r)
    table passes its own)."""
    from .geometry_axisymmetric import base_mesh_size

    size = base_mesh_size(scene) if mesh_size is None else float(mesh_size)
    degree = scene.field.degree if degree is None else int(degree)
    if field_method(method).dimension == 3:
        dofs = _dofs_3d(scene, size, degree)
        check = _dofs_3d(scene, 2.0 * size, degree) if estimate_error else 0.0
        per_dof, rate = BYTES_PER_DOF_3D, SECONDS_PER_DOF_3D
    else:
        if position is None:   # the layouts clamp it to the smallest meshed gap
            position = 0.0
        dofs = _axisymmetric_dofs(scene, position, size)
        check = _axisymmetric_dofs(scene, position, 0.5 * size, grading_size=size) \
            if estimate_error else 0.0
        per_dof, rate = BYTES_PER_DOF_2D, SECONDS_PER_DOF_2D
    return SolveCost(method, dofs, check, BASE_MEMORY_BYTES + per_dof * (dofs + check),
                     rate * (dofs + check))


def check_memory(scene, cost: SolveCost) -> None:
    """Raise :class:`FieldError` (one line naming ``[field] max_memory_gb``) when the
    estimated peak of ``cost`` exceeds the scene's limit."""
    limit = memory_limit_bytes(scene)
    if cost.memory_bytes <= limit:
        return
    written = float(getattr(scene.field, "max_memory_gb", 0.0) or 0.0)
    how = (f"{written:g}" if written > 0 else
           f"0 (= {MACHINE_SHARE:.0%} of this machine's {machine_memory_bytes() / 1e9:.3g} GB)")
    raise FieldError(
        f"[field] max_memory_gb = {how}: one {cost.method} field solve of this scene needs "
        f"about {cost.memory_gb:.3g} GB ({cost.dofs:.3g} dofs"
        + (f" + {cost.check_dofs:.3g} for its error estimate" if cost.check_dofs else "")
        + f"): allowed <= {limit / 1e9:.3g} GB; raise max_memory_gb or mesh_size_mm")


def expected_error_3d(scene, dofs: float, grading: str | None = None) -> float | None:
    """The relative error [-] a P2 3D solve of ``dofs`` dofs of this scene's shape is
    expected to reach with ``grading`` (default ``[field] mesh_grading``): the shape's
    measured error against dofs (``error_3d``), None where it has none or the degree is
    not 2. Rough (one device, one position), and said so."""
    from ..scene.shapes import shape_of

    table = getattr(shape_of(scene.device.shape), "error_3d", None)
    grading = scene.field.mesh_grading if grading is None else grading
    if not table or grading not in table or scene.field.degree != 2 or dofs <= 0:
        return None
    error, reference, rate = table[grading]
    return error * (dofs / reference) ** -rate


def dofs_for_error_3d(scene, error: float, grading: str | None = None) -> float | None:
    """The dofs of a P2 3D solve expected to reach the relative ``error`` (the inverse of
    :func:`expected_error_3d`), or None."""
    from ..scene.shapes import shape_of

    table = getattr(shape_of(scene.device.shape), "error_3d", None)
    grading = scene.field.mesh_grading if grading is None else grading
    if not table or grading not in table or scene.field.degree != 2 or error <= 0:
        return None
    measured, reference, rate = table[grading]
    return reference * (measured / error) ** (1.0 / rate)


def _memory_of(dofs: float) -> float:
    """The peak bytes of a 3D solve of ``dofs`` with its twice-coarser estimate mesh."""
    check = dofs * 2.0 ** -DOFS_3D_EXPONENT
    return BASE_MEMORY_BYTES + BYTES_PER_DOF_3D * (dofs + check)


def tolerance_problem(scene, cost: SolveCost) -> str | None:
    """One line when a 3D solve of ``scene`` is not expected to reach ``[field]
    tolerance`` within ``[field] max_memory_gb`` (the shape's measured error against dofs,
    :func:`expected_error_3d`), naming what it is expected to reach, what reaching the
    tolerance needs and, where the other grading would fit, that; None otherwise (an
    axisymmetric solve, a shape or degree without a measurement, a tolerance in reach)."""
    if field_method(cost.method).dimension != 3:
        return None
    tolerance = float(scene.field.tolerance)
    expected = expected_error_3d(scene, cost.dofs)
    needed = dofs_for_error_3d(scene, tolerance)
    if expected is None or needed is None or expected <= tolerance:
        return None
    limit = memory_limit_bytes(scene)
    if _memory_of(needed) <= limit:
        return None
    grading = scene.field.mesh_grading
    line = (f"[field] tolerance = {tolerance:g}: a 3D solve of this scene is expected to "
            f"end near {expected:.2g} ({_count(cost.dofs)} dofs, mesh_grading = {grading!r}; "
            f"the measured error against dofs, docs/field3d.md); reaching {tolerance:g} "
            f"needs ~{_count(needed)} dofs, ~{_memory_of(needed) / 1e9:.2g} GB, more than "
            f"[field] max_memory_gb allows ({limit / 1e9:.3g} GB)")
    for other in ("graded", "uniform"):
        if other == grading:
            continue
        need = dofs_for_error_3d(scene, tolerance, other)
        if need is not None and _memory_of(need) <= limit:
            line += (f"; mesh_grading = {other!r} is expected to reach it with "
                     f"~{_count(need)} dofs, ~{_memory_of(need) / 1e9:.2g} GB")
    return line


def check_tolerance(scene, cost: SolveCost) -> None:
    """Warn (one line, before the work) when :func:`tolerance_problem` has one."""
    problem = tolerance_problem(scene, cost)
    if problem is not None:
        import warnings
        warnings.warn(problem, stacklevel=3)     # the caller of solve_position


def describe(cost: SolveCost, solves: int, *, what: str = "field solves",
             ranks: int = 1) -> str:
    """One line: ``field: N solves, ~D dofs each (+ its error estimate), ~M GB, ~T s each,
    ~W s in all on R ranks (estimated before meshing)``."""
    total = cost.seconds * solves / max(ranks, 1)
    check = f" (+{_count(cost.check_dofs)} for the error estimate)" if cost.check_dofs else ""
    return (f"{what}: {solves}, ~{_count(cost.dofs)} dofs each{check}, ~{cost.memory_gb:.2g} GB "
            f"and ~{_seconds(cost.seconds)} per solve, ~{_seconds(total)} in all"
            + (f" on {ranks} ranks" if ranks > 1 else "") + " (estimated before meshing)")


def _count(n: float) -> str:
    if n >= 1e6:
        return f"{n / 1e6:.2g}M"
    if n >= 1e4:
        return f"{n / 1e3:.0f}k"
    return f"{n / 1e3:.2g}k" if n >= 1e3 else f"{n:.0f}"


def _seconds(s: float) -> str:
    return f"{s / 60:.2g} min" if s >= 120 else f"{s:.2g} s"
