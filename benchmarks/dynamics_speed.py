"""Impact-map speed: impacts per second on one core (long two-plate run), impacts per
second inside ``simulate()`` on the single-plate scene of issue #9 against the plain
Python yardstick (benchmarks/dynamics_python_yardstick.py), the whole ``tengfield
dynamics`` process against ``simulate()`` for 600 000 impacts, a 100 x 100 regime map
with 200 periods per point, and soft contact vs impact map run time at equal
trajectory accuracy.

    .venv/bin/python benchmarks/dynamics_speed.py [--quick]

Prints the figures and writes benchmarks/out/dynamics_speed.csv.
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import resource
import time
from pathlib import Path

import numpy as np

from tengfield.dynamics import regime_map
from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.soft import integrate_soft
from tengfield.dynamics.table import sine_table
from tengfield.scene import default_scene


def impacts_per_second(periods: int) -> dict:
    """Two-plate run: 2 mm, 60 Hz, e = 0.9 (many impacts at both plates)."""
    f = 60.0
    table = sine_table(2e-3, 2 * math.pi * f, 0.0)
    integrate(table, 3e-3, Restitution(0.9), t_start=0, t_end=1 / f, period=1 / f)  # JIT
    t0, c0 = time.perf_counter(), time.process_time()
    _, imp, n_events = integrate(table, 3e-3, Restitution(0.9), t_start=0.0,
                                 t_end=periods / f, period=1 / f)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    n = len(imp[0])
    return {"benchmark": "impacts_per_second", "value": n / wall, "unit": "impacts/s",
            "detail": f"{n} impacts ({np.count_nonzero(imp[1] == 1)} upper) in {wall:.3f} s wall "
                      f"({n / cpu:.3g} impacts per CPU second), {periods} periods, "
                      "2 mm / 60 Hz / e = 0.9, 1 core"}


def simulate_vs_python(python_duration: float = 100.0) -> dict:
    """Issue #9 scene (Gamma = 1.3, e = 0.8, 20 Hz, 2000 s) inside simulate(), CPU time,
    and the ratio to the plain-Python guaranteed-step loop with brentq."""
    import sys
    sys.path.insert(0, str(Path(__file__).parent))
    from dynamics_python_yardstick import measure

    m = measure(python_duration, 2000.0)
    return {"benchmark": "simulate_impacts_per_cpu_second", "value": m["rate"],
            "unit": "impacts/s",
            "detail": f"{m['impacts']} impacts in {m['cpu_s']:.3f} CPU s (Gamma 1.3, e 0.8, "
                      f"20 Hz, 2000 s, {m['regime']} period {m['period']}); plain Python + "
                      f"brentq {m['python_rate']:.3g} /s ({m['python_impacts']} impacts); "
                      f"ratio {m['rate'] / m['python_rate']:.1f}"}


def _child(cmd: list[str]) -> tuple[float, float]:
    """(wall s, CPU s) of a child process."""
    import subprocess

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL,
                   env=dict(os.environ, MPLBACKEND="Agg"))
    wall = time.perf_counter() - w0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def cli_vs_simulate(tmp: Path, repeats: int = 3) -> dict:
    """`tengfield dynamics` whole process for 600k impacts (best of ``repeats``, the
    figure drawn by the figure process) against a process that only imports tengfield
    and calls simulate() once (what a script pays: start-up, numba cache, the run: the
    headline ratio), and against simulate() warm in this process (best of ``repeats``)."""
    import sys

    from tengfield.dynamics import simulate
    from tengfield.scene import load_scene

    scene_file = tmp / "impacts600k.toml"
    scene_file.write_text("[excitation]\nfrequency_hz = 60.0\namplitude_mm = 2.0\n"
                          "[contact]\nrestitution = 0.9\n[run]\n"
                          "duration_s = 3333.3333333333335\nsample_rate_hz = 100.0\n")
    scene = load_scene(scene_file)
    simulate(scene, duration=1.0)
    runs = []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        res = simulate(scene)
        runs.append((time.perf_counter() - w0, time.process_time() - c0))
    sim_wall, sim_cpu = min(runs)
    cli = [sys.executable, "-m", "tengfield.cli", "dynamics", str(scene_file), "-o",
           str(tmp / "out")]
    script = [sys.executable, "-c", "from tengfield.dynamics import simulate; "
              "from tengfield.scene import load_scene; "
              f"simulate(load_scene({str(scene_file)!r}))"]
    _child(cli)  # numba cache, page cache
    cli_wall, cli_cpu = min(_child(cli) for _ in range(repeats))
    only_wall, only_cpu = min(_child(script) for _ in range(repeats))
    return {"benchmark": "cli_over_simulate_process_600k", "value": cli_wall / only_wall,
            "unit": "ratio",
            "detail": f"tengfield dynamics {cli_wall:.2f} s wall ({cli_cpu:.2f} CPU s) vs "
                      f"simulate() warm {sim_wall:.2f} s wall ({sim_cpu:.2f} CPU s): "
                      f"{cli_wall / sim_wall:.2f}x wall, {cli_cpu / sim_cpu:.2f}x CPU; vs a "
                      f"process running simulate() alone {only_wall:.2f} s wall "
                      f"({only_cpu:.2f} CPU s): {cli_wall / only_wall:.2f}x wall, "
                      f"{cli_cpu / only_cpu:.2f}x CPU; {len(res.impacts)} impacts, "
                      f"{res.t.size} samples written"}


def regime_map_time(n: int, periods: int, jobs: int) -> dict:
    scene = default_scene()
    freqs = np.linspace(5, 70, n)
    amps = np.linspace(0.1e-3, 5e-3, n)
    def cpu_seconds():
        own = resource.getrusage(resource.RUSAGE_SELF)
        kids = resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime

    t0, c0 = time.perf_counter(), cpu_seconds()
    m = regime_map(scene, freqs, amps, jobs=jobs, progress=False, periods=periods)
    wall, cpu = time.perf_counter() - t0, cpu_seconds() - c0
    counts = {k: int(np.sum(m.regime == k)) for k in np.unique(m.regime)}
    return {"benchmark": f"regime_map_{n}x{n}", "value": wall, "unit": "s",
            "detail": f"{periods} periods/point, {jobs} processes, {cpu:.1f} CPU s in all "
                      f"({cpu / jobs:.1f} s per process if the cores were ours), {counts}"}


def soft_vs_impact(tolerance: float = 2e-5) -> dict:
    """Stiffness needed for max |z_soft - z_impact| < tolerance, and the run-time ratio."""
    f, amp, e, stroke, mass = 20.0, 1.5e-3, 0.6, 3e-3, default_scene().device.ball_mass
    table = sine_table(amp, 2 * math.pi * f, 0.0)
    t_end = 0.25
    t = np.linspace(0.0, t_end, 2000)
    t0 = time.perf_counter()
    for _ in range(20):
        ref, _, _ = integrate(table, stroke, Restitution(e), t_start=0.0, t_end=t_end,
                              period=1 / f)
    impact_time = (time.perf_counter() - t0) / 20
    z_ref, _, _ = ref(t)
    rows = []
    for k in [1e4, 1e5, 1e6, 1e7]:
        t0 = time.perf_counter()
        soft, _, _ = integrate_soft(table, stroke, e, mass, k, t_start=0.0, t_end=t_end,
                                    period=1 / f, rtol=1e-9)
        wall = time.perf_counter() - t0
        z, _, _ = soft(t)
        err = float(np.max(np.abs(z - z_ref)))
        rows.append((k, err, wall))
        print(f"  soft k = {k:.0e} N/m: max|dz| = {err:.3g} m, {wall:.3f} s")
        if err < tolerance:
            break
    k, err, wall = rows[-1]
    return {"benchmark": "soft_over_impact_time", "value": wall / impact_time, "unit": "ratio",
            "detail": f"soft k = {k:.0e} N/m reaches max|dz| = {err:.2g} m (< {tolerance:g} m) "
                      f"in {wall:.3f} s; impact map (exact) {impact_time * 1e3:.3f} ms; "
                      f"{t_end} s at 1.5 mm / 20 Hz"}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="smaller sizes (smoke run)")
    args = ap.parse_args()
    results = [impacts_per_second(20_000 if args.quick else 200_000)]
    print(results[-1])
    results.append(simulate_vs_python(20.0 if args.quick else 100.0))
    print(results[-1])
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        results.append(cli_vs_simulate(Path(tmp)))
    print(results[-1])
    results.append(regime_map_time(20 if args.quick else 100, 200, os.cpu_count() or 1))
    print(results[-1])
    results.append(soft_vs_impact())
    print(results[-1])
    load = os.getloadavg()
    out = Path(__file__).parent / "out"
    out.mkdir(exist_ok=True)
    with open(out / "dynamics_speed.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["benchmark", "value", "unit", "detail", "load"])
        w.writeheader()
        for r in results:
            w.writerow({**r, "load": f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"})
    print(f"load average during the run: {load}; wrote {out / 'dynamics_speed.csv'}")


if __name__ == "__main__":
    main()
