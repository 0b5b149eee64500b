"""σ and restitution, N = 256 with Sobol indices (1024 evaluations), the default scene,
with ``mpirun -n 2`` (issue #34's speed target: <= 60 s on this 2-core machine).

    python benchmarks/uncertainty_speed.py [--samples 256] [--ranks 2] [--runs 3]

Writes the scene (default device; σ uniform between half the breakdown limit and the
limit, 25.9 uC/m^2; restitution uniform 0.05-0.8), runs it once to fill the surrogate
and numba caches, then times the whole command ``mpirun -n RANKS tengfield uncertainty
SCENE`` (figures on) RUNS times, process start to exit, and prints min / median / max,
the load average and the study's Q_SC interval and dominant input as a check that it did
its work. The README's figure was measured with ``farm-bench`` on the same command.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SCENE = """
[uncertainty]
samples = {n}
method = "sobol"
seed = 0

[uncertainty.vary]
"device.surface_charge_uC_per_m2" = {{ distribution = "uniform", low = -25.9, high = -12.95 }}
"contact.restitution" = {{ distribution = "uniform", low = 0.05, high = 0.8 }}
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    src = Path(__file__).resolve().parents[1] / "src"
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
               PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe",
               PYTHONPATH=os.pathsep.join(p for p in (str(src), os.environ.get("PYTHONPATH"))
                                          if p))
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scene.toml"
        scene.write_text(SCENE.format(n=args.samples))
        out = Path(tmp) / "out"
        command = ["mpirun", "-n", str(args.ranks), sys.executable, "-m", "tengfield.cli",
                   "uncertainty", str(scene), "-o", str(out)]
        subprocess.run(command, env=env, check=True, capture_output=True)   # warm caches
        times = []
        for _ in range(args.runs):
            start = time.perf_counter()
            subprocess.run(command, env=env, check=True, capture_output=True)
            times.append(time.perf_counter() - start)
        data = json.loads((out / "uncertainty.json").read_text())
    q = data["outputs"]["peak_to_peak.Q_sc_C"]
    print(f"{data['evaluations']} evaluations (N = {args.samples}, sobol), mpirun -n "
          f"{args.ranks}: wall {min(times):.2f} / {statistics.median(times):.2f} / "
          f"{max(times):.2f} s (min / median / max of {args.runs}); load average "
          f"{os.getloadavg()[0]:.2f}; {data['dynamics_runs']} dynamics runs, "
          f"{data['field_solves']} field solves")
    print(f"Q_SC peak-to-peak 90 % in [{q['percentiles']['5'] * 1e9:.3g}, "
          f"{q['percentiles']['95'] * 1e9:.3g}] nC, dominated by {q.get('dominant_input')}")


if __name__ == "__main__":
    main()
