"""``[field] mesh_grading`` (issue #55): the 3D meshes graded from the gaps, the electrode
rims and the ball ("graded") against the base size in the whole device ("uniform")."""
import numpy as np
import pytest

from tengfield.errors import FieldError, SceneError
from tengfield.scene import default_scene
from tengfield.scene import Scene, check_field


def test_a_bad_mesh_grading_is_one_line_naming_key_value_and_choices():
    message = r"^\[field\] mesh_grading = 'steep' is not allowed: choose one of 'uniform', 'graded'"
    with pytest.raises(SceneError, match=message) as info:
        default_scene().with_values(field={"mesh_grading": "steep"})
    assert "\n" not in str(info.value)
    scene = Scene.from_dict({"field": {"mesh_grading": "steep"}})  # a dynamics-only run may
    with pytest.raises(SceneError, match=message) as info:
        check_field(scene)
    assert "\n" not in str(info.value)


def test_mesh_settings_refuse_an_unknown_grading_in_one_line():
    from tengfield.field.geometry3d import MeshSettings

    with pytest.raises(FieldError, match=r"mesh_grading = 'steep' .*'uniform', 'graded'") as info:
        MeshSettings(size=1e-3, domain_radius=20e-3, grading="steep")
    assert "\n" not in str(info.value)


def test_uniform_keeps_the_field_hash_and_graded_changes_it():
    scene = default_scene()
    assert scene.field.mesh_grading == "uniform"
    assert "mesh_grading" not in scene.field_inputs()["field"]
    assert scene.with_values(field={"mesh_grading": "uniform"}).field_hash() == scene.field_hash()
    graded = scene.with_values(field={"mesh_grading": "graded"})
    assert graded.field.mesh_grading == "graded"
    assert graded.field_hash() != scene.field_hash()


# -- physics: the default device, ball on the axis at mid-stroke (z = 1.5 mm), P2, far
# field "kelvin". Measured (benchmarks/field3d_graded.py, docs/field3d.md "Graded meshes"):
# graded at 0.5 mm 548k dofs, largest deviation 2.5e-3, its estimate 7.1e-3; uniform at
# 0.7 mm 443k dofs, 4.5e-3 (at 0.5 mm 1.13M dofs, 3.2e-3).

POSITION = 1.5e-3


def _entries(res):
    """C_ll, C_lu, C_uu [F] and q_lower, q_upper [C]."""
    return np.r_[res.capacitance[np.triu_indices(2)], res.induced_charge]


@pytest.fixture(scope="module")
def axisymmetric_reference():
    """The independent reference on the axis: the axisymmetric solve at 0.25 mm (its own
    estimate ~2e-5, 100x below the 3D errors compared here)."""
    from mpi4py import MPI

    from tengfield.field import solve_position

    res = solve_position(default_scene(), POSITION, comm=MPI.COMM_SELF, method="axisymmetric",
                         mesh_size_mm=0.25)
    assert res.relative_error_estimate < 1e-4
    return res


def _solve_3d(grading: str, mesh_size_mm: float, estimate: bool):
    from mpi4py import MPI

    from tengfield.field import solve_position

    scene = default_scene().with_values(field={"mesh_grading": grading,
                                               "mesh_size_mm": mesh_size_mm})
    return solve_position(scene, POSITION, comm=MPI.COMM_SELF, method="3d",
                          estimate_error=estimate)


@pytest.fixture(scope="module")
def graded_fine():
    """The graded 3D solve at 0.5 mm with its own error estimate (~40 s)."""
    return _solve_3d("graded", 0.5, True)


@pytest.mark.slow
def test_graded_3d_on_axis_agrees_with_axisymmetric_within_the_estimates(
        graded_fine, axisymmetric_reference):
    res, axi = graded_fine, axisymmetric_reference
    assert res.method == "3d" and res.info["mesh_size_m"] == pytest.approx(0.5e-3)
    tolerance = res.relative_error_estimate + axi.relative_error_estimate
    assert 0 < res.relative_error_estimate < 0.05
    deviation = np.abs(_entries(res) - _entries(axi)) / np.abs(_entries(axi))
    assert np.all(deviation <= tolerance), (deviation, tolerance)
    assert res.terminal_capacitance() == pytest.approx(axi.terminal_capacitance(), rel=tolerance)


@pytest.mark.slow
def test_graded_is_more_accurate_than_uniform_for_its_dofs(graded_fine, axisymmetric_reference):
    """Graded at 0.5 mm against uniform at 0.7 mm: a smaller largest error of C and q, and
    of C_T, and a smaller error x dofs. The uniform mesh's error falls like N^-0.8
    (measured), so its error x N grows with N: beating it from more dofs is beating it
    at equal dofs."""
    uniform = _solve_3d("uniform", 0.7, False)
    reference = _entries(axisymmetric_reference)

    def error(res):
        return float(np.max(np.abs(_entries(res) - reference) / np.abs(reference)))

    assert error(graded_fine) < error(uniform), (error(graded_fine), error(uniform))
    assert error(graded_fine) * graded_fine.dofs < error(uniform) * uniform.dofs
    c_t = axisymmetric_reference.terminal_capacitance()
    assert (abs(graded_fine.terminal_capacitance() - c_t)
            < abs(uniform.terminal_capacitance() - c_t))
