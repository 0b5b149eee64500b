"""Issue #53: `run` says why nothing happens and what would (below lift-off), and runs
low frequencies by extending the settle time as `sweep` does (one rule:
``sweeps.extended_duration``), saying so."""
import json
import math

import pytest

from tengfield import cli, sweeps
from tengfield.dynamics.mapping import below_liftoff, liftoff_amplitude, liftoff_frequency
from tengfield.scene import default_scene
from tengfield.scene.constants import G

SHORT = ["--set", "run.duration_s=0.3", "--set", "run.settle_periods=2",
         "--set", "run.sample_rate_hz=2000"]


def run_main(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_run_below_liftoff_says_why_and_the_liftoff_amplitude_and_frequency(tmp_path, capsys):
    out_dir = tmp_path / "out"
    code, out, err = run_main(["run", "--set", "excitation.amplitude_mm=0.3", *SHORT,
                               "-o", out_dir], capsys)
    assert code == 0, err
    a_lift = G / (2 * math.pi * 20.0) ** 2            # 0.621 mm at 20 Hz
    f_lift = math.sqrt(G / 0.3e-3) / (2 * math.pi)     # 28.8 Hz at 0.3 mm
    regime = [ln for ln in out.splitlines() if ln.startswith("regime:")]
    assert len(regime) == 1
    line = regime[0]
    assert line.startswith("regime: rest") and "the ball never lifts off" in line
    assert "A (2 pi f)^2" in line and "below g" in line
    assert f"amplitude_mm > {a_lift * 1e3:.3g} at 20 Hz" in line
    assert f"frequency_hz > {f_lift:.3g} at 0.3 mm" in line
    summary = json.loads((out_dir / "summary.json").read_text())
    block = summary["regime"]
    assert block["regime"] == "rest" and block["reason"] in line
    lift = block["liftoff"]
    assert lift["liftoff_amplitude_mm"] == pytest.approx(a_lift * 1e3, rel=1e-12)
    assert lift["liftoff_frequency_hz"] == pytest.approx(f_lift, rel=1e-12)
    assert lift["gamma"] == pytest.approx(0.3e-3 * (2 * math.pi * 20) ** 2 / G, rel=1e-12)
    assert (out_dir / "waveforms.png").is_file() and (out_dir / "trajectory.png").is_file()


def test_the_liftoff_numbers_are_the_threshold_both_ways():
    # A (2 pi f)^2 = g on the curve: each function inverts the other
    for f in (5.0, 20.0, 133.0):
        assert liftoff_frequency(liftoff_amplitude(f)) == pytest.approx(f, rel=1e-13)
    above = default_scene()                     # 1.5 mm at 20 Hz: Gamma = 2.4
    assert below_liftoff(above) is None
    below = above.with_values(excitation={"amplitude_mm": 0.6})   # Gamma = 0.966
    assert below_liftoff(below)["gamma"] == pytest.approx(0.966, abs=1e-3)
    # a random excitation has no one amplitude: no lift-off numbers claimed
    noisy = above.with_values(excitation={"kind": "random", "band_hz": [10.0, 500.0],
                                          "rms_acceleration_m_per_s2": 1.0})
    assert below_liftoff(noisy) is None


@pytest.mark.parametrize("frequency", [8.0, 10.0])
def test_run_at_a_low_frequency_extends_its_settling_as_sweep_does(frequency, tmp_path,
                                                                   capsys):
    out_dir = tmp_path / "out"
    code, out, err = run_main(["run", "--set", f"excitation.frequency_hz={frequency:g}",
                               "--set", "run.sample_rate_hz=2000", "-o", out_dir], capsys)
    assert code == 0, err
    base = default_scene()
    expected = sweeps.point_duration(base, frequency)          # the sweep point's length
    assert expected == pytest.approx((10 + 10) / frequency)
    lines = [ln for ln in err.splitlines() if "extended" in ln]
    assert len(lines) == 1
    assert lines[0] == (f"run: [run] settle_periods = 10 leaves no steady window in "
                        f"duration_s = 1 s at {frequency:g} Hz: extended to duration_s = "
                        f"{expected:g} s (settle_periods + 10 steady periods, as sweep "
                        "extends its points)")
    summary = json.loads((out_dir / "summary.json").read_text())
    assert summary["run_extended"]["duration_s"] == pytest.approx(expected, rel=1e-12)
    assert summary["run_extended"]["stated_duration_s"] == 1.0
    assert summary["window"]["end_s"] == pytest.approx(expected, rel=1e-9)
    assert summary["window"]["start_s"] == pytest.approx(10 / frequency, rel=1e-9)
    assert (out_dir / "waveforms.png").is_file()


def test_a_duration_the_user_sets_is_kept_and_the_refusal_names_what_to_set(tmp_path, capsys):
    code, out, err = run_main(["run", "--set", "excitation.frequency_hz=8", "--set",
                               "run.duration_s=1", "-o", tmp_path / "out"], capsys)
    assert code == 2
    assert "settle_periods = 10 leaves no steady window" in err
    assert "set [run] duration_s > 1.25 or settle_periods < 8" in err
    assert not (tmp_path / "out").exists()


def test_other_commands_still_refuse(tmp_path, capsys):
    code, out, err = run_main(["dynamics", "--set", "excitation.frequency_hz=8", "-o",
                               tmp_path / "out"], capsys)
    assert code == 2 and "leaves no steady window" in err
