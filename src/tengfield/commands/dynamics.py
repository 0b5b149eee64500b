"""``tengfield dynamics`` (one trajectory) and ``tengfield map`` (regime map).

Neither imports dolfinx or gmsh.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from ..errors import SceneError
from ._common import scene_command
from ._ranges import number_text, parse_range


def register(sub) -> None:
    p = scene_command(sub, "dynamics", output="dynamics-out",
                      help="simulate the ball's motion (impact map or soft contact)",
                      description="Writes trajectory.csv, impacts.csv, summary.json and "
                                  "trajectory.png to DIR (3D motion: also contacts.csv and "
                                  "trajectory3d.png).")
    p.add_argument("--duration-s", type=float, default=None,
                   help="simulated time [s] (default: [run] duration_s)")
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip the PNG files (the CSVs and summary.json are written)")
    p.set_defaults(func=_run_dynamics, one_process="one trajectory; `tengfield map` spreads "
                                                   "many over the ranks")

    m = scene_command(sub, "map", output="map-out", help="regime map over frequency x amplitude",
                      description="Writes map.csv and map.png to DIR. Ranges are START:STOP:N "
                                  "(N evenly spaced values, both ends included).")
    m.add_argument("--frequency-hz", required=True, metavar="START:STOP:N",
                   help="table frequencies [Hz], e.g. 5:70:100")
    m.add_argument("--amplitude-mm", required=True, metavar="START:STOP:N",
                   help="table amplitudes [mm], e.g. 0.1:5:100")
    m.add_argument("--periods", type=int, default=200,
                   help="excitation periods simulated per point (default 200)")
    m.add_argument("--jobs", "-j", type=int, default=None,
                   help="worker processes (default: all cores)")
    m.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip map.png")
    m.set_defaults(func=_run_map)


def _run_dynamics(args) -> int:
    from contextlib import nullcontext

    from ..plotting.process import FigureProcess

    # matplotlib loads in a second process while this one simulates
    with FigureProcess() if not args.no_plots else nullcontext() as figures:
        return _dynamics(args, figures)


def _dynamics(args, figures) -> int:
    from ..dynamics import simulate
    from ..scene import load_scene
    from ..scene.limits import check_steady_window

    scene = load_scene(args.scene)
    if args.duration_s is not None:
        if not (args.duration_s > 0 and math.isfinite(args.duration_s)):
            raise SceneError(f"--duration-s = {args.duration_s!r}: allowed (0, inf)")
        check_steady_window(scene.excitation, scene.run.settle_periods, args.duration_s,
                            name="--duration-s")
        try:   # the scene of that length: a noise record is drawn for it, its limits hold
            scene = scene.with_values(run={"duration_s": args.duration_s})
        except SceneError as exc:
            raise SceneError(f"--duration-s = {number_text(args.duration_s)}: {exc}") from None
    result = simulate(scene)
    out = Path(args.output)
    result.write(out, plots=not args.no_plots, figures=figures)
    summary = result.summary
    if figures is not None:
        figures.finish()
    from ..dynamics.regime import regime_label

    label = regime_label(summary["regime"], summary["period"],
                         settled_by_s=summary.get("settled_by_s"),
                         checked_to_s=summary.get("regime_checked_to_s") or 0.0,
                         duration_s=summary.get("duration_s"))
    print(f"regime {label}, max gap "
          f"{summary['max_gap_mm']:.4g} mm, {summary['impacts']} impacts, "
          f"{summary['wall_time_s']:.3g} s -> {out}/")
    from ..dynamics.regime import contacts_text

    print(contacts_text(summary["lower_contacts_per_period"],
                        summary["upper_contacts_per_period"], summary["period"]))
    return 0


def _run_map(args) -> int:
    import numpy as np

    from .._mpi import check_jobs, rank_of, world_if_parallel
    from ..dynamics import regime_map
    from ..dynamics.mapping import check_map_size
    from ..scene import load_scene

    scene = load_scene(args.scene)
    comm = world_if_parallel()
    from ..dynamics.excitation import excitation_kind

    if not excitation_kind(scene).periodic and rank_of(comm) == 0:
        import warnings
        warnings.warn(f"map: [excitation] kind = {scene.excitation.kind!r} is not used: every "
                      f"grid point is a sine of that frequency and amplitude (the device's "
                      f"regime map)", RuntimeWarning, stacklevel=1)
    freqs = list(parse_range(args.frequency_hz, "--frequency-hz"))
    amps_mm = list(parse_range(args.amplitude_mm, "--amplitude-mm", positive=False))
    check_map_size(len(freqs) * len(amps_mm), args.periods)   # before any work
    check_jobs(args.jobs, comm)
    result = regime_map(scene, np.array(freqs), np.array(amps_mm) * 1e-3, jobs=args.jobs,
                        progress=sys.stderr.isatty(), periods=args.periods, comm=comm)
    if comm is not None and comm.rank != 0:      # every rank holds the map; rank 0 writes
        return 0
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    result.write(out, plots=not args.no_plots)
    from ..dynamics.regime import regime_table
    from ..dynamics.result import REGIMES

    counts = {str(n): int(np.sum(result.regime == n)) for n in np.unique(result.regime)}
    print(f"{result.regime.size} points: {out}/")
    print(regime_table(counts, REGIMES))
    return 0
