"""Issue 52: a contact-charged run's charge follows every impact of the run, its electrical
stage (waveforms, peaks, figures) only the steady window at the run's end, ``[charge]
waveforms = "steady"`` (the start-up, the whole run, on request: ``"start-up"``; ``"auto"``
takes the start-up where a rectifier fills a store). The window's waveforms are the
whole run's samples there, the charge block is the whole run's, and a run no longer than
the window is the whole run, bit for bit."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

import tengfield as tf
from tengfield.dynamics.columns import is_sampled, tail
from tengfield.errors import SceneError

import plate_model as fx

#: 60 s at 20 Hz (1200 periods): the window is the last 10 + 20 periods, 1.5 s
LONG = {"duration_s": 60.0, "settle_periods": 10, "sample_rate_hz": 2000.0}
RISING = {"model": "contact", "discharge": "none", "equilibrium_uC_per_m2": -100.0,
          "efficiency": 0.002, "window_periods": 20}
COLUMNS = ("gap_m", "V_oc_V", "Q_sc_C", "I_sc_A", "C_T_F", "q_ball_C")


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _run(cache, run=LONG, **sections):
    return tf.run(fx.scene_with(run=run, **sections), cache_dir=cache,
                  solve=fx.plate_model_solve)


@pytest.fixture(scope="module")
def rising(cache):
    """A ball still charging at the window (eta = 0.002): the steady run and the start-up."""
    steady = _run(cache, charge={**RISING, "waveforms": "steady"})
    start_up = _run(cache, charge={**RISING, "waveforms": "start-up"})
    return steady, start_up


def test_the_steady_window_holds_the_whole_runs_samples_there(rising):
    steady, start_up = rising
    t = np.asarray(steady.waveforms["time_s"])
    whole = np.asarray(start_up.waveforms["time_s"])
    assert t[0] == pytest.approx(60.0 - 30 / 20.0, abs=1e-9) and t[-1] == whole[-1] == 60.0
    assert len(t) == 3001 and len(whole) == 120001
    first = int(np.searchsorted(whole, t[0]))
    np.testing.assert_array_equal(whole[first:], t)
    for column in COLUMNS:
        np.testing.assert_allclose(steady.waveforms[column],
                                   start_up.waveforms[column][first:], rtol=1e-12,
                                   atol=1e-12 * np.max(np.abs(start_up.waveforms[column])),
                                   err_msg=column)
    # the ball is still charging there: the window's charge is not the run's start
    q = np.asarray(steady.waveforms["q_ball_C"])
    assert abs(q[0]) > 0.5 * abs(q[-1]) > 0.0 and abs(q[-1]) > abs(q[0])


def test_the_charge_block_is_the_whole_runs_and_says_what_the_waveforms_cover(rising):
    steady, start_up = rising
    a, b = steady.summary["charge"], start_up.summary["charge"]
    window, whole = a.pop("waveforms"), b.pop("waveforms")
    assert a == b
    assert a["contacts"] > 1000              # every impact of the 60 s, not the window's
    assert window["mode"] == "steady" and not window["whole_run"]
    assert window["start_s"] == pytest.approx(58.5) and window["end_s"] == 60.0
    assert whole["mode"] == "start-up" and whole["whole_run"]
    assert steady.extras["_charge_record"]["window_s"] == pytest.approx((58.5, 60.0))
    assert "window_s" not in start_up.extras["_charge_record"]


def test_the_window_peaks_are_the_whole_runs_once_the_charge_is_steady(cache):
    """A ball at sigma_eq from the start, no cap: the charge is constant, the motion
    periodic, so the last 20 periods' peaks are the whole steady window's (the same
    period repeated: 1e-9)."""
    charge = {"model": "contact", "discharge": "none", "equilibrium_uC_per_m2": -100.0,
              "initial_uC_per_m2": -100.0, "window_periods": 20}
    steady = _run(cache, charge=charge)
    whole = _run(cache, charge={**charge, "waveforms": "start-up"})
    assert steady.summary["regime"]["regime"] == "bounce"
    for name, value in whole.peaks.items():
        assert steady.peaks[name] == pytest.approx(value, rel=1e-9), name


def test_a_run_no_longer_than_the_window_is_the_whole_run_bit_for_bit(cache):
    run = {"duration_s": 2.0, "settle_periods": 10, "sample_rate_hz": 2000.0}
    charge = {"model": "contact", "discharge": "none"}
    steady = _run(cache, run=run, charge={**charge, "waveforms": "steady"})
    whole = _run(cache, run=run, charge={**charge, "waveforms": "start-up"})
    assert steady.summary["charge"]["waveforms"]["whole_run"]
    for column in COLUMNS:
        np.testing.assert_array_equal(steady.waveforms[column], whole.waveforms[column])
    assert steady.peaks == whole.peaks


@pytest.mark.parametrize("waveforms, whole_run", [("auto", True), ("steady", False)])
def test_auto_runs_a_rectifier_over_the_whole_run(cache, waveforms, whole_run):
    """A rectifier fills its store from empty: its charging is the run, so "auto" runs it
    from the start; "steady" asks for the window and gets it."""
    run = {"duration_s": 4.0, "settle_periods": 10, "sample_rate_hz": 2000.0}
    result = _run(cache, run=run, circuit={"kind": "rectifier"},
                  charge={"model": "contact", "discharge": "none", "waveforms": waveforms,
                          "window_periods": 20})
    block = result.summary["charge"]["waveforms"]
    assert block["whole_run"] is whole_run
    assert block["mode"] == ("start-up" if whole_run else "steady")
    t = np.asarray(result.waveforms["time_s"])
    assert t[0] == pytest.approx(0.0 if whole_run else 4.0 - 30 / 20.0, abs=1e-9)
    assert np.all(np.isfinite(result.waveforms["V_store_V"]))


def test_an_open_run_defaults_to_the_window(cache):
    result = _run(cache, charge={"model": "contact", "discharge": "none",
                                 "window_periods": 20})
    assert result.summary["charge"]["waveforms"]["mode"] == "steady"
    assert result.summary["charge"]["waveforms"]["requested"] == "auto"


@pytest.mark.parametrize("key, value, needle", [
    ("waveforms", "all", "[charge] waveforms = 'all'"),
    ("window_periods", 0, "[charge] window_periods = 0"),
    ("window_periods", 2.5, "[charge] window_periods"),
])
def test_bad_window_keys_are_one_line(key, value, needle):
    with pytest.raises(SceneError) as info:
        fx.scene_with(charge={"model": "contact", key: value})
    text = str(info.value)
    assert needle in text and "\n" not in text
    if key == "waveforms":
        assert "'steady'" in text and "'start-up'" in text
    elif value == 0:
        assert ">= 1" in text or "[1," in text


def test_an_instrument_too_slow_for_the_window_is_refused_before_the_work():
    """0.5 readings a second take 2 in the whole 60 s but fewer than 2 in the last 20
    periods the waveforms cover."""
    with pytest.raises(SceneError) as info:
        fx.scene_with(run=LONG, charge={"model": "contact", "window_periods": 20},
                      instrument={"sample_rate_hz": 0.5})
    text = str(info.value)
    assert "[charge] window_periods = 20" in text and "[instrument] sample_rate_hz = 0.5" in text
    fx.scene_with(run=LONG, charge={"model": "contact", "waveforms": "start-up"},
                  instrument={"sample_rate_hz": 0.5})   # the whole run: enough readings


@pytest.mark.parametrize("model", ["impact", "soft"])
def test_a_tail_is_the_runs_own_samples(model, monkeypatch):
    """``tail`` of a run (arrays) and of a long run sampled on request (LAZY_ROWS lowered
    to 4096 samples: 0.5 s at 20 kHz is such a run here): the same numbers, and still
    sampled on request while longer than LAZY_ROWS."""
    from tengfield.dynamics import columns

    scene = fx.scene_with(run={"duration_s": 0.5, "settle_periods": 2,
                               "sample_rate_hz": 20000.0}, contact={"model": model})
    short = tf.simulate(scene)
    cut = tail(short, 4000)
    for name in ("t", "elapsed", "gap", "gap_velocity", "table"):
        np.testing.assert_array_equal(getattr(cut, name), np.asarray(getattr(short, name))[4000:])
    assert cut.impacts is short.impacts and cut.regime is short.regime
    assert tail(short, 0) is short
    monkeypatch.setattr(columns, "LAZY_ROWS", 4096)
    dyn = tf.simulate(scene)
    assert is_sampled(dyn.gap) and not is_sampled(short.gap)
    n = len(dyn.gap)
    for index, lazy in ((n - 4096 - 10, True), (n - 1000, False)):
        part = tail(dyn, index)
        assert is_sampled(part.gap) is lazy and len(part.gap) == n - index
        for name in ("elapsed", "gap", "gap_velocity", "table"):
            got = np.asarray(getattr(part, name)[-700:])
            want = np.asarray(getattr(short, name))[n - 700:]
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-15 * max(
                1.0, float(np.max(np.abs(want)))), err_msg=f"{name} from {index}")
        assert float(part.elapsed[0]) == index / 20000.0
        assert float(part.t[0]) == float(short.t[index])


def test_cli_a_ten_minute_contact_run_writes_its_window_with_figures(tmp_path, run_cli,
                                                                     cli_env):
    """``tengfield run`` of 600 s at 20 Hz (12 M samples of the run): the charge over all
    its ~12,000 contacts, waveforms.csv over the last 60 periods, the figures."""
    scene = tmp_path / "long.toml"
    scene.write_text(fx.SMALL_SCENE.replace("duration_s = 0.3", "duration_s = 600.0")
                     .replace("sample_rate_hz = 5000.0", "sample_rate_hz = 20000.0")
                     + '\n[charge]\nmodel = "contact"\n')
    out = run_cli("run", scene, "-o", tmp_path / "out",
                  env=cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache", MPLBACKEND="Agg"))
    assert out.returncode == 0, out.stderr
    # settle_periods = 2 + window_periods = 50 periods at 20 Hz: the last 2.6 s
    assert "waveforms, peaks and figures: t = 597.4 to 600 s" in out.stdout
    with open(tmp_path / "out" / "waveforms.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 52 * 1000 + 1                    # 1000 samples a period
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["charge"]["contacts"] > 10_000
    assert summary["charge"]["waveforms"]["start_s"] == pytest.approx(float(rows[0]["time_s"]))
    for name in ("waveforms.png", "ball_charge.png", "trajectory.png"):
        assert (tmp_path / "out" / name).stat().st_size > 10_000, name
    assert not (tmp_path / "out" / "run.h5").exists()
    assert math.isfinite(summary["peak_to_peak"]["V_oc_V"])


def test_a_long_sweep_row_is_the_windowed_run_at_its_values(cache):
    """A sweep point of a long contact scene takes the run's window: its row holds the
    run's peak-to-peak values (1e-12), not the start-up's."""
    from tengfield.sweeps import sweep_study

    base = fx.scene_with(run=LONG, charge=RISING)
    rows = sweep_study(base, vary={"charge.efficiency": [0.002, 0.01]}, cache_dir=cache,
                       solve=fx.plate_model_solve)
    for row in rows:
        charge = {"efficiency": row["charge.efficiency"]}
        run = _run(cache, charge={**RISING, **charge})
        start_up = _run(cache, charge={**RISING, **charge, "waveforms": "start-up"})
        for column, name in (("V_oc_pp_V", "V_oc_V"), ("Q_sc_pp_C", "Q_sc_C")):
            assert row[column] == pytest.approx(run.summary["peak_to_peak"][name], rel=1e-12)
            assert row[column] != pytest.approx(start_up.summary["peak_to_peak"][name],
                                                rel=1e-3)


def test_an_array_of_contact_cells_covers_the_window_and_is_n_times_one_cell(cache):
    """``[array]`` over the same 60 s: the cells charge over every impact, the array's
    outputs cover the window, and N identical cells are N x the (windowed) single cell."""
    one = _run(cache, charge=RISING)
    array = _run(cache, charge=RISING, array={"cells": 3})
    t = np.asarray(array.waveforms["time_s"])
    np.testing.assert_array_equal(t, one.waveforms["time_s"])
    assert t[0] == pytest.approx(58.5)
    for column in ("Q_sc_C", "I_sc_A", "C_T_F"):
        np.testing.assert_allclose(array.waveforms[column], 3.0 * one.waveforms[column],
                                   rtol=1e-12, atol=0.0, err_msg=column)
    assert array.summary["charge"]["contacts"] == one.summary["charge"]["contacts"] > 1000
    assert array.extras["_charge_record"]["window_s"] == pytest.approx((58.5, 60.0))
    spread = _run(cache, charge=RISING, array={"cells": 3, "restitution_spread": 0.2,
                                               "seed": 2})
    assert np.asarray(spread.waveforms["time_s"])[0] == pytest.approx(58.5)
    assert np.all(np.isfinite(spread.waveforms["Q_sc_C"]))
