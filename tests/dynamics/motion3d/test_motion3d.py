"""Physics checks of the 3D ball (issue #13 item 5)."""
import math

import numpy as np
import pytest

from tengfield.dynamics import DynamicsResult
from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.soft import simulate_soft
from tengfield.dynamics.table import sine_table
from tengfield.errors import SceneError
from tengfield.dynamics.motion3d import Motion3DResult, integrate_3d, simulate_3d
from tengfield.dynamics.motion3d.simulate import resting_position
from tengfield.scene import G, default_scene

SHORT = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000.0}


@pytest.fixture(scope="module")
def base():
    return default_scene().with_values(run=SHORT, contact={"restitution": 0.6})


@pytest.mark.slow
def test_on_axis_reduces_to_soft_contact_at_fourth_order(base):
    """Vertical drive, ball on the axis, power law e = 1: the 1-D soft model's z(t)."""
    soft = simulate_soft(base.with_values(contact={"model": "soft"}))
    scene = base.with_values(contact={"model": "3d", "law": "power"})
    steps = np.array([16, 32, 64])
    errors = []
    for n in steps:
        r = simulate_3d(scene, steps=int(n))
        assert np.all(r.x == 0.0) and np.all(r.y == 0.0) and np.all(r.spin == 0.0)
        errors.append(np.max(np.abs(r.gap - soft.gap)))
        assert len(r.impacts) == len(soft.impacts)
    np.testing.assert_allclose(r.impacts.time, soft.impacts.time, atol=1e-7)
    errors = np.array(errors)
    order = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    print(f"3d vs soft: max |dz| = {errors} m at {steps} steps per period, order {order:.2f}")
    assert errors[-1] < 1e-8
    assert order > 3.0   # RK4


def test_converges_to_impact_map_as_stiffness_grows(base):
    f, amplitude, e, stroke = 20.0, 1.5e-3, 0.6, 3e-3
    t_end = 0.12
    ref, _, _ = integrate(sine_table(amplitude, 2 * math.pi * f, 0.0), stroke, Restitution(e),
                          t_start=0.0, t_end=t_end, period=1 / f)
    t = np.linspace(0.05, t_end, 400)
    z_ref, _, _ = ref(t)
    stiffness = np.array([1e4, 1e5, 1e6])
    errors = []
    for k in stiffness:
        scene = base.with_values(contact={"model": "3d", "law": "power", "stiffness_N_per_m": k},
                                 run={"duration_s": t_end})
        r = simulate_3d(scene)
        z, _, _ = r.sample(t)
        errors.append(np.max(np.abs(z - z_ref)))
    errors = np.array(errors)
    rate = -np.polyfit(np.log(stiffness), np.log(errors), 1)[0]
    print(f"3d -> impact map: errors {errors} m at k = {stiffness} N/m, rate k^-{rate:.2f}")
    assert np.all(np.diff(errors) < 0)
    assert rate > 0.3


def _energy(scene, state, gravity):
    m = scene.device.ball_mass
    r = scene.device.ball_radius
    v = state[:, 3:6]
    w = state[:, 6:9]
    return (0.5 * m * np.sum(v * v, axis=1) + 0.2 * m * r * r * np.sum(w * w, axis=1)
            - m * state[:, 0:3] @ gravity)


def test_energy_conserved_with_restitution_one_and_no_friction():
    scene = default_scene().with_values(
        contact={"model": "3d", "restitution": 1.0, "friction_static": 0.0,
                 "friction_dynamic": 0.0},
        excitation={"amplitude_mm": 0.0}, device={"tilt_deg": 20.0})
    g = np.array([G * math.sin(math.radians(20.0)), 0.0, -G * math.cos(math.radians(20.0))])
    p0 = np.array([0.1e-3, -0.2e-3, 3.5e-3 + 1.0e-3])
    v0 = np.array([0.3, 0.2, 0.5])
    drift = []
    steps = np.array([32, 64, 128])
    for n in steps:
        status, knots, episodes, *_ = integrate_3d(scene, t_start=0.0, t_end=0.2,
                                                   position0=p0, velocity0=v0,
                                                   spin0=(5.0, -3.0, 2.0), steps=int(n))
        assert status == 0
        flight = knots[knots[:, 10] == 0.0]
        energy = _energy(scene, flight[:, 1:10], g)
        drift.append(np.ptp(energy) / abs(energy[0]))
        # without friction the spin never changes
        np.testing.assert_allclose(knots[-1, 7:10], (5.0, -3.0, 2.0), rtol=0, atol=1e-12)
    surfaces = episodes[:, 0]
    order = -np.polyfit(np.log(steps), np.log(drift), 1)[0]
    print(f"{np.sum(surfaces == 0)} lower, {np.sum(surfaces == 1)} upper, "
          f"{np.sum(surfaces == 2)} wall contacts; energy drift {drift} at {steps} steps "
          f"per period, order {order:.2f}")
    assert np.sum(surfaces == 2) >= 5 and np.sum(surfaces == 1) >= 5
    assert drift[1] < 1e-5          # the default resolution (64)
    assert order > 3.0              # RK4 (with the edge refinement of the contact step)


def _incline(tilt_deg, mu_s, mu_d):
    return default_scene().with_values(
        contact={"model": "3d", "friction_static": mu_s, "friction_dynamic": mu_d},
        excitation={"amplitude_mm": 0.0}, device={"tilt_deg": tilt_deg,
                                                  "tube_inner_radius_mm": 20.0,
                                                  "tube_outer_radius_mm": 22.0},
        field={"domain_radius_mm": 60.0})


@pytest.mark.parametrize("mu, factor", [(0.1, 5.0 / 7.0), (0.0, 1.0)])
def test_ball_on_tilted_plate_rolls_at_five_sevenths_g_sin(mu, factor):
    tilt = 5.0
    scene = _incline(tilt, mu, mu)
    g = np.array([G * math.sin(math.radians(tilt)), 0.0, -G * math.cos(math.radians(tilt))])
    p0 = resting_position(scene, 0.0, 0.0, x0=-15e-3)
    status, knots, _, *_ = integrate_3d(scene, t_start=0.0, t_end=0.12, position0=p0,
                                        velocity0=np.zeros(3))
    assert status == 0
    t = knots[:, 0]
    sel = t > 0.02
    acc = 2.0 * np.polyfit(t[sel], knots[sel, 1], 2)[0]
    expected = factor * G * math.sin(math.radians(tilt))
    print(f"mu = {mu}: x'' = {acc:.6f} m/s^2, expected {expected:.6f}")
    assert acc == pytest.approx(expected, rel=2e-3)
    if mu > 0:   # rolling without slipping: v_x = R w_y
        r = scene.device.ball_radius
        np.testing.assert_allclose(knots[-1, 4], r * knots[-1, 8], rtol=1e-3)


def test_wall_impact_with_sliding_friction_gives_textbook_spin():
    """Sliding throughout: tangential impulse mu * normal impulse, dw = 5 mu dv_n / (2 R)."""
    mu, e = 0.02, 0.5
    scene = default_scene().with_values(
        contact={"model": "3d", "restitution": e, "friction_static": mu, "friction_dynamic": mu},
        excitation={"amplitude_mm": 0.0})
    r = scene.device.ball_radius
    p0 = np.array([0.0, 0.0, r + 1.5e-3])
    v0 = np.array([0.0, 1.0, 0.3])   # toward the wall at +y, sliding along +z
    status, knots, episodes, *_ = integrate_3d(scene, t_start=0.0, t_end=0.8e-3, position0=p0,
                                               velocity0=v0, gravity=np.zeros(3))
    assert status == 0
    assert episodes.shape[0] == 1 and episodes[0, 0] == 2 and np.isfinite(episodes[0, 2])
    v1 = knots[-1, 4:7]
    w1 = knots[-1, 7:10]
    dvn = v0[1] - v1[1]                       # normal impulse / m
    e_eff = -v1[1] / v0[1]
    print(f"wall: e_eff = {e_eff:.4f}, dv_n = {dvn:.5f}, dv_t = {v1[2] - v0[2]:.6f}, "
          f"w_x = {w1[0]:.4f} rad/s (textbook {-2.5 * mu * dvn / r:.4f})")
    assert v1[2] - v0[2] == pytest.approx(-mu * dvn, rel=1e-3)
    assert w1[0] == pytest.approx(-2.5 * mu * dvn / r, rel=1e-3)
    assert abs(w1[1]) < 1e-9 and abs(w1[2]) < 1e-9
    assert e_eff == pytest.approx(e, abs=1e-3)   # calibrated damping, also at the wall


def test_lateral_drive_moves_the_ball_off_axis_and_onto_the_wall():
    scene = default_scene().with_values(
        contact={"model": "3d"}, run=SHORT,
        excitation={"frequency_hz": 30.0, "amplitude_mm": 3.0, "amplitude_x_mm": 0.5,
                    "phase_x_deg": 30.0})
    r = simulate_3d(scene)
    assert isinstance(r, Motion3DResult) and isinstance(r, DynamicsResult)
    assert r.wall_contacts > 0
    assert np.max(r.radial) <= r.tube_clearance + 1e-5   # compliant wall: microns
    assert np.max(r.radial) > 0.9 * r.tube_clearance
    s = r.summary
    assert s["wall_contacts"] == r.wall_contacts and s["steps_per_contact"] > 20
    assert r.min_steps_per_contact >= 10
    # the sampler reproduces the samples
    z, v, y = r.sample(r.t[::50])
    np.testing.assert_allclose(z, r.gap[::50], atol=1e-15)


def test_recorded_three_axis_csv_matches_the_sine(tmp_path):
    f, az, ax = 30.0, 2.0e-3, 0.4e-3
    t = np.linspace(0.0, 0.4, 8001)
    w = 2 * math.pi * f
    data = np.column_stack([t, az * np.sin(w * t), ax * np.sin(w * t + 0.5)])
    np.savetxt(tmp_path / "table.csv", data, delimiter=",", header="time_s,z_m,x_m",
               comments="")
    (tmp_path / "s.toml").write_text(
        '[excitation]\nkind = "recorded"\nfile = "table.csv"\nsignal_column = "z_m"\n'
        f'signal_x_column = "x_m"\nfrequency_hz = {f}\n'
        '[contact]\nmodel = "3d"\n[run]\nduration_s = 0.2\nsettle_periods = 2\n'
        'sample_rate_hz = 5000.0\n')
    from tengfield.scene import load_scene
    rec = simulate_3d(load_scene(tmp_path / "s.toml"))
    sine = simulate_3d(default_scene().with_values(
        contact={"model": "3d"}, run={"duration_s": 0.2, "settle_periods": 2,
                                      "sample_rate_hz": 5000.0},
        excitation={"frequency_hz": f, "amplitude_mm": az * 1e3, "amplitude_x_mm": ax * 1e3,
                    "phase_x_deg": math.degrees(0.5)}))
    # same motion up to the first impacts (the spline differs from the sine by ~1e-12 m)
    early = rec.t < 0.05
    np.testing.assert_allclose(rec.gap[early], sine.gap[early], atol=1e-7)
    np.testing.assert_allclose(rec.x[early], sine.x[early], atol=1e-7)
    assert np.max(np.abs(rec.x)) > 0


def test_bad_3d_keys_raise_scene_errors(tmp_path):
    with pytest.raises(SceneError, match="friction_dynamic"):
        simulate_3d(default_scene().with_values(
            contact={"model": "3d", "friction_static": 0.05, "friction_dynamic": 0.1}))
    with pytest.raises(SceneError, match="damping_N_s_per_m"):
        simulate_3d(default_scene().with_values(
            contact={"model": "3d", "law": "power", "exponent": 1.5}))
    with pytest.raises(SceneError, match="tilt_deg"):
        default_scene().with_values(device={"tilt_deg": 200.0})
    np.savetxt(tmp_path / "t.csv", np.column_stack([np.linspace(0, 1, 20), np.zeros(20)]),
               delimiter=",", header="time_s,displacement_m", comments="")
    with pytest.raises(SceneError, match="signal_x_column"):   # read with the scene
        default_scene().with_values(
            contact={"model": "3d"}, excitation={"kind": "recorded",
                                                 "file": str(tmp_path / "t.csv"),
                                                 "signal_x_column": "ax"},
            run={"duration_s": 0.5, "settle_periods": 1})


def test_default_scenes_unchanged_by_the_3d_keys():
    scene = default_scene()
    assert scene.contact.model == "impact"
    assert scene.field_hash() == default_scene().with_values(
        contact={"friction_static": 0.3}, device={"tilt_deg": 10.0}).field_hash()


def test_writers_and_figure(tmp_path):
    import matplotlib
    matplotlib.use("Agg")   # the caller chooses the backend
    from tengfield.io import EXTRA_COLUMNS, write_contacts_csv, write_trajectory3d_csv
    from tengfield.plotting.dynamics import plot_trajectory3d
    scene = default_scene().with_values(
        contact={"model": "3d"}, run={"duration_s": 0.1, "settle_periods": 1,
                                      "sample_rate_hz": 2000.0},
        excitation={"frequency_hz": 30.0, "amplitude_mm": 3.0, "amplitude_y_mm": 0.5})
    r = simulate_3d(scene)
    write_trajectory3d_csv(r, tmp_path / "trajectory.csv")
    table = np.genfromtxt(tmp_path / "trajectory.csv", delimiter=",", names=True)
    assert table.dtype.names[:4] == ("time_s", "gap_m", "gap_velocity_m_per_s", "table_m")
    assert table.dtype.names[4:] == EXTRA_COLUMNS
    np.testing.assert_allclose(table["y_m"], r.y, rtol=1e-10, atol=1e-15)
    write_contacts_csv(r, tmp_path / "contacts.csv")
    contacts = np.genfromtxt(tmp_path / "contacts.csv", delimiter=",", names=True, dtype=None,
                             encoding="utf-8")
    assert contacts.size == r.contacts["surface"].size
    assert np.count_nonzero(contacts["surface"] == "wall") == r.wall_contacts
    plot_trajectory3d(r, tmp_path / "trajectory3d.png")
    assert (tmp_path / "trajectory3d.png").stat().st_size > 10_000


@pytest.mark.parametrize("speed", [0.1, 0.5, 2.0])
def test_undamped_hertz_impact_time_and_rebound(speed):
    """e = 1: the Hertz contact time 2.943 (5 m / 4 k)^(2/5) v^(-1/5), full rebound."""
    from tengfield.dynamics.motion3d.contact import hertz_contact_time, surface_parameters
    scene = default_scene().with_values(contact={"model": "3d", "restitution": 1.0},
                                        excitation={"amplitude_mm": 0.0})
    r = scene.device.ball_radius
    status, knots, episodes, *_ = integrate_3d(
        scene, t_start=0.0, t_end=1e-3, position0=[0.0, 0.0, r + 1e-6],
        velocity0=[0.0, 0.0, -speed], gravity=np.zeros(3))
    assert episodes.shape[0] == 1
    k = surface_parameters(scene)[0, 1]
    dwell = episodes[0, 2] - episodes[0, 1]
    assert dwell == pytest.approx(hertz_contact_time(scene.device.ball_mass, k, speed), rel=1e-4)
    assert knots[-1, 6] == pytest.approx(speed, rel=1e-4)
    assert episodes[0, 5] >= 30   # steps resolving the contact


def _rebound(e, speed, damping_model):
    scene = default_scene().with_values(
        contact={"model": "3d", "restitution": e, "damping_model": damping_model},
        excitation={"amplitude_mm": 0.0})
    r = scene.device.ball_radius
    _, knots, episodes, *_ = integrate_3d(scene, t_start=0.0, t_end=1e-3,
                                          position0=[0.0, 0.0, r + 1e-7],
                                          velocity0=[0.0, 0.0, -speed], gravity=np.zeros(3))
    assert episodes.shape[0] == 1
    return knots[-1, 6] / speed


@pytest.mark.parametrize("e", [0.1, 0.5, 0.9])
def test_calibrated_hertz_rebounds_with_the_restitution_at_any_speed(e):
    rebound = [_rebound(e, v, "calibrated") for v in (0.1, 0.5, 2.0)]
    print(f"e = {e}: rebound {rebound} at 0.1, 0.5, 2 m/s")
    np.testing.assert_allclose(rebound, e, rtol=2e-3)


def test_chrono_damping_rebound_matches_its_dimensionless_contact():
    """Chrono's closed-form beta: the rebound of x'' = -x^1.5 - a x^(1/4) x' (0.253 for e = 0.1)."""
    from tengfield.dynamics.motion3d.contact import SQRT_5_6, beta, rebound_of_damping
    for e in (0.1, 0.5):
        expected = rebound_of_damping(-beta(e) * 2 * SQRT_5_6 * math.sqrt(1.5))
        assert _rebound(e, 0.5, "chrono") == pytest.approx(expected, rel=2e-3)
    assert rebound_of_damping(-beta(0.1) * 2 * SQRT_5_6 * math.sqrt(1.5)) > 0.2


def test_lateral_drive_symmetries():
    """Mirror (x drive phase + 180 deg -> x -> -x) and rotation (x drive -> y drive)."""
    base = default_scene().with_values(
        contact={"model": "3d"}, run={"duration_s": 0.15, "settle_periods": 1,
                                      "sample_rate_hz": 4000.0},
        excitation={"frequency_hz": 30.0, "amplitude_mm": 3.0})
    a = simulate_3d(base.with_values(excitation={"amplitude_x_mm": 0.5, "phase_x_deg": 30.0}))
    b = simulate_3d(base.with_values(excitation={"amplitude_x_mm": 0.5, "phase_x_deg": 210.0}))
    c = simulate_3d(base.with_values(excitation={"amplitude_y_mm": 0.5, "phase_y_deg": 30.0}))
    assert a.wall_contacts > 0
    np.testing.assert_allclose(b.x, -a.x, atol=1e-9)
    np.testing.assert_allclose(b.gap, a.gap, atol=1e-9)
    np.testing.assert_allclose(c.y, a.x, atol=1e-9)
    np.testing.assert_allclose(c.x, 0.0, atol=1e-15)
    np.testing.assert_allclose(c.gap, a.gap, atol=1e-9)
    # spin about the axis perpendicular to the drive, opposite in the mirror
    np.testing.assert_allclose(b.spin[:, 1], -a.spin[:, 1], atol=1e-6)
    np.testing.assert_allclose(c.spin[:, 0], -a.spin[:, 1], atol=1e-6)


def test_simulate_dispatches_the_3d_model():
    """`tengfield.simulate` (and so `tengfield run`) runs the 3D ball for model = "3d"."""
    import tengfield as tf
    from tengfield.dynamics.motion3d import Motion3DResult
    scene = tf.default_scene().with_values(contact={"model": "3d"},
                                           run={"duration_s": 0.1, "settle_periods": 1,
                                                "sample_rate_hz": 2000.0})
    result = tf.simulate(scene)
    assert isinstance(result, Motion3DResult)
    assert np.all(result.gap >= -1e-4) and np.all(result.gap <= scene.device.stroke + 1e-4)


def test_run_writes_the_same_3d_dynamics_files_as_the_dynamics_command(tmp_path):
    """`tengfield run` and `tengfield dynamics` write the dynamics through one function: a
    3D scene's run now has the 3D trajectory columns, contacts.csv and trajectory3d.png
    (it used to write the 1-D files only), identical to the dynamics command's."""
    import csv

    import plate_model as fx

    import tengfield as tf
    from tengfield.cli import main

    scene_text = "[contact]\nmodel = '3d'\n[run]\nduration_s = 0.3\nsettle_periods = 2\n"
    scene_file = tmp_path / "s.toml"
    scene_file.write_text(scene_text)
    scene = tf.scene.load_scene(scene_file)
    run = tf.run(scene, cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    (tmp_path / "run").mkdir()
    written = tf.io.write_dynamics_outputs(run, tmp_path / "run", plots=True)
    names = {p.name for p in written}
    assert names == {"trajectory.csv", "contacts.csv", "impacts.csv", "trajectory3d.png",
                     "trajectory.png"}
    assert main(["dynamics", str(scene_file), "-o", str(tmp_path / "dyn"), "--no-plots"]) == 0
    for name in ("contacts.csv", "impacts.csv"):
        assert (tmp_path / "run" / name).read_bytes() == (tmp_path / "dyn" / name).read_bytes()
    extra = ["x_m", "y_m", "radial_m", "vx_m_per_s", "vy_m_per_s",
             "spin_x_rad_per_s", "spin_y_rad_per_s", "spin_z_rad_per_s"]
    with open(tmp_path / "dyn" / "trajectory.csv") as fh:
        dyn = list(csv.reader(fh))
    assert dyn[0][4:] == extra
    # run's trajectory.csv leaves out what waveforms.csv holds (issue #28): time_s, then
    # the 3D columns, the same cells as the dynamics command's
    with open(tmp_path / "run" / "trajectory.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["time_s", *extra]
    assert rows[1:] == [[r[0], *r[4:]] for r in dyn[1:]]
