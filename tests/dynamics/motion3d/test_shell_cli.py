"""End to end: `tengfield dynamics` of a spherical shell with `[contact] model = "3d"` and a
3-axis drive (figures on), and `tengfield run` refusing it in one line until the shell's
(z, r) surrogate exists (issue #32)."""
import csv
import json

import numpy as np
import pytest
from shell_model import SHELL, shell_device_toml  # noqa: F401

from tengfield.cli import main

SHELL_3D = shell_device_toml() + """\
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
@pytest.mark.field
def test_run_joins_the_shells_3d_contact_to_its_zr_surrogate(shell_file, tmp_path, monkeypatch):
    """`tengfield run` of the ball rolling and bouncing in the shell: the 3D contact's (z, r)
    path feeds the shell's (z, r) surrogate (offsets scaled to the cavity at each height),
    anchored on the axisymmetric one; figures on. The (z, r) table is built small here
    (P1, 5 mm, one round of 5 heights x 3 offsets: 3 heights solved by the mirror symmetry,
    the ends on the axis; gmsh's meshing is most of each solve) instead of the default
    (P2, 1.5 mm, from 17 x 3 up to 33 x 9: ~17 min on one core): the join is under test,
    not the table's accuracy. (This 5-height grid hit a gmsh HXT meshing failure at 4 mm,
    in the coarse mesh of an error estimate; 4.5 and 5 mm mesh it.)"""
    import functools

    from tengfield import pipeline

    monkeypatch.setattr(pipeline, "obtain_radial_table", functools.partial(
        pipeline.obtain_radial_table, initial_positions=3, max_positions=5, max_offsets=3))
    shell_file.write_text(SHELL_3D.replace("[run]", "[field]\nmesh_size_mm = 2\ndegree = 1\n"
                                           "radial_mesh_size_mm = 5\nradial_degree = 1\n\n[run]"))
    out = tmp_path / "run"
    assert main(["run", str(shell_file), "-o", str(out), "--cache-dir", str(tmp_path / "cache")]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field_zr"]["status"] == "ran"
    assert "1-D surrogate on the axis" in summary["stages"]["field_zr"]["details"]["curves"]
    for name in ("waveforms.png", "surrogate.png", "trajectory3d.png", "trajectory.png"):
        assert (out / name).stat().st_size > 10_000, name
    with open(out / "waveforms.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(row["time_s"]) for row in rows])
    q = np.array([float(row["Q_sc_C"]) for row in rows])
    i = np.array([float(row["I_sc_A"]) for row in rows])
    with open(out / "trajectory.csv", newline="") as f:
        radial = np.array([float(row["radial_m"]) for row in csv.DictReader(f)])
    a, r = 10e-3, 4e-3
    assert radial.max() > 0.5 * (a - r)                    # the ball did leave the axis
    ball_charge = 50e-6 * np.pi * (2 * r) ** 2
    assert 0.05 * ball_charge < np.ptp(q) < ball_charge     # moved, and never more than Q
    # I_SC = dQ/dz z' + dQ/dr r': the time derivative of the sampled Q_SC
    assert np.median(np.abs(np.gradient(q, t) - i)) < 2e-2 * np.abs(i).max()


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
