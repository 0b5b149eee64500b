"""Long runs (issue #28 "big outputs", #30.11): output size, wall time and peak memory
of ``tengfield run`` on the default scene for 100 s and 15 min (the paper's stability
record, ``duration_s = 900`` at the default 20 kHz), 999 s, and a 500 s rectifier with
the UVLO chip, each measured with ``/usr/bin/time -v`` (peak RSS of the main process
and its figure process, the larger one). The surrogate must be cached (run once
first); the machine may be shared: the load average is printed with every figure.

    .venv/bin/python benchmarks/long_run.py [--cases 100s 900s 999s rect500] [--keep DIR]

Measured (2 shared cores, load average 3-8, surrogate cached). "CSV" = commit 713fd0e;
"run.h5" = branch relcore (the tables in run.h5 past the 2e6-row CSV bound, whole-record
arrays); "streamed" = branch stream (the electrical stage a chunk at a time past 2^20
samples, docs/long_runs.md):

| case | output CSV | run.h5 | wall CSV / run.h5 | peak RSS CSV / run.h5 |
|---|---|---|---|---|
| 100 s (2e6 rows) | 348 MB | 25 MB | 58.9 s / 5.5 s | 877 MB / 411 MB |
| 900 s (1.8e7 rows) | 3.14 GB | 260 MB | 147 s / 21 s | 4.72 GB / 2.03 GB |
| 999 s (2e7 rows) | - | 290 MB | - / 47 s | 5.17 GB / 2.23 GB |
| rectifier + uvlo, 500 s (1e7 rows) | CSV | 141 MB | 118 s / 30 s | 5.41 GB / 5.04 GB |

Streamed (branch stream), paired with its parent commit 6631751 in one session (load
average 2-6; the same run.h5 files):

| case | wall before / streamed | peak RSS before / streamed |
|---|---|---|
| 100 s | 2.6 s / 3.0 s | 427 MB / 301 MB |
| 900 s | 13.3 s / 12.3 s | 2069 MB / 937 MB |
| 999 s | 17.5 s / 13.8 s | 2276 MB / 1016 MB |
| rectifier + uvlo, 500 s | 33.5 s / 11.5 s | 5715 MB / 737 MB |

The streamed stage computes the electrical columns twice (once for the summary, once
while writing run.h5), which the smaller allocations pay for.

Dynamics sampled on request (branch dynstream: past 2^20 samples a 1-D run keeps its
compact trajectory and samples t, elapsed, gap, velocity and table a chunk at a time,
dynamics/columns.py), paired with its parent b3c8a09 (the streamed stage above) in one
session (load average 1-2; the same run.h5 files, bit for bit):

| case | wall before / after | peak RSS before / after |
|---|---|---|
| 100 s | 2.9 s / 3.0 s | 301 MB / 241 MB |
| 900 s | 11.6 s / 10.8 s | 936 MB / 257 MB |
| 999 s | 11.5 s / 11.0 s | 1016 MB / 255 MB |
| rectifier + uvlo, 500 s | 10.2 s / 9.7 s | 730 MB / 360 MB |

The peak no longer grows with the run (the 5 whole-record arrays, 40 bytes per sample,
720 MB at 900 s, are gone); a single /usr/bin/time run is noisy in wall time: paired
with farm-bench (-n 3) the 900 s run takes 11.44 s against the parent's 10.95 s
(medians, A/B 1.03: the trajectory is sampled twice, for the summary and for run.h5).
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHON = sys.executable

CASES = {
    "100s": "[run]\nduration_s = 100\n",
    "900s": "[run]\nduration_s = 900\n",
    "999s": "[run]\nduration_s = 999\n",
    "rect500": '[run]\nduration_s = 500\n[circuit]\nkind = "rectifier"\npmic = "uvlo"\n',
}


def measure(name: str, text: str, work: Path) -> dict:
    scene = work / f"{name}.toml"
    scene.write_text(text)
    out = work / f"out-{name}"
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT / "src"),
               OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = ["/usr/bin/time", "-v", PYTHON, "-m", "tengfield.cli", "run", str(scene), "-o",
           str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        raise SystemExit(f"{name}: exit {proc.returncode}\n{proc.stderr[-2000:]}")
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", proc.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    parts = [float(x) for x in wall.group(1).split(":")]
    seconds = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
    files = {p.name: p.stat().st_size for p in out.iterdir()
             if p.is_file() and not p.name.startswith(".")}
    return {"case": name, "wall_s": seconds, "peak_rss_MB": int(rss.group(1)) / 1e3,
            "output_MB": sum(files.values()) / 1e6, "files": files,
            "load": os.getloadavg()[0]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["100s", "900s"], choices=list(CASES))
    parser.add_argument("--keep", type=Path, help="keep the outputs in this directory")
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="tengfield-long-"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        for name in args.cases:
            r = measure(name, CASES[name], work)
            big = ", ".join(f"{k} {v / 1e6:.3g} MB" for k, v in r["files"].items()
                            if v > 1e6)
            print(f"{name}: output {r['output_MB']:.4g} MB ({big}), wall {r['wall_s']:.1f} s, "
                  f"peak RSS {r['peak_rss_MB']:.0f} MB (load average {r['load']:.1f})",
                  flush=True)
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
