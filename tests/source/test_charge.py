"""Contact electrification of the ball (issue #52): Hertz's contact area, the condenser
law's closed forms, leakage's steady state, the cap, conservation."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import solve_ivp

from tengfield.source.charge import (COPPER_MODULUS_PA, COPPER_POISSON, PTFE_MODULUS_PA,
                                     PTFE_POISSON, ContactCharging, charge_history,
                                     effective_modulus, hertz_contact_area, hertz_indentation,
                                     leaky_steady_charge, periodic_charge)

MASS = 0.395e-3     # the paper's 7 mm PTFE ball [kg]
RADIUS = 3.5e-3     # [m]
AREA = math.pi * (2 * RADIUS) ** 2
E_STAR = effective_modulus(PTFE_MODULUS_PA, PTFE_POISSON, COPPER_MODULUS_PA, COPPER_POISSON)


@pytest.mark.parametrize("speed", [0.05, 0.3, 1.0])
def test_hertz_indentation_is_where_the_contact_force_stops_the_ball(speed):
    """m x'' = -(4/3) E* sqrt(R) x^(3/2), integrated: the turning point is delta_max."""
    k = 4.0 / 3.0 * E_STAR * math.sqrt(RADIUS) / MASS

    def rhs(_, y):
        return [y[1], -k * max(y[0], 0.0) ** 1.5]

    turn = lambda _, y: y[1]   # noqa: E731
    turn.terminal, turn.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 1e-2), [0.0, speed], events=turn, rtol=1e-11, atol=1e-16)
    assert sol.t_events[0].size == 1
    np.testing.assert_allclose(hertz_indentation(MASS, RADIUS, speed, E_STAR),
                               sol.y_events[0][0][0], rtol=1e-7)


def test_hertz_area_of_the_papers_ball_and_its_four_fifths_power():
    """DESIGN §8: at 0.3 m/s delta ~ 17 µm, S ~ 1.9e-7 m^2 ~ 1.2e-3 A; S ~ v^(4/5)."""
    delta = hertz_indentation(MASS, RADIUS, 0.3, E_STAR)
    area = hertz_contact_area(MASS, RADIUS, 0.3, E_STAR)
    assert 16e-6 < delta < 18e-6
    assert 1.8e-7 < area < 2.0e-7
    assert area == pytest.approx(math.pi * RADIUS * delta)
    ratio = hertz_contact_area(MASS, RADIUS, 0.6, E_STAR) / area
    assert ratio == pytest.approx(2 ** 0.8, rel=1e-12)


def test_equal_contacts_follow_the_closed_form():
    law = ContactCharging(equilibrium=-113e-6, efficiency=0.7, ball_area=AREA)
    s = 1.9e-7
    history = charge_history(law, np.arange(1, 2001) / 40.0, np.full(2000, s))
    n = np.arange(1, 2001)
    np.testing.assert_allclose(history.after,
                               periodic_charge(n, law.equilibrium * AREA, 0.7 * s / AREA),
                               rtol=1e-11)


def test_a_ball_at_equilibrium_stays_there_without_leakage_or_cap():
    law = ContactCharging(equilibrium=-8e-6, efficiency=1.0, ball_area=AREA, initial=-8e-6)
    history = charge_history(law, np.sort(np.random.default_rng(1).uniform(0, 5, 300)),
                             np.random.default_rng(2).uniform(1e-8, 1e-6, 300))
    np.testing.assert_allclose(history.after, -8e-6 * AREA, rtol=1e-14)
    np.testing.assert_allclose(history.at(np.linspace(0, 6, 50)), -8e-6 * AREA, rtol=1e-14)


@pytest.mark.parametrize("tau", [5.0, 60.0, 600.0])
def test_the_leaky_steady_charge(tau):
    """Equal contacts at rate 1/T with leakage tau: exactly k q_eq / (1 - (1 - k) e^-T/tau),
    and q_eq r / (r + 1/tau), r = k/T, when k and T/tau are small."""
    period, s = 1 / 40.0, 1.9e-7
    k = s / AREA
    law = ContactCharging(equilibrium=-113e-6, efficiency=1.0, ball_area=AREA, leakage_time=tau)
    n = int(40 * 20 * max(tau, 30.0))
    history = charge_history(law, period * np.arange(1, n + 1), np.full(n, s))
    q_eq = law.equilibrium * AREA
    exact = leaky_steady_charge(q_eq, k, period, tau)
    assert history.after[-1] == pytest.approx(exact, rel=1e-9)
    r = k / period
    assert exact == pytest.approx(q_eq * r / (r + 1 / tau), rel=k + period / tau)   # O(k, T/tau)


def test_doubling_the_efficiency_halves_the_rise_time_where_the_patch_is_small():
    times = np.arange(1, 200001) / 40.0
    s = np.full(times.size, 1e-8)    # S/A = 6.5e-5
    rise = [charge_history(ContactCharging(-113e-6, eta, AREA), times, s)
            .rise_time(0.9, steady=-113e-6 * AREA) for eta in (0.25, 0.5)]
    assert rise[1] == pytest.approx(rise[0] / 2, rel=2e-3)


def test_leakage_between_contacts_decays_exponentially():
    law = ContactCharging(-50e-6, 1.0, AREA, initial=-50e-6, leakage_time=2.0)
    history = charge_history(law, np.array([10.0]), np.array([1e-9]))
    q0 = -50e-6 * AREA
    assert history.at(1.0) == pytest.approx(q0 * math.exp(-0.5), rel=1e-13)
    assert history.before[0] == pytest.approx(q0 * math.exp(-5.0), rel=1e-13)


@settings(max_examples=60, deadline=None)
@given(eq=st.floats(-200e-6, 200e-6), eta=st.floats(1e-3, 1.0), start=st.floats(-300e-6, 300e-6),
       cap=st.floats(5e-6, 100e-6), tau=st.sampled_from([0.0, 0.5, 50.0]),
       seed=st.integers(0, 2 ** 31 - 1))
def test_the_cap_holds_and_every_gain_comes_from_an_electrode(eq, eta, start, cap, tau, seed):
    """|q| <= the cap at every contact and separation; the ball's gains add up to its
    change over the contacts less what leaked (the electrodes gave exactly that)."""
    rng = np.random.default_rng(seed)
    times = np.sort(rng.uniform(0, 10, 50))
    law = ContactCharging(eq, eta, AREA, initial=start, leakage_time=tau, cap=cap)
    history = charge_history(law, times, rng.uniform(1e-9, 5e-6, 50))
    bound = cap * AREA * (1 + 1e-12)
    assert np.all(np.abs(history.after) <= bound) and np.all(np.abs(history.before) <= bound)
    assert np.all(np.abs(history.at(rng.uniform(0, 12, 40))) <= bound)
    leaked = np.concatenate(([history.start], history.after[:-1])) - history.before
    assert math.fsum(history.gains) == pytest.approx(
        history.after[-1] - history.start + math.fsum(leaked), abs=1e-12 * bound)
    if tau == 0.0 and abs(start) <= cap and abs(eq) <= cap:
        # toward the equilibrium, never past it
        distance = np.abs(history.after - eq * AREA)
        assert np.all(np.diff(distance) <= 1e-15 * AREA)


@pytest.mark.parametrize("kwargs, word", [({"efficiency": 0.0}, "efficiency"),
                                          ({"efficiency": 1.5}, "efficiency"),
                                          ({"leakage_time": -1.0}, "leakage_time"),
                                          ({"cap": 0.0}, "cap"), ({"ball_area": 0.0}, "ball_area")])
def test_bad_values_name_the_parameter_and_its_range(kwargs, word):
    base = dict(equilibrium=-1e-5, efficiency=0.5, ball_area=AREA)
    with pytest.raises(ValueError, match=f"{word} = .*allowed"):
        ContactCharging(**{**base, **kwargs})


def test_inside_the_shells_concave_electrodes_the_area_is_hertzs_of_the_equivalent_radius():
    """The shell's electrodes are the cavity's sphere (radius a): Hertz with R_e = R a/(a−R)
    (the 3D contact's own rule), so the area is the flat one times (a/(a−R))^(4/5) at
    every speed (1.41 for the default 20 mm cavity); the tube's plates are flat (R)."""
    from tengfield.dynamics import Impacts
    from tengfield.scene import default_scene, with_settings
    from tengfield.source.contacts import contact_modulus, contacts_of

    impacts = Impacts(np.array([0.1, 0.2, 0.3]), np.array(["lower", "upper", "lower"]),
                      np.array([0.2, 0.5, 1.0]), np.array([0.1, 0.2, 0.4]))
    tube = default_scene()
    shell = with_settings(tube, ["device.shape=spherical-shell"])
    _, flat, _ = contacts_of(tube, impacts, impacts.time)
    _, concave, upper = contacts_of(shell, impacts, impacts.time)
    device = tube.device
    np.testing.assert_allclose(flat, hertz_contact_area(device.ball_mass, device.ball_radius,
                                                        impacts.speed_before,
                                                        contact_modulus(tube)), rtol=1e-14)
    a, r = 0.5 * shell.device.cavity_diameter, shell.device.ball_radius
    np.testing.assert_allclose(concave / flat, (a / (a - r)) ** 0.8, rtol=1e-12)
    assert (a / (a - r)) ** 0.8 == pytest.approx(1.41, abs=0.005)
    assert list(upper) == [False, True, False]
