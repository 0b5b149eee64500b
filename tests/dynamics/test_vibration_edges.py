"""Edge cases of the random excitation (QA): narrow bands keep their rms, bands and
components far apart are refused at load instead of exhausting memory."""
import math

import numpy as np
import pytest

from tengfield.dynamics.vibration import band_psd, tabulated_psd, vibration_table
from tengfield.errors import SceneError
from tengfield.scene import parse_scene


@pytest.mark.slow
@pytest.mark.parametrize("band", [(100.0, 102.0), (100.5, 102.0), (300.0, 301.0)])
def test_a_band_narrower_than_its_lowest_frequency_keeps_its_rms(band):
    """A 1-2 Hz wide band at 100-300 Hz was synthesised on a grid of f1/32 (3-9 Hz)
    spacing: no grid line fell inside it and the table stood still (rms 0 for a
    requested 20 m/s^2). Over 5 seeds of 40 s (B T >= 40 per seed: the mean square's
    relative standard error is <= 1/sqrt(200) = 0.07 over all) the mean square is
    the requested one within 25 %."""
    psd = band_psd(band, 20.0)
    duration, rate = 40.0, 4.0 * band[1]
    t = np.arange(int(duration * rate)) / rate
    ms = [np.mean(vibration_table(duration=duration, seed=s, psd=psd).evaluate(t)[2] ** 2)
          for s in range(5)]
    assert np.mean(ms) / 400.0 == pytest.approx(1.0, abs=0.25)


@pytest.mark.slow
def test_a_narrow_tabulated_psd_keeps_its_rms():
    psd = tabulated_psd([200.0, 201.0, 202.0], [1.0, 4.0, 1.0]).scaled(10.0)
    duration, rate = 40.0, 1000.0
    t = np.arange(int(duration * rate)) / rate
    ms = [np.mean(vibration_table(duration=duration, seed=s, psd=psd).evaluate(t)[2] ** 2)
          for s in range(5)]
    assert np.mean(ms) / 100.0 == pytest.approx(1.0, abs=0.25)


SHORT = "\n[run]\nduration_s = 0.5\nsettle_periods = 1\nsample_rate_hz = 4000.0\n"


@pytest.mark.parametrize("excitation, message", [
    # lower edge 1e-3 Hz: blocks of 32 / 1e-3 s at 32 x 200 Hz = 2e8 samples (1.6 GB
    # per array: it ran out of memory after the scene was accepted)
    ('kind = "random"\nband_hz = [0.001, 200.0]\nrms_acceleration_m_per_s2 = 1.0\n',
     r"band_hz = \[0.001, 200\]: the noise is synthesised in blocks .* lower edge \(0.001 Hz\)"
     r".*allowed <= 2e\+07"),
    # a 1e-7 Hz wide band: blocks of 32 / 1e-7 s
    ('kind = "random"\nband_hz = [100.0, 100.0000001]\nrms_acceleration_m_per_s2 = 1.0\n',
     r"band_hz = \[100, 100\]: .*width"),
    # a component at 1e-3 Hz beside one at 100 Hz: the record spans one period of the
    # lowest after the run (1000 s) at 3200 samples/s
    ('kind = "harmonics"\nfrequency_hz = [0.001, 100.0]\namplitude_mm = [0.1, 0.1]\n',
     r"frequency_hz = \[0.001, 100\]: the synthesised record .*3.2e\+06 samples: "
     r"allowed < 2e\+06"),
])
def test_records_too_large_for_memory_are_refused_at_load(excitation, message):
    extra = "[run]\nduration_s = 0.5\nsettle_periods = 0\nsample_rate_hz = 4000.0\n"
    with pytest.raises(SceneError, match=message):
        parse_scene("[excitation]\n" + excitation + extra)


def test_a_tabulated_psd_far_below_its_top_is_refused_at_load(tmp_path):
    (tmp_path / "psd.csv").write_text("frequency_hz,psd_g2_per_hz\n0.001,0.01\n200,0.01\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "random"\npsd_file = "psd.csv"\n'
                                     + SHORT)
    from tengfield.scene import load_scene
    with pytest.raises(SceneError, match=r"psd_file = 'psd.csv': the noise is synthesised"):
        load_scene(tmp_path / "s.toml")


def test_the_load_check_counts_the_blocks_the_synthesis_makes():
    """The limit's block size is the one noise_signal synthesises (a band just inside it
    is accepted and its block is what the check computed)."""
    from tengfield.dynamics.vibration import noise_block_samples, record_grid
    from tengfield.scene.limits import MAX_NOISE_BLOCK_SAMPLES
    scene = parse_scene('[excitation]\nkind = "random"\nband_hz = [0.02, 200.0]\n'
                        'rms_acceleration_m_per_s2 = 1.0\n' + SHORT.replace("settle_periods = 1",
                                                                          "settle_periods = 0"))
    psd = band_psd(scene.excitation.band, 1.0)
    _, dt = record_grid(0.5, 200.0, 0.02)
    block = noise_block_samples(psd, dt)
    assert block == 2 * math.ceil(16 * 32 * 200.0 / 0.02)
    assert block <= MAX_NOISE_BLOCK_SAMPLES


@pytest.mark.parametrize("value", [-1, 2**32])
def test_a_seed_out_of_range_names_the_exact_bounds(value):
    """The message gave 'allowed [0, 4.29497e+09]': the largest seed rounded (4294967295
    is allowed, 4294970000 is not)."""
    with pytest.raises(SceneError, match=rf"\[excitation\] seed = {value} is out of range: "
                                         r"allowed \[0, 4294967295\]"):
        parse_scene('[excitation]\nkind = "random"\nband_hz = [10.0, 200.0]\n'
                    f'rms_acceleration_m_per_s2 = 1.0\nseed = {value}\n' + SHORT)


def test_the_largest_seed_is_accepted_and_ensembles_wrap_around():
    from tengfield.ensemble import realisation_seeds
    scene = parse_scene('[excitation]\nkind = "random"\nband_hz = [10.0, 200.0]\n'
                        'rms_acceleration_m_per_s2 = 1.0\nseed = 4294967295\n' + SHORT)
    assert realisation_seeds(scene.excitation.seed, 3) == [4294967295, 0, 1]


@pytest.mark.parametrize("excitation, message", [
    ('kind = "random"\nband_hz = [0.0, 10.0]\nrms_acceleration_m_per_s2 = 1.0\n',
     r"band_hz = \[0.0, 10.0\]: entry 1 = 0.0 is out of range: allowed \(0, 1e\+06\]"),
    ('kind = "harmonics"\nfrequency_hz = [10.0, -1.0]\namplitude_mm = [1.0, 1.0]\n',
     r"frequency_hz = \[10.0, -1.0\]: entry 2 = -1.0 is out of range"),
    ('kind = "harmonics"\nfrequency_hz = [10.0, 20.0]\namplitude_mm = [1.0, "x"]\n',
     r"amplitude_mm = \[1.0, 'x'\]: entry 2 = 'x': expected a number"),
])
def test_a_bad_list_entry_shows_the_list_and_its_position(excitation, message):
    """A bad entry was reported as if it were the key's value ('band_hz = 0.0 is out of
    range'), without the list the user wrote or which entry it was."""
    with pytest.raises(SceneError, match=message):
        parse_scene("[excitation]\n" + excitation + SHORT)


@pytest.mark.parametrize("excitation, message", [
    # harmonics with a noise level but no spectrum: the noise was silently left out
    ('kind = "harmonics"\nfrequency_hz = [20.0, 40.0]\namplitude_mm = [1.0, 0.1]\n'
     'rms_acceleration_m_per_s2 = 3.0\n',
     r"rms_acceleration_m_per_s2 = 3 needs band_hz = \[f1, f2\] or psd_file"),
    # a sine with a noise level: silently a pure sine
    ('kind = "sine"\nrms_acceleration_m_per_s2 = 3.0\n',
     r"rms_acceleration_m_per_s2 = 3 needs kind = 'random' or 'harmonics' \(kind = 'sine'\)"),
])
def test_a_noise_level_without_noise_is_refused(excitation, message):
    with pytest.raises(SceneError, match=message):
        parse_scene("[excitation]\n" + excitation + SHORT)


def test_the_mean_square_of_a_table_is_the_exact_log_log_integral():
    """A segment with a zero end is zero everywhere in log-log interpolation: the mean
    square is the closed-form integral of the other segments (power laws), not a
    trapezoid sum that also counted a sliver next to every isolated non-zero row."""
    psd = tabulated_psd([10.0, 20.0, 100.0, 200.0, 400.0], [1.0, 0.0, 1.0, 1.0, 4.0])
    # [100, 200]: 1 -> 100; [200, 400]: S = (f / 200)^2 -> 200 (2^3 - 1) / 3
    assert psd.mean_square() == pytest.approx(100.0 + 200.0 * 7.0 / 3.0, rel=1e-12)
    # S ~ 1/f (exponent -1): the logarithm
    assert tabulated_psd([10.0, 100.0], [1.0, 0.1]).mean_square() == pytest.approx(
        10.0 * math.log(10.0), rel=1e-12)


def test_a_table_whose_power_is_one_isolated_row_is_refused(tmp_path):
    """frequency_hz,psd = (10, 0.01), (20, 0), (200, 0): log-log interpolation gives no
    power anywhere, but the trapezoid mean square counted a sliver at 10 Hz; rescaled to
    rms_acceleration_m_per_s2 = 20 the table acceleration's rms came out 166 m/s^2."""
    (tmp_path / "psd.csv").write_text("frequency_hz,psd_g2_per_hz\n10,0.01\n20,0\n200,0\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "random"\npsd_file = "psd.csv"\n'
                                     'rms_acceleration_m_per_s2 = 20.0\n' + SHORT)
    from tengfield.scene import load_scene
    with pytest.raises(SceneError, match=r"psd_file = 'psd.csv' holds no power: .*two "
                                         r"neighbouring rows"):
        load_scene(tmp_path / "s.toml")


def test_a_psd_without_power_is_not_scaled():
    from tengfield.errors import DynamicsError
    with pytest.raises(DynamicsError, match="without power"):
        tabulated_psd([10.0, 20.0, 30.0], [1.0, 0.0, 0.0]).scaled(3.0)
