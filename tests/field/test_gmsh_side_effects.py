"""#30 items 12, 13: starting gmsh leaves the process as it was.

``gmsh.initialize`` set the C-level SIGTERM (and SIGPIPE) handler back to the default
under Python's: after any gmsh solve, SIGTERM killed tengfield with exit 143, no
``tengfield: interrupted`` and a staging directory left in -o. And the FLTK in the gmsh
wheel wrote ``~/.fltk/fltk.org/fltk.prefs`` on every solve.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

_PROBE = textwrap.dedent("""
    import os, signal, sys
    from tengfield.field._gmsh import initialize
    import gmsh

    got = []
    signal.signal(signal.SIGTERM, lambda signum, frame: got.append(signum))
    initialize(["-nt", "1"], readConfigFiles=False, interruptible=False)
    gmsh.finalize()
    initialize(interruptible=False)          # a second start (the 3D solver's)
    gmsh.finalize()
    os.kill(os.getpid(), signal.SIGTERM)     # the default disposition would end us here
    print("handled" if got == [signal.SIGTERM] else "lost",
          signal.getsignal(signal.SIGPIPE) == signal.SIG_IGN)
    """)


@pytest.mark.slow
def test_gmsh_start_keeps_the_sigterm_handler_and_writes_nothing_in_home(tmp_path, cli_env):
    home = tmp_path / "home"
    home.mkdir()
    done = subprocess.run([sys.executable, "-c", _PROBE], env=cli_env(HOME=str(home)),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.returncode, done.stderr)
    assert done.stdout.split() == ["handled", "True"], done.stdout
    assert list(home.iterdir()) == []                  # no ~/.fltk/fltk.org/fltk.prefs
    assert not list(tmp_path.glob("tengfield-gmsh-*"))


@pytest.mark.slow
@pytest.mark.field
def test_sigterm_after_a_cold_field_stage_is_an_interrupt(tmp_path, cli_command, cli_env):
    """A cold run (empty surrogate cache): SIGTERM once the surrogate is cached (the
    gmsh solves are done) ends it as Ctrl-C does."""
    scene = tmp_path / "coarse.toml"
    scene.write_text("[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 0.5\n"
                     "[run]\nduration_s = 400\nsettle_periods = 2\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("previous\n")
    home = tmp_path / "home"
    home.mkdir()
    err_path = tmp_path / "stderr.txt"
    env = cli_env(TENGFIELD_CACHE_DIR=str(tmp_path / "cache"), HOME=str(home),
                  XDG_CACHE_HOME=os.environ.get("XDG_CACHE_HOME",
                                                os.path.expanduser("~/.cache")))
    with open(err_path, "w") as err_file:
        proc = subprocess.Popen(cli_command("run", scene, "--no-plots", "-o", out), cwd=tmp_path,
                                env=env, stdout=subprocess.DEVNULL, stderr=err_file)
    try:
        end = time.monotonic() + 600
        while time.monotonic() < end and proc.poll() is None \
                and not list((tmp_path / "cache").glob("surrogate-*.h5")):
            time.sleep(0.2)
        time.sleep(0.5)
        assert proc.poll() is None, ("the run ended before the signal", err_path.read_text())
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
        err = err_path.read_text()
        assert proc.returncode == 130, (proc.returncode, err)
        assert err.strip().splitlines()[-1] == "tengfield: interrupted", err
        assert "Traceback" not in err, err
        assert (out / "summary.json").read_text() == "previous\n"
        assert not any(p.name.startswith(".tengfield-staging") for p in out.iterdir())
        assert not (home / ".fltk").exists()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
