"""``tengfield uncertainty``: predictions with bands, and which input matters (issue #34).

``[uncertainty]`` (samples, method "sobol" or "monte-carlo", seed) and
``[uncertainty.vary]`` ("section.key" -> distribution) are validated by :mod:`.spec`
(:func:`uncertainty_spec`, also what ``tengfield scene`` calls); :mod:`.sampling`
draws the points (SALib's Saltelli scheme, scipy's scrambled Sobol sequence);
:mod:`.evaluation` runs them as cheaply as the physics allows (σ and circuit keys: the
electrical stage only; excitation and contact keys: the dynamics; geometry keys: one
field solve per distinct geometry, cached); :mod:`.statistics` summarises them (SALib's
Sobol indices with bootstrap intervals, percentiles, Clopper-Pearson regime fractions);
:mod:`.study` ties them together; :mod:`.output` writes uncertainty.csv/json/png.
"""
from .evaluation import output_quantities
from .spec import UncertaintySpec, uncertainty_spec
from .statistics import parse_percentile, percentile_score
from .study import Study, candidate_percentile, candidate_percentiles, run_study

__all__ = ["UncertaintySpec", "uncertainty_spec", "run_study", "Study", "output_quantities",
           "candidate_percentile", "candidate_percentiles", "parse_percentile", "percentile_score"]
