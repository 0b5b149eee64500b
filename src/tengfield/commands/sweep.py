"""``tengfield sweep``: peak-to-peak V_OC, Q_SC, I_SC and load power over a grid of
excitations (and loads) with one surrogate (paper Figs. 9e-f, S13).

One surrogate (cached), the dynamics at every grid point (in parallel),
peak-to-peak values over the steady window as ``tengfield run`` reports
them and, with --load-ohm, the mean power into each load. Writes
DIR/sweep.csv and DIR/sweep.png.

On one machine --jobs worker processes share the points. Under
``mpirun -n N tengfield sweep ...`` the points are farmed over the N ranks
(dynamic schedule; the rows equal a serial run's) and rank 0 writes the
files; --jobs must then be omitted or 1.
"""
from __future__ import annotations

import sys
from pathlib import Path

from .._mpi import world_if_parallel
from ._common import add_cache_argument, add_jobs_argument, command_line, scene_command
from ._ranges import parse_range


def register(sub) -> None:
    p = scene_command(sub, "sweep", output="sweep-out", description=__doc__,
                      help="peak-to-peak V_OC/Q_SC/I_SC and load power over frequency x amplitude")
    grid = {"--frequency-hz": "excitation frequencies [Hz] (linear)",
            "--amplitude-mm": "table amplitudes [mm] (linear)",
            "--load-ohm": "load resistances [ohm] (logarithmic)"}
    for option, values in grid.items():
        p.add_argument(option, required=option != "--load-ohm", default=None,
                       metavar="START:STOP:N", help=f"{values}, or one value")
    add_jobs_argument(p)
    add_cache_argument(p)
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip sweep.png")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..io import atomic_path, write_sweep_csv
    from ..plotting.waveforms import plot_sweep
    from ..scene import load_scene
    from ..breakdown import charge_line, obtain_run_table, uses_breakdown_charge
    from .._mpi import check_jobs
    from ..sweep import check_grid, check_sweep_size, extension_line, sweep

    scene = load_scene(args.scene)
    frequencies = parse_range(args.frequency_hz, "--frequency-hz")
    amplitudes = parse_range(args.amplitude_mm, "--amplitude-mm") * 1e-3
    loads = parse_range(args.load_ohm, "--load-ohm", log=True) if args.load_ohm else ()
    check_sweep_size(scene, len(frequencies), len(amplitudes), len(loads))
    check_grid(scene, frequencies, amplitudes)      # before the surrogate is computed
    comm = world_if_parallel()
    check_jobs(args.jobs, comm)
    root = comm is None or comm.rank == 0
    # a missing surrogate is computed by the same farm; rank 0 writes the cache; the
    # scene and table at the charge it runs with ("breakdown": -sigma_max)
    at_limit = uses_breakdown_charge(scene)
    scene, table, outcome, _ = obtain_run_table(scene, cache_dir=args.cache_dir, comm=comm,
                                                progress=True, command_line=command_line())
    if root:
        print(f"surrogate: {outcome.status} ({table.count} positions, error estimate "
              f"{table.interpolation_error:.2g})", file=sys.stderr)
        if at_limit:
            print(charge_line(scene), file=sys.stderr)
        longer = extension_line(scene, frequencies)
        if longer:
            print(longer, file=sys.stderr)
    rows = sweep(scene, table, frequencies, amplitudes, loads, jobs=args.jobs, comm=comm,
                 progress=True)
    if not root:
        return 0
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    write_sweep_csv(out / "sweep.csv", rows)
    written = [out / "sweep.csv"]
    if not args.no_plots:
        with atomic_path(out / "sweep.png") as tmp:
            plot_sweep(rows, tmp)
        written.append(out / "sweep.png")
    print(f"{len(rows)} rows; wrote {', '.join(map(str, written))}")
    return 0
