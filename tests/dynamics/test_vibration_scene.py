"""Random and harmonics excitations through scene files and the dynamics models."""
import math

import numpy as np
import pytest

from tengfield.dynamics import simulate
from tengfield.dynamics.excitation import table_from_scene
from tengfield.errors import SceneError
from tengfield.scene import parse_scene

SHORT = """
[run]
duration_s = 0.5
settle_periods = 5
sample_rate_hz = 4000.0
"""


def _scene(excitation: str, extra: str = ""):
    return parse_scene("[excitation]\n" + excitation + SHORT + extra)


def test_one_harmonic_run_equals_the_sine_run_bit_for_bit():
    sine = _scene('kind = "sine"\nfrequency_hz = 33.0\namplitude_mm = 0.75\nphase_deg = 20.0\n')
    one = _scene('kind = "harmonics"\nfrequency_hz = [33.0]\namplitude_mm = [0.75]\n'
                 'phase_deg = [20.0]\n')
    a, b = simulate(sine), simulate(one)
    assert np.array_equal(a.gap, b.gap) and np.array_equal(a.impacts.time, b.impacts.time)
    # the same window, the same largest gap, and the same regime: a harmonics drive
    # without noise repeats each period, so it is checked for settling as the sine is
    assert a.regime.max_gap == b.regime.max_gap
    assert (b.regime.name, b.regime.period, b.regime.settled_by_s, b.regime.checked_to_s) \
        == (a.regime.name, a.regime.period, a.regime.settled_by_s, a.regime.checked_to_s)


def test_whole_harmonics_are_checked_for_settling_and_others_are_not():
    from tengfield.dynamics.excitation import repeats_each_period

    whole = _scene('kind = "harmonics"\nfrequency_hz = [20.0, 40.0, 60.0]\n'
                   'amplitude_mm = [0.6, 0.2, 0.05]\n')
    beating = _scene('kind = "harmonics"\nfrequency_hz = [20.0, 28.2842712]\n'
                     'amplitude_mm = [0.6, 0.2]\n')
    noisy = _scene('kind = "harmonics"\nfrequency_hz = [20.0, 40.0]\namplitude_mm = [0.6, 0.2]\n'
                   'band_hz = [10.0, 200.0]\nrms_acceleration_m_per_s2 = 1.0\n')
    assert repeats_each_period(whole)
    assert not repeats_each_period(beating) and not repeats_each_period(noisy)
    checked = simulate(whole).regime
    assert checked.checked_to_s >= 0.5
    # settled: the longer run it was checked against has the same regime
    if checked.settled_by_s is not None:
        longer = simulate(whole.with_values(run={"duration_s": checked.checked_to_s}))
        assert (longer.regime.name, longer.regime.period) == (checked.name, checked.period)
    for scene in (beating, noisy):      # the window's own regime, never "not-settled"
        regime = simulate(scene).regime
        assert regime.name != "not-settled" and not regime.checked_to_s   # unchecked: 0


def test_acceleration_amplitudes_are_displacements_over_omega_squared():
    scene = _scene('kind = "harmonics"\nfrequency_hz = [20.0, 40.0]\n'
                   'acceleration_m_per_s2 = [10.0, 5.0]\n')
    amps = [c[1] for c in scene.excitation.harmonics]
    assert amps == pytest.approx([10.0 / (2 * math.pi * 20) ** 2, 5.0 / (2 * math.pi * 40) ** 2])
    # the fundamental sets the analysis period
    assert scene.excitation.frequency == 20.0


def test_same_seed_same_run_other_seed_other():
    text = 'kind = "random"\nband_hz = [10.0, 200.0]\nrms_acceleration_m_per_s2 = 40.0\nseed = {}\n'
    a = simulate(_scene(text.format(1)))
    b = simulate(_scene(text.format(1)))
    c = simulate(_scene(text.format(2)))
    assert np.array_equal(a.gap, b.gap) and np.array_equal(a.impacts.time, b.impacts.time)
    assert not np.array_equal(a.gap, c.gap)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["impact", "soft"])
def test_random_table_rms_and_ball_stays_between_plates(model):
    scene = _scene('kind = "random"\nband_hz = [10.0, 200.0]\nrms_acceleration_m_per_s2 = 40.0\n',
                   f'[contact]\nmodel = "{model}"\n')
    result = simulate(scene)
    _, _, acc = table_from_scene(scene).evaluate(np.arange(0.0, 0.5, 1e-4))
    # 0.5 s of a 190 Hz band: relative sampling error of the mean square ~ 1/sqrt(95)
    assert np.sqrt(np.mean(acc**2)) == pytest.approx(40.0, rel=0.4)
    stroke = scene.device.stroke
    # soft contact: the plates yield by a penetration far below the stroke
    tol = 0.05 * stroke if model == "soft" else 1e-12
    assert np.all(result.gap >= -tol) and np.all(result.gap <= stroke + tol)
    assert result.impacts.time.size > 0


def test_psd_file_in_g2_per_hz(tmp_path):
    (tmp_path / "psd.csv").write_text("frequency_hz,psd_g2_per_hz\n10,0.01\n100,0.01\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "random"\npsd_file = "psd.csv"\n' + SHORT)
    from tengfield.scene import load_scene
    scene = load_scene(tmp_path / "s.toml")
    assert scene.excitation.psd_values == pytest.approx([0.01 * 9.80665**2] * 2)
    rescaled = scene.with_values(excitation={"rms_acceleration_m_per_s2": 3.0})
    from tengfield.dynamics.vibration import scene_psd
    assert scene_psd(rescaled.excitation).mean_square() == pytest.approx(9.0, rel=1e-6)


@pytest.mark.parametrize("text, message", [
    ('kind = "random"\n', "needs band_hz"),
    ('kind = "random"\nband_hz = [10.0]\nrms_acceleration_m_per_s2 = 1.0\n', "f1 < f2"),
    ('kind = "random"\nband_hz = [100.0, 10.0]\nrms_acceleration_m_per_s2 = 1.0\n', "f1 < f2"),
    ('kind = "random"\nband_hz = [10.0, 100.0]\n', "rms_acceleration_m_per_s2 > 0"),
    ('kind = "random"\nband_hz = [10.0, "x"]\nrms_acceleration_m_per_s2 = 1.0\n', "expected a number"),
    ('kind = "random"\nband_hz = [10.0, 1e300]\nrms_acceleration_m_per_s2 = 1.0\n', "out of range"),
    ('kind = "harmonics"\namplitude_mm = [1.0]\n', "needs frequency_hz"),
    ('kind = "harmonics"\nfrequency_hz = [10.0, 20.0]\namplitude_mm = [1.0]\n', "1 entries but frequency_hz has 2"),
    ('kind = "harmonics"\nfrequency_hz = [10.0]\n', "exactly one of"),
    ('kind = "harmonics"\nfrequency_hz = [10.0, -1.0]\namplitude_mm = [1.0, 1.0]\n', "out of range"),
    ('kind = "sine"\nfrequency_hz = [10.0, 20.0]\n', "only with [excitation] kind = 'harmonics'"),
    ('kind = "sine"\nband_hz = [10.0, 20.0]\n', "needs kind = 'random'"),
    ('kind = "random"\nband_hz = [10.0, 2e5]\nrms_acceleration_m_per_s2 = 1.0\n', "record samples"),
])
def test_bad_vibration_input_is_one_clear_error(text, message):
    with pytest.raises(SceneError, match=message.replace("[", r"\[").replace("]", r"\]")):
        _scene(text)


def test_3d_model_runs_with_per_axis_noise():
    scene = _scene('kind = "random"\nband_hz = [10.0, 200.0]\nrms_acceleration_m_per_s2 = 30.0\n'
                   'rms_acceleration_x_m_per_s2 = 10.0\n', '[contact]\nmodel = "3d"\n')
    from tengfield.dynamics.motion3d.simulate import lateral_tables
    tx, ty = lateral_tables(scene)
    _, _, ax = tx.evaluate(np.arange(0.0, 0.5, 1e-4))
    assert np.sqrt(np.mean(ax**2)) == pytest.approx(10.0, rel=0.5)
    assert ty.acc_bound == 0.0        # no y noise, no y sine
    result = simulate(scene)
    assert np.all(np.isfinite(result.gap))


def test_changed_copies_keep_every_harmonic():
    """with_values (ensembles, fit, design, sweeps) rebuilds the scene from its file
    values: every component survives, and the rebuilt run is the same run."""
    scene = _scene('kind = "harmonics"\nfrequency_hz = [33.0, 66.0, 132.0]\n'
                   'amplitude_mm = [0.5, 0.05, 0.01]\nphase_deg = [0.0, 40.0, 110.0]\n'
                   'band_hz = [10.0, 300.0]\nrms_acceleration_m_per_s2 = 3.0\nseed = 1\n')
    again = scene.with_values(excitation={"seed": 1})
    assert again.excitation.harmonics == scene.excitation.harmonics
    assert len(again.excitation.harmonics) == 3
    assert scene.raw["excitation"]["frequency_hz"] == [33.0, 66.0, 132.0]
    a, b = simulate(scene), simulate(again)
    assert np.array_equal(a.gap, b.gap)


def test_a_single_number_applies_to_every_component():
    scene = _scene('kind = "harmonics"\nfrequency_hz = [20.0, 40.0]\namplitude_mm = 0.5\n'
                   'phase_deg = 30.0\n')
    assert [c[1] for c in scene.excitation.harmonics] == [0.5e-3, 0.5e-3]
    assert [c[2] for c in scene.excitation.harmonics] == pytest.approx([math.pi / 6] * 2)
