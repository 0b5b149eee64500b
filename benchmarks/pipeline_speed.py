"""Pipeline speed: cold and warm `tengfield run` on the default scene, and the
parallel efficiency of `tengfield precompute` on 2 ranks; with ``--cost-split``
instead the per-position cost of a cold surrogate (mesh, assemble, factor,
solve) with the field error estimated at every position and at the sampled
ones only (``precompute(field_error="every" | "sampled")``).

Targets (issue 4): cold run (surrogate computed) <= 60 s on 2 cores, warm
(cached) <= 3 s, precompute efficiency at 2 ranks >= 80 %. The machine may be
shared: the load average is printed with every figure.

    .venv/bin/python benchmarks/pipeline_speed.py [--scene FILE] [--skip-serial]
    .venv/bin/python benchmarks/pipeline_speed.py --cost-split [--scene FILE]
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
    sampled = (surrogate.error_sample_positions(stroke, bool(table.provenance.get(
        "mirror_symmetry")), counts[0]) if "field_error_rule" in table.provenance else ())
    busiest = total = 0.0
    for level in levels:
        todo = level[level <= 0.5 * stroke * (1 + 1e-12)] if table.provenance.get(
            "mirror_symmetry") else level
        todo = todo[surrogate.contact_first_order(todo, stroke, sampled)]
        free_at = np.zeros(ranks)
        for z in todo:
            free_at[np.argmin(free_at)] += cost[float(z)]
            total += cost[float(z)]
        busiest += free_at.max()
    return float(total / (ranks * busiest))


class CostSplit:
    """Wall time [s] of every axisymmetric field solve by phase, per surrogate position.

    Wraps (in this process only) the phases of :mod:`tengfield.field.axisymmetric`:
    ``build_mesh`` (gmsh + conversion: "mesh"), ``discretise`` ("assemble"),
    ``_dolfinx.create_ksp`` (MUMPS analysis + factorisation: "factor") and
    ``_dolfinx.solve`` (forward/back substitution: "solve"); the rest of each
    position's wall time (A P products, potentials -> C and q) is "other". Meshes and
    solves of the error estimate (half mesh size) are counted apart ("estimate").
    """

    PHASES = ("mesh", "assemble", "factor", "solve")

    def __init__(self):
        from tengfield.field import _dolfinx, axisymmetric

        self.modules = (axisymmetric, _dolfinx)
        self.rows: dict[float, dict[str, float]] = {}
        self.position = None
        self.coarse_size = None
        self.fine = False
        self.saved = []

    def _timed(self, module, name, phase):
        original = getattr(module, name)
        self.saved.append((module, name, original))

        def wrapper(*args, **kwargs):
            if phase == "mesh":   # the estimate's mesh has half the scene's mesh size
                self.fine = args[0].field.mesh_size < 0.75 * self.coarse_size
            start = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                key = f"estimate {phase}" if self.fine else phase
                row = self.rows.setdefault(self.position, {})
                row[key] = row.get(key, 0.0) + time.perf_counter() - start
        setattr(module, name, wrapper)

    def __enter__(self):
        axisymmetric, dx_api = self.modules
        outer = axisymmetric.solve_serial
        self.saved.append((axisymmetric, "solve_serial", outer))

        def solve_serial(scene, position, comm, **options):
            self.position, self.coarse_size = float(position), scene.field.mesh_size
            start = time.perf_counter()
            result = outer(scene, position, comm, **options)
            row = self.rows.setdefault(self.position, {})
            row["wall"] = time.perf_counter() - start
            row["solves"] = 3 if "contact_rule" in result.info else 1
            return result
        axisymmetric.solve_serial = solve_serial
        self._timed(axisymmetric, "build_mesh", "mesh")
        self._timed(axisymmetric, "discretise", "assemble")
        self._timed(dx_api, "create_ksp", "factor")
        self._timed(dx_api, "solve", "solve")
        return self

    def __exit__(self, *exc):
        for module, name, original in reversed(self.saved):
            setattr(module, name, original)

    def table(self) -> str:
        keys = [*self.PHASES, *(f"estimate {p}" for p in self.PHASES)]
        lines = [f"{'z [mm]':>8s} {'solves':>6s} " + " ".join(f"{k:>10s}" for k in
                                                           ["wall", *keys, "other"])]
        total = {k: 0.0 for k in ["wall", *keys, "other"]}
        for z in sorted(self.rows):
            row = self.rows[z]
            other = row["wall"] - sum(row.get(k, 0.0) for k in keys)
            values = [row["wall"], *(row.get(k, 0.0) for k in keys), other]
            for k, v in zip(total, values):
                total[k] += v
            lines.append(f"{z * 1e3:8.4f} {row['solves']:6d} "
                         + " ".join(f"{v:10.3f}" for v in values))
        lines.append(f"{'sum':>8s} {'':6s} " + " ".join(f"{v:10.3f}" for v in total.values()))
        return "\n".join(lines)


def cost_split(scene_file: str | None) -> None:
    """Cold surrogates of the scene in this process, every / sampled field error."""
    import warnings

    import numpy as np

    from tengfield import surrogate
    from tengfield.field import solve_position
    from tengfield.scene import load_scene

    scene = load_scene(scene_file)
    from mpi4py import MPI
    # warm the JIT (FFCx forms) and gmsh so that neither run pays for them
    solve_position(scene, 0.5 * scene.device.stroke, comm=MPI.COMM_SELF)
    tables = {}
    for mode in ("every", "sampled"):
        with CostSplit() as split, warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            start, cpu = time.perf_counter(), time.process_time()
            tables[mode] = surrogate.precompute(scene, field_error=mode)
            elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
        print(f"\nfield_error = {mode!r}: {elapsed:.2f} s wall, {cpu:.2f} s CPU for "
              f"{tables[mode].count} positions ({len(split.rows)} solved), load: {uptime()}")
        print(split.table())
    every, sampled = tables["every"], tables["sampled"]
    same = bool(np.array_equal(every.capacitance, sampled.capacitance)
                and np.array_equal(every.induced_fraction, sampled.induced_fraction))
    bounds = bool(np.all(sampled.field_error >= every.field_error))
    print(f"\nsame C and q: {same}; interpolation error {every.interpolation_error:.3g} / "
          f"{sampled.interpolation_error:.3g}; max field error {np.max(every.field_error):.4g} / "
          f"{np.max(sampled.field_error):.4g}; sampled >= every at each position: {bounds}")


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=None, help="scene file (default: embedded default)")
    parser.add_argument("--skip-serial", action="store_true",
                        help="skip the serial precompute (no efficiency figure)")
    parser.add_argument("--cost-split", action="store_true",
                        help="only the per-position cost split of a cold surrogate (in process)")
    args = parser.parse_args()
    if args.cost_split:
        cost_split(args.scene)
        return
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
