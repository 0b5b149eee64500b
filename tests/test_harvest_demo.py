"""demos/harvest_ship.py --fast: the ship case runs and its numbers hang together."""
import pytest


@pytest.mark.field
@pytest.mark.slow
def test_ship_demo_fast(tmp_path, load_demo):
    out = load_demo("harvest_ship").main(["--fast", "-o", str(tmp_path),
                                          "--cache-dir", str(tmp_path / "cache")])
    # the store reaches the falling level before the rising one, the chip then cycles
    assert 0 < out["time_to_uvlo_falling_level_s"] < out["time_to_first_uvlo_rising_s"]
    assert out["chip_bursts"] >= 1
    # the load draws more than is harvested: the chip cannot stay on
    assert 0 < out["duty_cycle_after_first_on"] < 1
    assert out["duty_cycle_after_first_on"] == pytest.approx(out["expected_duty_cycle"], rel=0.5)
    assert out["energy_residual_max"] < 1e-6
    assert (tmp_path / "harvest_ship.png").stat().st_size > 0
