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
import warnings
from typing import Any, Callable

import numpy as np

from .. import terminals
from .._mpi import farm, rank_of, size_of
from ..errors import FieldError
from .provenance import provenance, radial_hash, solver_fingerprint
from .sampling import (DEFAULT_DEGREE, DEFAULT_MESH_SIZE_MM, DEFAULT_TOLERANCE, INITIAL_OFFSETS,
                       INITIAL_POSITIONS, MAX_OFFSETS, MAX_POSITIONS, MAX_POSITIONS_ZR,
                       contact_first_order, grid_key, is_lobatto_count, is_mirror_symmetric,
                       lobatto_positions, max_offset, mirrored, offset_coordinate,
                       offset_positions, offset_refinement, physical_offset,
                       refinement_positions)
from .table import (RadialTable, RadialTerminalCurves, SurrogateError, SurrogateTable,
                    TerminalCurves, UNIT_CHARGE, table_from_grid, table_from_results,
                    terminal_grid, terminal_samples)

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


def _announce(scene, solves: int, comm, *, method, what: str, mesh_size=None,
              degree=None) -> None:
    """One line on stderr (a terminal only, :func:`tengfield._console.progress_shown`):
    how many solves and what each costs, estimated before meshing
    (:mod:`tengfield.field.cost`); a scene past ``[field] max_memory_gb`` is refused
    by the solve itself."""
    import sys

    from .._console import progress_shown
    if not progress_shown(True):
        return
    try:
        from ..field import cost, resolve_method
        chosen = method or resolve_method(scene)
        estimate = cost.solve_cost(scene, method=chosen, mesh_size=mesh_size, degree=degree,
                                   position=0.5 * scene.device.stroke)
    except Exception:  # noqa: BLE001 - an estimate never stops the work; the solve says why
        return
    print(f"tengfield: {cost.describe(estimate, solves, what=what, ranks=size_of(comm))}",
          file=sys.stderr, flush=True)


def check_tabulated_offset(scene) -> None:
    """A table of the whole stroke at ``[field] ball_offset_mm``: a cell that cannot hold
    that offset at every height (the spherical shell: only the axis at the ends of its
    stroke) refuses it here, before any solve (its ``check_tabulated_offset``, a
    :class:`~tengfield.field.cells.Cell` hook, raises :class:`FieldError`)."""
    offset = scene.field.ball_offset
    if offset == 0.0:
        return
    from ..field.cells import cell_of
    cell_of(scene).check_tabulated_offset(offset)


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
    # the breakdown lines (tengfield.air_breakdown) come with the default axisymmetric solves
    lines = (solve is None and scene.has_gap_lines
             if breakdown_lines is None else bool(breakdown_lines))
    if solve is None:
        solve = _default_solver()
    if solve_comm is None:
        from mpi4py import MPI
        solve_comm = MPI.COMM_SELF
    if field_error not in FIELD_ERROR_MODES:
        raise ValueError(f"field_error = {field_error!r}: choose one of {FIELD_ERROR_MODES}")
    check_tabulated_offset(scene)
    stroke = scene.device.stroke
    tolerance = scene.field.tolerance
    count = int(initial_positions)
    if not is_lobatto_count(count):
        raise ValueError(f"initial_positions = {count}: must be 2^k + 1 >= 3")
    symmetric = is_mirror_symmetric(scene)
    bar = None
    if progress and rank_of(comm) == 0:
        first = 2 * count - 1   # the cost before the work (issue #40), on a terminal
        _announce(scene, (first + 1) // 2 if symmetric else first, comm, method=None,
                  what=f"field solves (at least; {first} positions"
                       + (", mirror symmetry)" if symmetric else ")"))
        from .._console import progress_bar
        bar = progress_bar(count, "field solves", unit="position")

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
    placed = {"moved": 0, "meshed": 0}   # how the solves' meshes were placed (#40)

    def solve_level(positions: np.ndarray) -> SurrogateTable:
        """Solve ``positions`` (with mirror symmetry: only those in the lower half)."""
        nonlocal measured
        todo = positions[positions <= 0.5 * stroke * (1 + 1e-12)] if symmetric else positions
        if bar is not None:
            bar.total += todo.size - positions.size
            bar.refresh()
        todo = todo[contact_first_order(todo, stroke, sample_at if sampled else ())]
        results = farm(comm, list(todo), work, progress=advance)
        for r in results:
            for key, count in (getattr(r, "info", None) or {}).get("mesh_placements", {}).items():
                placed[key] = placed.get(key, 0) + int(count)
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
    if getattr(scene.field, "mesh_motion", "remesh") == "move":   # the table is done:
        from ..field import moving, moving3d   # its reference meshes and solvers are freed
        moving.release_references()
        moving3d.release_references()   # a 3D table (the honeycomb's)
    rule = (_field_error_rule(sample_at, "", "at the other positions") if sampled
            else "measured at every position")
    table = dataclasses.replace(
        table, interpolation_error=estimate, tolerance=tolerance,
        converged=bool(estimate <= tolerance), error_history=history,
        field_hash=scene.field_hash(),
        provenance={**provenance(scene, command_line), "mirror_symmetry": symmetric,
                    **({"breakdown_line_angles_deg": list(_line_angles())} if lines else {}),
                    "field_error_rule": rule, "solver_fingerprint": solver_fingerprint(),
                    **({"mesh_placements": placed} if sum(placed.values()) else {})},
        scene=scene)
    warn_accuracy(table, comm)
    return table


# ---------------------------------------------------------------------------
# accuracy: the held-out error estimates and the check on the axis
def held_out_error(coarse: SurrogateTable, held_out: SurrogateTable) -> float:
    """Largest relative deviation of ``coarse``'s interpolants from direct solves.

    Over both references and the quantities Q_SC, C_T and V_OC, each relative
    to its largest magnitude on the union of both position sets.
    """
    union = coarse.merged(held_out)
    worst = 0.0
    for reference in terminals.REFERENCES:
        curves = TerminalCurves(coarse, reference, UNIT_CHARGE)   # relative: any charge
        q_all, c_all = terminal_samples(union, reference, UNIT_CHARGE)
        inside = np.isin(union.positions, held_out.positions)
        z = union.positions[inside]
        q_direct, c_direct = q_all[inside], c_all[inside]
        v_all = q_all / c_all
        pairs = [(curves.charge(z), q_direct, np.max(np.abs(q_all))),
                 (curves.capacitance(z), c_direct, np.max(np.abs(c_all))),
                 (curves.voltage(z), q_direct / c_direct, np.max(np.abs(v_all)))]
        for interpolated, direct, scale in pairs:
            if scale > 0.0:
                worst = max(worst, float(np.max(np.abs(interpolated - direct)) / scale))
    return worst


def held_out_error_zr(coarse: RadialTable, fine: RadialTable) -> tuple[float, float, float]:
    """``(all, along_z, along_r)``: largest relative deviation of ``coarse``'s
    interpolant from the direct solves at the points of ``fine`` not in ``coarse``
    (all of them; those whose offset is a coarse one; those whose gap is a coarse
    one). Over Q_SC, C_T, V_OC and both references, each relative to its largest
    magnitude on ``fine``; NaN where a group is empty."""
    zz, rr = np.meshgrid(fine.positions, fine.offsets, indexing="ij")
    old_z = np.isin(np.round(fine.positions * 1e13), np.round(coarse.positions * 1e13))
    old_r = np.isin(np.round(fine.offsets * 1e13), np.round(coarse.offsets * 1e13))
    old_z, old_r = np.meshgrid(old_z, old_r, indexing="ij")
    held = ~(old_z & old_r)
    groups = {"all": held, "z": held & old_r, "r": held & old_z}
    worst = {name: (0.0 if np.any(mask) else math.nan) for name, mask in groups.items()}
    for reference in terminals.REFERENCES:
        curves = RadialTerminalCurves(coarse, reference, UNIT_CHARGE)   # relative: any charge
        q_fine, c_fine = terminal_grid(fine, reference, UNIT_CHARGE)
        v_fine = q_fine / c_fine
        q_coarse, c_coarse = curves.grid_values(zz, rr)
        deviations = [(q_coarse, q_fine), (c_coarse, c_fine),
                      (terminals.open_circuit_voltage(q_coarse, c_coarse), v_fine)]
        for interpolated, direct in deviations:
            scale = float(np.max(np.abs(direct)))
            if scale <= 0.0:
                continue
            relative = np.abs(interpolated - direct) / scale
            for name, mask in groups.items():
                if np.any(mask):
                    worst[name] = max(worst[name], float(np.max(relative[mask])))
    return worst["all"], worst["z"], worst["r"]


def axis_check(table: RadialTable, axis_table: SurrogateTable) -> dict:
    """Compare the r = 0 column of ``table`` with the axisymmetric surrogate ``axis_table``.

    Returns ``deviation``: the largest relative difference of Q_SC and C_T
    (both references, each relative to its largest magnitude) at the (z, r)
    table's gaps, and ``allowed``: the sum of both tables' largest field error
    estimates and the axisymmetric interpolation error; ``ok`` = deviation <= allowed.
    """
    z = table.positions
    deviation = 0.0
    for reference in terminals.REFERENCES:
        q_grid, c_grid = terminal_grid(table, reference, UNIT_CHARGE)
        axis = TerminalCurves(axis_table, reference, UNIT_CHARGE)
        for ours, theirs in ((q_grid[:, 0], axis.charge(z)), (c_grid[:, 0], axis.capacitance(z))):
            scale = float(np.max(np.abs(theirs)))
            if scale > 0.0:
                deviation = max(deviation, float(np.max(np.abs(ours - theirs)) / scale))
    axis_interp = axis_table.interpolation_error
    allowed = float(np.nanmax(table.field_error[:, 0])) + float(np.nanmax(axis_table.field_error)) \
        + (float(axis_interp) if math.isfinite(axis_interp) else 0.0)
    return {"deviation": deviation, "allowed": allowed, "ok": deviation <= allowed}


# ---------------------------------------------------------------------------
# the (z, r) surrogate: an off-axis ball (issue #13, DESIGN §8 "Field over (z, r)")
def precompute_radial(scene, *, comm=None, solve=None, solve_comm=None,
                      mesh_size_mm: float = DEFAULT_MESH_SIZE_MM, degree: int = DEFAULT_DEGREE,
                      tolerance: float = DEFAULT_TOLERANCE,
                      initial_positions: int = INITIAL_POSITIONS,
                      initial_offsets: int = INITIAL_OFFSETS,
                      max_positions: int = MAX_POSITIONS_ZR, max_offsets: int = MAX_OFFSETS,
                      progress: bool = False, command_line: str = "",
                      field_error: str = "sampled") -> RadialTable:
    """Adaptive (z, r) table of 3D field solves for ``scene`` (module docstring).

    ``solve(scene, z, comm=..., offset=r, method="3d", mesh_size_mm=..., degree=...)``
    defaults to :func:`tengfield.field.solve_position` (given ``estimate_error=``
    when it takes it). ``comm`` spreads each round over its ranks (task farm,
    each solve on ``solve_comm``, default ``COMM_SELF``); every rank returns
    the same table. ``field_error``: "sampled" (the solver's own estimate at
    the middle and next to the ends of the stroke, on the axis and at the wall;
    the largest x (1 + FIELD_ERROR_MARGIN) elsewhere) or "every".
    """
    if solve is None:
        if scene.field.environment != "free-space":   # before any solve, on every rank
            raise FieldError(f"[field] environment = {scene.field.environment!r} is not "
                             "supported by the 3D solver of the (z, r) surrogate: allowed "
                             "'free-space'")
        solve = _default_solver()
    if solve_comm is None:
        from mpi4py import MPI
        solve_comm = MPI.COMM_SELF
    if field_error not in FIELD_ERROR_MODES:
        raise ValueError(f"field_error = {field_error!r}: choose one of {FIELD_ERROR_MODES}")
    nz, nr = int(initial_positions), int(initial_offsets)
    if not is_lobatto_count(nz):
        raise ValueError(f"initial_positions = {nz}: must be 2^k + 1 >= 3")
    if not (nr == 2 or is_lobatto_count(nr)):
        raise ValueError(f"initial_offsets = {nr}: must be 2 or 2^k + 1")
    if not (math.isfinite(tolerance) and tolerance > 0.0):
        raise ValueError(f"tolerance = {tolerance!r}: must be > 0")
    stroke = scene.device.stroke
    largest = max_offset(scene.device)
    coordinate = offset_coordinate(scene.device)
    if not largest > 0.0:
        raise SurrogateError(f"the ball fills the tube (tube inner radius - ball radius = "
                             f"{largest * 1e3:g} mm): no radial offset to tabulate")

    def offset_of(z: float, u: float) -> float:
        """The ball's offset [m] at grid point (z, u): u itself, or scaled to r_max(z)."""
        if coordinate == "scaled":
            return float(physical_offset(z, u, stroke, largest))
        return float(u)
    symmetric = is_mirror_symmetric(scene)
    sampled = field_error == "sampled" and _accepts_keyword(solve, "estimate_error")
    sample_z = error_sample_positions(stroke, symmetric, nz)
    sample_keys = {grid_key(z, r) for z in sample_z for r in (0.0, largest)}
    bar = None
    if progress and rank_of(comm) == 0:
        first = (2 * nz - 1) * (2 * nr - 1 if nr > 2 else 3)
        _announce(scene, (first + 1) // 2 if symmetric else first, comm, method="3d",
                  what=f"3D field solves (z, r) (at least; mesh_size_mm = {mesh_size_mm:g}, "
                       f"degree = {degree})", mesh_size=mesh_size_mm * 1e-3, degree=degree)
        from .._console import progress_bar
        bar = progress_bar(0, "3D field solves (z, r)", unit="solve")

    def work(point):
        z, r, estimate = point
        kwargs = dict(comm=solve_comm, offset=r, method="3d",
                      mesh_size_mm=mesh_size_mm, degree=degree)
        if sampled:
            kwargs["estimate_error"] = estimate
        return solve(scene, float(z), **kwargs)

    def advance(n):
        if bar is not None:
            bar.update(n)

    solved: dict = {}
    placed = {"moved": 0, "meshed": 0}
    by_place: dict = {}   # the solves by the ball's (z, r): a scaled grid's ends share one
    measured = math.nan

    def solve_grid(positions, offsets) -> None:
        nonlocal measured
        todo_z = positions[positions <= 0.5 * stroke * (1 + 1e-12)] if symmetric else positions
        todo_z = todo_z[contact_first_order(todo_z, stroke)]
        todo = [(z, r) for z in todo_z for r in offsets[::-1] if grid_key(z, r) not in solved]
        # grid points that put the ball at the same place (a scaled table's ends of the
        # stroke, where r_max = 0) are solved once
        places: dict = {}   # grid_key of the ball's (z, r) -> [z, r, estimate_error]
        for z, u in todo:
            r = offset_of(z, u)
            estimate = grid_key(z, u) in sample_keys
            if grid_key(z, r) in by_place:
                continue                     # solved in an earlier round
            if grid_key(z, r) in places:
                places[grid_key(z, r)][2] |= estimate
            else:
                places[grid_key(z, r)] = [float(z), r, estimate]
        tasks = [tuple(task) for task in places.values()]
        if bar is not None:
            bar.total += len(tasks)
            bar.refresh()
        farmed = farm(comm, tasks, work, progress=advance)
        for r in farmed:   # how the solves' meshes were placed (#40, mesh_motion = "move")
            for key, count in (getattr(r, "info", None) or {}).get("mesh_placements", {}).items():
                placed[key] = placed.get(key, 0) + int(count)
        if sampled:
            farmed, measured = _sampled_field_errors(farmed, [t[2] for t in tasks], measured)
        by_place.update(zip(places, farmed))
        results = [by_place[grid_key(z, offset_of(z, r))] for z, r in todo]
        for (z, r), res in zip(todo, results):
            solved[grid_key(z, r)] = res
            if symmetric and not math.isclose(z, 0.5 * stroke, rel_tol=1e-12):
                solved[grid_key(stroke - z, r)] = mirrored(res, stroke)

    def grid(positions, offsets) -> RadialTable:
        return table_from_grid(solved, positions, offsets, stroke=stroke, largest_offset=largest,
                               offset_coordinate=coordinate)

    z_now, r_now = lobatto_positions(stroke, nz), offset_positions(largest, nr)
    z_next = np.sort(np.concatenate([z_now, refinement_positions(stroke, nz)]))
    r_next = np.sort(np.concatenate([r_now, offset_refinement(largest, nr)]))
    solve_grid(z_next, r_next)
    history: list[tuple[int, int, float]] = []
    error_z = error_r = math.inf
    while True:
        estimate, along_z, along_r = held_out_error_zr(grid(z_now, r_now), grid(z_next, r_next))
        error_z = along_z if not math.isnan(along_z) else error_z
        error_r = along_r if not math.isnan(along_r) else error_r
        history.append((z_now.size, r_now.size, estimate))
        z_now, r_now = z_next, r_next
        if estimate <= tolerance:
            break
        refine_z = error_z > tolerance or not error_r > tolerance
        refine_r = error_r > tolerance or not error_z > tolerance
        refine_z &= 2 * z_now.size - 1 <= max_positions
        refine_r &= 2 * r_now.size - 1 <= max_offsets
        if not (refine_z or refine_r):
            break
        if refine_z:
            z_next = np.sort(np.concatenate([z_now, refinement_positions(stroke, z_now.size)]))
        if refine_r:
            r_next = np.sort(np.concatenate([r_now, offset_refinement(largest, r_now.size)]))
        solve_grid(z_next, r_next)
    if bar is not None:
        bar.close()
    if getattr(scene.field, "mesh_motion", "remesh") == "move":   # the table is done:
        from ..field import moving3d   # its reference meshes and their solvers are freed
        moving3d.release_references()
    rule = (_field_error_rule(sample_z, f" on the axis and at r = {largest:.6g} m", "elsewhere")
            if sampled else "measured at every point")
    table = grid(z_now, r_now)
    table = dataclasses.replace(
        table, interpolation_error=estimate, tolerance=float(tolerance),
        converged=bool(estimate <= tolerance),
        error_history=history, degree=int(degree), mesh_size=float(mesh_size_mm) * 1e-3,
        field_hash=radial_hash(scene, mesh_size_mm=mesh_size_mm, degree=degree,
                               tolerance=tolerance),
        provenance={**provenance(scene, command_line), "mirror_symmetry": symmetric,
                    "field_error_rule": rule, "solver_fingerprint": solver_fingerprint(),
                    "kind": "zr",
                    **({"mesh_placements": placed} if sum(placed.values()) else {})})
    warn_problems(radial_accuracy_problems(table), comm, stacklevel=2)
    return table


def radial_accuracy_problems(table: RadialTable) -> list[str]:
    """The interpolation error estimate of ``table`` above its tolerance, as one line (the
    (z, r) tolerance is an interpolation target below the 3D field error, so the field
    error is not held to it)."""
    if not table.interpolation_error > table.tolerance:
        return []
    nz, nr = table.shape
    return [f"(z, r) surrogate: interpolation error estimate {table.interpolation_error:.3g} "
            f"is above the tolerance {table.tolerance:g} after {nz} x {nr} points"]
