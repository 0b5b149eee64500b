"""`[device] stroke_mm` is the free stroke (issue #29); the old name `gap_mm` is read for
one release with one warning line saying what to write; `[initial] gap_mm` (the ball's
gap) keeps its name; the cached surrogates keep their field hash."""
from __future__ import annotations

import tomllib
import warnings

import pytest

from tengfield.cli import main
from tengfield.errors import SceneError
from tengfield.scene import default_scene, default_text, parse_scene

# the default scene's field hash (sigma left out of it since #28: the value of test_scene_schema)
DEFAULT_FIELD_HASH = "b60e9f08787bcb2dcfe3f4759b8cac5b3bf8488ea49dd5adb3b2c65053007eff"


def test_stroke_mm_is_the_stroke():
    scene = parse_scene("[device]\nstroke_mm = 2.5\n[initial]\ngap_mm = 1.0\n")
    assert scene.device.stroke == pytest.approx(2.5e-3)
    assert scene.initial.gap == pytest.approx(1e-3)
    assert scene.to_dict()["device"]["stroke_mm"] == 2.5 and "gap_mm" not in scene.to_dict()["device"]
    assert "stroke_mm = 3.0" in default_text()


def test_old_key_reads_the_same_scene_with_one_warning():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        old = parse_scene("[device]\ngap_mm = 2.5\n", source="old.toml")
    new = parse_scene("[device]\nstroke_mm = 2.5\n")
    assert old == new and old.field_hash() == new.field_hash()
    said = [str(w.message) for w in caught]
    assert said == ["old.toml: [device] gap_mm is now called stroke_mm: write stroke_mm = 2.5 "
                    "(gap_mm is read until the next release)"]


def test_both_names_are_refused():
    with pytest.raises(SceneError, match=r"\[device\] gap_mm and stroke_mm are the same key"):
        parse_scene("[device]\ngap_mm = 2.5\nstroke_mm = 3.0\n")


def test_with_values_replaces_the_value_under_either_name():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        old = parse_scene("[device]\ngap_mm = 2.5\n")
    assert old.with_values(device={"stroke_mm": 2.0}).device.stroke == pytest.approx(2e-3)
    assert default_scene().with_values(device={"gap_mm": 2.0}).device.stroke == pytest.approx(2e-3)


def test_field_hash_unchanged_by_the_rename():
    """The rename is a name only: the field hash of the default scene is the pinned one
    (test_scene_schema.DEFAULT_FIELD_HASH) and the old key gives the same hash."""
    assert default_scene().field_hash() == DEFAULT_FIELD_HASH
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        old = parse_scene("[device]\ngap_mm = 3.0\n")
    assert old.field_hash() == DEFAULT_FIELD_HASH


def test_cli_warns_once(tmp_path, capsys):
    (tmp_path / "old.toml").write_text("[device]\ngap_mm = 2.5\n")
    assert main(["scene", str(tmp_path / "old.toml")]) == 0
    out = capsys.readouterr()
    lines = [ln for ln in out.err.splitlines() if "gap_mm" in ln]
    assert len(lines) == 1 and lines[0].startswith("tengfield: warning: ")
    assert "write stroke_mm = 2.5" in lines[0]
    assert tomllib.loads(out.out)["device"]["stroke_mm"] == 2.5


def test_set_with_the_old_name_warns_once_and_sets_the_stroke(tmp_path, capsys):
    (tmp_path / "old.toml").write_text("[device]\ngap_mm = 2.5\n")
    assert main(["scene", str(tmp_path / "old.toml"), "--set", "run.duration_s=2"]) == 0
    out = capsys.readouterr()
    assert len([ln for ln in out.err.splitlines() if "gap_mm" in ln]) == 1   # the file's
    assert main(["scene", "--set", "device.gap_mm=2"]) == 0
    out = capsys.readouterr()
    lines = [ln for ln in out.err.splitlines() if "gap_mm" in ln]
    assert len(lines) == 1 and "write --set device.stroke_mm=2" in lines[0]
    assert tomllib.loads(out.out)["device"]["stroke_mm"] == 2
