"""Memory per field solve in a long-running process (issue #40): a process that solves
position after position (a remeshed design, a sweep) must not keep what each solve
made. Solves the default tube at 1 mm (estimate on: two meshes a solve) for geometries
that change every time (the ball's diameter in steps of 0.04 mm), and prints the
resident memory after every ten and the growth per solve.

    .venv/bin/python benchmarks/solve_memory.py [--solves 60] [--mesh-motion remesh|move]

With ``move`` the growth includes the canonical templates kept for mapping
(field/moving.py, at most MAX_TEMPLATES).
"""
from __future__ import annotations

import argparse
import gc
import warnings


def resident_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--solves", type=int, default=60)
    ap.add_argument("--mesh-motion", choices=("remesh", "move"), default="remesh")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    from mpi4py import MPI

    from tengfield.field import moving, solve_position
    from tengfield.scene import default_scene

    scene = default_scene().with_values(field={"mesh_size_mm": 1.0,
                                               "mesh_motion": args.mesh_motion})
    first = None
    for i in range(args.solves + 1):
        candidate = scene.with_values(device={"ball_diameter_mm": 5.0 + 0.04 * (i % 70)})
        solve_position(candidate, 1.0e-3, comm=MPI.COMM_SELF, estimate_error=True)
        moving.release_references()
        if i % 10 == 0:
            gc.collect()
            now = resident_mb()
            first = now if first is None else first
            print(f"after {i + 1:4d} solves: {now:7.1f} MB resident", flush=True)
    print(f"growth: {(now - first) / args.solves:.2f} MB per solve "
          f"({args.mesh_motion}, {args.solves} solves after the first)")


if __name__ == "__main__":
    main()
