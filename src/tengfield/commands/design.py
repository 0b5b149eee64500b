"""``tengfield design``: the device geometry that serves the scene's [design] band best.

Scores candidates of the [design.vary] box (each with its own field surrogate, cached
by field hash, on the design's coarse stated field settings) on every band point of
[design.excitation], with a space-filling start and shrinking boxes around the best.
Writes DIR/design.csv (every candidate), DIR/design.json (best, ranking, error bars,
settings, wall time), DIR/design.png and DIR/best.toml (ready for `tengfield run`).

On one machine --jobs worker processes share each round's candidates. Under
``mpirun -n N tengfield design ...`` they are farmed over the N ranks (the result
equals a serial run's) and rank 0 writes the files; --jobs must then be omitted or 1.
"""
from __future__ import annotations

import sys

from .._mpi import world_if_parallel
from ._common import add_cache_argument, add_jobs_argument, scene_command


def register(sub) -> None:
    p = scene_command(sub, "design", output="design-out", description=__doc__,
                      help="search the [design.vary] geometry for the best objective over a band")
    p.add_argument("--candidates", type=int, default=None, metavar="N",
                   help="evaluation budget (overrides [design] candidates)")
    p.add_argument("--seed", type=int, default=None, metavar="N",
                   help="search seed (overrides [design] seed)")
    add_jobs_argument(p)
    add_cache_argument(p)
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip design.png")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..design import design, parse_design_section, write_design_outputs
    from ..design.spec import OBJECTIVES
    from ..scene import load_scene

    scene = load_scene(args.scene)
    overrides = {k: v for k, v in (("candidates", args.candidates), ("seed", args.seed))
                 if v is not None}
    parse_design_section(scene, overrides)        # bad [design] input: before any work
    comm = world_if_parallel()
    result = design(scene, comm=comm, jobs=args.jobs, cache_dir=args.cache_dir,
                    progress=True, overrides=overrides or None)   # SIGTERM: cli.py
    if comm is not None and comm.rank != 0:
        return 0
    written = write_design_outputs(result, args.output, plots=not args.no_plots)
    counts = {s: sum(r["status"] == s for r in result.rows) for s in ("ok", "infeasible",
                                                                       "skipped")}
    print(f"{len(result.rows)} candidates ({counts['ok']} scored, {counts['infeasible']} "
          f"infeasible, {counts['skipped']} skipped) in {result.wall_time:.1f} s on "
          f"{result.ranks} rank(s)", file=sys.stderr)
    best = result.best
    if best is None:
        print("no candidate is feasible: see design.csv (reason)")
    else:
        unit = OBJECTIVES[result.spec.objective][0]
        conf = result.confidence()
        print(f"best: " + ", ".join(f"{k} = {v:g}" for k, v in best["values"].items())
              + f": {result.spec.objective} = {best['objective']:.4g} +- "
              f"{best['objective_error']:.2g} {unit} ({result.spec.aggregate} over "
              f"{len(result.spec.band)} band point{'s' * (len(result.spec.band) != 1)})")
        if "margin_over_error_bars" in conf:
            print(f"runner-up #{conf['runner_up_index']}: margin {conf['margin']:.3g} {unit} = "
                  f"{conf['margin_over_error_bars']:.3g} x the error bars; "
                  f"{conf['candidates_within_error_bars']} candidate(s) within the error bars")
    print("wrote " + ", ".join(map(str, written)))
    return 0
