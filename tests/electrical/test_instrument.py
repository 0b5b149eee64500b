"""The bench's instrument (issue #39, ``[instrument]``): the first-order front end against
its closed forms, the aperture's mean of known waveforms, the readings at the sample
rate, an ideal instrument giving back the terminal's columns, the state carried from
chunk to chunk (a long run read in pieces = read whole), and the books of a terminal
loaded by the instrument's input resistance. The field is the analytic plate model."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import tengfield as tf
from tengfield.electrical import stream
from tengfield.electrical.instrument import Aperture, Chain, FirstOrder, SampleHold, time_constant
from tengfield.scene import Instrument

import plate_model as fx

RUN = {"duration_s": 0.4, "settle_periods": 3, "sample_rate_hz": 5000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def test_first_order_step_response_is_the_exponential():
    tau = time_constant(50.0)                     # 3.18 ms
    t = np.r_[0.0, 0.0, np.linspace(1e-4, 0.03, 300)]
    x = np.r_[0.0, np.ones(301)]                  # a jump at t = 0 (a repeated instant)
    y = FirstOrder(tau)(t, x)
    assert y[1] == 0.0                            # the output does not jump
    np.testing.assert_allclose(y[1:], 1.0 - np.exp(-t[1:] / tau), rtol=0, atol=1e-13)


def test_first_order_sine_response_is_the_closed_form():
    f_c, f = 100.0, 250.0
    tau, w = time_constant(f_c), 2 * math.pi * f
    wt = w * tau
    errors = []
    for n in (4001, 8001):          # the input linear between samples: second order
        t = np.linspace(0.0, 0.04, n)
        y = FirstOrder(tau)(t, np.sin(w * t))
        exact = (np.sin(w * t) - wt * np.cos(w * t) + wt * np.exp(-t / tau)) / (1 + wt * wt)
        errors.append(np.max(np.abs(y - exact)))
    assert errors[1] < 5e-6
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)
    late = t > 0.03                               # steady: gain 1 / sqrt(1 + (f/f_c)^2)
    assert np.max(np.abs(y[late])) == pytest.approx(1 / math.sqrt(1 + (f / f_c) ** 2), rel=1e-3)


def test_aperture_is_the_mean_over_the_last_interval():
    t = np.linspace(0.0, 0.1, 10001)
    # a ramp: the mean over [t - T, t] is the value at t - T/2, exactly
    y = Aperture(0.01)(t, 3.0 * t)
    full = t >= 0.01
    np.testing.assert_allclose(y[full], 3.0 * (t[full] - 0.005), rtol=1e-12)
    np.testing.assert_allclose(y[~full], 1.5 * t[~full], rtol=1e-12, atol=1e-15)  # since t0
    # a sine: (cos w(t - T) - cos wt) / (w T)
    w, T = 2 * math.pi * 40.0, 0.004
    y = Aperture(T)(t, np.sin(w * t))
    exact = (np.cos(w * (t - T)) - np.cos(w * t)) / (w * T)
    np.testing.assert_allclose(y[t >= T], exact[t >= T], atol=1e-6)


def test_readings_come_at_the_sample_rate_and_are_held():
    t = np.linspace(0.0, 0.1, 1001)               # 10 kHz rows, 1 kHz readings
    y = SampleHold(1000.0)(t, 2.0 * t + 1.0)
    np.testing.assert_allclose(y, 2.0 * np.floor(t * 1000.0 + 1e-6) / 1000.0 + 1.0, rtol=1e-12)
    assert len(np.unique(y)) == 101


@pytest.mark.parametrize("pieces", [[7], [1, 2, 3, 500], [333, 334]])
def test_the_chain_read_in_pieces_is_the_chain_read_whole(pieces):
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(1e-5, 3e-4, 1200))
    x = np.sin(2 * math.pi * 30 * t) + np.where(t > 0.1, 0.5, 0.0)
    inst = Instrument(bandwidth=80.0, aperture=2.5e-3, sample_rate=700.0, given=True)
    whole = Chain(inst)(t, x)
    chain, out, i = Chain(inst), [], 0
    bounds = np.cumsum(pieces * (len(t) // sum(pieces) + 1))
    for j in [b for b in bounds if b < len(t)] + [len(t)]:
        out.append(chain(t[i:j], x[i:j]))
        i = j
    np.testing.assert_allclose(np.concatenate(out), whole, rtol=0, atol=1e-12)


def test_an_ideal_instrument_gives_back_the_terminals_columns(cache):
    plain = tf.run(fx.scene_with(run=RUN, circuit={"kind": "open"}), cache_dir=cache,
                   solve=fx.plate_model_solve)
    read = tf.run(fx.scene_with(run=RUN, instrument={"capacitance_pF": 338.0}),
                  cache_dir=cache, solve=fx.plate_model_solve)
    w, p = read.waveforms, plain.waveforms
    c_p = 338e-12
    np.testing.assert_allclose(w["Q_read_C"], p["Q_sc_C"], rtol=1e-12, atol=0)
    np.testing.assert_allclose(w["I_read_A"], p["I_sc_A"], rtol=1e-12, atol=0)
    np.testing.assert_allclose(w["V_read_V"], p["Q_sc_C"] / (p["C_T_F"] + c_p), rtol=1e-12)
    assert read.peak["I_read"] == pytest.approx(read.peak["I_sc"], rel=1e-12)  # impacts too
    assert read.peaks["Q_read"] == pytest.approx(read.peaks["Q_sc"], rel=1e-12)
    # without [instrument] no read quantity at all
    assert not {"V_read_V", "Q_read_C", "I_read_A"} & set(p)
    assert "Q_read_C" not in plain.summary["peak"]


def test_a_filtered_instrument_reads_a_lower_current_peak(cache):
    ideal = tf.run(fx.scene_with(run=RUN, instrument={"capacitance_pF": 338.0}),
                   cache_dir=cache, solve=fx.plate_model_solve)
    slow = tf.run(fx.scene_with(run=RUN, instrument={"capacitance_pF": 338.0,
                                                     "bandwidth_hz": 100.0,
                                                     "aperture_s": 1e-3}),
                  cache_dir=cache, solve=fx.plate_model_solve)
    assert slow.peak["I_read"] < 0.9 * ideal.peak["I_read"]
    # a charge changes slowly: the same filter barely touches it
    assert slow.peaks["Q_read"] == pytest.approx(ideal.peaks["Q_read"], rel=0.1)


def test_streamed_with_an_instrument_equals_whole(cache, monkeypatch):
    scene = fx.scene_with(run=RUN, instrument={"capacitance_pF": 100.0,
                                               "input_resistance_ohm": 1e9,
                                               "bandwidth_hz": 300.0, "aperture_s": 5e-4,
                                               "sample_rate_hz": 2000.0})
    whole = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    monkeypatch.setattr(stream, "STREAM_ROWS", 10)
    monkeypatch.setattr(stream, "CHUNK_ROWS", 97)
    streamed = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    assert isinstance(streamed.waveforms, stream.StreamedWaveforms)
    for column in ("V_read_V", "Q_read_C", "I_read_A"):
        a = np.asarray(whole.waveforms[column])
        np.testing.assert_allclose(streamed.waveforms[column], a, rtol=0,
                                   atol=1e-9 * np.max(np.abs(a)), err_msg=column)
    for name in ("V_read", "Q_read", "I_read"):
        assert streamed.peaks[name] == pytest.approx(whole.peaks[name], rel=1e-9)


def test_the_input_resistance_books_close(cache):
    """An open terminal read through R_in || C_p (no filter): the charge on the terminal's
    capacitance, (C_T + C_p) V, is the charge the device drove in, ∫ I_SC dt, less the
    charge through R_in, ∫ V / R_in dt (Kirchhoff at the node); the energy the mechanics
    delivers, ∫ (V I_SC - V^2/2 dC_T/dt) dt, is what R_in dissipates plus the change
    stored. Both integrals by the trapezoidal rule on the output samples."""
    r_in, c_p = 1e9, 100e-12
    res = tf.run(fx.scene_with(run=RUN, instrument={"capacitance_pF": 100.0,
                                                    "input_resistance_ohm": r_in}),
                 cache_dir=cache, solve=fx.plate_model_solve)
    w = res.waveforms
    t = np.asarray(w["time_s"])
    v, q, i, c = (np.asarray(w[k]) for k in ("V_read_V", "Q_sc_C", "I_sc_A", "C_T_F"))

    def running(y):
        return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])

    stored_charge = (c + c_p) * v
    books = stored_charge[0] + running(i) - running(v / r_in)
    assert np.max(np.abs(stored_charge - books)) < 1e-3 * np.max(np.abs(stored_charge))
    unloaded = q / (c + c_p)
    assert np.max(np.abs(v - unloaded)) > 0.1 * np.max(np.abs(unloaded))   # R_in loads it
    delivered = running(v * i - 0.5 * v * v * np.gradient(c, t))[-1]
    dissipated = running(v * v / r_in)[-1]
    stored = 0.5 * ((c[-1] + c_p) * v[-1] ** 2 - (c[0] + c_p) * v[0] ** 2)
    assert delivered == pytest.approx(dissipated + stored, rel=1e-2)


def test_the_rectifiers_books_do_not_see_the_instrument(cache):
    circuit = {"kind": "rectifier", "storage_capacitance_uF": 0.01}
    plain = tf.run(fx.scene_with(run=RUN, circuit=circuit), cache_dir=cache,
                   solve=fx.plate_model_solve)
    read = tf.run(fx.scene_with(run=RUN, circuit=circuit,
                                instrument={"bandwidth_hz": 50.0}),
                  cache_dir=cache, solve=fx.plate_model_solve)
    assert read.summary["rectifier"] == plain.summary["rectifier"]
    assert "I_read_A" in read.waveforms


def test_the_old_key_is_read_with_one_warning(tmp_path):
    path = tmp_path / "old.toml"
    path.write_text("[circuit]\nparallel_capacitance_pF = 338.0\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = tf.load_scene(path)
    said = [str(w.message) for w in caught if "capacitance_pF" in str(w.message)]
    assert len(said) == 1 and "[instrument] capacitance_pF = 338" in said[0]
    assert scene.circuit.parallel_capacitance == pytest.approx(338e-12)
    assert scene.instrument.capacitance == pytest.approx(338e-12)
    both = tmp_path / "both.toml"
    both.write_text("[circuit]\nparallel_capacitance_pF = 1.0\n[instrument]\ncapacitance_pF = 2.0\n")
    with pytest.raises(tf.SceneError, match="capacitance_pF"), \
            pytest.warns(FutureWarning, match="parallel_capacitance_pF is now"):
        tf.load_scene(both)


@pytest.mark.parametrize("array", [{"cells": 3}, {"cells": 3, "restitution_spread": 0.1}],
                         ids=["identical", "spread"])
def test_an_array_is_read_by_the_instrument_too(cache, array):
    """[array] cells read through one instrument: its three columns and peaks, the read
    current below the array's I_SC (a 100 Hz front end)."""
    r = tf.run(fx.scene_with(run=RUN, array=array,
                             instrument={"capacitance_pF": 100.0, "bandwidth_hz": 100.0}),
               cache_dir=cache, solve=fx.plate_model_solve)
    assert {"V_read_V", "Q_read_C", "I_read_A", "C_T_F"} <= set(r.waveforms)
    assert r.summary["peak"]["I_read_A"] < r.summary["peak"]["I_sc_A"]
    w = r.waveforms
    np.testing.assert_allclose(w["V_oc_V"], w["Q_sc_C"] / w["C_T_F"], rtol=1e-12)


def test_with_values_changes_the_one_capacitance_under_either_name():
    """An uncertainty study or a fit sets [circuit] parallel_capacitance_pF on a scene
    with an [instrument]: the instrument's capacitance changes (it was refused as two
    different values of one capacitance); a new [instrument] value replaces the old key."""
    inst = tf.default_scene().with_values(instrument={"capacitance_pF": 338.0,
                                                      "bandwidth_hz": 50.0})
    moved = inst.with_values(circuit={"parallel_capacitance_pF": 100.0})
    assert moved.instrument.capacitance == pytest.approx(100e-12)
    assert moved.circuit.parallel_capacitance == pytest.approx(100e-12)
    assert moved.instrument.bandwidth == 50.0
    old = tf.default_scene().with_values(circuit={"parallel_capacitance_pF": 338.0})
    new = old.with_values(instrument={"capacitance_pF": 10.0})
    assert new.circuit.parallel_capacitance == pytest.approx(10e-12)
    assert "parallel_capacitance_pF" not in new.raw.get("circuit", {})


def test_equal_steps_take_the_compiled_recurrence_with_the_loops_numbers():
    from tengfield.electrical.instrument import _recurrence

    rng = np.random.default_rng(0)
    decay, source = np.full(5000, 0.97), rng.normal(size=5000)
    expected, prev = np.empty(5000), 0.3
    for k in range(5000):
        prev = decay[k] * prev + source[k]
        expected[k] = prev
    np.testing.assert_allclose(_recurrence(decay, source, 0.3), expected, rtol=0, atol=1e-12)
