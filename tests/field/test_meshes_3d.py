"""The reference meshes in meshes/ still come out of gmsh the same way.

``meshes/generate.py`` wrote ``meshes/reference.json`` (statistics of each
reference mesh and its degree-1 solution). Here each mesh is regenerated
and compared (a gmsh or geometry change shows up as a count or measure
change), the stored ``.msh`` files are checked against the exact geometry,
and the solver is checked to reproduce the stored numbers on them.
"""
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("gmsh")

from tengfield.field import geometry3d, solver3d  # noqa: E402
from tengfield.field.cells import plate_model3d  # noqa: E402

MESHES = Path(__file__).resolve().parents[2] / "meshes"
REFERENCE = json.loads((MESHES / "reference.json").read_text())
CASES = plate_model3d.reference_cases()


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CASES))
def test_regenerated_mesh_matches_the_stored_statistics(name):
    case = CASES[name]
    stored = REFERENCE["cases"][name]
    assert stored["position_m"] == case.position and stored["offset_m"] == case.offset
    with solver3d.gmsh_model(geometry3d.unique_model_name(name)):
        geometry3d.build_model(case.cell, case.position, case.offset, case.settings)
        stats = geometry3d.mesh_statistics()
    assert stats["nodes"] == pytest.approx(stored["statistics"]["nodes"], rel=0.03)
    assert set(stats["groups"]) == set(stored["statistics"]["groups"])
    for group, values in stored["statistics"]["groups"].items():
        assert stats["groups"][group]["elements"] == pytest.approx(values["elements"], rel=0.05), group
        assert stats["groups"][group]["measure"] == pytest.approx(values["measure"], rel=1e-3), group


@pytest.mark.parametrize("name", sorted(CASES))
def test_stored_mesh_measures_match_the_exact_geometry(name):
    """Volumes and areas of the first-order meshes approach the exact ones (chord error only)."""
    case = CASES[name]
    groups = REFERENCE["cases"][name]["statistics"]["groups"]
    radius = 0.5 * case.cell.ball_diameter
    assert groups["ball"]["measure"] == pytest.approx(4 / 3 * math.pi * radius**3, rel=0.08)
    assert groups["ball_surface"]["measure"] == pytest.approx(4 * math.pi * radius**2, rel=0.05)
    if isinstance(case.cell, plate_model3d.CylindricalCell):
        electrode = math.pi * case.cell.electrode_radius**2
    else:
        electrode = 2 * math.sqrt(3) * case.cell.inner_apothem**2
    for side in ("lower", "upper"):
        assert groups[f"electrode_{side}"]["measure"] == pytest.approx(electrode, rel=0.02)
    far = 4 * math.pi * case.settings.domain_radius**2
    assert groups["far_boundary"]["measure"] == pytest.approx(far, rel=0.05)


@pytest.mark.parametrize("name", sorted(CASES))
def test_solver_reproduces_the_stored_numbers_on_the_stored_mesh(name):
    from mpi4py import MPI

    stored = REFERENCE["cases"][name]
    # the stored case is the one the code defines (settings and permittivities)
    assert stored["mesh_settings"] == dataclasses.asdict(CASES[name].settings)
    assert stored["cell"]["ball_permittivity"] == CASES[name].cell.ball_permittivity
    assert stored["cell"]["wall_permittivity"] == CASES[name].cell.wall_permittivity
    sol = solver3d.solve_reference_mesh(MESHES / f"{name}.msh", stored, comm=MPI.COMM_SELF)
    ref = stored["solution_degree1"]
    np.testing.assert_allclose(sol.capacitance, ref["capacitance_F"], rtol=1e-7)
    np.testing.assert_allclose(sol.induced_fraction, ref["induced_fraction"], rtol=1e-7)


class _Scalar(float):
    """A float whose repr is not a number, as numpy 2's ``np.float64(...)``."""

    def __repr__(self):
        return f"np.float64({float(self)!r})"


def test_size_expressions_hold_plain_numbers_only():
    """gmsh's MathEval parser aborts the whole process on ``np.float64(...)`` (numpy 2,
    Debian 13: the honeycomb cell at an off-axis position did). Every number written
    into an expression is the float's shortest decimal, whatever its type's repr."""
    expr = geometry3d._gap_size(_Scalar(1e-4), (_Scalar(1.8e-20), np.float64(3e-4), -0.003))
    assert "np" not in expr
    assert expr == "0.0001 + 0.35*sqrt((x-(1.8e-20))^2+(y-(0.0003))^2+(z-(-0.003))^2)"
    assert geometry3d.eval_number(_Scalar(0.1)) == "0.1"


@pytest.mark.slow
def test_every_size_field_of_an_off_axis_honeycomb_mesh_parses(monkeypatch):
    """The mesh that aborted on Debian 13: all its MathEval strings are plain."""
    import gmsh

    written = []
    real = gmsh.model.mesh.field.setString

    def record(tag, option, value):
        written.append(value)
        return real(tag, option, value)

    monkeypatch.setattr(gmsh.model.mesh.field, "setString", record)
    case = CASES["honeycomb_cell"]
    with solver3d.gmsh_model(geometry3d.unique_model_name("off-axis honeycomb")):
        model = geometry3d.build_model(case.cell, 1.0e-3, 0.3e-3, case.settings,
                                       offset_angle=math.pi / 6 + math.pi / 3)
    assert len(written) >= 4 and not any("np" in value for value in written)
    assert set(model["groups"]) >= {"ball", "air", "electrode_lower", "electrode_upper"}
