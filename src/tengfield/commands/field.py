"""``tengfield field``: electrostatics at one ball position (numbers, field.json,
potential.xdmf, field.png). The only place of the field stack that uses
``MPI.COMM_WORLD``."""
from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

from ..scene.shapes.methods import field_method
from ..terminals import REFERENCES
from ._common import scene_command
from ._ranges import number_text


def register(sub) -> None:
    p = scene_command(
        sub, "field", output="field-out",
        help="capacitance matrix, induced charges and potential at one ball position",
        description="Solve the electrostatics of the device with the ball at gap Z above the "
                    "lower electrode. Prints the Maxwell capacitance matrix, the induced "
                    "charges (electrodes grounded) and C_T; writes DIR/field.json, "
                    "DIR/potential.xdmf (open-circuit potential for ParaView) and DIR/field.png.")
    p.add_argument("--position-mm", type=float, required=True, metavar="Z",
                   help="gap between the ball's bottom and the lower electrode [mm], 0..stroke_mm")
    p.add_argument("--offset-mm", type=float, default=None, metavar="R",
                   help="lateral ball offset from the axis [mm] (3D only; default [field] "
                        "ball_offset_mm)")
    p.add_argument("--method", choices=("auto", "axisymmetric", "3d"), default=None,
                   help="solver (default [field] method)")
    p.add_argument("--reference", choices=REFERENCES, default=None,
                   help="two-terminal reference (default [circuit] reference)")
    p.add_argument("--no-plots", "--no-plot", dest="no_plot", action="store_true",
                   help="skip potential.xdmf and field.png")
    # field.png is drawn by pyvista, a PNG only: --figure-format pdf/svg is refused in
    # one line before any work (it wrote a PNG silently)
    p.set_defaults(func=_run, figure_formats=("png",))


def _resolved_charge(scene, comm):
    """The scene with ``σ = "breakdown"`` replaced by
    -sigma_max (from the cached surrogate's breakdown lines, computed once if missing),
    so the solve is at the charge a run would use; any other scene as it is."""
    from .. import air_breakdown
    from ..run_surrogate import surrogate_for_run
    from ..scene import check_field

    if not air_breakdown.uses_breakdown_charge(scene):
        return scene
    check_field(scene)
    scene, _, _, _ = surrogate_for_run(scene, comm=comm if comm.size > 1 else None,
                                       progress=True)
    if comm.rank == 0:
        print(air_breakdown.charge_line(scene))
    return scene


def _run(args) -> int:
    import pyvista  # noqa: F401 - before dolfinx: the reverse order breaks VTK text rendering
    from mpi4py import MPI

    from ..errors import FieldError
    from ..field import check_position, resolve_method, solve_position
    from ..scene import load_scene

    comm = MPI.COMM_WORLD
    scene = _resolved_charge(load_scene(args.scene), comm)
    if args.offset_mm is not None:
        from ..scene.shapes import shape_of

        widest = shape_of(scene.device.shape).max_offset(scene.device)   # the scene's rule
        if not (math.isfinite(args.offset_mm) and 0 <= args.offset_mm * 1e-3 <= widest + 1e-15):
            raise FieldError(f"offset_mm = {number_text(args.offset_mm)} is out of range: "
                             f"allowed [0, {widest * 1e3:g}] mm (the ball must stay inside "
                             f"the {shape_of(scene.device.shape).enclosure})")
        scene = scene.with_values(field={"ball_offset_mm": args.offset_mm})
    position = args.position_mm * 1e-3
    _check_position(scene, args.position_mm)
    check_position(scene, position)
    reference = args.reference or scene.circuit.reference
    method = resolve_method(scene, args.method, scene.field.ball_offset)
    from ..field import cost   # before any meshing: refused past [field] max_memory_gb
    estimate = cost.solve_cost(scene, method=method, position=position)
    cost.check_memory(scene, estimate)
    from .._console import progress_shown
    if progress_shown(True, comm):   # the cost before the work, on a terminal (issue #40)
        print(f"tengfield: {cost.describe(estimate, 1, what='field solve')}", file=sys.stderr,
              flush=True)
    out = Path(args.output)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    plot = not args.no_plot
    if field_method(method).serial:
        # a small problem: solved and written on rank 0, the outcome shared
        result, potentials, written = _on_rank_zero(
            comm, lambda: _axisymmetric(scene, position, reference, out, plot=plot))
    else:
        result = solve_position(scene, position, comm=comm, method="3d", keep_solution=plot)
        potentials = None
        written = result.write(out, plots=plot, reference=reference)     # collective
        result.solution = None
        if plot and comm.size > 1 and comm.rank == 0:
            print("tengfield: field.png of a 3D run is drawn in serial runs only; "
                  "potential.xdmf holds psi_lower, psi_upper", file=sys.stderr)
    if comm.rank == 0:
        from ..field import io

        for line in io.summary_lines(result, reference, potentials):
            print(line)
        problem = io.accuracy_problem(result, scene)
        if problem is not None:   # one line, as the surrogate's (refinement.warn_problems)
            warnings.warn(problem, RuntimeWarning, stacklevel=1)
        print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _check_position(scene, position_mm: float) -> None:
    """FieldError unless 0 <= ``position_mm`` <= the stroke (the library's rule,
    ``field.check_position``), the value shown with the digits that tell it from the bound
    (``3.0000000001``, not ``3``)."""
    from ..errors import FieldError

    stroke = scene.device.stroke
    if not (math.isfinite(position_mm) and 0.0 <= position_mm * 1e-3 <= stroke * (1.0 + 1e-12)):
        raise FieldError(f"position_mm = {number_text(position_mm)} is out of range: allowed "
                         f"[0, {stroke * 1e3:g}] mm (the free stroke, [device] stroke_mm)")


def _on_rank_zero(comm, work):
    """``work()`` on rank 0 of ``comm``, its outcome (or exception) on every rank."""
    from ..field import _dolfinx  # noqa: F401 - every rank: PETSc init is collective

    outcome = None
    if comm.rank == 0:
        try:
            outcome = work()
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank
            outcome = exc
    if comm.size > 1:
        outcome = comm.bcast(outcome, root=0)
    if isinstance(outcome, Exception):
        raise outcome
    return outcome


def _axisymmetric(scene, position, reference, out, *, plot: bool):
    """The open circuit at ``position`` on this process, its files written
    (``OpenCircuit.write``); the result without its solution, the potentials, the paths."""
    from mpi4py import MPI

    from ..field import open_circuit

    state = open_circuit(scene, position, comm=MPI.COMM_SELF, method="axisymmetric",
                         reference=reference, keep_solution=plot)
    written = state.write(out, plots=plot)
    state.result.solution = None   # stays on rank 0
    return state.result, state.potentials, written
