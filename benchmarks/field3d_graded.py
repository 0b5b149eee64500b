"""3D field solves, `[field] mesh_grading = "uniform"` against `"graded"` (issue #55).

    .venv/bin/python benchmarks/field3d_graded.py [--sizes 1.0 0.7 0.5] [--out DIR]

The default device with the ball on the axis at z = 1.5 mm, solved by the public API
(``tengfield.field.solve_position(..., method="3d")``: degree 2, far field "kelvin",
R = 20 mm, the solver's own error estimate on a twice coarser mesh) for each mesh size and
grading: dofs, wall time of the solve (both meshes), C_T (floating), q_lower / q_ball,
q_upper / q_ball, the solver's ``relative_error_estimate`` and the signed relative error of
C_ll, C_lu, C_uu, q_lower, q_upper, C_T against an independent reference: the axisymmetric
solve of the same position at ``--reference-mm`` (default 0.25 mm; its own estimate is
printed, ~2e-5). Prints a markdown table and writes ``field3d_graded.csv``; ``uptime``
is recorded since the machine may be shared. Whole-process times are the CLI's
(``tengfield field --set field.method=3d --set field.mesh_grading=... --position-mm 1.5``),
timed from outside.

``--own-mesh`` (issue #55 item 5, a study): instead, for each size and grading, solve the
same mesh at P2 and P3 and compare ``|Q_P3 - Q_P2|`` (a P(k+1) estimate on the solve's own
mesh) with the P2 error against the reference.
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import time
from pathlib import Path

KEYS = ("C_ll", "C_lu", "C_uu", "q_lower", "q_upper", "C_T")


def values(result) -> dict:
    """The terminal quantities of a PositionResult: C [F], q / q_ball, C_T [F] (floating)."""
    from tengfield import terminals

    c, q = result.capacitance, result.induced_fractions()
    c_t = float(terminals.terminal_capacitance(c[0, 0], c[0, 1], c[1, 1], "floating"))
    return dict(zip(KEYS, (c[0, 0], c[0, 1], c[1, 1], q[0], q[1], c_t)))


def run(sizes, gradings, position_mm: float, reference_mm: float, out: Path | None) -> list[dict]:
    from mpi4py import MPI

    from tengfield.field import solve_position
    from tengfield.scene import default_scene

    comm = MPI.COMM_SELF
    scene = default_scene()
    z = position_mm * 1e-3
    axi = solve_position(scene, z, comm=comm, method="axisymmetric", mesh_size_mm=reference_mm)
    reference = values(axi)
    print(f"reference: axisymmetric, {reference_mm} mm, {axi.dofs} dofs, own estimate "
          f"{axi.relative_error_estimate:.1e}; C_T = {reference['C_T'] * 1e12:.6f} pF, "
          f"q_upper/q_ball = {reference['q_upper']:.6f}", flush=True)
    rows = []
    for h in sizes:
        for grading in gradings:
            graded = scene.with_values(field={"mesh_grading": grading, "mesh_size_mm": h})
            start = time.perf_counter()
            res = solve_position(graded, z, comm=comm, method="3d")
            wall = time.perf_counter() - start
            vals = values(res)
            err = {k: (vals[k] - reference[k]) / abs(reference[k]) for k in KEYS}
            rows.append({"grading": grading, "mesh_size_mm": h, "dofs": res.dofs, "wall_s": wall,
                         "C_T_pF": vals["C_T"] * 1e12, "q_lower_per_q_ball": vals["q_lower"],
                         "q_upper_per_q_ball": vals["q_upper"],
                         "estimate": res.relative_error_estimate,
                         **{f"err_{k}": err[k] for k in KEYS},
                         "err_max": max(abs(err[k]) for k in KEYS[:5])})
            r = rows[-1]
            print(f"{grading:8s} h {h} mm: {r['dofs']} dofs, {wall:.1f} s, estimate "
                  f"{r['estimate']:.1e}, max err {r['err_max']:.1e}", flush=True)
    print(f"\nuptime: {subprocess.run(['uptime'], capture_output=True, text=True).stdout.strip()}")
    print("\n| grading | h [mm] | dofs | solve wall [s] | C_T [pF] | q_upper/q_ball | estimate | "
          "err C_T | err q_upper | err C_lu | max err (C, q) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['grading']} | {r['mesh_size_mm']} | {r['dofs']:,} | {r['wall_s']:.1f} | "
              f"{r['C_T_pF']:.5f} | {r['q_upper_per_q_ball']:.5f} | {r['estimate']:.1e} | "
              f"{r['err_C_T']:+.1e} | {r['err_q_upper']:+.1e} | {r['err_C_lu']:+.1e} | "
              f"{r['err_max']:.1e} |".replace(",", " "))
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        with open(out / "field3d_graded.csv", "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    return rows


def own_mesh(sizes, gradings, position_mm: float, reference_mm: float) -> list[dict]:
    """P2 and P3 on one mesh: their errors against the axisymmetric reference and
    ``max |Q_P3 - Q_P2| / |Q_P3|`` over C_ll, C_lu, C_uu, q_lower, q_upper."""
    import numpy as np
    from mpi4py import MPI

    from tengfield.field import solve_position, solver3d
    from tengfield.field.cells import plate_model3d
    from tengfield.scene import default_scene

    comm = MPI.COMM_SELF
    scene = default_scene()
    z = position_mm * 1e-3
    axi = solve_position(scene, z, comm=comm, method="axisymmetric", mesh_size_mm=reference_mm)
    reference = np.array([values(axi)[k] for k in KEYS[:5]])
    cell = plate_model3d.cylindrical_cell(scene.device)
    perm = solver3d.cell_permittivity(cell)
    radius = scene.field.domain_radius
    rows = []
    for h in sizes:
        for grading in gradings:
            settings = solver3d.Solve3DSettings(degree=2, mesh_size=h * 1e-3, domain_radius=radius,
                                                far_field="kelvin", mesh_grading=grading)
            cell_mesh = solver3d.mesh_cell(cell, z, 0.0, settings.mesh_settings(), comm=comm)
            found = {}
            for degree in (2, 3):
                start = time.perf_counter()
                pot = solver3d.solve_weighting_potentials(cell_mesh, perm, degree=degree,
                                                          far_field="kelvin", domain_radius=radius)
                c = solver3d.capacitance_matrix(cell_mesh, pot, perm, far_field="kelvin",
                                                domain_radius=radius)
                q = -solver3d.ball_surface_means(cell_mesh, pot)
                found[degree] = (np.array([c[0, 0], c[0, 1], c[1, 1], q[0], q[1]]), pot.dofs,
                                 time.perf_counter() - start)
            (v2, n2, t2), (v3, n3, t3) = found[2], found[3]
            rows.append({"grading": grading, "mesh_size_mm": h, "dofs_p2": n2, "dofs_p3": n3,
                         "wall_p2_s": t2, "wall_p3_s": t3,
                         "err_p2": float(np.max(np.abs(v2 - reference) / np.abs(reference))),
                         "err_p3": float(np.max(np.abs(v3 - reference) / np.abs(reference))),
                         "own_mesh_estimate": float(np.max(np.abs(v3 - v2) / np.abs(v3)))})
            r = rows[-1]
            print(f"| {grading} | {h} | {n2} | {n3} | {t2:.1f} | {t3:.1f} | {r['err_p2']:.1e} | "
                  f"{r['err_p3']:.1e} | {r['own_mesh_estimate']:.1e} |", flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[1.0, 0.7, 0.5],
                        help="mesh_size_mm values")
    parser.add_argument("--gradings", nargs="+", default=["uniform", "graded"])
    parser.add_argument("--position-mm", type=float, default=1.5)
    parser.add_argument("--reference-mm", type=float, default=0.25,
                        help="the axisymmetric reference's mesh_size_mm")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--own-mesh", action="store_true",
                        help="P2 against P3 on the same mesh (a P(k+1) error estimate)")
    args = parser.parse_args()
    if args.own_mesh:
        print("| grading | h [mm] | dofs P2 | dofs P3 | wall P2 [s] | wall P3 [s] | err P2 | "
              "err P3 | abs(P3 - P2) |\n|---|---|---|---|---|---|---|---|---|")
        own_mesh(args.sizes, args.gradings, args.position_mm, args.reference_mm)
        return
    run(args.sizes, args.gradings, args.position_mm, args.reference_mm, args.out)


if __name__ == "__main__":
    main()
