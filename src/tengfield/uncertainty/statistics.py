"""Statistics of a study (pure functions): each output's mean, standard deviation and
percentiles; Sobol indices S1 and ST with their bootstrap 95 % confidence (SALib's
Saltelli/Jansen estimators, :func:`SALib.analyze.sobol.analyze`); the fraction of
evaluations per regime with its Clopper-Pearson interval
(:func:`tengfield.ensemble.fraction_statistics`); a percentile score for a robust design.
"""
from __future__ import annotations

import math
import re
import warnings

import numpy as np

#: the percentiles reported per output
PERCENTILES = (5, 25, 50, 75, 95)
#: bootstrap resamples of the Sobol confidence intervals
BOOTSTRAP_RESAMPLES = 1000
CONFIDENCE = 0.95


def distribution_statistics(values) -> dict:
    """``{"n", "missing", "mean", "std", "percentiles": {"5": ..}}`` of ``values`` (NaN or
    None left out and counted; std with ddof = 1; percentiles by numpy's linear rule)."""
    x = np.asarray([np.nan if v is None else v for v in values], dtype=float)
    finite = x[np.isfinite(x)]
    out = {"n": int(finite.size), "missing": int(x.size - finite.size), "mean": None,
           "std": None, "percentiles": {}}
    if finite.size == 0:
        return out
    out["mean"] = float(finite.mean())
    out["std"] = float(finite.std(ddof=1)) if finite.size > 1 else None
    out["percentiles"] = {str(p): float(v) for p, v in
                          zip(PERCENTILES, np.percentile(finite, PERCENTILES))}
    return out


def sobol_indices(keys: list[str], values, seed: int = 0) -> dict:
    """First-order and total Sobol indices of one output from its values at SALib's
    Saltelli points (:func:`tengfield.uncertainty.sampling.unit_samples`, method
    "sobol", in that order): ``{key: {"S1", "S1_conf", "ST", "ST_conf"}}``, the
    ``_conf`` values the half-widths of the bootstrap 95 % intervals. Raises
    ValueError for an output with missing values or no variance (no index exists)."""
    from SALib.analyze import sobol

    y = np.asarray([np.nan if v is None else v for v in values], dtype=float)
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{int(np.count_nonzero(~np.isfinite(y)))} evaluations have no value")
    if float(np.var(y)) == 0.0 or np.ptp(y) <= 1e-12 * max(np.max(np.abs(y)), 1e-300):
        raise ValueError("the output does not vary")
    problem = {"num_vars": len(keys), "names": list(keys), "bounds": [[0.0, 1.0]] * len(keys)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # pandas' FutureWarning inside SALib
        result = sobol.analyze(problem, y, calc_second_order=False,
                               num_resamples=BOOTSTRAP_RESAMPLES, conf_level=CONFIDENCE,
                               print_to_console=False, seed=seed)
    return {k: {"S1": float(result["S1"][j]), "S1_conf": float(result["S1_conf"][j]),
                "ST": float(result["ST"][j]), "ST_conf": float(result["ST_conf"][j])}
            for j, k in enumerate(keys)}


def regime_fractions(regimes: list[str]) -> dict:
    """``{regime: {"fraction", "ci95_low", "ci95_high", "count"}}`` over the evaluations
    (exact binomial, Clopper-Pearson)."""
    from ..ensemble import fraction_statistics

    out = {}
    for label in sorted(set(regimes)):
        stats = fraction_statistics([1.0 if r == label else 0.0 for r in regimes])
        out[label or "none"] = {"fraction": stats["mean"], "ci95_low": stats["ci95_low"],
                                "ci95_high": stats["ci95_high"],
                                "count": int(sum(r == label for r in regimes))}
    return out


def dominant_input(sobol: dict | None) -> tuple[str, float] | None:
    """The input with the largest total index ST (and its ST), or None."""
    if not sobol:
        return None
    key = max(sobol, key=lambda k: (sobol[k]["ST"] if sobol[k]["ST"] == sobol[k]["ST"]
                                    else -math.inf))
    return key, sobol[key]["ST"]


_AGGREGATE = re.compile(r"^p(\d{1,2}(?:\.\d+)?)$")


def parse_percentile(aggregate: str) -> float | None:
    """``"p10"`` -> 10.0 (a percentile aggregate over ``[uncertainty.vary]``), None for
    any other text (e.g. design's own ``"min"`` / ``"mean"``); a percentile outside
    (0, 100) raises ValueError."""
    match = _AGGREGATE.match(str(aggregate))
    if not match:
        return None
    p = float(match.group(1))
    if not 0.0 < p < 100.0:
        raise ValueError(f"aggregate = {aggregate!r}: the percentile must lie in (0, 100)")
    return p


def percentile_score(values, percentile: float) -> float:
    """The ``percentile``-th percentile of one candidate's objective over the study's
    evaluations (numpy's linear rule; NaN left out; NaN if none is left). With
    ``"p10"`` a design maximising the objective picks the candidate whose worse-case
    decile is best."""
    x = np.asarray([np.nan if v is None else v for v in values], dtype=float)
    x = x[np.isfinite(x)]
    return float(np.percentile(x, percentile)) if x.size else math.nan


def percentile_interval(values, percentile: float, confidence: float = CONFIDENCE) -> tuple:
    """``(low, high)``: the distribution-free ``confidence`` interval of the
    ``percentile``-th percentile of the values' distribution, between two order
    statistics (binomial ranks; NaN left out; NaN, NaN when fewer than 2 values). For
    quasi-random points it is conservative (their percentiles converge faster)."""
    from scipy import stats

    x = np.sort(np.asarray([np.nan if v is None else v for v in values], dtype=float))
    x = x[np.isfinite(x)]
    n = x.size
    if n < 2:
        return math.nan, math.nan
    q = percentile / 100.0
    tail = 0.5 * (1.0 - confidence)
    lo = int(stats.binom.ppf(tail, n, q)) - 1          # 0-based rank of the lower bound
    hi = int(stats.binom.ppf(1.0 - tail, n, q))        # 0-based rank of the upper bound
    return float(x[min(max(lo, 0), n - 1)]), float(x[min(max(hi, 0), n - 1)])
