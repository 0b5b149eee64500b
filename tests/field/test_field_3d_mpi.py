"""The 3D solver on 2 MPI ranks gives the serial numbers (``make test-mpi``).

Run with ``mpirun -n 2 .venv/bin/python -m pytest -m mpi tests``. The
stored reference meshes of ``meshes/`` are solved on ``MPI.COMM_WORLD``
and compared with the serial solution stored in ``meshes/reference.json``
(written by ``meshes/generate.py`` on one rank); a fresh degree-2 solve of
the off-axis paper device is compared with a ``COMM_SELF`` solve of the
same gmsh mesh on every rank.
"""
import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

MESHES = Path(__file__).resolve().parents[2] / "meshes"
pytestmark = pytest.mark.mpi


@pytest.mark.parametrize("name", ["paper_device", "honeycomb_cell"])
def test_stored_mesh_on_world_equals_serial_reference(name):
    from mpi4py import MPI

    from tengfield.field import solver3d

    case = json.loads((MESHES / "reference.json").read_text())["cases"][name]
    sol = solver3d.solve_reference_mesh(MESHES / f"{name}.msh", case, comm=MPI.COMM_WORLD)
    ref = case["solution_degree1"]
    assert sol.potentials.dofs == ref["dofs"]
    np.testing.assert_allclose(sol.capacitance, ref["capacitance_F"], rtol=1e-7)
    np.testing.assert_allclose(sol.induced_fraction, ref["induced_fraction"], rtol=1e-7)


@pytest.mark.parametrize("electrodes", [("lower", "upper"), ("lower",)], ids=["pair", "single"])
def test_degree2_offaxis_world_equals_self(electrodes):
    """The pair and the single-electrode cell (issue #51: its upper plate bare)."""
    import dataclasses

    from mpi4py import MPI

    from tengfield.field import solver3d
    from tengfield.field.cells.plate_model3d import cylindrical_cell
    from tengfield.field.geometry3d import MeshSettings
    from tengfield.scene import default_scene

    cell = dataclasses.replace(cylindrical_cell(default_scene().device), electrodes=electrodes)
    settings = solver3d.Solve3DSettings(degree=2, mesh_size=2e-3, domain_radius=20e-3,
                                        far_field="kelvin", estimate_error=False)
    mesh_settings = MeshSettings(size=2e-3, domain_radius=20e-3, order=2)
    world = solver3d.solve_on_mesh(
        solver3d.mesh_cell(cell, 0.7e-3, 0.4e-3, mesh_settings, comm=MPI.COMM_WORLD),
        solver3d.cell_permittivity(cell), settings)
    serial = solver3d.solve_on_mesh(
        solver3d.mesh_cell(cell, 0.7e-3, 0.4e-3, mesh_settings, comm=MPI.COMM_SELF),
        solver3d.cell_permittivity(cell), settings)
    assert MPI.COMM_WORLD.size == 1 or world.cell_mesh.mesh.topology.index_map(3).size_local \
        < world.potentials.cells, "the mesh is not distributed"
    assert world.potentials.dofs == serial.potentials.dofs
    assert world.capacitance.shape == (len(electrodes),) * 2
    np.testing.assert_allclose(world.capacitance, serial.capacitance, rtol=1e-7)
    np.testing.assert_allclose(world.induced_fraction, serial.induced_fraction, rtol=1e-7)
