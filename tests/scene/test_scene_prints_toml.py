"""``tengfield scene FILE`` prints the checked scene as TOML, a scene file that loads back
to the same scene; ``--json`` keeps the JSON (issue #42 item 7)."""
from __future__ import annotations

import json
import tomllib

from tengfield.cli import main
from tengfield.scene import load_scene

DESIGN = ('[design]\nobjective = "charge"\n[design.vary]\nstroke_mm = [1.0, 3.0]\n'
          '[design.excitation]\nfrequency_hz = [20.0]\namplitude_mm = [1.5]\n')


def test_scene_file_prints_toml_that_loads_back(tmp_path, capsys):
    (tmp_path / "s.toml").write_text("[run]\nduration_s = 0.7\n" + DESIGN)
    assert main(["scene", str(tmp_path / "s.toml"), "--set", "contact.restitution=0.4"]) == 0
    text = capsys.readouterr().out
    data = tomllib.loads(text)
    assert data["run"]["duration_s"] == 0.7 and data["contact"]["restitution"] == 0.4
    assert data["design"]["vary"]["stroke_mm"] == [1.0, 3.0]
    (tmp_path / "again.toml").write_text(text)
    again, first = load_scene(tmp_path / "again.toml"), load_scene(tmp_path / "s.toml")
    assert again.field_hash() == first.field_hash()
    assert again.to_dict()["run"] == {**first.to_dict()["run"]}


def test_json_on_request(tmp_path, capsys):
    (tmp_path / "s.toml").write_text("[run]\nduration_s = 0.7\n")
    assert main(["scene", str(tmp_path / "s.toml"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["run"]["duration_s"] == 0.7
