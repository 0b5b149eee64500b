"""`tengfield design` answers the question end to end (issue 31; real field solver, figures
on): the answer on stdout, one warning line per problem, no progress display when piped,
a best.toml that `tengfield run` takes to the value it names, a default study on a scene
without [design], and a bad spec under mpirun as one line with exit 2."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from helpers import mpi_env as env

SCENE = """
[field]
degree = 2
mesh_size_mm = 1.0
tolerance = 0.02
[design]
objective = "power"
candidates = 4
batch = 2
seed = 3
field = "scene"
settle_periods = 10
window_periods = 10
samples_per_period = 120
[design.vary]
stroke_mm = [1.5, 4.0]
[design.excitation]
frequency_hz = [25.0, 33.0]
amplitude_mm = [0.3, 1.0]
"""


def warnings_of(stderr: str) -> list[str]:
    return [ln for ln in stderr.splitlines() if ln.startswith("tengfield: warning: ")]


@pytest.mark.slow   # real field solves (4 geometries) and a run
def test_cli_states_the_answer_warns_and_best_toml_runs_to_its_value(tmp_path, run_cli):
    scene = tmp_path / "band.toml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    proc = run_cli("design", scene, "-o", out, "--cache-dir", tmp_path / "cache", "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    # piped: no progress display
    assert "candidate/s" not in proc.stderr and "it/s" not in proc.stderr
    assert "\r" not in proc.stderr
    # the answer
    summary = json.loads((out / "design.json").read_text())
    best = summary["best"]
    assert f"plate spacing h = stroke + ball diameter = {best['plate_spacing_mm']:g} mm" \
        in proc.stdout
    assert "σ = -8 µC/m^2 (the scene's)" in proc.stdout and "load: matched" in proc.stdout
    assert "25 Hz" in proc.stdout and "rest" in proc.stdout
    assert best["band_points"][0]["regime"] == "rest" and best["band_points"][0]["value"] == 0
    # one warning line: the band point where nothing moves
    moves = [w for w in warnings_of(proc.stderr) if "no candidate moves" in w]
    assert moves and moves[0].startswith("tengfield: warning: 25 Hz / 0.3 mm: no candidate "
                                         "moves")
    assert len(warnings_of(proc.stderr)) == len(summary["warnings"])
    assert (out / "design.png").stat().st_size > 10_000
    # best.toml runs at the band point it names, to its value within 1 %
    point = summary["best_toml_band_point"]
    assert point["value"] > 0 and (point["frequency_hz"], point["amplitude_mm"]) != (25.0, 0.3)
    run = run_cli("run", out / "best.toml", "-o", tmp_path / "run", "--cache-dir",
                  tmp_path / "cache", "--no-plots")
    assert run.returncode == 0, run.stderr
    ran = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert ran["regime"]["regime"] != "rest"
    assert ran["load"]["mean_power_W"] == pytest.approx(point["value"], rel=0.01)


@pytest.mark.slow   # real field solves (4 geometries)
def test_a_scene_without_design_gets_a_default_study_said_in_one_line(tmp_path, run_cli):
    out = tmp_path / "out"
    proc = run_cli("design", "-o", out, "--cache-dir", tmp_path / "cache", "--jobs", "1",
                   "--candidates", "4", "--no-plots")
    assert proc.returncode == 0, proc.stderr
    said = [ln for ln in proc.stderr.splitlines() if "has no [design]" in ln]
    assert said == [
        "tengfield: <default> has no [design]: a default study of power density over "
        "stroke_mm = [1.5, 4.5] and ball_diameter_mm = [4.9, 9.1] (tube and electrodes follow "
        "the ball) at 20 Hz / 1.5 mm, 4 candidates (docs/design.md: write a [design] "
        "section for your own)"]
    summary = json.loads((out / "design.json").read_text())
    assert summary["settings"]["vary"] == {"stroke_mm": [1.5, 4.5],
                                           "ball_diameter_mm": [4.9, 9.1]}
    assert summary["counts"]["ok"] == 4 and "best:" in proc.stdout


@pytest.mark.slow
def test_a_bad_spec_under_mpirun_is_one_line_and_exit_2(tmp_path):
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")
    bad = tmp_path / "bad.toml"
    bad.write_text('[design]\ncandidates = 3\n[design.vary]\nstroke_mm = [1.0, 5.0]\n')
    proc = subprocess.run(
        ["mpirun", "-n", "2", sys.executable, "-m", "tengfield.cli", "design", str(bad),
         "-o", str(tmp_path / "out")], env=env(), capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    ours = [ln for ln in proc.stderr.splitlines() if ln.startswith("tengfield")]
    assert ours == ["tengfield: error: [design] candidates = 3 is out of range: allowed "
                    "whole numbers [4, 100000]"]
    assert "MPI_ABORT" not in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()
