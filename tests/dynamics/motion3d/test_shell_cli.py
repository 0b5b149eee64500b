"""End to end: `tengfield dynamics` of a spherical shell with `[contact] model = "3d"` and a
3-axis drive (figures on), and `tengfield run` refusing it in one line until the shell's
(z, r) surrogate exists (issue #32)."""
import csv
import json

import numpy as np
import pytest

from tengfield.cli import main

SHELL_3D = """\
[device]
shape = "spherical-shell"
cavity_diameter_mm = 20
shell_thickness_mm = 2
electrode_band_mm = 2
ball_diameter_mm = 8
wall_permittivity = 3.0
surface_charge_uC_per_m2 = -50

[excitation]
frequency_hz = 20
amplitude_mm = 3
amplitude_x_mm = 1
phase_x_deg = 60

[contact]
model = "3d"

[run]
duration_s = 0.4
settle_periods = 2
sample_rate_hz = 5000
"""


@pytest.fixture
def shell_file(tmp_path):
    path = tmp_path / "shell3d.toml"
    path.write_text(SHELL_3D)
    return path


@pytest.mark.slow
def test_dynamics_of_the_ball_in_the_shell_writes_its_files_and_figures(shell_file, tmp_path):
    out = tmp_path / "out"
    assert main(["dynamics", str(shell_file), "-o", str(out)]) == 0
    for name in ("trajectory.csv", "impacts.csv", "contacts.csv", "summary.json",
                 "trajectory.png", "trajectory3d.png"):
        assert (out / name).exists(), name
    assert (out / "trajectory3d.png").stat().st_size > 10_000
    table = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    a, r = 10e-3, 4e-3
    centre = np.column_stack([table["x_m"], table["y_m"], table["gap_m"] + r - a])
    assert np.max(np.linalg.norm(centre, axis=1)) <= a - r + 2e-5   # compliant: microns
    assert np.max(table["radial_m"]) > 0.5 * (a - r)                 # off the axis
    with open(out / "contacts.csv", newline="") as f:
        surfaces = [row["surface"] for row in csv.DictReader(f)]
    summary = json.loads((out / "summary.json").read_text())
    assert {"lower", "upper", "band"} <= set(surfaces) and "wall" not in surfaces
    assert surfaces.count("band") == summary["wall_contacts"] > 0
    with open(out / "impacts.csv", newline="") as f:
        plates = {row["plate"] for row in csv.DictReader(f)}
    assert plates == {"lower", "upper"}


@pytest.mark.slow
def test_run_refuses_the_shells_3d_contact_in_one_line(shell_file, tmp_path, capsys):
    assert main(["run", str(shell_file), "-o", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("tengfield: error: [contact] model = '3d' on shape = "
                             "'spherical-shell': the field stage needs the shell's (z, r) "
                             "surrogate")
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_an_uncharged_ball_runs_without_a_field_stage(shell_file, tmp_path):
    """No field stage, nothing refused: the 3D motion and zero outputs; the shell's field
    hash does not depend on the contact model."""
    from tengfield.scene import load_scene

    shell_file.write_text(SHELL_3D.replace("surface_charge_uC_per_m2 = -50",
                                           "surface_charge_uC_per_m2 = 0"))
    out = tmp_path / "run0"
    assert main(["run", str(shell_file), "-o", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (out / "trajectory3d.png").exists() and (out / "contacts.csv").exists()
    scene = load_scene(shell_file)
    assert summary["field_hash"] == scene.field_hash() == scene.with_values(
        contact={"model": "impact"}).field_hash()
