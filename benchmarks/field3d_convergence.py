"""3D field solver: relative error against wall time (paper device, z = 1 mm).

    .venv/bin/python benchmarks/field3d_convergence.py [--out DIR] [--quick]
    mpirun -n 2 .venv/bin/python benchmarks/field3d_convergence.py --out DIR

For mesh sizes x degree 1/2 it solves the off-axis (offset 0.3 mm) paper
device at z = 1 mm on MPI.COMM_WORLD, and measures the relative error of
q_upper, C_T (floating) and the max over C_ll, C_lu, C_uu, q_lower, q_upper
against a Richardson extrapolation of the two finest degree-2 solutions
(rate fitted from the three finest). A second table doubles the domain
radius (Robin and Dirichlet far field) to measure the truncation error.
Writes ``field3d_convergence.csv`` and ``field3d_convergence.png`` and
prints the table; ``uptime`` is recorded since the machine may be shared.
"""
from __future__ import annotations

import argparse
import csv
import os
import subprocess
import time
from pathlib import Path

import numpy as np


def run(out: Path, quick: bool) -> None:
    from mpi4py import MPI

    from tengfield import terminals
    from tengfield.field import geometry3d, solver3d
    from tengfield.scene import default_scene

    comm = MPI.COMM_WORLD
    cell = geometry3d.cylindrical_cell(default_scene().device)
    z, offset = 1.0e-3, 0.3e-3
    sizes = {1: [2.0, 1.5, 1.0, 0.7, 0.5], 2: [2.0, 1.5, 1.0, 0.7, 0.5]}
    if quick:
        sizes = {1: [2.0, 1.5, 1.0], 2: [2.0, 1.5, 1.0]}
    rows = []
    for degree, hs in sizes.items():
        for h in hs:
            settings = solver3d.Solve3DSettings(degree=degree, mesh_size=h * 1e-3,
                                                domain_radius=20e-3, far_field="robin",
                                                estimate_error=False)
            comm.Barrier()
            start = time.perf_counter()
            sol = solver3d.solve_cell(cell, z, offset, settings, comm=comm)
            wall = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
            c = sol.capacitance
            c_t = float(terminals.terminal_capacitance(c[0, 0], c[0, 1], c[1, 1], "floating"))
            rows.append({"degree": degree, "mesh_size_mm": h, "dofs": sol.potentials.dofs,
                         "cells": sol.potentials.cells, "wall_s": wall,
                         "solve_s": sol.potentials.solve_time, "mesh_s": sol.cell_mesh.mesh_time,
                         "C_ll": c[0, 0], "C_lu": c[0, 1], "C_uu": c[1, 1], "C_T": c_t,
                         "q_lower": sol.induced_fraction[0], "q_upper": sol.induced_fraction[1]})
            if comm.rank == 0:
                print(f"degree {degree} h {h} mm: {rows[-1]['dofs']} dofs, {wall:.1f} s", flush=True)
    keys = ["C_ll", "C_lu", "C_uu", "q_lower", "q_upper", "C_T"]
    p2 = [r for r in rows if r["degree"] == 2]
    hs = np.array([r["mesh_size_mm"] for r in p2[-3:]])
    reference, rates = {}, {}
    for k in keys:
        v = np.array([r[k] for r in p2[-3:]])
        # rate from the three finest (v = v_inf + A h^p); Richardson on the two finest
        d1, d2 = v[1] - v[0], v[2] - v[1]
        rate = np.log(abs(d1 / d2)) / np.log(hs[0] / hs[1]) if d2 != 0 and d1 * d2 > 0 else 1.0
        rate = float(np.clip(rate, 0.5, 4.0))
        ratio = (hs[1] / hs[2]) ** rate
        reference[k] = v[2] + (v[2] - v[1]) / (ratio - 1.0)
        rates[k] = rate
    for r in rows:
        errs = {k: abs(r[k] - reference[k]) / abs(reference[k]) for k in keys}
        r["err_q_upper"] = errs["q_upper"]
        r["err_C_T"] = errs["C_T"]
        r["err_max"] = max(errs[k] for k in keys[:5])

    truncation = []
    for far_field in ("robin", "dirichlet"):
        for radius in (20e-3, 40e-3, 80e-3):
            settings = solver3d.Solve3DSettings(degree=2, mesh_size=1.0e-3, domain_radius=radius,
                                                far_field=far_field, estimate_error=False)
            sol = solver3d.solve_cell(cell, z, offset, settings, comm=comm)
            truncation.append({"far_field": far_field, "R_mm": radius * 1e3,
                               "values": np.r_[sol.capacitance[np.triu_indices(2)],
                                               sol.induced_fraction]})
    if comm.rank != 0:
        return
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "field3d_convergence.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"\nuptime: {subprocess.run(['uptime'], capture_output=True, text=True).stdout.strip()}")
    print(f"MPI ranks: {comm.size}; reference = Richardson of degree 2, rates "
          + ", ".join(f"{k} {v:.2f}" for k, v in rates.items()))
    print("| degree | h [mm] | dofs | wall [s] | solve [s] | err q_upper | err C_T | max err |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['degree']} | {r['mesh_size_mm']} | {r['dofs']} | {r['wall_s']:.1f} | "
              f"{r['solve_s']:.1f} | {r['err_q_upper']:.1e} | {r['err_C_T']:.1e} | {r['err_max']:.1e} |")
    print("\nfar-field truncation (degree 2, h = 1 mm): max relative change of C, q vs R = 80 mm")
    print("| far field | R [mm] | max rel. change vs R = 80 mm |")
    print("|---|---|---|")
    for far_field in ("robin", "dirichlet"):
        ref = next(t["values"] for t in truncation if t["far_field"] == far_field and t["R_mm"] == 80)
        for t in truncation:
            if t["far_field"] == far_field and t["R_mm"] < 80:
                change = np.max(np.abs(t["values"] - ref) / np.abs(ref))
                print(f"| {far_field} | {t['R_mm']:.0f} | {change:.1e} |")

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
    ax.set_xlabel(f"wall time per position [s] ({comm.size} MPI ranks)")
    ax.set_ylabel("relative error")
    ax.set_title("3D solver, paper device, z = 1 mm, offset 0.3 mm")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "field3d_convergence.png", dpi=150)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/benchmarks"))
    parser.add_argument("--quick", action="store_true", help="three mesh sizes per degree")
    args = parser.parse_args()
    run(args.out, args.quick)
