"""#8.17: normal use prints only tengfield's own lines.

Every command once, in a fresh process, with cold caches (the ffcx JIT cache
under ``XDG_CACHE_HOME`` and the surrogate cache both in tmp), without
``PYVISTA_OFF_SCREEN`` or ``DISPLAY`` set (the CLI must render off screen by
itself). The field is coarse (degree 1, 1.5 mm): one solve for ``field``, the
fewest positions for ``precompute``, reused by ``run`` and ``sweep``.
"""
import re

import pytest

#: The lines tengfield itself writes to stderr (commands/*.py, _mpi.py, cli.py).
OWN_LINE = re.compile(r"^(tengfield: (warning|error|interrupted)|surrogate: |# field hash )")

COARSE = ("[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 0.5\n"
          "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n")


def foreign_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.strip() and not OWN_LINE.match(line)]


@pytest.mark.slow
@pytest.mark.field
def test_every_command_prints_only_its_own_lines(tmp_path, run_cli, cli_env):
    scene = tmp_path / "coarse.toml"
    scene.write_text(COARSE)
    env = cli_env(XDG_CACHE_HOME=str(tmp_path / "cold-cache"))
    env.pop("TENGFIELD_CACHE_DIR", None)
    commands = [
        ("scene", scene),
        ("info",),
        ("dynamics", scene, "-o", "dyn"),
        ("map", scene, "--frequency-hz", "15:25:2", "--amplitude-mm", "1:2:2", "--periods", "20",
         "--jobs", "1", "-o", "map"),
        ("field", scene, "--position-mm", "1", "-o", "field"),           # cold ffcx JIT + VTK
        ("precompute", scene, "--max-positions", "17"),
        ("run", scene, "-o", "run"),
        ("sweep", scene, "--frequency-hz", "20", "--amplitude-mm", "1.5", "--jobs", "1",
         "-o", "sweep"),
    ]
    seen = {}
    for args in commands:
        result = run_cli(*args, cwd=tmp_path, env=env)
        assert result.returncode == 0, (args, result.stderr)
        assert not foreign_lines(result.stderr), (args[0], result.stderr)
        assert "\x1b[" not in result.stderr + result.stdout, args[0]      # no colour codes
        seen[args[0]] = result
    assert (tmp_path / "cold-cache" / "fenics").is_dir()                  # the JIT really ran cold
    assert (tmp_path / "field" / "field.png").stat().st_size > 10_000    # and VTK still drew


def test_foreign_lines_are_recognised():
    sample = ("INFO:root:running build_ext\n"
              "x86_64-linux-gnu-gcc -shared ./libffcx_forms_0.o -o ./libffcx_forms_0.so\n"
              "WARNING:py.warnings:/x/surrogate.py:569: RuntimeWarning: cache unreadable\n"
              "\x1b[0m\x1b[33m2026-11-23 vtkXOpenGLRenderWindow.:1452 WARN| bad X server\n"
              "tengfield: warning: cache unreadable; recomputing\n"
              "surrogate: computed (17 positions, error estimate 0.01)\n")
    assert len(foreign_lines(sample)) == 4


def test_warnings_and_library_logging_go_through_one_formatter(capsys):
    import logging
    import warnings

    from tengfield import cli

    cli.configure_output()
    root = logging.getLogger()
    level = root.level
    try:
        warnings.warn("surrogate: cache file is not trusted; recomputing", RuntimeWarning)
        root.setLevel(logging.INFO)                    # what setuptools does during a JIT build
        root.info("running build_ext")
        logging.getLogger("py.warnings").warning(
            "/x/surrogate.py:569: RuntimeWarning: cache unreadable\n  warnings.warn(...)\n")
        logging.basicConfig()                          # what ffcx does at import: no effect
        root.info("x86_64-linux-gnu-gcc -shared ...")
    finally:
        root.setLevel(level)
    err = capsys.readouterr().err
    assert err == ("tengfield: warning: surrogate: cache file is not trusted; recomputing\n"
                   "tengfield: warning: cache unreadable\n")
