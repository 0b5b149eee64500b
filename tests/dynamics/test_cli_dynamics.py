"""End-to-end: `tengfield dynamics` and `tengfield map` on small scenes."""
import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tengfield.cli import main

SMALL_SCENE = """
[excitation]
frequency_hz = 30.0
amplitude_mm = 3.0
[run]
duration_s = 0.3
settle_periods = 3
sample_rate_hz = 2000.0
"""


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "small.toml"
    p.write_text(SMALL_SCENE)
    return p


def test_cli_dynamics_writes_all_outputs(scene_file, tmp_path):
    out = tmp_path / "dyn"
    assert main(["dynamics", str(scene_file), "-o", str(out)]) == 0
    data = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    assert data.dtype.names == ("time_s", "gap_m", "gap_velocity_m_per_s", "table_m")
    assert data.size == 601
    assert np.all((data["gap_m"] >= 0) & (data["gap_m"] <= 3e-3))
    with open(out / "impacts.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert rows and set(rows[0]) == {"time_s", "plate", "speed_before_m_per_s",
                                     "speed_after_m_per_s"}
    assert {r["plate"] for r in rows} == {"lower", "upper"}
    summary = json.loads((out / "summary.json").read_text())
    for key in ("regime", "period", "max_gap_mm", "upper_contacts_per_period",
                "lower_contacts_per_period", "impacts", "wall_time_s"):
        assert key in summary
    assert summary["impacts"] == len(rows)
    assert summary["max_gap_mm"] == pytest.approx(3.0)
    assert (out / "trajectory.png").stat().st_size > 10_000


def test_cli_map_small_grid(scene_file, tmp_path):
    out = tmp_path / "map"
    rc = main(["map", str(scene_file), "--frequency-hz", "5:40:4", "--amplitude-mm", "0.2:3:3",
               "--periods", "40", "--jobs", "2", "-o", str(out)])
    assert rc == 0
    with open(out / "map.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 12
    by_point = {(float(r["frequency_hz"]), float(r["amplitude_mm"])): r for r in rows}
    # below the lift-off curve (Gamma < 1) the ball rests
    assert by_point[(5.0, 0.2)]["regime"] == "rest"
    assert by_point[(40.0, 3.0)]["regime"] in ("regular-contact", "critical-contact", "chaos")
    assert (out / "map.png").stat().st_size > 10_000


@pytest.mark.parametrize("bad", ["5:70", "a:b:3", "5:70:0", "-5:70:3", "5:inf:3"])
def test_cli_map_bad_range_is_a_clear_error(bad, tmp_path, capsys):
    rc = main(["map", f"--frequency-hz={bad}", "--amplitude-mm", "1:2:2", "-o", str(tmp_path)])
    assert rc == 2
    err = capsys.readouterr().err
    assert "--frequency-hz" in err and "Traceback" not in err


@pytest.mark.slow
def test_console_script_dynamics(scene_file, tmp_path):
    exe = Path(sys.executable).parent / "tengfield"
    out = tmp_path / "dyn"
    proc = subprocess.run([str(exe), "dynamics", str(scene_file), "-o", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "regime" in proc.stdout
    assert (out / "summary.json").exists()
    bad = subprocess.run([str(exe), "map", "--frequency-hz", "1:2", "--amplitude-mm", "1:2:2"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "START:STOP:N" in bad.stderr and "Traceback" not in bad.stderr


@pytest.mark.slow
def test_dynamics_run_does_not_import_fem_stack(scene_file, tmp_path):
    code = ("import sys; from tengfield.cli import main; "
            f"main(['dynamics', {str(scene_file)!r}, '-o', {str(tmp_path / 'o')!r}]); "
            "bad = [m for m in sys.modules if m.split('.')[0] in "
            "('dolfinx', 'gmsh', 'pyvista', 'petsc4py', 'ufl', 'basix')]; "
            "print('HEAVY', bad); sys.exit(1 if bad else 0)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.parametrize("spelling", ["--no-plots", "--no-plot"])
def test_cli_dynamics_without_plots_writes_the_tables_only(scene_file, tmp_path, spelling):
    """`--no-plots` (as `run`, `fit`, `field`, `map` and `sweep` spell it; `--no-plot` too)
    skips the PNG and writes the same CSVs and summary as a run with the figure."""
    with_plot, without = tmp_path / "a", tmp_path / "b"
    assert main(["dynamics", str(scene_file), "-o", str(with_plot)]) == 0
    assert main(["dynamics", str(scene_file), "-o", str(without), spelling]) == 0
    assert not list(without.glob("*.png"))
    for name in ("trajectory.csv", "impacts.csv"):
        assert (without / name).read_bytes() == (with_plot / name).read_bytes()
    summaries = [json.loads((d / "summary.json").read_text()) for d in (with_plot, without)]
    for s in summaries:
        s.pop("wall_time_s")
    assert summaries[0] == summaries[1]


def test_cli_map_without_plots(scene_file, tmp_path):
    out = tmp_path / "map"
    assert main(["map", str(scene_file), "--frequency-hz", "10:20:2", "--amplitude-mm", "1:2:2",
                 "--periods", "20", "--jobs", "1", "--no-plots", "-o", str(out)]) == 0
    assert (out / "map.csv").exists() and not (out / "map.png").exists()


def test_duration_option_draws_the_noise_for_the_whole_run(tmp_path):
    """--duration-s longer than [run] duration_s of a random scene: the record is drawn
    for the run asked for (it failed: "outside the recorded excitation [-0.01, 0.6]");
    on a sine it equals the scene file with that duration."""
    noise = ('[excitation]\nkind = "random"\nband_hz = [10.0, 100.0]\n'
             'rms_acceleration_m_per_s2 = 10.0\n[run]\nduration_s = 0.5\nsettle_periods = 1\n')
    (tmp_path / "r.toml").write_text(noise)
    assert main(["dynamics", str(tmp_path / "r.toml"), "--duration-s", "3",
                 "-o", str(tmp_path / "r"), "--no-plots"]) == 0
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["duration_s"] == 3.0
    t = np.loadtxt(tmp_path / "r" / "trajectory.csv", delimiter=",", skiprows=1)[:, 0]
    assert t[-1] - t[0] == pytest.approx(3.0)
    (tmp_path / "s.toml").write_text("[run]\nduration_s = 0.5\nsettle_periods = 2\n")
    (tmp_path / "s2.toml").write_text("[run]\nduration_s = 2.0\nsettle_periods = 2\n")
    assert main(["dynamics", str(tmp_path / "s.toml"), "--duration-s", "2",
                 "-o", str(tmp_path / "a"), "--no-plots"]) == 0
    assert main(["dynamics", str(tmp_path / "s2.toml"), "-o", str(tmp_path / "b"),
                 "--no-plots"]) == 0
    assert (tmp_path / "a" / "trajectory.csv").read_bytes() == \
        (tmp_path / "b" / "trajectory.csv").read_bytes()
