"""Fixtures for the robustness tests: the CLI as a user runs it."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"


def _cli_env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYVISTA_OFF_SCREEN", "DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    env["PYTHONPATH"] = str(SRC) + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.update(extra)
    return env


@pytest.fixture
def cli_env():
    """``cli_env(**extra)``: the environment of a CLI subprocess, this checkout first and
    nothing set up for it (no PYVISTA_OFF_SCREEN, no DISPLAY: the CLI must cope)."""
    return _cli_env


@pytest.fixture
def cli_command():
    """``cli_command(*args)``: the argv that runs ``tengfield args...``."""
    return lambda *args: [sys.executable, "-m", "tengfield.cli", *map(str, args)]


@pytest.fixture
def run_cli(cli_command):
    """``run_cli(*args, cwd=..., env=None)`` -> CompletedProcess (text, captured)."""
    def run(*args, cwd, env=None, timeout=900):
        return subprocess.run(cli_command(*args), cwd=cwd, env=env or _cli_env(),
                              capture_output=True, text=True, timeout=timeout)
    return run


@pytest.fixture
def short_scene(tmp_path) -> Path:
    """A 0.3 s default-device run with small outputs."""
    path = tmp_path / "short.toml"
    path.write_text("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n")
    return path
