"""The charge a device holds as a band (issue #38, tengfield.air_breakdown.band) on the planar
contact-separation device, whose static limits are known in closed form: Paschen with
its γ, the empirical air table, the seed count, the edges' order and where they bind."""
import math

import numpy as np
import pytest
from planar_lines import planar_lines

from tengfield.air_breakdown import band as bandmod
from tengfield.air_breakdown import evaluate
from tengfield.paschen import ATMOSPHERE, EMPIRICAL_AIR, Paschen
from tengfield.scene import EPS0

GAMMAS = (1e-4, 1e-3, 0.01, 0.1)


@pytest.mark.parametrize("gamma", GAMMAS)
def test_townsend_curve_is_the_closed_form_for_each_gamma(gamma):
    p = Paschen(gamma=gamma)
    d = np.geomspace(1.05 * p.d_min, 0.95 * p.d_streamer, 50)
    pd = ATMOSPHERE * d
    closed = 273.75 * pd / (np.log(11.25 * pd) - math.log(math.log(1 + 1 / gamma)))
    assert p.voltage(d) == pytest.approx(closed, rel=1e-12)
    # and the planar device's open-circuit limit is eps0 V_b(x_max) / x_max at that gamma
    x_max = 1e-3
    limit = evaluate(planar_lines(x_max, 1e-3), p, ("open",), "grounded-lower").sigma_max
    assert limit == pytest.approx(EPS0 * float(p.voltage(x_max)) / x_max, rel=1e-9)


def test_a_lower_gamma_raises_the_breakdown_voltage():
    d = np.geomspace(2e-5, 5e-3, 40)
    curves = [Paschen(gamma=g).voltage(d) for g in GAMMAS]
    assert all(np.all(a > b) for a, b in zip(curves, curves[1:]))


def test_empirical_curve_passes_through_its_table():
    p = Paschen(curve="empirical")
    table = np.asarray(EMPIRICAL_AIR)
    d = table[:, 0] / ATMOSPHERE
    assert p.voltage(d) == pytest.approx(table[:, 1], rel=1e-12)
    # between rows: log-log interpolation (the geometric mean at the geometric midpoint)
    mid = np.sqrt(d[1:] * d[:-1])
    assert p.voltage(mid) == pytest.approx(np.sqrt(table[1:, 1] * table[:-1, 1]), rel=1e-12)
    # Dakin's law at its rows, gamma does not enter, the minimum is the table's first row
    x = table[1:, 0] / 1e3
    assert table[1:, 1] == pytest.approx((24.36 * x + 6.72 * np.sqrt(x)) * 1e3, rel=1e-12)
    assert Paschen(curve="empirical", gamma=1e-4).voltage(1e-3) == p.voltage(1e-3)
    assert p.v_min == 327.0 and set(p.regime([1e-4, 1e-2])) == {"empirical"}
    # continuous and non-decreasing over the gaps a device has
    g = np.geomspace(1e-8, 5e-2, 100001)
    v = p.voltage(g)
    assert np.all(np.isfinite(v)) and np.all(np.diff(v) >= -1e-9 * v[1:])
    # against the Townsend curve at mm gaps (both describe air): within 15 %
    assert p.voltage(1e-3) == pytest.approx(Paschen().voltage(1e-3), rel=0.15)


def triangle(x_top: float, period: float = 0.05, periods: int = 4, samples: int = 4001):
    """The gap rising at a constant speed from 0 to ``x_top`` and back, ``periods`` times."""
    t = np.linspace(0.0, period * periods, samples)
    phase = (t / period) % 1.0
    return bandmod.Trajectory(t, x_top * (1.0 - np.abs(2.0 * phase - 1.0)))


def test_seed_count_follows_the_formula():
    """V_s = x (1 m^2 column) where x is above the critical gap x_c: N = S_v ∫ V_s dt +
    n_ion (growth of V_s) = S_v (x_top² − x_c²)/(2 v) per half pass + n_ion x_top per rise."""
    lines = planar_lines(3e-3, 1e-3)
    paschen = Paschen()
    x_top, period = 2e-3, 0.05
    traj = triangle(x_top, period)
    track = bandmod.stress_track(lines, paschen, ("open",), "grounded-lower", traj)
    sigma = 1.02 * EPS0 * float(paschen.voltage(x_top)) / x_top
    x = np.geomspace(1e-5, x_top, 200001)
    x_c = x[np.argmax(EPS0 * paschen.voltage(x) / x < sigma)]
    speed = 2 * x_top / period
    rises = 4
    seeds = bandmod.Seeds(seed_rate=1e7, ion_density=5e8)
    got = bandmod.expected_seeds(track, sigma, seeds)
    assert got["ions_taken_in"] == pytest.approx(5e8 * x_top * rises, rel=1e-9)
    assert got["volume_ionisation"] == pytest.approx(
        1e7 * 2 * rises * (x_top**2 - x_c**2) / (2 * speed), rel=2e-2)
    assert got["per_s"] == pytest.approx(got["total"] / traj.duration)
    # linear in n_ion and S_v; more with a wider gap
    double = bandmod.expected_seeds(track, sigma, bandmod.Seeds(2e7, 1e9))
    assert double["total"] == pytest.approx(2 * got["total"], rel=1e-12)
    wider = bandmod.stress_track(lines, paschen, ("open",), "grounded-lower", triangle(2.5e-3))
    more = bandmod.expected_seeds(wider, sigma, seeds)
    assert more["ions_taken_in"] == pytest.approx(5e8 * 2.5e-3 * rises, rel=1e-9)
    assert more["volume_ionisation"] > got["volume_ionisation"]
    # below the static limit nothing is over-stressed
    assert bandmod.expected_seeds(track, 0.99 * sigma / 1.02, seeds)["total"] == 0.0


@pytest.mark.parametrize("x_top", [1.0e-3, 2.0e-3, 3.0e-3])
def test_edges_are_the_closed_form_limits_and_ordered(x_top):
    """lower: eps0 V_b(x_max)/x_max at gamma = 0.1 (the device's critical gap is its
    widest); upper: the same at the trajectory's widest gap x_top and gamma = 1e-4."""
    x_max = 3e-3
    lines = planar_lines(x_max, 1e-3)
    band = bandmod.compute_band(lines, Paschen(), ("open",), "grounded-lower",
                                triangle(x_top), (1e-4, 0.1), bandmod.Seeds())
    assert band.lower == pytest.approx(
        EPS0 * float(Paschen(gamma=0.1).voltage(x_max)) / x_max, rel=1e-9)
    assert band.upper == pytest.approx(
        EPS0 * float(Paschen(gamma=1e-4).voltage(x_top)) / x_top, rel=1e-6)
    assert band.gamma_lower == 0.1 and band.gamma_upper == 1e-4
    assert band.upper_gap == pytest.approx(x_top, rel=1e-6)
    assert band.lower <= band.static_at_gamma <= band.estimate <= band.upper
    data = band.to_json()
    assert data["lower_uC_per_m2"] <= data["estimate_uC_per_m2"] <= data["upper_uC_per_m2"]
    assert set(data["assumptions"]) == {"lower", "estimate", "upper"}


def test_estimate_is_where_the_seeds_reach_the_criterion():
    lines = planar_lines(3e-3, 1e-3)
    traj = triangle(2e-3)
    # a column of 1 m^2: S_v = 1 /m^3/s gives 2e-6 ... 7.5e-4 seeds per second in the band
    seeds = bandmod.Seeds(seed_rate=1.0, ion_density=0.0, breakdowns_per_s=2e-4)
    band = bandmod.compute_band(lines, Paschen(), ("open",), "grounded-lower", traj,
                                (1e-4, 0.1), seeds)
    assert band.static_at_gamma < band.estimate < band.upper
    track = band.track
    assert bandmod.expected_seeds(track, band.estimate, seeds)["per_s"] >= 2e-4
    assert bandmod.expected_seeds(track, band.estimate * (1 - 1e-6), seeds)["per_s"] < 2e-4
    # a higher criterion needs more charge; plentiful seeds bring it to the static limit
    harder = bandmod.compute_band(lines, Paschen(), ("open",), "grounded-lower", traj,
                                  (1e-4, 0.1), bandmod.Seeds(1.0, 0.0, 5e-4))
    assert harder.estimate > band.estimate
    plenty = bandmod.compute_band(lines, Paschen(), ("open",), "grounded-lower", traj,
                                  (1e-4, 0.1), bandmod.Seeds(1e20, 0.0, 1.0))
    # (the static limit along the trajectory: it turns at 2 mm, the device's critical gap
    # is its widest, 3 mm)
    assert plenty.estimate == pytest.approx(plenty.track.threshold.min(), rel=1e-6)
    assert plenty.track.threshold.min() > plenty.static_at_gamma


def test_no_seeds_clamp_the_estimate_to_the_upper_edge():
    band = bandmod.compute_band(planar_lines(3e-3, 1e-3), Paschen(), ("open",),
                                "grounded-lower", triangle(2e-3), (1e-4, 0.1),
                                bandmod.Seeds(0.0, 0.0, 1.0))
    assert band.estimate == band.upper
    assert "clamped" in band.estimate_rule


def test_scene_gamma_outside_the_range_widens_it():
    band = bandmod.compute_band(planar_lines(3e-3, 1e-3), Paschen(gamma=0.5), ("open",),
                                "grounded-lower", triangle(2e-3), (1e-4, 0.1), bandmod.Seeds())
    assert band.gamma_lower == 0.5
    assert band.lower <= band.estimate <= band.upper
    # the range said (terminal, breakdown.json) is the one the edges were taken over
    assert band.gamma_range == (1e-4, 0.5) and band.to_json()["gamma_range"] == [1e-4, 0.5]
    assert "gamma in [0.0001, 0.5]" in bandmod.gamma_line(band)


def test_trajectory_block_at_the_scene_sigma():
    band = bandmod.compute_band(planar_lines(3e-3, 1e-3), Paschen(), ("open",),
                                "grounded-lower", triangle(2e-3), (1e-4, 0.1), bandmod.Seeds())
    peak_limit = band.track.threshold.min()
    below = bandmod.trajectory_block(band, -0.9 * peak_limit)
    assert below["peak_gap_voltage_over_breakdown"] == pytest.approx(0.9, rel=1e-12)
    assert below["time_above_breakdown_s"] == 0.0
    above = bandmod.trajectory_block(band, -1.2 * peak_limit)
    assert above["peak_gap_voltage_over_breakdown"] == pytest.approx(1.2, rel=1e-12)
    assert 0.0 < above["time_above_breakdown_s"] < band.track.time[-1]


def test_output_band_scales_each_output_with_its_edge():
    band = bandmod.compute_band(planar_lines(3e-3, 1e-3), Paschen(), ("open",),
                                "grounded-lower", triangle(2e-3), (1e-4, 0.1), bandmod.Seeds())
    sigma = band.static_at_gamma
    summary = {"peak_to_peak": {"Q_sc_C": 2e-9, "V_oc_V": 30.0},
               "peak": {"I_sc_A": 1e-7}, "load": {"mean_power_W": 1e-6}}
    out = bandmod.output_band(summary, band, -sigma)
    assert out["peak_to_peak.Q_sc_C"]["upper"] == pytest.approx(2e-9 * band.upper / sigma)
    assert out["peak.I_sc_A"]["lower"] == pytest.approx(1e-7 * band.lower / sigma)
    assert out["load.mean_power_W"]["estimate"] == pytest.approx(
        1e-6 * (band.estimate / sigma) ** 2)
    assert bandmod.output_band(summary, band, -sigma, linear=False) == {}


def test_breakdown_keys_of_the_band(tmp_path):
    """[breakdown] gamma (read under its old name secondary_emission with one warning),
    gamma_range as [low, high], the curve's name."""
    import warnings

    from tengfield.errors import SceneError
    from tengfield.scene import load_scene

    path = tmp_path / "old.toml"
    path.write_text("[breakdown]\nsecondary_emission = 0.001\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_scene(path)
    assert scene.breakdown.gamma == 0.001
    assert any("gamma" in str(w.message) for w in caught)
    assert Paschen.from_scene(scene).gamma == 0.001
    path.write_text('[breakdown]\ngamma_range = [0.1, 0.001]\n')
    with pytest.raises(SceneError, match=r"gamma_range = \[0.1, 0.001\].*low <= high"):
        load_scene(path)
    path.write_text('[breakdown]\npaschen = "dakin"\n')
    with pytest.raises(SceneError, match="paschen"):
        load_scene(path)
    path.write_text('[breakdown]\npaschen = "empirical"\nion_density_per_cm3 = 100\n')
    scene = load_scene(path)
    assert Paschen.from_scene(scene).curve == "empirical"
    assert bandmod.Seeds.from_scene(scene).ion_density == pytest.approx(1e8)


@pytest.mark.parametrize("kind, linear", [("open", True), ("load", True), ("series-rc", True),
                                          ("rectifier", False)])
def test_a_runs_band_block_and_which_circuits_scale(kind, linear):
    """band_summary on the planar lines and a prescribed trajectory (plate_model's
    FakeDynamics): the band, the trajectory at the run's σ and, for σ = "breakdown", the
    outputs scaled (open) or said to need runs (a rectifier: its diodes)."""
    from plate_model import FakeDynamics

    from tengfield.scene import default_scene

    scene = default_scene().with_values(device={"stroke_mm": 3.0}, circuit={"kind": kind},
                                        run={"duration_s": 0.4, "settle_periods": 4})
    given = scene.with_values(device={"surface_charge_uC_per_m2": "breakdown"})
    lines = planar_lines(3e-3, 1e-3)
    result = evaluate(lines, Paschen(), ("open",), "grounded-lower")
    at = scene.with_values(device={"surface_charge_uC_per_m2": -result.sigma_max * 1e6})
    summary = {"peak_to_peak": {"Q_sc_C": 1e-9}, "peak": {"I_sc_A": 1e-7}}
    block = bandmod.band_summary(summary, at, given, result, FakeDynamics(at))
    band = block["band"]
    assert band["lower_uC_per_m2"] <= band["estimate_uC_per_m2"] <= band["upper_uC_per_m2"]
    assert block["trajectory"]["peak_gap_voltage_over_breakdown"] == pytest.approx(1.0, abs=1e-3)
    if linear:
        q = block["outputs"]["peak_to_peak.Q_sc_C"]
        assert q["upper"] == pytest.approx(1e-9 * band["upper_uC_per_m2"] /
                                           (result.sigma_max * 1e6), rel=1e-12)
    else:
        assert block["outputs"]["available"] is False
        assert "diodes" not in block["outputs"]["reason"]   # the entry says, not a name
    # a scene sigma that is not "breakdown": no outputs' band
    assert "outputs" not in bandmod.band_summary(summary, at, at, result, FakeDynamics(at))
