"""The spherical shell's axisymmetric solve on 2 MPI ranks (``make test-mpi``): solved
on rank 0, every rank gets the serial numbers, an error on rank 0 reaches every rank."""
import numpy as np
import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

pytestmark = [pytest.mark.mpi, pytest.mark.field]


def shell():
    from tengfield.field.cells import SphericalShell
    return SphericalShell(cavity_diameter=20e-3, shell_thickness=2e-3, electrode_band=2e-3,
                          ball_diameter=8e-3, wall_permittivity=3.0)


def test_world_result_equals_serial_on_every_rank():
    from mpi4py import MPI

    from tengfield.field.cells.solve import solve_cell_position

    world = MPI.COMM_WORLD
    opts = dict(sigma=-1e-5, mesh_size=1e-3, estimate_error=False)
    shared = solve_cell_position(shell(), 2.5e-3, comm=world, **opts)
    serial = solve_cell_position(shell(), 2.5e-3, comm=MPI.COMM_SELF, **opts)
    np.testing.assert_allclose(shared.capacitance, serial.capacitance, rtol=1e-10)
    np.testing.assert_allclose(shared.induced_charge, serial.induced_charge, rtol=1e-10)
    everyone = world.allgather(shared.induced_charge)
    for charges in everyone:
        np.testing.assert_array_equal(charges, everyone[0])


def test_error_on_rank_zero_is_raised_on_every_rank():
    from mpi4py import MPI

    from tengfield.errors import FieldError
    from tengfield.field.cells.solve import solve_cell_position

    with pytest.raises(FieldError, match="domain_radius_mm = 12 is too small"):
        solve_cell_position(shell(), 2.5e-3, comm=MPI.COMM_WORLD, mesh_size=1e-3,
                            domain_radius=12e-3, estimate_error=False)


def test_off_axis_3d_solve_distributed_equals_serial_on_every_rank():
    """The shell's 3D model (an off-axis ball touching the wall: the contact rule along the
    radius) meshed on rank 0 and distributed: the serial numbers within the solver's
    tolerance, the same on every rank."""
    from mpi4py import MPI

    world = MPI.COMM_WORLD
    cell = shell()
    z = 4e-3
    opts = dict(offset=cell.admissible_offset(z), offset_angle=0.3, sigma=-1e-5,
                mesh_size=3e-3, degree=1, estimate_error=False)
    shared = cell.solve_3d(z, comm=world, **opts)
    serial = cell.solve_3d(z, comm=MPI.COMM_SELF, **opts)
    assert "contact_rule" in shared.info and shared.dofs == serial.dofs
    np.testing.assert_allclose(shared.capacitance, serial.capacitance, rtol=1e-7)
    np.testing.assert_allclose(shared.induced_charge, serial.induced_charge, rtol=1e-7)
    everyone = world.allgather(shared.induced_charge)
    for charges in everyone:
        np.testing.assert_allclose(charges, everyone[0], rtol=1e-12)
