"""Each dynamics demo runs in --fast mode, prints its comparison with the paper, writes its
figure and returns its numbers from ``main()``."""
import math
from pathlib import Path

import pytest

DEMOS = sorted((Path(__file__).resolve().parents[2] / "demos").glob("dynamics_*.py"))


def numbers_in(value):
    """Every number in a (nested) dict of the demo's results."""
    if isinstance(value, dict):
        return [x for v in value.values() for x in numbers_in(v)]
    return [value] if isinstance(value, (int, float)) and not isinstance(value, bool) else []


def test_there_are_four_dynamics_demos():
    assert len(DEMOS) >= 4


@pytest.mark.slow
@pytest.mark.parametrize("demo", DEMOS, ids=lambda p: p.stem)
def test_demo_runs_fast(demo, tmp_path, load_demo, capsys):
    numbers = load_demo(demo.stem).main(["--fast", "-o", str(tmp_path)])
    assert "paper" in capsys.readouterr().out
    png = tmp_path / f"{demo.stem}.png"
    assert png.exists() and png.stat().st_size > 10_000
    values = numbers_in(numbers)
    assert values and all(math.isfinite(v) for v in values), numbers
