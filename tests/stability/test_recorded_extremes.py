"""Recorded excitation with measurement noise and with a discontinuous acceleration.

A noisy record has huge derivative bounds (white noise in displacement is
amplified by (sample rate)² in acceleration), which shrink the provably
contact-free steps and multiply the lift-off crossings; a square-wave
acceleration has jumps that the C² interpolant rings around. Each run must
stay bounded, finite and inside the stroke, and converge: to the clean
record as the noise vanishes (linearly), to the exact piecewise-parabolic
flight as the sampling of the square wave is refined.
"""
import math

import numpy as np
import pytest

from stability_checks import assert_sane_dynamics, fitted_slope, scene_with

from tengfield.dynamics import simulate
from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.table import recorded_table
from tengfield.scene import G

FREQUENCY, AMPLITUDE, STROKE = 20.0, 1.5e-3, 3e-3
OMEGA = 2 * math.pi * FREQUENCY
RATE = 5000.0


def noisy_record(signal, sigma, *, seed=7, duration=0.6):
    """The default drive sampled at 5 kHz plus white noise of standard deviation sigma."""
    t = np.arange(0.0, duration + 1e-12, 1.0 / RATE)
    clean = AMPLITUDE * np.sin(OMEGA * t)
    if signal == "acceleration":
        clean = -OMEGA**2 * clean
    return t, clean + sigma * np.random.default_rng(seed).standard_normal(t.size)


def first_impacts(table, count=3):
    _, (times, plates, speeds, _), n = integrate(table, STROKE, Restitution(0.1), t_start=0.05,
                                                 t_end=0.55, period=1 / FREQUENCY)
    assert n <= 10 * 20_000
    return times[:count], speeds[:count]


@pytest.mark.parametrize("signal,sigmas", [
    ("displacement", [1e-9, 1e-10, 1e-11]),       # m
    ("acceleration", [1e-1, 1e-2, 1e-3]),         # m/s²
])
def test_noise_perturbs_the_answer_linearly(signal, sigmas):
    """First impacts of a noisy record → those of the clean record, error ∝ σ."""
    clean_times, clean_speeds = first_impacts(recorded_table(*noisy_record(signal, 0.0), signal))
    errors = []
    for sigma in sigmas:
        times, speeds = first_impacts(recorded_table(*noisy_record(signal, sigma), signal))
        assert times.size == clean_times.size
        errors.append(np.max(np.abs(times - clean_times)) * FREQUENCY)
    assert np.all(np.diff(errors) < 0), errors
    assert fitted_slope(sigmas, errors) == pytest.approx(1.0, abs=0.15), errors


@pytest.mark.parametrize("signal,sigma", [("displacement", 1e-6), ("acceleration", 1.0),
                                          ("acceleration", 10.0)])
def test_heavy_measurement_noise_stays_bounded(tmp_path, signal, sigma):
    """1 µm displacement noise (≈ 2e4 m/s² in the acceleration bound) or an accelerometer
    noise of 0.4 g: a full scene run from the CSV file stays bounded and in range."""
    t, values = noisy_record(signal, sigma)
    path = tmp_path / "table.csv"
    np.savetxt(path, np.column_stack([t, values]), delimiter=",",
               header=f"time_s,{signal}", comments="")
    scene = scene_with(excitation={"kind": "recorded", "file": str(path), "signal": signal,
                                   "signal_column": signal, "frequency_hz": FREQUENCY},
                       run={"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 20000.0})
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=10 * 20_000)
    assert len(res.impacts) > 0


# -- discontinuous acceleration ---------------------------------------------------------
def square_wave_table(rate, gamma=1.5):
    """ÿ = -Γg on (kT, kT + T/2), +Γg on (kT + T/2, (k+1)T), sampled off the jumps."""
    period = 1 / FREQUENCY
    t = -0.5 * period + (np.arange(int(2 * period * rate)) + 0.5) / rate
    phase = np.mod(t, period) / period
    values = np.where(phase < 0.5, -gamma * G, gamma * G)
    return recorded_table(t, values, "acceleration")


def exact_square_wave_landing(gamma=1.5):
    """From rest at t = 0: relative acceleration α = (Γ - 1) g up to T/2, then -β,
    β = (Γ + 1) g. With u = s / (T/2): α/2 + α u - β u²/2 = 0, u = (α + √(α² + αβ))/β
    (< 1 for Γ < 2: it lands before the next switch) at speed (T/2) √(α² + αβ)."""
    half = 0.5 / FREQUENCY
    alpha, beta = (gamma - 1) * G, (gamma + 1) * G
    root = math.sqrt(alpha**2 + alpha * beta)
    return half * (1 + (alpha + root) / beta), half * root


def test_discontinuous_acceleration_converges_to_the_exact_flight():
    t_exact, v_exact = exact_square_wave_landing()
    rates = np.array([1000.0, 2000.0, 4000.0, 8000.0])
    errors = []
    for rate in rates:
        table = square_wave_table(rate)
        _, (times, plates, speeds, _), n = integrate(
            table, STROKE, Restitution(0.1), t_start=0.0, t_end=0.95 / FREQUENCY,
            period=1 / FREQUENCY)
        assert n < 100
        assert plates[0] == 0
        errors.append(max(abs(times[0] - t_exact) * FREQUENCY, abs(speeds[0] / v_exact - 1)))
    assert np.all(np.diff(errors) < 0), errors
    assert fitted_slope(1 / rates, errors) > 0.9, errors
    assert errors[-1] < 2e-3, errors


def test_discontinuous_acceleration_scene_run_is_bounded(tmp_path):
    rate = 4000.0
    period = 1 / FREQUENCY
    t = -0.5 * period + (np.arange(int(12 * period * rate)) + 0.5) / rate
    values = np.where(np.mod(t, period) < 0.5 * period, -3.0 * G, 3.0 * G)
    path = tmp_path / "square.csv"
    np.savetxt(path, np.column_stack([t, values]), delimiter=",",
               header="time_s,acceleration_m_per_s2", comments="")
    scene = scene_with(excitation={"kind": "recorded", "file": str(path),
                                   "signal": "acceleration",
                                   "signal_column": "acceleration_m_per_s2",
                                   "frequency_hz": FREQUENCY},
                       run={"duration_s": 10 * period, "settle_periods": 2})
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=10 * 20_000)
    assert "upper" in set(res.impacts.plate)    # Γ = 3: it reaches the upper plate
