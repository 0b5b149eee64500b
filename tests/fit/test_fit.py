"""Calibration on synthetic traces made by the tool (plate-model surrogate, real impact map)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tengfield.fit import fit_trace, parse_fit_section
from tengfield.fit._model import ForwardModel
from tengfield.fit._problem import _Problem, _Space

from fit_synthetic import SHIFT, TRUE, synthetic

FREE = {"surface_charge_uC_per_m2": {"start": -10.0},
        "parallel_capacitance_pF": {"start": 300.0, "max": 1000.0},
        "restitution": {"start": 0.2, "max": 0.5},
        "time_shift_s": {}}


def _errors_in_se(result, period):
    """(fitted - true) / standard error; the time shift modulo the period (steady state)."""
    z = {}
    for name, true in {**TRUE, "time_shift_s": SHIFT}.items():
        err = result.values[name] - true
        if name == "time_shift_s":
            err = (err + 0.5 * period) % period - 0.5 * period
        z[name] = err / result.standard_errors[name]
    return z


def _fit(scene, surrogate, trace, free=FREE, **fit_keys):
    spec = parse_fit_section(scene.with_values(fit={"parameters": free, **fit_keys}))
    return fit_trace(scene, surrogate[0], surrogate[1], trace, spec)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_recovers_known_parameters_within_standard_errors(plate_scene, plate_surrogate, seed):
    """V and Q traces with white noise, 50 Hz hum and an unknown shift: σ, C_p, e and the
    shift come back within 3.5 stated standard errors, each identifiable."""
    trace, _ = synthetic(plate_scene, plate_surrogate, seed)
    result = _fit(plate_scene, plate_surrogate, trace)
    z = _errors_in_se(result, plate_scene.excitation.period)
    assert all(abs(v) < 3.5 for v in z.values()), (z, result.values, result.standard_errors)
    assert all(result.identifiable.values()), result.notes
    assert result.chi2_reduced == pytest.approx(1.0, rel=0.05)   # noise estimated per column
    # the standard errors are small: the parameters are well determined
    assert result.standard_errors["surface_charge_uC_per_m2"] < 0.02 * 30.0


@pytest.mark.slow
def test_standard_errors_cover_the_truth_over_many_seeds(plate_scene, plate_surrogate):
    """Over 20 seeds (80 estimates), |error| < 2 SE for about 95 % of them (>= 85 %
    required). Binomial tolerance: with honest SEs (95.45 % inside), fewer than 68 of 80
    inside has probability 6e-5 (1.2 % even if a seed's four estimates were one draw);
    SEs 1.5x too small (82 % inside) pass with probability 0.28 (0.17 over 40 seeds)."""
    inside, total = 0, 0
    for seed in range(100, 120):
        trace, _ = synthetic(plate_scene, plate_surrogate, seed)
        z = _errors_in_se(_fit(plate_scene, plate_surrogate, trace),
                          plate_scene.excitation.period)
        inside += sum(abs(v) < 2.0 for v in z.values())
        total += len(z)
    assert inside / total >= 0.85, inside / total


@pytest.mark.slow
def test_voltage_alone_flags_sigma_and_parallel_capacitance(plate_scene, plate_surrogate):
    """With C_p >> C_T a voltage trace fixes only σ/(C_T + C_p): the pair is flagged, the
    voltage is still fitted, and the profile of C_p is flat towards its upper bound."""
    scene = plate_scene.with_values(circuit={"parallel_capacitance_pF": 338.0})
    true = {**TRUE, "parallel_capacitance_pF": 338.0}
    trace, clean = synthetic(scene, plate_surrogate, 5, ("V",), true=true, hum=0.0)
    result = _fit(scene, plate_surrogate, trace, profile=True)
    assert not result.identifiable["surface_charge_uC_per_m2"]
    assert not result.identifiable["parallel_capacitance_pF"]
    assert result.identifiable["restitution"] and result.identifiable["time_shift_s"]
    assert any("not separately identifiable" in n and "charge-mode" in n for n in result.notes)
    assert abs(result.correlation[0, 1]) > 0.995
    misfit = np.sqrt(np.mean((result.fitted["V"] - clean["V"]) ** 2))
    assert misfit < 0.003 * np.ptp(clean["V"])      # noise 1 % of pp per sample
    profile = result.profiles["parallel_capacitance_pF"]
    assert "upper" in profile["flat_towards"], profile   # nothing bounds C_p from above
    # adding the charge-mode trace separates them
    both, _ = synthetic(scene, plate_surrogate, 5, ("V", "Q"), true=true, hum=0.0)
    separated = _fit(scene, plate_surrogate, both)
    assert all(separated.identifiable.values()), separated.notes
    assert separated.values["parallel_capacitance_pF"] == pytest.approx(338.0, rel=0.02)


def test_trace_shorter_than_a_period_at_any_rate(plate_scene, plate_surrogate):
    """0.8 of a period sampled at an odd 3.3 kHz, starting at t = -1.234 s: σ and the shift."""
    trace, _ = synthetic(plate_scene, plate_surrogate, 7, ("Q",), duration=0.04, rate=3300.0,
                         start=-1.234, hum=0.0)
    free = {"surface_charge_uC_per_m2": {}, "time_shift_s": {}}
    result = _fit(plate_scene, plate_surrogate, trace, free)
    z = (result.values["surface_charge_uC_per_m2"] + 30.0) / \
        result.standard_errors["surface_charge_uC_per_m2"]
    assert abs(z) < 3.5
    period = plate_scene.excitation.period
    err = (result.values["time_shift_s"] - SHIFT + 0.5 * period) % period - 0.5 * period
    assert abs(err) < 3.5 * result.standard_errors["time_shift_s"]


def test_robust_loss_resists_outliers(plate_scene, plate_surrogate):
    """2 % of the Q samples replaced by spikes of 3x the peak-to-peak: soft_l1 keeps σ within
    3 % while the plain least squares is pulled further away."""
    trace, clean = synthetic(plate_scene, plate_surrogate, 3, ("Q",), hum=0.0)
    rng = np.random.default_rng(3)
    spikes = rng.choice(trace.time.size, trace.time.size // 50, replace=False)
    trace.values["Q"][spikes] += 3.0 * np.ptp(clean["Q"])
    free = {"surface_charge_uC_per_m2": {}, "time_shift_s": {}}
    robust = _fit(plate_scene, plate_surrogate, trace, free, loss="soft_l1", loss_scale=2.0)
    plain = _fit(plate_scene, plate_surrogate, trace, free)
    err_robust = abs(robust.values["surface_charge_uC_per_m2"] + 30.0)
    err_plain = abs(plain.values["surface_charge_uC_per_m2"] + 30.0)
    assert err_robust < 0.03 * 30.0
    assert err_robust < err_plain


def test_model_is_linear_in_sigma_and_its_jacobian_column_exact(plate_scene, plate_surrogate):
    """V, Q, I scale with σ (one surrogate serves every σ); the exact σ column of the Jacobian
    matches central differences."""
    curves, sigma_ref = plate_surrogate
    model = ForwardModel(plate_scene, curves, sigma_ref, span=0.2)
    t = model.window_start + np.linspace(0.0, 0.1, 500)
    a = model.waveforms({**TRUE}, t)
    b = model.waveforms({**TRUE, "surface_charge_uC_per_m2": -75.0}, t)
    for q in "VQI":
        np.testing.assert_allclose(b[q], 2.5 * a[q], rtol=1e-12, atol=1e-30)
    trace, _ = synthetic(plate_scene, plate_surrogate, 0, ("V", "I"), hum=0.0)
    spec = parse_fit_section(plate_scene.with_values(fit={"parameters": FREE}))
    space = _Space(spec.parameters)

    def residual(values):
        w = model.waveforms(values, model.model_times(trace.time, SHIFT), ("V", "I"))
        return np.concatenate([w[q] - trace.values[q] for q in ("V", "I")])
    problem = _Problem(model, space, residual)
    u = space.to_u([-25.0, 120.0, 0.1, SHIFT])
    J = problem.jacobian(u)
    h = 1e-3
    fd = (problem(u + [h, 0, 0, 0]) - problem(u - [h, 0, 0, 0])) / (2 * h)
    np.testing.assert_allclose(J[:, 0], fd, rtol=1e-6, atol=1e-9 * np.abs(fd).max())


def test_load_resistance_from_the_load_voltage(plate_scene, plate_surrogate):
    """[circuit] kind = "load": V is the load voltage; R (fitted in decades) and σ come back
    from V_load + Q_SC."""
    scene = plate_scene.with_values(circuit={"kind": "load", "load_ohm": 3e8,
                                             "parallel_capacitance_pF": 0.0})
    true = {"surface_charge_uC_per_m2": -30.0, "load_ohm": 3e8}
    trace, _ = synthetic(scene, plate_surrogate, 11, ("V", "Q"), true=true, hum=0.0,
                         duration=0.3)
    free = {"surface_charge_uC_per_m2": {}, "load_ohm": {"start": 1e9, "min": 1e6, "max": 1e11},
            "time_shift_s": {}}
    result = _fit(scene, plate_surrogate, trace, free)
    for name, value in true.items():
        assert abs(result.values[name] - value) < 3.5 * result.standard_errors[name], \
            (name, result.values, result.standard_errors)
    assert math.isfinite(result.standard_errors["load_ohm"])


def test_given_noise_levels_are_used_and_checked(plate_scene, plate_surrogate):
    """White noise of a stated level: reduced χ² ≈ 1 and the SEs use that level; stating a
    noise 10x too small is caught by χ² (and the SEs are scaled up by sqrt(χ²))."""
    trace, clean = synthetic(plate_scene, plate_surrogate, 9, ("Q",), hum=0.0, white=0.02)
    level = 0.02 * float(np.ptp(clean["Q"]))
    free = {"surface_charge_uC_per_m2": {}, "time_shift_s": {}}
    trace.columns[0].noise = level
    honest = _fit(plate_scene, plate_surrogate, trace, free)
    assert honest.noise["Q"]["how"].startswith("given")
    assert honest.chi2_reduced == pytest.approx(1.0, abs=0.1)
    trace.columns[0].noise = level / 10.0
    understated = _fit(plate_scene, plate_surrogate, trace, free)
    assert understated.chi2_reduced == pytest.approx(100.0, rel=0.1)
    assert any("not consistent" in n for n in understated.notes)
    se = "surface_charge_uC_per_m2"
    assert understated.standard_errors[se] == pytest.approx(honest.standard_errors[se], rel=0.1)


def test_excitation_amplitude_scale(plate_scene, plate_surrogate):
    """The table amplitude is 8 % larger than the scene says: the amplitude scale, σ and the
    shift come back from a Q + I trace (the dynamics re-run, the surrogate reused)."""
    true = {"surface_charge_uC_per_m2": -30.0, "amplitude_scale": 1.08}
    trace, _ = synthetic(plate_scene, plate_surrogate, 13, ("Q", "I"), true=true, hum=0.0)
    free = {"surface_charge_uC_per_m2": {}, "amplitude_scale": {"min": 0.8, "max": 1.3},
            "time_shift_s": {}}
    result = _fit(plate_scene, plate_surrogate, trace, free)
    for name, value in true.items():
        assert abs(result.values[name] - value) < 3.5 * result.standard_errors[name], \
            (name, result.values, result.standard_errors)
    assert result.dynamics_runs > 1


def test_bootstrap_spread_agrees_with_the_jacobian_errors(plate_scene, plate_surrogate):
    """White noise: the block bootstrap's standard deviation of σ and of the shift is the
    Jacobian standard error within a factor 1.6 (30 replicas: ~13 % sampling scatter)."""
    trace, _ = synthetic(plate_scene, plate_surrogate, 17, ("Q",), hum=0.0)
    free = {"surface_charge_uC_per_m2": {}, "time_shift_s": {}}
    result = _fit(plate_scene, plate_surrogate, trace, free, bootstrap=30)
    assert result.bootstrap["replicas"] == 30
    for name in free:
        ratio = result.bootstrap[name]["standard_deviation"] / result.standard_errors[name]
        assert 1 / 1.6 < ratio < 1.6, (name, ratio)
