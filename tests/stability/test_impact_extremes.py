"""Stability of the event-driven impact map at the edges of its parameter space.

Cases (issue 5): restitution 0, 1e-6, 0.999999 and 1 on a still table;
Γ = 1 ± 1e-9 and Γ = 10³; 0.1 Hz and 2 kHz; Δh = 1 µm and 100 mm; a ball
that almost fills the tube. Each run must end within a bounded number of
events, stay finite and inside 0 ≤ gap ≤ Δh, and keep its invariants
(energy never grows on a still table, exact restitution at every impact).
The impact map has no tolerance to tighten (free flight is exact, contacts
are located to 1e-13 m), so its answers are held to closed forms and to
limits approached continuously (Γ → 1⁺: max gap → 4.5 g δ²/ω²).
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from stability_checks import (amplitude_mm_for, assert_sane_dynamics,
                              scene_with, still_table_energy)

from tengfield.dynamics import simulate
from tengfield.scene import G

RESTITUTIONS = [0.0, 1e-6, 0.999999, 1.0]
FAST_RUN = {"duration_s": 1.0, "settle_periods": 2, "sample_rate_hz": 20000.0}


def still_table(restitution, gap_mm, velocity=0.0, stroke_mm=3.0, duration=1.0):
    """A still table (A = 0): only gravity and the plates act on the ball."""
    return scene_with(device={"stroke_mm": stroke_mm},
                      excitation={"amplitude_mm": 0.0, "frequency_hz": 20.0},
                      contact={"restitution": restitution},
                      initial={"gap_mm": gap_mm, "velocity_m_per_s": velocity},
                      run={"duration_s": duration, "settle_periods": 1,
                           "sample_rate_hz": 50000.0},
                      field={"domain_radius_mm": 200.0})


# -- restitution on a still table ------------------------------------------------
@pytest.mark.parametrize("restitution", RESTITUTIONS)
def test_dropped_ball_follows_the_geometric_bounce_series(restitution):
    """Drop from 2 mm: impacts at t_1 = √(2h/g), t_{k+1} = t_k + 2 e^k v_1 / g,
    v_after = e v_before exactly; chatter ends at t_∞ = t_1 + 2 e v_1 / (g (1 - e))
    and the ball then rests; energy g z + v²/2 never grows."""
    height = 2e-3
    res = simulate(still_table(restitution, height * 1e3))
    assert_sane_dynamics(res, max_events=200)
    v1, t1 = math.sqrt(2 * G * height), math.sqrt(2 * height / G)
    imp = res.impacts
    assert imp.time[0] == pytest.approx(t1, rel=1e-12)
    assert imp.speed_before[0] == pytest.approx(v1, rel=1e-12)
    assert np.all(imp.plate == "lower")
    rebound = np.where(imp.speed_before * restitution < 1e-9, 0.0,
                       imp.speed_before * restitution)
    assert imp.speed_after == pytest.approx(rebound, rel=1e-12, abs=1e-15)
    n = min(len(imp), 20)
    expected = t1 + np.concatenate([[0.0], np.cumsum(2 * restitution ** np.arange(1, n) * v1 / G)])
    assert imp.time[:n] == pytest.approx(expected, rel=1e-9)

    energy = still_table_energy(*res.sample(np.linspace(0.0, 1.0, 200001))[:2])
    assert np.max(np.diff(energy)) <= 1e-12 * energy[0]
    if restitution == 1.0:
        assert np.ptp(energy) <= 1e-9 * energy[0]
    if restitution < 1e-3:
        t_inf = t1 + 2 * restitution * v1 / (G * (1 - restitution))
        z, v, _ = res.sample(np.linspace(t_inf + 1e-9, 1.0, 1000))
        assert np.all(z == 0.0) and np.all(v == 0.0)


@pytest.mark.parametrize("restitution", RESTITUTIONS)
def test_ball_thrown_between_still_plates_never_gains_energy(restitution):
    """Thrown up at 0.4 m/s from 1 mm: it hits the upper plate (v²/2g = 8 mm > Δh)
    and the lower one; g z + v²/2 is non-increasing, conserved for e = 1."""
    res = simulate(still_table(restitution, 1.0, velocity=0.4))
    assert_sane_dynamics(res, max_events=2000)
    assert "upper" in set(res.impacts.plate)
    energy = still_table_energy(*res.sample(np.linspace(0.0, 1.0, 200001))[:2])
    assert np.max(np.diff(energy)) <= 1e-12 * energy[0]
    if restitution == 1.0:
        assert np.ptp(energy) <= 1e-9 * energy[0]
        assert res.impacts.speed_after == pytest.approx(res.impacts.speed_before, rel=1e-12)


def test_restitution_limits_are_approached_continuously():
    """e = 0.999999 differs from e = 1 by O(1 - e) over a few bounces, e = 1e-6 from e = 0
    by O(e): no jump in the answer at either end of [0, 1]."""
    def gaps(e):
        res = simulate(still_table(e, 1.0, velocity=0.4, duration=0.2))
        return res.gap
    assert np.max(np.abs(gaps(0.999999) - gaps(1.0))) < 1e-3 * 3e-3
    assert np.max(np.abs(gaps(1e-6) - gaps(0.0))) < 1e-3 * 3e-3


# -- Γ at the lift-off threshold and far above it -------------------------------------
def first_flight_max_gap(gamma, frequency):
    """Max gap of the first hop after lift-off, sampled densely around it."""
    scene = scene_with(excitation={"amplitude_mm": amplitude_mm_for(gamma, frequency),
                                   "frequency_hz": frequency},
                       contact={"restitution": 0.1},
                       run={"duration_s": 1.0 / frequency, "settle_periods": 0})
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=100)
    omega, delta = 2 * math.pi * frequency, gamma - 1.0
    lift = math.asin(1.0 / gamma) / omega
    t = lift + np.linspace(0.0, 4.0 * math.sqrt(2.0 * max(delta, 1e-30)) / omega, 40001)
    return float(np.max(res.sample(t)[0])), res


def hop_height(delta, frequency):
    """Max gap of the first hop for Γ = 1 + δ, δ → 0: z'' = g(Γ sin ωt - 1) ≈ g(δ - φ²/2)
    near ωt = π/2 + φ; with φ = √(2δ) u the hop starts at u = -1, its top is at u = 2,
    height 2.25 · 2 g δ² / ω² = 4.5 g δ² / ω²."""
    return 4.5 * G * delta**2 / (2 * math.pi * frequency) ** 2


def test_lift_off_threshold_gamma_just_below_one_stays_at_rest():
    scene = scene_with(excitation={"amplitude_mm": amplitude_mm_for(1 - 1e-9, 20.0)},
                       run=FAST_RUN)
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=5)
    assert len(res.impacts) == 0 and np.all(res.gap == 0.0)
    assert res.regime.name == "rest"


def test_lift_off_threshold_gamma_just_above_one_hops_by_delta_squared():
    """Γ = 1 + δ: the hop height tends to 4.5 g δ²/ω² (ratio → 1 as δ → 0, slope 2);
    at δ = 1e-9 it is below the rounding floor of z (≈ 1e-16 A) and never negative."""
    frequency = 1.0
    deltas = np.array([1e-2, 1e-3, 1e-4])
    heights = np.array([first_flight_max_gap(1 + d, frequency)[0] for d in deltas])
    ratio = heights / hop_height(deltas, frequency)
    assert abs(ratio[-1] - 1.0) < 2e-3, ratio
    assert np.all(np.diff(np.abs(ratio - 1.0)) < 0), ratio       # converges as δ → 0
    slope = np.polyfit(np.log(deltas), np.log(heights), 1)[0]
    assert slope == pytest.approx(2.0, abs=0.02)

    scene = scene_with(excitation={"amplitude_mm": amplitude_mm_for(1 + 1e-9, 20.0)},
                       run=FAST_RUN)
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=2000)
    floor = 64 * np.finfo(float).eps * scene.excitation.amplitude
    assert res.gap.max() <= hop_height(1e-9, 20.0) + floor


def test_gamma_one_thousand_first_upper_impact_is_the_exact_root():
    """Γ = 10³ at 20 Hz (A = 0.62 m): the first impact on the upper plate is the first
    root of the closed-form flight z(t) = Δh after lift-off; the run stays bounded."""
    gamma, frequency = 1e3, 20.0
    scene = scene_with(excitation={"amplitude_mm": amplitude_mm_for(gamma, frequency),
                                   "frequency_hz": frequency},
                       run={"duration_s": 0.5, "settle_periods": 2})
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=10 * 20_000)
    amp, omega, stroke = scene.excitation.amplitude, scene.excitation.omega, scene.device.stroke
    t0 = math.asin(1.0 / gamma) / omega
    y0, yd0 = amp * math.sin(omega * t0), amp * omega * math.cos(omega * t0)

    def gap(t):
        s = t - t0
        return -0.5 * G * s * s - (amp * math.sin(omega * t) - y0 - yd0 * s)

    grid = t0 + np.linspace(1e-12, 0.25 / frequency, 200001)
    values = np.array([gap(t) for t in grid]) - stroke
    k = int(np.flatnonzero(values >= 0)[0])
    t_hit = brentq(lambda t: gap(t) - stroke, grid[k - 1], grid[k], xtol=1e-15, rtol=1e-15)
    assert res.impacts.plate[0] == "upper"
    assert res.impacts.time[0] == pytest.approx(t_hit, rel=1e-11)


# -- frequency: 0.1 Hz and 2 kHz --------------------------------------------------------
@pytest.mark.parametrize("frequency", [0.1, 2000.0])
def test_extreme_frequencies_on_the_paper_device(frequency):
    """Γ = 2 on the real device (A = 50 m at 0.1 Hz, 0.12 µm at 2 kHz): bounded, finite,
    inside the stroke; at 2 kHz the hops are far below Δh (no upper impact)."""
    scene = scene_with(excitation={"amplitude_mm": amplitude_mm_for(2.0, frequency),
                                   "frequency_hz": frequency},
                       run={"duration_s": 20.0 / frequency, "settle_periods": 2,
                            "sample_rate_hz": 200.0 * frequency})
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=20 * 20_000)
    if frequency > 1000:
        assert "upper" not in set(res.impacts.plate)
        assert res.gap.max() < 1e-5
    else:
        assert "upper" in set(res.impacts.plate)


# -- Δh: 1 µm and 100 mm ----------------------------------------------------------------
def test_one_micron_stroke_follows_the_table_sign_of_g_plus_acceleration():
    """Δh = 1 µm, Γ = 2: the ball is (almost) always on a plate: on the upper one while
    ÿ < -g, i.e. a fraction (π - 2 asin(1/Γ)) / 2π of the time (± transit time)."""
    gamma = 2.0
    scene = scene_with(device={"stroke_mm": 1e-3},
                       excitation={"amplitude_mm": amplitude_mm_for(gamma, 20.0)},
                       run={"duration_s": 1.0, "settle_periods": 2, "sample_rate_hz": 2e5})
    res = simulate(scene)
    assert_sane_dynamics(res, max_events=20 * 20_000)
    window = res.t >= res.window_start
    on_upper = np.mean(res.gap[window] >= res.stroke * (1 - 1e-9))
    expected = (math.pi - 2 * math.asin(1 / gamma)) / (2 * math.pi)
    # leaving a plate the relative acceleration starts from 0 and grows with the jerk
    # j = Γ g ω cos(asin 1/Γ): the crossing takes (6 Δh / j)^(1/3), twice per period
    omega = scene.excitation.omega
    jerk = gamma * G * omega * math.cos(math.asin(1 / gamma))
    transit = 2 * (6 * res.stroke / jerk) ** (1 / 3) / scene.excitation.period
    assert expected - 1.5 * transit <= on_upper <= expected, (on_upper, expected, transit)


@pytest.mark.parametrize("restitution", [0.999999, 1.0])
def test_hundred_millimetre_stroke_exact_impact_speeds(restitution):
    """Δh = 100 mm, still table, thrown up at 2 m/s: the upper impact speed is
    √(v0² - 2gΔh); with e = 1 every later impact repeats the first two."""
    stroke, v0 = 0.1, 2.0
    res = simulate(still_table(restitution, 0.0, velocity=v0, stroke_mm=100.0, duration=2.0))
    assert_sane_dynamics(res, max_events=1000)
    imp = res.impacts
    assert imp.plate[0] == "upper"
    assert imp.speed_before[0] == pytest.approx(math.sqrt(v0**2 - 2 * G * stroke), rel=1e-12)
    assert imp.speed_before[1] == pytest.approx(
        math.sqrt((restitution * imp.speed_before[0]) ** 2 + 2 * G * stroke), rel=1e-12)
    if restitution == 1.0:
        assert imp.speed_before[::2] == pytest.approx(imp.speed_before[0], rel=1e-9)
        assert imp.speed_before[1::2] == pytest.approx(v0, rel=1e-9)


# -- a ball that almost fills the tube ------------------------------------------------
def test_ball_almost_filling_the_tube_moves_like_any_ball():
    """The impact map is mass independent (no wall friction in the model): a ball with
    0.05 µm radial clearance follows exactly the default ball's trajectory."""
    tight = scene_with(device={"ball_diameter_mm": 7.9999}, run=FAST_RUN)
    res = simulate(tight)
    assert_sane_dynamics(res, max_events=20 * 20_000)
    reference = simulate(scene_with(run=FAST_RUN))
    assert np.array_equal(res.gap, reference.gap)
    assert np.array_equal(res.impacts.time, reference.impacts.time)
