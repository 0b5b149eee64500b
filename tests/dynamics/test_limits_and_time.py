"""Absolute times, noisy records, weak soft contacts and size limits (issue #8 items 6, 8-10)."""
import math

import numpy as np
import pytest

from tengfield.cli import main
from tengfield.dynamics import regime_map, simulate
from tengfield.dynamics.impact import Restitution, integrate
from tengfield._mpi import max_jobs
from tengfield.dynamics.mapping import MAX_MAP_WORK
from tengfield.dynamics.table import recorded_table
from tengfield.errors import DynamicsError, SceneError
from tengfield.scene import G, default_scene

FREQUENCY = 20.0


def short_scene(**sections):
    base = {"run": {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 2000.0}}
    base.update(sections)
    return default_scene().with_values(**base)


@pytest.mark.parametrize("origin", [1e5, 1e9, 1e12])
def test_large_start_times_change_nothing(origin):
    """[initial] time_s = 1e5 ... 1e12 (f t0 whole: same table phase): the run is the
    one started at 0 (integrated relative to the start), to round-off."""
    ref = simulate(short_scene())
    res = simulate(short_scene(initial={"time_s": origin}))
    assert res.regime == ref.regime
    np.testing.assert_array_equal(res.elapsed, ref.elapsed)
    np.testing.assert_allclose(res.gap, ref.gap, rtol=0, atol=1e-15)
    assert np.array_equal(res.impacts.plate, ref.impacts.plate)
    np.testing.assert_allclose(res.impacts.time - origin, ref.impacts.time, rtol=0,
                               atol=4 * np.spacing(origin))
    z, _, _ = res.sample_elapsed(ref.elapsed[::7])
    np.testing.assert_allclose(z, ref.gap[::7], rtol=0, atol=1e-15)


@pytest.mark.slow
def test_trajectory_csv_keeps_every_time_at_1e9(tmp_path, capsys):
    """Times are written at full precision: 1e9 s + k / 2 kHz stay distinct."""
    scene = tmp_path / "late.toml"
    scene.write_text("[initial]\ntime_s = 1e9\n[run]\nduration_s = 0.2\nsettle_periods = 1\n"
                     "sample_rate_hz = 2000.0\n")
    assert main(["dynamics", str(scene), "-o", str(tmp_path / "out")]) == 0
    data = np.genfromtxt(tmp_path / "out" / "trajectory.csv", delimiter=",", names=True)
    assert np.unique(data["time_s"]).size == data.size
    np.testing.assert_allclose(np.diff(data["time_s"]), 1 / 2000.0, rtol=0,
                               atol=2 * np.spacing(1e9))


def write_record(path, times, values, column="displacement_m", digits=17):
    with open(path, "w") as fh:
        fh.write(f"time_s,{column}\n")
        fh.writelines(f"{t!r},{v:.{digits}g}\n" for t, v in zip(times.tolist(), values.tolist()))


def test_epoch_stamped_record_gives_the_same_motion(tmp_path):
    """A record stamped 1.7e9 s + t behaves like the same record starting at 0."""
    rate, epoch = 5000.0, 1.7e9
    t = np.arange(0.0, 0.6, 1 / rate)
    y = 1.5e-3 * np.sin(2 * math.pi * FREQUENCY * t)
    write_record(tmp_path / "plain.csv", t, y)
    write_record(tmp_path / "epoch.csv", epoch + t, y)
    runs = []
    for name, start in (("plain.csv", 0.01), ("epoch.csv", epoch + 0.01)):
        runs.append(simulate(short_scene(
            excitation={"kind": "recorded", "file": str(tmp_path / name),
                        "frequency_hz": FREQUENCY},
            initial={"time_s": start})))
    plain, stamped = runs
    assert stamped.regime.name == plain.regime.name == "bounce"
    assert stamped.regime.period == plain.regime.period
    assert len(stamped.impacts) == len(plain.impacts)
    # the file's epoch times are themselves rounded to 2.4e-7 s
    np.testing.assert_allclose(stamped.impacts.time - stamped.time_origin,
                               plain.impacts.time - plain.time_origin, rtol=0, atol=2e-6)
    assert np.unique(stamped.t).size == stamped.t.size


def rounded_record(tmp_path, digits):
    """The drive (Gamma = 1.3) at 100 kHz, displacement written with ``digits`` digits."""
    rate = 100_000.0
    omega = 2 * math.pi * FREQUENCY
    t = np.arange(0.0, 0.6, 1 / rate)
    y = 1.3 * G / omega**2 * np.sin(omega * t)
    path = tmp_path / f"rounded{digits}.csv"
    write_record(path, t, y, digits=digits)
    return path, t, np.array([float(f"{v:.{digits}g}") for v in y])


@pytest.mark.slow
def test_smoothing_removes_rounding_noise(tmp_path):
    """Displacement rounded to 7 digits: its spline's acceleration is noisy enough to make
    the ball hop on the plate hundreds of times; smoothing_hz = 1 kHz restores the
    clean drive's motion (same impacts to 1e-7 s)."""
    path, _, _ = rounded_record(tmp_path, 7)
    amplitude_mm = 1e3 * 1.3 * G / (2 * math.pi * FREQUENCY) ** 2
    clean = simulate(short_scene(excitation={"amplitude_mm": amplitude_mm}))
    recorded = {"kind": "recorded", "file": str(path), "frequency_hz": FREQUENCY}
    noisy = simulate(short_scene(excitation=recorded))
    smooth = simulate(short_scene(excitation={**recorded, "smoothing_hz": 1000.0}))
    assert len(noisy.impacts) > 5 * len(clean.impacts)
    assert len(smooth.impacts) == len(clean.impacts)
    np.testing.assert_allclose(smooth.impacts.time, clean.impacts.time, rtol=0, atol=1e-7)


def test_event_bound_on_a_noisy_record_blames_the_data(tmp_path):
    _, t, y = rounded_record(tmp_path, 7)
    table = recorded_table(t, y, "displacement")
    with pytest.raises(DynamicsError, match="record is noisy.*smoothing_hz"):
        integrate(table, 3e-3, Restitution(0.1), t_start=0.0, t_end=0.5, period=1 / FREQUENCY,
                  max_events_per_period=20)


def test_smoothing_above_nyquist_is_refused(tmp_path):
    path, _, _ = rounded_record(tmp_path, 7)
    scene = short_scene(excitation={"kind": "recorded", "file": str(path),
                                    "frequency_hz": FREQUENCY, "smoothing_hz": 60_000.0})
    with pytest.raises(DynamicsError, match=r"smoothing_hz = 60000: allowed \[[0-9.e-]+, 50000\)"):
        simulate(scene)


def test_weak_soft_contact_is_refused_with_the_stiffness_needed():
    scene = short_scene(contact={"model": "soft", "stiffness_N_per_m": 1.0})
    with pytest.raises(SceneError, match=r"stiffness_N_per_m = 1: .*allowed >= ") as info:
        simulate(scene)
    needed = float(str(info.value).rsplit(">= ", 1)[1].split()[0])
    # the suggested stiffness is accepted and keeps the ball out of the plate
    res = simulate(scene.with_values(contact={"model": "soft", "stiffness_N_per_m": needed}))
    assert res.gap.min() > -0.1 * scene.device.stroke


def test_cli_soft_contact_at_1_N_per_m_exits_2(tmp_path, capsys):
    scene = tmp_path / "soft.toml"
    scene.write_text('[contact]\nmodel = "soft"\nstiffness_N_per_m = 1.0\n'
                     "[run]\nduration_s = 0.2\nsettle_periods = 1\n")
    assert main(["dynamics", str(scene), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "stiffness_N_per_m" in err


@pytest.mark.parametrize("sections, match", [
    ({"excitation": {"frequency_hz": 1e9}}, "excitation periods.*allowed <="),
    ({"run": {"duration_s": 1e6, "settle_periods": 1}}, "duration_s x sample_rate_hz"),
])
def test_huge_runs_are_refused_before_integrating(sections, match):
    with pytest.raises((SceneError, DynamicsError), match=match):
        simulate(default_scene().with_values(**sections))


@pytest.mark.parametrize("args, match", [
    (["--jobs", "1000"], r"--jobs = 1000 is out of range: allowed \[1, "),
    (["--jobs", "0"], r"--jobs = 0 is out of range: allowed \[1, "),
    (["--periods", "1000000000"], r"map periods = 1000000000: allowed \[2, "),
    (["--frequency-hz", "5:70:100000", "--amplitude-mm", "0.1:5:100000"],
     r"map points = 1e\+10"),
    (["--frequency-hz", "5:70:1000", "--amplitude-mm", "0.1:5:1000", "--periods", "100000"],
     r"points x periods = 1e\+06 x 100000 = 1e\+11: allowed <= 1e\+10"),
])
def test_map_limits_exit_2(tmp_path, capsys, args, match):
    argv = ["map", "--frequency-hz", "5:70:3", "--amplitude-mm", "0.5:1:2", "-o",
            str(tmp_path / "m")]
    # later options win over the defaults above
    assert main(argv + args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    import re
    assert re.search(match, err), err
    assert not (tmp_path / "m").exists()


def test_map_jobs_bound_is_named():
    assert max_jobs() >= 4 and MAX_MAP_WORK == 10_000_000_000
    with pytest.raises(SceneError, match="--jobs"):
        regime_map(default_scene(), [20.0], [1e-3], jobs=max_jobs() + 1, progress=False)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["impact", "soft", "3d"])
def test_a_duration_override_inside_the_settle_window_is_refused(model):
    """simulate(duration=) follows the scene file's rule: a run that ends before its regime
    window starts (10 periods at 20 Hz = 0.5 s) is refused with the numbers, not
    classified as 'rest' over an empty window."""
    scene = default_scene().with_values(contact={"model": model})
    with pytest.raises(SceneError, match=r"settle_periods = 10 leaves no steady window: "
                                         r"settle_periods / frequency_hz = 0.5 s must be < "
                                         r"the duration asked for = 0.1"):
        simulate(scene, duration=0.1)
    assert simulate(scene, duration=0.6).t[-1] == pytest.approx(0.6)


def test_cli_duration_inside_the_settle_window_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["dynamics", "--duration-s", "1e-9", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "must be < --duration-s = 1e-09" in err[0]
    assert not out.exists()
