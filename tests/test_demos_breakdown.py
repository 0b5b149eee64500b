"""demos/breakdown_limit.py runs in --fast mode, writes its figure and returns its numbers."""
from __future__ import annotations

import pytest


@pytest.mark.slow   # field surrogates of seven devices (coarse) and their runs
def test_breakdown_demo(load_demo, tmp_path):
    cache = tmp_path / "cache"
    numbers = load_demo("breakdown_limit").main(["--fast", "-o", str(tmp_path),
                                                 "--cache-dir", str(cache)])
    png = tmp_path / "breakdown_limit.png"
    assert png.exists() and 10_000 < png.stat().st_size < 300_000
    for name in ("device", "honeycomb"):
        res = numbers[name]
        # tens of uC/m^2, the range air breakdown allows contact-electrified devices
        assert 10e-6 < res["sigma_max"] < 80e-6
        assert res["Q_sc"] > 0 and res["V_oc"] > 0
    # the output at the limit scales with sigma_max: Q_SC / sigma_max is geometry only
    strokes = numbers["sweep"]["stroke"]
    assert [v for v, _ in strokes] == [1.0, 3.0, 5.0]
    assert all(r["sigma_max"] > 0 for _, r in strokes)
