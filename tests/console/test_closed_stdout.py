"""A closed stdout (``tengfield run ... | head -1``) loses nothing (issue #42 item 2).

The reader of stdout went away: tengfield stops printing, finishes the command (its
-o directory written complete), blames no path and exits as a Unix tool whose pipe
closed does (status 141 = 128 + SIGPIPE, nothing on stderr)."""
from __future__ import annotations

import json
import subprocess

import pytest

pytestmark = pytest.mark.slow


def run_with_stdout_closed(cli_command, *args, cwd):
    """``tengfield args`` with its stdout a pipe whose reader closed before it wrote."""
    from conftest import cli_environment

    proc = subprocess.Popen(cli_command(*args), cwd=cwd, env=cli_environment(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    proc.stdout.close()                 # `| head -0`: nobody reads
    err = proc.stderr.read()
    return proc.wait(timeout=600), err


def test_dynamics_into_a_closed_pipe_writes_its_files(cli_command, tmp_path):
    code, err = run_with_stdout_closed(cli_command, "dynamics", "--set", "run.duration_s=0.8",
                                       "-o", "out/dyn", cwd=tmp_path)
    out = tmp_path / "out" / "dyn"
    assert "Broken pipe" not in err and "error" not in err, err
    assert code == 141
    for name in ("trajectory.csv", "impacts.csv", "summary.json", "trajectory.png"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert json.loads((out / "summary.json").read_text())["duration_s"] == pytest.approx(0.8)


def test_run_into_head_keeps_the_run(tmp_path):
    """The issue's line, through bash: ``run -o out/q2 --no-plots | head -1``."""
    from conftest import cli_environment
    import sys

    env = cli_environment()
    proc = subprocess.run(["bash", "-c", f"set -o pipefail; {sys.executable} -m tengfield.cli "
                          "run --set run.duration_s=0.8 -o out/q2 --no-plots | head -1"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
    assert "Broken pipe" not in proc.stderr and "error" not in proc.stderr, proc.stderr
    assert proc.stdout.count("\n") == 1
    out = tmp_path / "out" / "q2"
    assert (out / "summary.json").is_file() and (out / "waveforms.csv").is_file()
    assert proc.returncode in (0, 141)      # 141 only if tengfield wrote after head left


@pytest.mark.field
def test_a_field_solve_into_a_closed_pipe_writes_its_files(cli_command, tmp_path):
    """With the field solved in the run (gmsh, PETSc): gmsh died of SIGPIPE and PETSc's
    signal handler turned the EPIPE of tengfield's own line into a crash (exit -11, no
    output directory). C libraries now write to /dev/null, SIGPIPE stays ignored."""
    code, err = run_with_stdout_closed(
        cli_command, "run", "--set", "run.duration_s=0.8", "--set", "field.mesh_size_mm=1.5",
        "--set", "field.degree=1", "--set", "field.tolerance=0.2", "--no-plots",
        "--cache-dir", tmp_path / "cache", "-o", "out/r", cwd=tmp_path)
    assert code == 141 and "error" not in err, (code, err)
    assert list((tmp_path / "cache").glob("surrogate-*.h5"))       # it did solve
    for name in ("waveforms.csv", "summary.json", "impacts.csv"):
        assert (tmp_path / "out" / "r" / name).stat().st_size > 0
