"""A study's work is counted and said before it starts, and refused past its limits
(issue #43.6, #43.3): field solves, dynamics runs, surrogate cache and memory."""
from __future__ import annotations

import pytest

import plate_model
from tengfield.errors import SceneError
from tengfield.uncertainty_study import run_study, uncertainty_spec
from tengfield.uncertainty_study.cost import (EVALUATION_BYTES, SURROGATE_BYTES, WorkCost,
                                        check_cost, study_cost)
from tengfield.uncertainty_study.sampling import study_values

BALL = "device.ball_diameter_mm"


def scene_with(vary, samples=64, method="monte-carlo", **extra):
    return plate_model.scene_with(uncertainty={"samples": samples, "method": method,
                                               "seed": 1, "vary": vary, **extra})


def never(*args, **kwargs):
    raise AssertionError("no work may start")


def test_a_geometry_study_past_its_field_solve_limit_is_refused_before_any_work(tmp_path):
    scene = scene_with({BALL: {"distribution": "uniform", "low": 5.0, "high": 7.5}},
                       samples=2048, max_field_solves=100)
    with pytest.raises(SceneError) as err:
        run_study(scene, cache_dir=tmp_path, solve=never, simulate=never, jobs=1)
    text = str(err.value)
    assert "\n" not in text
    assert "[uncertainty] max_field_solves = 100" in text and "2,049 field solves" in text


def test_the_counts_are_those_of_the_draws():
    """Monte Carlo over ball x restitution: every draw its own geometry and dynamics;
    Sobol over sigma alone: one field, one group (and the nominal run)."""
    scene = scene_with({BALL: {"distribution": "uniform", "low": 5.0, "high": 7.5},
                        "contact.restitution": {"distribution": "uniform", "low": 0.1,
                                                "high": 0.5}}, samples=40)
    spec = uncertainty_spec(scene)
    cost = study_cost(scene, spec, study_values(spec))
    assert (cost.evaluations, cost.field_solves, cost.dynamics_runs) == (40, 41, 41)
    assert cost.cache_bytes == 41 * SURROGATE_BYTES
    sigma = scene_with({"device.surface_charge_uC_per_m2": {"distribution": "uniform",
                                                            "low": -10.0, "high": -6.0}},
                       samples=64, method="sobol")
    spec = uncertainty_spec(sigma)
    cost = study_cost(sigma, spec, study_values(spec))
    assert (cost.evaluations, cost.field_solves, cost.dynamics_runs) == (192, 1, 2)
    assert cost.memory_bytes >= 192 * EVALUATION_BYTES


def test_a_study_larger_than_the_memory_is_refused_naming_samples():
    cost = WorkCost(evaluations=10**6, field_solves=1, dynamics_runs=2, cache_bytes=0,
                    memory_bytes=5 * 10**9)
    with pytest.raises(SceneError, match=r"\[uncertainty\] samples = 262144: the study would "
                                         r"hold ~5 GB .* of the 4 GB available"):
        check_cost(cost, field_limit=1000, field_key="[uncertainty] max_field_solves",
                   size_key="[uncertainty] samples = 262144", memory=4 * 10**9)
    check_cost(cost, field_limit=1000, field_key="k", size_key="s", memory=16 * 10**9)


def test_a_bad_limit_is_one_line():
    scene = scene_with({"contact.restitution": {"distribution": "uniform", "low": 0.1,
                                                "high": 0.5}}, max_field_solves=-1)
    with pytest.raises(SceneError, match=r"\[uncertainty\] max_field_solves = -1: allowed"):
        uncertainty_spec(scene)


@pytest.mark.slow
def test_the_cli_says_the_work_before_it_starts(tmp_path, run_cli):
    scene = tmp_path / "s.toml"
    scene.write_text('[uncertainty]\nsamples = 20\nmethod = '
                     '"monte-carlo"\n[uncertainty.vary]\n"device.surface_charge_uC_per_m2" = '
                     '{ distribution = "uniform", low = -10.0, high = -6.0 }\n')
    proc = run_cli("uncertainty", scene, "-o", tmp_path / "out", "--no-plots", "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    said = [line for line in proc.stderr.splitlines() if "field solve" in line]
    assert said and said[0].startswith("tengfield: uncertainty: 20 evaluations: at most 1 "
                                       "field solve"), proc.stderr
    assert "2 dynamics runs" in said[0]
    assert "20 evaluations" in proc.stdout       # the summary after the work


def test_a_shell_cavity_counts_as_geometry():
    """A spherical shell's cavity_diameter_mm changes its field (the shape's own key,
    not a FIELD_KEYS one): each distinct cavity drawn is a field solve."""
    from shell_model import shell_device_toml
    from tengfield.scene import parse_scene

    scene = parse_scene(shell_device_toml() + '\n[uncertainty]\nsamples = 24\nmethod = '
                        '"monte-carlo"\n[uncertainty.vary]\n"device.cavity_diameter_mm" = '
                        '{ distribution = "uniform", low = 11.0, high = 12.0 }\n')
    spec = uncertainty_spec(scene)
    cost = study_cost(scene, spec, study_values(spec))
    assert cost.field_solves == 25 and cost.dynamics_runs == 25
