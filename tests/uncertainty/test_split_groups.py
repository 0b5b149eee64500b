"""A σ- or circuit-only study is one group of every evaluation: it is split into chunks
so that --jobs and mpirun share it, and the files stay byte-identical between serial,
--jobs 2 and mpirun -n 2 (issue #43.21)."""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

import plate_model
from helpers import mpi_env
from tengfield.uncertainty_study import run_study
from tengfield.uncertainty_study.evaluation import CHUNK_EVALUATIONS, Group, chunked

SIGMA = "device.surface_charge_uC_per_m2"


def test_a_large_group_is_split_into_ordered_chunks():
    members = [(i, {SIGMA: float(i)}) for i in range(2 * CHUNK_EVALUATIONS + 5)]
    small = Group({"contact.restitution": 0.2}, [(999, {})])
    out = chunked([Group({}, members), small])
    assert [len(g.members) for g in out] == [CHUNK_EVALUATIONS, CHUNK_EVALUATIONS, 5, 1]
    assert [m for g in out[:3] for m in g.members] == members
    assert all(g.dynamic == {} for g in out[:3]) and out[3] is not small and out[3].members == \
        small.members


@pytest.mark.slow
def test_a_sigma_only_study_is_farmed_in_chunks_with_the_same_outputs(tmp_path):
    scene = plate_model.scene_with(uncertainty={"samples": 128, "method": "sobol", "seed": 4,
                                                "vary": {SIGMA: {"distribution": "uniform",
                                                                 "low": -12.0, "high": -4.0}}})
    serial = run_study(scene, cache_dir=tmp_path / "a", solve=plate_model.plate_model_solve, jobs=1)
    ev = serial.evaluations
    assert len(ev.rows) == 384
    assert ev.tasks == 1 + 384 // CHUNK_EVALUATIONS       # the nominal run and 3 chunks
    assert ev.dynamics_runs == 2                          # one group: its dynamics once
    farmed = run_study(scene, cache_dir=tmp_path / "b", solve=plate_model.plate_model_solve, jobs=2)
    assert farmed.evaluations.rows == ev.rows
    assert farmed.evaluations.regimes == ev.regimes
    assert farmed.summary == serial.summary
    q = np.array([row["peak_to_peak.Q_sc_C"] for row in ev.rows])
    assert np.all(q > 0) and np.ptp(q) > 0


@pytest.mark.slow
def test_serial_jobs_and_mpirun_write_the_same_csv_for_a_split_group(tmp_path, run_cli,
                                                                     cli_command):
    scene = tmp_path / "sigma.toml"
    scene.write_text('[uncertainty]\nsamples = 128\nmethod = "sobol"\nseed = 3\n'
                     '[uncertainty.vary]\n"device.surface_charge_uC_per_m2" = { distribution = '
                     '"uniform", low = -12.0, high = -4.0 }\n"circuit.parallel_capacitance_pF" = '
                     '{ distribution = "uniform", low = 0.0, high = 50.0 }\n')
    serial = run_cli("uncertainty", scene, "-o", tmp_path / "serial", "--jobs", "1",
                     "--no-plots")
    assert serial.returncode == 0, serial.stderr
    expected = (tmp_path / "serial" / "uncertainty.csv").read_bytes()
    assert expected.count(b"\n") == 1 + 128 * 4
    jobs = run_cli("uncertainty", scene, "-o", tmp_path / "jobs", "--jobs", "2", "--no-plots")
    assert jobs.returncode == 0, jobs.stderr
    assert (tmp_path / "jobs" / "uncertainty.csv").read_bytes() == expected
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    proc = subprocess.run(["mpirun", "-n", "2", *cli_command(
        "uncertainty", scene, "-o", tmp_path / "mpi", "--no-plots")], capture_output=True,
        text=True, env=mpi_env(), timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "mpi" / "uncertainty.csv").read_bytes() == expected
