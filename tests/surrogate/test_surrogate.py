"""Surrogate: sampling, honest error estimate, exact derivatives, HDF5 file and cache."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from tengfield import surrogate, terminals
from tengfield.surrogate import SurrogateError

h5py = surrogate._import_h5py()   # the build that coexists with dolfinx if it is loaded

import plate_model as fx

SOLVE_COMM = object()   # the analytic model needs no communicator
#: for tests about something else whose stand-in or coarse field misses [field] tolerance
#: (the warning itself is tested in test_a_cached_table_that_misses_its_tolerance_warns_again)
FIELD_TOLERANCE_MISSED = ("ignore:surrogate. field error estimate .* is above .field. "
                          "tolerance:RuntimeWarning")


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


@pytest.mark.filterwarnings(FIELD_TOLERANCE_MISSED)
@pytest.mark.parametrize("tolerance", [1e-2, 1e-4, 1e-6])
def test_error_estimate_is_honest(tolerance):
    """The held-out estimate bounds the true interpolation error (dense check)."""
    scene = fx.scene_with(field={"tolerance": tolerance})
    table = model_table(scene, max_positions=257)
    assert table.converged and table.interpolation_error <= tolerance
    z = np.linspace(0, scene.device.stroke, 2001)
    for reference in terminals.REFERENCES:
        curves = table.curves(reference, scene.device.ball_charge)
        q, c_t = model_terminals(scene, z, reference)
        err_q = np.abs(curves.charge(z) - q).max() / np.abs(q).max()
        err_c = np.abs(curves.capacitance(z) - c_t).max() / c_t.max()
        err_v = np.abs(curves.voltage(z) - q / c_t).max() / np.abs(q / c_t).max()
        assert max(err_q, err_c, err_v) <= table.interpolation_error


def test_refinement_history_falls_at_the_spline_order():
    """Several refinement levels (an unreachable tolerance): the held-out estimate falls
    with every doubling, about as h^4 (cubic splines)."""
    scene = fx.scene_with(field={"tolerance": 1e-8})
    with pytest.warns(RuntimeWarning, match="above"):
        table = model_table(scene, max_positions=129)
    counts, estimates = np.array(table.error_history).T
    assert list(counts) == [9, 17, 33, 65]
    assert np.all(np.diff(estimates) < 0)
    rate = -np.polyfit(np.log(counts - 1), np.log(estimates), 1)[0]
    assert 3.0 < rate < 5.0


def test_held_out_estimate_is_tight_for_the_set_it_belongs_to():
    """The estimate of the 9-position interpolant vs its dense true error."""
    scene = fx.scene_with(field={"tolerance": 1e-4})
    table = model_table(scene)
    coarse_count, coarse_estimate = table.error_history[0]
    coarse = model_table(scene.with_values(field={"tolerance": 0.5}))
    keep = np.isin(coarse.positions, surrogate.lobatto_positions(scene.device.stroke, coarse_count))
    coarse = surrogate.SurrogateTable(**{**coarse.__dict__, **{
        k: getattr(coarse, k)[keep] for k in ("positions", "capacitance", "induced_fraction", "dofs",
                                              "cells", "wall_time", "solve_time", "field_error")}})
    z = np.linspace(0, scene.device.stroke, 4001)
    true = 0.0
    for reference in terminals.REFERENCES:
        curves = coarse.curves(reference, scene.device.ball_charge)
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


def test_a_field_error_above_the_tolerance_warns_with_the_position_and_the_keys():
    """The solver's own estimate above [field] tolerance (a mesh too coarse for the device)
    is a warning naming the largest estimate, where, and what to change."""
    import dataclasses

    def coarse_solver(scene, z, *, comm=None, **_):
        result = fx.plate_model_solve(scene, z)
        return dataclasses.replace(result, relative_error_estimate=0.02 + 0.1 * z)

    scene = fx.scene_with(field={"tolerance": 1e-2})
    with pytest.warns(RuntimeWarning) as record:
        table = surrogate.precompute(scene, solve=coarse_solver, solve_comm=SOLVE_COMM)
    messages = [str(w.message) for w in record if "field error estimate" in str(w.message)]
    assert len(messages) == 1
    assert messages[0] == (f"surrogate: field error estimate up to "
                           f"{np.max(table.field_error):.3g} ({table.count} of {table.count} "
                           "positions) is above [field] tolerance = 0.01: lower [field] "
                           "mesh_size_mm or raise degree")
    assert np.max(table.field_error) >= 0.02 + 0.1 * 0.5 * scene.device.stroke
    assert table.converged            # the interpolation itself met the tolerance


def test_a_cached_table_that_misses_its_tolerance_warns_again(tmp_path):
    """Reading an unconverged table from the cache warns as computing it did: a second run
    is not quieter than the first (interpolation and field error estimate alike)."""
    import warnings

    scene = fx.scene_with(field={"tolerance": 1e-8})
    runs = []
    for _ in range(2):
        with warnings.catch_warnings(record=True) as record:
            warnings.simplefilter("always")
            table, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path,
                                                    solve=fx.plate_model_solve)
        runs.append(sorted(str(w.message) for w in record
                           if str(w.message).startswith("surrogate:")))
    assert outcome.status == "cached" and not table.converged
    assert runs[0] == runs[1] and len(runs[1]) == 2
    assert (f"surrogate: interpolation error estimate {table.interpolation_error:.3g} is "
            f"above [field] tolerance = 1e-08 after {table.count} positions (precompute "
            "--max-positions refines further)") in runs[1]
    assert any(m.startswith("surrogate: field error estimate up to") for m in runs[1])


@pytest.mark.filterwarnings(FIELD_TOLERANCE_MISSED)
def test_curves_reference_state_and_exact_derivative():
    scene = fx.scene_with(field={"tolerance": 1e-6})
    table = model_table(scene, max_positions=257)
    curves = table.curves("floating", scene.device.ball_charge)
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


def test_grounded_lower_reference_uses_c_uu(plate_default_scene):
    scene = plate_default_scene
    table = model_table(scene)
    _, c_t = surrogate.terminal_samples(table, "grounded-lower", scene.device.ball_charge)
    np.testing.assert_allclose(c_t, table.capacitance[:, 1, 1])
    with pytest.raises(ValueError, match="reference"):
        table.curves("grounded-upper", scene.device.ball_charge)


def test_file_round_trip_is_atomic_and_complete(tmp_path, plate_default_scene):
    scene = plate_default_scene
    table = model_table(scene, command_line="tengfield precompute")
    path = surrogate.write_table(tmp_path / "s.h5", table)
    assert [p.name for p in tmp_path.iterdir()] == ["s.h5"]   # no temporary left behind
    back = surrogate.read_table(path, expected_hash=scene.field_hash())
    np.testing.assert_array_equal(back.positions, table.positions)
    np.testing.assert_array_equal(back.capacitance, table.capacitance)
    np.testing.assert_array_equal(back.induced_fraction, table.induced_fraction)
    assert back.interpolation_error == table.interpolation_error
    assert back.provenance["command_line"] == "tengfield precompute"
    assert "gmsh" in back.provenance["versions"]
    with h5py.File(path) as f:
        assert f.attrs["complete"] and "[device]" in f.attrs["scene_text"]


def test_cache_hit_miss_partial_and_corrupt(tmp_path, plate_default_scene):
    scene = plate_default_scene
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
    moved = scene.with_values(device={"ball_permittivity": 3.0})
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


def test_read_rejects_foreign_hash(tmp_path, plate_default_scene):
    scene = plate_default_scene
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
    np.testing.assert_allclose(half.induced_fraction, full.induced_fraction, rtol=1e-12)


def test_contact_first_order():
    z = surrogate.lobatto_positions(3e-3, 17)
    order = surrogate.contact_first_order(z, 3e-3)
    assert sorted(order) == list(range(z.size))
    distance = np.minimum(z, 3e-3 - z)[order]
    assert np.all(np.diff(distance) >= 0) and distance[0] == 0.0


def test_positions_with_an_error_estimate_go_first():
    """The estimate positions (a second, finer mesh: the dearest solves) are handed out
    first, the rest closest to a plate first; an empty or unmatched set changes nothing."""
    stroke = 3e-3
    z = surrogate.lobatto_positions(stroke, 17)
    sampled = surrogate.error_sample_positions(stroke, False)
    order = surrogate.contact_first_order(z, stroke, sampled)
    assert sorted(order) == list(range(z.size))
    head, tail = z[order[:sampled.size]], z[order[sampled.size:]]
    np.testing.assert_array_equal(np.sort(head), np.sort(sampled))
    distance = np.minimum(tail, stroke - tail)
    assert np.all(np.diff(distance) >= 0) and distance[0] == 0.0
    np.testing.assert_array_equal(surrogate.contact_first_order(z, stroke, ()),
                                  surrogate.contact_first_order(z, stroke))
    np.testing.assert_array_equal(surrogate.contact_first_order(z, stroke, [1.234]),
                                  surrogate.contact_first_order(z, stroke))


# ---------------------------------------------------------------------------
# one constant for the position counts
def test_position_counts_derive_from_one_constant():
    assert surrogate.INITIAL_POSITIONS == 2 ** surrogate.INITIAL_LEVEL + 1
    assert surrogate.FEWEST_POSITIONS == 2 * surrogate.INITIAL_POSITIONS - 1
    assert surrogate.is_lobatto_count(surrogate.MAX_POSITIONS)
    # a loose tolerance ends with the fewest positions the adaptive surrogate can have
    table = model_table(fx.scene_with(field={"tolerance": 0.5}))
    assert table.count == surrogate.FEWEST_POSITIONS
    assert table.error_history[0][0] == surrogate.INITIAL_POSITIONS


def test_max_positions_zero_is_refused_with_its_range(capsys):
    from tengfield.cli import main

    assert main(["precompute", "--max-positions", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "--max-positions = 0" in err[0]
    assert f"{surrogate.FEWEST_POSITIONS} <= N <= " in err[0]


# ---------------------------------------------------------------------------
# field error estimate: measured next to the ends and at the middle, carried to the rest
class EstimateRecordingSolver:
    """The plate model with a position-dependent field error estimate that it only
    reports when asked to estimate (like the real solver: NaN otherwise)."""

    def __init__(self):
        self.asked = {}

    @staticmethod
    def estimate(scene, z):
        u = z / scene.device.stroke
        return 1e-4 * (1.0 + 0.5 * np.sin(np.pi * u))      # largest at the middle

    def __call__(self, scene, position, *, comm=None, estimate_error=True):
        self.asked[float(position)] = estimate_error
        result = fx.plate_model_solve(scene, position)
        result.relative_error_estimate = self.estimate(scene, position) if estimate_error \
            else float("nan")
        return result


@pytest.mark.filterwarnings(FIELD_TOLERANCE_MISSED)
@pytest.mark.parametrize("environment", ["free-space", "grounded-table"])
def test_field_error_is_measured_next_to_the_ends_and_at_the_middle_only(environment):
    scene = fx.scene_with(field={"tolerance": 1e-5, "environment": environment})
    stroke = scene.device.stroke
    solver = EstimateRecordingSolver()
    table = surrogate.precompute(scene, solve=solver, solve_comm=SOLVE_COMM)
    estimated = sorted(z for z, asked in solver.asked.items() if asked)
    z = surrogate.lobatto_positions(stroke, surrogate.FEWEST_POSITIONS)   # the first batch
    expected = [z[1], 0.5 * stroke] + ([z[-2]] if environment == "grounded-table" else [])
    np.testing.assert_allclose(estimated, expected, atol=1e-15)
    # sampled positions keep their own estimate, every other one gets the largest of
    # those with the margin: never NaN, never below what the solver would have said there
    measured = (1 + surrogate.refinement.FIELD_ERROR_MARGIN) * max(
        solver.estimate(scene, z) for z in expected)
    targets = np.array([z[1], 0.5 * stroke, z[-2]])                    # (or mirror images)
    at_sample = np.min(np.abs(table.positions[:, None] - targets), axis=1) <= 1e-12 * stroke
    np.testing.assert_allclose(table.field_error[at_sample],
                               solver.estimate(scene, table.positions[at_sample]))
    np.testing.assert_array_equal(table.field_error[~at_sample], measured)
    assert np.all(table.field_error >= solver.estimate(scene, table.positions))
    assert "measured at z" in table.provenance["field_error_rule"]
    assert np.max(table.field_error) > np.max(solver.estimate(scene, table.positions))
    # "every" asks for the estimate everywhere and stores the solver's own figures
    solver = EstimateRecordingSolver()
    every = surrogate.precompute(scene, solve=solver, solve_comm=SOLVE_COMM, field_error="every")
    assert all(solver.asked.values())
    np.testing.assert_allclose(every.field_error, solver.estimate(scene, every.positions))
    np.testing.assert_array_equal(every.capacitance, table.capacitance)


def test_solver_without_estimate_keyword_is_called_as_before():
    calls = []

    def solve(scene, z, comm=None):          # e.g. report.verify's cached solver
        calls.append(z)
        return fx.plate_model_solve(scene, z)

    table = surrogate.precompute(fx.scene_with(), solve=solve, solve_comm=SOLVE_COMM)
    assert len(calls) == (table.count + 1) // 2
    np.testing.assert_array_equal(table.field_error, 1e-6)   # the solver's own figure


# ---------------------------------------------------------------------------
# cache faults: warn once, keep the table
def _cache_warnings(record):
    return [w for w in record if issubclass(w.category, RuntimeWarning)
            and "surrogate" in str(w.message)]


@pytest.mark.parametrize("fault", ["cache dir is a file", "cache dir read-only",
                                   "cache path is a directory"])
def test_unwritable_cache_warns_once_and_returns_the_table(tmp_path, monkeypatch, fault,
                                                           plate_default_scene):
    import warnings

    scene = plate_default_scene
    cache_dir = tmp_path / "cache"
    if fault == "cache dir is a file":
        cache_dir.write_text("not a directory")
        named = cache_dir
    elif fault == "cache dir read-only":
        cache_dir.mkdir()
        cache_dir.chmod(0o555)
        if os.geteuid() == 0:   # root writes anyway: the kernel's answer to others
            from tengfield.files import atomic

            def refuse(*args, **kwargs):
                raise PermissionError(13, "Permission denied", str(cache_dir))
            monkeypatch.setattr(atomic.tempfile, "mkstemp", refuse)
        named = surrogate.cache_path(scene, cache_dir)
    else:
        surrogate.cache_path(scene, cache_dir).mkdir(parents=True)
        named = surrogate.cache_path(scene, cache_dir)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        table, outcome = surrogate.obtain_table(scene, cache_dir=cache_dir,
                                                solve=fx.plate_model_solve)
    cache_dir.chmod(0o755) if cache_dir.is_dir() else None
    found = _cache_warnings(record)
    assert len(found) == 1, [str(w.message) for w in record]
    message = str(found[0].message)
    assert str(named) in message and "could not be written" in message
    assert outcome.status == "computed" and not outcome.stored
    reference = model_table(scene)
    np.testing.assert_array_equal(table.capacitance, reference.capacitance)
    assert not any(p.name.endswith(".tmp") for p in tmp_path.rglob("*"))


def test_run_with_an_unwritable_cache_still_gives_waveforms(tmp_path, plate_default_scene):
    from tengfield import pipeline

    blocked = tmp_path / "cache"
    blocked.write_text("a file where the cache directory should be")
    scene = plate_default_scene
    with pytest.warns(RuntimeWarning, match="could not be written"):
        result = pipeline.run(scene, cache_dir=blocked, solve=fx.plate_model_solve,
                              simulate=lambda s: fx.FakeDynamics(s, duration=0.2,
                                                                 sample_rate=2000))
    assert result.table is not None and result.table.count == model_table(scene).count
    assert np.ptp(result.waveforms["V_oc_V"]) > 0.0


# ---------------------------------------------------------------------------
# corruption: never trusted
def _written(tmp_path, scene=None):
    scene = scene or fx.scene_with()
    table = model_table(scene)
    path = surrogate.write_table(tmp_path / "s.h5", table)
    return scene, table, path


def _rewrite(path, name, values, *, rehash):
    """Overwrite dataset ``name`` in place; with ``rehash`` also its stored SHA-256
    (a consistent but wrong file, e.g. a writer bug: only the structure checks catch it)."""
    from tengfield.surrogate import store

    with h5py.File(path, "r+") as f:
        f[name][...] = values
        if rehash:
            f[name].attrs["sha256"] = store.array_digest(f[name][()])


DATASETS = list(surrogate.store.ARRAYS.values()) + ["error_history"]


def test_overwritten_induced_charge_is_not_trusted_and_recomputed(tmp_path, plate_default_scene):
    """The case of the issue: a valid HDF5 file whose q array was scaled gave
    V_OC 5x too large, marked "cached"."""
    scene = plate_default_scene
    solver = fx.CountingSolver()
    table, _ = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=solver)
    path = surrogate.cache_path(scene, tmp_path)
    _rewrite(path, "induced_fraction", 5.0 * table.induced_fraction, rehash=False)
    with pytest.raises(SurrogateError, match="induced_fraction.*checksum"):
        surrogate.read_table(path)
    calls = solver.calls
    with pytest.warns(RuntimeWarning, match=r"cached surrogate .*s?urrogate-.*\.h5 not trusted "
                                            r"\(.*checksum.*\), recomputing"):
        again, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "recomputed" and solver.calls > calls
    np.testing.assert_array_equal(again.induced_fraction, table.induced_fraction)
    _, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "cached"


@pytest.mark.parametrize("name", DATASETS)
def test_a_flipped_bit_in_any_array_is_caught(tmp_path, name):
    """Through HDF5 (Fletcher-32 recomputed on write): the SHA-256 catches it."""
    _, _, path = _written(tmp_path)
    with h5py.File(path, "r") as f:
        data = f[name][()]
    raw = data.copy().view(np.uint8).reshape(-1)
    for byte in (0, raw.size // 2, raw.size - 1):
        for bit in (0, 7):
            flipped = raw.copy()
            flipped[byte] ^= 1 << bit
            _rewrite(path, name, flipped.view(data.dtype).reshape(data.shape), rehash=False)
            with pytest.raises(SurrogateError, match="checksum"):
                surrogate.read_table(path)
    _rewrite(path, name, data, rehash=False)
    surrogate.read_table(path)              # restored: trusted again


def test_flipped_bits_in_the_file_bytes_are_caught(tmp_path):
    """Bits flipped on disk inside each array's stored bytes (below HDF5): every
    flip is refused (Fletcher-32 or SHA-256), none is read as data."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    _, _, path = _written(tmp_path)
    pristine = path.read_bytes()
    extents = {}
    with h5py.File(path, "r") as f:
        for name in DATASETS:
            info = f[name].id.get_chunk_info(0)
            extents[name] = (info.byte_offset, info.size)

    @settings(max_examples=60, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(name=st.sampled_from(DATASETS), where=st.floats(0.0, 1.0, exclude_max=True),
           bit=st.integers(0, 7))
    def flip(name, where, bit):
        offset, size = extents[name]
        data = bytearray(pristine)
        data[offset + int(where * size)] ^= 1 << bit
        path.write_bytes(bytes(data))
        with pytest.raises(SurrogateError, match="corrupt|checksum"):
            surrogate.read_table(path)

    flip()
    path.write_bytes(pristine)
    surrogate.read_table(path)


@pytest.mark.parametrize("damage, reason", [
    ("unsorted", "not strictly ascending"),
    ("duplicate", "not strictly ascending"),
    ("no upper end", "not from 0 to the stroke"),
    ("nan", "not strictly ascending|non-finite"),
    ("C not positive definite", "positive definite"),
    ("C_lu positive", "positive definite"),
    ("charge above the ball's", "induced fractions"),
])
def test_consistent_but_wrong_data_is_not_trusted(tmp_path, damage, reason, plate_default_scene):
    """Checksums recomputed after the damage (a writer bug, not a disk fault): the
    structure checks refuse the file, and a cached copy is recomputed."""
    scene = plate_default_scene
    table, _ = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    path = surrogate.cache_path(scene, tmp_path)
    z, C, q = table.positions.copy(), table.capacitance.copy(), table.induced_fraction.copy()
    name, values = {
        "unsorted": ("positions_m", z[[1, 0, *range(2, z.size)]]),
        "duplicate": ("positions_m", np.concatenate([z[:3], z[2:3], z[4:]])),
        "no upper end": ("positions_m", np.concatenate([z[:-1], [(1 - 1e-4) * z[-1]]])),
        "nan": ("positions_m", np.where(np.arange(z.size) == 4, np.nan, z)),
        "C not positive definite": ("capacitance_F", C * np.array([[1.0, 3.0], [3.0, 1.0]])),
        "C_lu positive": ("capacitance_F", np.abs(C)),
        "charge above the ball's": ("induced_fraction", 3.0 * q),
    }[damage]
    _rewrite(path, name, values, rehash=True)
    with pytest.raises(SurrogateError, match=reason):
        surrogate.read_table(path)
    # what `tengfield precompute` and `tengfield run` consult: never a valid file
    with pytest.warns(RuntimeWarning, match="not trusted"):
        cached, status, _ = surrogate.load_cached(path, scene)
    assert cached is None and status == "recomputed"
    with pytest.warns(RuntimeWarning, match="not trusted"):
        again, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path,
                                                solve=fx.plate_model_solve)
    assert outcome.status == "recomputed"
    np.testing.assert_array_equal(again.positions, table.positions)
    surrogate.read_table(path)     # the recomputed file is trusted


def test_old_format_is_recomputed(tmp_path):
    scene, _, path = _written(tmp_path)
    with h5py.File(path, "r+") as f:
        f.attrs["format_version"] = 1
    with pytest.raises(SurrogateError, match=r"has format version 1, written by another "
                                             r"tengfield version \(this one reads formats 3, \d+\)"):
        surrogate.read_table(path)   # a plain 1 (numpy 2 would print np.int64(1))


def test_scalar_attributes_are_checksummed(tmp_path):
    _, table, path = _written(tmp_path)
    with h5py.File(path, "r+") as f:
        f.attrs["stroke_m"] = 2.0 * table.stroke
    with pytest.raises(SurrogateError, match="scalar"):
        surrogate.read_table(path)


@pytest.mark.field
@pytest.mark.slow
@pytest.mark.filterwarnings(FIELD_TOLERANCE_MISSED)
@pytest.mark.parametrize("environment", ["free-space", "grounded-table"])
def test_sampled_field_error_is_no_looser_than_every_position(environment):
    """The real solver on a coarse device mesh: measuring the field error only next to the
    ends and at the middle (the default) gives the same solves and surrogate error
    estimate as measuring it everywhere (as before), and at every position a field
    error estimate at least as large as that position's own."""
    import pyvista  # noqa: F401 - before dolfinx

    scene = fx.scene_with(field={"mesh_size_mm": 1.5, "degree": 1, "tolerance": 0.05,
                                 "environment": environment})
    every = surrogate.precompute(scene, field_error="every")
    sampled = surrogate.precompute(scene)
    np.testing.assert_array_equal(sampled.positions, every.positions)
    np.testing.assert_array_equal(sampled.capacitance, every.capacitance)
    np.testing.assert_array_equal(sampled.induced_fraction, every.induced_fraction)
    assert sampled.interpolation_error == every.interpolation_error
    assert np.all(np.isfinite(sampled.field_error))
    assert np.all(sampled.field_error >= every.field_error)
    # ... and not much larger: the margin, no more
    margin = 1 + surrogate.refinement.FIELD_ERROR_MARGIN
    assert np.max(sampled.field_error) <= margin * np.max(every.field_error)


@pytest.mark.parametrize("where", ["cache dir is a file", "output is a directory",
                                   "output under a file"])
def test_precompute_refuses_an_unwritable_target_before_any_solve(tmp_path, capsys, where):
    """`tengfield precompute` only exists to write its file: refused up front (one line,
    exit 2) instead of after the solves. (No solver runs: this takes milliseconds.)"""
    from tengfield.cli import main

    blocker = tmp_path / "file"
    blocker.write_text("x")
    args = {"cache dir is a file": ["--cache-dir", str(blocker)],
            "output is a directory": ["-o", str(tmp_path)],
            "output under a file": ["-o", str(blocker / "s.h5")]}[where]
    assert main(["precompute", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    option = "--cache-dir" if where == "cache dir is a file" else "-o"
    assert len(err) == 1 and err[0].startswith(f"tengfield: error: {option} ")
    assert str(blocker if where != "output is a directory" else tmp_path) in err[0]


def test_solver_fingerprint_covers_the_solver_and_not_its_plots(tmp_path, monkeypatch):
    """Plot or file-writing changes keep cached surrogates; a solver change does not."""
    import shutil

    import tengfield.field as field_package
    from tengfield.surrogate.provenance import solver_fingerprint

    names = [p.name for p in field_package.solver_source_paths()]
    assert {"axisymmetric.py", "solver3d.py", "contact.py", "_dolfinx.py"} <= set(names)
    assert not {"plot.py", "io.py"} & set(names)
    copies = []
    for path in field_package.solver_source_paths():
        shutil.copy(path, tmp_path / path.name)
        copies.append(tmp_path / path.name)
    monkeypatch.setattr(field_package, "solver_source_paths", lambda: copies)
    before = solver_fingerprint()
    (tmp_path / "contact.py").write_text((tmp_path / "contact.py").read_text() + "\n# changed\n")
    assert solver_fingerprint() != before
