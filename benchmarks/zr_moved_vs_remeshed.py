"""A whole (z, r) table with moved meshes against the same table remeshed (issue #40:
"tables from moved meshes agree with today's remeshed tables within each table's error
estimate at every position").

    mpirun -n 2 python benchmarks/zr_moved_vs_remeshed.py [--cavity-mm 10]
        [--mesh-size-mm 1.5] [--degree 2] [--tolerance 1e-2] [--out DIR]

The spherical shell of the README's (z, r) target (``shape = "spherical-shell"``,
``cavity_diameter_mm = 10``, the rest the default scene's), its (z, r) table built twice
on ``COMM_WORLD`` (the task farm) with the scene's radial settings (default P2, 1.5 mm,
tolerance 1e-2): ``[field] mesh_motion = "remesh"`` (gmsh at every position) and
``"move"`` (:mod:`tengfield.field.moving3d`). Prints, per table, the wall time, the grid,
the held-out interpolation estimate of each round, the field error estimates and how the
meshes were placed; then, at every grid point the two tables share (the refinement is
nested), the change of C and of q between them (relative to each table's largest
magnitude, as the field tests measure it) against the sum of the two tables' field error
estimates there (each value is within its own estimate of the exact one), and the
worst ratio. Writes ``zr_moved_vs_remeshed.json`` to ``--out``.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def build(scene, motion: str, settings: dict, comm):
    from tengfield.field import moving3d
    from tengfield.surrogate.refinement import precompute_radial

    moved = scene.with_values(field={"mesh_motion": motion})
    moving3d.clear()
    comm.Barrier()
    start = time.perf_counter()
    table = precompute_radial(moved, comm=comm, **settings)
    comm.Barrier()
    wall = time.perf_counter() - start
    moving3d.clear()
    return table, wall


def shared_points(a, b):
    """Indices of ``a``'s grid points in ``b``'s grid (nested refinement)."""
    iz = np.array([int(np.argmin(np.abs(b.positions - z))) for z in a.positions])
    ir = np.array([int(np.argmin(np.abs(b.offsets - r))) for r in a.offsets])
    scale = max(a.positions.max(), 1e-12)
    if np.max(np.abs(b.positions[iz] - a.positions)) > 1e-9 * scale or \
            np.max(np.abs(b.offsets[ir] - a.offsets)) > 1e-9 * scale:
        raise SystemExit("the two grids are not nested: no shared points to compare")
    return iz, ir


def compare(coarse, fine):
    """Per shared grid point: the change of C and of q (relative to ``coarse``'s largest
    magnitude of each) and the sum of the two field error estimates."""
    iz, ir = shared_points(coarse, fine)
    c_f = fine.capacitance[np.ix_(iz, ir)]
    q_f = fine.induced_fraction[np.ix_(iz, ir)]
    change_c = np.abs(coarse.capacitance - c_f).max(axis=(2, 3)) \
        / np.abs(coarse.capacitance).max()
    change_q = np.abs(coarse.induced_fraction - q_f).max(axis=2) \
        / np.abs(coarse.induced_fraction).max()
    change = np.maximum(change_c, change_q)
    bound = coarse.field_error + fine.field_error[np.ix_(iz, ir)]
    return change, bound


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cavity-mm", type=float, default=10.0)
    ap.add_argument("--mesh-size-mm", type=float, default=None,
                    help="default: the scene's [field] radial_mesh_size_mm")
    ap.add_argument("--degree", type=int, default=None)
    ap.add_argument("--tolerance", type=float, default=None)
    ap.add_argument("--out", default="out/benchmarks")
    args = ap.parse_args()
    from mpi4py import MPI

    from tengfield.scene import default_scene

    comm = MPI.COMM_WORLD
    scene = default_scene().with_values(device={"shape": "spherical-shell",
                                                "cavity_diameter_mm": args.cavity_mm})
    fld = scene.field
    settings = {"mesh_size_mm": args.mesh_size_mm or fld.radial_mesh_size * 1e3,
                "degree": args.degree or fld.radial_degree,
                "tolerance": args.tolerance or fld.radial_tolerance}
    tables, report = {}, {"settings": settings, "cavity_mm": args.cavity_mm,
                          "ranks": comm.size, "tables": {}}
    for motion in ("remesh", "move"):
        table, wall = build(scene, motion, settings, comm)
        tables[motion] = table
        info = {"wall_s": wall, "grid": list(table.shape),
                "interpolation_history": [list(h) for h in table.error_history],
                "field_error_min": float(np.min(table.field_error)),
                "field_error_max": float(np.max(table.field_error)),
                "mesh_placements": dict(table.provenance.get("mesh_placements", {}))}
        report["tables"][motion] = info
        if comm.rank == 0:
            print(f"{motion}: {wall:.1f} s on {comm.size} rank(s), grid {table.shape[0]} x "
                  f"{table.shape[1]}, interpolation estimates "
                  + ", ".join(f"{e:.3g} ({nz} x {nr})" for nz, nr, e in table.error_history)
                  + f"; field error estimates {info['field_error_min']:.3g} .. "
                  f"{info['field_error_max']:.3g}; meshes {info['mesh_placements']}",
                  flush=True)
    a, b = tables["remesh"], tables["move"]
    coarse, fine = (a, b) if a.count <= b.count else (b, a)
    change, bound = compare(coarse, fine)
    ratio = change / bound
    worst = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    report["shared_points"] = int(change.size)
    report["largest_change"] = float(change.max())
    report["largest_ratio"] = float(ratio.max())
    report["worst_point_mm"] = [float(coarse.positions[worst[0]] * 1e3),
                                float(coarse.offsets[worst[1]] * 1e3)]
    if comm.rank == 0:
        print(f"{change.size} shared grid points: largest change of C or q "
              f"{change.max():.3g}; largest change / (sum of the two field error estimates) "
              f"{ratio.max():.3f} at z = {report['worst_point_mm'][0]:.3f} mm, "
              f"{coarse.offset_coordinate} offset {report['worst_point_mm'][1]:.3f} mm; "
              f"every point within the sum: {bool(np.all(change <= bound))}")
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "zr_moved_vs_remeshed.json").write_text(json.dumps(report, indent=2) + "\n")
        print(f"wrote {out / 'zr_moved_vs_remeshed.json'}")


if __name__ == "__main__":
    main()
