"""Error against run time for every stage, and the cheapest settings for a target accuracy.

``tengfield report`` (docs/report.md). The measurement (pure: no files, no
plots) lives in :mod:`tengfield.accuracy_report.study` (:func:`build_report`, the
verification), :mod:`tengfield.accuracy_report.stages` (each stage's rows),
:mod:`tengfield.accuracy_report.plan` (settings, plan, rows, error arithmetic) and
:mod:`tengfield.accuracy_report.recommend` (the recommendation logic); the files it
writes in :mod:`tengfield.accuracy_report.output`, the default recommendations in
``calibration.json`` (:func:`default_recommendations`). This package
re-exports the public names::

    from tengfield.accuracy_report import build_report, write_report, recommended_field_settings
"""
from __future__ import annotations

from ..plotting.report import plot_stage
from .output import markdown, scene_text, toml_value, write_report
from .plan import (BUDGET_SHARE, MIN_ADAPTIVE_POSITIONS, QUANTITIES, TARGETS, FieldSetting,
                   Plan, Row, cheapest, make_plan, max_relative_deviation, peak_errors,
                   relative_error, richardson, solves_needed)
from .recommend import (Recommendation, default_recommendations, recommend,
                        recommended_field_settings, recommended_sample_rate,
                        scene_with_recommended, surrogate_tolerance)
from .stages import circuit_rows, dynamics_rows, field_rows, surrogate_rows
from .study import Report, build_report, verify

__all__ = ["BUDGET_SHARE", "MIN_ADAPTIVE_POSITIONS", "QUANTITIES", "TARGETS", "FieldSetting",
           "Plan", "Recommendation", "Report", "Row", "build_report", "cheapest",
           "circuit_rows", "default_recommendations", "dynamics_rows", "field_rows",
           "make_plan", "markdown", "max_relative_deviation", "peak_errors", "plot_stage",
           "recommend", "recommended_field_settings", "recommended_sample_rate",
           "relative_error", "richardson", "scene_text", "scene_with_recommended",
           "solves_needed", "surrogate_rows", "surrogate_tolerance", "toml_value", "verify",
           "write_report"]
