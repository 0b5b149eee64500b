"""Adaptive refinement of the surrogate: which field solves, and when to stop.

Sampling: nested Chebyshev–Lobatto sets (:mod:`.sampling`), starting with
:data:`INITIAL_POSITIONS`. Each refinement solves the ``n - 1`` new positions
(the angular midpoints of the current set) first as *held-out* points: the
largest relative deviation of the current interpolant from those direct
solves (over Q_SC, C_T and V_OC, both references; :func:`held_out_error`) is
the error estimate. Refinement stops once it is below ``[field] tolerance``;
the stored surrogate then includes the held-out points, so the estimate is
conservative (it belongs to the coarser set).

Field error (``field_error="sampled"``, the default): the solver's own
error estimate (a second solve on a mesh of half the size) is dear, so it is
measured only next to both ends and at the middle of the stroke
(:func:`error_sample_positions`); every other position gets the largest of
those times ``1 + FIELD_ERROR_MARGIN`` (or its own contact extrapolation error,
if the contact rule applied there and that is larger). The margin covers the
variation of the estimate along the stroke, measured with every position
estimated: at most 5 % above the largest sampled value (default scene
2.41-2.53e-4, largest at the middle; mesh 1.5 mm, degree 1: 0.127-0.132 free
space, 0.192-0.206 grounded table, largest at z = 0.31 Δh, not sampled).
``field_error="every"`` measures it at every position (as before).
"""
from __future__ import annotations

import dataclasses
import inspect
import math
import sys
import warnings
from typing import Any, Callable

import numpy as np

from .._mpi import farm, rank_of
from .sampling import (INITIAL_POSITIONS, MAX_POSITIONS, contact_first_order, is_lobatto_count,
                       is_mirror_symmetric, lobatto_positions, mirrored, refinement_positions)
from .provenance import provenance, solver_fingerprint
from .table import SurrogateTable, held_out_error, table_from_results

SolveFunction = Callable[..., Any]
#: positions without their own field error estimate get the largest sampled one
#: times (1 + FIELD_ERROR_MARGIN) (module docstring)
FIELD_ERROR_MARGIN = 0.25
#: how the per-position field error estimate is obtained (see the module docstring)
FIELD_ERROR_MODES = ("sampled", "every")


def _default_solver() -> SolveFunction:
    from ..field import solve_position  # dolfinx/gmsh only load inside the solve
    return solve_position


def _line_angles():
    from ..field.breakdown import LINE_ANGLES_DEG   # pure numpy
    return LINE_ANGLES_DEG


def _accepts_keyword(function, name: str) -> bool:
    """True when ``function`` takes the keyword ``name`` (or any keyword)."""
    try:
        parameters = inspect.signature(function).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == name or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)


def error_sample_positions(stroke: float, symmetric: bool,
                           count: int = INITIAL_POSITIONS) -> np.ndarray:
    """Gaps [m] where the field solver's own error estimate is measured ("sampled" mode):
    the middle of the stroke and, at each end, the first position off the plate of the
    first batch of solves (the Lobatto set of ``2 count - 1``, which :func:`precompute`
    always solves). The end positions themselves are not used: a ball touching a plate is
    extrapolated from three meshes (the contact rule), each of which would need its own
    estimate solve; the position next to it is meshed as it is (on the default device at
    a gap of 0.029 mm, between the contact rule's first two anchor gaps, 0.02 and
    0.04 mm). With mirror symmetry the upper one is the image of the lower one."""
    z = lobatto_positions(stroke, 2 * count - 1)
    return np.array([z[1], z[count - 1]] + ([] if symmetric else [z[-2]]))


def _carry_field_error(result, measured: float):
    """``result`` with the field error estimate ``measured`` (the largest sampled one
    with its margin), raised to its own contact extrapolation error if the contact
    rule applied."""
    contact = float(getattr(result, "info", {}).get("contact_extrapolation_error", 0.0) or 0.0)
    info = {**getattr(result, "info", {}), "field_error": "carried over from the sampled positions"}
    return dataclasses.replace(result, relative_error_estimate=max(measured, contact), info=info)


def _sampled_field_errors(results: list, sampled: list, measured: float):
    """``(results, measured)``: the largest field error estimate of the ``sampled``
    results times ``1 + FIELD_ERROR_MARGIN`` (``measured``, once: NaN until then),
    carried over (:func:`_carry_field_error`) to the other results."""
    if math.isnan(measured):
        values = [r.relative_error_estimate for r, here in zip(results, sampled) if here]
        finite = [v for v in values if math.isfinite(v)]
        measured = (1.0 + FIELD_ERROR_MARGIN) * max(finite) if finite else math.nan
    return [r if here else _carry_field_error(r, measured)
            for r, here in zip(results, sampled)], measured


def _field_error_rule(sample_z, where: str, others: str) -> str:
    """The provenance's "field_error_rule" when sampled at the gaps ``sample_z`` [m]
    (``where``: further places sampled at, ``others``: where the largest is carried)."""
    return (f"measured at z = {', '.join(f'{z:.6g}' for z in sample_z)} m{where}; the largest "
            f"x {1.0 + FIELD_ERROR_MARGIN:g} {others}")


def accuracy_problems(table) -> list[str]:
    """What in ``table`` misses its ``[field] tolerance`` (the relative accuracy target of
    the field and the surrogate): the interpolation error estimate, the largest field
    error estimate. One line each; empty when both are within it."""
    tolerance = float(table.tolerance)
    if not math.isfinite(tolerance):
        return []
    problems = []
    if table.interpolation_error > tolerance:
        problems.append(f"surrogate: interpolation error estimate {table.interpolation_error:.3g} "
                        f"is above [field] tolerance = {tolerance:g} after {table.count} "
                        f"positions (precompute --max-positions refines further)")
    field_error = np.asarray(table.field_error, dtype=float)
    above = np.count_nonzero(field_error > tolerance)     # NaN compares False
    if above:
        problems.append(f"surrogate: field error estimate up to {np.nanmax(field_error):.3g} "
                        f"({above} of {field_error.size} positions) is above [field] tolerance "
                        f"= {tolerance:g}: lower [field] mesh_size_mm or raise degree")
    return problems


def warn_problems(problems: list[str], comm, stacklevel: int = 3) -> None:
    """Rank 0 of ``comm`` warns each line of ``problems`` (``RuntimeWarning`` pointing at
    the caller's caller): a surrogate that misses its tolerance says so whether it was
    just computed or read from the cache."""
    if rank_of(comm) == 0:
        for problem in problems:
            warnings.warn(problem, RuntimeWarning, stacklevel=stacklevel + 1)


def warn_accuracy(table, comm) -> None:
    """:func:`warn_problems` of :func:`accuracy_problems` (the 1-D surrogate)."""
    warn_problems(accuracy_problems(table), comm, stacklevel=3)


def precompute(scene, *, comm=None, solve: SolveFunction | None = None, solve_comm=None,
               initial_positions: int = INITIAL_POSITIONS, max_positions: int = MAX_POSITIONS,
               progress: bool = False, command_line: str = "",
               field_error: str = "sampled", breakdown_lines: bool | None = None
               ) -> SurrogateTable:
    """Adaptive table of field solves for ``scene`` (see the module docstring).

    ``comm`` spreads the positions of each refinement level over its ranks
    (a task farm, each solve on ``solve_comm``, by default ``COMM_SELF``);
    every rank returns the same table. ``solve(scene, position, comm=...)``
    defaults to :func:`tengfield.field.solve_position` (it is passed
    ``estimate_error=`` when it takes that keyword). When the device is
    mirror-symmetric (:func:`is_mirror_symmetric`) only the positions
    ``z <= Δh/2`` are solved and the others are their mirror images.
    ``field_error``: "sampled" or "every" (module docstring). ``breakdown_lines``: also
    sample the breakdown lines (:mod:`tengfield.field.breakdown`); None: with the default
    axisymmetric solver.
    """
    # the breakdown lines (tengfield.breakdown) come with the default axisymmetric solves
    lines = (solve is None and scene.is_axisymmetric and scene.field.method != "3d"
             if breakdown_lines is None else bool(breakdown_lines))
    if solve is None:
        solve = _default_solver()
    if solve_comm is None:
        from mpi4py import MPI
        solve_comm = MPI.COMM_SELF
    if field_error not in FIELD_ERROR_MODES:
        raise ValueError(f"field_error = {field_error!r}: choose one of {FIELD_ERROR_MODES}")
    stroke = scene.device.stroke
    tolerance = scene.field.tolerance
    count = int(initial_positions)
    if not is_lobatto_count(count):
        raise ValueError(f"initial_positions = {count}: must be 2^k + 1 >= 3")
    bar = None
    if progress and rank_of(comm) == 0:
        from tqdm import tqdm
        bar = tqdm(total=count, desc="field solves", unit="position", file=sys.stderr,
                   disable=not sys.stderr.isatty())

    symmetric = is_mirror_symmetric(scene)
    sampled = field_error == "sampled" and _accepts_keyword(solve, "estimate_error")
    sample_at = error_sample_positions(stroke, symmetric, count)

    def estimated_here(z: float) -> bool:
        return not sampled or bool(np.any(np.abs(sample_at - z) <= 1e-12 * stroke))

    extra = {"breakdown_lines": True} if lines else {}

    def work(z):
        if sampled:
            return solve(scene, float(z), comm=solve_comm, estimate_error=estimated_here(z),
                         **extra)
        return solve(scene, float(z), comm=solve_comm, **extra)

    def advance(n):
        if bar is not None:
            bar.update(min(n, bar.total - bar.n))

    measured = math.nan   # largest field error estimate at the sampled positions

    def solve_level(positions: np.ndarray) -> SurrogateTable:
        """Solve ``positions`` (with mirror symmetry: only those in the lower half)."""
        nonlocal measured
        todo = positions[positions <= 0.5 * stroke * (1 + 1e-12)] if symmetric else positions
        if bar is not None:
            bar.total += todo.size - positions.size
            bar.refresh()
        todo = todo[contact_first_order(todo, stroke, sample_at if sampled else ())]
        results = farm(comm, list(todo), work, progress=advance)
        if sampled:
            results, measured = _sampled_field_errors(
                results, [estimated_here(r.position) for r in results], measured)
        if symmetric:
            results += [mirrored(r, stroke) for r in results
                        if not math.isclose(r.position, 0.5 * stroke, rel_tol=1e-12)]
        return table_from_results(results, stroke=stroke)

    # the first refinement is always needed: solve it with the initial set in one
    # batch (better balance over the ranks), then split coarse / held-out
    initial = lobatto_positions(stroke, count)
    new = refinement_positions(stroke, count)
    if bar is not None:
        bar.total += new.size
    both = solve_level(np.concatenate([initial, new]))
    table, held_out = both.subset(np.isin(both.positions, initial)), \
        both.subset(np.isin(both.positions, new))
    history: list[tuple[int, float]] = []
    while True:
        estimate = held_out_error(table, held_out)
        history.append((count, estimate))
        table = table.merged(held_out)
        count = 2 * count - 1
        if estimate <= tolerance or 2 * count - 1 > max_positions:
            break
        new = refinement_positions(stroke, count)
        if bar is not None:
            bar.total += new.size
            bar.refresh()
        held_out = solve_level(new)
    if bar is not None:
        bar.n = bar.total
        bar.close()
    rule = (_field_error_rule(sample_at, "", "at the other positions") if sampled
            else "measured at every position")
    table = dataclasses.replace(
        table, interpolation_error=estimate, tolerance=tolerance,
        converged=bool(estimate <= tolerance), error_history=history,
        field_hash=scene.field_hash(),
        provenance={**provenance(scene, command_line), "mirror_symmetry": symmetric,
                    **({"breakdown_line_angles_deg": list(_line_angles())} if lines else {}),
                    "field_error_rule": rule, "solver_fingerprint": solver_fingerprint()})
    warn_accuracy(table, comm)
    return table
