"""``tengfield sweep``: peak-to-peak V_OC, Q_SC, I_SC and load power over a grid of
excitations (and loads) and/or any scene keys (paper Figs. 9e-f, S13).

One surrogate per geometry (cached by field hash: points that differ only in σ, the
circuit or the excitation share one), the dynamics at every grid point (in parallel),
peak-to-peak values over the steady window as ``tengfield run`` reports
them and, with --load-ohm, the mean power into each load. Writes
DIR/sweep.csv (one row per point and load) and DIR/sweep.png, or with --vary one
DIR/sweep_<section.key>.png per varied key.

--vary section.key=START:STOP:N (or =v1,v2,...) varies any scene key in its file unit
(repeatable: the product of the values, the first key outermost), with or without the
frequency and amplitude axes: e.g. --vary device.stroke_mm=1:5:9
--vary device.ball_diameter_mm=5:9:5. Each point's scene is built as --set builds one,
so a bad key or value is one line naming the point, the key, the value and the allowed
range, before any work.

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
                      help="peak-to-peak V_OC/Q_SC/I_SC and load power over frequency x "
                           "amplitude and/or any scene key (--vary)")
    grid = {"--frequency-hz": "excitation frequencies [Hz] (linear)",
            "--amplitude-mm": "table amplitudes [mm] (linear)",
            "--load-ohm": "load resistances [ohm] (logarithmic)"}
    for option, values in grid.items():
        p.add_argument(option, default=None, metavar="START:STOP:N",
                       help=f"{values}, or one value")
    p.add_argument("--vary", action="append", default=[], metavar="SECTION.KEY=START:STOP:N",
                   help="vary any scene key in its file unit, e.g. --vary device.stroke_mm=1:5:9 "
                        "or --vary circuit.load_ohm=1e6,1e8 (repeatable: the product; each "
                        "point's scene is checked as --set checks it); one figure per key")
    add_jobs_argument(p)
    add_cache_argument(p)
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip the figures")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..errors import SceneError
    from ..scene import load_scene
    from ..air_breakdown import charge_line, uses_breakdown_charge
    from .._mpi import check_jobs
    from ..sweeps import check_sweep_size, extension_line, parse_vary, sweep_study

    scene = load_scene(args.scene)
    vary = dict(parse_vary(text) for text in args.vary)
    if len(vary) != len(args.vary):
        keys = [parse_vary(text)[0] for text in args.vary]
        twice = next(k for k in keys if keys.count(k) > 1)
        raise SceneError(f"--vary {twice} is given twice: give each key once")
    if not vary and (args.frequency_hz is None or args.amplitude_mm is None):
        missing = "--frequency-hz" if args.frequency_hz is None else "--amplitude-mm"
        raise SceneError(f"sweep needs {missing} (START:STOP:N or one value), or "
                         "--vary section.key=START:STOP:N")
    frequencies = parse_range(args.frequency_hz, "--frequency-hz") \
        if args.frequency_hz is not None else None
    amplitudes = parse_range(args.amplitude_mm, "--amplitude-mm") * 1e-3 \
        if args.amplitude_mm is not None else None
    loads = parse_range(args.load_ohm, "--load-ohm", log=True) if args.load_ohm else ()
    if not vary:
        check_sweep_size(scene, len(frequencies), len(amplitudes), len(loads))
    comm = world_if_parallel()
    check_jobs(args.jobs, comm)
    root = comm is None or comm.rank == 0

    def said(counts, with_tables):       # once the surrogates are at hand (rank 0)
        if not root:
            return
        if vary:
            n = counts["geometries"]
            print(f"surrogates: {n} geometr{'y' if n == 1 else 'ies'} ({counts['computed']} "
                  f"computed, {counts['cached']} cached; {counts['reused']} points reuse "
                  "one)", file=sys.stderr)
        else:
            resolved, table = with_tables[0]
            status = "computed" if counts["computed"] else "cached"
            print(f"surrogate: {status} ({table.count} positions, error estimate "
                  f"{table.interpolation_error:.2g})", file=sys.stderr)
            if uses_breakdown_charge(scene):
                print(charge_line(resolved), file=sys.stderr)
        if frequencies is not None:
            longer = extension_line(scene, frequencies)
            if longer:
                print(longer, file=sys.stderr)

    # every point checked on every rank before any work (in sweep_study); a missing
    # surrogate is computed over the ranks, rank 0 writes the cache
    result = sweep_study(scene, vary=vary, frequencies=frequencies, amplitudes=amplitudes,
                         loads=loads, cache_dir=args.cache_dir, jobs=args.jobs, comm=comm,
                         progress=True, command_line=command_line(), on_surrogates=said)
    if not root:
        return 0
    written = result.write(Path(args.output), plots=not args.no_plots)
    print(f"{len(result)} rows; wrote {', '.join(map(str, written))}")
    return 0
