"""Issue #21 item 3: the circuits run on the run's own time axis, so an absolute start
time ([initial] time_s = 1.7e9, an epoch stamp) gives the run started at 0.

At t ~ 1.7e9 s the doubles are 2.4e-7 s apart: the impact offsets (1e-9 periods)
and the step lengths of the load and rectifier integrators vanish or are rounded
there unless they are computed relative to the start. Field: the analytic plate
model; dynamics: the real impact map.
"""
from __future__ import annotations

import numpy as np
import pytest

import tengfield as tf

import plate_model as fx

SHORT_RUN = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 4000.0}
EPOCH = 1.7e9


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def pair(cache, circuit, **sections):
    runs = [tf.run(fx.scene_with(run=SHORT_RUN, circuit=circuit, initial={"time_s": t0},
                                 **sections), cache_dir=cache, solve=fx.plate_model_solve)
            for t0 in (0.0, EPOCH)]
    np.testing.assert_allclose(runs[1].waveforms["time_s"] - EPOCH, runs[0].waveforms["time_s"],
                               atol=3e-7)     # the output column keeps the absolute time
    return runs


def same_columns(a, b, columns, rtol=1e-9):
    for col in columns:
        x, y = np.asarray(a.waveforms[col]), np.asarray(b.waveforms[col])
        scale = float(np.ptp(x))
        assert scale > 0, col
        assert np.max(np.abs(x - y)) <= rtol * scale, (col, np.max(np.abs(x - y)) / scale)


def same_peaks(a, b, rtol=1e-9):
    for name, value in a.peaks.items():
        assert b.peaks[name] == pytest.approx(value, rel=rtol), name


@pytest.mark.parametrize("sections", [{}, {"array": {"cells": 3}},
                                      {"array": {"cells": 3, "restitution_spread": 0.05}}],
                         ids=["single", "array-identical", "array-spread"])
def test_epoch_start_gives_the_same_load_waveforms_and_power(cache, sections):
    a, b = pair(cache, {"kind": "load", "load_ohm": 3e9}, **sections)
    same_columns(a, b, ["Q_sc_C", "I_sc_A", "V_load_V", "I_load_A", "P_load_W"])
    same_peaks(a, b)
    assert b.summary["load"]["mean_power_W"] == pytest.approx(
        a.summary["load"]["mean_power_W"], rel=1e-9)
    if not sections:
        for key, value in a.summary["load"]["energy_balance_J"].items():
            assert b.summary["load"]["energy_balance_J"][key] == pytest.approx(
                value, rel=1e-8, abs=1e-12 * abs(a.summary["load"]["energy_balance_J"][
                    "delivered_energy_J"])), key
        area = a.summary["energy_per_cycle"]["load_loop_area_J"]
        assert b.summary["energy_per_cycle"]["load_loop_area_J"] == pytest.approx(area, rel=1e-8)


@pytest.mark.parametrize("sections", [
    {}, {"array": {"cells": 3}},
    {"array": {"cells": 3, "restitution_spread": 0.05, "connection": "rectified-parallel"}}],
    ids=["single", "array-identical", "array-spread"])
def test_epoch_start_gives_the_same_rectifier_outputs(cache, sections):
    chip = {"kind": "rectifier", "storage_capacitance_uF": 1e-4, "pmic": "uvlo",
            "pmic_quiescent_current_A": 0.0, "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0,
            "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}
    a, b = pair(cache, chip, **sections)
    same_columns(a, b, ["V_store_V", "E_store_J"])
    np.testing.assert_array_equal(a.waveforms["pmic_on"], b.waveforms["pmic_on"])
    ra, rb = a.summary["rectifier"], b.summary["rectifier"]
    for key in ("final_store_voltage_V", "final_stored_energy_J", "average_harvested_power_W",
                "energy_per_cycle_J", "chip_output_energy_J", "chip_duty_cycle"):
        assert rb[key] == pytest.approx(ra[key], rel=1e-9), key
    for key in ("chip_switch_on_count", "chip_switch_off_count"):
        assert rb[key] == ra[key]
    for key in ("time_to_uvlo_falling_V_s", "time_to_uvlo_rising_V_s", "chip_first_on_s",
                "window_start_s"):
        # instants stay absolute, as the time_s column
        assert rb[key] - EPOCH == pytest.approx(ra[key], abs=3e-7), key
    for key, value in ra["energy_books_J"].items():
        assert rb["energy_books_J"][key] == pytest.approx(value, rel=1e-9, abs=1e-20), key
