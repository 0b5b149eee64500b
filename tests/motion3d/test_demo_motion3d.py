"""The motion3d demo runs in --fast mode and writes its figures."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

DEMO = Path(__file__).resolve().parents[2] / "demos" / "motion3d_lateral.py"


@pytest.mark.slow
def test_lateral_demo_runs_fast(tmp_path):
    proc = subprocess.run([sys.executable, str(DEMO), "--fast", "-o", str(tmp_path)],
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "paper" in proc.stdout
    for name in ("motion3d_lateral.png", "motion3d_lateral_trajectory3d.png"):
        assert (tmp_path / name).stat().st_size > 10_000
