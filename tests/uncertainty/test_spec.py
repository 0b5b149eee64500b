"""[uncertainty] validation: every bad value is one SceneError line naming the key, the
value and what is allowed (issue #34)."""
from __future__ import annotations

import pytest

from tengfield.errors import SceneError
from tengfield.scene import default_scene
from tengfield.uncertainty_study import uncertainty_spec

RESTITUTION = {"contact.restitution": {"distribution": "uniform", "low": 0.05, "high": 0.5}}


def spec_of(**section):
    section.setdefault("vary", RESTITUTION)
    return uncertainty_spec(default_scene().with_values(uncertainty=section))


def refused(**section) -> str:
    with pytest.raises(SceneError) as info:
        spec_of(**section)
    text = str(info.value)
    assert "\n" not in text
    return text


def test_a_valid_section_gives_its_inputs_and_evaluations():
    spec = spec_of(samples=32, method="sobol", seed=3, vary={
        **RESTITUTION,
        "device.surface_charge_uC_per_m2": {"distribution": "normal", "mean": -20.0, "std": 2.0},
        "circuit.parallel_capacitance_pF": {"distribution": "triangular", "low": 5.0,
                                            "mode": 10.0, "high": 20.0},
        "excitation.amplitude_mm": {"distribution": "lognormal", "median": 1.5, "factor": 1.1}})
    assert spec.keys[0] == "contact.restitution" and len(spec.inputs) == 4
    assert spec.evaluations == 32 * (4 + 2)
    assert spec_of(samples=20, method="monte-carlo").evaluations == 20


def test_the_scene_without_the_section_is_none_when_not_required():
    assert uncertainty_spec(default_scene(), required=False) is None
    with pytest.raises(SceneError, match="no \\[uncertainty\\] section"):
        uncertainty_spec(default_scene())


def test_unknown_keys_get_did_you_mean():
    assert "did you mean 'samples'" in refused(sample=32)
    assert "did you mean 'contact.restitution'" in refused(vary={
        "contact.restitutio": RESTITUTION["contact.restitution"]})
    assert "unknown section [contac]" in refused(vary={
        "contac.restitution": RESTITUTION["contact.restitution"]})
    assert "did you mean 'high'" in refused(vary={
        "contact.restitution": {"distribution": "uniform", "low": 0.1, "hihg": 0.5}})
    assert "did you mean 'normal'" in refused(vary={
        "contact.restitution": {"distribution": "norma", "mean": 0.3, "std": 0.1}})
    assert "did you mean 'sobol'" in refused(method="sobl")


def test_a_range_outside_the_keys_own_range_is_refused():
    text = refused(vary={"contact.restitution": {"distribution": "uniform", "low": 0.5,
                                                 "high": 1.2}})
    assert "[contact] restitution is allowed [0, 1]" in text and "1.2" in text
    # a normal's tails: mean 0.9, std 0.1 reaches above 1
    assert "allowed [0, 1]" in refused(vary={"contact.restitution": {
        "distribution": "normal", "mean": 0.9, "std": 0.1}})
    assert "allowed (0, inf)" in refused(vary={"contact.restitution": {
        "distribution": "lognormal", "median": -0.3, "factor": 1.5}})


def test_non_numeric_keys_and_bad_parameters_are_refused():
    assert "text key" in refused(vary={"circuit.kind": {"distribution": "uniform", "low": 0,
                                                         "high": 1}})
    assert "whole-number key" in refused(vary={"device.cells": {"distribution": "uniform",
                                                                 "low": 1, "high": 4}})
    assert "must be below high" in refused(vary={"contact.restitution": {
        "distribution": "uniform", "low": 0.5, "high": 0.1}})
    assert "missing std" in refused(vary={"contact.restitution": {"distribution": "normal",
                                                                    "mean": 0.3}})


def test_too_few_samples_for_the_inputs_are_refused():
    assert "power of two >= 16" in refused(samples=8)
    assert "power of two" in refused(samples=48)
    many = {f"contact.{k}": {"distribution": "uniform", "low": 0.1, "high": 0.2}
            for k in ("restitution", "friction_static", "friction_dynamic", "exponent")}
    many["contact.exponent"] = {"distribution": "uniform", "low": 1.1, "high": 1.5}
    many["contact.restitution_exponent"] = {"distribution": "uniform", "low": 0.1, "high": 0.2}
    assert ">= 20" in refused(samples=16, vary=many)       # 4 x 5 inputs
    assert ">= 20" in refused(samples=10, method="monte-carlo")


def test_a_value_that_breaks_a_rule_between_keys_is_named():
    # a ball wider than the bore: each end of the distribution is built as a scene
    text = refused(vary={"device.ball_diameter_mm": {"distribution": "uniform", "low": 5.0,
                                                      "high": 9.0}})
    assert "device.ball_diameter_mm" in text and "9" in text


def test_arrays_and_the_3d_model_are_refused_by_name():
    section = {"samples": 32, "vary": RESTITUTION}
    with pytest.raises(SceneError, match="\\[array\\] cells = 4"):
        uncertainty_spec(default_scene().with_values(uncertainty=section, array={"cells": 4}))
    with pytest.raises(SceneError, match="model = '3d'"):
        uncertainty_spec(default_scene().with_values(uncertainty=section,
                                                     contact={"model": "3d"}))
