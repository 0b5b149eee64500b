"""Each dynamics demo runs in --fast mode and writes its figure."""
import subprocess
import sys
from pathlib import Path

import pytest

DEMOS = sorted((Path(__file__).resolve().parents[2] / "demos").glob("dynamics_*.py"))


def test_there_are_four_dynamics_demos():
    assert len(DEMOS) >= 4


@pytest.mark.parametrize("demo", DEMOS, ids=lambda p: p.stem)
def test_demo_runs_fast(demo, tmp_path):
    proc = subprocess.run([sys.executable, str(demo), "--fast", "-o", str(tmp_path)],
                          capture_output=True, text=True, timeout=600,
                          env={**__import__("os").environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "paper" in proc.stdout
    png = tmp_path / f"{demo.stem}.png"
    assert png.exists() and png.stat().st_size > 10_000
