"""fit with a real-vibration excitation (issue #25): the forward model re-runs the scene's
own realisation (harmonics + noise, seed), so σ and C_p come back from a trace made with
them, as for a sine."""
from __future__ import annotations

import pytest

from tengfield.fit import fit_trace, parse_fit_section, reference_surrogate

import plate_model as fx
from fit_synthetic import TRUE, synthetic

ENGINE = {"kind": "harmonics", "frequency_hz": [20.0, 40.0], "amplitude_mm": [1.5, 0.1],
          "phase_deg": [0.0, 30.0], "band_hz": [10.0, 200.0],
          "rms_acceleration_m_per_s2": 5.0, "seed": 4}


def test_fit_recovers_sigma_and_parallel_capacitance_under_harmonics_and_noise(
        surrogate_cache):
    scene = fx.scene_with(excitation=ENGINE, circuit={"parallel_capacitance_pF": 100.0},
                          run={"duration_s": 5.0})
    curves, sigma_ref, _ = reference_surrogate(scene, cache_dir=surrogate_cache,
                                               solve=fx.plate_model_solve)
    trace, _ = synthetic(scene, (curves, sigma_ref), seed=0, shift=0.0, start=3.0)
    free = {"surface_charge_uC_per_m2": {"start": -10.0},
            "parallel_capacitance_pF": {"start": 300.0, "max": 1000.0}}
    spec = parse_fit_section(scene.with_values(fit={"parameters": free}))
    result = fit_trace(scene, curves, sigma_ref, trace, spec)
    for name in free:
        z = (result.values[name] - TRUE[name]) / result.standard_errors[name]
        assert abs(z) < 3.5, (name, result.values, result.standard_errors)
    assert all(result.identifiable.values()), result.notes
