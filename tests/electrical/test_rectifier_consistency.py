"""Issue #21 item 5: a rectifier summary never contradicts itself.

A store so small that a chip burst (on at uvlo_rising_V, locked out at
uvlo_falling_V) fits inside one output step used to give a UVLO crossing time with
zero switch-ons, V_store = 0 at every sample yet shunt energy, and a backward-Euler
dissipation of half the delivered energy, silently. Such a store is refused (one
line naming the key, its value and the allowed range); above the limit the summary
is consistent; a numerical dissipation above 1 % of the delivered energy warns.
Field: the analytic plate model; dynamics: the real impact map.
"""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import tengfield as tf
from tengfield import electrical
from tengfield.errors import SceneError

import plate_model as fx

SHORT_RUN = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 4000.0}
#: chip levels the plate model's 0.3 nC cell reaches (no quiescent current)
CHIP = {"kind": "rectifier", "pmic": "uvlo", "pmic_quiescent_current_A": 0.0,
        "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0, "pmic_output_V": 3.3,
        "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def run(cache, circuit, **sections):
    scene = fx.scene_with(run=SHORT_RUN, circuit=circuit, **sections)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    return result, [w for w in caught if "numerical_dissipation_J" in str(w.message)]


@pytest.mark.parametrize("sections", [{}, {"array": {"cells": 2}},
                                      {"array": {"cells": 2, "restitution_spread": 0.05,
                                                 "connection": "rectified-parallel"}}],
                         ids=["single", "array", "array-spread"])
def test_a_store_the_step_cannot_resolve_is_refused_with_key_value_and_range(cache, sections):
    scene = fx.scene_with(run=SHORT_RUN, circuit={"kind": "rectifier", "pmic": "uvlo",
                                                  "storage_capacitance_uF": 1e-5}, **sections)
    with pytest.raises(SceneError) as err:
        tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    text = str(err.value)
    assert "[circuit] storage_capacitance_uF = 1e-05 is out of range" in text
    smallest = electrical.smallest_resolved_store(scene) * 1e6
    assert f"allowed >= {smallest:.3g}" in text and "\n" not in text
    # the limit: a chip burst at the chip's largest draw lasts one output step
    c = scene.circuit
    draw = c.pmic_output**2 / (c.pmic_load * c.pmic_efficiency) + c.pmic_quiescent_current \
        * c.pmic_shunt
    burst = 0.5 * smallest * 1e-6 * (c.uvlo_rising**2 - c.uvlo_falling**2)
    assert burst / draw == pytest.approx(1.0 / scene.run.sample_rate, rel=1e-12)


@pytest.mark.parametrize("store_uF", [2.1e-6, 1e-5, 1e-4])
def test_summary_is_consistent_above_the_limit(cache, store_uF):
    """From just above the smallest resolved store (2.0e-6 uF here) up: a UVLO crossing
    implies a switch-on, shunt energy implies a stored voltage, the books close, and the
    warning fires exactly when the step's own dissipation exceeds 1 %."""
    res, warned = run(cache, {**CHIP, "storage_capacitance_uF": store_uF})
    rect = res.summary["rectifier"]
    books = rect["energy_books_J"]
    u = res.waveforms["V_store_V"]
    if np.isfinite(rect["time_to_uvlo_rising_V_s"]) or np.isfinite(rect["chip_first_on_s"]):
        assert rect["chip_switch_on_count"] >= 1
        assert np.any(res.waveforms["pmic_on"] > 0)
    assert rect["chip_switch_off_count"] <= rect["chip_switch_on_count"]
    if books["shunt_J"] > 0 or books["chip_input_J"] > 0:
        assert np.max(u) > 0 and rect["max_store_voltage_V"] > 0
    assert max(rect["energy_residuals"].values()) < 1e-9
    ratio = books["numerical_dissipation_J"] / books["delivered_J"]
    assert (len(warned) == 1) == (ratio > 0.01)
    if store_uF >= 1e-4:
        # the books close without the step's own dissipation to 1 %
        sinks = (books["stored_change_J"] + books["leakage_J"] + books["quiescent_J"]
                 + books["chip_input_J"] + books["shunt_J"] + books["diode_loss_J"])
        assert sinks == pytest.approx(books["delivered_J"], rel=0.01)
        assert not warned


def test_large_numerical_dissipation_warns_once(cache):
    """A store just above the limit (the chip's bursts a few steps long) moves tens of
    volts per step: the step's own dissipation is several % of the delivered energy;
    one warning naming the quantity and the fix."""
    res, warned = run(cache, {**CHIP, "storage_capacitance_uF": 2.1e-6})
    books = res.summary["rectifier"]["energy_books_J"]
    assert books["numerical_dissipation_J"] > 0.05 * books["delivered_J"]
    assert len(warned) == 1
    text = str(warned[0].message)
    assert "\n" not in text and "numerical_dissipation_J" in text
    assert "sample_rate_hz" in text and "storage_capacitance_uF" in text


def test_per_cell_stores_warn_too(cache):
    # a 1 pF store (the smallest [circuit] storage_capacitance_uF allows) behind a 1 MOhm
    # leak: a time constant of 1 us, far below the output step
    res, warned = run(cache, {"kind": "rectifier", "storage_capacitance_uF": 1e-6,
                              "storage_leakage_ohm": 1e6},
                      array={"cells": 2, "restitution_spread": 0.05,
                             "connection": "rectified-per-cell"})
    assert len(warned) == 1


@pytest.mark.slow
def test_cli_refuses_in_one_line_and_warns_in_one_line(tmp_path, run_cli, cli_env):
    env = cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true",
                  TENGFIELD_CACHE_DIR=tmp_path / "cache")
    head = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 4000.0\n"
    (tmp_path / "tiny.toml").write_text(head + '[circuit]\nkind = "rectifier"\npmic = "uvlo"\n'
                                        "storage_capacitance_uF = 1e-5\n")
    proc = run_cli("run", "tiny.toml", "-o", "out", cwd=tmp_path, env=env, timeout=600)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: [circuit] "
                                                   "storage_capacitance_uF = 1e-05")
    (tmp_path / "small.toml").write_text(
        head + "[circuit]\n" + "".join(f"{k} = {v!r}\n".replace("'", '"')
                                       for k, v in CHIP.items())
        + "storage_capacitance_uF = 2.1e-6\n")
    with pytest.warns(RuntimeWarning, match="rectifier: numerical_dissipation_J"):
        tf.run(tf.load_scene(tmp_path / "small.toml"), cache_dir=tmp_path / "cache",
               solve=fx.plate_model_solve)                   # fills the surrogate cache
    proc = run_cli("run", "small.toml", "-o", "out", "--no-plots", cwd=tmp_path, env=env,
                   timeout=600)
    assert proc.returncode == 0, proc.stderr
    warned = [line for line in proc.stderr.splitlines() if "numerical_dissipation_J" in line]
    assert len(warned) == 1 and warned[0].startswith("tengfield: warning: rectifier: ")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["rectifier"]["energy_books_J"]["numerical_dissipation_J"] > 0
