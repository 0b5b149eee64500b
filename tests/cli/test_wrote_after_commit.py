"""#43 item 9: "wrote DIR/..." is printed only once the set is in place: a Ctrl-C (or any
failure) while the staged files are moved into DIR printed it for files that were then
not there."""
from __future__ import annotations

import os

import pytest

from tengfield.files import directory as outputs
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


DRIVER = '''
import errno, sys
from tengfield import cli
from tengfield.files import directory as outputs
from tengfield.commands import dynamics

real_map = dynamics._run_map


def run_map(args):          # a command that says what it wrote, as run and sweep do
    code = real_map(args)
    print(f"wrote {args.output}/map.csv")
    return code


def commit(self):           # as the real one fails: its staging directory cleaned up
    self._cleanup()
    raise OSError(errno.ENOSPC, "No space left on device", str(self.target / "map.csv"))


dynamics._run_map = run_map
outputs.StagedOutput.commit = commit
sys.exit(cli.main(sys.argv[1:]))
'''


@pytest.mark.slow
def test_under_mpirun_a_failed_move_prints_no_wrote(tmp_path):
    """Rank 0 moves the set into place under mpirun: a failure there (a full disk) prints
    its one line and no "wrote" (`map`: no field solve)."""
    import shutil
    import subprocess
    import sys

    from helpers import mpi_env

    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    (tmp_path / "driver.py").write_text(DRIVER)
    out = tmp_path / "out"
    proc = subprocess.run(["timeout", "200", "mpirun", "-n", "2", sys.executable,
                           str(tmp_path / "driver.py"), "map", "--frequency-hz", "10:20:2",
                           "--amplitude-mm", "1:2:2", "-o", str(out)],
                          capture_output=True, text=True, env=mpi_env(), timeout=240)
    assert proc.returncode not in (0, 124), proc.stderr
    assert "wrote" not in proc.stdout and "wrote" not in proc.stderr, proc.stdout
    assert "points" in proc.stdout                       # the rest of the terminal lines
    ours = [line for line in proc.stderr.splitlines() if line.startswith("tengfield: error")]
    assert ours == [f"tengfield: error: No space left on device: {out / 'map.csv'}"], \
        proc.stderr
    assert not out.exists()
