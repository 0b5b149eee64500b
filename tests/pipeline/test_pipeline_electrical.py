"""One set of electrical numbers: run, sweep and report agree; peaks include the impacts.

The field is the analytic plate model of ``plate_model`` (no
dolfinx); the dynamics are the real impact map on a short run, so the
velocity jumps at impacts are the real ones.
"""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tengfield as tf
from tengfield import accuracy_report, electrical, io, sweeps

import plate_model as fx

ROOT = Path(__file__).resolve().parents[2]
SHORT_RUN = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000.0}


def scene_with_cells_and_instrument(**circuit):
    """4 cells in parallel read through C_p = 10 pF: the case report got wrong."""
    return fx.scene_with(device={"cells": 4}, run=SHORT_RUN,
                         circuit={"parallel_capacitance_pF": 10.0, **circuit})


@pytest.fixture(scope="module")
def cached(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def test_run_sweep_and_report_agree_with_cells_and_parallel_capacitance(cached):
    scene = scene_with_cells_and_instrument()
    result = tf.run(scene, cache_dir=cached, solve=fx.plate_model_solve)
    assert result.dynamics.impacts.time.size > 4          # impacts inside the window
    ran = result.peaks

    (row,) = sweeps.sweep_point(scene, result.table, scene.excitation.frequency,
                               scene.excitation.amplitude)
    swept = {"V_oc": row["V_oc_pp_V"], "Q_sc": row["Q_sc_pp_C"], "I_sc": row["I_sc_pp_A"]}

    rate = scene.run.sample_rate    # report's dynamics stage with its reference = run's sampling
    plan = dataclasses.replace(accuracy_report.make_plan(fast=True), sample_rates=(rate,),
                               reference_sample_rate=rate, stiffnesses=())
    rows, (_, _, reported) = accuracy_report.dynamics_rows(plan, scene, result.curves)

    swept["V_read"] = row["V_read_pp_V"]
    for name in ("V_oc", "Q_sc", "I_sc", "V_read"):
        assert swept[name] == pytest.approx(ran[name], rel=1e-12, abs=0), name
    for name in ("V_oc", "Q_sc", "I_sc"):
        assert reported[name] == pytest.approx(ran[name], rel=1e-12, abs=0), name
        assert rows[0].errors[name] <= 1e-12, name      # was 3.0 (cells) and 0.99 (C_p)
    # what cells and C_p do: Q_SC and I_SC x 4; V_OC (ideal) the same; the voltage read
    # through C_p below it
    one = tf.run(fx.scene_with(run=SHORT_RUN), cache_dir=cached, solve=fx.plate_model_solve)
    assert ran["Q_sc"] == pytest.approx(4 * one.peaks["Q_sc"], rel=1e-12)
    assert ran["I_sc"] == pytest.approx(4 * one.peaks["I_sc"], rel=1e-12)
    assert ran["V_oc"] == pytest.approx(one.peaks["V_oc"], rel=1e-12)
    assert ran["V_read"] < one.peaks["V_oc"]


def test_sweep_power_equals_the_run_with_that_load(cached):
    load = 3e9
    scene = scene_with_cells_and_instrument()
    loaded = scene_with_cells_and_instrument(kind="load", load_ohm=load)
    result = tf.run(loaded, cache_dir=cached, solve=fx.plate_model_solve)
    (row,) = sweeps.sweep_point(scene, result.table, scene.excitation.frequency,
                               scene.excitation.amplitude, loads=(load,))
    power = result.summary["load"]["mean_power_W"]
    assert power > 0
    assert row["P_mean_W"] == pytest.approx(power, rel=1e-12)
    assert row["power_density_W_per_m3"] == pytest.approx(
        result.summary["load"]["power_density_W_per_m3"], rel=1e-12)


def test_current_peak_does_not_depend_on_the_sampling(cached):
    """I_SC jumps at every impact and takes its extremes there: with the impact
    instants the peak at 20 kHz is the 200 kHz one; the samples alone are low."""
    peaks, sampled = {}, {}
    for rate in (20000.0, 200000.0):
        scene = fx.scene_with(device={"cells": 4}, run={**SHORT_RUN, "sample_rate_hz": rate})
        result = tf.run(scene, cache_dir=cached, solve=fx.plate_model_solve)
        mask, _ = electrical.steady_window(result.t, scene)
        peaks[rate], sampled[rate] = result.peaks["I_sc"], np.ptp(result.I_sc[mask])
    assert peaks[20000.0] == pytest.approx(peaks[200000.0], rel=1e-6)
    assert sampled[20000.0] < peaks[200000.0] * (1 - 5e-4)
    assert sampled[200000.0] <= peaks[200000.0]


def test_notebook_api(tmp_path):
    scene = fx.scene_with(run=SHORT_RUN)
    r = tf.run(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    assert r.t is r.waveforms["time_s"] and r.V_oc is r.waveforms["V_oc_V"]
    assert r.Q_sc is r.waveforms["Q_sc_C"] and r.I_sc is r.waveforms["I_sc_A"]
    assert r.peaks["Q_sc"] == r.summary["peak_to_peak"]["Q_sc_C"] > 0
    assert set(r.stages) == {"dynamics", "field", "surrogate", "circuit"}
    assert r.stages["field"].status == "ran"
    assert tf.simulate(scene).t.size == r.t.size
    assert tf.build_surrogate(scene, cache_dir=tmp_path)[1].status == "cached"
    assert callable(tf.solve_position) and tf.load_scene(None).source == tf.default_scene().source


def test_importing_tengfield_loads_no_heavy_stack():
    code = ("import sys, tengfield as tf; tf.run; tf.default_scene(); "
            "print(sorted(m for m in ('dolfinx', 'gmsh', 'numba', 'pyvista', 'petsc4py', "
            "'matplotlib') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


@pytest.mark.slow
def test_plots_leave_the_callers_matplotlib_backend_alone(tmp_path):
    """A notebook's backend is not switched: the library draws on Figure objects."""
    code = ("import sys; sys.path.insert(0, 'tests'); import matplotlib; matplotlib.use('svg'); "
            "import plate_model as fx; import tengfield as tf; "
            f"out = {str(tmp_path)!r}; "
            "r = tf.run(fx.scene_with(run={'duration_s': 0.3, 'settle_periods': 2}), "
            "cache_dir=out, "
            "solve=fx.plate_model_solve); tf.io.write_run_outputs(r, out); "
            "from tengfield.plotting.dynamics import plot_trajectory3d; "
            "m = tf.simulate_3d(fx.scene_with(contact={'model': '3d'}, "
            "run={'duration_s': 0.1, 'settle_periods': 1})); "
            "plot_trajectory3d(m, out + '/trajectory3d.png'); "
            "print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    env.pop("MPLBACKEND", None)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "svg False"          # backend kept, pyplot never loaded
    for name in ("waveforms.png", "surrogate.png", "trajectory3d.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_waveform_times_keep_full_precision(tmp_path):
    """Samples 1/20 kHz apart at t ~ 1e6 s stay distinct and round-trip exactly."""
    t = 1e6 + np.arange(5) / 20000.0
    columns = {c: np.linspace(0.0, 1.0, t.size) for c in electrical.WAVEFORM_COLUMNS}
    columns["time_s"] = t
    path = io.write_waveforms_csv(tmp_path / "waveforms.csv", columns)
    back = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(back[:, 0], t)
    assert np.all(np.diff(back[:, 0]) > 0)


def test_notebook_user_reaches_every_capability_by_public_names():
    """No private names needed: the 3D ball, calibration, harvesting, arrays, (z, r)."""
    import tengfield as tf

    assert callable(tf.simulate_3d) and callable(tf.calibrate)
    assert callable(tf.harvest.harvest) and callable(tf.array.run_array)
    assert callable(tf.surrogate.radial.obtain_radial_table)
    with pytest.raises(AttributeError):
        tf.no_such_thing  # noqa: B018
