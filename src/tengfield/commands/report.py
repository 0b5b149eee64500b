"""``tengfield report``: error against run time of every stage, cheapest settings.

Writes DIR/report.md, DIR/report.csv, DIR/report.json, DIR/{field,surrogate,
dynamics,circuit}.png and DIR/recommended-<target>.toml (see docs/report.md).

Under ``mpirun -n N tengfield report`` the field solves and the trajectories
are farmed over the N ranks (each solve on one rank); the errors equal a
serial run's, and rank 0 writes the files.
"""
from __future__ import annotations

from .._mpi import world_if_parallel
from ._common import scene_command


def register(sub) -> None:
    p = scene_command(sub, "report", output="report", description=__doc__,
                      help="error against run time of every stage; "
                           "cheapest settings for 1e-2 / 1e-3")
    p.add_argument("--fast", action="store_true",
                   help="CI-sized report (coarse levels, about a minute)")
    p.set_defaults(func=_report)


def _report(args) -> int:
    from mpi4py import MPI

    from ..accuracy_report import build_report
    from ..scene import load_scene

    scene = load_scene(args.scene)
    farm_comm = world_if_parallel()
    report = build_report(scene, fast=args.fast, comm=MPI.COMM_SELF, progress=True,
                          farm_comm=farm_comm)
    if farm_comm is not None and farm_comm.rank != 0:
        return 0
    written = report.write(args.output)
    for rec in report.recommendations:
        f = rec.field
        print(f"target {rec.target:g}: {f['method']} degree {f['degree']} mesh "
              f"{f['mesh_size_mm']:g} mm {f['far_field']}, tolerance {f['tolerance']:g}, "
              f"sample rate {rec.sample_rate_hz:g} Hz -> measured error "
              f"{rec.measured_error:.2g} in {rec.measured_wall_time_s:.1f} s "
              f"({'reached' if rec.reached else 'NOT reached'})")
    print(f"report wall time {report.wall_time_s:.0f} s; wrote "
          + ", ".join(str(p) for p in written))
    return 0
