"""Rectifier runs through the pipeline and the CLI: [circuit] kind = "rectifier",
the store's columns and summary, chunked runs, the CMEO bound, bad keys.

The field is the analytic plate model of ``plate_model`` (no
dolfinx); the dynamics are the real impact map on short runs (or a
prescribed trajectory where the physics needs an exactly periodic drive).
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import tengfield as tf
from tengfield import electrical
from tengfield.harvest import Diode, Harvester, PowerChip, harvest

import plate_model as fx

ROOT = Path(__file__).resolve().parents[2]
SHORT_RUN = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 5000.0}
#: a small store and chip levels the plate model's 0.3 nC cell reaches in 0.5 s
SMALL_CHIP = {"kind": "rectifier", "storage_capacitance_uF": 1e-4, "pmic": "uvlo",
              "pmic_quiescent_current_A": 0.0, "uvlo_rising_V": 20.0, "uvlo_falling_V": 10.0,
              "pmic_output_V": 3.3, "pmic_load_ohm": 1e7, "pmic_shunt_V": 100.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def rect_run(cache, simulate=None, **circuit):
    scene = fx.scene_with(run=SHORT_RUN, circuit={"kind": "rectifier", **circuit})
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve, simulate=simulate)


def test_rectifier_run_end_to_end(cache):
    """Real impact dynamics: the store only charges (no sinks), E = C U^2 / 2, the three
    energy books close to round-off, the times to each level are where U crosses it."""
    res = rect_run(cache, storage_capacitance_uF=1e-4)
    w = res.waveforms
    for col in electrical.RECTIFIER_COLUMNS:
        assert w[col].shape == w["time_s"].shape
    u = w["V_store_V"]
    assert u[-1] > 0 and np.all(np.diff(u) >= -1e-12 * u.max())
    np.testing.assert_allclose(w["E_store_J"], 0.5 * 1e-10 * u**2, rtol=1e-12)
    assert np.all(w["I_store_A"] >= 0) and not np.any(w["pmic_on"])
    rect = res.summary["rectifier"]
    assert max(rect["energy_residuals"].values()) < 1e-9
    books = rect["energy_books_J"]
    assert books["delivered_J"] == pytest.approx(books["stored_change_J"]
                                                 + books["numerical_dissipation_J"], rel=1e-9)
    for key, level in (("time_to_uvlo_falling_V_s", 4.04), ("time_to_uvlo_rising_V_s", 5.05)):
        t_hit = rect[key]
        assert np.interp(t_hit, w["time_s"], u) == pytest.approx(level, rel=0.02)
    # the stored energy never exceeds the mechanical work; the chip was not fitted
    assert books["mechanical_work_J"] >= rect["final_stored_energy_J"]
    assert res.summary["energy_per_cycle"]["rectifier_loop_area_J"] > 0
    # the impact instants are on the rectifier's grid
    assert res.stages["circuit"].details["integration_points"] > w["time_s"].size


def test_huge_store_charges_by_twice_q_sc_per_period(cache):
    """C_L >> C_T: the terminal swings fully each half period and the store gains
    2 Q_SC,pp per period (DESIGN §8)."""
    res = rect_run(cache, lambda s: fx.FakeDynamics(s, kind="smooth"),
                   storage_capacitance_uF=1e6)
    periods = SHORT_RUN["duration_s"] * res.scene.excitation.frequency
    q_pp = res.peaks["Q_sc"]
    charge = 1.0 * res.waveforms["V_store_V"][-1]
    assert charge == pytest.approx(2 * q_pp * periods, rel=0.01)


def test_small_store_saturates_at_the_derived_voltage(cache):
    """Ideal bridge, no load, a periodic drive: U -> U_sat = Q_SC,max / (C(x_max) + C(0))
    (summary's saturation_voltage_V from the surrogate), within 1 %."""
    # 1 pF (the smallest store [circuit] allows) saturates within ~20 periods
    scene = fx.scene_with(run={**SHORT_RUN, "duration_s": 2.0},
                          circuit={"kind": "rectifier", "storage_capacitance_uF": 1e-6})
    res = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve,
                 simulate=lambda s: fx.FakeDynamics(s, kind="smooth"))
    rect = res.summary["rectifier"]
    assert rect["max_store_voltage_V"] == pytest.approx(rect["saturation_voltage_V"], rel=0.01)
    assert rect["max_store_voltage_V"] <= rect["saturation_voltage_V"] * (1 + 1e-9)


def test_uvlo_switching_counts_and_burst_energy(cache):
    """The chip switches on at the rising level, off at the falling one, never on twice
    in a row; each completed burst drains at least C (V_r^2 - V_f^2) / 2."""
    res = rect_run(cache, **{k: v for k, v in SMALL_CHIP.items() if k != "kind"})
    rect = res.summary["rectifier"]
    on, off = rect["chip_switch_on_count"], rect["chip_switch_off_count"]
    assert on >= 2 and on - off in (0, 1)
    burst = 0.5 * 1e-10 * (20.0**2 - 10.0**2)
    chip = rect["energy_books_J"]["chip_input_J"]
    assert chip >= off * burst * (1 - 1e-9)
    assert chip <= on * burst + rect["energy_books_J"]["delivered_J"]
    u = res.waveforms["V_store_V"]
    flag = res.waveforms["pmic_on"] > 0
    assert np.all(u[flag] >= 10.0 - 1e-9)          # on only above the falling level
    assert rect["chip_first_on_s"] == pytest.approx(rect["time_to_uvlo_rising_V_s"], abs=2e-4)
    assert 0 < rect["chip_duty_cycle"] < 1


@pytest.mark.slow
def test_chunked_harvester_equals_one_pass():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 0.2, 2001)
    phase = rng.uniform(0, 2 * np.pi, 3)
    s = 0.5 * (1 - np.cos(2 * np.pi * 20 * t[:, None] + phase))
    q, c = 1e-9 * s, 0.3e-12 + 0.05e-12 * s
    kwargs = dict(storage_capacitance=2e-12, chip=PowerChip(uvlo_rising=60, uvlo_falling=40,
                                                            output_voltage=3.3, load=1e9,
                                                            shunt_voltage=1e4),
                  diode=Diode(model="shockley", series_resistance=1e3), leakage=1e12)
    whole = harvest(t, q, c, **kwargs)
    run = Harvester(3, **kwargs)
    parts = [run.advance(t[a:b], q[a:b], c[a:b]) for a, b in ((0, 700), (700, 701), (701, 2001))]
    joined = electrical.concat_results(parts)
    np.testing.assert_allclose(joined.store_voltage, whole.store_voltage, rtol=1e-12, atol=0)
    # cumulative charges: a chunk adds its offset after summing (reassociation), so
    # the absolute floor is round-off of the charge scale, 1e-12 of the largest value
    np.testing.assert_allclose(joined.bridge_charge, whole.bridge_charge, rtol=1e-12,
                               atol=1e-12 * np.abs(whole.bridge_charge).max())
    a, b = joined.balance(), whole.balance()
    for key in a:
        assert a[key] == pytest.approx(b[key], rel=1e-9, abs=1e-15), key
    assert whole.chip_on.any()


def test_load_run_reports_cmeo_bound_above_its_loop(cache):
    """E_m (CMEO) bounds the energy a resistive load takes per cycle; the V-Q loop's
    area equals the load's mean power x period in the periodic regime."""
    scene = fx.scene_with(run=SHORT_RUN, circuit={"kind": "load", "load_ohm": 3e9})
    res = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve,
                 simulate=lambda s: fx.FakeDynamics(s, kind="bounce"))
    energy = res.summary["energy_per_cycle"]
    assert 0 < energy["load_loop_area_J"] < energy["max_energy_per_cycle_J"]
    assert energy["load_loop_area_J"] == pytest.approx(
        energy["load_mean_power_times_period_J"], rel=0.02)
    q, c_max, c_0 = energy["Q_sc_max_C"], energy["C_at_max_gap_F"], energy["C_at_zero_F"]
    assert energy["max_energy_per_cycle_J"] == pytest.approx(0.5 * q * q * (1 / c_max + 1 / c_0))
    assert energy["figure_of_merit_structural"] > 0


@pytest.fixture
def cli(run_cli, cli_env, tmp_path):
    """``cli(args)``: the CLI run in tmp_path with the surrogate cache tmp_path/cache."""
    return lambda args: run_cli(*args, cwd=tmp_path, timeout=600,
                                env=cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true",
                                            TENGFIELD_CACHE_DIR=tmp_path / "cache"))


SCENE_TEXT = """\
[run]
duration_s = 0.3
settle_periods = 2
sample_rate_hz = 5000.0
[circuit]
kind = "rectifier"
storage_capacitance_uF = 1e-4
pmic = "uvlo"
pmic_quiescent_current_A = 0.0
uvlo_rising_V = 20.0
uvlo_falling_V = 10.0
pmic_load_ohm = 1e7
pmic_shunt_V = 100.0
"""


@pytest.mark.slow
def test_cli_rectifier_run(tmp_path, cli):
    """`tengfield run` of a rectifier scene (surrogate cached from the plate model)."""
    path = tmp_path / "rect.toml"
    path.write_text(SCENE_TEXT)
    scene = tf.load_scene(path)
    tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)   # fills the cache
    proc = cli(["run", "rect.toml", "-o", "out"])
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "out"
    for name in ("charging.png", "vq.png", "waveforms.csv", "summary.json"):
        assert (out / name).stat().st_size > 0
    with open(out / "waveforms.csv") as f:
        header = next(csv.reader(f))
    assert header == electrical.WAVEFORM_COLUMNS + electrical.RECTIFIER_COLUMNS
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field"]["status"] == "cached"
    assert summary["rectifier"]["chip_switch_on_count"] >= 1
    assert "energy per cycle" in proc.stdout and "chip: on" in proc.stdout


@pytest.mark.slow
@pytest.mark.parametrize("text, expected", [
    ('[circuit]\nkind = "rectifier"\nstorage_capacitance_uF = 0.0\n',
     "[circuit] storage_capacitance_uF = 0.0 is out of range"),
    ('[circuit]\nkind = "rectifier"\ndiode = "schottky"\n',
     "[circuit] diode = 'schottky' is not allowed"),
    ('[circuit]\nuvlo_rising_V = 3.0\n', "[circuit] uvlo_rising_V = 3 must exceed"),
    ('[circuit]\npmic_output_V = 4.5\n', "[circuit] pmic_output_V = 4.5 is out of range"),
    ('[circuit]\ndiode_saturation_current_A = 0.0\n',
     "[circuit] diode_saturation_current_A = 0.0 is out of range"),
    ('[device]\ncells = 4\n[array]\ncells = 4\n', "[array] cells = 4 and [device] cells = 4"),
    ('[array]\ncells = 4\nconnection = "rectified-parallel"\n',
     "needs [circuit] kind = 'rectifier'"),
    ('[array]\ncells = 4\nconnection = "series"\n', "[array] connection = 'series' is not allowed"),
    ('[array]\nrestitution_spread = 0.1\n', "[array] spreads and connection need"),
])
def test_bad_harvest_and_array_keys_are_one_line_errors(tmp_path, cli, text, expected):
    (tmp_path / "bad.toml").write_text(text)
    proc = cli(["run", "bad.toml", "-o", "out"])
    assert proc.returncode == 2
    assert expected in proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
