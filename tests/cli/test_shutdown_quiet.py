"""The wrappers ``tengfield`` puts around stdout and stderr say nothing when Python
collects them at exit (Debian 13's Python 3.13 printed ``Exception ignored in:
<tengfield.cli._PathRewriter ...> ... ImportError: sys.meta_path is None`` after a
sweep or an uncertainty study had written everything)."""
from __future__ import annotations

import subprocess
import sys

from conftest import cli_environment

PROGRAM = """
import sys
from tengfield import _console, cli
sys.stdout = cli._PathRewriter(_console.PipeSafeStdout(sys.stdout), "/staging", "/out")
sys.stderr = cli._PathRewriter(_console.PipeSafeStdout(sys.stderr), "/staging", "/out")
print("results in /staging/a.csv")
# held (as a progress bar or a warnings registry may hold one) until Python shuts down
_console.held_at_exit = (sys.stdout, sys.stderr)
sys.stdout, sys.stderr = sys.__stdout__, sys.__stderr__
"""


def test_wrapped_streams_collected_at_exit_print_nothing_more():
    proc = subprocess.run([sys.executable, "-c", PROGRAM], capture_output=True, text=True,
                          env=cli_environment(), timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == "", proc.stderr
    assert proc.stdout == "results in /out/a.csv\n"

