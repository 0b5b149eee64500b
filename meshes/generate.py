"""Regenerate the reference meshes of tengfield's 3D field solver.

    .venv/bin/python meshes/generate.py

For every case of :func:`tengfield.field.geometry3d.reference_cases` (the
paper's device with an off-axis ball, one honeycomb cell) this writes
``meshes/<name>.msh`` (gmsh 4.1, named physical groups) and collects in
``meshes/reference.json``: the case parameters, the mesh statistics
(nodes, elements and measure per physical group, gmsh version) and the
degree-1 solution on that very mesh (C [F], q/q_ball, serial, Robin far
field). tests/field/test_meshes_3d.py regenerates the meshes and compares
their statistics; tests/field/test_field_3d_mpi.py solves the stored
meshes on 2 ranks and compares with the stored numbers.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

HERE = Path(__file__).resolve().parent


def generate(out_dir: Path = HERE) -> dict:
    import gmsh
    from mpi4py import MPI

    from tengfield.field import geometry3d, solver3d

    reference = {"gmsh_version": gmsh.__version__, "cases": {}}
    for name, case in geometry3d.reference_cases().items():
        with solver3d.gmsh_model(geometry3d.unique_model_name(name)):
            meta = geometry3d.build_model(case.cell, case.position, case.offset, case.settings)
            stats = geometry3d.mesh_statistics()
            gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
            gmsh.option.setNumber("Mesh.Binary", 0)
            gmsh.write(str(out_dir / f"{name}.msh"))
        reference["cases"][name] = {
            "cell": {"type": type(case.cell).__name__, **dataclasses.asdict(case.cell)},
            "position_m": case.position, "offset_m": case.offset,
            "mesh_settings": dataclasses.asdict(case.settings),
            "ball_centre_m": [float(c) for c in meta["ball_centre"]],
            "statistics": stats,
        }
        sol = solver3d.solve_reference_mesh(out_dir / f"{name}.msh", reference["cases"][name],
                                            comm=MPI.COMM_SELF)
        reference["cases"][name]["solution_degree1"] = {
            "capacitance_F": sol.capacitance.tolist(),
            "induced_fraction": sol.induced_fraction.tolist(), "dofs": sol.potentials.dofs}
        print(f"{name}: {stats['nodes']} nodes, C = {sol.capacitance.ravel()[[0, 1, 3]]} F, "
              f"q/q_ball = {sol.induced_fraction}")
    (out_dir / "reference.json").write_text(json.dumps(reference, indent=2) + "\n")
    return reference


if __name__ == "__main__":
    generate()
