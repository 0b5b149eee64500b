"""``tengfield uncertainty``: the scene's outputs with prediction bands, and which input
decides their spread (issue #34).

The scene's [uncertainty] section gives the sample count N, the method ("sobol":
Saltelli sampling with first-order and total Sobol indices, N (D + 2) evaluations;
"monte-carlo": N quasi-random points for intervals only) and the seed;
[uncertainty.vary] maps scene keys ("contact.restitution") to distributions. Writes
DIR/uncertainty.csv (one row per evaluation), DIR/uncertainty.json (statistics, Sobol
indices, regime fractions, field solves) and DIR/uncertainty.png, and prints the nominal
value, median and 90 % interval of each main output with its dominant input.

σ and circuit keys rerun only the electrical stage; excitation and contact keys the
dynamics; geometry keys one field solve per distinct geometry (cached). Under
``mpirun -n N tengfield uncertainty ...`` the evaluations are farmed over the ranks and
rank 0 writes; on one machine --jobs worker processes share them. The files do not
depend on how the work was spread.
"""
from __future__ import annotations

import sys
import warnings

from ._common import add_cache_argument, add_jobs_argument, scene_command


def register(sub) -> None:
    p = scene_command(sub, "uncertainty", output="uncertainty-out", description=__doc__,
                      help="prediction intervals and Sobol sensitivity over [uncertainty.vary]")
    add_jobs_argument(p)
    add_cache_argument(p)
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip uncertainty.png")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from .._mpi import check_jobs, world_if_parallel
    from ..scene import load_scene
    from ..uncertainty_study import run_study, uncertainty_spec
    from ..uncertainty_study.output import summary_lines

    from ..uncertainty_study.spec import default_uncertainty_section

    scene = load_scene(args.scene)
    comm = world_if_parallel()
    if "uncertainty" not in scene.raw:   # e.g. the default scene: a default study, said once
        section, said = default_uncertainty_section(scene)
        scene = scene.with_values(uncertainty=section)
        if comm is None or comm.rank == 0:
            print(f"tengfield: {said}", file=sys.stderr)
    spec = uncertainty_spec(scene)
    check_jobs(args.jobs, comm)
    root = comm is None or comm.rank == 0
    study = run_study(scene, spec, comm=comm, jobs=args.jobs, cache_dir=args.cache_dir,
                      progress=True)
    if not root:
        return 0
    for category, message in study.evaluations.warnings:
        warnings.warn(message, category, stacklevel=1)
    from ..uncertainty_study.output import nominal_outside_warnings

    for message in nominal_outside_warnings(study):
        warnings.warn(message, RuntimeWarning, stacklevel=1)
    written = study.write(args.output, plots=not args.no_plots)
    for line in summary_lines(study):
        print(line)
    print(f"wrote {', '.join(map(str, written))}", file=sys.stderr)
    return 0
