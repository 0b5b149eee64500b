"""Recommendations measured by ``tengfield report`` on the embedded default scene.

Used by :func:`tengfield.report.recommended_field_settings` when no report
of one's own is passed. Regenerate with ``tengfield report -o DIR`` and copy
``DIR/report.json → recommendations`` (target, field, sample_rate_hz,
measured_error) here; docs/report.md shows the run these come from.
"""
from __future__ import annotations

DEFAULT_RECOMMENDATIONS = [
    # provisional (fast-mode run); replaced by the full report's numbers
    {"target": 1e-2, "field": {"method": "axisymmetric", "degree": 1, "mesh_size_mm": 1.0,
                               "far_field": "kelvin", "domain_radius_mm": 20.0,
                               "tolerance": 0.00333},
     "sample_rate_hz": 5000.0, "measured_error": float("nan")},
    {"target": 1e-3, "field": {"method": "axisymmetric", "degree": 2, "mesh_size_mm": 1.0,
                               "far_field": "kelvin", "domain_radius_mm": 20.0,
                               "tolerance": 0.000333},
     "sample_rate_hz": 20000.0, "measured_error": float("nan")},
]
