"""tengfield design over MPI: ranks give the serial result (library, plate model, under
``mpirun -n 2``), and the CLI end to end with the real field solver, figures on."""
from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import plate_model as fx
from tengfield.design_study import design

ROOT = Path(__file__).resolve().parents[2]
#: columns that depend on the machine and the cache, not on the result
MACHINE_COLUMNS = ("field_status", "field_wall_s", "dynamics_wall_s", "circuit_wall_s")
SCENE = """
[design]
objective = "power_density"
candidates = 4
batch = 2
seed = 3
settle_periods = 10
window_periods = 10
samples_per_period = 120
[design.vary]
stroke_mm = [1.5, 4.0]
[design.excitation]
frequency_hz = [33.0]
amplitude_mm = [1.0]
"""


def plate_scene():
    return fx.scene_with(design={
        "candidates": 12, "batch": 4, "seed": 2, "settle_periods": 10, "window_periods": 10,
        "samples_per_period": 120, "vary": {"stroke_mm": [1.0, 5.0], "ball_diameter_mm": [5.0, 9.0]},
        "excitation": {"frequency_hz": [33.0], "amplitude_mm": [0.75, 1.0]}})


@pytest.mark.mpi
def test_design_on_two_ranks_equals_the_serial_design(tmp_path_factory):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    cache = comm.bcast(str(tmp_path_factory.mktemp("cache")) if comm.rank == 0 else None)
    parallel = design(plate_scene(), comm=comm, cache_dir=cache, solve=fx.plate_model_solve)
    serial = design(plate_scene(), cache_dir=cache + "-serial", solve=fx.plate_model_solve,
                    jobs=1)

    def strip(rows):
        return [{k: v for k, v in r.items() if k not in ("wall_s", "field_status")}
                for r in rows]
    assert strip(parallel.rows) == strip(serial.rows)
    # the chaotic band points' further windows (their spread in the error bar) included
    assert any(w == 3 for r in serial.rows for w in r["windows"])
    assert parallel.ranking == serial.ranking and parallel.ranks == comm.size
    for other in comm.allgather(strip(parallel.rows)):
        assert other == strip(serial.rows)


@pytest.mark.mpi
def test_p10_design_on_two_ranks_equals_the_serial_design(tmp_path_factory):
    """aggregate = "p10": each candidate's study runs on the rank that scores it; the
    rows (percentiles, their intervals, the study's counts) are the serial ones."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    cache = comm.bcast(str(tmp_path_factory.mktemp("cache")) if comm.rank == 0 else None)
    scene = fx.scene_with(
        design={"objective": "charge", "candidates": 8, "batch": 4, "seed": 1,
                "aggregate": "p10", "settle_periods": 10, "window_periods": 10,
                "samples_per_period": 120, "vary": {"stroke_mm": [1.0, 5.0]},
                "excitation": {"frequency_hz": [33.0], "amplitude_mm": [1.0]}},
        contact={"restitution": 0.8},
        uncertainty={"samples": 32, "method": "monte-carlo", "seed": 0, "vary": {
            "contact.restitution": {"distribution": "uniform", "low": 0.05, "high": 0.8}}})
    parallel = design(scene, comm=comm, cache_dir=cache, solve=fx.plate_model_solve)
    serial = design(scene, cache_dir=cache + "-serial", solve=fx.plate_model_solve, jobs=1)

    def strip(rows):
        return [{k: v for k, v in r.items() if k not in ("wall_s", "field_status")}
                for r in rows]
    assert strip(parallel.rows) == strip(serial.rows)
    assert all(r["uncertainty_evaluations"] == 32 for r in serial.rows if r["status"] == "ok")
    assert parallel.ranking == serial.ranking
    for other in comm.allgather(strip(parallel.rows)):
        assert other == strip(serial.rows)


def env():
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
                PYTHONPATH=os.pathsep.join(p for p in (str(ROOT / "src"),
                                                       os.environ.get("PYTHONPATH")) if p))


#: the field solver's own error estimate (and the error bar made of it) agrees to ~1e-13
#: between a serial process and an mpirun rank (the values C, q themselves are identical)
ESTIMATE_COLUMNS = ("field_relative_error", "power_density_error_W_per_m3")


def rows_of(path):
    with open(path) as f:
        return [{k: v for k, v in r.items() if k not in MACHINE_COLUMNS + ESTIMATE_COLUMNS}
                for r in csv.DictReader(f)]


def estimates_of(path):
    with open(path) as f:
        return [float(r[k]) for r in csv.DictReader(f) for k in ESTIMATE_COLUMNS]


@pytest.mark.slow   # real field solves (4 geometries), serial and mpirun -n 2
def test_cli_design_end_to_end_and_mpirun_gives_the_serial_files(tmp_path, run_cli):
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    scene = tmp_path / "ship.toml"
    scene.write_text(SCENE)
    serial = run_cli("design", scene, "-o", tmp_path / "serial", "--cache-dir",
                     tmp_path / "cache-serial", "--jobs", "1")
    assert serial.returncode == 0, serial.stderr
    assert "best: stroke_mm = " in serial.stdout and "µW/cm^3" in serial.stdout
    out = tmp_path / "serial"
    for name in ("design.csv", "design.json", "design.png", "best.toml"):
        assert (out / name).stat().st_size > 0
    assert (out / "design.png").stat().st_size > 10_000
    summary = json.loads((out / "design.json").read_text())
    assert summary["counts"]["ok"] == 4 and summary["best"]["objective"] > 0
    # the coarse field's error bar is stated and small
    assert 0 < summary["best"]["relative_error"] < 0.05
    parallel = subprocess.run(
        ["mpirun", "-n", "2", sys.executable, "-m", "tengfield.cli", "design", str(scene),
         "-o", str(tmp_path / "mpi"), "--cache-dir", str(tmp_path / "cache-mpi")],
        env=env(), capture_output=True, text=True, timeout=900)
    assert parallel.returncode == 0, parallel.stderr
    assert rows_of(tmp_path / "mpi" / "design.csv") == rows_of(out / "design.csv")
    assert estimates_of(tmp_path / "mpi" / "design.csv") == pytest.approx(
        estimates_of(out / "design.csv"), rel=1e-9)
    mpi_summary = json.loads((tmp_path / "mpi" / "design.json").read_text())
    inexact = ("objective_error", "relative_error", "objectives", "field_error")
    assert {k: v for k, v in mpi_summary["best"].items() if k not in inexact} == \
        {k: v for k, v in summary["best"].items() if k not in inexact}
    assert mpi_summary["best"]["objective_error"] == pytest.approx(
        summary["best"]["objective_error"], rel=1e-9)
    assert mpi_summary["ranks"] == 2
    # the answer: the same band table, band point of best.toml and warnings
    for key in ("best_toml_band_point", "warnings"):
        assert mpi_summary[key] == summary[key]
    assert (out / "best.toml").read_text() == (tmp_path / "mpi" / "best.toml").read_text()
    # best.toml runs
    run = run_cli("run", out / "best.toml", "-o", tmp_path / "run", "--cache-dir",
                  tmp_path / "cache-serial", "--no-plots")
    assert run.returncode == 0, run.stderr
    assert not list((tmp_path / "mpi").glob(".*tmp*"))


@pytest.mark.slow
def test_cli_bad_design_is_one_line_and_jobs_next_to_mpirun_is_refused(tmp_path, run_cli):
    bad = tmp_path / "bad.toml"
    bad.write_text('[design]\ncandidates = 3\n[design.vary]\nstroke_mm = [1.0, 5.0]\n')
    result = run_cli("design", bad, "-o", tmp_path / "out")
    assert result.returncode == 2
    assert result.stderr.strip() == ("tengfield: error: [design] candidates = 3 is out of "
                                     "range: allowed whole numbers [4, 100000]")
    assert not (tmp_path / "out").exists()


ROBUST_SCENE = """
[contact]
restitution = 0.8
[design]
objective = "charge"
aggregate = "p10"
candidates = 4
batch = 2
seed = 3
settle_periods = 10
window_periods = 10
samples_per_period = 120
[design.vary]
stroke_mm = [1.5, 4.0]
[design.excitation]
frequency_hz = [33.0]
amplitude_mm = [1.0]
[uncertainty]
samples = 32
method = "monte-carlo"
[uncertainty.vary]
"contact.restitution" = { distribution = "uniform", low = 0.05, high = 0.8 }
"device.surface_charge_uC_per_m2" = { distribution = "uniform", low = -10.0, high = -6.0 }
"""


@pytest.mark.slow   # real field solves (4 geometries) once, then cached: serial, --jobs 2, mpirun
def test_cli_p10_design_serial_jobs_and_mpirun_write_the_same_rows(tmp_path, run_cli):
    """aggregate = "p10" end to end (figures on): the study of each candidate reuses its
    cached surrogate (no further field solve), the sample count is stated, and serial,
    --jobs 2 and mpirun -n 2 write the same design.csv. The two parallel runs read the
    serial run's cache (their studies are what differs; the field solves farmed over
    ranks from an empty cache are test_cli_design_end_to_end_and_mpirun_gives_the_serial_files')."""
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    scene = tmp_path / "robust.toml"
    scene.write_text(ROBUST_SCENE)
    serial = run_cli("design", scene, "-o", tmp_path / "serial", "--cache-dir",
                     tmp_path / "cache-serial", "--jobs", "1")
    assert serial.returncode == 0, serial.stderr
    assert "the 10th percentile over [uncertainty.vary] (contact.restitution, " \
           "device.surface_charge_uC_per_m2; monte-carlo, N = 32: 32 evaluations per band " \
           "point)" in serial.stdout
    summary = json.loads((tmp_path / "serial" / "design.json").read_text())
    assert summary["settings"]["uncertainty"]["samples"] == 32
    assert summary["cost_per_candidate_s"]["uncertainty_evaluations"] == 4 * 32
    assert summary["cost_per_candidate_s"]["uncertainty_field_solves"] == 0
    best = summary["best"]
    assert best["objective"] < best["robust"]["nominal"]   # the worse decile of σ and e
    assert (tmp_path / "serial" / "design.png").stat().st_size > 10_000
    jobs = run_cli("design", scene, "-o", tmp_path / "jobs", "--cache-dir",
                   tmp_path / "cache-serial", "--jobs", "2")
    assert jobs.returncode == 0, jobs.stderr
    parallel = subprocess.run(
        ["mpirun", "-n", "2", sys.executable, "-m", "tengfield.cli", "design", str(scene),
         "-o", str(tmp_path / "mpi"), "--cache-dir", str(tmp_path / "cache-serial")],
        env=env(), capture_output=True, text=True, timeout=900)
    assert parallel.returncode == 0, parallel.stderr
    want = rows_of(tmp_path / "serial" / "design.csv")
    assert rows_of(tmp_path / "jobs" / "design.csv") == want
    got = rows_of(tmp_path / "mpi" / "design.csv")
    # the error bar holds the field solver's own error estimate (~1e-13 apart under mpirun)

    def exact(rows):
        return [{k: v for k, v in r.items() if k != "charge_error_C"} for r in rows]
    assert exact(got) == exact(want)
    assert [float(r["charge_error_C"]) for r in got] == pytest.approx(
        [float(r["charge_error_C"]) for r in want], rel=1e-9)
