"""3D field solver: relative error against wall time (paper device, z = 1 mm).

    .venv/bin/python benchmarks/field3d_convergence.py [--out DIR] [--quick]
    mpirun -n 2 .venv/bin/python benchmarks/field3d_convergence.py --out DIR

For mesh sizes x degree 1/2 it solves the paper's device with the ball on
the axis at z = 1 mm on MPI.COMM_WORLD (far field "kelvin", i.e. the exact
low-order DtN condition, R = 20 mm), and measures the relative error of
q_upper, C_T (floating) and the max over C_ll, C_lu, C_uu, q_lower, q_upper
against an independent reference: the axisymmetric solver on a fine mesh
(degree 2, 0.25 mm, Kelvin inversion; its own estimate is ~2e-5). A second
table gives the error of each far-field treatment at R = 20 and 40 mm
(degree 2, 1.5 mm). Writes ``field3d_convergence.csv`` and
``field3d_convergence.png`` and prints markdown tables; ``uptime`` is
recorded since the machine may be shared.
"""
from __future__ import annotations

import argparse
import csv
import os
import subprocess
import time
from pathlib import Path



def run(out: Path, quick: bool, full: bool = False) -> None:
    from mpi4py import MPI

    from tengfield import terminals
    from tengfield.field import solver3d
    from tengfield.field.cells import plate_model3d
    from tengfield.scene import default_scene

    from tengfield.field import solve_position

    comm = MPI.COMM_WORLD
    scene = default_scene()
    cell = plate_model3d.cylindrical_cell(scene.device)
    z = 1.0e-3
    keys = ["C_ll", "C_lu", "C_uu", "q_lower", "q_upper", "C_T"]

    def values(c, q):
        c_t = float(terminals.terminal_capacitance(c[0, 0], c[0, 1], c[1, 1], "floating"))
        return dict(zip(keys, [c[0, 0], c[0, 1], c[1, 1], q[0], q[1], c_t]))

    axi = solve_position(scene, z, comm=MPI.COMM_SELF, method="axisymmetric", mesh_size_mm=0.25)
    reference = values(axi.capacitance, axi.induced_fractions())

    def errors(vals):
        return {k: abs(vals[k] - reference[k]) / abs(reference[k]) for k in keys}

    sizes = {1: [1.5, 1.0, 0.7], 2: [2.0, 1.5, 1.0]}
    if quick:
        sizes = {1: [1.5, 1.0], 2: [2.0, 1.5]}
    if full:
        sizes = {1: [1.5, 1.0, 0.7, 0.5], 2: [2.0, 1.5, 1.0, 0.7]}
    rows = []
    for degree, hs in sizes.items():
        for h in hs:
            settings = solver3d.Solve3DSettings(degree=degree, mesh_size=h * 1e-3,
                                                domain_radius=20e-3, far_field="kelvin",
                                                estimate_error=False)
            comm.Barrier()
            start, cpu_start = time.perf_counter(), time.process_time()
            sol = solver3d.solve_cell(cell, z, 0.0, settings, comm=comm)
            wall = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
            cpu = comm.allreduce(time.process_time() - cpu_start, op=MPI.MAX)
            vals = values(sol.capacitance, sol.induced_fraction)
            err = errors(vals)
            rows.append({"degree": degree, "mesh_size_mm": h, "dofs": sol.potentials.dofs,
                         "cells": sol.potentials.cells, "wall_s": wall, "cpu_s": cpu,
                         "solve_s": sol.potentials.solve_time, "mesh_s": sol.cell_mesh.mesh_time,
                         **vals, "err_q_upper": err["q_upper"], "err_C_T": err["C_T"],
                         "err_max": max(err[k] for k in keys[:5])})
            if comm.rank == 0:
                print(f"degree {degree} h {h} mm: {rows[-1]['dofs']} dofs, {wall:.1f} s "
                      f"(cpu {cpu:.1f} s), "
                      f"max err {rows[-1]['err_max']:.1e}", flush=True)

    truncation = []
    for far_field in ("kelvin", "robin", "dirichlet"):
        for radius in (20e-3, 40e-3):
            settings = solver3d.Solve3DSettings(degree=2, mesh_size=1.5e-3, domain_radius=radius,
                                                far_field=far_field, estimate_error=False)
            sol = solver3d.solve_cell(cell, z, 0.0, settings, comm=comm)
            err = errors(values(sol.capacitance, sol.induced_fraction))
            truncation.append({"far_field": far_field, "R_mm": radius * 1e3,
                               "err_max": max(err[k] for k in keys[:5]), "err_C_T": err["C_T"]})
    if comm.rank != 0:
        return
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "field3d_convergence.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"\nuptime: {subprocess.run(['uptime'], capture_output=True, text=True).stdout.strip()}")
    print(f"MPI ranks: {comm.size}; reference: axisymmetric, degree 2, 0.25 mm, Kelvin "
          f"(estimate {axi.relative_error_estimate:.1e})")
    print("| degree | h [mm] | dofs | wall [s] | cpu/rank [s] | solve [s] | err q_upper | err C_T "
          "| max err |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['degree']} | {r['mesh_size_mm']} | {r['dofs']} | {r['wall_s']:.1f} | "
              f"{r['cpu_s']:.1f} | "
              f"{r['solve_s']:.1f} | {r['err_q_upper']:.1e} | {r['err_C_T']:.1e} | {r['err_max']:.1e} |")
    print("\nfar field (degree 2, h = 1.5 mm): error against the axisymmetric reference")
    print("| far field | R [mm] | max err | err C_T |")
    print("|---|---|---|---|")
    for t in truncation:
        print(f"| {t['far_field']} | {t['R_mm']:.0f} | {t['err_max']:.1e} | {t['err_C_T']:.1e} |")

    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for degree, marker in ((1, "o"), (2, "s")):
        sel = [r for r in rows if r["degree"] == degree]
        ax.loglog([r["wall_s"] for r in sel], [r["err_q_upper"] for r in sel], marker + "-",
                  label=f"q_upper, degree {degree}")
        ax.loglog([r["wall_s"] for r in sel], [r["err_C_T"] for r in sel], marker + "--",
                  label=f"C_T, degree {degree}")
    ax.axhline(1e-2, color="grey", lw=0.8)
    ax.axvline(60, color="grey", lw=0.8)
    ax.set_xlabel(f"wall time per position [s] ({comm.size} MPI ranks, shared machine)")
    ax.set_ylabel("relative error")
    ax.set_title("3D solver, paper device, z = 1 mm (on axis, vs axisymmetric)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "field3d_convergence.png", dpi=150)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/benchmarks"))
    parser.add_argument("--quick", action="store_true", help="two mesh sizes per degree")
    parser.add_argument("--full", action="store_true", help="four mesh sizes per degree")
    args = parser.parse_args()
    run(args.out, args.quick, args.full)
