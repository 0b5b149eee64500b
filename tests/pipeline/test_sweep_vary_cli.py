"""`tengfield sweep --vary` from the command line: files and figures, one-line errors, a
geometry key with real (coarse) field solves, and `mpirun -n 2` writing the serial file.
The σ/circuit runs read the analytic plate model's surrogate from a prepared cache (no
field solve: the surrogate scales with σ)."""
from __future__ import annotations

import csv
import shutil
import subprocess

import pytest

from tengfield import surrogate
from tengfield.scene import load_scene

import plate_model as fx

#: 0.6 s at 5 kHz, the transient 2 periods: 3000 rows a point (the points' outputs, not
#: their accuracy, are what these tests check)
SCENE = "[run]\nduration_s = 0.6\nsettle_periods = 2\nsample_rate_hz = 5000.0\n"


def prepared(tmp_path):
    """A short scene file and a cache holding its plate-model surrogate."""
    scene_file = tmp_path / "short.toml"
    scene_file.write_text(SCENE)
    cache = tmp_path / "cache"
    scene = load_scene(scene_file)
    surrogate.write_table(surrogate.cache_path(scene, cache),
                          surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve))
    return scene_file, cache


def rows_of(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


@pytest.mark.slow
def test_cli_vary_of_sigma_and_a_circuit_key_writes_rows_and_a_figure_per_key(tmp_path,
                                                                               run_cli):
    scene_file, cache = prepared(tmp_path)
    proc = run_cli("sweep", scene_file, "--cache-dir", cache,
                   "--vary", "device.surface_charge_uC_per_m2=-10:-30:3",
                   "--vary", "circuit.parallel_capacitance_pF=0,10", "--load-ohm", "1e8",
                   "--jobs", "1", "-o", tmp_path / "out", cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "surrogates: 1 geometry (0 computed, 1 cached; 5 points reuse one)" in proc.stderr
    out = tmp_path / "out"
    rows = rows_of(out / "sweep.csv")
    assert len(rows) == 6
    assert [(r["device.surface_charge_uC_per_m2"], r["circuit.parallel_capacitance_pF"])
            for r in rows] == [(s, c) for s in ("-10.0", "-20.0", "-30.0") for c in ("0", "10")]
    assert all(float(r["P_mean_W"]) > 0 for r in rows)
    for key in ("device.surface_charge_uC_per_m2", "circuit.parallel_capacitance_pF"):
        assert (out / f"sweep_{key}.png").stat().st_size > 20_000
    assert not (out / "sweep.png").exists()
    assert "6 rows; wrote" in proc.stdout


@pytest.mark.slow
@pytest.mark.parametrize("args, expected", [
    (["--vary", "device.stroke_mm=2,-1"],
     "tengfield: error: sweep point device.stroke_mm = -1: [device] stroke_mm = -1.0 is out "
     "of range: allowed [1e-06, 10000]"),
    (["--vary", "device.strok_mm=1:2:2"],
     "unknown key [device] strok_mm (did you mean 'stroke_mm'?)"),
    (["--vary", "device.stroke_mm=1:2"], "tengfield: error: --vary 'device.stroke_mm=1:2': "
                                         "expected START:STOP:N"),
    (["--vary", "device.stroke_mm=1,2", "--vary", "device.stroke_mm=3"],
     "tengfield: error: --vary device.stroke_mm is given twice"),
    (["--frequency-hz", "20"], "tengfield: error: sweep needs --amplitude-mm"),
])
def test_cli_bad_vary_is_one_line_and_writes_nothing(tmp_path, run_cli, args, expected):
    scene_file, cache = prepared(tmp_path)
    proc = run_cli("sweep", scene_file, "--cache-dir", cache, *args, "-o", tmp_path / "out",
                   cwd=tmp_path, timeout=300)
    assert proc.returncode == 2, proc.stderr
    ours = [ln for ln in proc.stderr.splitlines() if ln.startswith("tengfield")]
    assert len(ours) == 1 and expected in ours[0], proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
@pytest.mark.field
def test_cli_vary_of_a_geometry_key_solves_each_geometry_once(tmp_path, run_cli, cli_env):
    """Two strokes (a coarse real field each) crossed with two restitutions: two field
    solves; the second run finds both in the cache."""
    (tmp_path / "g.toml").write_text(
        "[run]\nduration_s = 0.5\nsettle_periods = 2\nsample_rate_hz = 5000.0\n"
        "[field]\nmesh_size_mm = 1.5\ndegree = 1\ntolerance = 0.05\n")
    env = cli_env(MPLBACKEND="Agg", TENGFIELD_CACHE_DIR=tmp_path / "cache")
    args = ["sweep", "g.toml", "--vary", "device.stroke_mm=2.5,3", "--vary",
            "contact.restitution=0.5,0.7", "--jobs", "1"]
    first = run_cli(*args, "-o", "a", cwd=tmp_path, env=env, timeout=900)
    assert first.returncode == 0, first.stderr
    assert "surrogates: 2 geometries (2 computed, 0 cached; 2 points reuse one)" in first.stderr
    rows = rows_of(tmp_path / "a" / "sweep.csv")
    assert [r["device.stroke_mm"] for r in rows] == ["2.5", "2.5", "3", "3"]   # as written
    assert all(float(r["Q_sc_pp_C"]) > 0 for r in rows)
    assert (tmp_path / "a" / "sweep_device.stroke_mm.png").stat().st_size > 20_000
    second = run_cli(*args, "--no-plots", "-o", "b", cwd=tmp_path, env=env, timeout=900)
    assert second.returncode == 0, second.stderr
    assert "surrogates: 2 geometries (0 computed, 2 cached; 2 points reuse one)" in second.stderr
    assert (tmp_path / "b" / "sweep.csv").read_text() == (tmp_path / "a" / "sweep.csv").read_text()
    assert not list((tmp_path / "b").glob("*.png"))


@pytest.mark.slow
def test_cli_vary_under_mpirun_writes_the_serial_file(tmp_path, cli_command, cli_env):
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    scene_file, cache = prepared(tmp_path)
    env = cli_env(MPLBACKEND="Agg", OMPI_MCA_rmaps_base_oversubscribe="1")
    args = cli_command("sweep", scene_file, "--cache-dir", cache,
                       "--vary", "device.surface_charge_uC_per_m2=-10,-20",
                       "--vary", "contact.restitution=0.5:0.7:3", "--frequency-hz", "20",
                       "--amplitude-mm", "1:1.5:2")
    # the serial reference without figures (only its sweep.csv is compared; the MPI
    # run's figure is asserted below)
    serial = subprocess.run(args + ["--jobs", "1", "--no-plots",
                                    "-o", str(tmp_path / "serial")],
                            capture_output=True, text=True, env=env, timeout=300)
    assert serial.returncode == 0, serial.stderr
    parallel = subprocess.run(["timeout", "280", "mpirun", "-n", "2"] + args
                              + ["-o", str(tmp_path / "mpi")],
                              capture_output=True, text=True, env=env, timeout=300)
    assert parallel.returncode == 0, parallel.stderr
    text = (tmp_path / "serial" / "sweep.csv").read_text()
    assert (tmp_path / "mpi" / "sweep.csv").read_text() == text
    assert len(rows_of(tmp_path / "serial" / "sweep.csv")) == 12
    assert parallel.stdout.count("12 rows; wrote") == 1          # rank 0 alone writes
    assert (tmp_path / "mpi" / "sweep_contact.restitution.png").stat().st_size > 20_000
