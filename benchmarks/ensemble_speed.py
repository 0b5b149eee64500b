"""100 realisations of 2 s of the default device under random vibration, with
``mpirun -n 2`` (issue #25's speed target: <= 60 s on this 2-core machine).

    python benchmarks/ensemble_speed.py [--realisations 100] [--ranks 2] [--runs 3]

Writes the scene (default device, flat 10-100 Hz band at 20 m/s^2 rms, 2 s,
[run] realisations), runs it once to fill the surrogate cache and the numba
cache, then times the whole command ``mpirun -n RANKS tengfield run SCENE
--no-plots`` RUNS times (process start to exit: MPI start-up, imports, the
first realisation, the farm, the outputs) and prints min / median / max,
the machine's load average, and the ensemble's mean I_SC peak-to-peak with
its 95 % CI as a check that the run did its work. The README's figure was
measured with ``farm-bench`` on the same command.
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
[excitation]
kind = "random"
band_hz = [10.0, 100.0]
rms_acceleration_m_per_s2 = 20.0
[run]
duration_s = 2.0
realisations = {n}
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realisations", type=int, default=100)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1",
               PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe")
    tengfield = str(Path(sys.executable).with_name("tengfield"))
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scene.toml"
        scene.write_text(SCENE.format(n=args.realisations))
        command = ["mpirun", "-n", str(args.ranks), tengfield, "run", str(scene), "-o",
                   str(Path(tmp) / "out"), "--no-plots"]
        subprocess.run(command, env=env, check=True, capture_output=True)   # warm caches
        times = []
        for _ in range(args.runs):
            start = time.perf_counter()
            subprocess.run(command, env=env, check=True, capture_output=True)
            times.append(time.perf_counter() - start)
        summary = json.loads((Path(tmp) / "out" / "summary.json").read_text())
    i_pp = summary["ensemble"]["quantities"]["I_sc_pp_A"]
    print(f"{args.realisations} realisations x 2 s, mpirun -n {args.ranks}: wall "
          f"{min(times):.2f} / {statistics.median(times):.2f} / {max(times):.2f} s "
          f"(min / median / max of {args.runs}); load average {os.getloadavg()[0]:.2f}")
    print(f"I_SC peak-to-peak {i_pp['mean'] * 1e9:.4g} nA +- {i_pp['ci95_half_width'] * 1e9:.3g} nA "
          "(95 % CI)")


if __name__ == "__main__":
    main()
