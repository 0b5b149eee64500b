"""Fixtures for the robustness tests (the CLI runners ``run_cli``, ``cli_command`` and
``cli_env`` come from ``tests/conftest.py``)."""
from pathlib import Path

import pytest


@pytest.fixture
def short_scene(tmp_path) -> Path:
    """A 0.3 s default-device run with small outputs."""
    path = tmp_path / "short.toml"
    path.write_text("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n")
    return path
