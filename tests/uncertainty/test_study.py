"""Studies of the default scene with the analytic plate model as field solver (a fresh
cache per test): σ is a scaling, two inputs' indices behave, a geometry key reuses the
cached fields, and an evaluation equals ``tengfield.pipeline.run`` (issue #34)."""
from __future__ import annotations

import numpy as np
import pytest

import plate_model
from tengfield.pipeline import run
from tengfield.uncertainty_study import evaluation, run_study

pytestmark = pytest.mark.slow

SIGMA = "device.surface_charge_uC_per_m2"
Q = "peak_to_peak.Q_sc_C"


def scene_with(vary, samples=64, method="sobol", seed=2, **sections):
    return plate_model.scene_with(uncertainty={"samples": samples, "method": method,
                                               "seed": seed, "vary": vary}, **sections)


def test_sigma_alone_is_the_linear_scaling_of_the_nominal_run(tmp_path):
    scene = scene_with({SIGMA: {"distribution": "normal", "mean": -20.0, "std": 2.0}})
    study = run_study(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve, jobs=1)
    nominal = run(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve)
    sigma0 = scene.device.surface_charge * 1e6           # -8 uC/m^2
    per_sigma = nominal.summary["peak_to_peak"]["Q_sc_C"] / abs(sigma0)
    sigma = study.values[:, 0]
    q = np.array([row[Q] for row in study.evaluations.rows])
    np.testing.assert_allclose(q, per_sigma * np.abs(sigma), rtol=1e-9)   # each evaluation
    block = study.summary["outputs"][Q]
    n = len(q)
    assert block["nominal"] == pytest.approx(nominal.summary["peak_to_peak"]["Q_sc_C"],
                                             rel=1e-12)
    # the distribution's own numbers, scaled: within sampling error of N points
    assert block["mean"] == pytest.approx(per_sigma * 20.0, abs=3 * per_sigma * 2.0 / n ** 0.5)
    assert block["std"] == pytest.approx(per_sigma * 2.0, rel=3 / (2 * (n - 1)) ** 0.5)
    for p, z in (("5", 1.6449), ("95", -1.6449)):     # |σ| is smallest at σ's 95 %
        expected = per_sigma * abs(-20.0 + 2.0 * z)
        assert block["percentiles"][p] == pytest.approx(expected, rel=0.03)
    s = block["sobol"][SIGMA]
    assert s["S1"] == pytest.approx(1.0, abs=max(s["S1_conf"], 1e-6))
    assert s["ST"] == pytest.approx(1.0, abs=max(s["ST_conf"], 1e-6))
    assert study.summary["field_solves"] <= 1
    assert study.summary["dynamics_runs"] == 2            # the nominal run and one group


def test_two_inputs_total_at_least_first_order_and_first_orders_sum_below_one(tmp_path):
    scene = scene_with({SIGMA: {"distribution": "uniform", "low": -30.0, "high": -10.0},
                        "contact.restitution": {"distribution": "uniform", "low": 0.05,
                                                "high": 0.5}})
    study = run_study(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve, jobs=1)
    assert study.summary["field_solves"] == 1
    checked = 0
    for name in study.summary["main_outputs"]:
        indices = study.summary["outputs"][name]["sobol"]
        if not indices:
            continue
        checked += 1
        conf = 0.0
        for r in indices.values():
            assert r["ST"] >= r["S1"] - (r["ST_conf"] + r["S1_conf"]), (name, r)
            conf += r["S1_conf"]
        assert sum(r["S1"] for r in indices.values()) <= 1.0 + conf, name
    assert checked >= 3
    assert study.main == study.summary["main_outputs"]
    # the restitution changes the dynamics: one group per distinct value (A and B rows)
    assert study.summary["dynamics_runs"] == 1 + 2 * 64


def test_a_peak_equal_to_its_peak_to_peak_everywhere_is_shown_once():
    """Q_SC of the real device starts from 0 at the lower plate: its peak is its
    peak-to-peak in every evaluation and the figure shows it once; the bipolar
    current's peak differs and is shown; one differing evaluation keeps the panel."""
    from tengfield.uncertainty_study.evaluation import Evaluations
    from tengfield.uncertainty_study.study import shown_outputs

    def rows(q_peak_last):
        return [{Q: 1.0, "peak.Q_sc_C": 1.0, "peak_to_peak.I_sc_A": 2.0, "peak.I_sc_A": 1.2},
                {Q: 2.0, "peak.Q_sc_C": q_peak_last, "peak_to_peak.I_sc_A": 3.0,
                 "peak.I_sc_A": 1.9}]

    def shown(q_peak_last):
        ev = Evaluations(rows=rows(q_peak_last), regimes=["", ""], nominal=rows(2.0)[1],
                         nominal_regime="", field_solves=0, geometries=0, dynamics_runs=0,
                         warnings=[])
        return shown_outputs(list(rows(2.0)[0]), ev)
    assert shown(2.0) == [Q, "peak_to_peak.I_sc_A", "peak.I_sc_A"]
    assert shown(2.0 * (1 + 1e-8))[:3] == [Q, "peak_to_peak.I_sc_A", "peak.I_sc_A"]  # a rounding
    assert shown(1.5) == [Q, "peak_to_peak.I_sc_A", "peak.Q_sc_C", "peak.I_sc_A"]


def test_a_geometry_key_reuses_the_cached_fields(tmp_path):
    scene = scene_with({"device.ball_permittivity": {"distribution": "uniform", "low": 2.0,
                                                     "high": 2.2}},
                       samples=20, method="monte-carlo")
    first_solver = plate_model.CountingSolver()
    first = run_study(scene, cache_dir=tmp_path, solve=first_solver, jobs=1)
    geometries = first.summary["geometries"]
    assert geometries == 21                              # 20 values and the nominal one
    assert first.summary["field_solves"] == geometries and first_solver.calls > 0
    evaluation._OBTAINED.clear()       # this process's memory: the files must do it
    again_solver = plate_model.CountingSolver()
    again = run_study(scene, cache_dir=tmp_path, solve=again_solver, jobs=1)
    assert again.summary["field_solves"] == 0 and again_solver.calls == 0
    assert again.evaluations.rows == first.evaluations.rows


def test_an_evaluation_equals_the_run_of_its_scene(tmp_path):
    scene = scene_with({"contact.restitution": {"distribution": "uniform", "low": 0.05,
                                                "high": 0.5},
                        "circuit.load_ohm": {"distribution": "lognormal", "median": 1e8,
                                             "factor": 3.0}},
                       samples=20, method="monte-carlo", circuit={"kind": "load"})
    study = run_study(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve, jobs=1)
    for i in (0, 7):
        e, load = study.values[i]
        point = scene.with_values(contact={"restitution": e}, circuit={"load_ohm": load})
        summary = run(point, cache_dir=tmp_path, solve=plate_model.plate_model_solve).summary
        row = study.evaluations.rows[i]
        for block in ("peak_to_peak", "load"):
            for key, value in summary[block].items():
                if isinstance(value, float):
                    assert row[f"{block}.{key}"] == pytest.approx(value, rel=1e-12), key
        assert "load.mean_power_W" in study.summary["main_outputs"]


def test_a_candidates_percentile_score_is_its_worse_case_decile(tmp_path):
    from tengfield.uncertainty_study import candidate_percentile, uncertainty_spec

    scene = scene_with({SIGMA: {"distribution": "uniform", "low": -30.0, "high": -10.0}},
                       samples=64, method="monte-carlo")
    spec = uncertainty_spec(scene)
    score, count = candidate_percentile(scene, spec, Q, 10.0, cache_dir=tmp_path,
                                        solve=plate_model.plate_model_solve)
    nominal = run(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve)
    per_sigma = nominal.summary["peak_to_peak"]["Q_sc_C"] / 8.0
    assert count == 64
    # |σ| uniform on [10, 30]: its 10th percentile is 12 (quasi-random points: close)
    assert score == pytest.approx(per_sigma * 12.0, rel=0.02)


def test_groups_that_keep_the_geometry_build_no_scene_for_the_field_phase(tmp_path,
                                                                          monkeypatch):
    """A contact key changes the dynamics, not the field: the field phase takes the
    nominal geometry for its groups (the scene of a group's restitution is built once,
    for its dynamics), and still obtains exactly one surrogate."""
    from tengfield.scene import Scene

    scene = scene_with({SIGMA: {"distribution": "uniform", "low": -30.0, "high": -10.0},
                        "contact.restitution": {"distribution": "uniform", "low": 0.05,
                                                "high": 0.5}}, samples=16)
    calls = []
    original = Scene.with_values

    def counting(self, **sections):
        import traceback
        calls.append((traceback.extract_stack()[-2].name, sorted(sections)))
        return original(self, **sections)
    monkeypatch.setattr(Scene, "with_values", counting)
    study = run_study(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve, jobs=1)
    groups = study.summary["dynamics_runs"] - 1            # without the nominal run
    assert groups == 32
    # scenes with a group's restitution: one per group for its dynamics, none for the
    # field phase (evaluate_study builds no scene)
    assert sum(name == "_group_task" and "contact" in c for name, c in calls) == groups
    assert not [c for name, c in calls if name == "evaluate_study"]
    assert study.summary["geometries"] == 1 and study.summary["field_solves"] == 1
    assert evaluation.changes_field({"device.stroke_mm": 1.0})
    assert not evaluation.changes_field({"contact.restitution": 0.3})


def test_excitation_draws_are_evaluated_at_their_own_excitation(tmp_path):
    """Groups that share a surrogate keep their own scene: a draw of the frequency and
    the amplitude gives the outputs of ``tengfield run`` at that excitation (its own
    steady window), for every evaluation, not the first group's."""
    scene = scene_with({"excitation.frequency_hz": {"distribution": "uniform", "low": 15.0,
                                                    "high": 30.0},
                        "excitation.amplitude_mm": {"distribution": "uniform", "low": 1.0,
                                                    "high": 2.0}},
                       samples=20, method="monte-carlo")
    study = run_study(scene, cache_dir=tmp_path, solve=plate_model.plate_model_solve, jobs=1)
    assert study.summary["field_solves"] == 1
    for i in (0, 5, 13, 19):
        f, a = study.values[i]
        point = scene.with_values(excitation={"frequency_hz": f, "amplitude_mm": a})
        summary = run(point, cache_dir=tmp_path, solve=plate_model.plate_model_solve).summary
        row = study.evaluations.rows[i]
        for key, value in summary["peak_to_peak"].items():
            assert row[f"peak_to_peak.{key}"] == pytest.approx(value, rel=1e-12), (i, key)
