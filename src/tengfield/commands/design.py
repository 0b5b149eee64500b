"""``tengfield design``: the device geometry that serves the scene's [design] band best.

Scores candidates of the [design.vary] box (each with its own field surrogate, cached
by field hash, on the design's coarse stated field settings) on every band point of
[design.excitation], with a space-filling start and shrinking boxes around the best.
Writes DIR/design.csv (every candidate), DIR/design.json (best, ranking, error bars,
settings, wall time), DIR/design.png and DIR/best.toml (ready for `tengfield run`).

A scene without [design] (e.g. the one `tengfield scene --default` writes) gets a default
study, said in one line: the stroke stroke_mm over 0.5-1.5 x and the ball diameter over
0.7-1.3 x the scene's values (tube and electrode follow the ball; a spherical shell: its
cavity over 0.8-1.2 x and the ball), at the scene's excitation, 24 candidates.

The answer (stdout): the best design and the runner-up, with the plate spacing (a
shell: its stroke), what
followed, σ, the load and the band table; warnings (stderr) name a band point where
nothing moves, an optimum on a bound of its range, a tie, chaos in the best design.
Progress (done/total, ETA, current best) on a terminal; --quiet or a pipe: none.

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
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no progress display (it is off anyway when stderr is not a terminal)")
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip design.png")
    p.set_defaults(func=_run)


def _run(args) -> int:
    import warnings

    from ..design_study import design, parse_design_section
    from ..design_study.answer import answer_lines
    from ..design_study.spec import default_design_section
    from ..scene import load_scene

    scene = load_scene(args.scene)
    overrides = {k: v for k, v in (("candidates", args.candidates), ("seed", args.seed))
                 if v is not None}
    comm = world_if_parallel()
    if "design" not in scene.raw:   # e.g. the default scene: a default study, said once
        section, said = default_design_section(scene, args.candidates)
        scene = scene.with_values(design=section)
        if comm is None or comm.rank == 0:
            print(f"tengfield: {said}", file=sys.stderr)
    parse_design_section(scene, overrides)        # bad [design] input: before any work
    result = design(scene, comm=comm, jobs=args.jobs, cache_dir=args.cache_dir,
                    progress=not args.quiet, overrides=overrides or None)   # SIGTERM: cli.py
    if comm is not None and comm.rank != 0:
        return 0
    written = result.write(args.output, plots=not args.no_plots)
    counts = {s: sum(r["status"] == s for r in result.rows) for s in ("ok", "infeasible",
                                                                       "skipped")}
    print(f"{len(result.rows)} candidates ({counts['ok']} scored, {counts['infeasible']} "
          f"infeasible, {counts['skipped']} skipped) in {result.wall_time:.1f} s on "
          f"{result.ranks} rank(s)", file=sys.stderr)
    print("\n".join(answer_lines(result)))
    from ..design_study.answer import breakdown_band_lines   # issue #38
    for line in breakdown_band_lines(result, result.breakdown_band()):
        print(line)
    sys.stdout.flush()
    from ..design_study.answer import design_warnings
    for text in design_warnings(result):    # one `tengfield: warning: ...` line each
        warnings.warn(text, UserWarning, stacklevel=1)
    print("wrote " + ", ".join(map(str, written)))
    return 0
