"""Random and multi-harmonic table motion: realised rms and PSD, reproducibility,
consistency of displacement and acceleration, the one-harmonic case is the sine."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.signal import welch

from tengfield.dynamics.table import sine_phase_at, sine_table
from tengfield.dynamics.vibration import (
    STANDARD_GRAVITY, Harmonic, band_psd, noise_record, record_grid, tabulated_psd,
    vibration_table,
)
from tengfield.errors import DynamicsError


def _acceleration(table, duration, rate=4000.0):
    t = np.arange(int(duration * rate)) / rate
    return t, table.evaluate(t)[2]


def test_band_rms_within_sampling_error():
    """The realised table acceleration has the requested rms: over 20 seeds the
    relative error of each rms stays within 4 of its standard errors, and their
    mean within 4/sqrt(20)."""
    psd = band_psd((20.0, 200.0), 3.0)
    duration = 4.0
    # standard error of a mean square over a band B and a record T: 1/sqrt(B T)
    rel_se = 1.0 / math.sqrt((200.0 - 20.0) * duration)
    errors = []
    for seed in range(20):
        table = vibration_table(duration=duration, seed=seed, psd=psd)
        _, a = _acceleration(table, duration)
        errors.append(np.mean(a**2) / 9.0 - 1.0)
    errors = np.array(errors)
    assert np.all(np.abs(errors) < 4.0 * rel_se)
    assert abs(errors.mean()) < 4.0 * rel_se / math.sqrt(20)


def test_welch_psd_inside_band_of_target():
    """The Welch estimate (2 s segments, 0.5 Hz resolution, ~90 averages over 100 s)
    lies within +-30 % of the flat target on the band's interior (the estimate's
    relative standard deviation per bin is ~1/sqrt(90) = 0.11: +-30 % is ~3 sd) and
    below 2 % of it well outside the band."""
    psd = band_psd((30.0, 120.0), 2.0)
    duration = 100.0
    table = vibration_table(duration=duration, seed=7, psd=psd)
    rate = 1000.0
    t, a = _acceleration(table, duration, rate)
    f, s = welch(a, fs=rate, nperseg=int(2 * rate))
    level = 4.0 / 90.0
    inside = (f > 35.0) & (f < 115.0)
    # smooth over 5 neighbouring bins: each value then has ~5 % sd
    smooth = np.convolve(s, np.ones(5) / 5, mode="same")
    assert np.all(np.abs(smooth[inside] / level - 1.0) < 0.3)
    outside = (f < 20.0) | ((f > 135.0) & (f < 400.0))
    assert np.all(s[outside] < 0.02 * level)


def test_tabulated_psd_log_log_and_units():
    psd = tabulated_psd([10.0, 100.0], [1e-3, 1e-1], unit="g2_per_hz")
    # log-log: a straight line of slope 2; at 31.62 Hz: 1e-2 g^2/Hz
    assert psd(np.array([math.sqrt(1000.0)]))[0] == pytest.approx(1e-2 * STANDARD_GRAVITY**2)
    assert psd(np.array([5.0, 200.0])).tolist() == [0.0, 0.0]
    # mean square: integral of c f^2 from 10 to 100 with c = 1e-5 g^2 / Hz^3
    exact = 1e-5 * (100.0**3 - 10.0**3) / 3.0 * STANDARD_GRAVITY**2
    assert psd.mean_square() == pytest.approx(exact, rel=1e-6)


@pytest.mark.parametrize("freqs, values, message", [
    ([10.0], [1.0], "at least 2"),
    ([10.0, 10.0], [1.0, 1.0], "strictly increasing"),
    ([0.0, 10.0], [1.0, 1.0], "> 0"),
    ([1.0, 10.0], [1.0, -1.0], ">= 0"),
    ([1.0, 10.0], [1.0, float("nan")], "NaN"),
])
def test_tabulated_psd_refuses_bad_tables(freqs, values, message):
    with pytest.raises(DynamicsError, match=message):
        tabulated_psd(freqs, values)


def test_same_seed_same_table_other_seed_other():
    psd = band_psd((20.0, 200.0), 1.0)
    a = vibration_table(duration=1.0, seed=3, psd=psd)
    b = vibration_table(duration=1.0, seed=3, psd=psd)
    c = vibration_table(duration=1.0, seed=4, psd=psd)
    assert np.array_equal(a.coeffs, b.coeffs) and np.array_equal(a.breaks, b.breaks)
    assert not np.allclose(a.coeffs, c.coeffs)


def test_one_harmonic_is_the_sine_bit_for_bit():
    h = Harmonic(frequency=33.0, amplitude=0.75e-3, phase=0.3)
    for origin in (0.0, 1.7e9):
        table = vibration_table(duration=2.0, harmonics=(h,), origin=origin)
        sine = sine_table(0.75e-3, 2 * math.pi * 33.0, sine_phase_at(33.0, 0.3, origin))
        assert table.kind == sine.kind
        assert np.array_equal(table.params, sine.params)
        assert (table.acc_bound, table.jerk_bound) == (sine.acc_bound, sine.jerk_bound)


def test_harmonics_table_follows_the_sum_of_sines():
    """Several harmonics: the spline's displacement and acceleration match the
    analytic sum (acceleration to 1e-5 of its amplitude); the kernel's bound
    covers the true maximum of |y''|."""
    hs = (Harmonic(33.0, 1e-3, 0.0), Harmonic(66.0, 0.2e-3, 1.0), Harmonic(132.0, 0.05e-3, 2.0))
    table = vibration_table(duration=1.0, harmonics=hs)
    t = np.linspace(0.0, 1.0, 7919)
    y, _, a = table.evaluate(t)
    y_exact = sum(h.amplitude * np.sin(2 * math.pi * h.frequency * t + h.phase) for h in hs)
    a_exact = sum(-h.amplitude * (2 * math.pi * h.frequency) ** 2
                  * np.sin(2 * math.pi * h.frequency * t + h.phase) for h in hs)
    amax = sum(h.amplitude * (2 * math.pi * h.frequency) ** 2 for h in hs)
    assert np.max(np.abs(y - y_exact)) < 1e-9 * amax
    assert np.max(np.abs(a - a_exact)) < 1e-5 * amax
    assert table.acc_bound >= np.max(np.abs(a_exact))


def test_noise_displacement_is_the_double_integral_of_acceleration():
    """Spectral check of consistency: y'' of the synthesised displacement (by FFT)
    equals the synthesised acceleration; no mean, no drift (periodic record)."""
    psd = band_psd((10.0, 50.0), 1.0)
    m, dt = record_grid(2.0, 50.0, 10.0)
    y, a = noise_record(psd, m, dt, seed=1)
    omega = 2 * np.pi * np.fft.rfftfreq(m, dt)
    a_from_y = np.fft.irfft(-omega**2 * np.fft.rfft(y), m)
    assert np.max(np.abs(a_from_y - a)) < 1e-9 * np.max(np.abs(a))
    assert abs(a.mean()) < 1e-12 and abs(y.mean()) < 1e-15


@settings(max_examples=20, deadline=None)
@given(f1=st.floats(5.0, 100.0), width=st.floats(5.0, 200.0), rms=st.floats(1e-3, 1e3),
       seed=st.integers(0, 2**32 - 1))
def test_noise_scales_with_rms_and_stays_in_band(f1, width, rms, seed):
    """Invariants for any band, level and seed: the acceleration scales linearly with
    the rms; its spectrum has no energy outside the band."""
    psd1 = band_psd((f1, f1 + width), 1.0)
    psd2 = band_psd((f1, f1 + width), rms)
    m, dt = record_grid(1.0, f1 + width, f1)
    _, a1 = noise_record(psd1, m, dt, seed)
    _, a2 = noise_record(psd2, m, dt, seed)
    np.testing.assert_allclose(a2, rms * a1, rtol=1e-9, atol=1e-12 * rms)
    spec = np.abs(np.fft.rfft(a1)) ** 2
    f = np.fft.rfftfreq(m, dt)
    out = (f < f1 * (1 - 1e-9)) | (f > (f1 + width) * (1 + 1e-9))
    assert spec[out].sum() <= 1e-20 * spec.sum()


def test_refuses_nothing_to_synthesise():
    with pytest.raises(DynamicsError, match="at least one harmonic"):
        vibration_table(duration=1.0)


def test_a_longer_run_extends_the_same_realisation():
    """The noise depends on the seed and the run's clock, not on the run's length: a 1 s
    and a 7 s table agree on the first second (the spline's samples to round-off)."""
    psd = band_psd((10.0, 120.0), 5.0)
    short = vibration_table(duration=1.0, seed=5, psd=psd)
    long = vibration_table(duration=7.0, seed=5, psd=psd)
    t = np.arange(0.0, 1.0, 1.0 / (32 * 120.0))
    np.testing.assert_allclose(short.evaluate(t)[0], long.evaluate(t)[0], rtol=0,
                               atol=1e-9 * np.max(np.abs(long.evaluate(t)[0])))
    np.testing.assert_allclose(short.evaluate(t[:-200])[2], long.evaluate(t[:-200])[2],
                               rtol=0, atol=1e-6 * 5.0)
