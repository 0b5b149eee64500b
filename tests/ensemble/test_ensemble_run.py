"""[run] realisations: every realisation is the single run of its seed, the rows do not
depend on how they were farmed (serial, --jobs, mpirun ranks), the summary block is the
statistics of the rows, and the random excitation works with loads, rectifiers and
arrays. The surrogate is the analytic plate model (``plate_model``): what is tested
here is the ensemble, not the field."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

import tengfield as tf
from tengfield.ensemble import QUANTITIES, realisation_row
from tengfield.pipeline import run_ensemble, run_one

import plate_model as fx
from helpers import mpi_env, needs_mpirun, same_rows

RANDOM = {"kind": "random", "band_hz": [10.0, 200.0], "rms_acceleration_m_per_s2": 40.0,
          "seed": 11}
SHORT = {"duration_s": 0.6, "settle_periods": 3, "sample_rate_hz": 4000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


def _scene(realisations=4, **sections):
    return fx.scene_with(excitation=RANDOM, run={**SHORT, "realisations": realisations},
                         **sections)


def _first(scene, cache):
    return run_one(scene, cache_dir=cache, solve=fx.plate_model_solve)


@pytest.mark.parametrize("circuit", [{"kind": "open"}, {"kind": "load", "load_ohm": 1e8}])
def test_each_realisation_is_the_run_of_its_seed(cache, circuit):
    scene = _scene(circuit=circuit)
    rows, block = run_ensemble(scene, _first(scene, cache), jobs=1, cache_dir=cache)
    assert [r["seed"] for r in rows] == [11, 12, 13, 14]
    for k, row in enumerate(rows):
        single = run_one(scene.with_values(excitation={"seed": 11 + k}), cache_dir=cache,
                         solve=fx.plate_model_solve)
        assert row == realisation_row(k, 11 + k, single.summary)
    # the realisations differ (the motion is random), the block is their statistics
    assert len({r["I_sc_pp_A"] for r in rows}) == 4
    for name, stats in block["quantities"].items():
        values = np.array([r[name] for r in rows], dtype=float)
        assert stats["mean"] == pytest.approx(values.mean(), rel=1e-12)
        assert stats["std"] == pytest.approx(values.std(ddof=1), rel=1e-9, abs=1e-300)
    fractions = sum(s["mean"] for s in block["regime_fractions"].values())
    assert fractions == pytest.approx(1.0)
    assert ("mean_power_W" in block["quantities"]) == (circuit["kind"] == "load")


def test_worker_processes_give_the_serial_rows(cache):
    scene = _scene(realisations=5)
    first = _first(scene, cache)
    serial, _ = run_ensemble(scene, first, jobs=1, cache_dir=cache)
    pooled, _ = run_ensemble(scene, first, jobs=2, cache_dir=cache)
    assert same_rows(serial, pooled)


def test_rectifier_and_array_take_a_random_excitation(cache):
    rect = _scene(realisations=2, circuit={"kind": "rectifier", "storage_capacitance_uF": 1e-4})
    rows, block = run_ensemble(rect, _first(rect, cache), jobs=1, cache_dir=cache)
    assert all(r["final_stored_energy_J"] > 0 for r in rows)
    assert block["quantities"]["average_harvested_power_W"]["n"] == 2
    arr = _scene(realisations=1, array={"cells": 3, "restitution_spread": 0.05})
    result = _first(arr, cache)
    assert result.summary["array"]["cells"] == 3
    assert np.all(np.isfinite(result.waveforms["I_sc_A"]))


def test_sine_refuses_realisations():
    with pytest.raises(tf.SceneError, match=r"realisations = 3 needs a random excitation"):
        fx.scene_with(run={"realisations": 3})


def _write_scene(path, extra=""):
    band = ", ".join(str(b) for b in RANDOM["band_hz"])
    path.write_text(f"""
[excitation]
kind = "random"
band_hz = [{band}]
rms_acceleration_m_per_s2 = 40.0
seed = 11
[run]
duration_s = 0.6
settle_periods = 3
sample_rate_hz = 4000.0
realisations = 4
{extra}""")
    return path


@pytest.fixture(scope="module")
def plate_cache(tmp_path_factory):
    """A cache holding the plate-model surrogate of the CLI scene (no dolfinx)."""
    from tengfield.scene import load_scene
    d = tmp_path_factory.mktemp("cli-cache")
    scene = load_scene(_write_scene(d / "s.toml"))
    run_one(scene, cache_dir=d, solve=fx.plate_model_solve)
    return d


@pytest.mark.slow
def test_cli_run_writes_the_ensemble_with_figures(run_cli, cli_env, tmp_path, plate_cache):
    scene = _write_scene(tmp_path / "s.toml")
    out = tmp_path / "out"
    res = run_cli("run", scene, "-o", out, "--cache-dir", plate_cache, "--jobs", "2")
    assert res.returncode == 0, res.stderr
    assert "Traceback" not in res.stderr
    assert "ensemble of 4 realisations" in res.stdout
    rows = list(csv.DictReader((out / "ensemble.csv").open()))
    assert [int(r["seed"]) for r in rows] == [11, 12, 13, 14]
    summary = json.loads((out / "summary.json").read_text())
    stats = summary["ensemble"]["quantities"]["I_sc_pp_A"]
    assert stats["mean"] == pytest.approx(np.mean([float(r["I_sc_pp_A"]) for r in rows]))
    png = (out / "ensemble.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 10_000


@pytest.mark.slow
def test_cli_under_mpirun_gives_the_serial_ensemble(tmp_path, plate_cache, python):
    import subprocess
    needs_mpirun()
    scene = _write_scene(tmp_path / "s.toml")
    outs = {}
    for name, prefix in (("serial", []), ("mpi", ["mpirun", "-n", "2"])):
        out = tmp_path / name
        res = subprocess.run(prefix + [python, "-m", "tengfield.cli", "run", str(scene), "-o",
                                       str(out), "--cache-dir", str(plate_cache), "--no-plots",
                                       *(["--jobs", "1"] if not prefix else [])],
                             env=mpi_env(), capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr
        outs[name] = (out / "ensemble.csv").read_text()
    assert outs["serial"] == outs["mpi"]


def test_a_resting_first_realisation_still_builds_the_surrogate_once(tmp_path, monkeypatch):
    """Realisation 0 of a weak band rests (no field stage, no surrogate in the cache); the
    others lift off. Each of them solved the field for itself, without caching it (N
    solves instead of one, and again at the next run). The ensemble now builds it once
    before farming: the workers read it from the cache and never solve."""
    scene = fx.scene_with(excitation={**RANDOM, "rms_acceleration_m_per_s2": 3.6, "seed": 0},
                          run={**SHORT, "duration_s": 0.5, "settle_periods": 1,
                               "realisations": 4})
    first = run_one(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    assert first.table is None and first.summary["regime"]["regime"] == "rest"
    import tengfield.surrogate.refinement as refinement

    def no_field_solver():
        raise AssertionError("a realisation solved the field itself")
    monkeypatch.setattr(refinement, "_default_solver", no_field_solver)
    rows, _ = run_ensemble(scene, first, jobs=1, cache_dir=tmp_path,
                           solve=fx.plate_model_solve)
    assert {r["regime"] for r in rows[1:]} != {"rest"}      # some realisations move
    assert any(r["Q_sc_pp_C"] > 0 for r in rows)
    assert list(tmp_path.glob("surrogate-*.h5"))


def test_an_ensemble_that_never_moves_is_all_rest(tmp_path):
    scene = fx.scene_with(excitation={**RANDOM, "rms_acceleration_m_per_s2": 1.0},
                          run={**SHORT, "realisations": 3})
    first = run_one(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    assert first.table is None
    rows, block = run_ensemble(scene, first, jobs=1, cache_dir=tmp_path,
                               solve=fx.plate_model_solve)
    assert {r["regime"] for r in rows} == {"rest"}
    assert block["regime_fractions"]["rest"]["mean"] == 1.0


@pytest.mark.parametrize("circuit, label", [
    ({"kind": "rectifier", "storage_capacitance_uF": 1e-4}, "energy into the store(s) [J]"),
    ({"kind": "load", "load_ohm": 1e8}, "mean load power [W]")])
def test_an_array_ensemble_reports_the_arrays_output(cache, circuit, label):
    """An [array] run reports its output under summary -> array (array_value, what it is
    in "compared"), not under load / rectifier: its ensemble rows had only the
    peak-to-peak values, the harvested energy or load power left empty in every row."""
    arr = _scene(realisations=2, circuit=circuit,
                 array={"cells": 3, "restitution_spread": 0.05})
    first = _first(arr, cache)
    rows, block = run_ensemble(arr, first, jobs=1, cache_dir=cache)
    assert rows[0]["array_value"] == first.summary["array"]["array_value"] > 0
    assert all(r["array_value"] > 0 for r in rows)
    assert block["array_quantity"] == label
    assert block["quantities"]["array_value"]["n"] == 2


@pytest.mark.slow
def test_the_library_runs_the_ensemble_the_cli_writes(run_cli, tmp_path, plate_cache):
    """tf.run(scene) honours [run] realisations (it used to run realisation 0 only: the
    CLI ran the others): its ensemble block and rows are those the CLI writes to
    summary.json and ensemble.csv (the CLI calls the library), and those of
    run_ensemble after the first run."""
    from tengfield.scene import load_scene
    path = _write_scene(tmp_path / "s.toml")
    scene = load_scene(path)
    result = tf.run(scene, cache_dir=plate_cache, jobs=1)
    rows, block = result.ensemble_rows, result.ensemble
    assert block is result.summary["ensemble"] and block["realisations"] == 4
    assert [r["seed"] for r in rows] == [11, 12, 13, 14]
    assert rows == run_ensemble(scene, run_one(scene, cache_dir=plate_cache), jobs=1,
                                cache_dir=plate_cache)[0]
    single = tf.run(scene.with_values(run={"realisations": 1}), cache_dir=plate_cache)
    assert single.ensemble is None and single.ensemble_rows is None
    out = tmp_path / "out"
    res = run_cli("run", path, "-o", out, "--cache-dir", plate_cache, "--jobs", "1")
    assert res.returncode == 0, res.stderr
    written = json.loads((out / "summary.json").read_text())["ensemble"]
    assert written == json.loads(json.dumps(block))
    csv_rows = list(csv.DictReader((out / "ensemble.csv").open()))
    assert [float(r["I_sc_pp_A"]) for r in csv_rows] == [r["I_sc_pp_A"] for r in rows]


@pytest.mark.slow
def test_result_ensemble_plot_is_the_figure_run_saves(cache, tmp_path):
    """#29 notebook use: ``r.ensemble.plot()`` returns the figure ``tengfield run`` saves
    as ensemble.png (figures on), and summary.json's block is the same dict as before."""
    from matplotlib.figure import Figure

    from tengfield.io import write_run_outputs

    scene = _scene(realisations=3)
    result = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    fig = result.ensemble.plot()
    assert isinstance(fig, Figure)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["V_OC peak-to-peak [V]", "Q_SC peak-to-peak [nC]",
                      "I_SC peak-to-peak [nA]", "fraction of realisations"]
    q = fig.axes[1].get_lines()[0].get_ydata()
    assert list(q) == pytest.approx([r["Q_sc_pp_C"] * 1e9 for r in result.ensemble_rows],
                                    rel=1e-12)
    written = write_run_outputs(result, tmp_path, plots=True)
    assert tmp_path / "ensemble.png" in written
    fig.savefig(tmp_path / "notebook.png", dpi=110)
    assert (tmp_path / "notebook.png").read_bytes() == (tmp_path / "ensemble.png").read_bytes()
    saved = json.loads((tmp_path / "summary.json").read_text())["ensemble"]
    assert saved == json.loads(json.dumps(dict(result.ensemble)))
    assert "rows" not in saved
