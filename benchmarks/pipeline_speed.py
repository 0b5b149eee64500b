"""Pipeline speed: cold and warm `tengfield run` on the default scene, and the
parallel efficiency of `tengfield precompute` on 2 ranks.

Targets (issue 4): cold run (surrogate computed) <= 60 s on 2 cores, warm
(cached) <= 3 s, precompute efficiency at 2 ranks >= 80 %. The machine may be
shared: the load average is printed with every figure.

    .venv/bin/python benchmarks/pipeline_speed.py [--scene FILE] [--skip-serial]
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHON = str(ROOT / ".venv" / "bin" / "python")


def env_with(cache: Path) -> dict:
    return dict(os.environ, TENGFIELD_CACHE_DIR=str(cache), MPLBACKEND="Agg",
                OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1")


CPU_SECONDS: dict[str, float] = {}


def timed(cmd, env, cwd, label: str = "") -> float:
    """Wall time [s] of ``cmd``; its CPU time (user + sys, all ranks) goes to CPU_SECONDS."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{proc.stderr[-3000:]}")
    if label:
        CPU_SECONDS[label] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return elapsed


def schedule_efficiency(path: Path, ranks: int) -> float:
    """Load balance of the task farm's dynamic schedule (next job to the first free
    rank, dearest first) on ``ranks`` ranks, from the per-position solve times of a
    serial run: sum / (ranks x sum over levels of the makespan). This is the parallel
    efficiency on an otherwise idle machine, communication neglected."""
    import numpy as np

    from tengfield import surrogate

    table = surrogate.read_table(path)
    stroke = table.stroke
    cost = dict(zip(table.positions.tolist(), table.wall_time.tolist()))
    # the initial set and the first refinement are solved as one batch
    counts = [int(n) for n, _ in table.error_history]
    levels = [np.concatenate([surrogate.lobatto_positions(stroke, counts[0]),
                              surrogate.refinement_positions(stroke, counts[0])])]
    levels += [surrogate.refinement_positions(stroke, n) for n in counts[1:]]
    busiest = total = 0.0
    for level in levels:
        todo = level[level <= 0.5 * stroke * (1 + 1e-12)] if table.provenance.get(
            "mirror_symmetry") else level
        todo = todo[surrogate.contact_first_order(todo, stroke)]
        free_at = np.zeros(ranks)
        for z in todo:
            free_at[np.argmin(free_at)] += cost[float(z)]
            total += cost[float(z)]
        busiest += free_at.max()
    return float(total / (ranks * busiest))


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=None, help="scene file (default: embedded default)")
    parser.add_argument("--skip-serial", action="store_true",
                        help="skip the serial precompute (no efficiency figure)")
    args = parser.parse_args()
    scene = [str(Path(args.scene).resolve())] if args.scene else []
    tengfield = [PYTHON, "-m", "tengfield.cli"]
    work = Path(tempfile.mkdtemp(prefix="tengfield-bench-"))
    results = {"scene": args.scene or "<default>", "uptime_before": uptime()}
    try:
        # warm the JIT caches (numba, FFCx) so that they do not count as "cold"
        warm_cache = work / "jit-cache"
        timed(tengfield + ["run", *scene, "-o", str(work / "o0"), "--no-plots"],
              env_with(warm_cache), work)
        cold = work / "cold-cache"
        results["cold_run_mpirun_2_s"] = timed(
            ["mpirun", "-n", "2", *tengfield, "run", *scene, "-o", str(work / "o1")],
            env_with(cold), work, "cold_run_mpirun_2")
        results["uptime_after_cold"] = uptime()
        results["warm_run_s"] = timed(tengfield + ["run", *scene, "-o", str(work / "o2")],
                                      env_with(cold), work, "warm_run")
        summary = json.loads((work / "o1" / "summary.json").read_text())
        results["positions"] = summary["stages"]["surrogate"]["reason"]
        results["surrogate_error_estimate"] = summary.get("surrogate_error_estimate")
        results["field_stage_s"] = summary["stages"]["field"]["wall_time_s"]
        # precompute: 2 ranks vs serial
        t2 = timed(["mpirun", "-n", "2", *tengfield, "precompute", *scene, "-o",
                    str(work / "p2.h5")], env_with(work / "c2"), work, "precompute_mpirun_2")
        results["precompute_mpirun_2_s"] = t2
        if not args.skip_serial:
            t1 = timed(tengfield + ["precompute", *scene, "-o", str(work / "p1.h5")],
                       env_with(work / "c1"), work, "precompute_serial")
            results["precompute_serial_s"] = t1
            results["parallel_efficiency_2_ranks"] = t1 / (2.0 * t2)
            results["schedule_efficiency_2_ranks"] = schedule_efficiency(work / "p1.h5", 2)
        results.update({f"{k}_cpu_s": v for k, v in CPU_SECONDS.items()})
        results["uptime_after"] = uptime()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    width = max(len(k) for k in results)
    for key, value in results.items():
        shown = f"{value:.4g}" if isinstance(value, float) else value
        print(f"{key:{width}s}  {shown}")


if __name__ == "__main__":
    main()
