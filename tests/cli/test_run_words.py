"""Words that do not confuse (issue #42 item 7): `run --help` names the files a run
writes (a 1-D run writes no trajectory.csv); the rectifier's energies per cycle are
named apart; the contacts per excitation period are not read as the period."""
from __future__ import annotations

import re

import pytest

from tengfield.cli import build_parser, main


def help_of(command: str) -> str:
    parser = build_parser()
    sub = [a for a in parser._subparsers._group_actions][0].choices[command]   # noqa: SLF001
    return sub.format_help()


def test_run_help_names_what_a_run_writes(tmp_path):
    text = " ".join(help_of("run").split())
    assert "trajectory.csv" not in text
    for name in ("waveforms.csv", "summary.json", "impacts.csv", "trajectory.png"):
        assert name in text


@pytest.mark.slow
def test_the_files_of_a_run_are_those_its_help_names(tmp_path, capsys):
    assert main(["run", "--set", "run.duration_s=0.8", "-o", str(tmp_path / "r")]) == 0
    names = {p.name for p in (tmp_path / "r").iterdir() if not p.name.startswith(".")}
    text = help_of("run")
    assert names == {"waveforms.csv", "summary.json", "waveforms.png", "surrogate.png",
                     "impacts.csv", "trajectory.png"}
    assert all(n in " ".join(text.split()) for n in names)


def test_dynamics_says_contacts_per_excitation_period_apart_from_the_period(tmp_path, capsys):
    assert main(["dynamics", "--set", "contact.restitution=0.5", "--no-plots",
                 "-o", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "period 1" in out
    line = [ln for ln in out.splitlines() if ln.startswith("contacts per excitation period")][0]
    assert re.search(r"lower \d", line) and "repeats every 1 excitation period" in line


@pytest.mark.slow
def test_the_rectifier_names_its_energies_apart(tmp_path, capsys):
    assert main(["run", "--set", "run.duration_s=0.8", "--set", "circuit.kind=rectifier",
                 "--set", "circuit.storage_capacitance_uF=1e-4", "--no-plots",
                 "-o", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "CMEO bound (the device's most)" in out
    assert "V-Q loop area of the last period through the rectifier" in out
    assert "into the store" in out and "J per excitation period" in out
    assert "J per cycle" not in out
