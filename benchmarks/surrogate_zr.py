"""Cost and accuracy of the (z, r) surrogate of an off-axis ball (issue #13, budget:
interpolation error <= 1e-2 in <= 5 min on 2 ranks).

    mpirun -n 2 python benchmarks/surrogate_zr.py [--out out/benchmarks] [--mesh-size-mm 1.5]
        [--degree 2] [--tolerance 1e-2] [--axis-check]

Builds the surrogate of the default scene from scratch (a fresh cache
directory) with :func:`tengfield.surrogate.radial.obtain_radial_table` on
``COMM_WORLD`` (the task farm), and prints:

* wall time, CPU time (user + sys) per rank and summed, the machine's load
  average before and after (other jobs inflate the wall clock: compare CPU);
* the grid (n_z x n_r), how many 3D solves ran (mirror images are free), the
  held-out interpolation error estimate per round and the field error estimates;
* how much the offset matters: the largest change of Q_SC, C_T and V_OC
  between r = 0 and the wall (relative to each quantity's largest magnitude);
* with ``--axis-check``: the r = 0 column against the axisymmetric
  surrogate of the same scene (:func:`axis_check`; it is solved or taken
  from the default cache).

Writes ``surrogate_zr.json`` and ``surrogate_zr.png`` (Q_SC(z) and C_T(z) at
several offsets, and the relative change of Q_SC over (z, r)) to ``--out``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/benchmarks")
    parser.add_argument("--mesh-size-mm", type=float, default=None)
    parser.add_argument("--degree", type=int, default=None)
    parser.add_argument("--tolerance", type=float, default=None)
    parser.add_argument("--axis-check", action="store_true")
    args = parser.parse_args(argv)

    from mpi4py import MPI

    from tengfield import surrogate, terminals
    from tengfield.scene import default_scene
    from tengfield.surrogate import radial

    comm = MPI.COMM_WORLD
    scene = default_scene()
    settings = {"mesh_size_mm": args.mesh_size_mm or radial.DEFAULT_MESH_SIZE_MM,
                "degree": args.degree or radial.DEFAULT_DEGREE,
                "tolerance": args.tolerance or radial.DEFAULT_TOLERANCE}
    cache = tempfile.mkdtemp(prefix="zr-bench-") if comm.rank == 0 else None
    cache = comm.bcast(cache, root=0)
    load_before = os.getloadavg()
    comm.Barrier()
    start, cpu = time.perf_counter(), _cpu()
    table, outcome = radial.obtain_radial_table(scene, cache_dir=cache, comm=comm,
                                                progress=True, **settings)
    wall = time.perf_counter() - start
    cpu_rank = _cpu() - cpu
    cpu_ranks = comm.gather(cpu_rank, root=0)
    load_after = os.getloadavg()

    axis = None
    if args.axis_check:
        axis_table, _ = surrogate.obtain_table(scene, comm=comm)
        axis = radial.axis_check(table, axis_table)
    if comm.rank != 0:
        return 0

    solves = int(np.count_nonzero(table.wall_time > 0.0))
    effect = {}
    for reference in terminals.REFERENCES:
        q, c = radial.terminal_grid(table, reference, scene.device.ball_charge)
        v = np.divide(q, c)
        effect[reference] = {
            name: float(np.max(np.abs(x[:, -1] - x[:, 0])) / np.max(np.abs(x)))
            for name, x in (("Q_SC", q), ("C_T", c), ("V_OC", v))}
    result = {
        "settings": settings, "ranks": comm.size, "status": outcome.status,
        "wall_s": wall, "cpu_per_rank_s": cpu_ranks, "cpu_total_s": float(sum(cpu_ranks)),
        "load_average_before": load_before, "load_average_after": load_after,
        "grid": list(table.shape), "solves": solves,
        "sum_of_solve_wall_times_s": table.total_solve_wall_time,
        "interpolation_error": table.interpolation_error, "converged": table.converged,
        "error_history": table.error_history,
        "field_error_max": float(np.nanmax(table.field_error)),
        "field_error_rule": table.provenance.get("field_error_rule"),
        "max_dofs": int(table.dofs.max()), "offset_effect_axis_to_wall": effect,
        "axis_check": axis, "offsets_mm": (table.offsets * 1e3).tolist(),
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "surrogate_zr.json").write_text(json.dumps(result, indent=2, default=float))
    print(json.dumps(result, indent=2, default=float))
    _plot(table, scene.device.ball_charge, out / "surrogate_zr.png")
    return 0


def _plot(table, ball_charge, path) -> None:
    import matplotlib
    matplotlib.use("Agg")   # a script, not library code
    import matplotlib.pyplot as plt

    curves = table.curves("floating", ball_charge)
    z = np.linspace(0.0, table.stroke, 301)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for r in np.linspace(0.0, table.max_offset, 4):
        axes[0].plot(z * 1e3, curves.charge(z, r) * 1e9, label=f"r = {r * 1e3:.2f} mm")
        axes[1].plot(z * 1e3, curves.capacitance(z, r) * 1e12)
    axes[0].set(xlabel="gap z [mm]", ylabel="Q_SC [nC]", title="short-circuit charge")
    axes[0].legend(fontsize=8)
    axes[1].set(xlabel="gap z [mm]", ylabel="C_T [pF]", title="terminal capacitance")
    zz, rr = np.meshgrid(z, np.linspace(0.0, table.max_offset, 61), indexing="ij")
    q = curves.charge(zz, rr)
    change = (q - curves.charge(zz, 0.0)) / np.max(np.abs(q))
    mesh = axes[2].pcolormesh(zz * 1e3, rr * 1e3, change, shading="auto", cmap="RdBu_r")
    fig.colorbar(mesh, ax=axes[2], label="(Q_SC(z, r) - Q_SC(z, 0)) / max |Q_SC|")
    axes[2].set(xlabel="gap z [mm]", ylabel="radial offset r [mm]", title="effect of the offset")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
