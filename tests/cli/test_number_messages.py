"""#30.20: a command-line value just beyond its bound is shown with the digits that tell
it from the bound (`position_mm = 3.0000000001 is out of range: allowed [0, 3]`, not
`3 is out of range: allowed [0, 3]`)."""
from __future__ import annotations

import pytest

from tengfield.commands._ranges import number_text


def test_number_text_keeps_the_digits_that_differ():
    assert number_text(3.5) == "3.5" and number_text(3.0) == "3"
    assert number_text(1e-6) == "1e-06" and number_text(-0.001) == "-0.001"
    assert number_text(3.0000000001) == "3.0000000001"
    assert number_text(1e6 + 1e-7) == repr(1e6 + 1e-7)
    assert number_text(float("inf")) == "inf" and number_text(float("nan")) == "nan"
    for x in (3.0000000001, 0.1 + 0.2, 123456.7, 2.5e-13):
        assert float(number_text(x)) == x      # the text is the number


@pytest.mark.slow
@pytest.mark.parametrize("args, expected", [
    (["--position-mm", "3.0000000001"],
     "position_mm = 3.0000000001 is out of range: allowed [0, 3] mm"),
    (["--position-mm=-1e-13"], "position_mm = -1e-13 is out of range: allowed [0, 3] mm"),
    (["--position-mm", "3", "--offset-mm", "0.5000000001", "--method", "3d"],
     "offset_mm = 0.5000000001 is out of range: allowed [0, 0.5] mm"),
    (["--position-mm", "3.5"], "position_mm = 3.5 is out of range: allowed [0, 3] mm"),
])
def test_field_positions_beyond_the_bound_show_their_digits(tmp_path, run_cli, cli_env, args,
                                                            expected):
    done = run_cli("field", *args, "-o", tmp_path / "out", env=cli_env(MPLBACKEND="Agg"))
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("tengfield: error: ")
    assert expected in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_dynamics_duration_beyond_its_bound_shows_its_digits(tmp_path, run_cli, cli_env):
    done = run_cli("dynamics", "--duration-s", "1000000.0000001", "--no-plots", "-o",
                   tmp_path / "out", env=cli_env(MPLBACKEND="Agg"))
    assert done.returncode == 2
    assert done.stderr.startswith("tengfield: error: --duration-s = 1000000.0000001: ")


def test_show_number_adds_the_digits_that_tell_a_value_from_its_bound():
    from tengfield.scene.limits import show_number

    assert show_number(3.5, 0.0, 3.0) == "3.5" and show_number(3.0, 0.0, 3.0) == "3"
    assert show_number(3.0000000001e-3 * 1e3, 0.0, 3.0) == "3.0000000001"
    assert show_number(-1e-13, 0.0, 3.0) == "-1e-13"
    assert show_number(0.5 + 2e-16, 0.5) == repr(0.5 + 2e-16)


@pytest.mark.parametrize("sections, expected", [
    ({"initial": {"gap_mm": 3.0000000001}},
     "[initial] gap_mm = 3.0000000001 is out of range: allowed [0, 3]"),
    ({"field": {"method": "3d", "ball_offset_mm": 0.5000000001}},
     "[field] ball_offset_mm = 0.5000000001 is out of range: allowed [0, 0.5] mm"),
])
def test_scene_rules_between_keys_show_the_digits_too(sections, expected):
    """The rules between keys (`--set` or the file) said `gap_mm = 3 is out of range:
    allowed [0, 3]`; the keys' own ranges already showed the value as written."""
    from tengfield.errors import SceneError
    from tengfield.scene import check_field, default_scene

    with pytest.raises(SceneError) as info:
        check_field(default_scene().with_values(**sections))
    assert expected in str(info.value)



def test_python_callers_see_the_digits_too():
    """tf.solve_position's check and the cells' own (the Python route, no CLI): a position
    or an offset just past its bound reads as itself, not as the bound."""
    from tengfield.errors import FieldError
    from tengfield.field import check_position
    from tengfield.field.cells import SphericalShell
    from tengfield.field.cells.shell_model3d import _check
    from tengfield.field.cells.solve import solve_cell_position
    from tengfield.field.geometry3d import check_position as check_3d
    from tengfield.field.cells.plate_model3d import cylindrical_cell
    from tengfield.scene import default_scene

    scene = default_scene()                                   # stroke 3 mm
    with pytest.raises(FieldError, match=r"position_mm = 3\.0000000003 is out"):
        check_position(scene, 3.0000000003e-3)
    with pytest.raises(FieldError, match=r"position_mm = 3\.0000000003 is out"):
        check_3d(cylindrical_cell(scene.device), 3.0000000003e-3)
    shell = SphericalShell(cavity_diameter=20e-3, shell_thickness=2e-3, electrode_band=2e-3,
                           ball_diameter=8e-3)                # stroke 12 mm
    with pytest.raises(FieldError, match=r"position_mm = 12\.00000001\d* is out"):
        _check(shell, 12.000000012e-3, 0.0)
    with pytest.raises(FieldError, match=r"offset_mm = 6\.00000001\d* is out"):
        _check(shell, 6e-3, 6.000000012e-3)                   # the centre: a - R = 6 mm
    with pytest.raises(FieldError, match=r"position = 12\.00000001\d* mm is out"):
        from mpi4py import MPI
        solve_cell_position(shell, 12.000000012e-3, comm=MPI.COMM_SELF, mesh_size=2e-3)
