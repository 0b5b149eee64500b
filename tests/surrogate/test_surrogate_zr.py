"""The (z, r) surrogate of an off-axis ball: sampling, honest error estimate, symmetry
(mirror in z, d/dr = 0 on the axis), exact derivatives, HDF5 file and cache, MPI farm,
and one small real 3D check (r = 0 against the axisymmetric solver)."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from tengfield import electrical, surrogate, terminals
from tengfield.surrogate import SurrogateError

h5py = surrogate._import_h5py()

import plate_model as fx
from zr_model import zr_model, zr_model_solve

SOLVE_COMM = object()   # the analytic model needs no communicator


class Counting:
    def __init__(self):
        self.points = []

    def __call__(self, scene, position, *, comm=None, offset=0.0, **kw):
        self.points.append((position, offset, kw.get("estimate_error")))
        return zr_model_solve(scene, position, comm=comm, offset=offset, **kw)


def model_terminals(scene, z, r, reference):
    ball = scene.device.ball_charge
    c_ll, c_lu, c_uu, q_l, q_u = zr_model(scene, z, r)
    c_t = terminals.terminal_capacitance(c_ll, c_lu, c_uu, reference)
    q0 = terminals.upper_short_circuit_charge(*zr_model(scene, 0.0, 0.0), ball, reference)
    q = terminals.upper_short_circuit_charge(c_ll, c_lu, c_uu, q_l, q_u, ball, reference) - q0
    return q, c_t


def table_of(scene, solve=zr_model_solve, **kw):
    kw.setdefault("tolerance", 1e-3)
    kw.setdefault("max_positions", 129)
    kw.setdefault("max_offsets", 33)
    return surrogate.precompute_radial(scene, solve=solve, solve_comm=SOLVE_COMM, **kw)


SCENE = fx.scene_with()
Q = SCENE.device.ball_charge      # the ball's charge [C] the curves are drawn for
STROKE = SCENE.device.stroke
R_MAX = surrogate.max_offset(SCENE.device)


def dense(scene, n=81):
    z = np.linspace(0.0, scene.device.stroke, n)
    r = np.linspace(0.0, surrogate.max_offset(scene.device), n // 2)
    return np.meshgrid(z, r, indexing="ij")


def true_error(table, scene):
    zz, rr = dense(scene)
    worst = 0.0
    for reference in terminals.REFERENCES:
        curves = table.curves(reference, scene.device.ball_charge)
        q, c_t = model_terminals(scene, zz, rr, reference)
        worst = max(worst, np.abs(curves.charge(zz, rr) - q).max() / np.abs(q).max(),
                    np.abs(curves.capacitance(zz, rr) - c_t).max() / c_t.max(),
                    np.abs(curves.voltage(zz, rr) - q / c_t).max() / np.abs(q / c_t).max())
    return worst


# ---------------------------------------------------------------------------
def test_offsets_are_nested_and_lobatto_in_r_squared():
    r2, r3, r5 = (surrogate.offset_positions(R_MAX, n) for n in (2, 3, 5))
    np.testing.assert_array_equal(r2, [0.0, R_MAX])
    np.testing.assert_allclose(r3[::2], r2, atol=1e-18)
    np.testing.assert_allclose(r5[::2], r3, atol=1e-18)
    np.testing.assert_allclose(surrogate.offset_refinement(R_MAX, 3), r5[1::2])
    np.testing.assert_allclose(r3[1]**2, 0.5 * R_MAX**2)          # the middle in s = r²
    s = r5**2   # Chebyshev-Lobatto in s: symmetric about s_max / 2
    np.testing.assert_allclose(s + s[::-1], R_MAX**2, rtol=1e-12)


@pytest.mark.parametrize("tolerance", [1e-2, 1e-3, 1e-4])
def test_error_estimate_is_honest(tolerance):
    """The held-out estimate bounds the true error of the stored surrogate (dense grid)."""
    table = table_of(SCENE, tolerance=tolerance, max_positions=129, max_offsets=17)
    assert table.converged and table.interpolation_error <= tolerance
    assert true_error(table, SCENE) <= table.interpolation_error


def test_only_the_direction_that_needs_it_is_refined():
    """The model's r-dependence is gentle: r stays coarser than z."""
    table = table_of(SCENE, tolerance=1e-4)
    nz, nr = table.shape
    assert nz >= 33 and nr < nz
    counts = [(a, b) for a, b, _ in table.error_history]
    assert counts[0] == (9, 2)
    estimates = [e for _, _, e in table.error_history]
    assert all(b < a for a, b in zip(estimates, estimates[1:]))


def test_unreachable_tolerance_warns_and_flags_not_converged():
    with pytest.warns(RuntimeWarning, match="above the tolerance"):
        table = table_of(SCENE, tolerance=1e-9, max_positions=17, max_offsets=3)
    assert not table.converged and table.shape == (17, 3)


def test_a_cached_unconverged_table_warns_again(tmp_path):
    """Read back from the cache, a (z, r) table that missed its tolerance warns as it did
    when it was computed (the same line), instead of being silent."""
    import warnings

    kw = dict(cache_dir=tmp_path, solve=zr_model_solve, tolerance=1e-9, max_positions=17,
              max_offsets=3)
    with pytest.warns(RuntimeWarning, match="above the tolerance") as first:
        surrogate.obtain_radial_table(SCENE, **kw)
    with warnings.catch_warnings(record=True) as again:
        warnings.simplefilter("always")
        table, outcome = surrogate.obtain_radial_table(SCENE, **kw)
    assert outcome.status == "cached" and not table.converged
    said = [str(w.message) for w in again if "above the tolerance" in str(w.message)]
    assert said == [str(w.message) for w in first if "above the tolerance" in str(w.message)]
    assert said == [f"(z, r) surrogate: interpolation error estimate "
                    f"{table.interpolation_error:.3g} is above the tolerance 1e-09 after 17 x 3 "
                    "points"]


def test_axis_is_the_one_dimensional_surrogate_and_flat_in_r():
    """r = 0 reproduces the 1-D surrogate of the same solver; dQ/dr = dC/dr = 0 there."""
    table = table_of(SCENE, tolerance=1e-4)
    one_d = surrogate.precompute(SCENE.with_values(field={"tolerance": 1e-4}),
                                 solve=zr_model_solve, solve_comm=SOLVE_COMM)
    z = np.linspace(0.0, STROKE, 301)
    for reference in terminals.REFERENCES:
        zr, line = table.curves(reference, Q), one_d.curves(reference, Q)
        scale = np.abs(line.charge(z)).max()
        assert np.abs(zr.charge(z, 0.0) - line.charge(z)).max() <= 2e-4 * scale
        assert np.abs(zr.capacitance(z, 0.0) - line.capacitance(z)).max() \
            <= 2e-4 * line.capacitance(z).max()
        assert np.all(zr.charge_derivative(z, 0.0)[1] == 0.0)
        assert np.all(zr.capacitance_derivative(z, 0.0)[1] == 0.0)
        # even in r: a small offset changes Q by O(r²), not O(r)
        dq_small = np.abs(zr.charge(z, 1e-2 * R_MAX) - zr.charge(z, 0.0)).max()
        dq_big = np.abs(zr.charge(z, 1e-1 * R_MAX) - zr.charge(z, 0.0)).max()
        assert dq_big > 50.0 * dq_small
    check = surrogate.axis_check(table, one_d)
    assert check["ok"] and check["deviation"] < 1e-12   # same solver on the axis


def test_derivatives_are_those_of_the_interpolant():
    table = table_of(SCENE, tolerance=1e-4)
    curves = table.curves("floating", Q)
    rng = np.random.default_rng(5)
    z = rng.uniform(0.05, 0.95, 40) * STROKE
    r = rng.uniform(0.05, 0.95, 40) * R_MAX
    h = 1e-9
    dq_dz, dq_dr = curves.charge_derivative(z, r)
    dc_dz, dc_dr = curves.capacitance_derivative(z, r)
    np.testing.assert_allclose(dq_dz, (curves.charge(z + h, r) - curves.charge(z - h, r)) / (2 * h),
                               rtol=1e-5, atol=1e-9 * np.abs(dq_dz).max())
    np.testing.assert_allclose(dq_dr, (curves.charge(z, r + h) - curves.charge(z, r - h)) / (2 * h),
                               rtol=1e-4, atol=1e-6 * np.abs(dq_dr).max())
    np.testing.assert_allclose(dc_dr, (curves.capacitance(z, r + h)
                                       - curves.capacitance(z, r - h)) / (2 * h),
                               rtol=1e-4, atol=1e-6 * np.abs(dc_dr).max())
    np.testing.assert_allclose(dc_dz, (curves.capacitance(z + h, r)
                                       - curves.capacitance(z - h, r)) / (2 * h),
                               rtol=1e-4, atol=1e-6 * np.abs(dc_dz).max())
    # against the model itself (the surrogate is accurate to 1e-4)
    q_h = model_terminals(SCENE, z, r + h, "floating")[0]
    q_l = model_terminals(SCENE, z, r - h, "floating")[0]
    model_dr = (q_h - q_l) / (2 * h)
    scale = np.abs(dq_dz).max() * STROKE / R_MAX
    assert np.abs(dq_dr - model_dr).max() < 1e-2 * scale
    # the reference state: on the lower plate, on the axis
    assert abs(curves.charge(0.0, 0.0)) <= 1e-12 * np.abs(curves.charge_samples).max()


def test_waveforms_current_is_the_total_derivative():
    """I_sc = dQ/dz z' + dQ/dr r' is the time derivative of Q_sc along a path."""
    table = table_of(SCENE, tolerance=1e-4)
    curves = table.curves("floating", Q)
    t = np.linspace(0.0, 0.1, 20001)
    w = 2 * np.pi * 20.0
    gap = 0.5 * STROKE * (1 - np.cos(w * t))
    gap_rate = 0.5 * STROKE * w * np.sin(w * t)
    r = R_MAX * 0.5 * (1 - np.cos(1.7 * w * t))
    r_rate = R_MAX * 0.5 * 1.7 * w * np.sin(1.7 * w * t)
    out = electrical.terminal_waveforms_zr(curves, gap, gap_rate, r, r_rate, cells=3,
                                           parallel_capacitance=1e-12)
    numeric = np.gradient(out["Q_sc"], t)
    inner = slice(5, -5)
    assert np.abs(out["I_sc"] - numeric)[inner].max() < 1e-4 * np.abs(out["I_sc"]).max()
    np.testing.assert_allclose(out["Q_sc"], 3 * curves.charge(gap, r))
    np.testing.assert_allclose(out["V_oc"], out["Q_sc"] / out["C_T"])       # ideal V_OC
    np.testing.assert_allclose(out["V_read"], out["Q_sc"] / (out["C_T"] + 1e-12))  # through C_p
    assert np.abs(out["dC_T_dt"] - np.gradient(out["C_T"], t))[inner].max() \
        < 1e-4 * np.abs(out["dC_T_dt"]).max()
    # the lateral motion alone moves charge
    still = electrical.terminal_waveforms_zr(curves, np.full_like(t, 0.4 * STROKE), 0 * t, r,
                                             r_rate)
    assert np.abs(still["I_sc"]).max() > 0.0


def test_radial_motion_of_a_trajectory():
    class Motion:
        x = np.array([0.0, 3e-4, 0.0])
        y = np.array([0.0, 4e-4, -2e-4])
        velocity = np.array([[1.0, 1.0, 0.0], [0.3, 0.4, 0.2], [5.0, 1.0, 0.0]])
    r, rate = surrogate.radial_motion(Motion)
    np.testing.assert_allclose(r, [0.0, 5e-4, 2e-4])
    np.testing.assert_allclose(rate, [0.0, 0.5, -1.0])


def test_mirror_symmetry_halves_the_solves_and_matches_a_full_run():
    solver = Counting()
    table = table_of(SCENE, solve=solver, tolerance=1e-3)
    assert all(z <= 0.5 * STROKE * (1 + 1e-12) for z, _, _ in solver.points)
    # the model is mirror-symmetric, so the mirrored table equals direct solves
    for i, z in enumerate(table.positions):
        for j, r in enumerate(table.offsets):
            c_ll, c_lu, c_uu, q_l, q_u = zr_model(SCENE, z, r)
            np.testing.assert_allclose(table.capacitance[i, j], [[c_ll, c_lu], [c_lu, c_uu]],
                                       rtol=1e-12)
            np.testing.assert_allclose(table.induced_fraction[i, j], np.array([q_l, q_u]) / Q,
                                       rtol=1e-12)
    nz, nr = table.shape
    assert len(solver.points) == (nz // 2 + 1) * nr
    # z -> stroke - z swaps lower and upper at every offset
    np.testing.assert_allclose(table.capacitance[::-1, :, 1, 1], table.capacitance[:, :, 0, 0],
                               rtol=1e-12)
    np.testing.assert_allclose(table.induced_fraction[::-1, :, 1], table.induced_fraction[:, :, 0],
                               rtol=1e-12)


def test_field_error_is_measured_on_the_axis_and_at_the_wall_only():
    solver = Counting()
    table = table_of(SCENE, solve=solver, tolerance=1e-3)
    asked = [(z, r) for z, r, estimate in solver.points if estimate]
    assert {r for _, r in asked} == {0.0, R_MAX}
    assert len(asked) == 4   # the middle and next to the lower plate, on the axis and at the wall
    assert np.all(table.field_error >= 1e-6)
    assert "axis" in table.provenance["field_error_rule"]


def test_grounded_table_is_not_mirrored():
    scene = fx.scene_with(field={"environment": "grounded-table"})
    solver = Counting()
    table = table_of(scene, solve=solver, tolerance=1e-3)
    assert any(z > 0.5 * STROKE for z, _, _ in solver.points)
    assert len(solver.points) == table.count


def test_file_round_trip_and_checks(tmp_path):
    table = table_of(SCENE, tolerance=1e-3)
    path = surrogate.write_radial_table(tmp_path / "zr.h5", table)
    back = surrogate.read_radial_table(path, expected_hash=table.field_hash)
    np.testing.assert_array_equal(back.capacitance, table.capacitance)
    np.testing.assert_array_equal(back.offsets, table.offsets)
    assert back.error_history == table.error_history
    assert back.interpolation_error == table.interpolation_error
    assert not list(tmp_path.glob(".*.tmp"))   # atomic: no temporary file left
    with pytest.raises(SurrogateError, match="was made for hash"):
        surrogate.read_radial_table(path, expected_hash="0" * 64)
    with pytest.raises(SurrogateError, match="another version of the field solver"):
        surrogate.read_radial_table(path, expected_solver="not-this-one")
    # a 1-D surrogate file is not a (z, r) one, and vice versa
    one_d = surrogate.write_table(tmp_path / "line.h5", surrogate.precompute(
        SCENE, solve=fx.plate_model_solve, solve_comm=SOLVE_COMM))
    with pytest.raises(SurrogateError, match="not a \\(z, r\\) surrogate"):
        surrogate.read_radial_table(one_d)
    with pytest.raises(SurrogateError):
        surrogate.read_table(path)


@pytest.mark.parametrize("name", ["capacitance_F", "induced_fraction", "offsets_m"])
def test_a_changed_array_is_caught(tmp_path, name):
    table = table_of(SCENE, tolerance=1e-3)
    path = surrogate.write_radial_table(tmp_path / "zr.h5", table)
    with h5py.File(path, "r+") as f:
        data = f[name][()]
        flat = data.reshape(-1)
        flat[1] *= 1.001
        f[name][...] = data
    with pytest.raises(SurrogateError, match="checksum"):
        surrogate.read_radial_table(path)


def test_consistent_but_wrong_data_is_not_trusted(tmp_path):
    """Correct checksums, nonsense physics: the structure checks catch it."""
    table = table_of(SCENE, tolerance=1e-3)
    bad = surrogate.RadialTable(**{**table.__dict__})
    bad.capacitance = table.capacitance.copy()
    bad.capacitance[3, 1, 0, 1] *= -1.0           # C_lu > 0 at one off-axis point
    path = surrogate.write_radial_table(tmp_path / "zr.h5", bad)
    with pytest.raises(SurrogateError, match="at offset r = .*positive definite"):
        surrogate.read_radial_table(path)
    bad = surrogate.RadialTable(**{**table.__dict__})
    bad.offsets = table.offsets[::-1].copy()
    path = surrogate.write_radial_table(tmp_path / "zr2.h5", bad)
    with pytest.raises(SurrogateError, match="offsets are not strictly ascending"):
        surrogate.read_radial_table(path)


def test_cache_hit_miss_and_corrupt(tmp_path):
    solver = Counting()
    kw = dict(cache_dir=tmp_path, solve=solver, tolerance=1e-3)
    table, outcome = surrogate.obtain_radial_table(SCENE, **kw)
    assert outcome.status == "computed" and outcome.stored and solver.points
    n = len(solver.points)
    again, outcome = surrogate.obtain_radial_table(SCENE, **kw)
    assert outcome.status == "cached" and len(solver.points) == n
    np.testing.assert_array_equal(again.induced_fraction, table.induced_fraction)
    # another 3D discretisation is another file
    _, outcome = surrogate.obtain_radial_table(SCENE, **{**kw, "mesh_size_mm": 1.0})
    assert outcome.status == "computed"
    # a truncated file is not trusted: one warning, recomputed, replaced
    path = Path(surrogate.radial_cache_path(SCENE, tmp_path, tolerance=1e-3))
    path.write_bytes(path.read_bytes()[:500])
    with pytest.warns(RuntimeWarning, match="not trusted"):
        _, outcome = surrogate.obtain_radial_table(SCENE, **kw)
    assert outcome.status == "recomputed"
    assert surrogate.read_radial_table(path).shape == table.shape


def test_unwritable_cache_warns_and_returns_the_table(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.warns(RuntimeWarning, match="could not be written"):
        table, outcome = surrogate.obtain_radial_table(SCENE, cache_dir=blocker,
                                                       solve=zr_model_solve, tolerance=1e-3)
    assert not outcome.stored and table.converged


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="initial_positions"):
        table_of(SCENE, initial_positions=6)
    with pytest.raises(ValueError, match="initial_offsets"):
        table_of(SCENE, initial_offsets=4)


def test_grounded_table_is_refused_before_any_solve_by_the_3d_solver():
    from tengfield.errors import FieldError

    scene = fx.scene_with(field={"environment": "grounded-table"})
    with pytest.raises(FieldError, match="environment = 'grounded-table'.*allowed 'free-space'"):
        surrogate.precompute_radial(scene)


def test_outside_the_grid_is_clipped():
    curves = table_of(SCENE, tolerance=1e-3).curves("floating", Q)
    assert curves.charge(-1e-3, 0.0) == curves.charge(0.0, 0.0)
    assert curves.charge(STROKE + 1e-3, 2 * R_MAX) == curves.charge(STROKE, R_MAX)
    assert curves.capacitance(1e-3, -1e-4) == curves.capacitance(1e-3, 1e-4)


# ---------------------------------------------------------------------------
@pytest.mark.mpi
def test_two_ranks_equal_serial():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    parallel = surrogate.precompute_radial(SCENE, comm=comm, solve=zr_model_solve, tolerance=1e-4,
                                           max_positions=129, max_offsets=33)
    serial = table_of(SCENE, tolerance=1e-4)
    np.testing.assert_array_equal(parallel.capacitance, serial.capacitance)
    np.testing.assert_array_equal(parallel.induced_fraction, serial.induced_fraction)
    assert parallel.error_history == serial.error_history


# ---------------------------------------------------------------------------
@pytest.mark.slow
def test_real_3d_axis_matches_the_axisymmetric_solver(tmp_path):
    """A small real (z, r) surrogate (degree 1, 2 mm mesh, 5 x 3 grid): the r = 0 column
    agrees with axisymmetric solves within the error estimates; the induced charges
    depend on r only weakly (< 1 %, even in r) and the derived V_OC stays sensible."""
    from mpi4py import MPI

    from tengfield.field import solve_position

    scene = fx.scene_with()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # one round only: may not converge
        table, outcome = surrogate.obtain_radial_table(
            scene, cache_dir=tmp_path, mesh_size_mm=2.0, degree=1, tolerance=0.5,
            initial_positions=3, initial_offsets=2)
    assert table.shape == (5, 3) and table.method == "3d" and outcome.stored
    assert np.all(np.isfinite(table.field_error)) and np.all(table.field_error > 0)
    surrogate.check_radial_table(table)
    axis = [solve_position(scene, float(z), comm=MPI.COMM_SELF, method="axisymmetric",
                           mesh_size_mm=1.0, degree=2) for z in table.positions]
    axis_table = surrogate.table_from_results(axis, stroke=scene.device.stroke)
    check = surrogate.axis_check(table, axis_table)
    assert check["ok"], check
    f = table.induced_fraction
    change = np.abs(f[:, -1] - f[:, 0])
    assert change.max() < 0.02
    curves = table.curves("floating", Q)
    zz = np.linspace(0.0, scene.device.stroke, 7)
    assert np.all(np.diff(curves.charge(zz, 0.5 * R_MAX)) != 0.0)
    assert np.all(curves.charge_derivative(zz, 0.0)[1] == 0.0)
    again, outcome = surrogate.obtain_radial_table(
        scene, cache_dir=tmp_path, mesh_size_mm=2.0, degree=1, tolerance=0.5,
        initial_positions=3, initial_offsets=2)
    assert outcome.status == "cached"


def test_anchored_curves_are_the_axis_on_the_axis_and_the_3d_change_off_it():
    """Anchoring a (z, r) table with a systematic 3D error (here: every C and q 2 % too
    large) to the 1-D surrogate removes that error on the axis and, to first order, off it."""
    def biased(scene, position, **kw):
        res = zr_model_solve(scene, position, **kw)
        res.capacitance = res.capacitance * 1.02
        res.induced_charge = res.induced_charge * 1.02
        res.induced_fraction = res.induced_fraction * 1.02   # what the table reads
        return res

    table = table_of(SCENE, solve=biased, tolerance=1e-4)
    axis = surrogate.precompute(SCENE.with_values(field={"tolerance": 1e-5}),
                                solve=fx.plate_model_solve, solve_comm=SOLVE_COMM)
    zz, rr = dense(SCENE)
    for reference in terminals.REFERENCES:
        plain = table.curves(reference, Q)
        anchored = surrogate.AnchoredTerminalCurves(plain, axis.curves(reference, Q))
        q, c_t = model_terminals(SCENE, zz, rr, reference)
        z = zz[:, 0]
        np.testing.assert_allclose(anchored.charge(z, 0.0), axis.curves(reference, Q).charge(z),
                                   rtol=1e-14, atol=1e-14 * np.abs(q).max())
        err_plain = np.abs(plain.capacitance(zz, rr) - c_t).max() / c_t.max()
        err_anchor = np.abs(anchored.capacitance(zz, rr) - c_t).max() / c_t.max()
        assert err_plain > 1e-2 and err_anchor < 2e-3
        err_q = np.abs(anchored.charge(zz, rr) - q).max() / np.abs(q).max()
        assert err_q < 0.2 * np.abs(plain.charge(zz, rr) - q).max() / np.abs(q).max()
        d_z, d_r = anchored.charge_derivative(zz, rr)
        h = 1e-9
        inner = (slice(None), slice(1, -1))   # the wall clips r + h
        fd = (anchored.charge(zz, rr + h) - anchored.charge(zz, rr - h)) / (2 * h)
        np.testing.assert_allclose(d_r[inner], fd[inner],
                                   atol=1e-4 * np.abs(d_z).max() * STROKE / R_MAX)
        assert np.all(anchored.capacitance_derivative(z, 0.0)[1] == 0.0)
        out = electrical.terminal_waveforms_zr(anchored, zz[:, 3], 0 * z + 1.0, rr[:, 3], 0 * z)
        np.testing.assert_allclose(out["I_sc"], d_z[:, 3])
    with pytest.raises(ValueError, match="references differ"):
        surrogate.AnchoredTerminalCurves(table.curves("floating", Q),
                                         axis.curves("grounded-lower", Q))


def test_radial_motion_at_given_times_and_leaving_the_axis():
    class Motion:
        gap = np.zeros(3)
        radial = np.array([0.0, 1e-7, 3e-4])

        @staticmethod
        def sample3d(times):
            t = np.asarray(times)
            state = np.zeros((t.size, 9))
            state[:, 0], state[:, 1] = 3e-4 * t, -4e-4 * t      # along a ray: r = 5e-4 t
            state[:, 3], state[:, 4] = 3e-4, -4e-4
            return state
    r, rate = surrogate.radial_motion(Motion, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(r, [0.0, 2.5e-4, 5e-4])
    np.testing.assert_allclose(rate, [0.0, 5e-4, 5e-4])
    assert surrogate.leaves_axis(SCENE, Motion)
    Motion.radial = np.array([0.0, 0.4e-3 * R_MAX])
    assert not surrogate.leaves_axis(SCENE, Motion)

    class OneD:
        gap = np.zeros(4)
    assert not surrogate.leaves_axis(SCENE, OneD)
    r_axis = surrogate.radial_motion(OneD)[0]
    assert np.all(r_axis == 0) and r_axis.size == 4
    assert surrogate.radial_motion(OneD, [0.1, 0.2])[1].size == 2
