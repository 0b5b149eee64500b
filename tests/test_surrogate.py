"""Surrogate: sampling, honest error estimate, exact derivatives, HDF5 file and cache."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

from tengfield import surrogate, terminals
from tengfield.surrogate import SurrogateError

h5py = surrogate._import_h5py()   # the build that coexists with dolfinx if it is loaded

sys.path.insert(0, str(Path(__file__).parent))
import test_pipeline_fixtures as fx  # noqa: E402

SOLVE_COMM = object()   # the analytic model needs no communicator


def model_table(scene, **kw):
    return surrogate.precompute(scene, solve=fx.plate_model_solve, solve_comm=SOLVE_COMM, **kw)


def model_terminals(scene, z, reference):
    c_ll, c_lu, c_uu, q_l, q_u = fx.plate_model(scene, z)
    c_t = terminals.terminal_capacitance(c_ll, c_lu, c_uu, reference)
    q0 = terminals.upper_short_circuit_charge(*fx.plate_model(scene, 0.0),
                                              scene.device.ball_charge, reference)
    q = terminals.upper_short_circuit_charge(c_ll, c_lu, c_uu, q_l, q_u,
                                             scene.device.ball_charge, reference) - q0
    return q, c_t


def test_lobatto_positions_are_nested_and_clustered_at_both_ends():
    coarse = surrogate.lobatto_positions(3e-3, 9)
    fine = surrogate.lobatto_positions(3e-3, 17)
    np.testing.assert_allclose(fine[::2], coarse, atol=1e-18)
    np.testing.assert_allclose(surrogate.refinement_positions(3e-3, 9), fine[1::2])
    assert coarse[0] == 0.0 and coarse[-1] == 3e-3
    steps = np.diff(fine)
    assert steps[0] < steps[len(steps) // 2] / 5 and steps[-1] < steps[len(steps) // 2] / 5
    np.testing.assert_allclose(fine + fine[::-1], 3e-3, atol=1e-18)  # symmetric


@pytest.mark.parametrize("tolerance", [1e-2, 1e-4, 1e-6])
def test_error_estimate_is_honest(tolerance):
    """The held-out estimate bounds the true interpolation error (dense check)."""
    scene = fx.scene_with(field={"tolerance": tolerance})
    table = model_table(scene, max_positions=257)
    assert table.converged and table.interpolation_error <= tolerance
    z = np.linspace(0, scene.device.stroke, 2001)
    for reference in terminals.REFERENCES:
        curves = table.curves(reference)
        q, c_t = model_terminals(scene, z, reference)
        err_q = np.abs(curves.charge(z) - q).max() / np.abs(q).max()
        err_c = np.abs(curves.capacitance(z) - c_t).max() / c_t.max()
        err_v = np.abs(curves.voltage(z) - q / c_t).max() / np.abs(q / c_t).max()
        assert max(err_q, err_c, err_v) <= table.interpolation_error
    # refinement history: the estimate falls with more positions (4th-order splines)
    counts, estimates = np.array(table.error_history).T
    if len(counts) >= 2:
        assert np.all(np.diff(estimates) < 0)


def test_held_out_estimate_is_tight_for_the_set_it_belongs_to():
    """The estimate of the 9-position interpolant vs its dense true error."""
    scene = fx.scene_with(field={"tolerance": 1e-4})
    table = model_table(scene)
    coarse_count, coarse_estimate = table.error_history[0]
    coarse = model_table(scene.with_values(field={"tolerance": 0.5}))
    keep = np.isin(coarse.positions, surrogate.lobatto_positions(scene.device.stroke, coarse_count))
    coarse = surrogate.SurrogateTable(**{**coarse.__dict__, **{
        k: getattr(coarse, k)[keep] for k in ("positions", "capacitance", "induced_charge", "dofs",
                                              "cells", "wall_time", "solve_time", "field_error")}})
    z = np.linspace(0, scene.device.stroke, 4001)
    true = 0.0
    for reference in terminals.REFERENCES:
        curves = coarse.curves(reference)
        q, c_t = model_terminals(scene, z, reference)
        true = max(true, np.abs(curves.charge(z) - q).max() / np.abs(q).max(),
                   np.abs(curves.capacitance(z) - c_t).max() / c_t.max(),
                   np.abs(curves.voltage(z) - q / c_t).max() / np.abs(q / c_t).max())
    assert coarse_estimate <= true * 1.001 and true <= 3.0 * coarse_estimate


def test_unreachable_tolerance_warns_and_flags_not_converged():
    scene = fx.scene_with(field={"tolerance": 1e-8})
    with pytest.warns(RuntimeWarning, match="above"):
        table = model_table(scene, max_positions=17)
    assert not table.converged and table.count == 17


def test_curves_reference_state_and_exact_derivative():
    scene = fx.scene_with(field={"tolerance": 1e-6})
    table = model_table(scene, max_positions=257)
    curves = table.curves("floating")
    assert curves.charge(0.0) == 0.0
    # PTFE (negative) ball rising: Q_SC > 0 and V_OC > 0 (terminals.py convention)
    z = np.linspace(0.1e-3, scene.device.stroke, 50)
    assert np.all(curves.charge(z) > 0) and np.all(curves.voltage(z) > 0)
    # derivative of the spline vs the model's derivative (central difference of the model)
    h = 1e-9
    q_plus, _ = model_terminals(scene, z + h, "floating")
    q_minus, _ = model_terminals(scene, z - h, "floating")
    np.testing.assert_allclose(curves.charge_derivative(z), (q_plus - q_minus) / (2 * h),
                               rtol=1e-4)


def test_grounded_lower_reference_uses_c_uu():
    scene = fx.scene_with()
    table = model_table(scene)
    _, c_t = surrogate.terminal_samples(table, "grounded-lower")
    np.testing.assert_allclose(c_t, table.capacitance[:, 1, 1])
    with pytest.raises(ValueError, match="reference"):
        table.curves("grounded-upper")


def test_file_round_trip_is_atomic_and_complete(tmp_path):
    scene = fx.scene_with()
    table = model_table(scene, command_line="tengfield precompute")
    path = surrogate.write_table(tmp_path / "s.h5", table)
    assert [p.name for p in tmp_path.iterdir()] == ["s.h5"]   # no temporary left behind
    back = surrogate.read_table(path, expected_hash=scene.field_hash())
    np.testing.assert_array_equal(back.positions, table.positions)
    np.testing.assert_array_equal(back.capacitance, table.capacitance)
    np.testing.assert_array_equal(back.induced_charge, table.induced_charge)
    assert back.interpolation_error == table.interpolation_error
    assert back.provenance["command_line"] == "tengfield precompute"
    assert "gmsh" in back.provenance["versions"]
    with h5py.File(path) as f:
        assert f.attrs["complete"] and "[device]" in f.attrs["scene_text"]


def test_cache_hit_miss_partial_and_corrupt(tmp_path):
    scene = fx.scene_with()
    solver = fx.CountingSolver()
    kw = dict(cache_dir=tmp_path, solve=solver)
    first, outcome = surrogate.obtain_table(scene, **kw)
    assert outcome.status == "computed" and solver.calls == (first.count + 1) // 2  # mirror
    calls = solver.calls
    # excitation, contact and circuit changes keep the field hash: hit
    other = scene.with_values(excitation={"frequency_hz": 35.0}, contact={"restitution": 0.3},
                              circuit={"kind": "load", "reference": "grounded-lower"})
    again, outcome = surrogate.obtain_table(other, **kw)
    assert outcome.status == "cached" and solver.calls == calls
    np.testing.assert_array_equal(again.capacitance, first.capacitance)
    # a field-relevant change: miss, a new file
    moved = scene.with_values(device={"surface_charge_uC_per_m2": -5.0})
    _, outcome = surrogate.obtain_table(moved, **kw)
    assert outcome.status == "computed" and solver.calls > calls
    assert len(list(tmp_path.glob("surrogate-*.h5"))) == 2
    # partial file (completeness flag unset): warning + recompute
    path = surrogate.cache_path(scene, tmp_path)
    with h5py.File(path, "r+") as f:
        f.attrs["complete"] = False
    calls = solver.calls
    with pytest.warns(RuntimeWarning, match="partial"):
        _, outcome = surrogate.obtain_table(scene, **kw)
    assert outcome.status == "recomputed" and solver.calls > calls
    # corrupt file (truncated): warning + recompute, then trusted again
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 3])
    with pytest.warns(RuntimeWarning, match="corrupt"):
        _, outcome = surrogate.obtain_table(scene, **kw)
    assert outcome.status == "recomputed"
    _, outcome = surrogate.obtain_table(scene, **kw)
    assert outcome.status == "cached"


def test_read_rejects_foreign_hash(tmp_path):
    scene = fx.scene_with()
    path = surrogate.write_table(tmp_path / "s.h5", model_table(scene))
    with pytest.raises(SurrogateError, match="field hash"):
        surrogate.read_table(path, expected_hash="0" * 64)


def test_default_cache_dir_follows_environment(monkeypatch, tmp_path):
    monkeypatch.delenv("TENGFIELD_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert surrogate.default_cache_dir() == tmp_path / "xdg" / "tengfield"
    monkeypatch.setenv("TENGFIELD_CACHE_DIR", str(tmp_path / "mine"))
    assert surrogate.default_cache_dir() == tmp_path / "mine"
    monkeypatch.delenv("TENGFIELD_CACHE_DIR")
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert surrogate.default_cache_dir() == Path(os.path.expanduser("~")) / ".cache" / "tengfield"


def test_mirror_symmetry_halves_the_solves_and_matches_a_full_run():
    scene = fx.scene_with(field={"tolerance": 1e-5})
    z = np.linspace(0, scene.device.stroke, 7)
    c_ll, c_lu, c_uu, q_l, q_u = fx.plate_model(scene, z)     # the model is symmetric too
    np.testing.assert_allclose(c_ll, c_uu[::-1])
    np.testing.assert_allclose(q_l, q_u[::-1])
    solver = fx.CountingSolver()
    half = surrogate.precompute(scene, solve=solver, solve_comm=SOLVE_COMM)
    assert half.provenance["mirror_symmetry"]
    assert solver.calls == (half.count + 1) // 2          # lower half incl. the midpoint
    # a grounded table breaks the symmetry: every position is solved
    solver = fx.CountingSolver()
    full = surrogate.precompute(scene.with_values(field={"environment": "grounded-table"}),
                                solve=solver, solve_comm=SOLVE_COMM)
    assert solver.calls == full.count == half.count
    np.testing.assert_allclose(half.capacitance, full.capacitance, rtol=1e-12)
    np.testing.assert_allclose(half.induced_charge, full.induced_charge, rtol=1e-12)


def test_contact_first_order():
    z = surrogate.lobatto_positions(3e-3, 17)
    order = surrogate.contact_first_order(z, 3e-3)
    assert sorted(order) == list(range(z.size))
    distance = np.minimum(z, 3e-3 - z)[order]
    assert np.all(np.diff(distance) >= 0) and distance[0] == 0.0
