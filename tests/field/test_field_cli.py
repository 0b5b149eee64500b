"""End-to-end: ``tengfield field`` on the default scene writes the three files."""
import json
import os
import subprocess

import pytest

pytest.importorskip("dolfinx")
pytest.importorskip("pyvista")


@pytest.fixture
def field_cli(run_cli, cli_env):
    """``field_cli(*args, cwd)``: ``tengfield field args...`` off screen."""
    return lambda *args, cwd: run_cli("field", *args, cwd=cwd,
                                      env=cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true"))


@pytest.mark.slow
def test_field_command_writes_json_xdmf_png(tmp_path, field_cli):
    scene = tmp_path / "coarse.toml"
    scene.write_text("[field]\nmesh_size_mm = 0.8\n")
    out = tmp_path / "out"
    done = field_cli(str(scene), "--position-mm", "1.5", "-o", str(out), cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "C_T (floating)" in done.stdout and "V_OC" in done.stdout
    data = json.loads((out / "field.json").read_text())
    cap, q = data["capacitance_F"], data["induced_charge_C"]
    assert set(cap) == {"lower_lower", "lower_upper", "upper_upper"}
    assert set(q) == {"lower", "upper"}
    assert cap["lower_lower"] > 0 > cap["lower_upper"]
    assert data["method"] == "axisymmetric" and data["degree"] == 2
    assert 0 < data["relative_error_estimate"] < 1e-2
    # ball at mid-stroke of a symmetric device: equal induced charges, each < |q_ball|/2
    assert q["lower"] == pytest.approx(q["upper"], rel=1e-3)
    assert 0 < q["upper"] < -0.5 * data["ball_charge_C"]
    # a negatively charged ball above its rest position: V_OC = V_lower - V_upper > 0
    v = data["open_circuit_potential_V"]
    assert v["lower"] - v["upper"] > 0
    assert (out / "potential.xdmf").stat().st_size > 0
    assert (out / "potential.h5").stat().st_size > 0
    png = (out / "field.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 50_000


@pytest.mark.slow
def test_field_command_reports_bad_position_without_traceback(tmp_path, field_cli):
    done = field_cli("--position-mm", "3.5", "-o", str(tmp_path / "x"), cwd=tmp_path)
    assert done.returncode == 2
    assert "position_mm = 3.5 is out of range: allowed [0, 3] mm" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.slow
def test_field_command_3d_on_two_ranks_equals_serial(tmp_path, field_cli, cli_command):
    """``mpirun -n 2 tengfield field --method 3d`` writes field.json and the weighting
    potentials, with the numbers of the serial run (same gmsh mesh: gmsh runs on rank 0)."""
    import shutil

    mpirun = shutil.which("mpirun")
    if mpirun is None:
        pytest.skip("mpirun not installed")
    scene = tmp_path / "coarse3d.toml"
    scene.write_text("[field]\nmesh_size_mm = 3.0\ndegree = 1\n")   # coarse: the same path
    args = [str(scene), "--method", "3d", "--position-mm", "1.5", "--offset-mm", "0.2"]
    serial = field_cli(*args, "-o", str(tmp_path / "serial"), cwd=tmp_path)
    assert serial.returncode == 0, serial.stderr[-3000:]
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "MPLBACKEND": "Agg"}
    env.pop("OMPI_COMM_WORLD_SIZE", None)
    parallel = subprocess.run([mpirun, "-n", "2",
                               *cli_command("field", *args, "-o", tmp_path / "mpi")],
                              capture_output=True, text=True, cwd=tmp_path, env=env)
    assert parallel.returncode == 0, parallel.stderr[-3000:]
    one = json.loads((tmp_path / "serial" / "field.json").read_text())
    two = json.loads((tmp_path / "mpi" / "field.json").read_text())
    assert one["method"] == two["method"] == "3d"
    for group in ("capacitance_F", "induced_charge_C"):
        for key, value in one[group].items():
            assert two[group][key] == pytest.approx(value, rel=1e-8), (group, key)
    for out in ("serial", "mpi"):
        assert (tmp_path / out / "potential.xdmf").stat().st_size > 0
        assert (tmp_path / out / "potential.h5").stat().st_size > 0
    png = (tmp_path / "serial" / "field.png").read_bytes()   # serial 3D runs draw the section
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000


@pytest.mark.slow
def test_field_command_solves_at_the_breakdown_charge(tmp_path, run_cli, cli_env):
    """``surface_charge_uC_per_m2 = "breakdown"``: the one-position solve is at -sigma_max,
    the charge a run uses (it was at the stand-in -1 uC/m^2, silently), figures on; and
    it equals a solve at that sigma written as a number."""
    import math

    env = cli_env(MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true",
                  TENGFIELD_CACHE_DIR=str(tmp_path / "cache"))
    coarse = "[field]\ndegree = 1\nmesh_size_mm = 1.0\ntolerance = 0.2\n"
    (tmp_path / "bd.toml").write_text('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n'
                                      + coarse)
    done = run_cli("field", "bd.toml", "--position-mm", "1.5", "-o", "out", cwd=tmp_path,
                   env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    limit = run_cli("breakdown", "bd.toml", "-o", "bd", "--no-plots", cwd=tmp_path, env=env)
    sigma_max = json.loads((tmp_path / "bd" / "breakdown.json").read_text())[
        "sigma_max_uC_per_m2"]
    assert limit.returncode == 0 and 10 < sigma_max < 60
    data = json.loads((tmp_path / "out" / "field.json").read_text())
    area = math.pi * 7e-3 ** 2                       # the default ball, 7 mm
    assert data["ball_charge_C"] == pytest.approx(-sigma_max * 1e-6 * area, rel=1e-9)
    assert f"-sigma_max = {-sigma_max:.4g} µC/m^2" in done.stdout
    assert (tmp_path / "out" / "field.png").stat().st_size > 50_000
    (tmp_path / "num.toml").write_text(f"[device]\nsurface_charge_uC_per_m2 = {-sigma_max!r}\n"
                                       + coarse)
    same = run_cli("field", "num.toml", "--position-mm", "1.5", "-o", "num", "--no-plots",
                   cwd=tmp_path, env=env)
    assert same.returncode == 0, same.stderr[-3000:]
    numeric = json.loads((tmp_path / "num" / "field.json").read_text())
    assert numeric["open_circuit_potential_V"]["lower"] == pytest.approx(
        data["open_circuit_potential_V"]["lower"], rel=1e-9)
