"""[circuit] kind = "series-rc": R in series with C_s (the registry's proof kind)."""
import numpy as np
import pytest

import plate_model as fx
from tengfield import electrical, io, pipeline
from tengfield.electrical.circuits.series_rc import series_response

SHORT_RUN = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 4000.0}
LOAD = {"load_ohm": 3e8, "parallel_capacitance_pF": 10.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def run(cache, series_pF=None, **sections):
    circuit = ({"kind": "load", **LOAD} if series_pF is None else
               {"kind": "series-rc", **LOAD, "series_capacitance_pF": series_pF})
    scene = fx.scene_with(run=SHORT_RUN, circuit=circuit, **sections)
    return pipeline.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


def test_a_huge_series_capacitor_is_the_plain_load(cache):
    load, series = run(cache), run(cache, 1e18)
    for column in electrical.LOAD_COLUMNS:
        scale = np.max(np.abs(load.waveforms[column]))
        assert np.max(np.abs(series.waveforms[column] - load.waveforms[column])) <= 1e-12 * scale
    assert series.summary["load"]["mean_power_W"] == pytest.approx(
        load.summary["load"]["mean_power_W"], rel=1e-12)
    assert series.summary["energy_per_cycle"]["load_loop_area_J"] == pytest.approx(
        load.summary["energy_per_cycle"]["load_loop_area_J"], rel=1e-9)
    assert np.max(np.abs(series.waveforms["V_series_C_V"])) < 1e-9


def test_a_vanishing_series_capacitor_passes_no_current(cache):
    load = run(cache)
    small, smaller = run(cache, 1e-3), run(cache, 1e-6)
    i_load = np.max(np.abs(load.waveforms["I_load_A"]))
    i_small = np.max(np.abs(small.waveforms["I_load_A"]))
    i_smaller = np.max(np.abs(smaller.waveforms["I_load_A"]))
    assert i_small < 1e-3 * i_load
    assert i_smaller == pytest.approx(1e-3 * i_small, rel=1e-2)     # I ~ C_s dV_oc/dt
    # no current: the branch sees the open-circuit voltage read through C_p (V_oc_V is
    # the ideal one, without C_p); the instrument reads the terminal: V_read_V = V_load_V
    assert smaller.V_read is smaller.waveforms["V_load_V"]
    read = electrical.scene_terminal_waveforms(smaller.scene, smaller.curves,
                                               smaller.waveforms["gap_m"],
                                               smaller.waveforms["gap_velocity_m_per_s"])["V_read"]
    np.testing.assert_allclose(smaller.waveforms["V_load_V"], read,
                               atol=1e-6 * np.max(np.abs(read)))
    np.testing.assert_allclose(smaller.waveforms["V_series_C_V"], read,
                               atol=1e-6 * np.max(np.abs(read)))


@pytest.mark.parametrize("series_pF", [100.0, 1e6])
def test_energy_books_close(cache, series_pF):
    out = run(cache, series_pF)
    books = out.summary["load"]["energy_balance_J"]
    assert out.stages["circuit"].details["energy_balance_relative_residual"] < 1e-3
    assert books["dissipated_energy_J"] > 0
    assert out.summary["load"]["series_capacitance_F"] == pytest.approx(series_pF * 1e-12)
    assert out.stages["circuit"].reason.startswith("series R + C ODE")


def test_series_response_is_the_exact_rc_step_for_a_constant_source():
    # Q_SC constant, C constant: Q(t) = C_eff V_oc (1 - exp(-t / (R C_eff)))
    t = np.linspace(0.0, 5e-3, 2001)
    q_sc, c_t, r, c_s = np.full_like(t, 1e-9), np.full_like(t, 1e-10), 1e7, 4e-10
    out = series_response(t, q_sc, np.zeros_like(t), c_t, r, 0.0, c_s)
    c_eff = 1e-10 * c_s / (1e-10 + c_s)
    expected = c_eff * 10.0 * (1.0 - np.exp(-t / (r * c_eff)))
    np.testing.assert_allclose(out["Q"], expected, rtol=1e-6, atol=1e-18)
    np.testing.assert_allclose(out["I"], np.gradient(out["Q"], t), rtol=2e-2, atol=1e-9)


def test_arrays_and_the_csv_carry_the_series_columns(cache, tmp_path):
    one = run(cache, 100.0, device={"cells": 3})
    identical = run(cache, 100.0, array={"cells": 3})
    np.testing.assert_array_equal(identical.waveforms["P_load_W"], one.waveforms["P_load_W"])
    spread = run(cache, 100.0, array={"cells": 3, "restitution_spread": 0.05})
    assert spread.summary["array"]["compared"] == "mean load power [W]"
    assert spread.summary["load"]["mean_power_W"] > 0
    path = io.write_waveforms_csv(tmp_path / "w.csv", one.waveforms)
    header = path.read_text().splitlines()[0].split(",")
    assert header[-4:] == ["V_load_V", "I_load_A", "P_load_W", "V_series_C_V"]
