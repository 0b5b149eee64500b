"""Speed of ``tengfield design``: a study over two parameters and a 3 x 3 band.

The ship study: 5 mm ball (tube following), power density into the matched load,
mean over the issue #40 target's 3 x 3 band {30, 33, 36} Hz x {0.5, 0.75, 1.0} mm
(``--frequencies 33`` gives the 3-point band of the README's earlier figures),
gap_mm in [1, 5] and ball_diameter_mm in [5, 10],
a fresh surrogate cache (every geometry solved). Prints the wall time, the CPU time of
all processes (user + sys), the cost per candidate split into field (surrogate), dynamics
and circuit (matched-load scan), and the load average.

    .venv/bin/python benchmarks/design_speed.py [--candidates 200] [--ranks 2] [--serial]
        [--frequencies 30,33,36]

``--ranks N`` runs ``mpirun -n N tengfield design``; ``--serial`` also runs the same
study on one process for the parallel efficiency T1 / (N T_N). The design's coarse
field (the default) moves the candidates' meshes with the ball and maps them from each
candidate's canonical geometry (field/moving.py); ``--mesh-motion remesh`` runs the same
field settings remeshed (``[design] field = "scene"`` with the coarse keys written in
``[field]``: degree 2, 1 mm, tolerance 0.02), for the comparison.
``TENGFIELD_MESH_MAPPING=0`` in the environment measures the moves without the mapping.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = """
[device]
ball_diameter_mm = 5.0
tube_inner_radius_mm = 3.0
electrode_radius_mm = 3.0
tube_outer_radius_mm = 4.5

{field}
[design]
objective = "power_density"
aggregate = "mean"
candidates = {candidates}
seed = 1
[design.vary]
gap_mm = [1.0, 5.0]
ball_diameter_mm = [5.0, 10.0]
[design.excitation]
frequency_hz = [{frequencies}]
amplitude_mm = [0.5, 0.75, 1.0]
"""


def run(command: list[str], env: dict) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        sys.exit(proc.stderr)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load": os.getloadavg(), "stdout": proc.stdout}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=200)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--serial", action="store_true", help="also time one process (--jobs 1)")
    ap.add_argument("--frequencies", default="30,33,36",
                    help="the band's frequencies [Hz], comma-separated (default 30,33,36: "
                         "with the 3 amplitudes the 3 x 3 band of issue #40's target)")
    ap.add_argument("--mesh-motion", choices=("remesh", "move"), default="move",
                    help="move: the design's coarse field (meshes moved with the ball and "
                         "mapped from canonical geometries); remesh: the same settings "
                         "remeshed for every position")
    args = ap.parse_args()
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
               PYTHONPATH=str(ROOT / "src"))
    work = Path(tempfile.mkdtemp(prefix="design-bench-"))
    scene = work / "study.toml"
    # every ball here is >= 5 mm: the coarse mesh size min(1 mm, d / 5) is 1 mm
    field = ("" if args.mesh_motion == "move" else
             '[field]\ndegree = 2\nmesh_size_mm = 1.0\ntolerance = 0.02\nmesh_motion = "remesh"\n')
    frequencies = ", ".join(repr(float(f)) for f in args.frequencies.split(","))
    text = SCENE.format(candidates=args.candidates, field=field, frequencies=frequencies)
    if args.mesh_motion == "remesh":
        text = text.replace("seed = 1\n", 'seed = 1\nfield = "scene"\n')
    scene.write_text(text)
    cli = [sys.executable, "-m", "tengfield.cli", "design", str(scene)]
    runs = {}
    runs[f"mpirun -n {args.ranks}"] = (run(["mpirun", "-n", str(args.ranks), *cli, "-o",
                                            str(work / "mpi"), "--cache-dir",
                                            str(work / "cache-mpi")], env), work / "mpi")
    if args.serial:
        runs["serial"] = (run([*cli, "--jobs", "1", "-o", str(work / "serial"), "--cache-dir",
                               str(work / "cache-serial")], env), work / "serial")
    for name, (r, out) in runs.items():
        summary = json.loads((out / "design.json").read_text())
        cost = summary["cost_per_candidate_s"]
        print(f"{name}: {args.candidates} candidates, wall {r['wall_s']:.1f} s, CPU "
              f"{r['cpu_s']:.1f} s (all processes), load average {r['load'][0]:.2f}")
        print(f"  per candidate: field {cost['field']:.2f} s (new geometry "
              f"{cost['field_per_new_geometry']:.2f} s, {cost['new_geometries']} new), dynamics "
              f"{cost['dynamics']:.2f} s, circuit {cost['circuit']:.2f} s; counts "
              f"{summary['counts']}; meshes {cost.get('mesh_placements')}")
        best = summary["best"]
        print(f"  best: stroke_mm = {best.get('stroke_mm', best.get('gap_mm'))}, "
              f"ball_diameter_mm = {best['ball_diameter_mm']}, "
              f"{best['objective']:.4g} +- {best['objective_error']:.2g} W/m^3")
    if args.serial:
        t1 = runs["serial"][0]["wall_s"]
        tn = runs[f"mpirun -n {args.ranks}"][0]["wall_s"]
        print(f"parallel efficiency T1 / ({args.ranks} T{args.ranks}) = "
              f"{t1 / (args.ranks * tn):.1%}")
    print(f"outputs in {work}")


if __name__ == "__main__":
    main()
