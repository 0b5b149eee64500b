"""``tengfield run``: dynamics -> surrogate (cached) -> circuit, end to end.

Writes DIR/waveforms.csv, DIR/summary.json, DIR/waveforms.png,
DIR/surrogate.png and the dynamics' trajectory.csv, impacts.csv and
trajectory.png. Under ``mpirun -n N`` the field solves (if the surrogate
is not cached) are spread over the ranks; rank 0 writes every file.
"""
from __future__ import annotations

from ._common import add_cache_argument, command_line, scene_command, world_if_parallel


def register(sub) -> None:
    p = scene_command(sub, "run", output="out", description=__doc__,
                      help="V_OC, Q_SC, I_SC (and load) waveforms of a scene, end to end")
    add_cache_argument(p)
    p.add_argument("--no-plots", action="store_true", help="skip the PNG files")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..io import write_dynamics_outputs, write_run_outputs
    from ..pipeline import run
    from ..scene import load_scene

    scene = load_scene(args.scene)
    comm = world_if_parallel()
    result = run(scene, comm=comm, cache_dir=args.cache_dir, progress=True,
                 command_line=command_line())
    if comm is None or comm.rank == 0:
        written = write_run_outputs(result, args.output, plots=not args.no_plots)
        written += write_dynamics_outputs(result, args.output, plots=not args.no_plots)
        print_summary(result.summary)
        print("wrote " + ", ".join(str(p) for p in written))
    return 0


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
