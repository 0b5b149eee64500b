"""The motion3d demo runs in --fast mode, writes its figures and returns its table."""
import pytest


@pytest.mark.slow
def test_lateral_demo_runs_fast(tmp_path, load_demo, capsys):
    numbers = load_demo("motion3d_lateral").main(["--fast", "-o", str(tmp_path)])
    assert "paper" in capsys.readouterr().out
    for name in ("motion3d_lateral.png", "motion3d_lateral_trajectory3d.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    assert [row["lateral_mm"] for row in numbers["rows"]] == [0.0, 0.5, 2.0]
