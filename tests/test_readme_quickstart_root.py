"""README's Quick start as root on a fresh machine (issue #42 item 1).

Open MPI's ``mpirun`` refuses to start as root unless the environment says
``OMPI_ALLOW_RUN_AS_ROOT=1`` and ``OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1`` (Open MPI 4 and
5 read only these variables; no MCA parameter file covers the check), so the block
exports them once, before its first ``mpirun`` line, and the lines run in one shell.
"""
from __future__ import annotations

import os
import shutil
import subprocess

import pytest

from helpers import quick_start_commands, quick_start_script

ROOT_VARS = ("OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM")


def fresh_env() -> dict:
    """This environment without the run-as-root variables (a fresh shell)."""
    return {k: v for k, v in os.environ.items() if k not in ROOT_VARS}


def test_the_block_allows_mpirun_as_root_before_its_first_mpirun_line():
    lines = quick_start_commands()
    first_mpirun = next(i for i, ln in enumerate(lines) if ln.startswith("mpirun "))
    exports = [ln for ln in lines[:first_mpirun] if ln.startswith("export ")]
    assert any(all(f"{v}=1" in ln for v in ROOT_VARS) for ln in exports), exports


def test_every_line_but_the_export_is_a_command():
    """The exports are the block's environment, not a command of their own."""
    lines = quick_start_commands()
    assert all(ln.split()[0] in ("make", "export", "mpirun") or ".venv/bin/tengfield" in ln
               for ln in lines)


@pytest.mark.skipif(shutil.which("mpirun") is None or os.geteuid() != 0,
                    reason="needs mpirun and root")
def test_mpirun_starts_as_root_with_the_block_environment(tmp_path):
    """The block's lines up to its first mpirun, with that mpirun line's program
    replaced by ``true``, as one script in a shell without the variables."""
    lines = quick_start_commands()
    exports = [ln for ln in lines if ln.startswith("export ")]
    bare = subprocess.run(["bash", "-c", "mpirun -n 1 true"], env=fresh_env(),
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert bare.returncode != 0 and "root" in bare.stderr     # the check this is about
    script = quick_start_script(exports + ["mpirun -n 1 true"])
    proc = subprocess.run(["bash", "-c", script], env=fresh_env(), capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
