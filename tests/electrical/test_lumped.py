"""Circuit numerics: limits, energy balance, analytic steady state, N-cell scaling."""
from __future__ import annotations


import numpy as np
import pytest
from scipy.integrate import trapezoid
from hypothesis import given, settings
from hypothesis import strategies as st

from tengfield import lumped

import plate_model as fx

PERIOD = 0.05            # 20 Hz
OMEGA = 2 * np.pi / PERIOD
C_MEAN = 1.0e-12         # 1 pF, the order of the device's C_T


def smooth_drive(times):
    """Q_SC, I_SC, C_T, dC_T/dt of a smooth prescribed motion (analytic)."""
    t = np.asarray(times)
    q = 1e-10 * (1 - np.cos(OMEGA * t))
    i = 1e-10 * OMEGA * np.sin(OMEGA * t)
    c = C_MEAN * (1 + 0.5 * np.sin(OMEGA * t) ** 2)
    dc = C_MEAN * 0.5 * 2 * np.sin(OMEGA * t) * np.cos(OMEGA * t) * OMEGA
    return q, i, c, dc


def test_short_and_open_closed_forms():
    q = np.array([0.0, 1e-10, 2e-10])
    c = np.array([1e-12, 2e-12, 4e-12])
    np.testing.assert_allclose(lumped.open_circuit_voltage(q, c), [0, 50, 50])
    np.testing.assert_allclose(lumped.open_circuit_voltage(q, c, 1e-12), [0, 100 / 3, 40])
    np.testing.assert_allclose(lumped.short_circuit_current([2.0, -1.0], [0.5, 3.0]), [1.0, -3.0])


def test_small_load_reproduces_short_circuit():
    t = np.linspace(0, 2 * PERIOD, 4001)
    q, i, c, _ = smooth_drive(t)
    res = lumped.load_response(t, q, i, c, load_ohm=1.0)
    # after the initial transient (R C = 1 ps) the load current is I_SC
    np.testing.assert_allclose(res.current[10:], i[10:], rtol=0, atol=1e-9 * np.abs(i).max())
    np.testing.assert_allclose(res.voltage[10:], 1.0 * i[10:], atol=1e-9 * np.abs(i).max())


def test_large_load_reproduces_open_circuit():
    t = np.linspace(0, 2 * PERIOD, 4001)
    q, i, c, _ = smooth_drive(t)
    cp = 3e-13
    res = lumped.load_response(t, q, i, c, load_ohm=1e15, parallel_capacitance=cp)
    v_open = lumped.open_circuit_voltage(q, c, cp)
    # R C = 1.3e3 s >> 0.1 s: the drift is ~ t / RC ~ 1e-4
    np.testing.assert_allclose(res.voltage, v_open, rtol=0, atol=2e-4 * np.abs(v_open).max())


def test_loads_from_1_ohm_to_1_petaohm_stay_between_the_limits():
    t = np.linspace(0, 3 * PERIOD, 3001)
    q, i, c, _ = smooth_drive(t)
    v_open = np.abs(lumped.open_circuit_voltage(q, c)).max()
    amplitudes = []
    for load in np.logspace(0, 15, 16):
        res = lumped.load_response(t, q, i, c, load_ohm=load)
        assert np.all(np.isfinite(res.voltage))
        amplitudes.append(np.abs(res.voltage[t > PERIOD]).max())
        assert amplitudes[-1] <= 1.0001 * v_open
    # the voltage amplitude grows monotonically with R (a single-pole divider)
    assert np.all(np.diff(amplitudes) > 0)


@pytest.mark.parametrize("load", [3e9, 3e10, 3e11])
def test_energy_balance_with_a_load(load):
    """Work delivered by the mechanics = stored + dissipated energy (integration error)."""
    t = np.linspace(0, 3 * PERIOD, 30001)
    q, i, c, dc = smooth_drive(t)
    cp = 2e-13
    res = lumped.load_response(t, q, i, c, load_ohm=load, parallel_capacitance=cp)
    delivered = trapezoid(lumped.delivered_power(res.voltage, i, dc), t)
    dissipated = trapezoid(res.power, t)
    stored = lumped.stored_energy(res.voltage, c, cp)
    assert dissipated > 0
    assert delivered == pytest.approx(dissipated + stored[-1] - stored[0], rel=1e-6)


def test_load_integrator_converges_at_second_order():
    load = 5e10  # R C ~ period / 1000 .. period: neither limit
    reference_t = np.linspace(0, PERIOD, 2**14 + 1)
    q, i, c, _ = smooth_drive(reference_t)
    reference = lumped.load_response(reference_t, q, i, c, load)
    steps, errors = [], []
    for n in (64, 128, 256, 512):
        t = np.linspace(0, PERIOD, n + 1)
        q, i, c, _ = smooth_drive(t)
        v = lumped.load_response(t, q, i, c, load).voltage
        exact = reference.voltage[:: 2**14 // n]
        steps.append(PERIOD / n)
        errors.append(np.abs(v - exact).max())
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order == pytest.approx(2.0, abs=0.25)


@settings(max_examples=25, deadline=None)
@given(log_tau=st.floats(min_value=-9.0, max_value=3.0))
def test_constant_capacitance_matches_the_phasor_steady_state(log_tau):
    """C_T constant, Q_SC = Q0 sin ωt: V = Q0 ω R / sqrt(1 + (ωτ)^2) · cos(ωt - atan ωτ)."""
    tau = PERIOD * 10.0**log_tau
    load = tau / C_MEAN
    q0 = 1e-10
    t = np.linspace(0, PERIOD, 2001)
    q = q0 * np.sin(OMEGA * t)
    i = q0 * OMEGA * np.cos(OMEGA * t)
    c = np.full_like(t, C_MEAN)
    wt = OMEGA * tau
    lag = np.arctan(wt)
    v_steady = q0 * OMEGA * load / np.hypot(1.0, wt) * np.cos(OMEGA * t - lag)
    # start on the steady state: Q_R(0) = Q_SC(0) - C V(0)
    res = lumped.load_response(t, q, i, c, load, initial_load_charge=q[0] - C_MEAN * v_steady[0])
    scale = np.abs(v_steady).max()
    assert np.abs(res.voltage - v_steady).max() <= 2e-5 * scale


def test_cells_scale_charge_current_capacitance_not_voltage():
    scene = fx.scene_with()
    from tengfield.surrogate import precompute
    from tengfield.electrical import terminal_waveforms
    table = precompute(scene, solve=fx.plate_model_solve, solve_comm=object())
    curves = table.curves("floating", scene.device.ball_charge)
    dyn = fx.FakeDynamics(scene, duration=0.1, sample_rate=2000)
    one = terminal_waveforms(curves, dyn.gap, dyn.gap_velocity, cells=1)
    five = terminal_waveforms(curves, dyn.gap, dyn.gap_velocity, cells=5)
    np.testing.assert_allclose(five["V_oc"], one["V_oc"], rtol=1e-12)
    for key in ("Q_sc", "I_sc", "C_T"):
        np.testing.assert_allclose(five[key], 5 * one[key], rtol=1e-12)
    # N cells on R / N with N C_p: the same voltage, N times the current
    t = dyn.t
    a = lumped.load_response(t, one["Q_sc"], one["I_sc"], one["C_T"], 1e10, 1e-13)
    b = lumped.load_response(t, five["Q_sc"], five["I_sc"], five["C_T"], 2e9, 5e-13)
    np.testing.assert_allclose(b.voltage, a.voltage, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b.current, 5 * a.current, rtol=1e-9, atol=1e-21)


def test_bad_load_is_rejected():
    t = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match="load_ohm"):
        lumped.load_response(t, t, t, t + 1, load_ohm=-1.0)
