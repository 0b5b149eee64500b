"""Field numbers that must agree between Debian 12 (dolfinx 0.5.2) and
Debian 13 (dolfinx 0.9): the stored table and the check against it.

    python field_table.py write   TABLE.json RUN_DIR   # make the table (on Debian 12)
    python field_table.py compare TABLE.json RUN_DIR   # check this stack against it
    mpirun -n 2 python field_table.py compare ...      # the same, solves on 2 ranks

What is compared (the default scene, its own [field] settings, the same gmsh
release on both stacks, so the same meshes):

* the Maxwell capacitance matrix C [F] and the induced charges q [C] of the
  axisymmetric solver at z = 0, Δh/4, Δh/2 and Δh (no error estimate);
* C and q of the 3D solver at one off-axis position (coarse: degree 1,
  h = 2 mm), whose ball-surface charge uses interior-facet integrals: under
  MPI those need shared-facet ghosts (DESIGN.md §9), which this catches;
* the peak-to-peak V_OC, Q_SC and I_SC in RUN_DIR/summary.json, written by
  ``tengfield run -o RUN_DIR`` on the default scene.

Every number must agree to ``--rtol`` (default 1e-6) relative to the
largest magnitude of its group (a C matrix, a q pair, one peak-to-peak
value). The solves run on the communicator of the launch (``mpirun -n 2``
spreads each mesh over two ranks); rank 0 prints and writes. Prints one line
per group and exits 1 when any group differs, 2 on bad usage.
"""
from __future__ import annotations

import argparse
import json
import math
import platform
import sys
from pathlib import Path

RTOL = 1e-6
#: axisymmetric positions as fractions of the free stroke Δh
AXISYMMETRIC_FRACTIONS = (0.0, 0.25, 0.5, 1.0)
#: the 3D position: z = Δh/2, the ball 0.5 mm off the axis, a coarse mesh
SOLID_CASE = {"fraction": 0.5, "offset_mm": 0.5, "degree": 1, "mesh_size_mm": 2.0}
PEAK_KEYS = ("V_oc_V", "Q_sc_C", "I_sc_A")


def _versions() -> dict[str, str]:
    import dolfinx
    import gmsh
    import numpy

    versions = {"python": platform.python_version(), "dolfinx": dolfinx.__version__,
                "gmsh": gmsh.__version__, "numpy": numpy.__version__}
    try:
        for line in Path("/etc/os-release").read_text().splitlines():
            if line.startswith("PRETTY_NAME="):
                versions["os"] = line.split("=", 1)[1].strip('"')
    except OSError:
        pass
    return versions


def field_numbers(comm) -> dict[str, dict]:
    """C and q of the default scene at the table's positions, solved on ``comm``."""
    from tengfield.field import solve_position
    from tengfield.scene import default_scene

    scene = default_scene()
    stroke = scene.device.stroke
    groups: dict[str, dict] = {}
    for fraction in AXISYMMETRIC_FRACTIONS:
        z = fraction * stroke
        res = solve_position(scene, z, comm=comm, method="axisymmetric", estimate_error=False)
        name = f"axisymmetric z={z * 1e3:.4g}mm"
        groups[f"{name} C_F"] = {"values": res.capacitance.ravel().tolist(), "dofs": res.dofs}
        groups[f"{name} q_C"] = {"values": res.induced_charge.tolist(), "dofs": res.dofs}
    case = SOLID_CASE
    z = case["fraction"] * stroke
    res = solve_position(scene, z, comm=comm, method="3d", offset=case["offset_mm"] * 1e-3,
                         degree=case["degree"], mesh_size_mm=case["mesh_size_mm"],
                         estimate_error=False)
    name = (f"3d z={z * 1e3:.4g}mm offset={case['offset_mm']:g}mm "
            f"degree={case['degree']} h={case['mesh_size_mm']:g}mm")
    groups[f"{name} C_F"] = {"values": res.capacitance.ravel().tolist(), "dofs": res.dofs}
    groups[f"{name} q_C"] = {"values": res.induced_charge.tolist(), "dofs": res.dofs}
    return groups


def run_numbers(run_dir: Path) -> dict[str, dict]:
    """The peak-to-peak values of ``tengfield run``'s summary.json in ``run_dir``."""
    path = run_dir / "summary.json"
    summary = json.loads(path.read_text())
    peaks = summary.get("peak_to_peak", {})
    missing = [k for k in PEAK_KEYS if k not in peaks]
    if missing:
        raise KeyError(f"{path}: peak_to_peak has no {missing} (keys: {sorted(peaks)})")
    return {f"default run peak-to-peak {k}": {"values": [float(peaks[k])]} for k in PEAK_KEYS}


def compare(table: dict, current: dict, rtol: float) -> list[str]:
    """One line per group ('ok ...' or 'FAIL ...'); groups missing on either side fail."""
    lines = []
    for name in sorted(set(table) | set(current)):
        if name not in current or name not in table:
            side = "this stack" if name not in current else "the table"
            lines.append(f"FAIL {name}: missing in {side}")
            continue
        want = [float(x) for x in table[name]["values"]]
        got = [float(x) for x in current[name]["values"]]
        if len(want) != len(got):
            lines.append(f"FAIL {name}: {len(got)} values, the table has {len(want)}")
            continue
        scale = max(abs(x) for x in want)
        worst = max((abs(a - b) / scale if scale > 0 else abs(a - b)) for a, b in zip(got, want))
        ok = math.isfinite(worst) and worst <= rtol
        dofs = ""
        if "dofs" in table[name]:
            dofs = f" (dofs {current[name].get('dofs')} vs {table[name]['dofs']})"
        lines.append(f"{'ok  ' if ok else 'FAIL'} {name}: max relative difference {worst:.2e}"
                     f" (rtol {rtol:g}){dofs}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mode", choices=("write", "compare"))
    parser.add_argument("table", type=Path, help="the stored table (JSON)")
    parser.add_argument("run_dir", type=Path, help="output directory of `tengfield run` "
                        "on the default scene (its summary.json)")
    parser.add_argument("--rtol", type=float, default=RTOL)
    args = parser.parse_args(argv)

    import pyvista  # noqa: F401 - tengfield imports pyvista before dolfinx
    from mpi4py import MPI

    comm = MPI.COMM_WORLD  # the script is the edge: the launch decides the ranks
    current = {**field_numbers(comm), **run_numbers(args.run_dir)}
    if comm.rank != 0:
        return 0
    if args.mode == "write":
        table = {"about": "tengfield field numbers; scripts/container/field_table.py",
                 "written_with": {**_versions(), "ranks": comm.size},
                 "rtol": args.rtol, "groups": current}
        args.table.write_text(json.dumps(table, indent=1) + "\n")
        print(f"wrote {args.table}: {len(current)} groups ({_versions()})")
        return 0
    table = json.loads(args.table.read_text())
    print(f"comparing with {args.table} (written with {table.get('written_with')})")
    print(f"this stack: {_versions()}, {comm.size} rank(s)")
    lines = compare(table["groups"], current, args.rtol)
    print("\n".join(lines))
    failed = sum(line.startswith("FAIL") for line in lines)
    print(f"field table: {len(lines) - failed} of {len(lines)} groups agree to {args.rtol:g}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
