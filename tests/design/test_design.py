"""tengfield.design_study with the analytic plate model (no dolfinx): the [design] section,
one candidate's score, the geometry rule, the cache, the search and its outputs."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

import plate_model as fx
import tengfield as tf
from tengfield import electrical
from tengfield.design_study import (candidate_scene, design, evaluate, followed_geometry,
                              parse_design_section, write_design_outputs)
from tengfield.design_study.candidate import _load_power, band_scene, loaded_scene
from tengfield.errors import SceneError
from tengfield.surrogate import TerminalCurves, precompute

SHIP_BAND = {"frequency_hz": [33.0], "amplitude_mm": [0.75, 1.0]}


def design_scene(**design_keys):
    section = {"objective": "power_density", "candidates": 12, "seed": 1,
               "settle_periods": 10, "window_periods": 10, "samples_per_period": 120,
               "vary": {"stroke_mm": [1.0, 5.0]}, "excitation": SHIP_BAND}
    section.update(design_keys)
    return fx.scene_with(design=section)


@pytest.fixture
def cache(tmp_path):
    return tmp_path / "cache"


# ---------------------------------------------------------------------------
# [design]: validated by its own package, one line naming key, value and range
@pytest.mark.parametrize("keys, message", [
    ({"objective": "powr"}, r"\[design\] objective = 'powr' is not allowed: choose one of "
                            r"'power_density'.*did you mean 'power'"),
    ({"aggregate": "max"}, r"\[design\] aggregate = 'max' is not allowed: choose one of 'mean', 'min'"),
    ({"candidates": 2}, r"\[design\] candidates = 2 is out of range: allowed whole numbers \[4, 100000\]"),
    ({"vary": {"gap_mn": [1, 2]}}, r"unknown key \[design.vary\] gap_mn \(did you mean 'gap_mm'\?\)"),
    ({"vary": {"gap_mm": [3.0, 1.0]}}, r"\[design.vary\] gap_mm = \[3.0, 1.0\]: min must be < max"),
    ({"vary": {"gap_mm": [-1.0, 1.0]}}, r"\[design.vary\] gap_mm = \[-1.0, 1.0\]: \[device\] gap_mm = "
                                       r"-1.0 is out of range: allowed \[1e-06, 10000\]"),
    ({"vary": {"gap_mm": 3.0}}, r"\[design.vary\] gap_mm = 3.0: expected \[min, max\]"),
    ({"excitation": {"frequency_hz": [0.0]}}, r"\[design.excitation\] frequency_hz = 0.0 is out "
                                              r"of range: allowed \(0, 1e5\]"),
    ({"excitation": {"amplitud_mm": [1.0]}}, r"unknown key \[design.excitation\] amplitud_mm"),
    ({"requir": "upper-contact"}, r"unknown key \[design\] requir \(did you mean 'require'\?\)"),
    ({"require": "contact"}, r"\[design\] require = 'contact' is not allowed"),
])
def test_bad_design_input_is_one_line_naming_key_value_and_range(keys, message):
    with pytest.raises(SceneError, match=message) as info:
        parse_design_section(design_scene(**keys))
    assert "\n" not in str(info.value)


def test_a_scene_file_with_design_loads_and_the_section_is_kept(tmp_path):
    path = tmp_path / "d.toml"
    path.write_text('[design]\nobjective = "charge"\n[design.vary]\nstroke_mm = [1.0, 5.0]\n'
                    'ball_diameter_mm = [5, 10]\n[design.excitation]\nfrequency_hz = [33.0]\n'
                    'amplitude_mm = [0.5, 0.75, 1.0]\n')
    spec = parse_design_section(tf.load_scene(path))
    assert spec.objective == "charge" and spec.aggregate == "mean" and spec.candidates == 200
    assert spec.vary == {"stroke_mm": (1.0, 5.0), "ball_diameter_mm": (5.0, 10.0)}
    assert spec.band == [(33.0, 0.5e-3), (33.0, 0.75e-3), (33.0, 1.0e-3)]
    assert spec.initial_count() == 64          # largest power of 2 <= 40 % of 200


def test_without_design_excitation_the_band_is_the_scenes_excitation():
    scene = fx.scene_with(design={"vary": {"stroke_mm": [1.0, 5.0]}})
    assert parse_design_section(scene).band == [(20.0, 1.5e-3)]


# ---------------------------------------------------------------------------
# the geometry rule and impossible candidates
def test_a_bigger_ball_takes_its_tube_and_electrode_along():
    base = fx.scene_with().to_dict()["device"]            # d 7, bore 4, outer 5.5, electrode 4
    follow = followed_geometry(base, {"ball_diameter_mm": 10.0})
    assert follow == {"tube_inner_radius_mm": 5.5, "electrode_radius_mm": 5.5,
                      "tube_outer_radius_mm": 7.0}       # clearance 0.5, wall 1.5, no inset
    # a varied key never follows
    assert "tube_outer_radius_mm" not in followed_geometry(
        base, {"ball_diameter_mm": 10.0, "tube_outer_radius_mm": 9.0})
    assert followed_geometry(base, {"stroke_mm": 2.0}) == {}


@pytest.mark.slow   # several candidates' dynamics and load scans
def test_impossible_candidates_are_skipped_with_the_reason_never_a_crash(cache):
    scene = design_scene(geometry="fixed", vary={"ball_diameter_mm": [5.0, 10.0]})
    spec = parse_design_section(scene)
    row = evaluate(scene, spec, {"ball_diameter_mm": 9.0}, cache_dir=cache,
                   solve=fx.plate_model_solve)
    assert row["status"] == "skipped"
    assert "the ball does not fit the tube" in row["reason"]
    assert math.isnan(row["objective"])
    # with the follow rule the same ball fits
    follow = design_scene(vary={"ball_diameter_mm": [5.0, 10.0]})
    ok = evaluate(follow, parse_design_section(follow), {"ball_diameter_mm": 9.0},
                  cache_dir=cache, solve=fx.plate_model_solve)
    assert ok["status"] == "ok" and ok["objective"] > 0


def test_a_missed_requirement_costs_no_field_solve(cache):
    scene = design_scene(require="upper-contact")
    spec = parse_design_section(scene)
    solver = fx.CountingSolver()
    row = evaluate(scene, spec, {"stroke_mm": 5.0}, cache_dir=cache, solve=solver)
    assert row["status"] == "infeasible" and "require = 'upper-contact' not met" in row["reason"]
    assert solver.calls == 0
    assert row["upper_contact_fraction"] == 0.0


# ---------------------------------------------------------------------------
# one candidate's score
def test_power_density_is_the_band_mean_of_the_matched_load_power_per_volume(cache):
    scene = design_scene()
    spec = parse_design_section(scene)
    row = evaluate(scene, spec, {"stroke_mm": 2.0}, cache_dir=cache, solve=fx.plate_model_solve)
    assert row["status"] == "ok" and row["field_status"] == "computed"
    cand = candidate_scene(scene, spec, {"stroke_mm": 2.0})
    volume = cand.device.cell_volume
    assert row["device_volume_m3"] == pytest.approx(volume)
    band = row["band_values"]["power_density"]
    assert row["objective"] == pytest.approx(np.mean(band), rel=1e-12)
    # the matched load maximises the band's mean power: 20 % either side gives less
    table = precompute(cand, solve=fx.plate_model_solve)
    curves = TerminalCurves(table, cand.circuit.reference, cand.device.ball_charge)
    points = [band_scene(cand, spec, f, a) for f, a in spec.band]
    dyn = [tf.simulate(p) for p in points]
    load = row["load_ohm"]

    def mean_density(r):
        return np.mean([_load_power(p, d, curves, r) for p, d in zip(points, dyn)]) / volume
    assert mean_density(load) == pytest.approx(row["objective"], rel=1e-9)
    assert mean_density(load * 1.2) < row["objective"]
    assert mean_density(load / 1.2) < row["objective"]
    # the error bar: 3 x (field + surrogate error estimate) of the objective
    eps = row["field_error"] + row["interpolation_error"]
    assert row["objective_error"] == pytest.approx(3 * eps * row["objective"])


@pytest.mark.parametrize("circuit", [{}, {"kind": "rectifier", "load_ohm": 5e6},
                                     {"kind": "series-rc", "series_capacitance_pF": 47.0}])
def test_the_load_scans_scene_is_the_scene_with_that_load(circuit):
    """The scan's fast copy (no parsing) equals ``with_values`` in its circuit and in the
    values as given (``raw``: what a written scene shows)."""
    point = fx.scene_with(circuit=circuit) if circuit else fx.scene_with()
    given = json.dumps(point.raw, sort_keys=True)
    fast = loaded_scene(point, 3.3e7)
    slow = point.with_values(circuit={"kind": "load", "load_ohm": 3.3e7})
    assert fast.circuit == slow.circuit and fast.circuit.load == 3.3e7
    assert fast.raw == slow.raw and fast.to_dict() == slow.to_dict()
    assert point.circuit.load != 3.3e7 and json.dumps(point.raw, sort_keys=True) == given


def test_worst_case_aggregate_is_the_smallest_band_value(cache):
    scene = design_scene(aggregate="min", objective="charge")
    row = evaluate(scene, parse_design_section(scene), {"stroke_mm": 2.0}, cache_dir=cache,
                   solve=fx.plate_model_solve)
    band = row["band_values"]["charge"]
    assert row["objective"] == min(band) and row["objective"] > 0
    # the charge is the run's Q_SC peak-to-peak at that band point
    cand = band_scene(candidate_scene(scene, parse_design_section(scene), {"stroke_mm": 2.0}),
                      parse_design_section(scene), 33.0, 1.0e-3)
    curves = TerminalCurves(precompute(cand, solve=fx.plate_model_solve),
                            cand.circuit.reference, cand.device.ball_charge)
    assert band[1] == pytest.approx(
        electrical.terminal_peaks(cand, tf.simulate(cand), curves)["Q_sc"], rel=1e-12)


def test_a_repeated_geometry_costs_no_field_solve(cache):
    scene = design_scene(vary={"stroke_mm": [1.0, 5.0], "load_ohm": [1e8, 1e12]})
    spec = parse_design_section(scene)
    solver = fx.CountingSolver()
    first = evaluate(scene, spec, {"stroke_mm": 2.0, "load_ohm": 1e9}, cache_dir=cache,
                     solve=solver)
    calls = solver.calls
    assert calls > 0 and first["load_ohm"] == 1e9
    again = evaluate(scene, spec, {"stroke_mm": 2.0, "load_ohm": 1e10}, cache_dir=cache,
                     solve=solver)
    assert solver.calls == calls and again["field_status"] == "cached"
    assert again["field_hash"] == first["field_hash"]


def test_harvested_power_and_stroke_objectives(cache):
    scene = design_scene(objective=["harvested_power", "stroke"])
    spec = parse_design_section(scene)
    row = evaluate(scene, spec, {"stroke_mm": 2.0}, cache_dir=cache, solve=fx.plate_model_solve)
    assert row["objectives"]["harvested_power"]["value"] > 0
    assert row["objectives"]["stroke"] == {"value": pytest.approx(2e-3), "error": 0.0}


def test_the_charge_comes_from_one_function(monkeypatch, cache):
    """candidate_charge is the one place that sets σ (the breakdown limit goes there)."""
    from tengfield.design_study import candidate as module

    scene = design_scene(objective="charge")
    spec = parse_design_section(scene)
    base = evaluate(scene, spec, {"stroke_mm": 2.0}, cache_dir=cache, solve=fx.plate_model_solve)
    def doubled_charge(s, t=None):   # the scene at twice its σ; the table (per unit) as is
        return s.with_values(device={"surface_charge_uC_per_m2":
                                     2e6 * s.device.surface_charge}), t
    monkeypatch.setattr(module, "candidate_charge", doubled_charge)
    doubled = evaluate(scene, spec, {"stroke_mm": 2.0}, cache_dir=cache, solve=fx.plate_model_solve)
    assert doubled["objective"] == pytest.approx(2 * base["objective"], rel=1e-9)


# ---------------------------------------------------------------------------
# the search
@pytest.mark.slow   # several candidates' dynamics and load scans
def test_search_is_deterministic_by_seed_and_spends_the_budget(cache):
    scene = design_scene(candidates=16, batch=4)
    a = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    b = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    assert [r["values"] for r in a.rows] == [r["values"] for r in b.rows]
    assert [r["objective"] for r in a.rows] == [r["objective"] for r in b.rows]
    assert len(a.rows) == 16 and len({tuple(r["values"].items()) for r in a.rows}) == 16
    assert a.rows[0]["phase"] == "space-filling" and a.rows[-1]["phase"].startswith("refine")
    c = design(design_scene(candidates=16, batch=4, seed=7), cache_dir=cache,
               solve=fx.plate_model_solve, jobs=1)
    assert [r["values"] for r in c.rows] != [r["values"] for r in a.rows]
    assert a.best == a.rows[a.ranking[0]]
    assert all(a.best["objective"] >= r["objective"] for r in a.rows if r["status"] == "ok")


def test_search_finds_the_largest_full_contact_stroke(cache):
    """objective = "stroke" with require: the search (boxes shrinking on a feasibility
    edge) lands within a dense scan's step of the largest stroke that keeps contact."""
    scene = design_scene(objective="stroke", require="upper-contact", candidates=32, batch=8,
                         vary={"stroke_mm": [0.5, 4.0]})
    result = design(scene, cache_dir=cache, jobs=1)
    spec = parse_design_section(scene)
    scan = np.linspace(0.5, 4.0, 36)
    feasible = [g for g in scan if evaluate(scene, spec, {"stroke_mm": float(g)})["status"] == "ok"]
    assert result.best is not None
    assert result.best["values"]["stroke_mm"] >= max(feasible) - 0.1 - 1e-9
    assert result.best["upper_contact_fraction"] == 1.0


@pytest.mark.slow   # several candidates' dynamics and load scans
def test_two_processes_give_the_serial_rows(cache):
    scene = design_scene(candidates=8, batch=4)
    serial = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    pooled = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=2)
    strip = ("wall_s", "field_status")
    assert [{k: v for k, v in r.items() if k not in strip} for r in pooled.rows] == \
        [{k: v for k, v in r.items() if k not in strip} for r in serial.rows]


@pytest.mark.slow   # several candidates' dynamics and load scans
def test_tf_design_is_the_api_and_the_outputs_are_complete(tmp_path, cache):
    scene = design_scene(candidates=8, batch=4,
                         vary={"stroke_mm": [1.0, 5.0], "ball_diameter_mm": [5.0, 10.0]})
    result = tf.design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    assert isinstance(result, tf.design_study.DesignResult)
    written = write_design_outputs(result, tmp_path)
    assert {p.name for p in written} == {"design.csv", "design.json", "best.toml", "design.png"}
    rows = list(csv.DictReader(open(tmp_path / "design.csv")))
    assert len(rows) == 8
    for column in ("stroke_mm", "ball_diameter_mm", "power_density_W_per_m3",
                   "power_density_at_33hz_0.75mm", "power_density_at_33hz_1mm", "regimes",
                   "upper_contact_fraction", "reason", "status"):
        assert column in rows[0]
    summary = json.loads((tmp_path / "design.json").read_text())
    best = summary["best"]
    assert {"stroke_mm", "ball_diameter_mm", "objective", "objective_error"} <= set(best)
    assert best["objective"] == result.best["objective"]
    assert summary["ranking"][0]["index"] == best["index"]
    assert summary["settings"]["candidates"] == 8 and summary["wall_time_s"] > 0
    assert set(summary["cost_per_candidate_s"]) >= {"field", "dynamics", "circuit"}
    # best.toml is a scene with the best geometry, its followed tube and the matched load
    again = tf.load_scene(tmp_path / "best.toml")
    assert again.device.stroke == pytest.approx(best["stroke_mm"] * 1e-3)
    assert again.device.ball_diameter == pytest.approx(best["ball_diameter_mm"] * 1e-3)
    assert again.device.tube_inner_radius == pytest.approx(
        (best["ball_diameter_mm"] / 2 + 0.5) * 1e-3)
    assert again.circuit.kind == "load" and again.circuit.load == pytest.approx(
        best["load_ohm"], rel=1e-5)
    assert "design" not in again.raw
    assert (tmp_path / "design.png").stat().st_size > 10_000


@pytest.mark.slow   # several candidates' dynamics and load scans
def test_two_objectives_give_a_pareto_plot(tmp_path, cache):
    scene = design_scene(candidates=8, batch=4, objective=["power_density", "charge"])
    result = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    front = result.pareto()
    assert result.ranking[0] in front
    write_design_outputs(result, tmp_path)
    assert json.loads((tmp_path / "design.json").read_text())["pareto"]
    assert (tmp_path / "design.png").stat().st_size > 10_000


@pytest.mark.slow
@pytest.mark.field
def test_breakdown_charge_scores_each_geometry_at_its_own_limit(tmp_path):
    """[device] surface_charge_uC_per_m2 = "breakdown": each candidate runs at -sigma_max of
    its own geometry (the limit `tengfield breakdown` reports for that scene), so Q_SC is
    the breakdown-limited charge; the two strokes get different limits."""
    from tengfield.air_breakdown import obtain_breakdown_table, scene_breakdown
    from tengfield.design_study import candidate_scene

    scene = design_scene(objective="charge").with_values(
        device={"surface_charge_uC_per_m2": "breakdown"})
    spec = parse_design_section(scene)
    rows = [evaluate(scene, spec, {"stroke_mm": gap}, cache_dir=tmp_path) for gap in (2.0, 4.0)]
    limits = []
    for gap, row in zip((2.0, 4.0), rows):
        assert row["status"] == "ok", row["reason"]
        cand = candidate_scene(scene, spec, {"stroke_mm": gap})
        table, _ = obtain_breakdown_table(cand, cache_dir=tmp_path)
        sigma_max = scene_breakdown(cand, table).sigma_max
        assert row["surface_charge_uC_per_m2"] == pytest.approx(-sigma_max * 1e6, rel=1e-12)
        limits.append(sigma_max)
    assert limits[0] != pytest.approx(limits[1], rel=1e-3)
    # the answer says which σ and that it is the breakdown limit
    from tengfield.design_study import DesignResult, answer_lines
    from tengfield.design_study.answer import describe
    rows = [{"index": i, "phase": "test", **r} for i, r in enumerate(rows)]
    result = DesignResult(scene=scene, spec=spec, rows=rows, ranking=[0, 1])
    stated = describe(result, rows[0])
    assert stated["breakdown"] is True
    assert stated["surface_charge_uC_per_m2"] == rows[0]["surface_charge_uC_per_m2"]
    assert "(the air-breakdown limit of this geometry)" in "\n".join(answer_lines(result))


def test_random_and_harmonics_excitations_are_scored_as_the_scene_gives_them(cache):
    """A random (or harmonics + noise) scene: every candidate meets the same realisation
    (its seed, on the run's clock); the score is deterministic, differs from the sine's,
    and [design.excitation] (a sine band) is refused next to it."""
    engine = {"kind": "harmonics", "frequency_hz": [33.0, 66.0], "amplitude_mm": [0.75, 0.05],
              "band_hz": [10.0, 300.0], "rms_acceleration_m_per_s2": 3.0, "seed": 2}
    section = {"objective": "charge", "candidates": 4, "seed": 1, "settle_periods": 10,
               "window_periods": 10, "samples_per_period": 120, "vary": {"stroke_mm": [1.0, 5.0]}}
    scene = fx.scene_with(excitation=engine, design=section)
    spec = parse_design_section(scene)
    a = evaluate(scene, spec, {"stroke_mm": 2.0}, cache_dir=cache, solve=fx.plate_model_solve)
    b = evaluate(scene, spec, {"stroke_mm": 2.0}, cache_dir=cache, solve=fx.plate_model_solve)
    assert a["status"] == "ok" and a["objective"] == b["objective"] > 0
    sine = fx.scene_with(design={**section, "excitation": {"frequency_hz": [33.0],
                                                            "amplitude_mm": [0.75]}})
    s = evaluate(sine, parse_design_section(sine), {"stroke_mm": 2.0}, cache_dir=cache,
                 solve=fx.plate_model_solve)
    assert s["objective"] != a["objective"]
    with pytest.raises(SceneError, match=r"\[design.excitation\] needs \[excitation\] kind"):
        parse_design_section(fx.scene_with(excitation=engine, design=sine.raw["design"]))


# ---------------------------------------------------------------------------
# best.toml: `tengfield run` on it reproduces the design's value at its band point
def _best_of(tmp_path, cache, scene):
    result = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    assert result.best is not None
    write_design_outputs(result, tmp_path, plots=False)
    best = tf.load_scene(tmp_path / "best.toml")
    run = tf.run(best, cache_dir=cache, solve=fx.plate_model_solve)
    return result, best, run.summary


@pytest.mark.parametrize("objective, load, value_of", [
    ("power_density", "one", lambda s: s["load"]["power_density_W_per_m3"]),
    ("power", "each", lambda s: s["load"]["mean_power_W"]),
    ("harvested_power", "one", lambda s: s["rectifier"]["average_harvested_power_W"]),
    ("charge", "one", lambda s: s["peak_to_peak"]["Q_sc_C"]),
])
def test_best_toml_runs_to_the_designs_value_at_its_band_point(tmp_path, cache,
                                                               objective, load, value_of):
    """best.toml carries the run the design scored (settle + window periods at the design's
    sampling), for harvested power the rectifier, with load = "each" the first band point's
    own matched load: `tengfield run` on it gives the design's value at the band point it
    names (it ran the scene's own [run], and an open circuit for harvested_power and for
    load = "each": no power at all)."""
    from tengfield.design_study.answer import chosen_band_point

    scene = design_scene(objective=objective, candidates=4, field="scene", load=load,
                         settle_periods=6, window_periods=8).with_values(
        run={"duration_s": 0.3, "settle_periods": 2})
    result, best, summary = _best_of(tmp_path, cache, scene)
    k = chosen_band_point(result, result.best)
    expected = result.best["band_values"][objective][k]
    assert best.excitation.amplitude == pytest.approx(result.spec.band[k][1])
    assert best.run.settle_periods == 6
    assert best.run.duration == pytest.approx(14 / best.excitation.frequency)
    assert value_of(summary) == pytest.approx(expected, rel=1e-6)
    assert f"{expected:.6g}" in (tmp_path / "best.toml").read_text()   # said in the header


def test_best_toml_keeps_a_harmonics_excitation(tmp_path, cache):
    """A harmonics (or random) scene is scored as it is given: best.toml keeps every
    component (it replaced the lists by the fundamental, a plain sine)."""
    engine = {"kind": "harmonics", "frequency_hz": [33.0, 66.0], "amplitude_mm": [0.75, 0.05],
              "band_hz": [10.0, 300.0], "rms_acceleration_m_per_s2": 3.0, "seed": 2}
    section = {"objective": "charge", "candidates": 4, "seed": 1, "settle_periods": 10,
               "window_periods": 10, "samples_per_period": 120, "field": "scene",
               "vary": {"stroke_mm": [1.0, 5.0]}}
    scene = fx.scene_with(excitation=engine, design=section)
    result, best, summary = _best_of(tmp_path, cache, scene)
    assert best.excitation.kind == "harmonics"
    assert best.raw["excitation"]["frequency_hz"] == [33.0, 66.0]
    assert best.raw["excitation"]["amplitude_mm"] == [0.75, 0.05]
    assert summary["peak_to_peak"]["Q_sc_C"] == pytest.approx(
        result.best["band_values"]["charge"][0], rel=1e-6)


def test_a_varied_load_is_one_column_of_design_csv(tmp_path, cache):
    """[design.vary] load_ohm: design.csv has one load_ohm column, the varied (= used) load
    (it had two of the same name: pandas reads the second as load_ohm.1, csv.DictReader
    keeps only one)."""
    scene = design_scene(objective="power", candidates=4, vary={"load_ohm": [1e6, 1e12]})
    result = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    write_design_outputs(result, tmp_path, plots=False)
    with open(tmp_path / "design.csv") as f:
        header = next(csv.reader(f))
    assert len(header) == len(set(header))
    rows = list(csv.DictReader(open(tmp_path / "design.csv")))
    assert [float(r["load_ohm"]) for r in rows] == [r["values"]["load_ohm"] for r in result.rows]


def test_a_random_excitation_is_labelled_as_such_not_by_an_unused_amplitude(tmp_path, cache):
    """A random excitation has no amplitude: design.csv's band columns and design.json's band
    named the scene's unused sine amplitude ('charge_at_33hz_1.5mm')."""
    noise = {"kind": "random", "band_hz": [10.0, 300.0], "rms_acceleration_m_per_s2": 20.0,
             "seed": 0, "frequency_hz": 33.0}
    section = {"objective": "charge", "candidates": 4, "seed": 1, "settle_periods": 10,
               "window_periods": 10, "samples_per_period": 120, "vary": {"stroke_mm": [1.0, 5.0]}}
    scene = fx.scene_with(excitation=noise, design=section)
    result = design(scene, cache_dir=cache, solve=fx.plate_model_solve, jobs=1)
    write_design_outputs(result, tmp_path, plots=False)
    with open(tmp_path / "design.csv") as f:
        header = next(csv.reader(f))
    assert "charge_at_33hz_random" in header
    assert not any("_at_" in c and c.endswith("mm") for c in header)
    band = json.loads((tmp_path / "design.json").read_text())["settings"]["band"]
    assert band == [{"frequency_hz": 33.0, "excitation": "random"}]


def test_the_old_stroke_key_is_read_once_under_its_new_name(tmp_path):
    """[design.vary] gap_mm (the stroke's name before issue #29) is read with one warning
    and stored as stroke_mm: candidates, design.csv's column and the answer name stroke_mm;
    both names at once are refused."""
    import warnings

    from tengfield.design_study.output import csv_columns
    from tengfield.design_study.search import DesignResult

    path = tmp_path / "old.toml"
    path.write_text('[design]\nobjective = "stroke"\n[design.vary]\ngap_mm = [1.0, 5.0]\n')
    scene = tf.load_scene(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        spec = parse_design_section(scene)
        again = parse_design_section(scene)       # the CLI parses twice: still one line
    lines = [str(w.message) for w in caught if "design.vary" in str(w.message)]
    assert len(lines) == 1 and "gap_mm is now called stroke_mm" in lines[0]
    assert spec.vary == again.vary == {"stroke_mm": (1.0, 5.0)}
    assert "stroke_mm" in csv_columns(DesignResult(scene, spec, [], []))
    assert candidate_scene(scene, spec, {"stroke_mm": 2.0}).device.stroke == pytest.approx(2e-3)
    both = fx.scene_with(design={"vary": {"gap_mm": [1.0, 5.0], "stroke_mm": [1.0, 5.0]}})
    with pytest.raises(SceneError, match=r"\[design.vary\] gap_mm and stroke_mm are the same "
                                         r"key \(gap_mm is its old name\): give stroke_mm only"):
        parse_design_section(both)


def test_bundles_keep_a_canonical_geometrys_candidates_together_within_a_share():
    """Random keys (None: a candidate without a canonical geometry): every index once,
    one key per bundle, no bundle past ceil(n / workers), the largest first; a key's
    candidates in as few bundles as the share allows."""
    from tengfield.design_study.search import bundles

    rng = np.random.default_rng(40)
    for _ in range(200):
        n, workers = int(rng.integers(1, 40)), int(rng.integers(1, 5))
        keys = [None if rng.random() < 0.1 else int(rng.integers(0, 6)) for _ in range(n)]
        out = bundles(keys, workers)
        share = -(-n // workers)
        assert sorted(i for b in out for i in b) == list(range(n))
        assert all(len(b) <= share and b == sorted(b) for b in out)
        assert all(len({keys[i] for i in b}) == 1 for b in out)
        assert [len(b) for b in out] == sorted((len(b) for b in out), reverse=True)
        for key in {k for k in keys if k is not None}:
            count = keys.count(key)
            assert sum(1 for b in out if keys[b[0]] == key) == -(-count // share)


def test_the_candidates_of_one_canonical_tube_share_a_mapping_group():
    """Two tubes within the canonical grid's rounding share the group; a ball 20 %
    smaller does not."""
    from tengfield.field import mapping_group
    from tengfield.scene import default_scene

    base = default_scene()
    near = base.with_values(device={"ball_diameter_mm": base.device.ball_diameter * 1e3 * 1.001})
    far = base.with_values(device={"ball_diameter_mm": base.device.ball_diameter * 1e3 * 0.8})
    assert mapping_group(base) is not None and mapping_group(base) == mapping_group(near)
    assert mapping_group(far) != mapping_group(base)
