"""Issue 52, ``[array]`` with ``[charge] model = "contact"``: each cell's ball charges on
its own impacts with the same contact law, each cell's terminals follow its own charge
history, and the array's terminals are their sum. N identical cells are N x one cell;
with spread each cell's steady charge is a single-cell run at that cell's phase,
restitution and initial velocity, and the array's Q_SC(t) is the sum of those runs'."""
from __future__ import annotations

import json
import math
import shutil
import subprocess

import numpy as np
import pytest

import tengfield as tf
from tengfield.array import draw_cells

import plate_model as fx
from helpers import needs_mpirun, oversubscribed_env

RUN = {"duration_s": 2.0, "settle_periods": 4, "sample_rate_hz": 2000.0}
#: leakage: the steady charge depends on each cell's contacts (their rate and areas)
CHARGE = {"model": "contact", "discharge": "none", "equilibrium_uC_per_m2": -100.0,
          "efficiency": 0.3, "leakage_time_s": 0.3}
SPREAD = {"cells": 4, "restitution_spread": 0.3, "initial_phase_spread_deg": 60.0,
          "initial_velocity_spread_m_per_s": 0.05, "seed": 1}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _run(scene, cache):
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


def _cell_scene(draw, **sections):
    """The single-cell scene of one array cell's draw (phase [rad], e, v0 [m/s])."""
    return fx.scene_with(run=RUN, charge=CHARGE, excitation={"phase_deg": math.degrees(draw[0])},
                         contact={"restitution": float(draw[1])},
                         initial={"velocity_m_per_s": float(draw[2])}, **sections)


@pytest.mark.parametrize("circuit", [{"kind": "open"}, {"kind": "short"}])
def test_n_identical_cells_are_n_times_one_contact_charged_cell(cache, circuit):
    """No spread: Q_SC(t), I_SC(t), C_T(t) are N x the single cell's (1e-12), V_oc the
    cell's, and the charge block the single cell's (every cell charges alike)."""
    one = _run(fx.scene_with(run=RUN, charge=CHARGE, circuit=circuit), cache)
    array = _run(fx.scene_with(run=RUN, charge=CHARGE, circuit=circuit,
                               array={"cells": 5}), cache)
    assert one.summary["charge"]["contacts"] > 50
    for column in ("Q_sc_C", "I_sc_A", "C_T_F"):
        np.testing.assert_allclose(array.waveforms[column], 5.0 * one.waveforms[column],
                                   rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(array.waveforms["V_oc_V"], one.waveforms["V_oc_V"], rtol=1e-12)
    for name in ("Q_sc_C", "I_sc_A"):
        assert array.summary["peak_to_peak"][name] == pytest.approx(
            5.0 * one.summary["peak_to_peak"][name], rel=1e-12)
    block, alone = array.summary["charge"], one.summary["charge"]
    assert {k: v for k, v in block.items() if k != "cells"} == alone
    cells = block["cells"]
    assert cells["count"] == 5 and cells["distinct"] == 1
    assert cells["steady_uC_per_m2"] == [alone["steady_uC_per_m2"]] * 5
    assert cells["contacts"] == [alone["contacts"]] * 5


def test_each_cell_charges_on_its_own_impacts(cache):
    """Spread in phase, restitution and initial velocity: each cell's steady charge, rise
    time and contacts are those of a single-cell contact run at its draw (1e-12); they
    differ from cell to cell; the array's Q_SC(t) and I_SC(t) (terminals in parallel) are
    the sums of the single-cell runs' (1e-9 of the peak); the block reported is the
    median cell's."""
    scene = fx.scene_with(run=RUN, charge=CHARGE, array=SPREAD)
    array = _run(scene, cache)
    cells = array.summary["charge"]["cells"]
    assert cells["count"] == 4 and cells["distinct"] == 4
    singles = [_run(_cell_scene(d), cache) for d in draw_cells(scene)]
    for k, single in enumerate(singles):
        block = single.summary["charge"]
        assert cells["steady_uC_per_m2"][k] == pytest.approx(block["steady_uC_per_m2"],
                                                             rel=1e-12)
        assert cells["rise_time_90_s"][k] == pytest.approx(block["rise_time_90_s"], rel=1e-12)
        assert cells["contacts"][k] == block["contacts"]
    steady = cells["steady_uC_per_m2"]
    assert len(set(steady)) == 4 and max(steady) - min(steady) > 0.05 * abs(np.mean(steady))
    assert cells["steady_mean_uC_per_m2"] == pytest.approx(np.mean(steady), rel=1e-12)
    median = sorted(steady)[1]                       # the lower middle of four
    reported = cells["reported_cell"]
    assert steady[reported] == median
    assert array.summary["charge"]["steady_uC_per_m2"] == median
    for column in ("Q_sc_C", "I_sc_A", "C_T_F"):
        total = sum(np.asarray(s.waveforms[column]) for s in singles)
        scale = np.max(np.abs(total))
        np.testing.assert_allclose(array.waveforms[column], total, rtol=0, atol=1e-9 * scale)
    # what a constant charge at each cell's steady sigma would not give: the charge grows
    constant = _run(fx.scene_with(run=RUN, array=SPREAD, device={
        "surface_charge_uC_per_m2": median}), cache)
    early = np.asarray(array.waveforms["time_s"]) < 0.1
    assert np.ptp(np.asarray(array.waveforms["Q_sc_C"])[early]) < \
        0.8 * np.ptp(np.asarray(constant.waveforms["Q_sc_C"])[early])


def test_a_rectified_per_cell_array_stores_what_its_cells_store(cache):
    """``connection = "rectified-per-cell"``: a bridge and store per cell, so the energy
    into the stores is the sum of the single-cell runs' (each at its own charge; 1 %: the
    array's stores step on the output samples, a single run's on its own finer grid, as
    tests/array/test_array.py compares them)."""
    rect = {"kind": "rectifier", "storage_capacitance_uF": 1e-4}
    scene = fx.scene_with(run=RUN, charge=CHARGE, circuit=rect,
                          array={**SPREAD, "connection": "rectified-per-cell"})
    array = _run(scene, cache)
    singles = [_run(_cell_scene(d, circuit=rect), cache) for d in draw_cells(scene)]
    stored = [s.summary["rectifier"]["energy_books_J"]["delivered_J"] for s in singles]
    assert array.summary["array"]["array_value"] == pytest.approx(sum(stored), rel=1e-2)
    assert max(stored) > 1.05 * min(stored)          # the cells' charges differ


@pytest.mark.slow
def test_cli_run_of_a_contact_charged_array_with_figures(tmp_path, cli_command, cli_env):
    """``tengfield run`` of a coarse real-field array (the cap of each cell's own breakdown
    band): summary.json's charge block with each cell's steady charge, ball_charge.png
    (the reported cell and the others) and array.png drawn, the terminal's charge line;
    ``mpirun -n 2`` (its own, empty cache) writes the serial waveforms.csv byte for byte
    and the same charge block."""
    scene = tmp_path / "array.toml"
    scene.write_text(fx.SMALL_SCENE + '\n[charge]\nmodel = "contact"\nefficiency = 0.3\n'
                     "leakage_time_s = 0.1\n[array]\ncells = 3\nrestitution_spread = 0.3\n"
                     "seed = 2\n")
    done = subprocess.run(cli_command("run", scene, "-o", tmp_path / "out"),
                          capture_output=True, text=True, timeout=600,
                          env=cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache"))
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    cells = summary["charge"]["cells"]
    assert cells["count"] == 3 and len(cells["steady_uC_per_m2"]) == 3
    assert all(s < 0.0 for s in cells["steady_uC_per_m2"])
    assert len(set(cells["steady_uC_per_m2"])) == 3
    assert f"(cell {cells['reported_cell']} of 3, the median; the cells' steady charge " \
        "from" in done.stdout
    for name in ("ball_charge.png", "array.png"):
        png = (tmp_path / "out" / name).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    needs_mpirun()
    two = subprocess.run([shutil.which("mpirun"), "-n", "2",
                          *cli_command("run", scene, "-o", tmp_path / "two")],
                         capture_output=True, text=True, timeout=600,
                         env=oversubscribed_env(cli_env, tmp_path / "cache-two"))
    assert two.returncode == 0, two.stderr[-3000:]
    assert (tmp_path / "two" / "waveforms.csv").read_bytes() == \
        (tmp_path / "out" / "waveforms.csv").read_bytes()
    assert json.loads((tmp_path / "two" / "summary.json").read_text())["charge"] == \
        summary["charge"]
