"""#30 item 2: under ``mpirun -n 2`` -o DIR is written all or nothing as in one process:
on a full disk (a 2 MB tmpfs, mounted when the tests run as root; skipped otherwise) the
previous set stays byte for byte and no staging directory is left; a successful run
writes the manifest (its clean-up of the previous set's files holds under mpirun too)."""
import hashlib
import os
import subprocess

import pytest

from helpers import mpi_env, needs_mpirun

MAP = ["map", "--frequency-hz", "10:20:2", "--amplitude-mm", "1:2:2"]
BIGGER = ["map", "--frequency-hz", "10:30:4", "--amplitude-mm", "1:2:3"]


@pytest.fixture
def small_disk(tmp_path):
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs",
                                            str(mnt)], capture_output=True).returncode:
        pytest.skip("a small tmpfs needs root (mount)")
    yield mnt
    subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def mpirun(cli_command, *args):
    return subprocess.run(["timeout", "120", "mpirun", "-n", "2", *cli_command(*args)],
                          capture_output=True, text=True, env=mpi_env(), timeout=150)


def digests(directory):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in directory.iterdir() if p.is_file() and p.name != ".tengfield.lock"}


@pytest.mark.slow
def test_full_disk_under_mpirun_keeps_the_previous_set(small_disk, cli_command):
    needs_mpirun()
    out = small_disk / "D"
    first = mpirun(cli_command, *MAP, "-o", out)
    assert first.returncode == 0, first.stderr
    assert (out / ".tengfield-manifest.json").is_file()     # staged and committed
    before = digests(out)
    (out / "stale.txt").write_text("not the previous command's: never removed\n")
    free = os.statvfs(small_disk).f_bavail * os.statvfs(small_disk).f_frsize
    (small_disk / "filler").write_bytes(b"\0" * max(free - 8192, 0))
    proc = mpirun(cli_command, *BIGGER, "-o", out)
    assert proc.returncode != 0
    assert "No space left on device" in proc.stderr, proc.stderr
    after = digests(out)
    after.pop("stale.txt")
    assert after == before
    assert not list(out.glob(".tengfield-staging-*"))
