"""SIGTERM (``kill``, a batch system's time limit) ends any command as Ctrl-C does
(cli.py): ``tengfield: interrupted``, exit 130, -o DIR keeps its previous content, no
staging directory, and no worker process outlives it or prints a traceback. Before,
`tengfield map --jobs 2` died with -15, left .tengfield-staging-* in DIR and its
workers printed BrokenPipeError tracebacks."""
from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        text = (task / "children").read_text() if (task / "children").exists() else ""
        out += [int(c) for c in text.split()]
    return out


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.slow
@pytest.mark.parametrize("jobs", ["2", "1"])
def test_sigterm_ends_map_like_ctrl_c(tmp_path, cli_command, cli_env, jobs):
    out = tmp_path / "out"
    out.mkdir()
    (out / "map.csv").write_text("previous\n")
    err_path = tmp_path / "stderr.txt"
    proc = subprocess.Popen(
        cli_command("map", "--frequency-hz", "5:70:60", "--amplitude-mm", "0.1:5:60",
                    "--periods", "3000", "--jobs", jobs, "-o", str(out)),
        cwd=tmp_path, env=cli_env(), stdout=subprocess.DEVNULL, stderr=open(err_path, "w"))
    workers: list[int] = []
    try:
        end = time.monotonic() + 60
        while time.monotonic() < end and proc.poll() is None:   # the grid is under way
            if any(p.name.startswith(".tengfield-staging") for p in out.iterdir()):
                workers = _children(proc.pid)
                if jobs == "1" or len(workers) >= 2:
                    break
            time.sleep(0.2)
        time.sleep(1.0)
        assert proc.poll() is None, "the map ended before it could be interrupted"
        workers = _children(proc.pid)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
        err = err_path.read_text()
        assert proc.returncode == 130, err
        assert err.strip().splitlines()[-1] == "tengfield: interrupted", err
        assert "Traceback" not in err and "Error" not in err, err
        assert (out / "map.csv").read_text() == "previous\n"
        assert not any(p.name.startswith(".tengfield-staging") for p in out.iterdir())
        end = time.monotonic() + 30
        while time.monotonic() < end and any(_alive(w) for w in workers):
            time.sleep(0.2)
        assert not [w for w in workers if _alive(w)], "workers outlived the command"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
