"""``tengfield precompute``: the field surrogate of a scene (HDF5), MPI task farm.

``mpirun -n N tengfield precompute SCENE`` spreads the field solves over the
ranks (each solve on COMM_SELF); rank 0 writes the file.
"""
from __future__ import annotations

from pathlib import Path

from ._common import add_cache_argument, command_line, world_if_parallel


def register(sub) -> None:
    p = sub.add_parser(
        "precompute", help="field solves over the stroke -> surrogate file (HDF5, cached)",
        description="Solve the electrostatics at Chebyshev-Lobatto ball positions, refining "
                    "until the held-out interpolation error is below [field] tolerance, and "
                    "write the surrogate (HDF5). Without -o the file goes to the cache that "
                    "`tengfield run` reads; an existing valid cache entry is kept unless --force.")
    p.add_argument("scene", nargs="?", help="scene file (default: the embedded default scene)")
    p.add_argument("-o", "--output", default=None, metavar="FILE",
                   help="write the surrogate to FILE instead of the cache")
    add_cache_argument(p)
    p.add_argument("--force", action="store_true", help="recompute even if cached")
    p.add_argument("--max-positions", type=int, default=None, metavar="N",
                   help="stop refining at N positions (2^k + 1; default 65)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from .. import surrogate
    from ..errors import SceneError
    from ..scene import load_scene

    scene = load_scene(args.scene)
    comm = world_if_parallel()
    rank = 0 if comm is None else comm.rank
    max_positions = args.max_positions or surrogate.MAX_POSITIONS
    if max_positions < 17:
        raise SceneError(f"--max-positions = {max_positions} is out of range: allowed >= 17")
    target = Path(args.output) if args.output else surrogate.cache_path(scene, args.cache_dir)
    if not args.force and args.output is None and target.exists():
        try:
            table = surrogate.read_table(target, expected_hash=scene.field_hash(),
                                        expected_solver=surrogate.solver_fingerprint())
        except surrogate.SurrogateError as exc:
            if rank == 0:
                print(f"tengfield: cached surrogate not trusted ({exc}); recomputing")
        else:
            if rank == 0:
                print(f"cached: {target} ({table.count} positions, error estimate "
                      f"{table.interpolation_error:.2g}); use --force to recompute")
            return 0
    table = surrogate.precompute(scene, comm=comm, progress=True, max_positions=max_positions,
                                 command_line=command_line())
    if rank == 0:
        surrogate.write_table(target, table)
        print(f"{table.count} positions, interpolation error estimate "
              f"{table.interpolation_error:.3g} (tolerance {table.tolerance:g}, "
              f"{'converged' if table.converged else 'NOT converged'}), "
              f"sum of solve times {table.total_solve_wall_time:.1f} s")
        print(f"wrote {target}")
    return 0
