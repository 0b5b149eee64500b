"""Soft contact (paper Eq. 1) as a stiff ODE, stiffness up to 1e12 N/m.

At k = 1e12 N/m the contact oscillation has ω_c = √(k/m) ≈ 5e7 rad/s
(contact time 60 ns) against a flight time of 30 ms: the stiff solver must
neither crawl through the rest phases nor lose the contact events. Each run
must end within a bounded number of phases, stay finite, penetrate no
deeper than the undamped bound v/ω_c (+ the static m g/k), never gain
mechanical energy (gravity + spring) on a still table, and converge to the
impact map as k grows, at the expected rate k^(-1/2).
"""
import math

import numpy as np
import pytest

from stability_checks import (amplitude_mm_for, assert_sane_dynamics,
                              fitted_slope, scene_with, still_table_energy)

from tengfield.dynamics import simulate
from tengfield.scene import G

STIFFNESSES = [1e6, 1e8, 1e10, 1e12]
DROP_HEIGHT = 1e-3


def dropped(model, stiffness=1e5, duration=0.06):
    """Ball dropped from 1 mm on a still table, e = 0.5 (chatter, then rest)."""
    return scene_with(excitation={"amplitude_mm": 0.0},
                      initial={"gap_mm": DROP_HEIGHT * 1e3},
                      contact={"model": model, "restitution": 0.5,
                               "stiffness_N_per_m": stiffness},
                      run={"duration_s": duration, "settle_periods": 0,
                           "sample_rate_hz": 1e5})


@pytest.fixture(scope="module")
def impact_reference():
    return simulate(dropped("impact"))


@pytest.fixture(scope="module")
def soft_runs():
    return {k: simulate(dropped("soft", k)) for k in STIFFNESSES}


@pytest.mark.parametrize("stiffness", STIFFNESSES)
def test_stiff_contact_is_bounded_finite_and_dissipative(soft_runs, stiffness):
    res = soft_runs[stiffness]
    scene = dropped("soft", stiffness)
    mass = scene.device.ball_mass
    omega_c = math.sqrt(stiffness / mass)
    impact_speed = math.sqrt(2 * G * DROP_HEIGHT)
    penetration = impact_speed / omega_c + G / omega_c**2
    assert_sane_dynamics(res, max_events=200, penetration=penetration)
    # mechanical energy per unit mass: gravity + spring (z < 0); the dashpot only takes
    t = np.linspace(0.0, scene.run.duration, 400001)
    z, v, _ = res.sample(t)
    energy = still_table_energy(z, v) + 0.5 * omega_c**2 * np.minimum(z, 0.0) ** 2
    assert np.max(np.diff(energy)) <= 1e-7 * energy[0]
    # the chatter ends in resting contact at the static penetration m g / k
    assert res.gap[-1] == pytest.approx(-G / omega_c**2, rel=1e-3, abs=1e-15)
    assert len(res.impacts) < 40


def test_stiff_contact_converges_to_the_impact_map(soft_runs, impact_reference):
    """max |z_soft - z_impact| over the run ~ k^(-1/2) (error ∝ contact time)."""
    errors = np.array([np.max(np.abs(soft_runs[k].gap - impact_reference.gap))
                       for k in STIFFNESSES])
    assert np.all(np.diff(errors) < 0), errors
    assert fitted_slope(STIFFNESSES, errors) == pytest.approx(-0.5, abs=0.05), errors
    assert errors[-1] < 1e-8


def test_stiff_contact_on_the_vibrating_table():
    """k = 1e12 N/m on the default drive (Γ = 2.4 at 20 Hz): bounded, finite, and the
    contacts agree with the impact map (same plates, entry times within 1e-5 s)."""
    drive = {"amplitude_mm": amplitude_mm_for(2.4, 20.0)}
    run = {"duration_s": 0.2, "settle_periods": 1, "sample_rate_hz": 2e4}
    soft = simulate(scene_with(excitation=drive, run=run,
                               contact={"model": "soft", "stiffness_N_per_m": 1e12}))
    hard = simulate(scene_with(excitation=drive, run=run))
    omega_c = math.sqrt(1e12 / scene_with().device.ball_mass)
    assert_sane_dynamics(soft, max_events=4 * 10_000, penetration=1.0 / omega_c)
    first = hard.impacts.time[:5]
    assert soft.impacts.time[:5] == pytest.approx(first, abs=1e-5)
    assert np.array_equal(soft.impacts.plate[:5], hard.impacts.plate[:5])
