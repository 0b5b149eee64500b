"""Files and text of one field position: field.json, XDMF for ParaView, the
summary lines the CLI prints. Writers take a
:class:`~tengfield.field.result.PositionResult` / :class:`~tengfield.field.result.FieldSolution`;
no physics here.
"""
from __future__ import annotations

import math

import numpy as np

from ..scene.shapes.methods import field_method
from ..terminals import terminal_voltage


def field_json(result, reference: str, potentials=None) -> dict:
    """The content of ``field.json``: :meth:`PositionResult.to_json` plus, when
    known, the open-circuit potentials [V]."""
    data = result.to_json(reference)
    if potentials is not None:
        data["open_circuit_potential_V"] = dict(zip(result.electrodes,
                                                    (float(v) for v in potentials)))
    return data


def write_field_json(path, result, reference: str, potentials=None) -> None:
    """Write :func:`field_json` to ``path`` (call on one rank; atomic, strict JSON)."""
    from ..files import write_json

    write_json(path, field_json(result, reference, potentials))


#: the files of one position: ``tengfield field`` and ``PositionResult.write``
FIELD_JSON, POTENTIAL_XDMF, FIELD_PNG = "field.json", "potential.xdmf", "field.png"


def write_position_files(result, out_dir, *, reference: str = "floating", potentials=None,
                         plots: bool = True) -> list:
    """What ``tengfield field`` writes for one position ``result`` (a
    :class:`~tengfield.field.result.PositionResult`) into ``out_dir``: field.json
    (:func:`field_json`, with the open-circuit ``potentials`` [V] when given) and, with
    ``plots``, potential.xdmf (:func:`write_xdmf`) and field.png (the axisymmetric
    potential, or the 3D weighting potential of a serial solve). ``plots`` needs the kept
    solution (``keep_solution=True``). Collective on a 3D solution's communicator (the
    XDMF file); field.json and field.png come from its rank 0. Returns the paths written."""
    from pathlib import Path

    out = Path(out_dir)
    solution = result.solution
    if plots and solution is None:
        raise ValueError("PositionResult.write(plots=True) draws potential.xdmf and field.png "
                         "from the solution: solve with keep_solution=True, or pass "
                         "plots=False for field.json alone")
    comm = None if solution is None else solution.mesh.comm
    three_d = solution is not None and field_method(solution.method).dimension == 3
    rank = 0 if comm is None or not three_d else comm.rank
    if rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    if comm is not None and three_d:
        comm.barrier()
    written = []
    if plots:
        write_xdmf(out / POTENTIAL_XDMF, solution, potentials)      # collective in 3D
        written.append(out / POTENTIAL_XDMF)
        if not three_d or comm.size == 1:   # a figure needs the whole mesh on one process
            _draw_position(result, out / FIELD_PNG, reference, potentials)
            written.append(out / FIELD_PNG)
    if rank == 0:
        write_field_json(out / FIELD_JSON, result, reference, potentials)
    return [out / FIELD_JSON] + written


def _draw_position(result, path, reference: str, potentials) -> None:
    """field.png: the open-circuit potential (axisymmetric) or ψ_upper (3D)."""
    from . import plot as field_plot

    solution, z = result.solution, result.position * 1e3
    if field_method(solution.method).dimension == 3:
        _, name, where = field_plot.shown_weighting(solution)
        field_plot.render_weighting_png_3d(
            path, solution, result.scene.device, window_size=figure_window((1200, 1100)),
            title=(f"3D weighting potential {name} (1 V on {where}), "
                   f"z = {z:.3g} mm, offset = {result.offset * 1e3:.3g} mm"))
        return
    potentials = (0.0,) * len(result.electrodes) if potentials is None else potentials
    v_oc = terminal_voltage(potentials)
    field_plot.render_potential_png(
        path, solution, solution.potential_values(potentials),
        window_size=figure_window((1400, 1100)),
        title=(f"potential, ball's bottom at z = {z:.3g} mm, V_OC = {v_oc:.4g} V "
               f"({result.wiring(reference).name})"))


def figure_window(size: tuple[int, int]) -> tuple[int, int]:
    """field.png's pixel size: ``size`` at the figures' own 120 dpi, scaled by ``--dpi``
    (within the figures' pixel bound, :func:`tengfield.files.figures.check_figure_pixels`)."""
    from ..files import figure_dpi
    from ..files.figures import check_figure_pixels

    dpi = check_figure_pixels("field.png", (size[0] / 120.0, size[1] / 120.0),
                              figure_dpi(120.0))
    scale = dpi / 120.0
    return tuple(max(200, round(n * scale)) for n in size)


def write_xdmf(path, solution, potentials=None) -> None:
    """The potentials of ``solution`` to XDMF/HDF5 for ParaView.

    Axisymmetric: φ [V] = φ_σ + V_lower ψ_lower + V_upper ψ_upper
    (``potentials`` = [V_lower, V_upper]; zeros give φ_σ alone) as
    ``potential_V`` on the device part of the mesh (the Kelvin image left out;
    P2 on the P2 geometry), serial. 3D: ψ_lower, ψ_upper (the potentials for
    1 V on that electrode) on the whole mesh, collective on the mesh's
    communicator (the FE degree equals the mesh order; volume tags are left
    out: dolfinx 0.5.2 cannot write meshtags of a second-order mesh).
    """
    from . import _dolfinx as dx_api

    if field_method(solution.method).dimension == 3:
        dx_api.write_xdmf(path, solution.mesh, list(solution.weighting), solution.mesh.comm)
        return
    from mpi4py import MPI
    from scipy.spatial import cKDTree

    phi = solution.potential_values((0.0, 0.0) if potentials is None else potentials)
    mesh = solution.mesh
    keep = np.setdiff1d(np.arange(dx_api.num_local_cells(mesh), dtype=np.int32),
                        solution.hidden_cells)
    sub = dx_api.submesh(mesh, keep)
    order = dx_api.geometry_degree(sub)
    W = dx_api.lagrange_space(sub, order)
    source = dx_api.function(solution.space, phi)
    if solution.degree != order:
        source = dx_api.interpolate(dx_api.lagrange_space(mesh, order), source)
    parent_xy = dx_api.dof_coordinates(source.function_space)[:, :2]
    sub_xy = dx_api.dof_coordinates(W)[:, :2]
    _, idx = cKDTree(parent_xy).query(sub_xy)
    out = dx_api.function(W, source.x.array[idx], name="potential_V")
    dx_api.write_xdmf(path, sub, [out], MPI.COMM_SELF)


def accuracy_problem(result, scene) -> str | None:
    """One line when ``result``'s relative error estimate exceeds the scene's
    ``[field] tolerance`` (naming the estimate, the tolerance and the keys to change);
    None when it is within, or not estimated (NaN)."""
    from .geometry_axisymmetric import mesh_size_text

    estimate, tolerance = result.relative_error_estimate, scene.field.tolerance
    if not estimate > tolerance:          # NaN: no estimate, nothing to say
        return None
    return (f"field: relative error estimate {estimate:.2g} at z = {result.position * 1e3:.4g} "
            f"mm is above [field] tolerance = {tolerance:g}: the {result.method} mesh does not "
            f"resolve the device; lower [field] {mesh_size_text(scene)} or raise degree = "
            f"{result.degree}")


def summary_lines(result, reference: str, potentials=None) -> list[str]:
    """Human-readable numbers of one position (for the CLI)."""
    fr = result.induced_fractions()
    names = result.electrodes
    letters = [n[0] for n in names]
    C = result.capacitance
    matrix = "   ".join(f"C_{letters[j]}{letters[k]} = {C[j, k] * 1e12:.6g} pF"
                       for j in range(len(names)) for k in range(j, len(names)))
    induced = "   ".join(f"q_{name} = {result.induced_charge[k] * 1e12:.6g} pC "
                         f"({fr[k]:+.5f} q_ball)" for k, name in enumerate(names))
    wired = result.wiring(reference).name
    lines = [
        f"position z = {result.position * 1e3:.4g} mm, offset = {result.offset * 1e3:.3g} mm, "
        f"method = {result.method}, degree = {result.degree}",
        matrix,
        f"{induced}   q_ball = {result.ball_charge * 1e12:.6g} pC",
        f"C_T ({wired}) = {result.terminal_capacitance(reference) * 1e12:.6g} pF",
    ]
    if potentials is not None:
        shown = ", ".join(f"V_{name} = {v:.6g} V" for name, v in zip(names, potentials))
        difference = "V_lower - V_upper" if len(names) == 2 else "V_lower (the ground at 0 V)"
        lines.append(f"open circuit: {shown}, V_OC = {difference} = "
                     f"{terminal_voltage(potentials):.6g} V")
    est = result.relative_error_estimate
    lines.append(f"dofs = {result.dofs}, cells = {result.cells}, wall time = {result.wall_time:.3g} s "
                 f"(solve {result.solve_time:.3g} s), relative error estimate = "
                 + ("n/a" if math.isnan(est) else f"{est:.2g}"))
    return lines


