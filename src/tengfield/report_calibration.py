"""Recommendations measured by ``tengfield report`` on the embedded default scene.

Used by :func:`tengfield.report.recommended_field_settings` when no report
of one's own is passed. Each entry was *verified*: the adaptive surrogate
built with these ``[field]`` keys and the dynamics sampled at
``sample_rate_hz`` reached ``measured_error`` (largest relative error of the
peak-to-peak V_OC, Q_SC, I_SC) against the full report's reference
(65 positions at degree 2 / 0.25 mm, impact instants included).

Measured by the full report of 2026-11-22 04:01 (idle machine, 116 s), after
the contact rule snapped near-1 exponents to 1 (PTFE) and with the peaks taken
as `tengfield run` reports them (samples and impact instants). Regenerate by copying ``DIR/report.json →
recommendations`` (target, field, sample_rate_hz, measured_error, positions)
of a full ``tengfield report -o DIR`` here.
"""
from __future__ import annotations

DEFAULT_RECOMMENDATIONS = [
    {"target": 0.01,
     "field": {"method": "axisymmetric", "degree": 2, "mesh_size_mm": 1.0, "far_field": "kelvin",
               "domain_radius_mm": 20.0, "tolerance": 0.00333},
     "sample_rate_hz": 5000.0, "measured_error": 0.00192, "positions": 17},
    {"target": 0.001,
     "field": {"method": "axisymmetric", "degree": 2, "mesh_size_mm": 0.5, "far_field": "kelvin",
               "domain_radius_mm": 20.0, "tolerance": 2.24e-05},
     "sample_rate_hz": 5000.0, "measured_error": 0.000228, "positions": 65},
]
