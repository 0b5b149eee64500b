"""3D and axisymmetric solvers agree for an on-axis ball within their error estimates."""
import numpy as np
import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")


@pytest.mark.slow
@pytest.mark.parametrize("position_mm", [0.0, 1.0])
def test_on_axis_3d_equals_axisymmetric_within_the_estimates(position_mm):
    """z = 0 exercises the shared contact rule (extrapolation from 20 and 40 µm)."""
    from mpi4py import MPI

    from tengfield.field import solve_position
    from tengfield.scene import default_scene

    scene = default_scene()
    z = position_mm * 1e-3
    axi = solve_position(scene, z, comm=MPI.COMM_SELF, method="axisymmetric")
    full = solve_position(scene, z, comm=MPI.COMM_SELF, method="3d", mesh_size_mm=1.5,
                          degree=2, far_field="kelvin")
    assert full.method == "3d" and axi.method == "axisymmetric"
    assert 0 < full.relative_error_estimate < 0.05
    tolerance = full.relative_error_estimate + axi.relative_error_estimate

    def entries(res):
        return np.r_[res.capacitance[np.triu_indices(2)], res.induced_charge]

    deviation = np.abs(entries(full) - entries(axi)) / np.abs(entries(axi))
    assert np.all(deviation <= tolerance), (deviation, tolerance)
    assert full.terminal_capacitance() == pytest.approx(axi.terminal_capacitance(), rel=tolerance)
