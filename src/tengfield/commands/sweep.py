"""``tengfield sweep``: peak-to-peak V_OC, Q_SC, I_SC and load power over a grid of
excitations (and loads) with one surrogate (paper Figs. 9e-f, S13).

One surrogate (cached), the dynamics at every grid point (in parallel),
peak-to-peak values over the steady window as ``tengfield run`` reports
them and, with --load-ohm, the mean power into each load. Writes
DIR/sweep.csv and DIR/sweep.png.
"""
from __future__ import annotations

import sys
from pathlib import Path

from ._common import add_cache_argument, command_line, scene_command
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
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    add_cache_argument(p)
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..io import write_sweep_csv
    from ..plotting.waveforms import plot_sweep
    from ..scene import load_scene
    from ..surrogate import obtain_table
    from ..sweep import sweep

    scene = load_scene(args.scene)
    frequencies = parse_range(args.frequency_hz, "--frequency-hz")
    amplitudes = parse_range(args.amplitude_mm, "--amplitude-mm") * 1e-3
    loads = parse_range(args.load_ohm, "--load-ohm", log=True) if args.load_ohm else ()
    table, outcome = obtain_table(scene, cache_dir=args.cache_dir, progress=True,
                                  command_line=command_line())
    print(f"surrogate: {outcome.status} ({table.count} positions, error estimate "
          f"{table.interpolation_error:.2g})", file=sys.stderr)
    rows = sweep(scene, table, frequencies, amplitudes, loads, jobs=args.jobs, progress=True)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    write_sweep_csv(out / "sweep.csv", rows)
    plot_sweep(rows, out / "sweep.png")
    print(f"{len(rows)} rows; wrote {out / 'sweep.csv'}, {out / 'sweep.png'}")
    return 0
