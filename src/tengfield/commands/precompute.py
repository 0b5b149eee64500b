"""``tengfield precompute``: the field surrogate of a scene (HDF5), MPI task farm.

``mpirun -n N tengfield precompute SCENE`` spreads the field solves over the
ranks (each solve on COMM_SELF); rank 0 decides whether the cache holds a
trusted file (and tells the others) and writes the file.
"""
from __future__ import annotations

from pathlib import Path

from .._mpi import world_if_parallel
from ._common import add_cache_argument, command_line, scene_command

#: --max-positions may not exceed this (2^10 + 1 field solves)
MAX_POSITIONS_LIMIT = 1025


def register(sub) -> None:
    from ..surrogate import FEWEST_POSITIONS, MAX_POSITIONS

    p = scene_command(
        sub, "precompute", output=None,
        help="field solves over the stroke -> surrogate file (HDF5, cached)",
        description="Solve the electrostatics at Chebyshev-Lobatto ball positions, refining "
                    "until the held-out interpolation error is below [field] tolerance, and "
                    "write the surrogate (HDF5). Without -o the file goes to the cache that "
                    "`tengfield run` reads; an existing valid cache entry is kept unless --force.")
    p.add_argument("-o", "--output", default=None, metavar="FILE",
                   help="write the surrogate to FILE instead of the cache")
    add_cache_argument(p)
    p.add_argument("--force", action="store_true", help="recompute even if cached")
    p.add_argument("--max-positions", type=int, default=None, metavar="N",
                   help=f"stop refining at N positions ({FEWEST_POSITIONS} <= N <= "
                        f"{MAX_POSITIONS_LIMIT}; default {MAX_POSITIONS})")
    p.set_defaults(func=_run)


def check_max_positions(value: int | None) -> int:
    """``--max-positions`` (None: the default), or a one-line SceneError naming the range."""
    from ..errors import SceneError
    from ..surrogate import FEWEST_POSITIONS, MAX_POSITIONS

    if value is None:
        return MAX_POSITIONS
    if not FEWEST_POSITIONS <= value <= MAX_POSITIONS_LIMIT:
        raise SceneError(f"--max-positions = {value} is out of range: allowed "
                         f"{FEWEST_POSITIONS} <= N <= {MAX_POSITIONS_LIMIT}")
    return int(value)


def _run(args) -> int:
    from .. import surrogate
    from ..files.directory import ensure_file_parent
    from ..scene import load_scene

    scene = load_scene(args.scene)
    max_positions = check_max_positions(args.max_positions)
    comm = world_if_parallel()
    rank = 0 if comm is None else comm.rank
    option = "-o" if args.output is not None else "--cache-dir"
    # "" is refused by ensure_file_parent, not taken for "no -o"
    target = args.output if args.output is not None else surrogate.cache_path(scene,
                                                                              args.cache_dir)
    problem = None
    if rank == 0:   # checked once, before any solve; every rank stops alike
        try:
            ensure_file_parent(target, option=option)
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank
            problem = exc
    if comm is not None:
        problem = comm.bcast(problem, root=0)
    if problem is not None:
        raise problem
    target = Path(target)
    if not args.force and args.output is None:
        table, status, _ = surrogate.load_cached(target, scene, comm)   # rank 0 decides
        if table is not None:
            if rank == 0:
                print(f"already cached, nothing solved: {target} ({table.count} positions, "
                      f"error estimate {table.interpolation_error:.2g}) is the surrogate "
                      f"`tengfield run` of this scene reads; a scene of another geometry or "
                      f"other [field] settings is solved and cached (e.g. --set "
                      f"device.ball_diameter_mm=...), --force solves this one again")
            return 0
    table = surrogate.precompute(scene, comm=comm, progress=True, max_positions=max_positions,
                                 command_line=command_line())
    if rank == 0:
        # again: a FIFO or device node put there during the solves is not replaced either
        ensure_file_parent(target, option=option)
        surrogate.write_table(target, table)
        print(f"{table.count} positions, interpolation error estimate "
              f"{table.interpolation_error:.3g} (tolerance {table.tolerance:g}, "
              f"{'converged' if table.converged else 'NOT converged'}), "
              f"sum of solve times {table.total_solve_wall_time:.1f} s")
        placed = (table.provenance or {}).get("mesh_placements")
        if placed and placed.get("moved"):   # [field] mesh_motion = "move" (issue #40)
            mapped = (f", {placed['mapped']} reference meshes mapped from another "
                      "geometry's" if placed.get("mapped") else "")
            print(f"meshes: {placed['moved']} positions moved with the ball, "
                  f"{placed['meshed']} gmsh meshings{mapped}")
        print(f"wrote {target}")
    return 0
