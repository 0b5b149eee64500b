"""End-to-end pipeline: waveforms, limits, energy balance, skipped stages, CLI runs."""
from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from tengfield import electrical, pipeline, surrogate

import plate_model as fx

ROOT = Path(__file__).resolve().parents[2]
SMALL_SCENE = fx.SMALL_SCENE


def model_run(scene, tmp_path, kind="bounce", **kw):
    return pipeline.run(scene, cache_dir=tmp_path, solve=fx.plate_model_solve,
                        simulate=lambda s: fx.FakeDynamics(s, kind=kind, **kw))


@pytest.fixture
def cli(run_cli, cli_env, tmp_path):
    """``cli(args, extra_env=None)``: the CLI run in tmp_path with its own surrogate cache."""
    def run(args, extra_env=None):
        env = cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true",
                      TENGFIELD_CACHE_DIR=tmp_path / "cache", **(extra_env or {}))
        return run_cli(*args, cwd=tmp_path, env=env, timeout=600)
    return run


@pytest.fixture(scope="module")
def small_run(tmp_path_factory, run_cli, cli_env):
    """(directory, its cache env, CompletedProcess): `tengfield run small.toml -o out1` of
    SMALL_SCENE with a load, figures on, on a cold surrogate cache of its own: the one
    coarse field solve that the end-to-end test checks and the precompute/sweep test then
    finds cached (a load is no field key: SMALL_SCENE alone has the same surrogate)."""
    where = tmp_path_factory.mktemp("small-run")
    (where / "small.toml").write_text(SMALL_SCENE + '\n[circuit]\nkind = "load"\n'
                                      'load_ohm = 1e9\nparallel_capacitance_pF = 5.0\n')
    env = cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true",
                  TENGFIELD_CACHE_DIR=where / "cache")
    return where, env, run_cli("run", "small.toml", "-o", "out1", cwd=where, env=env,
                               timeout=600)


# ---------------------------------------------------------------------------
# physics through the pipeline (analytic field model, prescribed trajectories)
def test_short_circuit_current_integrates_back_to_charge(tmp_path):
    scene = fx.scene_with(run={"sample_rate_hz": 20000.0})
    result = model_run(scene, tmp_path, kind="smooth", duration=0.2)
    w = result.waveforms
    charge = w["Q_sc_C"][0] + cumulative_trapezoid(w["I_sc_A"], w["time_s"], initial=0.0)
    np.testing.assert_allclose(charge, w["Q_sc_C"], atol=1e-5 * np.abs(w["Q_sc_C"]).max())
    # the real impact dynamics: integrate piecewise between impacts on a fine grid
    from tengfield.dynamics import simulate
    dyn = simulate(scene.with_values(run={"duration_s": 0.6}))
    curves = result.curves
    grid = np.linspace(dyn.t[0], dyn.t[-1], 200001)
    hits = dyn.impacts.time
    # each impact twice: the pre-impact state (just before) then the post-impact one
    t_fine = np.concatenate([grid, hits, hits])
    stamp = np.concatenate([grid, hits - 1e-12, hits + 1e-12])
    order = np.lexsort((stamp, t_fine))
    t_fine = t_fine[order]
    gap, vel, _ = dyn.sample(stamp[order])
    current = curves.charge_derivative(gap) * vel
    charge = curves.charge(gap[0]) + cumulative_trapezoid(current, t_fine, initial=0.0)
    scale = np.abs(curves.charge(gap)).max()
    assert np.abs(charge - curves.charge(gap)).max() < 1e-4 * scale


def test_load_limits_reproduce_short_and_open_circuit(tmp_path):
    small = model_run(fx.scene_with(circuit={"kind": "load", "load_ohm": 1.0}), tmp_path)
    w = small.waveforms
    np.testing.assert_allclose(w["I_load_A"][5:], w["I_sc_A"][5:], rtol=0,
                               atol=1e-6 * np.abs(w["I_sc_A"]).max())
    huge = model_run(fx.scene_with(circuit={"kind": "load", "load_ohm": 1e18,
                                            "parallel_capacitance_pF": 10.0}), tmp_path)
    w = huge.waveforms
    # the open terminal read through C_p (V_OC itself is the ideal one, without C_p)
    read = electrical.scene_terminal_waveforms(huge.scene, huge.curves, w["gap_m"],
                                               w["gap_velocity_m_per_s"])["V_read"]
    np.testing.assert_allclose(w["V_load_V"], read, rtol=0, atol=1e-6 * np.abs(read).max())


@pytest.mark.parametrize("load", [1e6, 1e9, 1e12])
def test_energy_balance_with_impacts(tmp_path, load):
    """Work delivered = stored + dissipated energy, with velocity jumps at impacts."""
    scene = fx.scene_with(circuit={"kind": "load", "load_ohm": load})
    result = model_run(scene, tmp_path)
    e = result.summary["load"]["energy_balance_J"]
    assert e["dissipated_energy_J"] > 0
    assert e["delivered_energy_J"] == pytest.approx(
        e["dissipated_energy_J"] + e["stored_energy_change_J"], rel=1e-3)


def test_mean_power_does_not_depend_on_the_output_sampling(tmp_path):
    powers = []
    for rate in (4000.0, 40000.0):
        scene = fx.scene_with(circuit={"kind": "load", "load_ohm": 3e9},
                              run={"sample_rate_hz": rate})
        powers.append(model_run(scene, tmp_path).summary["load"]["mean_power_W"])
    assert powers[0] == pytest.approx(powers[1], rel=2e-3)


def test_power_has_a_maximum_over_load(tmp_path):
    """P(R) rises as R and falls as 1/R: an optimum load in between (Fig. S13)."""
    loads = np.logspace(5, 13, 9)
    powers = [model_run(fx.scene_with(circuit={"kind": "load", "load_ohm": r}), tmp_path)
              .summary["load"]["mean_power_W"] for r in loads]
    best = int(np.argmax(powers))
    assert 0 < best < len(loads) - 1
    np.testing.assert_allclose(powers[1] / powers[0], loads[1] / loads[0], rtol=0.01)
    assert np.all(np.diff(powers[:best + 1]) > 0) and np.all(np.diff(powers[best:]) < 0)


def test_cells_in_parallel_through_the_pipeline(tmp_path):
    one = model_run(fx.scene_with(), tmp_path).summary["peak_to_peak"]
    four = model_run(fx.scene_with(device={"cells": 4}), tmp_path).summary["peak_to_peak"]
    assert four["V_oc_V"] == pytest.approx(one["V_oc_V"], rel=1e-12)
    assert four["Q_sc_C"] == pytest.approx(4 * one["Q_sc_C"], rel=1e-12)
    assert four["I_sc_A"] == pytest.approx(4 * one["I_sc_A"], rel=1e-12)


def test_uncharged_ball_skips_the_field(tmp_path):
    def no_solve(*a, **k):
        raise AssertionError("the field must not be solved")
    scene = fx.scene_with(device={"surface_charge_uC_per_m2": 0.0}, circuit={"kind": "load"})
    result = pipeline.run(scene, cache_dir=tmp_path, solve=no_solve,
                          simulate=lambda s: fx.FakeDynamics(s, kind="bounce"))
    stages = result.summary["stages"]
    assert stages["field"]["status"] == "skipped" and "charge is zero" in stages["field"]["reason"]
    assert not np.any(result.waveforms["V_load_V"])


def test_summary_says_what_ran(tmp_path, plate_default_scene):
    scene = plate_default_scene
    first = model_run(scene, tmp_path).summary
    second = model_run(scene.with_values(excitation={"frequency_hz": 25.0}), tmp_path).summary
    assert first["stages"]["field"]["status"] == "ran"
    assert second["stages"]["field"]["status"] == "cached"
    assert "load ODE not run" in second["stages"]["circuit"]["reason"]
    assert second["load"] is None and "no load" in second["load_reason"]
    assert second["reference"] == "floating"
    json.dumps(second)  # JSON-ready


# ---------------------------------------------------------------------------
# the real stack (dynamics + dolfinx), small scenes
@pytest.mark.slow
@pytest.mark.field
@pytest.mark.filterwarnings("ignore:surrogate. field error estimate:RuntimeWarning")  # coarse
def test_error_estimate_is_honest_against_direct_solves(tmp_path):
    import pyvista  # noqa: F401 - before dolfinx
    from mpi4py import MPI

    from tengfield import terminals
    from tengfield.field import solve_position
    scene = fx.scene_with(field={"mesh_size_mm": 1.5, "degree": 1, "tolerance": 0.05})
    table, _ = surrogate.obtain_table(scene, cache_dir=tmp_path)
    rng = np.random.default_rng(7)
    extra = [solve_position(scene, float(z), comm=MPI.COMM_SELF)
             for z in rng.uniform(0.0, scene.device.stroke, 3)]
    held = surrogate.table_from_results(extra, stroke=scene.device.stroke)
    worst = surrogate.held_out_error(table, held)
    assert worst <= table.interpolation_error
    for reference in terminals.REFERENCES:   # V_OC > 0 for a PTFE ball above z = 0
        assert np.all(table.curves(reference, scene.device.ball_charge)
                      .voltage(held.positions) > 0)
    # the mirror symmetry the surrogate exploits holds for the solver: z <-> Δh - z
    for direct in extra:
        image = solve_position(scene, scene.device.stroke - direct.position, comm=MPI.COMM_SELF)
        mirrored = surrogate.mirrored(image, scene.device.stroke)
        np.testing.assert_allclose(mirrored.capacitance, direct.capacitance, rtol=5e-3)
        np.testing.assert_allclose(mirrored.induced_charge, direct.induced_charge, rtol=5e-3)
        np.testing.assert_allclose(mirrored.induced_fraction, direct.induced_fraction, rtol=5e-3)


@pytest.mark.slow
@pytest.mark.field
def test_cli_run_end_to_end_then_cached(small_run, python):
    tmp_path, _, first = small_run
    assert first.returncode == 0, first.stderr
    out = tmp_path / "out1"
    for name in ("waveforms.csv", "summary.json", "waveforms.png", "surrogate.png",
                 "impacts.csv", "trajectory.png"):
        assert (out / name).stat().st_size > 0
    with open(out / "waveforms.csv") as f:
        header = next(csv.reader(f))
    # C_p = 5 pF across the load: the instrument's reading V_read_V (= V_load_V) too
    assert header == electrical.WAVEFORM_COLUMNS + ["V_read_V"] + electrical.LOAD_COLUMNS
    data = np.loadtxt(out / "waveforms.csv", delimiter=",", skiprows=1)
    assert data.shape[0] == 0.3 * 5000 + 1
    assert np.allclose(np.diff(data[:, 0]), 1 / 5000.0)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field"]["status"] == "ran"
    assert summary["load"]["power_density_W_per_m3"] > 0
    assert summary["stages"]["circuit"]["details"]["energy_balance_relative_residual"] < 1e-2
    assert summary["peak_to_peak"]["V_oc_V"] > 0 and summary["regime"]["regime"]
    # second run: cached surrogate, dolfinx never imported
    code = ("import sys; from tengfield.cli import main; rc = main(['run', 'small.toml', '-o', "
            "'out2', '--no-plots']); assert 'dolfinx' not in sys.modules and 'gmsh' not in "
            "sys.modules, 'heavy import'; sys.exit(rc)")
    env = dict(os.environ, MPLBACKEND="Agg", TENGFIELD_CACHE_DIR=str(tmp_path / "cache"))
    second = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                            cwd=tmp_path, timeout=300)
    assert second.returncode == 0, second.stderr
    summary2 = json.loads((tmp_path / "out2" / "summary.json").read_text())
    assert summary2["stages"]["field"]["status"] == "cached"
    np.testing.assert_allclose(np.loadtxt(tmp_path / "out2" / "waveforms.csv", delimiter=",",
                                          skiprows=1), data, rtol=1e-9)


@pytest.mark.slow
@pytest.mark.field
def test_cli_sweep_and_precompute_cache(small_run, run_cli):
    """`precompute` finds the surrogate `run` computed and stored (small_run: its field
    stage "ran"; `precompute` computing and storing one is tests/parallel/
    test_mpi_precompute.py's, under mpirun and serially), then two sweeps read it."""
    where, env, first = small_run
    assert first.returncode == 0, first.stderr
    tmp_path = where / "sweeps"
    tmp_path.mkdir()
    (tmp_path / "small.toml").write_text(SMALL_SCENE)

    def cli(args):
        return run_cli(*args, cwd=tmp_path, env=env, timeout=600)
    again = cli(["precompute", "small.toml"])
    assert again.returncode == 0 and "cached" in again.stdout
    sweep = cli(["sweep", "small.toml", "--frequency-hz", "15:25:2", "--amplitude-mm", "1.5",
                 "--load-ohm", "1e8:1e10:2", "--jobs", "2", "-o", "sw"])
    assert sweep.returncode == 0, sweep.stderr
    with open(tmp_path / "sw" / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and {r["load_ohm"] for r in rows} == {"100000000.0", "10000000000.0"}
    assert all(float(r["V_oc_pp_V"]) > 0 and float(r["P_mean_W"]) > 0 for r in rows)
    assert (tmp_path / "sw" / "sweep.png").stat().st_size > 0
    bare = cli(["sweep", "small.toml", "--frequency-hz", "15:25:2", "--amplitude-mm", "1.5",
                "--no-plots", "-o", "bare"])
    assert bare.returncode == 0, bare.stderr
    assert (tmp_path / "bare" / "sweep.csv").exists()
    assert not (tmp_path / "bare" / "sweep.png").exists()
    assert "sweep.png" not in bare.stdout


@pytest.mark.slow
def test_uncharged_run_never_imports_the_field_stack(tmp_path, python):
    (tmp_path / "dry.toml").write_text(SMALL_SCENE + "[device]\nsurface_charge_uC_per_m2 = 0.0\n")
    code = ("import sys; from tengfield.cli import main; rc = main(['run', 'dry.toml', '-o', "
            "'out', '--no-plots']); assert 'dolfinx' not in sys.modules and 'gmsh' not in "
            "sys.modules; sys.exit(rc)")
    env = dict(os.environ, MPLBACKEND="Agg", TENGFIELD_CACHE_DIR=str(tmp_path / "cache"))
    proc = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                          cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["stages"]["field"]["status"] == "skipped"
    assert not (tmp_path / "cache").exists()


@pytest.mark.slow
@pytest.mark.parametrize("section, key, value, expected", [
    ("circuit", "load_ohm", "-5.0", "[circuit] load_ohm = -5.0 is out of range"),
    ("circuit", "parallel_capacitance_pF", "-1.0", "[circuit] parallel_capacitance_pF = -1.0"),
    ("circuit", "reference", '"grounded-upper"', "[circuit] reference = 'grounded-upper' is not allowed"),
    ("circuit", "kind", '"resistor"', "[circuit] kind = 'resistor' is not allowed"),
])
def test_bad_circuit_input_is_a_clear_error(tmp_path, cli, section, key, value, expected):
    (tmp_path / "bad.toml").write_text(f"[{section}]\n{key} = {value}\n")
    proc = cli(["run", "bad.toml", "-o", "out"])
    assert proc.returncode == 2
    assert expected in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_bad_sweep_range_is_a_clear_error(tmp_path, cli):
    proc = cli(["sweep", "--frequency-hz", "10:20", "--amplitude-mm", "1", "-o", "o"])
    assert proc.returncode == 2 and "--frequency-hz = '10:20'" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.field
@pytest.mark.slow
def test_cli_run_of_the_real_default_scene(tmp_path, cli):
    """`tengfield run` with no scene: the paper's device at 1.5 mm / 20 Hz, cold cache.
    The field at 1 mm (degree 2, tolerance 2 %: its field error estimate stays below that,
    a few seconds of solves); the default's 0.5 mm-scaled field, cold, is README's `make run`
    (tests/test_readme_quickstart.py). The claims here are signs, conservation and the
    surrogate within its tolerance, which hold at any field accuracy."""
    coarse = {"mesh_size_mm": 1.0, "tolerance": 0.02}
    settings = [arg for key, value in coarse.items() for arg in ("--set", f"field.{key}={value}")]
    proc = cli(["run", "-o", "out", "--no-plots", *settings])
    assert proc.returncode == 0, proc.stderr
    assert "tengfield: warning" not in proc.stderr   # the field meets that tolerance
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    data = np.loadtxt(tmp_path / "out" / "waveforms.csv", delimiter=",", skiprows=1)
    columns = {name: data[:, i] for i, name in enumerate(electrical.WAVEFORM_COLUMNS)}
    from tengfield.scene import default_scene
    scene = default_scene().with_values(field=coarse)
    q_ball = abs(scene.device.ball_charge)
    q_sc = columns["Q_sc_C"]
    # a negative ball above its reference position: Q_SC >= 0, V_OC >= 0 (terminals.py)
    assert q_sc.min() >= -1e-6 * q_sc.max() and columns["V_oc_V"].min() >= -1e-6 * q_sc.max()
    # charge conservation: no more than the ball's charge can be transferred
    assert 0.1 * q_ball < summary["peak_to_peak"]["Q_sc_C"] < q_ball
    # I_SC has the sign of the ball's velocity (dQ_SC/dz > 0 along the stroke)
    current = columns["I_sc_A"]
    clear = (np.abs(columns["gap_velocity_m_per_s"]) > 1e-3) & (np.abs(current) > 1e-3 * np.abs(current).max())
    assert np.all(np.sign(current[clear]) == np.sign(columns["gap_velocity_m_per_s"][clear]))
    assert summary["surrogate_error_estimate"] <= scene.field.tolerance
    assert summary["stages"]["field"]["status"] == "ran"
    assert data.shape[0] == round(scene.run.duration * scene.run.sample_rate) + 1
