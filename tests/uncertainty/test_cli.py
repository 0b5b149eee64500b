"""``tengfield uncertainty`` end to end: the files with figures on, the terminal lines, the
same uncertainty.csv serially, with --jobs 2 and under mpirun -n 2, and bad input as one
line (issue #34). Uses the default scene's surrogate from the cache."""
from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from helpers import mpi_env

pytestmark = pytest.mark.slow

STUDY = """
[uncertainty]
samples = 16
method = "sobol"
seed = 5

[uncertainty.vary]
"device.surface_charge_uC_per_m2" = { distribution = "uniform", low = -25.9, high = -13.0 }
"contact.restitution" = { distribution = "uniform", low = 0.05, high = 0.5 }
"""


def test_serial_jobs_and_mpirun_write_the_same_csv(tmp_path, run_cli, cli_command):
    scene = tmp_path / "study.toml"
    scene.write_text(STUDY)
    serial = run_cli("uncertainty", scene, "-o", tmp_path / "serial", "--jobs", "1")
    assert serial.returncode == 0, serial.stderr
    out = tmp_path / "serial"
    assert {p.name for p in out.iterdir() if not p.name.startswith(".")} == {
        "uncertainty.csv", "uncertainty.json", "uncertainty.png"}
    assert (out / "uncertainty.png").stat().st_size > 10_000
    data = json.loads((out / "uncertainty.json").read_text())
    assert data["evaluations"] == 16 * 4 and data["samples"] == 16 and data["seed"] == 5
    q = data["outputs"]["peak_to_peak.Q_sc_C"]
    assert set(q["percentiles"]) == {"5", "25", "50", "75", "95"}
    assert set(q["sobol"]) == {"device.surface_charge_uC_per_m2", "contact.restitution"}
    assert data["field_solves"] <= 1
    assert abs(sum(r["fraction"] for r in data["regimes"].values()) - 1.0) < 1e-12
    lines = serial.stdout.splitlines()
    assert any(line.strip().startswith("Q_SC peak-to-peak [nC]: nominal")
               and "90 % in [" in line and "dominated by" in line
               for line in lines), serial.stdout
    rows = (out / "uncertainty.csv").read_text().splitlines()
    assert len(rows) == 1 + 64
    assert rows[0].startswith("evaluation,device.surface_charge_uC_per_m2,contact.restitution,"
                              "regime,")

    jobs = run_cli("uncertainty", scene, "-o", tmp_path / "jobs", "--jobs", "2", "--no-plots")
    assert jobs.returncode == 0, jobs.stderr
    assert (tmp_path / "jobs" / "uncertainty.csv").read_bytes() == \
        (out / "uncertainty.csv").read_bytes()
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    proc = subprocess.run(["mpirun", "-n", "2", *cli_command(
        "uncertainty", scene, "-o", tmp_path / "mpi", "--no-plots")], capture_output=True,
        text=True, env=mpi_env(), timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "mpi" / "uncertainty.csv").read_bytes() == \
        (out / "uncertainty.csv").read_bytes()


def test_bad_input_is_one_line_and_exit_2(tmp_path, run_cli):
    scene = tmp_path / "bad.toml"
    scene.write_text(STUDY.replace("high = 0.5", "high = 1.5"))
    proc = run_cli("uncertainty", scene, "-o", tmp_path / "out")
    assert proc.returncode == 2
    ours = [line for line in proc.stderr.splitlines() if line.startswith("tengfield")]
    assert len(ours) == 1 and ours[0].startswith("tengfield: error: ")
    assert "contact.restitution" in ours[0] and "allowed [0, 1]" in ours[0]
    assert not (tmp_path / "out").exists()


def test_draws_beyond_the_breakdown_limit_are_counted_and_named(tmp_path, run_cli):
    """σ up to 35.8 uC/m^2 (what the paper's 1.42 nC needs) exceeds the default device's
    limit, 25.9 uC/m^2 (docs/breakdown.md): the draws above it are counted, one warning."""
    scene = tmp_path / "beyond.toml"
    scene.write_text(STUDY.replace("low = -25.9, high = -13.0", "low = -35.8, high = -13.0")
                     .replace('method = "sobol"', 'method = "monte-carlo"')
                     .replace("samples = 16", "samples = 40"))
    proc = run_cli("uncertainty", scene, "-o", tmp_path / "out", "--no-plots", "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    data = json.loads((tmp_path / "out" / "uncertainty.json").read_text())
    import csv
    with open(tmp_path / "out" / "uncertainty.csv", newline="") as f:
        sigma = [float(r["device.surface_charge_uC_per_m2"]) for r in csv.DictReader(f)]
    expected = sum(abs(s) > 25.9 * 1.02 for s in sigma)     # sigma_max within its 1.1 %
    assert expected <= data["beyond_breakdown"] <= sum(abs(s) > 25.9 * 0.98 for s in sigma)
    assert data["beyond_breakdown"] > 0
    warned = [line for line in proc.stderr.splitlines() if "air-breakdown limit" in line]
    assert len(warned) == 1 and warned[0].startswith("tengfield: warning: "), proc.stderr
