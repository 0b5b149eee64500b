"""`tengfield sweep --vary section.key=START:STOP:N` and `tf.sweep(scene, vary=...)`: any
scene key in file units, each point's scene built through `--set`'s path (every scene
check applies), one surrogate per geometry (a σ or circuit key solves no field), one row
per point and load, one figure per varied key. The field is the analytic plate model
(plate_model.py), put in the cache or passed as ``solve``: what is tested is the sweep."""
from __future__ import annotations

import csv

import numpy as np
import pytest

import tengfield as tf
from tengfield import surrogate
from tengfield import sweeps as sweep_module
from tengfield.errors import SceneError
from tengfield.scene import parse_scene
from tengfield.sweeps import parse_vary, vary_points

import plate_model as fx

SHORT = "[run]\nduration_s = 1.0\n"


def short_scene():
    return parse_scene(SHORT)


def cached_plate_tables(scenes, cache):
    """The plate-model surrogate of every scene written into ``cache`` (a stand-in for
    a precomputed field)."""
    for scene in scenes:
        surrogate.write_table(surrogate.cache_path(scene, cache),
                              surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve))


# ---------------------------------------------------------------------------
# the --vary text
def test_parse_vary_reads_ranges_lists_and_one_value():
    assert parse_vary("device.stroke_mm=1:5:9") == ("device.stroke_mm",
                                                    [1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0])
    assert parse_vary("circuit.load_ohm=1e6,1e8") == ("circuit.load_ohm", [1e6, 1e8])
    assert parse_vary("circuit.kind=[load, rectifier]") == ("circuit.kind", ["load", "rectifier"])
    assert parse_vary(" contact.restitution = 0.5 ") == ("contact.restitution", [0.5])
    # a range whose points are not exact in binary is written as its shortest text
    assert parse_vary("device.stroke_mm=0.1:0.3:3")[1] == [0.1, 0.2, 0.3]


@pytest.mark.parametrize("text, expected", [
    ("stroke_mm=1:5:9", "write section.key=START:STOP:N"),
    ("device.stroke_mm", "write section.key=START:STOP:N"),
    ("device.stroke_mm=1:5", "expected START:STOP:N"),
    ("device.stroke_mm=a:5:3", "START and STOP must be numbers"),
    ("device.stroke_mm=1:5:0", "N = 0 is out of range: allowed [1, 100000]"),
    ("device.stroke_mm=1:inf:3", "START and STOP must be finite"),
])
def test_bad_vary_text_is_one_line_naming_it(text, expected):
    with pytest.raises(SceneError, match=r"--vary") as err:
        parse_vary(text)
    assert expected in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("vary, expected", [
    ({"device.stroke_mm": [2.0, -1.0]},
     "sweep point device.stroke_mm = -1: [device] stroke_mm = -1.0 is out of range: "
     "allowed [1e-06, 10000]"),
    ({"device.strok_mm": [2.0]}, "unknown key [device] strok_mm (did you mean 'stroke_mm'?)"),
    ({"device.ball_diameter_mm": [7.0, 30.0]},
     "sweep point device.ball_diameter_mm = 30: [device] ball_diameter_mm = 30: the ball "
     "does not fit the tube; allowed (0, 8) mm"),
    ({"contact.restitution": [0.5, 1.5]}, "[contact] restitution = 1.5 is out of range"),
])
def test_a_bad_point_is_refused_before_any_work_naming_key_value_and_range(vary, expected):
    with pytest.raises(SceneError) as err:
        vary_points(short_scene(), vary)
    assert expected in str(err.value), str(err.value)
    assert "\n" not in str(err.value) and "with --set" not in str(err.value)


def test_a_point_is_checked_at_every_excitation_corner():
    """The steady-window rule of a point's run at the lowest frequency of the axis."""
    scene = parse_scene("[run]\nduration_s = 1.0\nsettle_periods = 5\n")
    vary_points(scene, {"run.settle_periods": [5]}, [10.0, 20.0], [1e-3])
    with pytest.raises(SceneError, match=r"sweep point run.duration_s = 0.2: .*frequency_hz"):
        vary_points(scene, {"run.duration_s": [1.0, 0.2]}, [10.0, 20.0], [1e-3])


def test_vary_of_an_axis_key_beside_its_axis_is_refused():
    with pytest.raises(SceneError, match=r"--vary excitation.frequency_hz and --frequency-hz "
                                         r"both set excitation.frequency_hz"):
        vary_points(short_scene(), {"excitation.frequency_hz": [10, 20]}, [15.0], None)
    vary_points(short_scene(), {"excitation.frequency_hz": [15, 20]}, None, [1e-3])


def test_too_many_points_are_refused_before_any_scene_is_built():
    with pytest.raises(SceneError, match=r"sweep points = 1000 device.stroke_mm x 1000 "
                                         r"circuit.load_ohm x 1 excitations = 1e\+06: allowed"):
        vary_points(short_scene(), {"device.stroke_mm": np.linspace(1, 3, 1000),
                                    "circuit.load_ohm": np.logspace(6, 9, 1000)})


# ---------------------------------------------------------------------------
# the Python face: physics and the surrogate reuse
def test_sigma_sweep_solves_one_field_and_scales_the_charge(tmp_path):
    """σ is not a field input (the surrogate scales with it): three σ points cost one
    surrogate; the dynamics do not depend on σ, so Q_SC and V_OC are proportional to it."""
    solver = fx.CountingSolver()
    rows = tf.sweep(short_scene(), vary={"device.surface_charge_uC_per_m2": "-10:-30:3"},
                    cache_dir=tmp_path, solve=solver, jobs=1)
    assert rows.surrogates == {"computed": 1, "cached": 0, "reused": 2, "geometries": 1}
    positions = solver.calls
    assert positions > 0
    sigma = np.array([r["device.surface_charge_uC_per_m2"] for r in rows])
    np.testing.assert_array_equal(sigma, [-10.0, -20.0, -30.0])
    for column in ("Q_sc_pp_C", "V_oc_pp_V", "I_sc_pp_A"):
        values = np.array([r[column] for r in rows])
        np.testing.assert_allclose(values / sigma, values[0] / sigma[0], rtol=1e-9)
    again = tf.sweep(short_scene(), vary={"device.surface_charge_uC_per_m2": [-15.0]},
                     cache_dir=tmp_path, solve=solver, jobs=1)
    assert again.surrogates["cached"] == 1 and solver.calls == positions   # a cache hit


def test_geometry_points_reuse_the_surrogate_of_a_repeated_geometry(tmp_path):
    """Two strokes, the first repeated by another key's points: two surrogates, not four."""
    solver = fx.CountingSolver()
    rows = tf.sweep(short_scene(), vary={"device.stroke_mm": [2.5, 3.0],
                                         "circuit.parallel_capacitance_pF": [0.0, 20.0]},
                    cache_dir=tmp_path, solve=solver, jobs=1)
    assert len(rows) == 4
    assert rows.surrogates == {"computed": 2, "cached": 0, "reused": 2, "geometries": 2}
    assert [(r["device.stroke_mm"], r["circuit.parallel_capacitance_pF"]) for r in rows] == \
        [(2.5, 0.0), (2.5, 20.0), (3.0, 0.0), (3.0, 20.0)]
    # the instrument's capacitance loads the reading: V_read below the ideal V_OC
    for r in rows:
        if r["circuit.parallel_capacitance_pF"] > 0:
            assert 0 < r["V_read_pp_V"] < r["V_oc_pp_V"]
        else:
            assert r["V_read_pp_V"] is None


def test_load_power_peaks_at_a_load_between_the_ends(tmp_path):
    """Mean power into a resistor vanishes at 0 and infinity: a vary of circuit.load_ohm
    over six decades has its maximum inside (the matched load)."""
    rows = tf.sweep(short_scene(), vary={"contact.restitution": [0.6]}, load_ohm="1e5:1e12:8",
                    cache_dir=tmp_path, solve=fx.plate_model_solve, jobs=1)
    power = [r["P_mean_W"] for r in rows]
    k = int(np.argmax(power))
    assert 0 < k < len(power) - 1 and power[k] > 3 * max(power[0], power[-1])


def test_the_frequency_amplitude_face_equals_the_old_signature(tmp_path):
    scene = short_scene()
    table = surrogate.precompute(scene, comm=None, solve=fx.plate_model_solve)
    cached_plate_tables([scene], tmp_path)
    old = sweep_module.sweep(scene, table, [15.0, 25.0], [1e-3, 1.5e-3], [1e8], jobs=1)
    new = tf.sweep(scene, frequency_hz=[15, 25], amplitude_mm="1:1.5:2", load_ohm=[1e8],
                   cache_dir=tmp_path, jobs=1)
    assert new.vary == [] and list(new) == list(old)
    assert new.surrogates["cached"] == 1


def test_vary_with_the_excitation_axes_nests_the_axes_inside(tmp_path):
    rows = tf.sweep(short_scene(), vary={"contact.restitution": [0.5, 0.7]},
                    frequency_hz=[15, 25], cache_dir=tmp_path, solve=fx.plate_model_solve,
                    jobs=1)
    assert [(r["contact.restitution"], r["frequency_hz"], r["amplitude_mm"]) for r in rows] == \
        [(0.5, 15.0, 1.5), (0.5, 25.0, 1.5), (0.7, 15.0, 1.5), (0.7, 25.0, 1.5)]


def test_nothing_to_vary_is_refused():
    with pytest.raises(SceneError, match="sweep: nothing to vary"):
        tf.sweep(short_scene())


@pytest.mark.slow
def test_figure_per_key_is_labelled_in_words_and_units(tmp_path):
    rows = tf.sweep(short_scene(), vary={"device.surface_charge_uC_per_m2": [-10, -20],
                                         "circuit.kind": ["load", "open"]},
                    cache_dir=tmp_path, solve=fx.plate_model_solve, jobs=1)
    fig = rows.plot("device.surface_charge_uC_per_m2")
    labels = [ax.get_xlabel() for ax in fig.axes]
    assert labels and all(label == "[device] σ [µC/m²]" for label in labels)
    assert [ax.get_ylabel() for ax in fig.axes][:3] == \
        ["V_OC peak-to-peak [V]", "Q_SC peak-to-peak [nC]", "I_SC peak-to-peak [nA]"]
    assert "surface_charge_uC_per_m2" not in fig._suptitle.get_text()
    text = rows.plot("circuit.kind")
    assert [t.get_text() for t in text.axes[0].get_xticklabels()] == ["load", "open"]
    written = rows.write(tmp_path / "out")
    assert [p.name for p in written] == ["sweep.csv", "sweep_device.surface_charge_uC_per_m2.png",
                                         "sweep_circuit.kind.png"]
    with open(tmp_path / "out" / "sweep.csv") as fh:
        table = list(csv.DictReader(fh))
    assert list(table[0])[:3] == ["device.surface_charge_uC_per_m2", "circuit.kind",
                                  "frequency_hz"]
    assert len(table) == 4


@pytest.mark.mpi
def test_vary_on_two_ranks_equals_the_serial_rows(tmp_path_factory):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    assert comm.size >= 2
    cache = comm.bcast(str(tmp_path_factory.mktemp("cache")) if comm.rank == 0 else None)
    vary = {"device.stroke_mm": [2.5, 3.0], "contact.restitution": [0.5, 0.7]}
    parallel = tf.sweep(short_scene(), vary=vary, frequency_hz=[15, 25], load_ohm=[1e8],
                        cache_dir=cache, solve=fx.plate_model_solve, comm=comm)
    serial = tf.sweep(short_scene(), vary=vary, frequency_hz=[15, 25], load_ohm=[1e8],
                      cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    assert len(serial) == 8 and list(parallel) == list(serial)
    for other in comm.allgather(list(parallel)):
        assert other == list(serial)


def test_vary_alone_runs_an_excitation_without_frequency_and_amplitude(tmp_path):
    """A harmonics excitation has no one frequency/amplitude to sweep, but its other keys
    can be varied; adding a frequency axis is the existing one-line refusal."""
    scene = parse_scene('[excitation]\nkind = "harmonics"\nfrequency_hz = [20.0, 40.0]\n'
                        'amplitude_mm = [1.5, 0.1]\n' + SHORT)
    rows = tf.sweep(scene, vary={"contact.restitution": [0.5, 0.7]}, cache_dir=tmp_path,
                    solve=fx.plate_model_solve, jobs=1)
    assert [r["contact.restitution"] for r in rows] == [0.5, 0.7]
    assert all(r["Q_sc_pp_C"] > 0 for r in rows)
    with pytest.raises(SceneError, match=r"sweep point contact.restitution = 0.5: \[excitation\] "
                                         r"kind = 'harmonics': a sweep varies a sine's"):
        tf.sweep(scene, vary={"contact.restitution": [0.5]}, frequency_hz=[20],
                 cache_dir=tmp_path, solve=fx.plate_model_solve, jobs=1)


def test_an_error_mid_sweep_names_the_varied_point(tmp_path, monkeypatch):
    from tengfield.errors import DynamicsError

    real = sweep_module.sweep_point

    def point(scene, table, frequency, amplitude, loads=(), simulate=None):
        if scene.contact.restitution == 0.7:
            raise DynamicsError("impact map diverged")
        return real(scene, table, frequency, amplitude, loads, simulate)

    monkeypatch.setattr(sweep_module, "sweep_point", point)
    with pytest.raises(DynamicsError, match=r"^sweep point contact.restitution = 0.7: sweep "
                                            r"point frequency_hz = 25, amplitude_mm = 1.5: "
                                            r"impact map diverged$"):
        tf.sweep(short_scene(), vary={"contact.restitution": [0.5, 0.7]}, frequency_hz=[25],
                 cache_dir=tmp_path, solve=fx.plate_model_solve, jobs=1)
    with pytest.raises(DynamicsError, match=r"^sweep point contact.restitution = 0.7: impact "
                                            r"map diverged$"):
        tf.sweep(short_scene(), vary={"contact.restitution": [0.5, 0.7]},
                 cache_dir=tmp_path, solve=fx.plate_model_solve, jobs=1)


def test_vary_that_is_not_a_dict_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match=r"sweep\(vary='device.stroke_mm=1:5:9'\): expected a "
                                        r"dict"):
        tf.sweep(short_scene(), vary="device.stroke_mm=1:5:9")


# ---------------------------------------------------------------------------
# issue 54.4: a varied key takes effect (reaches the rows) or is refused before any work
LOADED = '[circuit]\nkind = "load"\n' + SHORT


def test_a_varied_load_reaches_each_row_as_the_run_at_that_load(tmp_path):
    """The README's ``--vary circuit.load_ohm=1e6,1e8 --set circuit.kind=load``: each row
    has its own load and the mean power ``tengfield run`` reports at that load."""
    from tengfield.pipeline import run

    scene = parse_scene(LOADED)
    cached_plate_tables([scene], tmp_path)
    rows = tf.sweep(scene, vary={"circuit.load_ohm": [1e6, 1e8]}, cache_dir=tmp_path, jobs=1)
    assert [r["load_ohm"] for r in rows] == [1e6, 1e8]
    power = [r["P_mean_W"] for r in rows]
    assert power[0] > 0 and power[1] > 10 * power[0]
    for r in rows:
        alone = run(scene.with_values(circuit={"load_ohm": r["load_ohm"]}), cache_dir=tmp_path)
        assert r["P_mean_W"] == pytest.approx(alone.summary["load"]["mean_power_W"], rel=1e-12)
        assert r["power_density_W_per_m3"] == pytest.approx(
            alone.summary["load"]["power_density_W_per_m3"], rel=1e-12)
        assert r["Q_sc_pp_C"] == pytest.approx(
            alone.summary["peak_to_peak"]["Q_sc_C"], rel=1e-12)
    # the figure: each row's load is its point's (no --load-ohm axis), one line per panel
    fig = rows.plot("circuit.load_ohm")
    assert len(fig.axes) == 4 and fig.axes[3].get_ylabel() == "mean power P [µW]"
    for ax in fig.axes:
        assert len(ax.lines) == 1 and len(ax.lines[0].get_xdata()) == 2
    np.testing.assert_allclose(fig.axes[3].lines[0].get_ydata(), np.array(power) * 1e6)


def test_a_varied_kind_reaches_the_rows_and_series_rc_is_its_own_circuit(tmp_path):
    scene = short_scene()
    cached_plate_tables([scene], tmp_path)
    rows = tf.sweep(scene, vary={"circuit.kind": ["load", "open", "series-rc"]},
                    cache_dir=tmp_path, jobs=1)
    load, open_, series = rows
    assert load["P_mean_W"] > 0 and open_["P_mean_W"] is None and open_["load_ohm"] is None
    # R + C_s (100 pF) is not the R || C_p load: another power at the same R
    assert series["P_mean_W"] > 0 and series["P_mean_W"] != pytest.approx(load["P_mean_W"])
    assert load["Q_sc_pp_C"] == open_["Q_sc_pp_C"] == series["Q_sc_pp_C"]
    capacitors = tf.sweep(parse_scene('[circuit]\nkind = "series-rc"\n' + SHORT),
                          vary={"circuit.series_capacitance_pF": [10.0, 1000.0]},
                          cache_dir=tmp_path, jobs=1)
    assert capacitors[0]["P_mean_W"] != pytest.approx(capacitors[1]["P_mean_W"], rel=1e-3)


def no_solve(*args, **kwargs):
    raise AssertionError("a field solve ran before the varied keys were checked")


@pytest.mark.parametrize("scene_text, vary, loads, expected", [
    (SHORT, {"fit.free": ["a", "b"]}, (), "[fit] is tengfield fit's"),
    (SHORT, {"design.candidates": [4, 8]}, (), "[design] is tengfield design's"),
    (SHORT, {"uncertainty.vary.x": [1, 2]}, (), "[uncertainty] is tengfield uncertainty's"),
    (SHORT, {"reference.V_pp_V": [1.0, 2.0]}, (), "[reference] holds measured values"),
    (SHORT, {"array.cells": [0, 4]}, (), "[array] cells are run by tengfield run"),
    (SHORT, {"run.output_format": ["csv", "hdf5"]}, (), "the format of run's tables"),
    (SHORT, {"circuit.kind": ["open", "short"]}, (), "no kind varied has a load"),
    (SHORT, {"circuit.load_ohm": [1e6, 1e8]}, (), "kind = 'open' does not report load_ohm"),
    (LOADED, {"circuit.series_capacitance_pF": [10, 100]}, (),
     "kind = 'load' does not report series_capacitance_pF in a sweep row (the rows report "
     "load_ohm)"),
    (LOADED, {"circuit.load_ohm": [1e6, 1e8]}, [1e8], "the --load-ohm axis sets the circuit"),
    (SHORT, {"circuit.kind": ["load", "open"]}, [1e8], "the --load-ohm axis sets the circuit"),
    ('[circuit]\nkind = "rectifier"\n' + SHORT, {"circuit.storage_capacitance_uF": [1, 10]}, (),
     "kind = 'rectifier' does not report storage_capacitance_uF"),
    (SHORT, {"breakdown.gamma": [0.01, 0.1]}, (), 'only with [device] surface_charge_uC_per_m2'
                                                  ' = "breakdown"'),
])
def test_a_key_that_reaches_no_row_is_refused_in_one_line_before_any_work(
        tmp_path, scene_text, vary, loads, expected):
    with pytest.raises(SceneError) as err:
        tf.sweep(parse_scene(scene_text), vary=vary, load_ohm=loads, cache_dir=tmp_path,
                 solve=no_solve, jobs=1)
    text = str(err.value)
    key = next(iter(vary))
    assert text.startswith(f"--vary {key}: ") and expected in text, text
    assert "vary keys of [device], [excitation]" in text and "\n" not in text
    assert not any(tmp_path.iterdir())
