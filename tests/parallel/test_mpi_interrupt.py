"""#43 items 7 and 8 under ``mpirun``: Ctrl-C or SIGTERM mid-study (``design``,
``uncertainty``) ends every rank promptly, also a rank blocked in an MPI call waiting for
another (``tengfield._mpi.SignalExit``): ``tengfield: interrupted`` once, no staging
directory, lock or new -o left, a previous -o set kept; and an error on one rank only
(not rank 0) is one line with nothing left in a new -o and no Open MPI abort banner.

Open MPI 4's mpirun forwards both SIGINT and SIGTERM to the ranks as SIGTERM and exits 1
by its own rule after a signal (the ranks exit 128 + the signal); the exit status is
checked to be that of the launcher's rule or the rank's."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ROOT, cli_environment
from helpers import needs_mpirun

pytestmark = pytest.mark.slow

SLEEPY = '''
import os, time
import plate_model as fx

def solve(scene, position, **kw):
    """plate_model_solve; on ranks other than 0 after a long pause, so rank 0 finishes
    the other candidates and waits for them in an MPI call."""
    rank = os.environ.get("OMPI_COMM_WORLD_RANK", "0")
    if rank != "0" and not os.environ.get("FAIL_ON_RANK"):
        open(os.path.join(os.environ["SLEEPY_DIR"], f"{os.getpid()}.pid"), "w").close()
        time.sleep(120)
    if os.environ.get("FAIL_ON_RANK") == rank:
        import errno        # not a candidate's own error (those are skipped): a fault
        raise OSError(errno.ENOSPC, f"No space left on device (rank {rank} on purpose)",
                      "/cache/surrogate.h5")
    return fx.plate_model_solve(scene, position, **kw)
'''

DRIVER = '''
import functools, sys
import sleepy
import tengfield.design_study
from tengfield import cli

if __name__ == "__main__":
    tengfield.design_study.design = functools.partial(tengfield.design_study.design, solve=sleepy.solve)
    sys.exit(cli.main(sys.argv[1:]))
'''

DESIGN = """
[design]
objective = "charge"
candidates = 6
field = "scene"
settle_periods = 4
window_periods = 4
[design.vary]
stroke_mm = [1.0, 5.0]
"""

STUDY = """
[uncertainty]
samples = 4096
method = "sobol"
seed = 5
[uncertainty.vary]
"device.surface_charge_uC_per_m2" = { distribution = "uniform", low = -25.9, high = -13.0 }
"contact.restitution" = { distribution = "uniform", low = 0.05, high = 0.5 }
"""

#: what Open MPI prints when a rank calls MPI_Abort or dies on its own
NOISE = ("MPI_ABORT", "-------", "mpirun detected", "Primary job", "exited on signal")


def _ranks_with(marker: str) -> list[int]:
    """PIDs of the processes other than mpirun whose command line names ``marker``."""
    pids = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            argv = (proc / "cmdline").read_bytes().split(b"\0")
            state = (proc / "stat").read_text().split(")")[-1].split()[0]
        except OSError:
            continue
        if state != "Z" and marker.encode() in argv and b"mpirun" not in argv[0]:
            pids.append(int(proc.name))
    return pids


def _wait_for(condition, limit_s: float) -> bool:
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.1)
    return condition()


def _mpirun(n: int, argv: list, tmp_path: Path, **extra) -> subprocess.Popen:
    settings = dict(TENGFIELD_CACHE_DIR=tmp_path / "cache", SLEEPY_DIR=tmp_path / "pids",
                    OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg")
    env = cli_environment(**{**settings, **extra})
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), str(ROOT / "tests"),
                                         str(ROOT / "tests" / "parallel"), env["PYTHONPATH"]])
    return subprocess.Popen(["mpirun", "-n", str(n), *map(str, argv)], cwd=tmp_path, env=env,
                            stdout=subprocess.DEVNULL,
                            stderr=open(tmp_path / "stderr.txt", "w"))


def _design(tmp_path: Path) -> list:
    (tmp_path / "sleepy.py").write_text(SLEEPY)
    (tmp_path / "driver.py").write_text(DRIVER)
    (tmp_path / "scene.toml").write_text(DESIGN)
    (tmp_path / "pids").mkdir()
    return [sys.executable, tmp_path / "driver.py", "--quiet", "design",
            tmp_path / "scene.toml"]


def _open_mpi_major() -> int:
    """4 on Debian 12, 5 on Debian 13 (``mpirun --version``: "mpirun (Open MPI) 5.0.7")."""
    text = subprocess.run(["mpirun", "--version"], capture_output=True, text=True).stdout
    match = re.search(r"Open MPI\)?\s+(\d+)\.", text)
    return int(match.group(1)) if match else 0


def _check_interrupted(proc, tmp_path, out: Path, signum: int, *, previous: bool):
    proc.send_signal(signum)
    proc.wait(timeout=60)
    err = (tmp_path / "stderr.txt").read_text()
    assert _wait_for(lambda: not _ranks_with(str(out)), 5.0), \
        f"ranks {_ranks_with(str(out))} outlived mpirun"
    assert proc.returncode in (1, 128 + signum), (proc.returncode, err)
    if _open_mpi_major() >= 5:
        # Open MPI 5's launcher (prterun) forwards the signal to the ranks as SIGTERM but
        # no longer forwards their output once signalled: the line may not reach us
        assert err.count("tengfield: interrupted") <= 1, err
    else:
        assert err.count("tengfield: interrupted") == 1, err
    assert not any(word in err for word in NOISE) and "Traceback" not in err, err
    if previous:
        # the lock file stays in a directory that was there before, as in one process;
        # rank 0's janitor removes the staging directory once the ranks are gone (it may
        # still be at it when the launcher returns: Open MPI 5 under load)
        assert _wait_for(lambda: {p.name for p in out.iterdir()}
                         <= {"design.csv", ".tengfield.lock"}, 10.0), list(out.iterdir())
        assert (out / "design.csv").read_text() == "previous\n"
    else:
        assert _wait_for(lambda: not out.exists(), 10.0), list(out.iterdir())


@pytest.mark.parametrize("signum, ranks", [(signal.SIGINT, 2), (signal.SIGTERM, 3)])
def test_an_interrupted_design_ends_every_rank_cleanly(tmp_path, signum, ranks):
    """Rank 0 waits in an MPI call for the others, which sit in a long field solve."""
    needs_mpirun()
    argv = _design(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "design.csv").write_text("previous\n")
    proc = _mpirun(ranks, [*argv, "-o", out], tmp_path)
    try:
        assert _wait_for(lambda: len(list((tmp_path / "pids").iterdir())) >= ranks - 1, 240), \
            (tmp_path / "stderr.txt").read_text()
        time.sleep(2.0)                  # rank 0 is through its candidates, waiting
        assert proc.poll() is None
        _check_interrupted(proc, tmp_path, out, signum, previous=True)
    finally:
        if proc.poll() is None:
            proc.kill()
        for pid in _ranks_with(str(out)):
            os.kill(pid, signal.SIGKILL)


def test_an_interrupted_uncertainty_study_leaves_no_new_directory(tmp_path, cli_command):
    needs_mpirun()
    (tmp_path / "pids").mkdir()
    (tmp_path / "study.toml").write_text(STUDY)
    out = tmp_path / "new" / "out"
    proc = _mpirun(2, [*cli_command("--quiet", "uncertainty", tmp_path / "study.toml",
                                    "--no-plots", "-o", out)], tmp_path,
                   TENGFIELD_CACHE_DIR=os.environ.get("TENGFIELD_CACHE_DIR",
                                                      Path.home() / ".cache" / "tengfield"))
    try:
        assert _wait_for(lambda: out.is_dir() and any(
            p.name.startswith(".tengfield-staging") for p in out.iterdir()), 240), \
            (tmp_path / "stderr.txt").read_text()
        time.sleep(3.0)                  # the draws are under way
        assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
        _check_interrupted(proc, tmp_path, out, signal.SIGINT, previous=False)
    finally:
        if proc.poll() is None:
            proc.kill()
        for pid in _ranks_with(str(out)):
            os.kill(pid, signal.SIGKILL)


@pytest.mark.parametrize("ranks", [2, 3])
def test_an_error_on_another_rank_than_0_is_one_line_and_leaves_nothing(tmp_path, ranks):
    """Item 8: rank 1's field solve fails; the others (rank 0 with the staging directory)
    are told, every rank ends through the agreement: one line, no Open MPI banner, no
    staging directory, lock or new -o left (as in one process)."""
    needs_mpirun()
    argv = _design(tmp_path)
    out = tmp_path / "new" / "out"
    proc = _mpirun(ranks, [*argv, "-o", out], tmp_path, FAIL_ON_RANK="1")
    try:
        proc.wait(timeout=240)
        err = (tmp_path / "stderr.txt").read_text()
        assert proc.returncode != 0, err
        # mpirun's own banner for a rank's non-zero exit (any failing command under
        # mpirun has it; `mpirun -q` leaves it out) is not tengfield's: its lines are
        lines = [line for line in err.splitlines() if line.startswith("tengfield")]
        assert lines == ["tengfield: error on rank 1 of %d: No space left on device (rank 1 "
                         "on purpose): /cache/surrogate.h5" % ranks], err
        assert "MPI_ABORT" not in err and "Traceback" not in err, err
        assert not out.exists() and not out.parent.exists(), list(out.parent.rglob("*"))
    finally:
        if proc.poll() is None:
            proc.kill()
