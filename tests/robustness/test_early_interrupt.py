"""Issue 54 item 14: Ctrl-C while the command line is still importing prints the one line a
later interrupt prints and exits 130 (a 20-line KeyboardInterrupt traceback before). The
first ~0.05 s are Python's own start-up (site.py), before any tengfield code runs."""
from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time

import pytest

import plate_model as fx


@pytest.mark.parametrize("delay", [0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0])
def test_an_interrupt_during_start_up_is_one_line_and_exit_130(delay, tmp_path, cli_command,
                                                              cli_env):
    scene = tmp_path / "small.toml"
    scene.write_text(fx.SMALL_SCENE)
    proc = subprocess.Popen(cli_command("run", scene, "-o", tmp_path / "out"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache"))
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 0:       # finished before the signal: nothing to see
        pytest.skip("the run ended before the interrupt")
    assert proc.returncode == 130, err[-2000:]
    assert "Traceback" not in err, err[-2000:]
    assert err.strip().splitlines()[-1] == "tengfield: interrupted"


@pytest.mark.parametrize("where", ["raise KeyboardInterrupt", "raise OSError(5, 'x')"])
def test_an_interrupt_in_code_run_by_exec_still_exits_130(where, tmp_path, cli_env, python):
    """A Ctrl-C that lands in code run by ``exec`` of a string (dataclasses builds a class's
    methods so while a command imports its modules) made CPython end the process by SIGINT
    (exit -2) after tengfield had caught it (1 in ~50 of the timed interrupts above), when
    run as ``python -m`` (as here and in every CLI test)."""
    script = tmp_path / "interrupted_cli.py"
    script.write_text(textwrap.dedent(f"""\
        import sys
        from tengfield import cli

        def command(parser, args):
            try:
                exec("raise KeyboardInterrupt")
            except KeyboardInterrupt as exc:
                if {where.startswith("raise OSError")!r}:
                    {where} from exc
                raise

        cli._run_command = command
        sys.exit(cli.main(["run", "scene.toml"]))
        """))
    out = subprocess.run([python, "-m", "interrupted_cli"], capture_output=True, text=True,
                         env=cli_env(), cwd=tmp_path, timeout=120)
    assert out.returncode == 130, out.stderr[-2000:]
    assert out.stderr.strip().splitlines()[-1] == "tengfield: interrupted"


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_an_interrupt_that_a_c_import_turns_into_an_import_error_exits_130(signame, tmp_path,
                                                                          cli_env, python):
    """numba's import, interrupted inside numpy's C API, raises ``ImportError: numpy._core.
    multiarray failed to import`` with no KeyboardInterrupt to follow (CI, stop 58): a
    command that fails after SIGINT (or SIGTERM, which the command line turns into an
    interrupt) came says it was interrupted."""
    script = tmp_path / "interrupted_import.py"
    script.write_text(textwrap.dedent(f"""\
        import os, signal, sys
        from tengfield import cli

        def command(parser, args):
            failed = False
            try:
                os.kill(os.getpid(), signal.{signame})
                for _ in range(1000):
                    pass
            except KeyboardInterrupt:   # as C code does: the interrupt is gone
                failed = True
            if failed:
                raise ImportError("numpy._core.multiarray failed to import")

        cli._run_command = command
        sys.exit(cli.main(["run", "scene.toml"]))
        """))
    out = subprocess.run([python, "-m", "interrupted_import"], capture_output=True,
                         text=True, env=cli_env(), cwd=tmp_path, timeout=120)
    assert out.returncode == 130, out.stderr[-2000:]
    assert out.stderr.strip().splitlines()[-1] == "tengfield: interrupted"
    assert "Traceback" not in out.stderr


def test_a_library_user_keeps_pythons_keyboard_interrupt():
    """``import tengfield`` in a script or a notebook leaves SIGINT to Python."""
    code = ("import signal, tengfield, tengfield.cli; "
            "print(signal.getsignal(signal.SIGINT) is signal.default_int_handler)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.stdout.strip() == "True", out.stderr
