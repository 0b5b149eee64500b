"""[array]: cells with their own dynamics sharing one surrogate (tengfield.array).

Field: the analytic plate model (no dolfinx); dynamics: the real impact map.
"""
from __future__ import annotations


import numpy as np
import pytest

import tengfield as tf
from tengfield import array, electrical

import plate_model as fx

SHORT_RUN = {"duration_s": 0.5, "settle_periods": 2, "sample_rate_hz": 4000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def run(cache, circuit, **arr):
    scene = fx.scene_with(run=SHORT_RUN, circuit=circuit, **arr)
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


@pytest.mark.parametrize("circuit", [
    {"kind": "open"},
    {"kind": "load", "load_ohm": 3e9, "parallel_capacitance_pF": 2.0},
    {"kind": "rectifier", "storage_capacitance_uF": 1e-4},
])
def test_identical_cells_are_device_cells_exactly(cache, circuit):
    """No spread: [array] cells = N gives today's [device] cells = N, to the last bit."""
    arr = run(cache, circuit, array={"cells": 5})
    dev = run(cache, circuit, device={"cells": 5})
    assert arr.summary["array"]["distinct_dynamics"] == 1
    assert set(dev.waveforms) <= set(arr.waveforms)
    for key, values in dev.waveforms.items():
        np.testing.assert_array_equal(arr.waveforms[key], values, err_msg=key)
    assert arr.summary["array"]["array_over_N_cells"] == pytest.approx(1.0, abs=1e-15)
    assert arr.summary["array"]["phase_coherence"] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.slow
def test_phase_spread_costs_parallel_cells_and_per_cell_bridges_recover_it(cache):
    """Spread phases partly cancel in a parallel wiring (ratio < 1); per-cell bridges into
    the same store never deliver less than one bridge on the parallel sum."""
    spread = {"cells": 12, "initial_phase_spread_deg": 240.0, "seed": 7}
    rect = {"kind": "rectifier", "storage_capacitance_uF": 1e-4}
    shared = run(cache, rect, array={**spread, "connection": "parallel"})
    per_cell = run(cache, rect, array={**spread, "connection": "rectified-parallel"})
    opened = run(cache, {"kind": "open"}, array=spread)
    assert opened.summary["array"]["array_over_N_cells"] < 0.9
    assert opened.summary["array"]["phase_coherence"] < 0.9
    a, b = shared.summary["array"], per_cell.summary["array"]
    assert a["N_x_one_cell_value"] == pytest.approx(b["N_x_one_cell_value"], rel=1e-12)
    assert b["array_value"] >= a["array_value"]
    assert b["array_over_N_cells"] > 0.9 > a["array_over_N_cells"]
    assert max(per_cell.summary["rectifier"]["energy_residuals"].values()) < 1e-9


def test_per_cell_stores_add_up(cache):
    """rectified-per-cell: N independent harvesters; with no spread the array is N x one."""
    rect = {"kind": "rectifier", "storage_capacitance_uF": 1e-4}
    one = run(cache, rect)
    arr = run(cache, rect, array={"cells": 3, "connection": "rectified-per-cell",
                                  "restitution_spread": 1e-9})
    # a spread too small to change the motion visibly: the stores still add up
    assert arr.summary["array"]["distinct_dynamics"] == 3
    e_one = one.summary["rectifier"]["energy_books_J"]["delivered_J"]   # ideal: all stored
    assert arr.summary["array"]["N_x_one_cell_value"] == pytest.approx(3 * e_one, rel=1e-2)
    assert arr.summary["array"]["array_value"] == pytest.approx(
        arr.summary["array"]["N_x_one_cell_value"], rel=1e-6)


def test_draws_follow_the_seed_and_stay_in_range():
    scene = fx.scene_with(array={"cells": 200, "initial_phase_spread_deg": 90.0,
                                 "restitution_spread": 0.5, "initial_velocity_spread_m_per_s": 0.2,
                                 "seed": 4})
    d = array.draw_cells(scene)
    np.testing.assert_array_equal(d, array.draw_cells(scene))
    assert not np.array_equal(d, array.draw_cells(scene.with_values(array={"seed": 5})))
    assert np.all(np.abs(d[:, 0] - scene.excitation.phase) <= np.pi / 4)
    assert np.all((d[:, 1] >= 0) & (d[:, 1] <= 1)) and d[:, 1].max() > 0.3
    assert np.all((d[:, 2] >= 0) & (d[:, 2] <= 0.2))


def test_processes_give_the_serial_trajectories():
    scene = fx.scene_with(run=SHORT_RUN, array={"cells": 16, "restitution_spread": 0.1,
                                                "initial_phase_spread_deg": 30.0})
    draws = array.draw_cells(scene)
    serial = array.simulate_cells(scene, draws, jobs=1)
    spread = array.simulate_cells(scene, draws, jobs=2)
    t = np.linspace(0, 0.5, 101)
    for (a, na), (b, nb) in zip(serial, spread):
        assert na == nb
        np.testing.assert_array_equal(a(t)[0], b(t)[0])


@pytest.mark.slow
def test_array_plot_and_csv(cache, tmp_path):
    from tengfield import io
    res = run(cache, {"kind": "load", "load_ohm": 3e9},
              array={"cells": 6, "initial_velocity_spread_m_per_s": 0.3})
    written = [p.name for p in io.write_run_outputs(res, tmp_path)]
    assert "array.png" in written and "vq.png" not in written
    data = np.loadtxt(tmp_path / "waveforms.csv", delimiter=",", skiprows=1)
    assert data.shape[1] == len(electrical.WAVEFORM_COLUMNS + electrical.LOAD_COLUMNS)
    assert res.summary["cells"] == 6 and len(res.summary["array"]["phases_deg"]) == 6


@pytest.mark.mpi
def test_mpi_ranks_give_the_serial_trajectories():
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    scene = fx.scene_with(run=SHORT_RUN, array={"cells": 6, "restitution_spread": 0.1})
    draws = array.draw_cells(scene)
    farmed = array.simulate_cells(scene, draws, comm=comm)
    serial = array.simulate_cells(scene, draws, jobs=1)
    t = np.linspace(0, 0.5, 51)
    for (a, _), (b, _) in zip(farmed, serial):
        np.testing.assert_array_equal(a(t)[0], b(t)[0])


@pytest.mark.slow
def test_cli_array_run(tmp_path, run_cli, cli_env):
    """`tengfield run` of an [array] scene (surrogate cached from the plate model)."""
    import json

    path = tmp_path / "arr.toml"
    path.write_text('[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 4000.0\n'
                    '[circuit]\nkind = "rectifier"\nstorage_capacitance_uF = 1e-4\n'
                    '[array]\ncells = 10\nconnection = "rectified-parallel"\n'
                    'initial_phase_spread_deg = 90\n')
    tf.run(tf.load_scene(path), cache_dir=tmp_path / "cache", solve=fx.plate_model_solve)
    env = cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true",
                  TENGFIELD_CACHE_DIR=tmp_path / "cache")
    proc = run_cli("run", "arr.toml", "-o", "out", cwd=tmp_path, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["cells"] == 10 and summary["array"]["distinct_dynamics"] == 10
    assert 0 < summary["array"]["array_over_N_cells"] <= 1.1
    assert (tmp_path / "out" / "array.png").stat().st_size > 0
    assert (tmp_path / "out" / "charging.png").stat().st_size > 0
    assert "array: 10 cells (rectified-parallel)" in proc.stdout


def test_an_array_whose_trajectories_would_not_fit_is_refused_at_load():
    """1e6 spread cells x 20 periods (about 28 GB at the peak) is a one-line error when
    the scene is read, before any field or dynamics work; identical cells share one
    trajectory and are not limited."""
    from tengfield.errors import SceneError
    from tengfield.scene import parse_scene
    from tengfield.scene.limits import MAX_ARRAY_CELL_PERIODS

    with pytest.raises(SceneError, match=r"\[array\] cells x \[run\] duration_s x \[excitation\] "
                                         r"frequency_hz = 1000000 x 1 x 20 = 2e\+07 cell-periods: "
                                         r"allowed <= 5e\+06 \(each cell keeps its trajectory: "
                                         r"about 28 GB here"):
        parse_scene("[array]\ncells = 1000000\nrestitution_spread = 0.1\n")
    assert parse_scene("[array]\ncells = 1000000\n").array.cells == 10**6
    cells = int(MAX_ARRAY_CELL_PERIODS // 20)
    assert parse_scene(f"[array]\ncells = {cells}\nrestitution_spread = 0.1\n").array.cells == cells
    with pytest.raises(SceneError, match="cell-periods"):
        parse_scene(f"[array]\ncells = {cells + 1}\nrestitution_spread = 0.1\n")


@pytest.mark.slow
def test_trajectory_bundle_equals_each_trajectory_bit_for_bit():
    """The compiled bundle (one call per chunk for every cell) gives exactly the values of
    sampling each cell's trajectory, for chunks of any size and cells of any phase;
    trajectories that differ in stroke are refused."""
    from tengfield.dynamics.impact import TrajectoryBundle
    from tengfield.scene import parse_scene

    scene = parse_scene("[array]\ncells = 40\nrestitution_spread = 0.5\n"
                        "initial_phase_spread_deg = 180\ninitial_velocity_spread_m_per_s = 0.3\n")
    trajectories = [tr for tr, _ in array.simulate_cells(scene, array.draw_cells(scene), jobs=1)]
    bundle = TrajectoryBundle(trajectories)
    t = np.sort(np.random.default_rng(3).uniform(0.0, scene.run.duration, 3001))
    for rows in (1, 7, 500, t.size):
        for lo in range(0, t.size, rows):
            times = t[lo:lo + rows]
            z, v = bundle(times)
            for j, tr in enumerate(trajectories):
                zj, vj, _ = tr(times)
                np.testing.assert_array_equal(z[:, j], zj)
                np.testing.assert_array_equal(v[:, j], vj)
    other = array.simulate_cells(scene.with_values(device={"stroke_mm": 2.0}),
                                 array.draw_cells(scene)[:1], jobs=1)[0][0]
    with pytest.raises(ValueError, match="differ in stroke"):
        TrajectoryBundle([trajectories[0], other])


@pytest.mark.parametrize("charge", [None, {"model": "contact", "discharge": "none",
                                           "equilibrium_uC_per_m2": -100.0,
                                           "efficiency": 0.3}])
def test_cells_launched_while_the_nominal_ball_rests_have_their_output(cache, charge):
    """Below lift-off the nominal ball rests (no field needed for it), but a cell with an
    initial velocity bounces: the array's Q_SC(t) is the sum of its cells' single runs
    (each at its draw), not 0 (the field is solved for the array's cells)."""
    import math

    exc = {"frequency_hz": 20.0, "amplitude_mm": 0.3}       # 4.7 m/s^2 < g
    extra = {"charge": charge} if charge else {}
    scene = fx.scene_with(run=SHORT_RUN, excitation=exc, array={
        "cells": 3, "initial_velocity_spread_m_per_s": 0.3, "seed": 1}, **extra)
    arr = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    assert arr.stages["field"].status != "skipped"
    total = 0.0
    for d in array.draw_cells(scene):
        cell = fx.scene_with(run=SHORT_RUN, excitation={**exc, "phase_deg": math.degrees(d[0])},
                             contact={"restitution": float(d[1])},
                             initial={"velocity_m_per_s": float(d[2])}, **extra)
        total = total + np.asarray(tf.run(cell, cache_dir=cache,
                                          solve=fx.plate_model_solve).waveforms["Q_sc_C"])
    assert np.max(np.abs(total)) > 1e-13
    np.testing.assert_allclose(arr.waveforms["Q_sc_C"], total, rtol=0,
                               atol=1e-9 * np.max(np.abs(total)))
