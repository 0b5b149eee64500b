"""Issue #53 item 3: a length typed in metres where a ``*_mm`` key asks for mm (0.0015)
warns in one line naming the key, the value and what it would be in mm: one check
(``scene.plausible``) for every ``*_mm`` key of the schema."""
import warnings

import pytest

from tengfield import cli
from tengfield.errors import SceneError
from tengfield.scene import parse_scene, with_settings, default_scene
from tengfield.scene.plausible import PLAUSIBLE_MM, PLAUSIBLE_MM_DEFAULT
from tengfield.scene.schema import SCHEMA

MM_KEYS = [(sec, key) for sec, keys in SCHEMA.items() for key in keys if key.endswith("_mm")]


def caught(build):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        try:
            build()
        except SceneError:      # a rule between keys may refuse the value too: not ours
            pass
    return [str(w.message) for w in seen if "meant in metres" in str(w.message)]


def test_every_mm_key_has_the_check():
    assert len(MM_KEYS) >= 15          # device, excitation, contact, initial, field keys


@pytest.mark.parametrize("section,key", MM_KEYS)
def test_a_tiny_mm_value_in_the_file_warns_naming_key_value_and_mm(section, key):
    bound = PLAUSIBLE_MM.get(key, PLAUSIBLE_MM_DEFAULT)
    value = bound * 0.3
    lines = caught(lambda: parse_scene(f"[{section}]\n{key} = {value!r}\n"))
    assert len(lines) == 1, lines
    assert f"[{section}] {key} = {value:g} mm" in lines[0]
    assert f"{key} = {value * 1e3:g}" in lines[0]          # the value in mm, if metres
    # the bound itself and 0 (a legal "none") are quiet
    assert caught(lambda: parse_scene(f"[{section}]\n{key} = {bound!r}\n")) == []
    assert caught(lambda: parse_scene(f"[{section}]\n{key} = 0.0\n")) == []


def test_set_warns_for_the_set_key_only():
    lines = caught(lambda: with_settings(default_scene(), ["device.stroke_mm=0.0015"]))
    assert lines == ["[device] stroke_mm = 0.0015 mm is 1.5 µm, below the 0.05 mm plausible "
                     "for it: if it was meant in metres, it is stroke_mm = 1.5"]
    assert caught(lambda: with_settings(default_scene(), ["device.stroke_mm=1.5"])) == []


def test_a_harmonics_list_is_checked_element_by_element():
    text = ('[excitation]\nkind = "harmonics"\nfrequency_hz = [30.0, 60.0]\n'
            "amplitude_mm = [0.5, 0.001]\n")
    lines = caught(lambda: parse_scene(text))
    assert len(lines) == 1 and "amplitude_mm = 0.001 mm" in lines[0]


def test_the_cli_line(capsys):
    code = cli.main(["scene", "--set", "excitation.amplitude_mm=0.0015"])
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = [ln for ln in err.splitlines() if "amplitude_mm" in ln]
    assert lines == ["tengfield: warning: [excitation] amplitude_mm = 0.0015 mm is 1.5 µm, "
                     "below the 0.005 mm plausible for it: if it was meant in metres, it "
                     "is amplitude_mm = 1.5"]


def test_a_whole_device_in_metres_is_one_line():
    text = "[device]\nstroke_mm = 0.0015\nball_diameter_mm = 0.008\nplate_thickness_mm = 0.001\n"
    lines = caught(lambda: parse_scene(text))
    assert len(lines) == 1, lines
    assert lines[0].startswith("3 lengths look like metres: ")
    for key, mm in [("stroke_mm", "1.5"), ("ball_diameter_mm", "8"), ("plate_thickness_mm", "1")]:
        assert f"{key} = {mm}" in lines[0]
