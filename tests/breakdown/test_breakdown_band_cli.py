"""The band on the command line (issue #38): ``tengfield breakdown`` writes it to
breakdown.json with its figure panel and says what each edge assumes; ``mpirun -n 2``
gives the same band; ``tengfield run`` with σ = "breakdown" prints each main output as
its band and writes summary.json ``breakdown_band``."""
import json
import shutil
import subprocess

import pytest
from band_scene import band_scene
from helpers import mpi_env

pytestmark = [pytest.mark.slow, pytest.mark.field]

def scene_text(sigma: str) -> str:
    return band_scene(sigma, "[instrument]\ncapacitance_pF = 338\n")


@pytest.fixture(scope="module")
def env(tmp_path_factory, cli_env):
    return cli_env(TENGFIELD_CACHE_DIR=tmp_path_factory.mktemp("cache"))


def test_breakdown_writes_the_band_and_mpirun_agrees(tmp_path, run_cli, cli_command, env):
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text("-8"))
    proc = run_cli("breakdown", scene, "-o", tmp_path / "serial", env=env)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((tmp_path / "serial" / "breakdown.json").read_text())
    band = data["band"]
    assert band["lower_uC_per_m2"] <= band["estimate_uC_per_m2"] <= band["upper_uC_per_m2"]
    assert band["gamma_range"] == [1e-4, 0.1]
    assert band["S_v_per_m3_s"] == 1e7 and band["n_ion_per_m3"] == 5e8
    assert {"lower_binds_at", "upper_binds_at", "estimate_binds_at"} <= set(band)
    assert 0.0 < data["trajectory"]["peak_gap_voltage_over_breakdown"] < 1.0   # -8 uC/m^2
    assert (tmp_path / "serial" / "breakdown.png").stat().st_size > 10_000
    out = proc.stdout.splitlines()
    assert any(line.startswith("static limit sigma_max by gamma in [0.0001, 0.1]: ") for line in out)
    for edge in ("lower", "estimate", "upper"):
        assert sum(line.strip().startswith(edge + " ") for line in out) == 1, proc.stdout
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    mpi = subprocess.run(["mpirun", "-n", "2", *cli_command(
        "breakdown", scene, "-o", tmp_path / "mpi", "--no-plots")], capture_output=True,
        text=True, env={**mpi_env(), **{k: v for k, v in env.items() if k.startswith(
            ("TENGFIELD", "PYTHONPATH"))}}, timeout=600)
    assert mpi.returncode == 0, mpi.stderr
    assert json.loads((tmp_path / "mpi" / "breakdown.json").read_text())["band"] == band


def test_run_at_the_breakdown_charge_prints_each_output_as_its_band(tmp_path, run_cli, env):
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text('"breakdown"'))
    proc = run_cli("run", scene, "-o", tmp_path / "run", env=env)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    outputs = summary["breakdown_band"]
    band = summary["breakdown"]["band"]
    sigma = -summary["breakdown"]["sigma_uC_per_m2"]
    for key in ("peak_to_peak.Q_sc_C", "peak.I_sc_A", "peak_to_peak.V_read_V"):
        stat, name = key.split(".")
        for edge in ("lower", "estimate", "upper"):
            assert outputs[key][edge] == pytest.approx(
                summary[stat][name] * band[f"{edge}_uC_per_m2"] / sigma, rel=1e-12)
    assert "time_above_breakdown_s" in summary["breakdown"]["trajectory"]
    out = proc.stdout
    assert "short-circuit charge Q_SC, peak-to-peak: " in out
    assert "(lower / estimate / upper)" in out and "  band: lower " in out
