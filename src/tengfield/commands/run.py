"""``tengfield run``: dynamics -> surrogate (cached) -> circuit, end to end.

Writes DIR/waveforms.csv, DIR/summary.json, DIR/waveforms.png,
DIR/surrogate.png and the dynamics' trajectory.csv, impacts.csv and
trajectory.png. Under ``mpirun -n N`` the field solves (if the surrogate
is not cached) are spread over the ranks; rank 0 writes every file.
"""
from __future__ import annotations

import shlex
import sys


def add_cache_argument(parser) -> None:
    parser.add_argument("--cache-dir", default=None, metavar="DIR",
                        help="surrogate cache (default $TENGFIELD_CACHE_DIR, else "
                             "$XDG_CACHE_HOME/tengfield or ~/.cache/tengfield)")


def register(sub) -> None:
    p = sub.add_parser(
        "run", help="V_OC, Q_SC, I_SC (and load) waveforms of a scene, end to end",
        description="Integrate the ball dynamics, build or reuse the field surrogate "
                    "(cached by the scene's field hash) and evaluate the circuit. Writes "
                    "waveforms.csv, summary.json, waveforms.png and surrogate.png to DIR.")
    p.add_argument("scene", nargs="?", help="scene file (default: the embedded default scene)")
    p.add_argument("-o", "--output", default="out", metavar="DIR",
                   help="output directory (created; default ./out)")
    add_cache_argument(p)
    p.add_argument("--no-plots", action="store_true", help="skip the PNG files")
    p.set_defaults(func=_run)


def command_line() -> str:
    return shlex.join(["tengfield", *sys.argv[1:]])


def _run(args) -> int:
    from ..pipeline import run, write_outputs
    from ..scene import load_scene

    scene = load_scene(args.scene)
    comm = world_if_parallel()
    result = run(scene, comm=comm, cache_dir=args.cache_dir, progress=True,
                 command_line=command_line())
    if comm is None or comm.rank == 0:
        written = write_outputs(result, args.output, plots=not args.no_plots)
        written += write_dynamics_outputs(result, args.output, plots=not args.no_plots)
        print_summary(result.summary)
        print("wrote " + ", ".join(str(p) for p in written))
    return 0


def write_dynamics_outputs(result, out_dir, *, plots: bool) -> list:
    """trajectory.csv, impacts.csv (and trajectory.png) with the writers of
    ``tengfield dynamics``."""
    from pathlib import Path

    from .dynamics import write_impacts_csv, write_trajectory_csv

    out = Path(out_dir)
    write_trajectory_csv(result.dynamics, out / "trajectory.csv")
    write_impacts_csv(result.dynamics, out / "impacts.csv")
    written = [out / "trajectory.csv", out / "impacts.csv"]
    if plots:
        from ..plotting.dynamics import plot_trajectory
        exc = result.scene.excitation
        plot_trajectory(result.dynamics, out / "trajectory.png", max_periods=5,
                        title=f"{exc.amplitude * 1e3:g} mm, {exc.frequency:g} Hz, "
                              f"e = {result.scene.contact.restitution:g}")
        written.append(out / "trajectory.png")
    return written


def world_if_parallel():
    """``MPI.COMM_WORLD`` when started by mpirun with several ranks, else None
    (a serial run never initialises MPI before it needs a field solve)."""
    import os

    launched = any(k in os.environ for k in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"))
    if not launched:
        return None
    from mpi4py import MPI
    return MPI.COMM_WORLD if MPI.COMM_WORLD.size > 1 else None


def print_summary(summary: dict) -> None:
    p2p = summary["peak_to_peak"]
    regime = summary.get("regime") or {}
    print(f"regime: {regime.get('regime', '?')} (period {regime.get('period', '?')}, "
          f"max gap {1e3 * (regime.get('max_gap_m') or 0):.3g} mm)")
    print(f"peak-to-peak ({summary['reference']} reference, {summary['cells']} cell(s)): "
          f"V_OC = {p2p['V_oc_V']:.4g} V, Q_SC = {p2p['Q_sc_C'] * 1e9:.4g} nC, "
          f"I_SC = {p2p['I_sc_A'] * 1e9:.4g} nA")
    if summary.get("load"):
        load = summary["load"]
        print(f"load {summary['circuit']['load_ohm']:.3g} ohm: mean power "
              f"{load['mean_power_W'] * 1e6:.4g} uW, {load['power_density_W_per_m3']:.4g} W/m^3")
    for name, stage in summary["stages"].items():
        print(f"  {name:9s} {stage['status']:8s} {stage['wall_time_s']:7.2f} s  {stage['reason']}")
