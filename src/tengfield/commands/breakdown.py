"""``tengfield breakdown``: the largest charge density the device can hold before the air
in its gaps breaks down (Paschen), from the field of every sampled ball position.

Writes DIR/breakdown.json (sigma_max, where and in which circuit state it binds, the gap
length and voltage there, the Paschen constants, pressure and the error estimate),
DIR/breakdown.csv (per sampled position, state and gap: the most critical line's length,
gap voltage per unit sigma, V_b, margin) and DIR/breakdown.png. The field solves are
those of the surrogate (cached: no solve when it exists).
"""
from __future__ import annotations

from .._mpi import world_if_parallel
from ._common import add_cache_argument, command_line, scene_command


def register(sub) -> None:
    p = scene_command(sub, "breakdown", output="breakdown-out", description=__doc__,
                      help="air-breakdown limit of the surface charge density (Paschen)")
    add_cache_argument(p)
    p.add_argument("--states", choices=("scene", "all"), default="scene",
                   help="circuit states checked: those the scene's [circuit] implies "
                        "(default) or all (open, open-top, short)")
    p.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                   help="skip breakdown.png")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from pathlib import Path

    from .. import air_breakdown
    from ..scene import load_scene

    comm = world_if_parallel()
    states = air_breakdown.STATES if args.states == "all" else None
    result = air_breakdown.study(load_scene(args.scene), states=states, cache_dir=args.cache_dir,
                                   comm=comm, progress=True, command_line=command_line())
    if comm is not None and comm.rank != 0:
        return 0
    written = result.write(Path(args.output), plots=not args.no_plots)
    scene, outcome = result.scene, result.field_outcome
    for line in air_breakdown.summary_lines(result, scene, result.band):
        print(line)
    print(f"field: {outcome.status} ({outcome.wall_time:.2f} s), {outcome.path}")
    print("wrote " + ", ".join(str(p) for p in written))
    return 0
