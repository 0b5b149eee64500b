"""The axisymmetric solver on 2 MPI ranks (``make test-mpi``): solved on rank 0,
every rank gets the serial numbers, and an error on rank 0 reaches every rank
(no hang)."""
import numpy as np
import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

pytestmark = pytest.mark.mpi

COARSE = dict(mesh_size_mm=1.0, degree=2, estimate_error=False)


def test_world_result_equals_serial_on_every_rank():
    from mpi4py import MPI

    from tengfield.field import solve_position
    from tengfield.scene import default_scene

    world = MPI.COMM_WORLD
    scene = default_scene()
    shared = solve_position(scene, 0.8e-3, comm=world, **COARSE)
    serial = solve_position(scene, 0.8e-3, comm=MPI.COMM_SELF, **COARSE)
    np.testing.assert_allclose(shared.capacitance, serial.capacitance, rtol=1e-10)
    np.testing.assert_allclose(shared.induced_charge, serial.induced_charge, rtol=1e-10)
    everyone = world.allgather(shared.induced_charge)
    for charges in everyone:
        np.testing.assert_array_equal(charges, everyone[0])


def test_error_on_rank_zero_is_raised_on_every_rank():
    from mpi4py import MPI

    from tengfield.errors import FieldError
    from tengfield.field import solve_position
    from tengfield.scene import default_scene

    scene = default_scene().with_values(field={"domain_radius_mm": 12.0})
    with pytest.raises(FieldError, match="domain_radius_mm = 12"):
        solve_position(scene, 1e-3, comm=MPI.COMM_WORLD, environment="grounded-table",
                       **COARSE)
