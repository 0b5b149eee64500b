"""The breakdown limit from real field solves (coarse meshes: a few seconds each)."""
import json
import math
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from tengfield import air_breakdown
from tengfield.scene import default_scene, parse_scene
from tengfield.surrogate import read_table

pytestmark = pytest.mark.slow

#: coarse on purpose: P1 at 1 mm has a field error estimate of ~0.08, within this tolerance
COARSE = {"degree": 1, "mesh_size_mm": 1.0, "tolerance": 0.1}


def coarse(**device):
    return default_scene().with_values(field=COARSE, device=device)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


def test_sigma_max_does_not_depend_on_the_scene_sigma(cache):
    limits = []
    for sigma in (-8.0, -30.0):
        scene = coarse(surface_charge_uC_per_m2=sigma)
        table, _ = air_breakdown.obtain_breakdown_table(scene, cache_dir=cache)
        limits.append(air_breakdown.scene_breakdown(scene, table, air_breakdown.STATES).sigma_max)
    assert limits[1] == pytest.approx(limits[0], rel=1e-9)
    assert 10e-6 < limits[0] < 60e-6


def test_an_uncharged_ball_has_the_same_limit(cache, tmp_path):
    """sigma = 0 gives no induced-charge fractions: its table is the stand-in sigma's, and
    sigma_max is the charged scene's (it was inf, written as null), the figure drawn at
    the limit."""
    charged = coarse(surface_charge_uC_per_m2=-8.0)
    table, _ = air_breakdown.obtain_breakdown_table(charged, cache_dir=cache)
    expected = air_breakdown.scene_breakdown(charged, table).sigma_max
    scene = coarse(surface_charge_uC_per_m2=0.0)
    table0, _ = air_breakdown.obtain_breakdown_table(scene, cache_dir=cache)
    result = air_breakdown.scene_breakdown(scene, table0)
    assert result.sigma_max == pytest.approx(expected, rel=1e-9)
    assert result.margin(0.0) == 0.0
    air_breakdown.write_outputs(result, scene, tmp_path, plots=True)
    data = json.loads((tmp_path / "breakdown.json").read_text())
    assert data["sigma_max_uC_per_m2"] == pytest.approx(expected * 1e6, rel=1e-9)
    assert (tmp_path / "breakdown.png").stat().st_size > 10_000


def test_lines_are_stored_with_the_surrogate_and_mirror_symmetric(cache):
    scene = coarse(surface_charge_uC_per_m2=-8.0)
    table, outcome = air_breakdown.obtain_breakdown_table(scene, cache_dir=cache)
    again = read_table(outcome.path)
    np.testing.assert_array_equal(again.line_potential, table.line_potential)
    assert again.line_potential.shape == (table.count, 2, 18, 3)
    # the upper half is the mirror image of the lower half: sides and psi's swapped
    lines = table.line_potential
    middle = table.count // 2                     # solved itself, not an image
    image = lines[::-1][:, ::-1][..., [0, 2, 1]]
    keep = np.arange(table.count) != middle
    np.testing.assert_allclose(image[keep], lines[keep], rtol=1e-12)
    # the half-size mesh values exist where the field error was measured
    assert np.sum(np.all(np.isfinite(table.line_check), axis=(1, 2, 3))) >= 2
    # ... and only there: the file holds those rows and their positions, never a NaN
    np.testing.assert_array_equal(again.line_check, table.line_check)   # NaN rows equal
    import h5py
    with h5py.File(outcome.path, "r") as f:
        for name, data in f.items():
            assert np.all(np.isfinite(data[()])), name
        solved = np.flatnonzero(np.all(np.isfinite(table.line_check), axis=(1, 2, 3)))
        np.testing.assert_array_equal(f["breakdown_line_potential_check_index"][()], solved)


def test_mirror_image_agrees_with_a_direct_solve():
    from mpi4py import MPI

    from tengfield.field import solve_position

    scene = coarse()
    z = 0.75e-3
    low = solve_position(scene, z, comm=MPI.COMM_SELF, breakdown_lines=True,
                         estimate_error=False).info["breakdown_lines"]
    high = solve_position(scene, scene.device.stroke - z, comm=MPI.COMM_SELF,
                          breakdown_lines=True, estimate_error=False).info["breakdown_lines"]
    mirrored = high[::-1][..., [0, 2, 1]]
    np.testing.assert_allclose(mirrored[..., 0], low[..., 0], rtol=1e-2)   # mesh noise, 1 mm
    np.testing.assert_allclose(mirrored[..., 1:], low[..., 1:], atol=1e-2)


def test_lower_pressure_lowers_sigma_max_at_mm_gaps(cache):
    scene = coarse()
    table, _ = air_breakdown.obtain_breakdown_table(scene, cache_dir=cache)
    one = air_breakdown.scene_breakdown(scene, table).sigma_max
    low = air_breakdown.scene_breakdown(scene.with_values(breakdown={"pressure_kPa": 30.0}),
                                    table).sigma_max
    assert low < 0.7 * one


def test_mesh_convergence_of_sigma_max(cache):
    """sigma_max on three meshes (degree 1, h, h/2, h/4): the changes shrink, and the
    coarse estimate covers its distance from the finest."""
    values, estimates = [], []
    for h in (1.0, 0.5, 0.25):
        scene = default_scene().with_values(field={"degree": 1, "mesh_size_mm": h,
                                                   "tolerance": COARSE["tolerance"]})
        table, _ = air_breakdown.obtain_breakdown_table(scene, cache_dir=cache)
        res = air_breakdown.scene_breakdown(scene, table, air_breakdown.STATES)
        values.append(res.sigma_max)
        estimates.append(res.relative_error_estimate)
    first, second = abs(values[1] - values[0]), abs(values[2] - values[1])
    assert second < first or second < 1e-3 * values[2]
    assert abs(values[0] - values[2]) / values[2] <= estimates[0]


def test_breakdown_run_uses_minus_sigma_max_and_warns_above_it(cache):
    from tengfield.pipeline import run

    base = {"field": COARSE, "run": {"duration_s": 0.5, "settle_periods": 4}}
    scene = parse_scene('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n').with_values(**base)
    r = run(scene, cache_dir=cache)
    block = r.summary["breakdown"]
    assert block["sigma_from"] == "breakdown limit"
    assert block["sigma_uC_per_m2"] == pytest.approx(-block["sigma_max_uC_per_m2"])
    assert r.scene.device.surface_charge == pytest.approx(-block["sigma_max_uC_per_m2"] * 1e-6)
    assert r.stages["field"].status in ("ran", "cached")
    # the same surrogate again: no field solve
    assert run(scene, cache_dir=cache).stages["field"].status == "cached"
    high = default_scene().with_values(device={"surface_charge_uC_per_m2": -200.0}, **base)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run(high, cache_dir=cache)
    text = [str(w.message) for w in caught if "air-breakdown limit" in str(w.message)]
    assert len(text) == 1 and "surface_charge_uC_per_m2 = -200" in text[0]
    assert r.summary["breakdown"]["margin"] > 1
    energy = r.summary["energy_per_cycle"]
    assert energy["max_energy_per_cycle_breakdown_limited_J"] == pytest.approx(
        energy["max_energy_per_cycle_J"] / r.summary["breakdown"]["margin"] ** 2)


def test_cli_breakdown_writes_its_files(tmp_path, cache):
    scene = tmp_path / "s.toml"
    scene.write_text("[field]\ndegree = 1\nmesh_size_mm = 1.0\ntolerance = 0.1\n"
                     "[breakdown]\npressure_kPa = 90\n")
    out = tmp_path / "out"
    exe = str(Path(sys.executable).with_name("tengfield"))
    proc = subprocess.run([exe, "breakdown", str(scene), "-o",
                           str(out), "--cache-dir", str(cache)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "breakdown.json").read_text())
    assert data["pressure_Pa"] == 90e3 and data["paschen"]["A_per_Pa_m"] == 11.25
    assert math.isfinite(data["sigma_max_uC_per_m2"]) and data["binding"]["gap_length_m"] > 0
    header = (out / "breakdown.csv").read_text().splitlines()[0].split(",")
    assert list(header) == list(air_breakdown.CSV_COLUMNS)
    assert (out / "breakdown.png").stat().st_size > 10_000
    assert "sigma_max" in proc.stdout


def test_sweep_runs_at_the_breakdown_charge(tmp_path, run_cli, cli_env):
    """`tengfield sweep` with "breakdown": every point at -sigma_max, as `run` does (it
    ran at the stand-in -1 uC/m^2, silently): the rows equal those of the scene with
    that sigma written as a number; figures on."""
    import csv

    env = cli_env(TENGFIELD_CACHE_DIR=str(tmp_path / "cache"))
    common = ("[field]\ndegree = 1\nmesh_size_mm = 1.0\ntolerance = 0.2\n"
              "[run]\nduration_s = 0.3\nsettle_periods = 2\n")
    (tmp_path / "bd.toml").write_text('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n'
                                      + common)
    grid = ("--frequency-hz", "20:30:2", "--amplitude-mm", "1.5:1.5:1")
    done = run_cli("sweep", "bd.toml", *grid, "-o", "bd", cwd=tmp_path, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    sigma = float(re.search(r"-sigma_max = (\S+) [uµ]C/m\^2", done.stderr).group(1))
    assert -60 < sigma < -10
    assert (tmp_path / "bd" / "sweep.png").stat().st_size > 10_000
    table, _ = air_breakdown.obtain_breakdown_table(
        parse_scene('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n' + common),
        cache_dir=tmp_path / "cache")
    exact = -air_breakdown.scene_breakdown(parse_scene(common), table).sigma_max * 1e6
    assert sigma == pytest.approx(exact, rel=1e-3)
    (tmp_path / "num.toml").write_text(f"[device]\nsurface_charge_uC_per_m2 = {exact!r}\n"
                                       + common)
    same = run_cli("sweep", "num.toml", *grid, "-o", "num", "--no-plots", cwd=tmp_path,
                   env=env)
    assert same.returncode == 0, same.stderr[-3000:]

    def rows(name):
        with open(tmp_path / name / "sweep.csv", newline="") as f:
            return list(csv.DictReader(f))
    for a, b in zip(rows("bd"), rows("num"), strict=True):
        assert float(a["Q_sc_pp_C"]) == pytest.approx(float(b["Q_sc_pp_C"]), rel=1e-9)
        assert float(a["V_oc_pp_V"]) == pytest.approx(float(b["V_oc_pp_V"]), rel=1e-9)
