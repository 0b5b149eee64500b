"""Issue 54, the instrument (items 3, 5, 6, 8): the first-order front end exact at every
bandwidth, an input resistance down to the smallest the scene allows read as its limit,
the impact extremes kept for a quantity the reader leaves unchanged, and the peaks of a
scene whose instrument has not read yet (sweep, report). The field is the analytic plate
model; the CLI cases run the base scene of the issue."""
from __future__ import annotations

import math
import warnings

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import tengfield as tf
from tengfield import electrical
from tengfield.electrical.instrument import FirstOrder, time_constant
from tengfield.surrogate import TerminalCurves

import plate_model as fx

RUN = {"duration_s": 0.4, "settle_periods": 3, "sample_rate_hz": 5000.0}
BASE = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
        "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 1e-2\n")


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


# ---------------------------------------------------------------------------
# item 5: the first-order filter at small (and large) bandwidths
def _exact_first_order(t, x, tau):
    """τ y' = x - y for x linear between the samples, from rest (y = x[0]), in 60 digits."""
    mpmath.mp.dps = 60
    tau = mpmath.mpf(tau)
    y = mpmath.mpf(x[0])
    out = [float(y)]
    for k in range(1, len(t)):
        h = mpmath.mpf(t[k]) - mpmath.mpf(t[k - 1])
        x0, x1 = mpmath.mpf(x[k - 1]), mpmath.mpf(x[k])
        s = (x1 - x0) / h
        y = x1 - s * tau + (y - x0 + s * tau) * mpmath.exp(-h / tau)
        out.append(float(y))
    return np.array(out)


@settings(max_examples=60, deadline=None)
@given(log_bandwidth=st.floats(-12.0, 12.0), steps=st.integers(2, 40),
       seed=st.integers(0, 2**31 - 1))
def test_the_first_order_filter_is_its_closed_form_at_any_bandwidth(log_bandwidth, steps,
                                                                    seed):
    """1e-12 ... 1e12 Hz (the key's range): the filtered samples of a piecewise-linear input agree with the
    exact solution to a few ulp of the input (they lost 1e-4 of it at 1e-9 Hz)."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-5, 1e-3, steps))
    x = rng.normal(0.0, 1.0, steps)
    tau = time_constant(10.0 ** log_bandwidth)
    y = FirstOrder(tau)(t, x)
    exact = _exact_first_order(t, x, tau)
    # rounding: a few ulp of the largest term of a step (y itself, or the input times
    # the step's weight h / τ, below 1)
    bound = 1e-13 * (np.max(np.abs(exact)) + np.max(np.abs(x)) * min(1.0, np.max(np.diff(t)) / tau))
    assert np.max(np.abs(y - exact)) <= bound


def test_a_slow_front_end_reads_the_integral_of_a_sine():
    """f_c = 1e-9 Hz reading a 20 Hz unit sine from rest: y ≈ ∫ x dt / τ, at most
    2 / (ω τ) = 1.0e-10 ... the issue's 3.4e-4 V against an exact 7.6e-10 V at a 1 V scale."""
    t = np.linspace(0.0, 0.3, 1501)
    w = 2 * math.pi * 20.0
    for f_c in (1e-9, 1e-6):
        tau = time_constant(f_c)
        y = FirstOrder(tau)(t, np.sin(w * t))
        exact = _exact_first_order(t, np.sin(w * t), tau)
        np.testing.assert_allclose(y, exact, rtol=1e-9, atol=1e-12 * np.max(np.abs(exact)))
        assert np.max(np.abs(y)) == pytest.approx(2.0 / (w * tau), rel=1e-2)


# ---------------------------------------------------------------------------
# item 3: a quantity the reader leaves unchanged keeps its impact extremes
@pytest.mark.parametrize("rate", [2000.0, 20000.0])
def test_an_input_resistance_alone_leaves_the_charge_and_current_peaks(cache, rate):
    """R_in loads the voltage only (Q and I are read in short circuit): Q_read and I_read
    equal Q_SC and I_SC row by row, and so do their peaks, which take the extremes just
    before and after the impacts at any sample rate (they were 0.920 x the I_SC peak at
    2 kHz, 0.985 at 20 kHz)."""
    run = {**RUN, "sample_rate_hz": rate}
    r = tf.run(fx.scene_with(run=run, instrument={"input_resistance_ohm": 1e8}),
               cache_dir=cache, solve=fx.plate_model_solve)
    w = r.waveforms
    np.testing.assert_array_equal(w["I_read_A"], w["I_sc_A"])
    np.testing.assert_array_equal(w["Q_read_C"], w["Q_sc_C"])
    for name, terminal in (("I_read", "I_sc"), ("Q_read", "Q_sc")):
        assert r.peak[name] == pytest.approx(r.peak[terminal], rel=1e-12), name
        assert r.peaks[name] == pytest.approx(r.peaks[terminal], rel=1e-12), name
    # the loaded voltage is continuous at the impacts: its samples alone
    v = np.asarray(w["V_read_V"])[electrical.steady_window(r.t, r.scene)[0]]
    assert r.peak["V_read"] == pytest.approx(np.max(np.abs(v)), rel=1e-12)


def test_a_filter_still_takes_its_samples_alone(cache):
    """With a bandwidth the read current is not I_SC: its peak is its samples' own."""
    r = tf.run(fx.scene_with(run=RUN, instrument={"input_resistance_ohm": 1e8,
                                                  "bandwidth_hz": 300.0}),
               cache_dir=cache, solve=fx.plate_model_solve)
    i = np.asarray(r.waveforms["I_read_A"])[electrical.steady_window(r.t, r.scene)[0]]
    assert r.peak["I_read"] == pytest.approx(np.max(np.abs(i)), rel=1e-12)
    assert r.peak["I_read"] < r.peak["I_sc"]


# ---------------------------------------------------------------------------
# item 6: the smallest input resistance the scene allows
def test_the_smallest_input_resistance_reads_its_limit_without_warnings(cache):
    """R_in -> 0 (1e-300 ohm, allowed): the instrument shorts the terminal, V = R_in I_SC
    to double precision (R_in (C_T + C_p) is 1e-310 s against 2e-4 s steps); no numpy
    overflow, no NaN ("peak n/a" and an empty column before)."""
    r_in = 1e-300
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)     # numpy's overflow, invalid
        r = tf.run(fx.scene_with(run=RUN, instrument={"input_resistance_ohm": r_in}),
                   cache_dir=cache, solve=fx.plate_model_solve)
    v = np.asarray(r.waveforms["V_read_V"])
    i = np.asarray(r.waveforms["I_sc_A"])
    assert np.all(np.isfinite(v))
    np.testing.assert_allclose(v, r_in * i, rtol=1e-6, atol=0)
    assert r.peak["V_read"] == pytest.approx(r_in * np.max(np.abs(
        i[electrical.steady_window(r.t, r.scene)[0]])), rel=1e-6)


@pytest.mark.parametrize("r_in", [1e-30, 1e-3, 1.0])
def test_a_small_input_resistance_is_the_quasi_static_voltage(cache, r_in):
    """Between the limit and the exponential integrator the voltage is continuous:
    R_in (C_T + C_p) << the step gives V = R_in I_SC to 1e-6 either way."""
    r = tf.run(fx.scene_with(run=RUN, instrument={"input_resistance_ohm": r_in}),
               cache_dir=cache, solve=fx.plate_model_solve)
    v = np.asarray(r.waveforms["V_read_V"])[10:]
    i = np.asarray(r.waveforms["I_sc_A"])[10:]
    np.testing.assert_allclose(v, r_in * i, rtol=1e-6, atol=1e-6 * r_in * np.max(np.abs(i)))


# ---------------------------------------------------------------------------
# item 8: the peaks of a scene whose instrument has not read yet
def test_the_peaks_of_an_unread_instrument_scene_are_the_terminals(cache):
    """sweep and report ask terminal_extremes for the dynamics alone (no read columns):
    with only [instrument] capacitance_pF it ended in KeyError: 'Q_read'."""
    scene = fx.scene_with(run=RUN, instrument={"capacitance_pF": 338.0})
    r = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    curves = TerminalCurves(r.table, scene.circuit.reference, r.scene.device.ball_charge)
    got = electrical.terminal_extremes(r.scene, r.dynamics, curves)
    for name in ("V_oc", "Q_sc", "I_sc"):
        assert got["peak"][name] == pytest.approx(r.peak[name], rel=1e-12)
        assert got["peak_to_peak"][name] == pytest.approx(r.peaks[name], rel=1e-12)
    assert got["peak"]["V_read"] == pytest.approx(r.peak["V_read"], rel=1e-12)
    assert electrical.terminal_peaks(r.scene, r.dynamics, curves)["Q_sc"] == \
        pytest.approx(r.peaks["Q_sc"], rel=1e-12)


@pytest.mark.slow
def test_sweep_varies_the_instruments_capacitance_end_to_end(tmp_path, run_cli):
    """`tengfield sweep --vary instrument.capacitance_pF=100,338 --jobs 2` on the base
    scene, figures on: two rows, the same V_OC, Q_SC, I_SC (C_p does not touch them)."""
    import csv

    scene = tmp_path / "base.toml"
    scene.write_text(BASE)
    out = run_cli("sweep", scene, "--vary", "instrument.capacitance_pF=100,338",
                  "--jobs", "2", "-o", tmp_path / "out")
    assert out.returncode == 0, out.stderr[-3000:]
    assert "Traceback" not in out.stderr
    rows = list(csv.DictReader(open(tmp_path / "out" / "sweep.csv")))
    assert len(rows) == 2
    pngs = [p for p in (tmp_path / "out").iterdir() if p.suffix == ".png"]
    assert pngs
    columns = [c for c in rows[0] if c.startswith("V_oc") or c.startswith("Q_sc")]
    assert columns
    for c in columns:
        assert rows[0][c] == rows[1][c] and rows[0][c] != ""
