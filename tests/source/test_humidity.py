"""Issue 52: ``[charge] relative_humidity_percent``, the assumed law of
:mod:`tengfield.humidity` (docs/charge.md): sigma_eq (1 - RH), tau 10^(-RH/0.2), Paschen's
B (1 + k AH). Its closed forms, a humid run equal to the dry run at the humid constants,
the cap following V_b, the refusals, and the humidity drawn in a sweep."""
from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import tengfield as tf
from tengfield.humidity import (SATURATION_G_PER_M3, breakdown_factor, humid_equilibrium,
                                humid_leakage_time)
from tengfield.paschen import Paschen
from tengfield.sweeps import sweep_study

import plate_model as fx

RUN = {"duration_s": 2.0, "settle_periods": 4, "sample_rate_hz": 2000.0}
DRY = {"model": "contact", "discharge": "none", "equilibrium_uC_per_m2": -100.0,
       "efficiency": 0.3, "leakage_time_s": 2.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, 1.0), st.floats(-1e-3, 1e-3), st.floats(0.0, 1e6))
def test_the_law_is_its_closed_form_and_dry_air_changes_nothing(rh, sigma, tau):
    assert humid_equilibrium(sigma, 0.0) == sigma and humid_leakage_time(tau, 0.0) == tau
    assert breakdown_factor(0.0) == 1.0
    assert humid_equilibrium(sigma, rh) == pytest.approx(sigma * (1.0 - rh), abs=1e-300)
    assert humid_leakage_time(tau, rh) == pytest.approx(tau / 10.0 ** (5.0 * rh), rel=1e-12,
                                                        abs=1e-300)
    assert humid_leakage_time(0.0, rh) == 0.0                 # no leakage stays none
    assert humid_leakage_time(tau, min(rh + 0.2, 1.0)) <= humid_leakage_time(tau, rh)


def test_the_breakdown_voltage_rises_two_to_three_percent_over_8_to_15_g_per_m3():
    """DESIGN's figure: V_b +2-3 % from 8 to 15 g/m^3 of water vapour (20 °C)."""
    rise = breakdown_factor(15.0 / SATURATION_G_PER_M3) / breakdown_factor(
        8.0 / SATURATION_G_PER_M3)
    assert 1.02 < rise < 1.03


def test_paschens_curve_of_a_humid_contact_scene_is_the_dry_one_scaled():
    dry = fx.scene_with(charge={"model": "contact"})
    humid = fx.scene_with(charge={"model": "contact", "relative_humidity_percent": 60.0})
    d = np.geomspace(20e-6, 5e-3, 40)          # the Townsend and streamer ranges in air
    ratio = Paschen.from_scene(humid).voltage(d) / Paschen.from_scene(dry).voltage(d)
    assert np.allclose(ratio, breakdown_factor(0.6), rtol=1e-12)
    assert Paschen.from_scene(dry) == Paschen.from_scene(fx.scene_with())


def test_a_humid_run_is_the_dry_run_at_the_humid_constants(cache):
    """RH = 30 %: the same numbers as sigma_eq x 0.7 and tau x 10^-1.5 given directly."""
    humid = tf.run(fx.scene_with(run=RUN, charge={**DRY, "relative_humidity_percent": 30.0}),
                   cache_dir=cache, solve=fx.plate_model_solve)
    same = tf.run(fx.scene_with(run=RUN, charge={**DRY, "equilibrium_uC_per_m2": -70.0,
                                                 "leakage_time_s": 2.0 * 10 ** -1.5}),
                  cache_dir=cache, solve=fx.plate_model_solve)
    a, b = humid.summary["charge"], same.summary["charge"]
    assert a["steady_uC_per_m2"] == pytest.approx(b["steady_uC_per_m2"], rel=1e-12)
    assert a["equilibrium_uC_per_m2"] == pytest.approx(-70.0, rel=1e-12)
    assert a["leakage_time_s"] == pytest.approx(2.0 * 10 ** -1.5, rel=1e-12)
    assert a["relative_humidity_percent"] == 30.0 and "assumption" in a["humidity_law"]
    for name, value in same.peaks.items():
        assert humid.peaks[name] == pytest.approx(value, rel=1e-12, abs=1e-300), name


def test_a_sweep_over_the_humidity_lowers_the_steady_charge(cache):
    rows = sweep_study(fx.scene_with(run=RUN, charge=DRY),
                       vary={"charge.relative_humidity_percent": [0.0, 20.0, 50.0, 80.0]},
                       cache_dir=cache, solve=fx.plate_model_solve)
    steady = [abs(row["sigma_steady_uC_per_m2"]) for row in rows]
    assert steady == sorted(steady, reverse=True) and steady[-1] < 0.1 * steady[0]


@pytest.mark.parametrize("sections, match", [
    ({"charge": {"relative_humidity_percent": 40.0}},
     r'relative_humidity_percent = 40 acts only with \[charge\] model = "contact"'),
    ({"charge": {"model": "contact", "relative_humidity_percent": 40.0},
      "breakdown": {"paschen": "empirical"}}, r'paschen = "empirical"'),
    ({"charge": {"model": "contact", "relative_humidity_percent": 101.0}},
     r"relative_humidity_percent = 101.*\[0, 100\]"),
])
def test_what_the_humidity_cannot_mean_is_refused_in_one_line(sections, match):
    with pytest.raises(tf.TengfieldError, match=match) as caught:
        fx.scene_with(**sections)
    assert "\n" not in str(caught.value)


def test_cli_the_humid_cap_follows_the_breakdown_voltage(tmp_path, cli_command, cli_env):
    """The real field (coarse): at RH = 50 % the steady charge bound by the band's cap is
    the dry cap x the factor on V_b (the field is linear in sigma), figures on."""
    scene = tmp_path / "humid.toml"
    scene.write_text(fx.SMALL_SCENE + '\n[charge]\nmodel = "contact"\n')
    env = cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache")
    blocks = {}
    for rh in (0, 50):
        done = subprocess.run(cli_command("run", scene, "--set",
                                          f"charge.relative_humidity_percent={rh}", "-o",
                                          tmp_path / f"rh{rh}"),
                              capture_output=True, text=True, env=env, timeout=600)
        assert done.returncode == 0, done.stderr
        blocks[rh] = json.loads((tmp_path / f"rh{rh}" / "summary.json").read_text())["charge"]
        assert (tmp_path / f"rh{rh}" / "ball_charge.png").stat().st_size > 20_000
    assert "cap" in blocks[50]["binds"]
    assert blocks[50]["cap_uC_per_m2"] / blocks[0]["cap_uC_per_m2"] == pytest.approx(
        breakdown_factor(0.5), rel=1e-9)
    assert blocks[50]["equilibrium_uC_per_m2"] == pytest.approx(-113.0 * 0.5, rel=1e-12)
    assert math.isclose(blocks[50]["breakdown_voltage_factor"], breakdown_factor(0.5))
