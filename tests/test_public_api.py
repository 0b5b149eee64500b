"""The one face of every result (issue #41): ``.scene``, ``.summary`` (a JSON-able dict, a
property), ``.plot()`` -> a matplotlib Figure, ``.write(out_dir, plots=True)`` writing
what the command line writes, and ``.t`` where the result has a time axis. Tiny scenes:
dynamics only, or the analytic plate model standing in for the field solve."""
from __future__ import annotations

import json
import warnings

import numpy as np
import plate_model as fx
from helpers import assert_labelled
import pytest
from matplotlib.figure import Figure

import tengfield as tf

pytestmark = pytest.mark.slow

SHORT_RUN = {"duration_s": 1.0}


@pytest.fixture(scope="module")
def cached(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@pytest.fixture(scope="module")
def scene():
    return fx.scene_with(run=SHORT_RUN)


def check_face(result, out_dir, *, expected_files, has_time=False):
    """The face every result shows; returns the summary."""
    summary = result.summary
    assert isinstance(summary, dict) and summary
    json.dumps(summary, allow_nan=True)               # plain JSON-able data
    fig = result.plot()
    assert isinstance(fig, Figure) and fig.axes
    assert_labelled(fig)            # the figure the command line saves, as a paper writes it
    fig.clear()
    written = result.write(out_dir, plots=True)
    names = {p.name for p in out_dir.iterdir()}
    assert set(expected_files) <= names, names
    assert all(p.exists() and p.stat().st_size > 0 for p in map(__import__("pathlib").Path,
                                                                 written))
    if has_time:
        t = np.asarray(result.t)
        assert t.ndim == 1 and t.size > 2 and np.all(np.diff(t) > 0)
    return summary


def test_dynamics_face_and_cli_files(scene, tmp_path, run_cli):
    """A trajectory's face; its files are the CLI's, byte for byte apart from wall time."""
    result = tf.simulate(scene)
    assert result.scene is scene
    summary = check_face(result, tmp_path / "api", has_time=True,
                         expected_files={"summary.json", "trajectory.csv", "impacts.csv",
                                         "trajectory.png"})
    assert summary["impacts"] == len(result.impacts)
    with pytest.warns(DeprecationWarning, match="summary"):
        assert result.summary() == summary          # the old spelling, still answered
    path = tmp_path / "scene.toml"
    path.write_text("[run]\nduration_s = 1.0\n")
    done = run_cli("dynamics", path, "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    api = tmp_path / "api2"
    tf.simulate(tf.load_scene(path)).write(api)
    assert_same_files(api, tmp_path / "cli", timing=("wall_time_s",))


def test_map_face_and_cli_files(tmp_path, run_cli):
    path = tmp_path / "scene.toml"
    path.write_text("[run]\nduration_s = 1.0\n")
    result = tf.map(path, frequency_hz="20:40:3", amplitude_mm=[1.0, 2.0], periods=30, jobs=1)
    assert result.scene.source == tf.load_scene(path).source
    summary = check_face(result, tmp_path / "api", expected_files={"map.csv", "map.png"})
    assert summary["points"] == 6 and sum(summary["regimes"].values()) == 6
    done = run_cli("map", path, "--frequency-hz", "20:40:3", "--amplitude-mm", "1:2:2",
                   "--periods", "30", "-j", "1", "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    assert_same_files(tmp_path / "api", tmp_path / "cli")


def test_run_face(scene, cached, tmp_path):
    result = tf.run(scene, cache_dir=cached, solve=fx.plate_model_solve)
    assert result.scene is scene
    summary = check_face(result, tmp_path / "out", has_time=True,
                         expected_files={"summary.json", "waveforms.csv", "waveforms.png"})
    written = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert written["peak_to_peak"] == pytest.approx(summary["peak_to_peak"])


def test_sweep_face(scene, cached, tmp_path):
    """``tf.sweep`` in file units: one row per frequency, the face of every result."""
    result = tf.sweep(scene, frequency_hz=[20, 30], cache_dir=cached,
                      solve=fx.plate_model_solve)
    assert len(result) == 2
    assert [r["frequency_hz"] for r in result] == pytest.approx([20.0, 30.0])
    check_face(result, tmp_path / "out", expected_files={"sweep.csv"})


@pytest.mark.field
def test_breakdown_face_and_cli_files(tmp_path, run_cli):
    """``tf.breakdown``: coarse field solves (P1, 1 mm; the surrogate cache shared with
    the CLI)."""
    path = tmp_path / "scene.toml"
    path.write_text("[field]\ndegree = 1\nmesh_size_mm = 1.0\ntolerance = 0.03\n")
    with pytest.warns(RuntimeWarning, match="field error estimate"):   # coarse on purpose
        result = tf.breakdown(path)
    assert result.scene.source == tf.load_scene(path).source
    summary = check_face(result, tmp_path / "api", expected_files={"breakdown.json",
                                                                   "breakdown.png"})
    assert summary == result.to_json()
    done = run_cli("breakdown", path, "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    assert_same_files(tmp_path / "api", tmp_path / "cli")


def assert_same_files(a, b, timing=()):
    """The same result files (the CLI's own dot-files: its lock, manifest and command line
    aside); CSV and JSON files with the same bytes (JSON: apart from the ``timing`` keys)."""
    def results(d):
        return sorted(p.name for p in d.iterdir() if not p.name.startswith("."))

    names = results(a)
    assert names == results(b)
    for name in names:
        if name.endswith(".csv"):
            assert (a / name).read_bytes() == (b / name).read_bytes(), name
        elif name.endswith(".json"):
            if not timing:
                assert (a / name).read_bytes() == (b / name).read_bytes(), name
            left, right = (json.loads((d / name).read_text()) for d in (a, b))
            for key in timing:
                assert key in left and key in right
                left.pop(key)
                right.pop(key)
            assert left == right, name


def test_uncertainty_face(cached, tmp_path):
    scene = fx.scene_with(run=SHORT_RUN, uncertainty={
        "samples": 16, "method": "sobol", "seed": 2,
        "vary": {"device.surface_charge_uC_per_m2": {"distribution": "normal", "mean": -20.0,
                                                     "std": 2.0}}})
    result = tf.uncertainty(scene, cache_dir=cached, solve=fx.plate_model_solve, jobs=1)
    assert result.scene is scene
    summary = check_face(result, tmp_path / "out", expected_files={"uncertainty.json"})
    written = json.loads((tmp_path / "out" / "uncertainty.json").read_text())
    assert written["output_keys"] == summary["output_keys"]


def test_design_face(cached, tmp_path):
    scene = fx.scene_with(design={"objective": "charge", "candidates": 4, "seed": 1,
                                  "settle_periods": 10, "window_periods": 10,
                                  "samples_per_period": 120, "vary": {"stroke_mm": [1.0, 5.0]}})
    result = tf.design(scene, cache_dir=cached, solve=fx.plate_model_solve, jobs=1)
    summary = check_face(result, tmp_path / "out", expected_files={"design.json", "design.csv"})
    written = json.loads((tmp_path / "out" / "design.json").read_text())
    assert written.keys() == json.loads(json.dumps(summary)).keys()


def test_report_verb_measures_the_scene(tmp_path):
    """``tf.report(scene, fast=True)`` with the plate model standing in for the field: a
    row per stage level, a verified recommendation per target, the report's files."""
    scene = fx.scene_with(run=SHORT_RUN)
    report = tf.report(scene, fast=True, solve=fx.plate_model_solve)
    assert report.scene is scene
    assert {row.stage for row in report.rows} == {"field", "surrogate", "dynamics", "circuit"}
    assert [rec.target for rec in report.recommendations] == [1e-2, 1e-3]
    summary = check_face(report, tmp_path / "out",
                         expected_files={"report.json", "report.csv", "report.md", "field.png"})
    assert summary == json.loads((tmp_path / "out" / "report.json").read_text())


def test_report_face(tmp_path):
    """A report from rows alone (no measuring): one Figure with a panel per stage."""
    from tengfield.accuracy_report import Report, Row, make_plan

    rows = [Row(stage, f"{stage} {i}", {"model": "impact"}, wall,
                {"V_oc": 10.0 ** -i, "Q_sc": 10.0 ** -i, "I_sc": 10.0 ** -i}, "ref")
            for stage in ("field", "dynamics") for i, wall in enumerate((0.1, 0.4, 1.6))]
    report = Report(tf.default_scene(), make_plan(fast=True), rows, [], {"field": "p2"},
                    {"regime": "period-1"}, 3.0, True)
    assert report.scene.source == tf.default_scene().source
    summary = check_face(report, tmp_path / "out",
                         expected_files={"report.json", "report.csv", "report.md", "field.png",
                                         "dynamics.png"})
    assert len(report.plot().axes) == 2
    assert summary == json.loads((tmp_path / "out" / "report.json").read_text())


def test_harvest_and_array_time_axis():
    """``.t`` where the result has a time axis (``.time``, the older name, stays); a
    harvest's summary is its energy balance, its figure the store voltage."""
    from tengfield.array import ArrayResult
    from tengfield.harvest import harvest

    t = np.linspace(0.0, 0.2, 2001)
    q_sc = 1e-9 * np.sin(2 * np.pi * 30.0 * t)            # 1 nC at 30 Hz
    c_t = np.full_like(t, 10e-12)                          # 10 pF
    charged = harvest(t, q_sc, c_t, storage_capacitance=1e-9)
    assert charged.t is charged.time
    summary = charged.summary
    json.dumps(summary, allow_nan=True)
    assert summary["final_store_voltage_V"] == pytest.approx(charged.store_voltage[-1])
    assert summary["final_store_voltage_V"] > 0.0          # the store charged
    fig = charged.plot()
    assert isinstance(fig, Figure)
    assert_labelled(fig)
    assert list(fig.axes[0].get_lines()[0].get_ydata()) == list(charged.store_voltage)
    array = ArrayResult(time=t, columns={}, output=t, reference=t, output_label="V",
                        phases_deg=np.zeros(3), period=0.1, summary={})
    assert array.t is array.time


def test_surrogate_table_and_field_position_face(scene, cached, tmp_path):
    """The cached surrogate (plate model) and one position's electrostatics."""
    from tengfield.surrogate import obtain_table

    table, _ = obtain_table(scene, cache_dir=cached, solve=fx.plate_model_solve)
    summary = table.summary
    json.dumps(summary, allow_nan=True)
    assert summary["positions_m"] == pytest.approx(list(table.positions))
    fig = table.plot()
    assert isinstance(fig, Figure)
    assert len(fig.axes) >= 3 and all(ax.lines for ax in fig.axes[:3])   # V_OC, Q_SC, C_T
    assert_labelled(fig)
    position = fx.plate_model_solve(scene, 1e-3)
    face = position.summary
    assert face == position.to_json()
    written = position.write(tmp_path / "field")
    assert json.loads(written[0].read_text())["position_m"] == pytest.approx(1e-3)


def test_fit_face(cached, tmp_path):
    """A targets fit (σ from a peak-to-peak Q_SC) on the plate model."""
    from tengfield.fit import calibrate

    scene = fx.scene_with(run=SHORT_RUN, circuit={"parallel_capacitance_pF": 100.0})
    result = calibrate(scene, targets=["Q_pp_nC=0.3"], free=["surface_charge_uC_per_m2"],
                       cache_dir=cached, solve=fx.plate_model_solve)
    assert result.scene is scene
    summary = check_face(result, tmp_path / "out", expected_files={"fit.json", "fitted.toml",
                                                                   "fit.png"})
    assert summary == result.as_dict()
    written = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert written.pop("scene") == scene.source
    assert written.keys() == summary.keys()
