"""End to end: `tengfield dynamics` of a spherical shell with `[contact] model = "3d"` and a
3-axis drive (figures on), and `tengfield run` refusing it in one line until the shell's
(z, r) surrogate exists (issue #32)."""
import csv
import json

import numpy as np
import pytest
from shell_zr_run import SHELL_3D, ZR_FIELD, ZR_GRID, shell_zr_run

from tengfield.cli import main


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
def test_run_joins_the_shells_3d_contact_to_its_zr_surrogate(tmp_path_factory):
    """`tengfield run` of the ball rolling and bouncing in the shell: the 3D contact's (z, r)
    path feeds the shell's (z, r) surrogate (offsets scaled to the cavity at each height),
    anchored on the axisymmetric one; figures on. The (z, r) table is built small
    (tests/shell_zr_run.py: P1, 5 mm, one round of 5 x 3): the join is under test, not
    the table's accuracy. The run is shared with test_spherical_shell_3d.py's held-out
    check of the same table (issue #41); its table is computed by this run ("ran")."""
    scene_file, out, cache = shell_zr_run(tmp_path_factory)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stages"]["field_zr"]["status"] == "ran"
    details = summary["stages"]["field_zr"]["details"]
    assert "1-D surrogate on the axis" in details["curves"]
    assert details["grid"] == [ZR_GRID["max_positions"], ZR_GRID["max_offsets"]]
    assert details["mesh_size_mm"] == pytest.approx(ZR_FIELD["radial_mesh_size_mm"])
    assert details["degree"] == ZR_FIELD["radial_degree"]
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
