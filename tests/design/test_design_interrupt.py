"""SIGTERM to `tengfield design --jobs 2` mid-study: the workers end with it, -o DIR keeps
its previous content and no staging directory is left (analytic plate model: no dolfinx)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ROOT, cli_environment

SLEEPY = '''
import os, time
import plate_model as fx

def solve(scene, position, **kw):
    """plate_model_solve after a long pause: the study is mid-candidate when it is killed."""
    open(os.path.join(os.environ["SLEEPY_DIR"], f"{os.getpid()}.pid"), "w").close()
    time.sleep(60)
    return fx.plate_model_solve(scene, position, **kw)
'''

DRIVER = '''
import functools, sys
import sleepy
import tengfield.design_study
from tengfield import cli

if __name__ == "__main__":   # spawned workers import this module too
    tengfield.design_study.design = functools.partial(tengfield.design_study.design, solve=sleepy.solve)
    sys.exit(cli.main(sys.argv[1:]))
'''

SCENE = """
[design]
objective = "charge"
candidates = 4
field = "scene"
settle_periods = 4
window_periods = 4
[design.vary]
stroke_mm = [1.0, 5.0]
"""


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def _wait_for(condition, limit_s: float = 120.0) -> bool:
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.2)
    return condition()


@pytest.mark.slow   # two spawned workers import tengfield
def test_sigterm_stops_the_workers_and_keeps_the_output_directory(tmp_path):
    (tmp_path / "sleepy.py").write_text(SLEEPY)
    (tmp_path / "driver.py").write_text(DRIVER)
    (tmp_path / "scene.toml").write_text(SCENE)
    pids = tmp_path / "pids"
    pids.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / "design.csv").write_text("previous\n")
    env = cli_environment(SLEEPY_DIR=pids, TENGFIELD_CACHE_DIR=tmp_path / "cache")
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), str(ROOT / "tests"), env["PYTHONPATH"]])
    proc = subprocess.Popen([sys.executable, str(tmp_path / "driver.py"), "design",
                             str(tmp_path / "scene.toml"), "-o", str(out), "--jobs", "2"],
                            cwd=tmp_path, env=env, stdout=subprocess.DEVNULL,
                            stderr=open(tmp_path / "stderr.txt", "w"))   # not a pipe the
    # workers could hold open
    workers: list[int] = []
    try:
        assert _wait_for(lambda: len(list(pids.iterdir())) >= 2), "the workers never started"
        workers = [int(p.stem) for p in pids.iterdir()]
        assert all(_alive(pid) for pid in workers) and proc.pid not in workers
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=120)
        err = (tmp_path / "stderr.txt").read_text()
        gone = _wait_for(lambda: not any(_alive(pid) for pid in workers), 30.0)
        assert gone, f"workers {[p for p in workers if _alive(p)]} outlived the study"
        assert proc.returncode == 130 and "tengfield: interrupted" in err, err
        assert (out / "design.csv").read_text() == "previous\n"
        assert not any(p.name.startswith(".tengfield-staging") for p in out.iterdir())
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for pid in workers:
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
