"""#43 item 17: switching ``[device] shape`` from the command line and the shapes' keys.

* ``--set device.shape=spherical-shell`` on a tube scene (the default) drops the tube's
  keys (its ``stroke_mm`` is derived for the shell) instead of asking to "leave stroke_mm
  out", which ``--set`` cannot do; keys set in the same command stay;
* shell keys on a tube are named in one warning line, not ignored without a word;
* a hexagonal cell with ``[field] method = "auto"`` (the default) is solved in 3D;
* a shell's messages say "cavity", not "tube"."""
from __future__ import annotations

import math

import pytest

from tengfield.cli import main
from tengfield.errors import FieldError, SceneError
from tengfield.field import resolve_method
from tengfield.scene import load_scene, parse_scene, with_settings


def test_set_shape_to_the_shell_on_the_default_scene(capsys):
    shell = with_settings(load_scene(None), ["device.shape=spherical-shell"])
    dev = shell.device
    assert dev.shape == "spherical-shell"
    assert math.isclose(dev.stroke, dev.cavity_diameter - dev.ball_diameter, rel_tol=1e-12)
    assert "stroke_mm" not in shell.raw["device"]
    assert main(["scene", "--set", "device.shape=spherical-shell"]) == 0
    assert "error" not in capsys.readouterr().err


def test_keys_set_with_the_switch_stay_and_are_checked():
    shell = with_settings(load_scene(None), ["device.shape=spherical-shell",
                                             "device.cavity_diameter_mm=24"])
    assert math.isclose(shell.device.stroke, 24e-3 - shell.device.ball_diameter)
    with pytest.raises(SceneError, match="stroke_mm = 3 does not apply"):
        with_settings(load_scene(None), ["device.shape=spherical-shell",
                                         "device.stroke_mm=3"])


def test_switching_back_to_the_tube_drops_the_shell_keys(capsys):
    shell = parse_scene('[device]\nshape = "spherical-shell"\ncavity_diameter_mm = 20\n'
                        "shell_thickness_mm = 2\nelectrode_band_mm = 2\n")
    tube = with_settings(shell, ["device.shape=tube"])
    assert tube.device.shape == "tube"
    assert not {"cavity_diameter_mm", "shell_thickness_mm"} & set(tube.raw["device"])
    assert tube.device.stroke == load_scene(None).device.stroke


def test_shell_keys_on_a_tube_are_named_in_one_warning(tmp_path, capsys):
    path = tmp_path / "tube.toml"
    path.write_text("[device]\ncavity_diameter_mm = 24\nshell_thickness_mm = 3\n")
    assert main(["scene", str(path)]) == 0
    err = capsys.readouterr().err
    warnings = [line for line in err.splitlines() if "warning" in line]
    assert warnings == ["tengfield: warning: [device] cavity_diameter_mm, shell_thickness_mm "
                        "left out: key(s) of another shape than shape = 'tube' (set [device] "
                        "shape to use them)"], err


def test_a_tools_own_file_of_every_key_does_not_warn(tmp_path, capsys):
    """A file of every key at its default (report's recommended-*.toml, scene.to_dict())
    holds the shell's keys at their defaults: not a user's value, no warning."""
    from tengfield.files import scene_toml

    path = tmp_path / "every.toml"
    path.write_text(scene_toml(load_scene(None).to_dict()))
    assert main(["scene", str(path)]) == 0
    assert "warning" not in capsys.readouterr().err


def test_a_hexagonal_cell_with_method_auto_is_solved_in_3d(tmp_path, capsys):
    path = tmp_path / "hex.toml"
    path.write_text('[device]\nshape = "hexagonal"\n')
    assert main(["scene", str(path)]) == 0, capsys.readouterr().err
    scene = load_scene(path)
    assert scene.field.method == "auto"
    assert resolve_method(scene) == "3d"
    axisymmetric = tmp_path / "hex_axi.toml"
    axisymmetric.write_text('[device]\nshape = "hexagonal"\n[field]\nmethod = "axisymmetric"\n')
    assert main(["scene", str(axisymmetric)]) == 2      # asked for by name: refused
    assert "3D cell" in capsys.readouterr().err


@pytest.mark.slow
def test_a_shells_offset_message_says_cavity(tmp_path, capsys):
    """`tengfield field` with an offset past the cavity's (it said "inside the tube")."""
    path = tmp_path / "shell.toml"
    path.write_text('[device]\nshape = "spherical-shell"\n')
    assert main(["field", str(path), "--position-mm", "5", "--offset-mm", "50",
                 "-o", str(tmp_path / "f")]) == 2
    err = capsys.readouterr().err
    assert "inside the cavity" in err and "tube" not in err, err
    problems = with_settings(load_scene(path), ["field.ball_offset_mm=50"]).field_problems
    assert any("inside the cavity" in p for p in problems), problems
