"""Rectifier + pmic = "uvlo" whose quiescent draw exceeds what the bridges deliver
(issue #30.5): the store stays at 0 V, one warning names both currents, no harvest is
reported at any step (it scaled with the step: an artefact), the books stay exact."""
import warnings

import pytest

import tengfield as tf

import plate_model as fx


def _rect(tmp_path, rate, **circuit):
    scene = fx.scene_with(run={"duration_s": 1.0, "settle_periods": 2, "sample_rate_hz": rate},
                          circuit={"kind": "rectifier", "pmic": "uvlo", **circuit})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    return r.summary["rectifier"], [str(w.message) for w in caught
                                    if issubclass(w.category, RuntimeWarning)]


@pytest.mark.parametrize("rate", [20000.0, 200000.0])
def test_a_starved_store_harvests_nothing_at_any_step(tmp_path, rate):
    rect, said = _rect(tmp_path, rate)
    starved = [m for m in said if "quiescent current" in m]
    assert len(starved) == 1, said
    assert "pmic_quiescent_current_A = 4.5e-07 A" in starved[0]
    bridge = float(starved[0].split("bridges deliver (")[1].split(" A)")[0])
    assert 0.0 < bridge < 4.5e-7
    assert not [m for m in said if "numerical_dissipation" in m]
    assert rect["final_store_voltage_V"] == 0.0 and rect["max_store_voltage_V"] == 0.0
    assert rect["average_harvested_power_W"] == 0.0 and rect["energy_per_cycle_J"] == 0.0
    books = rect["energy_books_J"]
    assert books["numerical_dissipation_J"] == 0.0 and books["quiescent_J"] == 0.0
    assert books["delivered_J"] == 0.0 and books["stored_change_J"] == 0.0
    assert all(v == 0.0 for v in rect["energy_residuals"].values()), rect["energy_residuals"]


def test_a_chip_the_bridges_can_feed_still_charges(tmp_path):
    rect, said = _rect(tmp_path, 20000.0, pmic_quiescent_current_A=1e-12)
    assert not [m for m in said if "quiescent current" in m]
    assert rect["final_store_voltage_V"] > 0.0 and rect["average_harvested_power_W"] > 0.0
    assert max(rect["energy_residuals"].values()) < 1e-9
