"""The rectifier run at its extremes: stores from 1 nF to 1 F, diode saturation
currents from 1e-15 to 1e-6 A, with and without series resistance, through the
whole pipeline (plate-model surrogate, real impact dynamics).

The Moreau scheme of ``tengfield.harvest`` is implicit in the diodes and the
store, so none of these may blow up: every column stays finite, the store
voltage stays in [0, U_sat] (the ideal bridge's saturation voltage bounds any
bridge), it only rises through ideal bridges without sinks, and the energy books close to 1e-6 of
the delivered energy.
"""

import numpy as np
import pytest

import plate_model as fx

import tengfield as tf
from tengfield import electrical

SHORT_RUN = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 4000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@pytest.mark.slow
@pytest.mark.parametrize("store_uF", [1e-3, 1.0, 1e3, 1e6])
@pytest.mark.parametrize("diode", [
    {"diode": "ideal"},
    {"diode": "ideal", "diode_forward_voltage_V": 0.3, "diode_series_resistance_ohm": 1e6},
    {"diode": "shockley", "diode_saturation_current_A": 1e-15},
    {"diode": "shockley", "diode_saturation_current_A": 1e-6,
     "diode_series_resistance_ohm": 10.0},
])
def test_rectifier_extremes(cache, store_uF, diode):
    scene = fx.scene_with(run=SHORT_RUN, circuit={"kind": "rectifier",
                                                  "storage_capacitance_uF": store_uF, **diode})
    res = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    for col in electrical.RECTIFIER_COLUMNS:
        assert np.all(np.isfinite(res.waveforms[col])), col
    u = res.waveforms["V_store_V"]
    rect = res.summary["rectifier"]
    assert np.all(u >= 0) and u.max() <= rect["saturation_voltage_V"] * (1 + 1e-9) + 1e-9
    if diode["diode"] == "ideal":      # Shockley bridges leak back (reverse I_s): U may dip
        assert np.all(np.diff(u) >= -1e-9 * max(u.max(), 1e-30))
    assert u[-1] > 0
    assert max(rect["energy_residuals"].values()) < 1e-6
    books = rect["energy_books_J"]
    assert 0 <= books["diode_loss_J"] <= books["delivered_J"] * (1 + 1e-9)
