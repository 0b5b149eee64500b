"""The one face of every result (issue #41): ``.scene``, ``.summary`` (a JSON-able dict, a
property), ``.plot()`` -> a matplotlib Figure, ``.write(out_dir, plots=True)`` writing
what the command line writes, and ``.t`` where the result has a time axis. Tiny scenes:
dynamics only, or the analytic plate model standing in for the field solve."""
from __future__ import annotations

import json
import warnings

import numpy as np
import plate_model as fx
from helpers import assert_labelled, assert_png
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
    """``tf.breakdown``: coarse field solves (P1, 1 mm) into a fresh surrogate cache that
    the CLI then shares: the same files, but for the field stage, which the library computed
    and the CLI found cached. (With the user's own cache the library found it cached on
    every run but the first after the solver's sources changed, and the files differed
    there.)"""
    path = tmp_path / "scene.toml"
    path.write_text("[field]\ndegree = 1\nmesh_size_mm = 1.0\ntolerance = 0.03\n")
    cache = tmp_path / "cache"
    # coarse on purpose: the only warning it may give is the field error estimate's
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = tf.breakdown(path, cache_dir=cache)
        summary = check_face(result, tmp_path / "api", expected_files={"breakdown.json",
                                                                       "breakdown.png"})
    # third-party deprecations (ffcx's np.product under NumPy 1.25 on Debian 12) aside
    ours = [w for w in caught if not (issubclass(w.category, DeprecationWarning)
                                      and "tengfield" not in str(w.filename))]
    assert all(issubclass(w.category, RuntimeWarning) and "field error estimate" in
               str(w.message) for w in ours), [(str(w.message), w.filename) for w in ours]
    assert result.scene.source == tf.load_scene(path).source
    assert summary == result.to_json()
    done = run_cli("breakdown", path, "--cache-dir", cache, "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    stages = [json.loads((tmp_path / d / "breakdown.json").read_text())["field_stage"]
              for d in ("api", "cli")]
    assert stages == ["computed", "cached"]
    assert_same_files(tmp_path / "api", tmp_path / "cli", timing=("field_stage",))


def assert_same_files(a, b, timing=(), *, summary_timing=False, binary=()):
    """The same result files (the CLI's own dot-files: its lock, manifest and command line
    aside); CSV and JSON files with the same bytes (JSON: apart from the ``timing`` keys;
    ``summary_timing``: apart from every ``*wall_time*`` key at any depth); the files named
    in ``binary`` with the same size."""
    def results(d):
        return sorted(p.name for p in d.iterdir() if not p.name.startswith("."))

    names = results(a)
    assert names == results(b)
    for name in names:
        if name in binary:
            assert (a / name).stat().st_size == (b / name).stat().st_size, name
        elif name.endswith(".csv"):
            assert (a / name).read_bytes() == (b / name).read_bytes(), name
        elif name.endswith(".json") and summary_timing:
            left, right = (json.loads((d / name).read_text()) for d in (a, b))
            assert _without_wall_times(left) == _without_wall_times(right), name
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
    assert table.scene is scene
    assert [p.name for p in table.write(tmp_path / "table", plots=False)] == ["surrogate.h5"]
    assert sorted(p.name for p in (tmp_path / "table").iterdir()) == ["surrogate.h5"]
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
    written = position.write(tmp_path / "field", plots=False)
    assert [p.name for p in written] == ["field.json"]
    assert json.loads(written[0].read_text())["position_m"] == pytest.approx(1e-3)
    with pytest.raises(ValueError, match="keep_solution=True"):   # no solution, no figures
        position.write(tmp_path / "figures")
    assert not (tmp_path / "figures").exists()                     # nothing half written


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


def test_harvest_and_array_write_what_the_run_command_writes(tmp_path, cached, run_cli):
    """A rectifier [array] run: its store record writes charging.png and the array
    array.png through the writers the CLI's run uses; the run's files are the CLI's, the
    CSV bytes equal (summary.json apart from the wall times)."""
    from tengfield.surrogate import obtain_table

    path = tmp_path / "scene.toml"
    path.write_text("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 4000.0\n"
                    "[circuit]\nkind = \"rectifier\"\nstorage_capacitance_uF = 1e-4\n"
                    "[array]\ncells = 3\ninitial_phase_spread_deg = 60.0\nseed = 3\n")
    scene = tf.load_scene(path)
    obtain_table(scene, cache_dir=cached, solve=fx.plate_model_solve)   # the CLI's surrogate
    result = tf.run(scene, cache_dir=cached)
    fine, array = result.harvest, result.array
    assert fine.scene is scene and array.scene is scene
    assert [p.name for p in fine.write(tmp_path / "harvest")] == ["charging.png"]
    assert [p.name for p in array.write(tmp_path / "array")] == ["array.png"]
    assert fine.write(tmp_path / "none", plots=False) == []
    assert_png(tmp_path / "harvest" / "charging.png")
    assert_png(tmp_path / "array" / "array.png")
    with pytest.raises(ValueError, match="needs its scene"):
        import dataclasses
        dataclasses.replace(fine, scene=None).write(tmp_path / "orphan")
    result.write(tmp_path / "api")
    done = run_cli("run", path, "--cache-dir", cached, "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    names = {p.name for p in (tmp_path / "cli").iterdir()}
    assert {"charging.png", "array.png"} <= names
    assert (tmp_path / "api" / "waveforms.csv").read_bytes() == \
        (tmp_path / "cli" / "waveforms.csv").read_bytes()
    assert_same_files(tmp_path / "api", tmp_path / "cli", summary_timing=True)


def _without_wall_times(data):
    """``data`` without its timings (``*wall_time*``, ``*solve_time*``: they differ run to
    run)."""
    if isinstance(data, dict):
        return {k: _without_wall_times(v) for k, v in data.items()
                if "wall_time" not in k and "solve_time" not in k}
    if isinstance(data, list):
        return [_without_wall_times(v) for v in data]
    return data


@pytest.mark.field
def test_surrogate_table_write_is_what_precompute_and_run_write(tmp_path, run_cli):
    """``SurrogateTable.write``: surrogate.h5 with the numbers ``tengfield precompute -o``
    writes (a coarse P1 field) and surrogate.png."""
    from tengfield.surrogate import read_table

    path = tmp_path / "scene.toml"
    path.write_text(fx.SMALL_SCENE)
    cli_file = tmp_path / "cli" / "surrogate.h5"
    done = run_cli("precompute", path, "-o", cli_file)
    assert done.returncode == 0, done.stderr
    table = read_table(cli_file)
    table.scene = tf.load_scene(path)
    written = table.write(tmp_path / "api")
    assert [p.name for p in written] == ["surrogate.h5", "surrogate.png"]
    assert_png(written[1])
    again = read_table(written[0], expected_hash=table.scene.field_hash())
    for name in ("positions", "capacitance", "induced_fraction", "wall_time"):
        np.testing.assert_array_equal(getattr(again, name), getattr(table, name), err_msg=name)
    assert again.provenance == table.provenance


@pytest.mark.field
def test_field_position_write_is_what_the_field_command_writes(tmp_path, run_cli):
    """``OpenCircuit.write`` / ``PositionResult.write``: field.json, potential.xdmf (+ .h5)
    and field.png, as ``tengfield field`` writes them (coarse P1 mesh)."""
    import pyvista  # noqa: F401 - before dolfinx, as the CLI does
    from mpi4py import MPI

    from tengfield.field import open_circuit

    path = tmp_path / "scene.toml"
    path.write_text("[field]\nmesh_size_mm = 1.5\ndegree = 1\n")
    done = run_cli("field", path, "--position-mm", "1.5", "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    state = open_circuit(tf.load_scene(path), 1.5e-3, comm=MPI.COMM_SELF, keep_solution=True)
    assert state.result.scene.source == tf.load_scene(path).source
    written = state.write(tmp_path / "api")
    assert [p.name for p in written] == ["field.json", "potential.xdmf", "field.png"]
    assert_png(tmp_path / "api" / "field.png")
    assert state.summary == json.loads((tmp_path / "api" / "field.json").read_text())
    assert_same_files(tmp_path / "api", tmp_path / "cli", summary_timing=True,
                      binary=("potential.h5",))
