"""Issue 21, item 2: an explicit ``[field] mesh_size_mm`` is used as written (never scaled by
the electrode spacing); only the default scales, with the smallest feature the mesh must
resolve; ``tengfield field`` warns once when its error estimate misses ``[field] tolerance``.

The "far" device: 4 mm electrodes (radius 2 mm) 400 mm apart, a 4 mm ball, εr = 1 ball and
walls, so the device is two small disks in free space: C_ll = C_uu = 8 ε0 a / (1 - k²),
C_lu = -k C_ll with k = 8a / (4π D) (a << D, first order in the disks' mutual field)."""
import math

import pytest

from tengfield.field import geometry_axisymmetric as geometry
from tengfield.scene import EPS0, Scene, default_scene
from tengfield.scene.limits import default_mesh_scale

FAR = {"ball_diameter_mm": 4.0, "stroke_mm": 396.0, "electrode_radius_mm": 2.0,
       "tube_inner_radius_mm": 3.0, "tube_outer_radius_mm": 4.0, "plate_thickness_mm": 2.0,
       "ball_permittivity": 1.0, "wall_permittivity": 1.0}
#: the lengths of the paper's device (the schema defaults)
PAPER_LENGTHS = {"ball_diameter_mm": 7.0, "stroke_mm": 3.0, "electrode_radius_mm": 4.0,
                 "tube_inner_radius_mm": 4.0, "tube_outer_radius_mm": 5.5,
                 "plate_thickness_mm": 2.0}


def scene_of(device: dict, **field) -> Scene:
    return Scene.from_dict({"device": dict(device), "field": dict(field)})


def scaled(factor: float, **changes) -> dict:
    return {**{k: v * factor for k, v in PAPER_LENGTHS.items()}, **changes}


def far_analytic() -> tuple[float, float]:
    a, spacing = 2e-3, 400e-3
    k = 8.0 * a / (4.0 * math.pi * spacing)
    c_self = 8.0 * EPS0 * a / (1.0 - k * k)
    return c_self, -k * c_self


# -- explicit values are used as written ------------------------------------------------
def test_an_explicit_mesh_size_is_used_as_written_for_a_large_spacing():
    """4 mm electrodes 400 mm apart, mesh_size_mm = 4: the mesh is 4 mm (it was 160 mm,
    scaled by spacing / 10 mm, and missed the electrodes)."""
    scene = scene_of(FAR, mesh_size_mm=4.0)
    for z in (0.0, 0.198, 0.396):
        assert geometry.layout(scene, z).mesh_size == 4e-3
    # also when every length is large: the value the user wrote is the value meshed
    big = scene_of(scaled(30.0), mesh_size_mm=3.0)
    assert geometry.layout(big, 45e-3).mesh_size == 3e-3


def test_the_3d_solver_uses_an_explicit_mesh_size_as_written(monkeypatch):
    from tengfield.field import solver3d
    from tengfield.field.cells import tube as tube_cell

    seen = {}

    def capture(cell, position, *, settings, **_):
        seen["size"] = settings.mesh_size
        return None

    monkeypatch.setattr(solver3d, "solve_cell_3d", capture)
    tube_cell.solve_position_3d(scene_of(FAR, mesh_size_mm=4.0), 0.198, offset=0.1e-3,
                                comm=None)
    assert seen["size"] == 4e-3
    tube_cell.solve_position_3d(scene_of(scaled(3.0, stroke_mm=6.0)), 3e-3, offset=0.1e-3,
                                comm=None)
    assert seen["size"] == pytest.approx(1e-3, rel=1e-12)   # the default, scaled


# -- defaults scale with the smallest feature --------------------------------------------
def test_the_default_scene_keeps_its_mesh_size_to_the_bit():
    written = default_scene()                      # data/default.toml writes 0.5
    unwritten = Scene.from_dict({})                # the schema default, same device
    for scene in (written, unwritten):
        lay = geometry.layout(scene, 1.5e-3)
        assert lay.mesh_size == 0.5e-3 == scene.field.mesh_size
    assert default_mesh_scale(unwritten.device, unwritten.field) == 1.0


@pytest.mark.parametrize("device, expected_mm", [
    (scaled(3.0), 1.5),                                      # geometrically similar x3
    (scaled(3.0, ball_diameter_mm=7.0), 0.5),                # the ball stays small
    (scaled(3.0, electrode_radius_mm=8.0), 1.0),             # electrodes x2 only
    (scaled(3.0, stroke_mm=6.0), 1.0),                          # stroke x2 only
    (scaled(3.0, tube_inner_radius_mm=11.0), 0.5),           # ball-tube clearance x1
    (FAR, 0.5),                                              # 400 mm spacing, small parts
    (scaled(0.5), 0.25),                                     # all smaller: scaled down too
])
def test_the_default_mesh_size_scales_with_the_smallest_feature(device, expected_mm):
    scene = scene_of(device)
    assert geometry.layout(scene, 0.0).mesh_size == pytest.approx(expected_mm * 1e-3,
                                                                  rel=1e-12)


def test_walls_of_permittivity_one_do_not_limit_the_default():
    """Without dielectric walls the tube and plates are not meshed: their thickness does
    not shrink the default size."""
    thin_walls = scaled(3.0, tube_outer_radius_mm=13.0, plate_thickness_mm=1.0)
    # with PMMA walls the 1 mm tube wall (the paper's: 1.5 mm) keeps the default at 0.5 mm
    assert geometry.layout(scene_of(thin_walls), 0.0).mesh_size == 0.5e-3
    airy = {**thin_walls, "wall_permittivity": 1.0}
    assert geometry.layout(scene_of(airy), 0.0).mesh_size == pytest.approx(1.5e-3, rel=1e-12)


@pytest.mark.slow
def test_the_far_device_meshed_as_written_matches_the_analytic_capacitance():
    """The 4 mm / 400 mm device at mesh_size_mm = 4: C_ll and C_lu within 1e-3 of the
    two-disk value (before: the 160 mm mesh gave C_ll 7x too large, 173 cells)."""
    pytest.importorskip("dolfinx")
    from mpi4py import MPI

    from tengfield.field import solve_position

    c_self, c_mutual = far_analytic()
    res = solve_position(scene_of(FAR, mesh_size_mm=4.0), 0.198, comm=MPI.COMM_SELF,
                         estimate_error=False)
    assert res.info["mesh_size_m"] == 4e-3
    assert res.cells > 10_000
    assert res.C_ll == pytest.approx(c_self, rel=1e-3)
    assert res.C_uu == pytest.approx(c_self, rel=1e-3)
    assert res.C_lu == pytest.approx(c_mutual, rel=1e-2)


# -- tengfield field warns once when its estimate misses the tolerance -------------------
@pytest.fixture
def field_cli(run_cli, cli_env):
    pytest.importorskip("dolfinx")
    return lambda *args, cwd: run_cli("field", *args, cwd=cwd,
                                      env=cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true"))


@pytest.mark.slow
@pytest.mark.parametrize("tolerance, warns", [(1e-8, True), (0.5, False)])
def test_field_command_warns_once_when_the_estimate_exceeds_the_tolerance(
        tmp_path, field_cli, tolerance, warns):
    scene = tmp_path / "coarse.toml"
    scene.write_text(f"[field]\nmesh_size_mm = 1.5\ntolerance = {tolerance!r}\n")
    done = field_cli(str(scene), "--position-mm", "1.5", "--no-plots", "-o",
                     str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = [line for line in done.stderr.splitlines() if line.startswith("tengfield: warning:")]
    if not warns:
        assert lines == [], done.stderr
        return
    assert len(lines) == 1, done.stderr
    assert "relative error estimate" in lines[0]
    assert "above [field] tolerance = 1e-08" in lines[0]
    assert "mesh_size_mm = 1.5" in lines[0]
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_a_large_device_without_a_mesh_size_is_not_refused_as_too_fine():
    """Every length x30 and no mesh_size_mm: the scene check judges the scaled default
    (15 mm), which the mesher uses, not the unscaled 0.5 mm (refused before as 'too fine')."""
    from tengfield.field.geometry_axisymmetric import base_mesh_size
    from tengfield.scene import Scene

    lengths = {"ball_diameter_mm": 7.0, "stroke_mm": 3.0, "electrode_radius_mm": 4.0,
               "tube_inner_radius_mm": 4.0, "tube_outer_radius_mm": 5.5,
               "plate_thickness_mm": 2.0}
    scene = Scene.from_dict({"device": {k: 30 * v for k, v in lengths.items()}})
    assert scene.field_problems == ()
    assert base_mesh_size(scene) == pytest.approx(15e-3)
    written = Scene.from_dict({"device": {k: 30 * v for k, v in lengths.items()},
                               "field": {"mesh_size_mm": 0.5}})
    assert any("too fine" in p for p in written.field_problems)
