"""``tengfield fit``, ``[array]`` and ``[run] realisations`` on a spherical shell (issue
#32), end to end through the CLI with figures on. One shell surrogate (axisymmetric solves
at 2.5 mm) is computed by the first run and cached for the others; what is tested is
that these studies take the shell's stroke, surrogate and volume."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from shell_model import SHELL, shell_device_toml  # noqa: F401

pytestmark = [pytest.mark.slow, pytest.mark.field]

SHELL_TOML = shell_device_toml(sigma="{sigma}") + """\
[excitation]
{excitation}

[field]
mesh_size_mm = 2.5
tolerance = 0.05

[run]
duration_s = {duration}
settle_periods = 4
sample_rate_hz = 5000
{extra}"""

SINE = "frequency_hz = 20\namplitude_mm = 3"
RANDOM = ('kind = "random"\nband_hz = [10.0, 200.0]\nrms_acceleration_m_per_s2 = 40.0\n'
          "seed = 11")
TRUE_SIGMA = -20.0


def shell_toml(sigma=TRUE_SIGMA, excitation=SINE, duration=0.4, extra=""):
    return SHELL_TOML.format(sigma=sigma, excitation=excitation, duration=duration,
                             extra=extra)


@pytest.fixture(scope="module")
def shell_run(tmp_path_factory, run_cli, cli_env):
    """(directory, env, summary) of ``tengfield run`` on the shell at σ = TRUE_SIGMA
    (figures on); its surrogate is in the directory's cache for the other runs."""
    d = tmp_path_factory.mktemp("shell")
    (d / "shell.toml").write_text(shell_toml())
    env = cli_env(TENGFIELD_CACHE_DIR=d / "cache", MPLBACKEND="Agg")
    proc = run_cli("run", d / "shell.toml", "-o", d / "run", env=env)
    assert proc.returncode == 0, proc.stderr
    assert (d / "run" / "waveforms.png").is_file()
    return d, env, json.loads((d / "run" / "summary.json").read_text())


def test_fit_recovers_sigma_from_a_shells_own_waveforms(shell_run, run_cli, tmp_path):
    """The shell's waveforms.csv (V_OC, Q_SC, I_SC at σ = -20 µC/m²) fitted from a start
    of -50: σ comes back (the same surrogate, scaled), fit.png and fitted.toml written,
    and fitted.toml is still a shell."""
    from tengfield.scene import load_scene

    d, env, _ = shell_run
    path = tmp_path / "fit.toml"
    path.write_text(shell_toml(sigma=-50.0) + "\n[fit.parameters]\n"
                    "surface_charge_uC_per_m2 = {min = -100.0, max = 0.0}\n")
    out = tmp_path / "fit"
    proc = run_cli("fit", path, "--measured", d / "run" / "waveforms.csv", "-o", out, env=env)
    assert proc.returncode == 0, proc.stderr
    fit = json.loads((out / "fit.json").read_text())
    sigma = fit["parameters"]["surface_charge_uC_per_m2"]
    assert sigma["value"] == pytest.approx(TRUE_SIGMA, rel=1e-6)
    assert set(fit["residual_rms"]) == {"V", "Q", "I"}
    assert (out / "fit.png").stat().st_size > 10_000
    fitted = load_scene(out / "fitted.toml")
    assert fitted.device.shape == "spherical-shell"
    assert fitted.device.surface_charge * 1e6 == pytest.approx(TRUE_SIGMA, rel=1e-5)


def test_an_array_of_shells(shell_run, run_cli, tmp_path):
    """[array] of 4 shells with spread restitution and phases (figures on): 4 distinct
    motions, the N-cell reference is 4 x the single shell's Q_SC, and the array's Q_SC is
    at most that (cells out of phase cancel); every cell stays inside the shell's stroke."""
    d, env, single = shell_run
    path = tmp_path / "array.toml"
    path.write_text(shell_toml(extra="[array]\ncells = 4\nrestitution_spread = 0.05\n"
                                     "initial_phase_spread_deg = 90\n"))
    out = tmp_path / "array"
    proc = run_cli("run", path, "-o", out, env=env)
    assert proc.returncode == 0, proc.stderr
    assert (out / "array.png").stat().st_size > 10_000
    summary = json.loads((out / "summary.json").read_text())
    block = summary["array"]
    assert summary["cells"] == 4 and block["distinct_dynamics"] == 4
    q_one = single["peak_to_peak"]["Q_sc_C"]
    assert block["N_x_one_cell_value"] == pytest.approx(4 * q_one, rel=1e-9)
    assert 0 < block["array_value"] <= block["N_x_one_cell_value"] * (1 + 1e-12)
    assert summary["peak_to_peak"]["Q_sc_C"] == pytest.approx(block["array_value"], rel=1e-12)
    assert 0 < summary["regime"]["max_gap_m"] <= 12e-3


def test_identical_shells_in_an_array_are_n_cells(shell_run):
    """No spread: [array] cells = 3 of shells is [device] cells = 3, to the bit."""
    import tengfield as tf

    d, _, _ = shell_run
    scene = tf.load_scene(d / "shell.toml")
    arr = tf.run(scene.with_values(array={"cells": 3}), cache_dir=d / "cache")
    dev = tf.run(scene.with_values(device={"cells": 3}), cache_dir=d / "cache")
    assert arr.summary["array"]["distinct_dynamics"] == 1
    for key, values in dev.waveforms.items():
        np.testing.assert_array_equal(arr.waveforms[key], values, err_msg=key)


def test_an_ensemble_of_shell_runs(shell_run, run_cli, tmp_path):
    """[run] realisations = 3 of a shell under a random drive (figures on): ensemble.csv
    holds seeds 11-13, realisation 0 is the run itself, the block's mean is the rows'."""
    d, env, _ = shell_run
    path = tmp_path / "ensemble.toml"
    path.write_text(shell_toml(excitation=RANDOM, duration=0.6).replace(
        "[run]\n", "[run]\nrealisations = 3\n"))
    out = tmp_path / "ensemble"
    proc = run_cli("run", path, "-o", out, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "ensemble of 3 realisations" in proc.stdout
    assert (out / "ensemble.png").stat().st_size > 10_000
    rows = list(csv.DictReader((out / "ensemble.csv").open()))
    assert [int(r["seed"]) for r in rows] == [11, 12, 13]
    summary = json.loads((out / "summary.json").read_text())
    assert float(rows[0]["Q_sc_pp_C"]) == pytest.approx(summary["peak_to_peak"]["Q_sc_C"],
                                                        rel=1e-12)
    assert len({r["Q_sc_pp_C"] for r in rows}) == 3          # the motion is random
    stats = summary["ensemble"]["quantities"]["Q_sc_pp_C"]
    assert stats["mean"] == pytest.approx(np.mean([float(r["Q_sc_pp_C"]) for r in rows]),
                                          rel=1e-12)
    assert summary["stages"]["field"]["status"] == "cached"   # the shell's own surrogate
