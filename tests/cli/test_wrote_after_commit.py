"""#43 item 9: "wrote DIR/..." is printed only once the set is in place: a Ctrl-C (or any
failure) while the staged files are moved into DIR printed it for files that were then
not there."""
from __future__ import annotations

import os

import pytest

from tengfield import outputs
from tengfield.cli import main

SHORT = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n"


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "short.toml"
    path.write_text(SHORT)
    return str(path)


@pytest.mark.slow
def test_an_interrupt_during_the_move_prints_no_wrote(tmp_path, capsys, monkeypatch, scene):
    def interrupted(self):
        raise KeyboardInterrupt

    monkeypatch.setattr(outputs.StagedOutput, "commit", interrupted)
    out = tmp_path / "out"
    assert main(["run", scene, "--no-plots", "-o", str(out)]) == 130
    captured = capsys.readouterr()
    assert "wrote" not in captured.out and "wrote" not in captured.err, captured.out
    assert captured.err.strip().endswith("tengfield: interrupted")
    assert not (out / "summary.json").exists()


@pytest.mark.slow
def test_wrote_follows_the_move_and_names_the_files_there(tmp_path, capsys, monkeypatch,
                                                          scene):
    seen = {}
    real_commit = outputs.StagedOutput.commit

    def commit(self):
        seen["before"] = capsys.readouterr().out      # what was printed before the move
        return real_commit(self)

    monkeypatch.setattr(outputs.StagedOutput, "commit", commit)
    out = tmp_path / "out"
    assert main(["run", scene, "--no-plots", "-o", str(out)]) == 0
    after = capsys.readouterr().out
    assert "wrote" not in seen["before"] and "regime" in seen["before"]
    line = next(x for x in after.splitlines() if x.startswith("wrote "))
    for name in line[len("wrote "):].split(", "):
        assert os.path.isfile(name), name
    assert ".tengfield-staging" not in line
