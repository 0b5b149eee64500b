"""#43 item 10: a message about a data file the user named (a recorded excitation, a PSD
table, fit's measured trace) names the file, the line and what was expected, never the
file's text: a credentials file named by mistake, a cell holding a password,
``--set excitation.file=/etc/shadow``, a 100 KB header. Through the CLI, so the promise
holds whichever CSV reader is behind it."""
from __future__ import annotations

import pytest

from tengfield.cli import main

TOKEN = "ghp_s3cr3tT0kenVALUE42"
CREDENTIALS = f"https://alice:{TOKEN}@github.com\n"
SHADOW = "root:*:19700:0:99999:7:::\ndaemon:*:19700:0:99999:7:::\n"


def _error(capsys, argv, code=2) -> str:
    assert main(argv) == code
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err       # one line
    assert err.startswith("tengfield: error: "), err
    return err


def _scene(tmp_path, body: str):
    path = tmp_path / "scene.toml"
    path.write_text(body)
    return str(path)


@pytest.mark.parametrize("section", [
    '[excitation]\nkind = "recorded"\nfile = ".git-credentials"\n',
    '[excitation]\nkind = "random"\npsd_file = ".git-credentials"\n',
])
def test_a_credentials_file_named_in_the_scene_is_not_shown(tmp_path, capsys, section):
    (tmp_path / ".git-credentials").write_text(CREDENTIALS)
    err = _error(capsys, ["scene", _scene(tmp_path, section)])
    assert ".git-credentials" in err
    assert TOKEN not in err and "alice" not in err and "github" not in err, err


def test_a_credentials_file_as_fits_measured_trace_is_not_shown(tmp_path, capsys):
    (tmp_path / ".git-credentials").write_text(CREDENTIALS * 30)
    err = _error(capsys, ["fit", "--measured", str(tmp_path / ".git-credentials"),
                          "-o", str(tmp_path / "fit")])
    assert ".git-credentials" in err and TOKEN not in err and "alice" not in err, err


def test_set_excitation_file_to_a_system_file_is_not_shown(tmp_path, capsys):
    shadow = tmp_path / "shadow"
    shadow.write_text(SHADOW)
    err = _error(capsys, ["scene", "--set", "excitation.kind=recorded",
                          "--set", f"excitation.file={shadow}"])
    assert "root:" not in err and "daemon" not in err and "19700" not in err, err
    assert "shadow" in err


@pytest.mark.parametrize("rows", [
    "time_s,displacement_m\n0.0,0.0\n0.001,hunter2-password\n0.002,0.0\n",      # a cell
    "time_s,displacement_m\n0.0,0.0\n0.001,0.0,hunter2-password\n0.002,0.0\n",  # a row
    "time_s,displacement_m,hunter2-password,hunter2-password\n0.0,0.0,1,1\n",    # twice
    "time_s;hunter2-password\n0.0;0.0\n",                                         # ';'
])
def test_a_data_cell_or_header_name_is_not_echoed(tmp_path, capsys, rows):
    (tmp_path / "rec.csv").write_text(rows)
    err = _error(capsys, ["scene", _scene(
        tmp_path, '[excitation]\nkind = "recorded"\nfile = "rec.csv"\n')])
    assert "hunter2" not in err and "rec.csv" in err, err


def test_a_measured_cell_is_not_echoed_and_the_line_is_named(tmp_path, capsys):
    rows = ["time_s,V_oc_V"] + [f"{i * 1e-3:.3f},{0.1 * i}" for i in range(40)]
    rows[7] = "0.006,hunter2-password"
    (tmp_path / "m.csv").write_text("\n".join(rows) + "\n")
    err = _error(capsys, ["fit", "--measured", str(tmp_path / "m.csv"),
                          "-o", str(tmp_path / "fit")])
    assert "hunter2" not in err and "line 8" in err, err


def test_a_100_kb_header_gives_a_short_line(tmp_path, capsys):
    header = ",".join(f"c{i:05d}_{'x' * 20}" for i in range(4000))     # ~100 KB
    (tmp_path / "wide.csv").write_text(header + "\n" + ",".join(["0"] * 4000) + "\n")
    err = _error(capsys, ["scene", _scene(
        tmp_path, '[excitation]\nkind = "recorded"\nfile = "wide.csv"\n')])
    assert len(err) < 400 and "xxxxxxxxxx" not in err, err[:300]
    assert "4000 columns" in err


def test_a_column_spelled_another_way_is_pointed_at(tmp_path, capsys):
    (tmp_path / "rec.csv").write_text("Time_s,displacement_m\n0.0,0.0\n")
    err = _error(capsys, ["scene", _scene(
        tmp_path, '[excitation]\nkind = "recorded"\nfile = "rec.csv"\n')])
    assert "(did you mean 'Time_s'?)" in err and "time_column = 'time_s'" in err, err
