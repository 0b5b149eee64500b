"""``tengfield report``: error against run time of every stage, cheapest settings.

Writes DIR/report.md, DIR/report.csv, DIR/report.json, DIR/{field,surrogate,
dynamics,circuit}.png and DIR/recommended-<target>.toml (see docs/report.md).
"""
from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser(
        "report", help="error against run time of every stage; cheapest settings for 1e-2 / 1e-3",
        description="Run the field, surrogate, dynamics and circuit stages at several accuracy "
                    "levels, measure the error of the peak-to-peak V_OC, Q_SC, I_SC against "
                    "stated references, and write report.md, report.csv, report.json, log-log "
                    "PNGs and recommended scene files (recommended-0.01.toml, "
                    "recommended-0.001.toml) for `tengfield run`.")
    p.add_argument("scene", nargs="?", help="scene file (default: the embedded default scene)")
    p.add_argument("-o", "--output", default="report", metavar="DIR",
                   help="output directory (created; default ./report)")
    p.add_argument("--fast", action="store_true",
                   help="CI-sized report (coarse levels, about a minute)")
    p.set_defaults(func=_report)


def _report(args) -> int:
    from mpi4py import MPI

    from ..report import build_report, write_report
    from ..scene import load_scene

    scene = load_scene(args.scene)
    report = build_report(scene, fast=args.fast, comm=MPI.COMM_SELF, progress=True)
    written = write_report(report, args.output)
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
