"""#30 items 8, 15: the paper's device divided by k meshes as the paper's (the mesh rule is
scale-free), or is refused before meshing with one line naming the key and the limit.

Before: the gap size field was ``(h / 1 mm) · (g + ρ²/d)`` for every device, so the device
/30 with mesh_size_mm = 0.01667 meshed its gaps 30x finer than the paper's (gmsh ran for
335 s at 11.5 GB); with an empty [field] the 0.5 mm default left a /10 device with 300
cells, /100 ended in a dolfinx gmshio AssertionError traceback and /1000 in
"no 'electrode_lower' entity found"."""
from __future__ import annotations

import pytest

from tengfield.field import geometry_axisymmetric as geometry
from tengfield.scene import Scene, SceneError, check_field, default_scene
from tengfield.scene.limits import default_mesh_scale

PAPER_LENGTHS = {"ball_diameter_mm": 7.0, "stroke_mm": 3.0, "electrode_radius_mm": 4.0,
                 "tube_inner_radius_mm": 4.0, "tube_outer_radius_mm": 5.5,
                 "plate_thickness_mm": 2.0}


def divided(k: float, mesh_size_mm: float | None = None) -> Scene:
    fld = {} if mesh_size_mm is None else {"mesh_size_mm": mesh_size_mm}
    return Scene.from_dict({"device": {key: v / k for key, v in PAPER_LENGTHS.items()},
                            "field": fld})


def test_the_paper_device_keeps_its_gap_rule_to_the_bit():
    scene = default_scene()
    lay = geometry.layout(scene, 0.0)
    assert geometry.gap_size_factor(lay) == lay.mesh_size / 1e-3      # the rule before
    assert default_mesh_scale(scene.device, scene.field) == 1.0


@pytest.mark.parametrize("k", [10.0, 30.0, 40.0])
@pytest.mark.parametrize("written", [True, False])
def test_a_divided_device_has_the_papers_mesh_rule(k, written):
    paper = default_scene()
    small = divided(k, 0.5 / k if written else None)
    assert geometry.base_mesh_size(small) == pytest.approx(0.5e-3 / k, rel=1e-12)
    for position in (0.0, 0.5, 1.0):          # a fraction of the stroke
        big = geometry.layout(paper, position * paper.device.stroke)
        lay = geometry.layout(small, position * small.device.stroke)
        assert geometry.gap_size_factor(lay) == pytest.approx(geometry.gap_size_factor(big),
                                                              rel=1e-9)
        # (within 2 %: domain_radius_mm = "auto" is rounded at two digits in mm)
        assert geometry.estimated_cells(lay) == pytest.approx(geometry.estimated_cells(big),
                                                              rel=0.02)


def test_the_cell_estimate_counts_the_gap_rule():
    """At contact the gap rule holds about a third of the mesh (measured: 11,564 cells at
    z = 0, 6,499 at mid-stroke); the estimate was the same at both (7,275)."""
    scene = default_scene()
    contact = geometry.estimated_cells(geometry.layout(scene, 0.0))
    middle = geometry.estimated_cells(geometry.layout(scene, 1.5e-3))
    assert contact > 1.4 * middle


@pytest.mark.parametrize("k", [100.0, 1000.0])
def test_a_device_below_gmshs_tolerance_is_refused_in_one_line(k):
    scene = divided(k)
    with pytest.raises(SceneError) as info:
        check_field(scene)
    text = str(info.value)
    assert "\n" not in text
    assert "ball_diameter_mm + stroke_mm" in text and "allowed >= 0.25 mm" in text
    assert f"{(7.0 + 3.0) / k:.3g} mm" in text


@pytest.mark.slow
@pytest.mark.field
@pytest.mark.parametrize("k, written", [(10.0, False), (30.0, True)])
def test_a_divided_device_meshes_as_the_papers(k, written):
    """The mesh of the device /k has the paper's cell count (within 2 %), and its
    capacitances are the paper's divided by k (electrostatics has no length scale)."""
    pytest.importorskip("dolfinx")
    from mpi4py import MPI

    from tengfield.field import solve_position

    paper, small = default_scene(), divided(k, 0.5 / k if written else None)
    ref = solve_position(paper, 0.5 * paper.device.stroke, comm=MPI.COMM_SELF,
                         estimate_error=False)
    res = solve_position(small, 0.5 * small.device.stroke, comm=MPI.COMM_SELF,
                         estimate_error=False)
    assert res.dofs == pytest.approx(ref.dofs, rel=0.02)
    for name in ("C_ll", "C_uu", "C_lu"):
        assert getattr(res, name) * k == pytest.approx(getattr(ref, name), rel=2e-3), name


@pytest.mark.slow
def test_field_command_refuses_the_device_divided_by_100(tmp_path, run_cli):
    scene = tmp_path / "tiny.toml"
    scene.write_text("[device]\n" + "".join(f"{key} = {v / 100!r}\n"
                                             for key, v in PAPER_LENGTHS.items()))
    done = run_cli("field", scene, "--position-mm", "0.01", "--no-plots", "-o",
                   tmp_path / "out", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    # the lengths are also implausible as mm: one warning line says so, one error refuses
    assert len(lines) == 2 and lines[0].startswith("tengfield: warning: "), done.stderr
    assert "lengths look like metres" in lines[0]
    assert lines[1].startswith("tengfield: error: "), done.stderr
    assert "ball_diameter_mm + stroke_mm = 0.1 mm" in lines[1]
    assert not (tmp_path / "out").exists()
