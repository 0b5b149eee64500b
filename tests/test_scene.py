"""Scene files: defaults, units, and one clear error per kind of bad input."""
import math

import pytest

from tengfield.scene import G, SceneError, default_scene, default_text, load_scene, parse_scene


def test_default_scene_is_the_paper_device():
    s = default_scene()
    d = s.device
    assert d.ball_diameter == pytest.approx(7e-3)
    assert d.stroke == pytest.approx(3e-3)
    assert d.plate_spacing == pytest.approx(10e-3)
    assert d.tube_inner_radius == pytest.approx(4e-3)
    assert d.tube_outer_radius == pytest.approx(5.5e-3)
    assert d.surface_charge == pytest.approx(-8e-6)
    assert d.ball_charge == pytest.approx(-8e-6 * math.pi * 49e-6)
    assert s.excitation.frequency == 20.0 and s.excitation.amplitude == pytest.approx(1.5e-3)
    assert s.excitation.gamma == pytest.approx(1.5e-3 * (40 * math.pi) ** 2 / G)
    assert s.is_axisymmetric


def test_default_text_round_trips():
    assert parse_scene(default_text()) == default_scene()


def test_field_hash_tracks_only_field_inputs():
    s = default_scene()
    h = s.field_hash()
    assert s.with_values(excitation={"frequency_hz": 33.0}).field_hash() == h
    assert s.with_values(contact={"restitution": 0.3}).field_hash() == h
    assert s.with_values(circuit={"kind": "load", "load_ohm": 1e6}).field_hash() == h
    assert s.with_values(device={"cells": 91}).field_hash() == h
    assert s.with_values(device={"ball_permittivity": 2.0}).field_hash() != h
    assert s.with_values(field={"mesh_size_mm": 0.4}).field_hash() != h
    assert s.with_values(device={"surface_charge_uC_per_m2": -9.0}).field_hash() != h


BAD = [
    ("[device]\nball_diameter_mm = -7\n", ["ball_diameter_mm", "-7", "(0, inf"]),
    ("[device]\nball_diameter_mm = 0\n", ["ball_diameter_mm", "0"]),
    ("[device]\ngap_mm = nan\n", ["gap_mm", "nan", "not finite"]),
    ("[device]\nball_diameter_mm = 8.0\n", ["ball_diameter_mm", "8", "does not fit", "8) mm"]),
    ("[device]\nelectrode_radius_mm = 6.0\n", ["electrode_radius_mm", "6", "larger than the plate"]),
    ("[contact]\nrestitution = 1.2\n", ["restitution", "1.2", "[0, 1]"]),
    ("[contact]\nrestitution = -0.1\n", ["restitution", "-0.1"]),
    ("[excitation]\nfrequency_hz = 0\n", ["frequency_hz", "0", "(0, inf"]),
    ("[excitation]\nfrequency_hz = -5\n", ["frequency_hz", "-5"]),
    ("[run]\nduration_s = 0\n", ["duration_s", "0"]),
    ("[run]\nduration_s = -1\n", ["duration_s", "-1"]),
    ("[devcie]\ngap_mm = 3\n", ["devcie", "did you mean 'device'"]),
    ("[device]\nball_diamter_mm = 7\n", ["ball_diamter_mm", "did you mean 'ball_diameter_mm'"]),
    ("[contact]\nmodel = 'sofft'\n", ["model", "sofft", "'impact', 'soft'", "did you mean 'soft'"]),
    ("[device]\ngap_mm = 3\nball_diameter_mm = \n", ["malformed TOML", "line 3"]),
    ("[device]\ngap_mm = 'three'\n", ["gap_mm", "'three'", "number"]),
    ("[device]\ncells = 2.5\n", ["cells", "2.5", "whole"]),
    ("[initial]\ngap_mm = 4\n", ["[initial] gap_mm", "4", "[0, 3]"]),
    ("[field]\nmesh_size_mm = 0\n", ["mesh_size_mm", "0"]),
    ("[field]\ndomain_radius_mm = 5\n", ["domain_radius_mm", "5", "must exceed"]),
    ("[circuit]\nload_ohm = -10\n", ["load_ohm", "-10"]),
    ("[circuit]\nparallel_capacitance_pF = -1\n", ["parallel_capacitance_pF", "-1"]),
    ("[circuit]\nreference = 'ground'\n", ["reference", "'ground'", "'floating'"]),
    ("[run]\nsettle_periods = 100\nduration_s = 1\n", ["settle_periods", "100", "steady window"]),
    ("[excitation]\nkind = 'recorded'\n", ["file"]),
]


@pytest.mark.parametrize("text,needles", BAD)
def test_bad_input_names_key_value_and_range(text, needles):
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    msg = str(info.value)
    for n in needles:
        assert n in msg, (n, msg)


def _recorded(tmp_path, body):
    (tmp_path / "table.csv").write_text(body)
    scene = tmp_path / "s.toml"
    scene.write_text("[excitation]\nkind = 'recorded'\nfile = 'table.csv'\n")
    return scene


def test_recorded_file_missing(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text("[excitation]\nkind = 'recorded'\nfile = 'nope.csv'\n")
    with pytest.raises(SceneError, match="nope.csv.*no such file"):
        load_scene(scene)


def test_recorded_file_unsorted(tmp_path):
    s = _recorded(tmp_path, "time_s,displacement_m\n0,0\n0.1,0\n0.05,0\n0.2,0\n0.3,0\n")
    with pytest.raises(SceneError, match="not strictly increasing at data row 3"):
        load_scene(s)


def test_recorded_file_nan(tmp_path):
    s = _recorded(tmp_path, "time_s,displacement_m\n0,0\n0.1,nan\n0.2,0\n0.3,0\n")
    with pytest.raises(SceneError, match="NaN or inf at data row 2"):
        load_scene(s)


def test_recorded_file_wrong_column(tmp_path):
    s = _recorded(tmp_path, "time_s,displacment_m\n0,0\n0.1,0\n0.2,0\n0.3,0\n")
    with pytest.raises(SceneError, match="did you mean 'displacment_m'"):
        load_scene(s)


def test_recorded_file_ok(tmp_path):
    s = _recorded(tmp_path, "time_s,displacement_m\n0,0\n0.1,1e-3\n0.2,0\n0.3,-1e-3\n")
    scene = load_scene(s)
    assert scene.excitation.times.tolist() == [0, 0.1, 0.2, 0.3]


def test_missing_scene_file():
    with pytest.raises(SceneError, match="does not exist"):
        load_scene("/nonexistent/scene.toml")
