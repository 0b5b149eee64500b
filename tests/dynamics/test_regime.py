"""Regime classification: Poincare period detection and the paper's named regimes."""
import numpy as np
import pytest

from tengfield.dynamics import regime_map, simulate
from tengfield.dynamics.regime import detect_period
from tengfield.scene import G, default_scene


@pytest.mark.parametrize("p", [1, 2, 3, 5])
def test_detect_period_of_periodic_sequences(p):
    rng = np.random.default_rng(p)
    base_z, base_v = rng.uniform(0, 3e-3, p), rng.uniform(-0.3, 0.3, p)
    z, v = np.tile(base_z, 40 // p + 1)[:40], np.tile(base_v, 40 // p + 1)[:40]
    assert detect_period(z, v, 3e-3, G) == p


def test_detect_period_of_noise_is_zero():
    rng = np.random.default_rng(0)
    assert detect_period(rng.uniform(0, 3e-3, 60), rng.uniform(-0.3, 0.3, 60), 3e-3, G) == 0


def test_map_regimes_match_the_paper_examples():
    # (Hz, mm): 25/0.5 bounce (Fig. 4a), 10/4.1 critical contact (Fig. 6a),
    # 30/3 regular contact (Fig. 7), 10/1 rest (Gamma = 0.4)
    scene = default_scene()
    m = regime_map(scene, [10.0, 25.0, 30.0], [0.5e-3, 1e-3, 3e-3, 4.1e-3], jobs=1,
                   progress=False, periods=120, settle_periods=60)
    reg = {(f, round(a * 1e3, 1)): m.regime[i, j] for i, a in enumerate(m.amplitude)
           for j, f in enumerate(m.frequency)}
    assert reg[(25.0, 0.5)] == "bounce"
    assert reg[(10.0, 4.1)] == "critical-contact"
    assert reg[(30.0, 3.0)] == "regular-contact"
    assert reg[(10.0, 1.0)] == "rest" and reg[(10.0, 0.5)] == "rest"
    i, j = list(m.amplitude).index(3e-3), list(m.frequency).index(30.0)
    assert m.max_gap[i, j] == scene.device.stroke
    assert m.upper_contacts_per_period[i, j] >= 1.0
    assert len(m.records()) == 12


def test_soft_model_through_simulate():
    scene = default_scene().with_values(
        contact={"model": "soft", "stiffness_N_per_m": 1e6},
        excitation={"amplitude_mm": 3.0, "frequency_hz": 30.0},
        run={"duration_s": 0.2, "settle_periods": 2, "sample_rate_hz": 5000.0})
    res = simulate(scene)
    assert res.model == "soft"
    assert set(res.impacts.plate) == {"lower", "upper"}
    # penetration is small: at most the impact speed / sqrt(k / m)
    speed = 3e-3 * 2 * np.pi * 30 + np.sqrt(2 * G * scene.device.stroke)
    pen = speed / np.sqrt(1e6 / scene.device.ball_mass)
    assert res.gap.min() > -pen and res.gap.max() < scene.device.stroke + pen
    assert res.gap.min() < 0.0     # it does penetrate
    assert np.all(np.diff(res.impacts.time) > 0)


@pytest.mark.parametrize("p, frequency, amplitude_mm", [(1, 20.0, 1.0), (2, 50.0, 0.5),
                                                         (3, 65.0, 0.5)])
def test_period_of_an_orbit_started_on_its_own_impact_phase(p, frequency, amplitude_mm):
    """Restarted at one of its impacts, every Poincare section time t0 + kT of a
    period-p orbit is an impact instant (issue #8.3: reported as chaos before)."""
    base = default_scene().with_values(
        excitation={"frequency_hz": frequency, "amplitude_mm": amplitude_mm},
        contact={"restitution": 0.1},
        run={"duration_s": 200 / frequency, "settle_periods": 100, "sample_rate_hz": 1000.0})
    first = simulate(base)
    assert first.regime.period == p
    k = int(np.flatnonzero(first.impacts.time > first.window_start)[0])
    t_hit, v_hit = first.impacts.time[k], first.impacts.speed_before[k]
    restart = base.with_values(initial={"time_s": t_hit, "gap_mm": 0.0,
                                        "velocity_m_per_s": -v_hit})
    res = simulate(restart)
    phase = (res.impacts.time - t_hit) * frequency
    late = res.impacts.time > res.window_start
    on_section = np.abs(phase - np.round(phase)) < 1e-9
    assert np.count_nonzero(on_section & late) >= 50 // p  # impacts at the section instants
    assert res.regime.period == p
    assert res.regime.name == first.regime.name
