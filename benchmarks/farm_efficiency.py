"""Parallel efficiency of ``tengfield sweep``'s MPI task farm at 2 ranks.

    python benchmarks/farm_efficiency.py [--frequencies 20] [--amplitudes 10] [--ranks 2]

Times the grid of :func:`tengfield.sweeps.sweep` (default scene, its cached
surrogate, loads 1e6/1e8/1e10 ohm) once serially in this process and once
under ``mpirun -n RANKS`` (this file with ``--worker``), both after a warm-up
point per process (numba and import caches loaded) and without the
interpreter start-up. Prints:

* wall times T1, TN and the parallel efficiency ``T1 / (N TN)``;
* CPU time (user + sys) of the timed part: serial, and summed over the ranks
  (work the farm adds, or contention on a shared machine, shows here);
* the schedule efficiency ``sum of point times / (N x busiest rank's time)``
  of the dynamic schedule (1 = perfectly balanced) and the farm efficiency
  (share of the ranks' wall time spent inside the points, the rest is MPI and
  waiting); times the ratio of the CPU time inside the points (serial / all
  ranks: what running N ranks side by side costs each point) it is what the
  wall-clock efficiency comes to on an idle machine;
* the machine's load average (other jobs make the wall clock meaningless),
  and whether the rows equal the serial ones exactly.
"""
from __future__ import annotations

import argparse
import os
import pickle
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

LOADS = (1e6, 1e8, 1e10)


def _grid(args):
    return np.linspace(15.0, 40.0, args.frequencies), np.linspace(0.5e-3, 2.5e-3, args.amplitudes)


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _timed_point(task):
    from tengfield import sweeps as sweep

    start, cpu = time.perf_counter(), time.process_time()
    rows = sweep.sweep_point(*task)
    return rows, (time.perf_counter() - start, time.process_time() - cpu)


def _measure(comm, args):
    """(rows, wall [s], cpu [s] of this process, (wall, cpu) [s] of each point it ran)."""
    from tengfield import sweeps as sweep
    from tengfield.scene import default_scene
    from tengfield.surrogate import obtain_table

    scene = default_scene()
    table, _ = obtain_table(scene, comm=comm)
    frequencies, amplitudes = _grid(args)
    tasks = [(scene, table, float(f), float(a), LOADS) for f in frequencies for a in amplitudes]
    sweep.sweep_point(scene, table, 20.0, 1.5e-3, LOADS)           # warm-up
    mine = []

    def work(task):
        rows, seconds = _timed_point(task)
        mine.append(seconds)
        return rows

    if comm is not None:
        comm.Barrier()
    cpu, start = _cpu(), time.perf_counter()
    results = sweep.run_tasks(work, tasks, comm=comm, jobs=1)
    if comm is not None:
        comm.Barrier()
    wall, cpu = time.perf_counter() - start, _cpu() - cpu
    return [row for rows in results for row in rows], wall, cpu, mine


def worker(args) -> None:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    rows, wall, cpu, mine = _measure(comm, args)
    parts = comm.gather((cpu, mine), root=0)
    if comm.rank == 0:
        with open(args.worker, "wb") as fh:
            pickle.dump({"rows": rows, "wall": wall, "cpu": [p[0] for p in parts],
                         "points": [p[1] for p in parts]}, fh)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frequencies", type=int, default=20)
    parser.add_argument("--amplitudes", type=int, default=10)
    parser.add_argument("--ranks", type=int, default=2)
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args)
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    n = args.ranks
    load_before = os.getloadavg()[0]
    rows1, t1, cpu1, points1 = _measure(None, args)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "mpi.pickle"
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1")
        subprocess.run(["mpirun", "-n", str(n), sys.executable, __file__, "--worker", str(out),
                        "--frequencies", str(args.frequencies), "--amplitudes",
                        str(args.amplitudes)], check=True, env=env, timeout=3600)
        par = pickle.loads(out.read_bytes())
    load_after = os.getloadavg()[0]
    tn = par["wall"]
    busy = [sum(w for w, _ in p) for p in par["points"]]
    point_cpu1 = sum(c for _, c in points1)
    point_cpu = sum(c for p in par["points"] for _, c in p)
    count = args.frequencies * args.amplitudes
    print(f"sweep of {count} points x {len(LOADS)} loads, default scene "
          f"(load average {load_before:.1f} before, {load_after:.1f} after; "
          f"{os.cpu_count()} cores)")
    print(f"serial:     {t1:7.2f} s wall, {cpu1:7.2f} s CPU, {t1 / count * 1e3:.1f} ms per point")
    print(f"{n} ranks:    {tn:7.2f} s wall, {sum(par['cpu']):7.2f} s CPU (ranks: "
          + ", ".join(f"{c:.2f}" for c in par["cpu"]) + "), points per rank: "
          + ", ".join(str(len(p)) for p in par["points"]))
    print("time inside the points per rank: " + ", ".join(f"{b:.2f} s" for b in busy)
          + f" of {tn:.2f} s (the rest: MPI, waiting)")
    print(f"parallel efficiency T1 / ({n} T{n}) = {t1 / (n * tn):.1%}  (wall clock)")
    schedule = sum(busy) / (n * max(busy))
    inside = sum(busy) / (n * tn)
    print(f"schedule efficiency (sum of point times / ({n} x busiest rank)) = {schedule:.1%}")
    print(f"farm efficiency (share of the {n} ranks' time spent inside the points) = {inside:.1%}")
    print(f"CPU inside the points: serial {point_cpu1:.2f} s, {n} ranks {point_cpu:.2f} s "
          f"(ratio {point_cpu1 / point_cpu:.1%}); whole timed part: serial {cpu1:.2f} s, "
          f"{n} ranks {sum(par['cpu']):.2f} s")
    print(f"expected on an idle machine (farm efficiency x point CPU ratio) = "
          f"{inside * point_cpu1 / point_cpu:.1%}")
    print(f"rows identical to the serial run: {par['rows'] == rows1}")


if __name__ == "__main__":
    main()
