"""The 3D ball inside the spherical shell (issue #32): the cavity's concave sphere as the
contact surface (gap a - R - |c|, normal along the radius, R_e = R a / (a - R)), split
by the contact point's height into the lower electrode, the band and the upper electrode;
and the tube's 3D model through the same cell route, unchanged."""
import math

import numpy as np
import pytest

from tengfield.dynamics import simulate
from tengfield.dynamics.motion3d import integrate_3d, simulate_3d
from tengfield.dynamics.motion3d.contact import (KN, cell_surfaces, effective_modulus,
                                                 surface_parameters)
from tengfield.field.cells import cell_of
from tengfield.field.cells.contact_surfaces import (CEILING, CYLINDER, FLOOR, SPHERE,
                                                    contact_surfaces)
from tengfield.scene import G, Scene, default_scene

SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 20.0, "shell_thickness_mm": 2.0,
         "electrode_band_mm": 2.0, "ball_diameter_mm": 8.0}
A, R = 10e-3, 4e-3          # cavity and ball radius [m]


def shell(contact=None, excitation=None, device=None, run=None):
    data = {"device": {**SHELL, **(device or {})}, "contact": {"model": "3d", **(contact or {})},
            "excitation": excitation or {"amplitude_mm": 0.0}}
    if run:
        data["run"] = run
    return Scene.from_dict(data)


def test_the_cells_give_the_walls():
    """The shell: one sphere (centre a above the bottom, radius a) in three zones of the
    contact point's height (lower electrode <= -w/2 < band < w/2 <= upper); the tube: the
    two planes and the cylinder, with the numbers the kernel read before (the scene's)."""
    s = contact_surfaces(cell_of(shell()))
    assert s.names == ("lower", "upper", "band") and s.spherical
    table = s.table()
    assert np.all(table[:, 0] == SPHERE)
    np.testing.assert_array_equal(table[:, 1:3], [[A, A]] * 3)
    w = 1e-3
    assert table[0, 4] == -w and table[1, 3] == w
    assert -w < table[2, 3] < table[2, 4] < w
    assert [x.material for x in s.surfaces] == ["plate", "plate", "wall"]
    assert s.clearance == pytest.approx(A - R) and s.height == pytest.approx(2 * A)
    tube = default_scene()
    t = contact_surfaces(cell_of(tube))
    assert t.names == ("lower", "upper", "wall") and not t.spherical
    assert list(t.table()[:, 0]) == [FLOOR, CEILING, CYLINDER]
    assert t.table()[1, 1] == tube.device.plate_spacing
    assert t.table()[2, 1] == tube.device.tube_inner_radius


def test_hertz_radius_inside_the_concave_sphere_and_the_materials():
    """k_n = 4/3 E* sqrt(R_e), R_e = R a / (a - R): the plate's material on the
    electrodes, the wall's on the band."""
    scene = shell()
    c = scene.contact
    S = surface_parameters(scene)
    r_e = R * A / (A - R)
    plate = effective_modulus(c.ball_youngs_modulus, c.ball_poisson_ratio,
                              c.plate_youngs_modulus, c.plate_poisson_ratio)
    wall = effective_modulus(c.ball_youngs_modulus, c.ball_poisson_ratio,
                             c.wall_youngs_modulus, c.wall_poisson_ratio)
    assert S[0, KN] == pytest.approx(4 / 3 * plate * math.sqrt(r_e), rel=1e-14)
    assert S[1, KN] == S[0, KN]
    assert S[2, KN] == pytest.approx(4 / 3 * wall * math.sqrt(r_e), rel=1e-14)


def test_energy_is_conserved_and_the_ball_stays_in_the_cavity():
    """Restitution 1, no friction, still shell: a ball thrown off-centre bounces on the
    lower and upper electrodes and the band; between contacts its energy stays within
    1e-6 (default resolution) and converges as RK4; |c| never exceeds a - R by more than
    the Hertz penetration of the fastest possible normal impact; the spin never changes."""
    scene = shell(contact={"restitution": 1.0, "friction_static": 0.0,
                           "friction_dynamic": 0.0})
    m = scene.device.ball_mass
    p0 = np.array([2e-3, -1e-3, A + 3e-3])
    v0 = np.array([0.4, 0.3, 0.2])
    spin0 = (5.0, -3.0, 2.0)
    drift = []
    for steps in (32, 64, 128):
        status, knots, episodes, *_ = integrate_3d(scene, t_start=0.0, t_end=0.5, position0=p0,
                                                   velocity0=v0, spin0=spin0, steps=steps)
        assert status == 0
        flight = knots[knots[:, 10] == 0.0]
        energy = (0.5 * m * np.sum(flight[:, 4:7] ** 2, axis=1)
                  + 0.2 * m * R * R * np.sum(flight[:, 7:10] ** 2, axis=1) + m * G * flight[:, 3])
        drift.append(np.ptp(energy) / energy[0])
        np.testing.assert_allclose(knots[-1, 7:10], spin0, rtol=0, atol=1e-12)
    counts = np.bincount(episodes[:, 0].astype(int), minlength=3)
    print(f"contacts lower/upper/band {counts}, energy drift {drift}")
    assert np.all(counts >= 2)
    assert drift[1] < 1e-6 and drift[2] < drift[1] < drift[0]
    # the deepest penetration: all the energy (from the bottom) into one normal impact
    e_max = 0.5 * m * v0 @ v0 + m * G * 2 * A
    kn = surface_parameters(scene)[:, KN].min()
    allowed = (1.25 * e_max * 2 / kn) ** 0.4       # (5 m v^2 / 4 k)^(2/5)
    radius = np.linalg.norm(knots[:, 1:4] - [0.0, 0.0, A], axis=1)
    print(f"max |c| - (a - R) = {np.max(radius) - (A - R):.3g} m, allowed {allowed:.3g} m")
    assert np.max(radius) - (A - R) <= allowed
    assert np.max(radius) - (A - R) > 0.0   # it did touch


@pytest.mark.parametrize("mu, factor", [(0.3, 7.0 / 5.0), (0.0, 1.0)])
def test_a_ball_released_at_the_side_oscillates_as_a_pendulum(mu, factor):
    """Released from rest 0.1 rad up the side of a still cavity, the ball rolls about the
    bottom with T = 2 pi sqrt(7 (a - R) / (5 g)) (rolling without slipping); without
    friction it slides with the point pendulum's T = 2 pi sqrt((a - R) / g). The small
    amplitude correction (1 + theta^2 / 16) is 6e-4: within 0.3 %."""
    scene = shell(contact={"friction_static": mu, "friction_dynamic": mu})
    theta = 0.1
    p0 = np.array([(A - R) * math.sin(theta), 0.0, A - (A - R) * math.cos(theta)])
    status, knots, episodes, *_ = integrate_3d(scene, t_start=0.0, t_end=0.8, position0=p0,
                                               velocity0=np.zeros(3))
    assert status == 0
    assert set(episodes[:, 0].astype(int)) == {0}     # on the lower electrode throughout
    t, x = knots[:, 0], knots[:, 1]
    i = np.flatnonzero((x[:-1] > 0) & (x[1:] <= 0))
    crossings = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    period = np.mean(np.diff(crossings))
    expected = 2 * math.pi * math.sqrt(factor * (A - R) / G)
    print(f"mu = {mu}: T = {period:.6f} s, expected {expected:.6f} s "
          f"({period / expected - 1:+.2e}), {len(crossings)} crossings")
    assert len(crossings) >= 4
    assert period == pytest.approx(expected, rel=3e-3)
    if mu > 0:   # rolling: after the landing (1e-4 m of fall) the contact point does not
        # slip, v + w x (R n) = 0 (n: outward radial), to the tangential spring's microslip
        v, w = knots[:, 4:7], knots[:, 7:10]
        c = knots[:, 1:4] - [0.0, 0.0, A]
        slip = np.linalg.norm(v + np.cross(w, R * c / np.linalg.norm(c, axis=1,
                                                                      keepdims=True)), axis=1)
        assert np.max(slip[t > 0.01]) < 1e-4 * np.max(np.linalg.norm(v, axis=1))


SMALL = {"cavity_diameter_mm": 10.0, "shell_thickness_mm": 1.5, "electrode_band_mm": 1.0,
         "ball_diameter_mm": 7.0}
DRIVE = {"frequency_hz": 20.0, "amplitude_mm": 1.5}


@pytest.mark.parametrize("restitution, tolerance", [(0.1, 0.01), (0.6, 0.03)])
def test_vertical_drive_on_the_axis_is_the_impact_models_motion(restitution, tolerance):
    """A 10 mm shell with the paper's 7 mm ball (stroke 3 mm), 1.5 mm / 20 Hz vertical
    drive: the ball stays on the axis, touches no band, and its gap follows the 1-D
    impact map's within a fraction of the stroke (0.26 % and 1.6 % observed; the
    compliant contact lasts ~0.1 ms), the plates hit in the same order within 1 ms."""
    run = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 5000.0}
    scenes = {model: shell(contact={"model": model, "restitution": restitution},
                           device=SMALL, excitation=DRIVE, run=run)
              for model in ("impact", "3d")}
    one, three = simulate(scenes["impact"]), simulate(scenes["3d"])
    stroke = scenes["3d"].device.stroke
    assert stroke == pytest.approx(3e-3)
    assert np.all(three.x == 0.0) and np.all(three.y == 0.0) and three.wall_contacts == 0
    error = np.max(np.abs(three.gap - one.gap))
    print(f"e = {restitution}: max |dz| = {error:.3g} m ({error / stroke:.2%} of the stroke), "
          f"{len(one.impacts)} vs {len(three.impacts)} impacts")
    assert error < tolerance * stroke
    assert np.max(one.gap) > 0.5 * stroke
    if restitution > 0.5:   # no chatter: the same impacts, one by one
        assert len(one.impacts) == len(three.impacts)
        assert list(one.impacts.plate) == list(three.impacts.plate)
        np.testing.assert_allclose(three.impacts.time, one.impacts.time, atol=1e-3)


def test_vertical_drive_on_the_axis_equals_the_tube_with_the_power_law():
    """With the power law (no contact radius) the shell's bottom and top on the axis are the
    tube's plates: the same 3D trajectory to rounding."""
    run = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000.0}
    law = {"law": "power", "restitution": 0.6}
    sh = simulate_3d(shell(contact=law, device=SMALL, excitation=DRIVE, run=run))
    tube = simulate_3d(default_scene().with_values(contact={"model": "3d", **law},
                                                   excitation=DRIVE, run=run))
    assert len(sh.impacts) == len(tube.impacts) > 5
    np.testing.assert_allclose(sh.gap, tube.gap, rtol=0, atol=1e-9)


def test_lateral_drive_rolls_and_bounces_around_the_cavity():
    """A 3-axis drive: the ball leaves the axis, touches the band, bounces on both
    electrodes, spins; it never leaves the cavity by more than microns."""
    scene = shell(excitation={"frequency_hz": 20.0, "amplitude_mm": 3.0, "amplitude_x_mm": 1.0,
                              "amplitude_y_mm": 0.5, "phase_x_deg": 60.0, "phase_y_deg": 20.0},
                  run={"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 5000.0})
    r = simulate_3d(scene)
    surfaces = set(r.contacts["surface"])
    print(r.summary, np.unique(r.contacts["surface"], return_counts=True))
    assert {"lower", "upper", "band"} <= surfaces and "wall" not in surfaces
    assert r.wall_contacts == np.count_nonzero(r.contacts["surface"] == "band") > 0
    assert r.surface_names == ("lower", "upper", "band")
    centre = np.column_stack([r.x, r.y, r.gap + R - A])
    assert np.max(np.linalg.norm(centre, axis=1)) <= A - R + 2e-5
    assert np.max(r.radial) > 0.5 * (A - R)
    assert r.summary["max_spin_rad_per_s"] > 10.0
    assert set(r.impacts.plate) == {"lower", "upper"}
    # an impact comes from flight (approaching); most electrode episodes here start by
    # sliding across a rim from the band, and those are not impacts
    c = r.contacts
    crossed = np.isin(c["time_in"], c["time_out"][np.isfinite(c["time_out"])])
    assert np.count_nonzero(crossed & (c["surface"] != "band")) > len(r.impacts) > 5
    assert not np.any(np.isin(r.impacts.time, c["time_out"]))
    assert np.all(r.impacts.speed_before > 0.0)


def test_the_honeycomb_has_no_3d_walls_yet():
    with pytest.raises(Exception, match=r"hexagonal"):
        cell_surfaces(Scene.from_dict({"device": {"shape": "hexagonal"},
                                       "contact": {"model": "3d"}, "field": {"method": "3d"}}))


def test_the_tubes_3d_motion_is_the_one_before_the_cell_route():
    """The tube's walls now come from its cell (contact_surfaces): a 3-axis run gives the
    numbers of the model that read the tube's attributes (commit 6631751; measured: the
    whole trajectory and contacts of this run, a vertical and a power-law tilted run
    identical to the bit). Pinned: the first impacts and wall contacts (before chaos
    could amplify a platform's rounding)."""
    scene = default_scene().with_values(
        contact={"model": "3d"},
        run={"duration_s": 0.03, "settle_periods": 0, "sample_rate_hz": 5000.0},
        excitation={"frequency_hz": 30.0, "amplitude_mm": 3.0, "amplitude_x_mm": 0.5,
                    "amplitude_y_mm": 0.3, "phase_x_deg": 30.0})
    r = simulate_3d(scene)
    assert r.surface_names == ("lower", "upper", "wall") and r.cavity_radius == 0.0
    assert r.tube_clearance == scene.device.tube_inner_radius - scene.device.ball_radius
    np.testing.assert_allclose(r.impacts.time[:3], [0.010994838532535443, 0.012801662086455255,
                                                    0.02628877233774488], rtol=1e-12)
    wall = r.contacts["time_in"][r.contacts["surface"] == "wall"][:2]
    np.testing.assert_allclose(wall, [0.008154143176408045, 0.00957134727221344], rtol=1e-12)


@pytest.mark.parametrize("which", ["shell", "tube"])
def test_the_kernels_gaps_and_normals_are_the_cells(which):
    """For centres all over the cavity the compiled kernel's largest overlap is minus the
    cell's ``wall_distance`` and its normal minus the cell's ``wall_normal`` (the Cell
    protocol's 3D contact geometry); in the shell exactly one zone holds the contact
    point, the one ``electrode_at`` names."""
    from tengfield.dynamics.motion3d import _kernel

    scene = shell() if which == "shell" else default_scene().with_values(contact={"model": "3d"})
    cell = cell_of(scene)
    surfaces = cell_surfaces(scene)
    radius = scene.device.ball_radius
    P = np.concatenate([[scene.device.ball_mass, radius, 0.0, surfaces.height,
                         surfaces.surfaces[2].concave_radius, 0.0, 0.0, -G],
                        surfaces.table().ravel()])
    rng = np.random.default_rng(7)
    reach = surfaces.clearance + 5e-5   # into the wall by up to 50 µm too
    half_stroke = 0.5 * scene.device.stroke + 5e-5
    for _ in range(200):
        if which == "shell":
            direction = rng.normal(size=3)
            centre = direction / np.linalg.norm(direction) * reach * rng.uniform() ** (1 / 3)
        else:
            centre = rng.uniform(-1.0, 1.0, 3) * [reach / 1.5, reach / 1.5, half_stroke]
        y = np.zeros(_kernel.N_STATE)
        y[0:3] = centre + [0.0, 0.0, surfaces.shift]
        d = _kernel.overlaps(y, P)
        k = int(np.argmax(d))
        assert d[k] == pytest.approx(-cell.wall_distance(centre), abs=1e-15)
        _, nx, ny, nz = _kernel._geometry(k, y[0:3], radius, P)
        np.testing.assert_allclose([nx, ny, nz], -cell.wall_normal(centre), atol=1e-12)
        if which == "shell":
            touched = np.flatnonzero(d > -A)   # the zone holding the contact point
            assert touched.size == 1
            point_z = A * centre[2] / np.linalg.norm(centre)
            assert surfaces.names[touched[0]] == (cell.electrode_at(point_z) or "band")
