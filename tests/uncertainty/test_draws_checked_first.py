"""What a study draws is checked before the work, in the user's words (issue #43.11,
#43.12, #43.16): joint corners of the draws, clipping where the spec checks, renamed,
measured and list keys, a lognormal factor too large for the doubles; a mid-study error
names its draw."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from tengfield.errors import DynamicsError, SceneError
from tengfield.scene import default_scene, parse_scene
from tengfield.uncertainty_study import run_study, uncertainty_spec
from tengfield.uncertainty_study.sampling import input_values
from tengfield.uncertainty_study.spec import TAIL, Distribution, UncertaintySpec

UVLO = '[circuit]\nkind = "rectifier"\npmic = "uvlo"\n'


def study(vary: str, head: str = "", samples=32, method="monte-carlo") -> str:
    return (head + f'[uncertainty]\nsamples = {samples}\nmethod = "{method}"\n'
            '[uncertainty.vary]\n' + vary)


def test_a_corner_of_two_draws_that_breaks_a_rule_is_named_before_the_work():
    scene = parse_scene(study('"circuit.uvlo_rising_V" = { distribution = "uniform", low = 4.5, '
                              'high = 5.2 }\n"circuit.uvlo_falling_V" = { distribution = '
                              '"uniform", low = 3.8, high = 4.8 }\n', UVLO))
    with pytest.raises(SceneError) as err:
        uncertainty_spec(scene)
    text = str(err.value)
    assert "\n" not in text
    assert "[uncertainty.vary] 'circuit.uvlo_rising_V' = 4.5 with 'circuit.uvlo_falling_V' = " \
           "4.8 (a corner of their joint draws" in text
    assert "must exceed uvlo_falling_V" in text


def test_ball_and_bore_corners_are_checked_too():
    scene = parse_scene(study('"device.ball_diameter_mm" = { distribution = "uniform", low = 6.0,'
                              ' high = 7.9 }\n"device.tube_inner_radius_mm" = { distribution = '
                              '"uniform", low = 3.6, high = 4.5 }\n'))
    with pytest.raises(SceneError, match=r"'device.ball_diameter_mm' = 7.9 with "
                                         r"'device.tube_inner_radius_mm' = 3.6 \(a corner"):
        uncertainty_spec(scene)


@pytest.mark.slow
def test_a_mid_study_error_names_the_draw_and_the_study():
    from tengfield.dynamics import simulate

    scene = parse_scene(study('"contact.restitution" = { distribution = "uniform", low = 0.3, '
                              'high = 0.5 }\n', samples=20))

    def failing(s):
        if s.contact.restitution != scene.contact.restitution:
            raise DynamicsError("the kernel gave up")
        return simulate(s)

    with pytest.raises(DynamicsError) as err:
        run_study(scene, jobs=1, simulate=failing)
    text = str(err.value)
    assert text.startswith("uncertainty: evaluation 0 of the study ([uncertainty.vary] draws "
                           "'contact.restitution' = "), text
    assert text.endswith(": the kernel gave up")


@pytest.mark.parametrize("dist", [
    Distribution("circuit.parallel_capacitance_pF", "normal", {"mean": 60.0, "std": 12.0}),
    Distribution("contact.restitution", "lognormal", {"median": 0.2, "factor": 1.3})])
def test_draws_are_clipped_where_the_spec_checks_them(dist):
    spec = UncertaintySpec(16, "monte-carlo", 0, inputs=(dist,))
    low, high = dist.support()
    x = input_values(spec, np.array([[1e-9], [0.5], [1.0 - 1e-9]]))[:, 0]
    assert x[0] == pytest.approx(low, rel=1e-11) and x[2] == pytest.approx(high, rel=1e-11)
    assert x[0] > 0.0                                    # a capacitance the spec allowed


def test_the_old_stroke_name_is_read_with_its_warning():
    scene = parse_scene(study('"device.gap_mm" = { distribution = "uniform", low = 2.0, '
                              'high = 4.0 }\n'), source="gap.toml")
    with pytest.warns(FutureWarning, match=r"\[uncertainty.vary\] 'device.gap_mm' is now called "
                                           r"'device.stroke_mm'"):
        spec = uncertainty_spec(scene)
    assert spec.keys == ["device.stroke_mm"]
    both = parse_scene(study('"device.gap_mm" = { distribution = "uniform", low = 2.0, high = 4.0'
                             ' }\n"device.stroke_mm" = { distribution = "uniform", low = 2.0, '
                             'high = 4.0 }\n'), source="both.toml")
    with pytest.raises(SceneError, match="are the same key"), warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        uncertainty_spec(both)


def test_measured_reference_values_are_not_inputs():
    scene = parse_scene(study('"reference.V_pp_V" = { distribution = "uniform", low = 1.0, '
                              'high = 2.0 }\n'))
    with pytest.raises(SceneError, match=r"^\[uncertainty.vary\] 'reference.V_pp_V': \[reference\]"
                                         r" holds measured values .* not inputs"):
        uncertainty_spec(scene)


def test_a_list_key_of_harmonics_is_refused_by_name():
    head = ('[excitation]\nkind = "harmonics"\nfrequency_hz = [30.0, 60.0]\n'
            'amplitude_mm = [1.0, 0.5]\n')
    scene = parse_scene(study('"excitation.frequency_hz" = { distribution = "uniform", low = 20.0,'
                              ' high = 40.0 }\n', head))
    with pytest.raises(SceneError) as err:
        uncertainty_spec(scene)
    text = str(err.value)
    assert text.startswith("[uncertainty.vary] 'excitation.frequency_hz': with [excitation] kind "
                           "= 'harmonics' frequency_hz is a list"), text
    assert "entries but" not in text


def test_a_huge_lognormal_factor_is_refused_without_a_numpy_warning():
    scene = parse_scene(study('"contact.restitution" = { distribution = "lognormal", median = '
                              '0.2, factor = 1e300 }\n'))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SceneError, match=r"factor = 1e\+300 is out of range: .* allowed "
                                             r"\(1, "):
            uncertainty_spec(scene)


def test_a_field_solve_error_names_the_draw(tmp_path):
    import plate_model
    from tengfield.errors import FieldError

    scene = plate_model.scene_with(uncertainty={"samples": 20, "method": "monte-carlo", "vary": {
        "device.ball_diameter_mm": {"distribution": "uniform", "low": 6.0, "high": 6.5}}})

    def solve(s, position, **kwargs):
        if s.device.ball_diameter != scene.device.ball_diameter:
            raise FieldError("the solver ran out of memory")
        return plate_model.plate_model_solve(s, position, **kwargs)

    with pytest.raises(FieldError) as err:
        run_study(scene, jobs=1, cache_dir=tmp_path, solve=solve)
    text = str(err.value)
    assert text.startswith("uncertainty: the field solve of the study ([uncertainty.vary] draws "
                           "'device.ball_diameter_mm' = 6."), text
    assert text.endswith(": the solver ran out of memory")
