"""Physics of the event-driven impact map against analytic solutions."""
import math

import numpy as np
import pytest

from tengfield.dynamics import _kernel as K
from tengfield.dynamics import simulate
from tengfield.scene import G, default_scene

from .conftest import run_sine


def test_gamma_below_one_stays_at_rest():
    # Gamma = A w^2 / g = 0.4: the plate never accelerates down faster than g
    scene = default_scene().with_values(excitation={"amplitude_mm": 1.0, "frequency_hz": 10.0},
                                        run={"duration_s": 2.0})
    res = simulate(scene)
    assert len(res.impacts) == 0
    assert np.all(res.gap == 0.0) and np.all(res.gap_velocity == 0.0)
    assert res.regime.name == "rest"


@pytest.mark.parametrize("amplitude, frequency", [(4.1e-3, 10.0), (1.5e-3, 20.0), (0.5e-3, 45.0)])
def test_liftoff_phase_and_launch_velocity_eq10(amplitude, frequency):
    w = 2 * math.pi * frequency
    gamma = amplitude * w**2 / G
    traj, _, _ = run_sine(amplitude, frequency, periods=0.9)
    # starts stuck on the lower plate, lifts off when y'' falls through -g
    assert traj.seg_mode[0] == K.STUCK_LOWER
    t_lift = traj.seg_t[1]
    assert t_lift == pytest.approx(math.asin(1.0 / gamma) / w, rel=1e-13)
    launch = traj.seg_yd[1]                       # ball moves with the table at lift-off
    eq10 = math.sqrt(amplitude**2 * w**4 - G**2) / w
    assert launch == pytest.approx(eq10, rel=1e-12)
    assert traj.seg_v[1] == 0.0                   # zero relative velocity at lift-off
    z, _, _ = traj(np.array([t_lift + 1e-4]))
    assert z[0] > 0.0
    if frequency == 10.0:                         # the paper's critical-contact example
        assert eq10 == pytest.approx(0.205, abs=5e-4)


def test_elastic_still_table_conserves_energy():
    # e = 1, no table motion, impacts at both plates
    traj, imp, _ = run_sine(0.0, 10.0, restitution=1.0, stroke=3e-3, gap0=1e-3,
                            velocity0=0.45, periods=50)
    assert np.count_nonzero(imp[1] == 1) > 20 and np.count_nonzero(imp[1] == 0) > 20
    t = np.linspace(0.0, 5.0, 20001)
    z, v, _ = traj(t)
    energy = 0.5 * v**2 + G * z
    e0 = 0.5 * 0.45**2 + G * 1e-3
    assert np.max(np.abs(energy - e0)) / e0 < 1e-12
    np.testing.assert_allclose(imp[2], imp[3], rtol=1e-14)


def test_chatter_on_still_table_ends_at_accumulation_point():
    e = 0.5
    traj, imp, _ = run_sine(0.0, 20.0, restitution=e, stroke=5e-3, gap0=1e-3, periods=20)
    t1, v1 = imp[0][0], imp[3][0]
    t_inf = t1 + 2 * v1 / (G * (1 - e))
    stuck = np.flatnonzero(traj.seg_mode == K.STUCK_LOWER)
    assert stuck.size == 1
    assert traj.seg_t[stuck[0]] == pytest.approx(t_inf, rel=1e-12)
    assert len(imp[0]) > 5                      # several explicit bounces before the collapse
    z, v, _ = traj(np.linspace(t_inf, 1.0, 100))
    assert np.all(z == 0.0) and np.all(v == 0.0)


@pytest.mark.parametrize("e, gamma", [(0.5, 3.0), (0.8, 1.2)])
def test_period_one_orbit_reproduced(e, gamma):
    # Gamma cos(phi) = pi (1 - e) / (1 + e): one impact per period, flight time T
    f = 20.0
    w = 2 * math.pi * f
    period = 1 / f
    amplitude = gamma * G / w**2
    phi = math.acos(math.pi * (1 - e) / ((1 + e) * gamma))
    table_velocity = amplitude * w * math.cos(phi)
    take_off = G * period / 2                    # absolute ball velocity after impact
    traj, imp, _ = run_sine(amplitude, f, restitution=e, stroke=1.0, phase=phi,
                            velocity0=take_off - table_velocity, periods=8.5)
    k = np.arange(1, 9)
    np.testing.assert_allclose(imp[0], k * period, rtol=0, atol=1e-12)
    np.testing.assert_allclose(imp[2], G * period / 2 + table_velocity, rtol=1e-9)
    np.testing.assert_allclose(imp[3], take_off - table_velocity, rtol=1e-9)


def test_upper_plate_sticking_window():
    # pressed to the upper plate while y'' <= -g, released when y'' rises through -g
    f, amplitude = 30.0, 3e-3
    w = 2 * math.pi * f
    gamma = amplitude * w**2 / G
    t0 = (math.pi / 2) / w                       # y'' = -A w^2 < -g
    traj, _, _ = run_sine(amplitude, f, t_start=t0, gap0=3e-3, velocity0=0.0, periods=0.4)
    assert traj.seg_mode[0] == K.STUCK_UPPER
    t_release = (math.pi - math.asin(1 / gamma)) / w
    assert traj.seg_t[1] == pytest.approx(t_release, rel=1e-13)
    z, _, _ = traj(np.linspace(t0, t_release, 50, endpoint=False))
    assert np.all(z == 3e-3)
    z_after, v_after, _ = traj(np.array([t_release + 1e-4]))
    assert z_after[0] < 3e-3 and v_after[0] < 0.0


def test_event_bound_raises_clear_error():
    from tengfield.dynamics.impact import Restitution, integrate
    from tengfield.dynamics.table import sine_table
    from tengfield.errors import DynamicsError
    # power-law restitution with e -> 1 at low speed: endless tiny bounces at the fixed point
    with pytest.raises(DynamicsError, match="events per excitation period"):
        integrate(sine_table(0.0, 2 * math.pi * 20, 0.0), 3e-3,
                  Restitution(0.6, True, 0.1, 0.2), t_start=0.0, t_end=1.0, gap0=1e-3,
                  period=0.05, max_events_per_period=10)


def test_power_law_restitution_applied_per_impact():
    from tengfield.dynamics.impact import Restitution, integrate
    from tengfield.dynamics.table import sine_table
    rest = Restitution(0.6, True, 0.1, 0.15)
    _, imp, _ = integrate(sine_table(0.0, 2 * math.pi * 20, 0.0), 3e-3, rest, t_start=0.0,
                          t_end=0.5, gap0=2e-3, period=0.05)
    expected = np.minimum(1.0, 0.6 * (imp[2] / 0.1) ** -0.15)
    assert len(imp[0]) > 10
    np.testing.assert_allclose(imp[3] / imp[2], expected, rtol=1e-13)


def test_sample_is_exact_free_fall_and_matches_the_sampled_arrays():
    scene = default_scene().with_values(
        excitation={"amplitude_mm": 0.0}, initial={"gap_mm": 2.0},
        run={"duration_s": 1.0, "settle_periods": 1, "sample_rate_hz": 1000.0})
    res = simulate(scene)
    t_hit = math.sqrt(2 * 2e-3 / G)
    assert res.impacts.time[0] == pytest.approx(t_hit, rel=1e-13)
    t = np.linspace(0.0, t_hit, 7)[:-1]
    z, v, y = res.sample(t)
    np.testing.assert_allclose(z, 2e-3 - 0.5 * G * t**2, rtol=0, atol=1e-17)
    np.testing.assert_allclose(v, -G * t, rtol=0, atol=1e-15)
    assert np.all(y == 0.0)
    z_all, v_all, y_all = res.sample(res.t)
    np.testing.assert_array_equal(z_all, res.gap)
    np.testing.assert_array_equal(v_all, res.gap_velocity)


def test_chatter_on_moving_table_ends_near_first_order_accumulation_point():
    # slowly moving table (Gamma = 0.08): |a| = g + y'' changes little during the chatter
    e, f, amplitude = 0.5, 2.0, 5e-3
    w = 2 * math.pi * f
    traj, imp, _ = run_sine(amplitude, f, restitution=e, stroke=5e-3, gap0=0.2e-3, periods=0.4)
    t1, v1 = imp[0][0], imp[3][0]
    a1 = G - amplitude * w**2 * math.sin(w * t1)            # g + y''(t1) > 0 presses down
    zeno = 2 * v1 / (a1 * (1 - e))
    stuck = np.flatnonzero(traj.seg_mode == K.STUCK_LOWER)
    t_stick = traj.seg_t[stuck[0]]
    jerk = amplitude * w**3
    # first order in the change of |a| over the sequence: error <~ jerk zeno^2 / |a|
    assert abs(t_stick - (t1 + zeno)) <= 2 * jerk * zeno**2 / a1
    assert abs(t_stick - (t1 + zeno)) > 0.0                # the table motion does matter
