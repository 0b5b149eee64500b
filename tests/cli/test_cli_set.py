"""``--set section.key=value`` on every command that takes a scene, and
``tengfield scene FILE`` checking every section the commands read (issue #29)."""
from __future__ import annotations

import json
import tomllib

import pytest

from tengfield.cli import build_parser, main
from tengfield.errors import SceneError
from tengfield.scene import load_scene, parse_scene, with_settings

SMALL = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000.0\n"


def _subparsers():
    parser = build_parser()
    return parser._subparsers._group_actions[0].choices          # noqa: SLF001


def test_every_command_that_takes_a_scene_has_set():
    for name, sub in _subparsers().items():
        dests = {a.dest for a in sub._actions}                    # noqa: SLF001
        if "scene" in dests:
            assert "settings" in dests, name
    assert {"run", "dynamics", "field", "sweep", "fit", "design", "report", "precompute",
            "breakdown", "map", "scene"} <= {n for n, s in _subparsers().items()
                                             if any(a.dest == "settings" for a in s._actions)}


def test_set_equals_the_same_value_in_the_file():
    base = parse_scene(SMALL)
    in_file = parse_scene(SMALL + "[excitation]\nfrequency_hz = 30.0\n[circuit]\n"
                          'kind = "load"\nload_ohm = 1e7\n')
    by_set = with_settings(base, ["excitation.frequency_hz=30", "circuit.kind=load",
                                  'circuit.load_ohm = 1e7'])
    assert by_set == in_file
    assert by_set.to_dict() == in_file.to_dict()
    assert by_set.field_hash() == in_file.field_hash()


def test_set_on_the_cli_gives_the_files_summary(tmp_path, capsys):
    """`tengfield dynamics my.toml --set ...` writes the summary the edited file writes."""
    (tmp_path / "a.toml").write_text(SMALL)
    (tmp_path / "b.toml").write_text(SMALL + "[excitation]\nfrequency_hz = 30.0\n"
                                     "amplitude_mm = 2.0\n")
    assert main(["dynamics", str(tmp_path / "a.toml"), "--no-plots", "--set",
                 "excitation.frequency_hz=30", "--set", "excitation.amplitude_mm=2",
                 "-o", str(tmp_path / "set")]) == 0
    assert main(["dynamics", str(tmp_path / "b.toml"), "--no-plots",
                 "-o", str(tmp_path / "file")]) == 0
    a = json.loads((tmp_path / "set" / "summary.json").read_text())
    b = json.loads((tmp_path / "file" / "summary.json").read_text())
    for key in ("regime", "impacts", "max_gap_mm"):
        assert a[key] == b[key], key
    assert (tmp_path / "set" / "trajectory.csv").read_text() == \
        (tmp_path / "file" / "trajectory.csv").read_text()


@pytest.mark.parametrize("setting, needle", [
    ("excitation.frequncy_hz=30", "unknown key [excitation] frequncy_hz (did you mean "
                                  "'frequency_hz'?)"),
    ("excitation.frequency_hz=-3", "[excitation] frequency_hz = -3.0 is out of range: allowed "
                                   "[1e-06, 1e+09]"),
    ("circuit.kind=rectifer", "[circuit] kind = 'rectifer'"),
    ("excitaton.frequency_hz=30", "unknown section [excitaton] (did you mean 'excitation'?)"),
    ("frequency_hz=30", "--set 'frequency_hz=30': write section.key=value"),
])
def test_a_bad_set_is_one_line(tmp_path, capsys, setting, needle):
    code = main(["dynamics", "--set", setting, "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith("tengfield: error: ") and needle in err[0], err[0]
    assert not (tmp_path / "out").exists()


def test_set_reaches_design_and_fit_sections():
    scene = with_settings(parse_scene(SMALL), ["design.objective=charge",
                                               "design.vary.stroke_mm=[2.0, 4.0]"])
    assert scene.raw["design"] == {"objective": "charge", "vary": {"stroke_mm": [2.0, 4.0]}}


# -- tengfield scene FILE checks every section --------------------------------------------
DESIGN = ('[design]\nobjective = "charge"\ncandidates = 4\n[design.vary]\ngap_mm = [2.0, 4.0]\n'
          '[design.excitation]\nfrequency_hz = [20.0]\namplitude_mm = [1.5]\n')


def _scene_cli(tmp_path, capsys, text):
    (tmp_path / "s.toml").write_text(text)
    code = main(["scene", str(tmp_path / "s.toml")])
    return code, capsys.readouterr()


def test_scene_accepts_good_design_and_fit(tmp_path, capsys):
    code, out = _scene_cli(tmp_path, capsys, SMALL + DESIGN + '[fit]\nloss = "soft_l1"\n')
    assert code == 0, out.err
    assert tomllib.loads(out.out)["run"]["duration_s"] == 0.3


@pytest.mark.parametrize("text, needle", [
    (DESIGN.replace("objective", "objectve"),
     "unknown key [design] objectve (did you mean 'objective'?)"),
    (DESIGN.replace('"charge"', '"charg"'), "[design] objective = 'charg'"),
    ('[fit]\nlos = "linear"\n', "unknown key [fit] los (did you mean 'loss'?)"),
    ('[fit]\nloss = "l2"\n', "[fit] loss = 'l2' is not allowed"),
    ("[breakdown]\npressure_kPa = -1.0\n", "[breakdown] pressure_kPa = -1.0"),
    ('[array]\ncels = 4\n', "unknown key [array] cels (did you mean 'cells'?)"),
])
def test_scene_refuses_a_bad_section(tmp_path, capsys, text, needle):
    code, out = _scene_cli(tmp_path, capsys, SMALL + text)
    err = out.err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith("tengfield: error: ") and needle in err[0], err[0]


def test_default_scene_templates_run_when_uncommented(capsys):
    """`scene --default` prints [design] and [fit] commented; uncommented they pass the
    checks design and fit make."""
    from tengfield.commands.scene import check_sections
    from tengfield.scene import default_text

    text = default_text()
    lines = text.splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("# [design]"))
    block = lines[start:]                          # the two templates end the file
    assert all(ln.startswith("#") or not ln.strip() for ln in block)
    uncommented = "\n".join(ln[2:] if ln.startswith("# ") else ln[1:] for ln in block)
    assert "[fit]" in uncommented and "[design.vary]" in uncommented
    scene = parse_scene(text + "\n" + uncommented + "\n")
    assert "design" in scene.raw and "fit" in scene.raw
    check_sections(scene)
    with pytest.raises(SceneError):   # the same checks refuse a typo
        check_sections(parse_scene(text + "\n" + uncommented.replace("objective", "objectve")))
