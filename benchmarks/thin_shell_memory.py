"""Peak memory and wall time of one field position of the thin spherical shell of issue
#40 / #43 item 4 (cavity 9.209 mm, ball 8.899 mm: stroke 0.31 mm), measured from outside
with ``/usr/bin/time -v`` (target: <= 1 GB).

    .venv/bin/python benchmarks/thin_shell_memory.py [--position-mm 0.155 0 ...]

Position 0 is the contact rule's three anchor solves. Before the gap rule of the shell
was kept in its gaps: 1.05 GB and 181 s at 0.155 mm (72k dofs), ~3.7 GB at contact;
after: 0.27 GB (10.4k dofs) and 0.32 GB (docs/field.md, "The thin spherical shell").
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = """\
[device]
shape = "spherical-shell"
cavity_diameter_mm = 9.209
shell_thickness_mm = 2
electrode_band_mm = 2
ball_diameter_mm = 8.899
wall_permittivity = 3.0
surface_charge_uC_per_m2 = -50
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--position-mm", type=float, nargs="+", default=[0.155, 0.0])
    args = parser.parse_args()
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), MPLBACKEND="Agg")
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "thin.toml"
        scene.write_text(SCENE)
        for z in args.position_mm:
            proc = subprocess.run(
                ["/usr/bin/time", "-v", sys.executable, "-m", "tengfield.cli", "field", scene,
                 "--position-mm", str(z), "--no-plots", "-o", Path(tmp) / f"out-{z}"],
                env=env, capture_output=True, text=True)
            if proc.returncode != 0:
                sys.exit(proc.stderr[-2000:])
            peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)",
                                 proc.stderr).group(1))
            wall = re.search(r"Elapsed \(wall clock\) time.*: (\S+)", proc.stderr).group(1)
            dofs = re.search(r"dofs = (\d+)", proc.stdout).group(1)
            print(f"z = {z:g} mm: {dofs} dofs, peak {peak / 1e6:.2f} GB, wall {wall} "
                  f"(load {os.getloadavg()[0]:.1f})")


if __name__ == "__main__":
    main()
