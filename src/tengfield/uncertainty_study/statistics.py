"""Statistics of a study (pure functions): each output's mean, standard deviation and
percentiles; Sobol indices S1 and ST with their bootstrap 95 % confidence (SALib's
Saltelli/Jansen estimators, a bootstrap streamed in blocks); the fraction of
evaluations per regime with its Clopper-Pearson interval
(:func:`tengfield.ensemble.fraction_statistics`); a percentile score for a robust design.
"""
from __future__ import annotations

import math
import re

import numpy as np

#: the percentiles reported per output
PERCENTILES = (5, 25, 50, 75, 95)
#: bootstrap resamples of the Sobol confidence intervals (up to N = 32768 base samples;
#: beyond, :func:`bootstrap_resamples`)
BOOTSTRAP_RESAMPLES = 1000
#: the bootstrap's work bound: resamples x N <= this (N = 32768 keeps all 1000); a
#: larger N takes fewer resamples, never fewer than MIN_BOOTSTRAP_RESAMPLES
BOOTSTRAP_WORK = 1 << 25
MIN_BOOTSTRAP_RESAMPLES = 100
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


#: indices drawn per block of the bootstrap (resamples x N): the resamples are streamed
#: in blocks of max(1, BOOTSTRAP_BLOCK_ELEMENTS // N) so that the bootstrap holds a few
#: arrays of this many numbers (~8 MB each) at any N, where drawing all N x 1000 at once
#: needs 8 kB x N per array (N = 32768: 262 MB each, N = 262144: 2 GB; issue #43.3)
BOOTSTRAP_BLOCK_ELEMENTS = 1 << 20
#: arrays of BOOTSTRAP_BLOCK_ELEMENTS numbers alive at once in a block (indices, A, B,
#: AB_j and the products): the bootstrap's peak memory is this x 8 bytes x the block
BOOTSTRAP_BLOCK_ARRAYS = 6


def bootstrap_resamples(samples: int) -> int:
    """Resamples of the bootstrap at ``samples`` (N) base samples: 1000 while N x 1000
    <= :data:`BOOTSTRAP_WORK` (N <= 32768), else max(100, BOOTSTRAP_WORK // N) (N =
    262144: 128). Its intervals' own relative error is about 1 / sqrt(2 x resamples):
    2 % at 1000, 6 % at 128; the intervals themselves narrow as 1 / sqrt(N)."""
    n = max(int(samples), 1)
    if n * BOOTSTRAP_RESAMPLES <= BOOTSTRAP_WORK:
        return BOOTSTRAP_RESAMPLES
    return max(MIN_BOOTSTRAP_RESAMPLES, BOOTSTRAP_WORK // n)


def bootstrap_bytes(samples: int) -> int:
    """Peak bytes of :func:`sobol_indices`' bootstrap for ``samples`` (N) base samples."""
    block = max(1, BOOTSTRAP_BLOCK_ELEMENTS // max(samples, 1)) * samples
    return BOOTSTRAP_BLOCK_ARRAYS * 8 * block


def sobol_indices(keys: list[str], values, seed: int = 0) -> dict:
    """First-order and total Sobol indices of one output from its values at SALib's
    Saltelli points (:func:`tengfield.uncertainty_study.sampling.unit_samples`, method
    "sobol", in that order): ``{key: {"S1", "S1_conf", "ST", "ST_conf"}}``, the
    ``_conf`` values the half-widths of the bootstrap 95 % intervals. Raises
    ValueError for an output with missing values or no variance (no index exists).

    The estimators are SALib's (:func:`SALib.analyze.sobol.analyze` with
    ``calc_second_order=False``: S1 Saltelli 2010, ST Jansen, both over the variance of
    A and B after the output is standardised); the bootstrap draws its
    :func:`bootstrap_resamples` resamples (1000 up to N = 32768) of the N rows from
    ``numpy.random.default_rng(seed)`` in blocks (:data:`BOOTSTRAP_BLOCK_ELEMENTS`), so
    its memory does not grow with N x resamples (:func:`bootstrap_bytes`) and its work
    stays below about 2^25 x D gathers per output."""
    from scipy.stats import norm

    y = np.asarray([np.nan if v is None else v for v in values], dtype=float)
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{int(np.count_nonzero(~np.isfinite(y)))} evaluations have no value")
    if float(np.var(y)) == 0.0 or np.ptp(y) <= 1e-12 * max(np.max(np.abs(y)), 1e-300):
        raise ValueError("the output does not vary")
    d = len(keys)
    step = d + 2
    if y.size % step:
        raise ValueError(f"{y.size} values are not N (D + 2) = N x {step} Saltelli points")
    n = y.size // step
    y = (y - y.mean()) / y.std()
    a_rows, b_rows = y[0::step], y[step - 1::step]
    ab_rows = [y[j + 1::step] for j in range(d)]
    var = float(np.var(np.concatenate([a_rows, b_rows])))
    s1 = [float(np.mean(b_rows * (ab - a_rows)) / var) for ab in ab_rows]
    st = [float(0.5 * np.mean((a_rows - ab) ** 2) / var) for ab in ab_rows]
    rng = np.random.default_rng(seed)
    per_block = max(1, BOOTSTRAP_BLOCK_ELEMENTS // n)
    resamples = bootstrap_resamples(n)
    s1_boot = np.empty((resamples, d))
    st_boot = np.empty((resamples, d))
    for start in range(0, resamples, per_block):
        count = min(per_block, resamples - start)
        rows = rng.integers(n, size=(count, n))       # one resample of the N rows per line
        a, b = a_rows[rows], b_rows[rows]
        mean = (a.sum(axis=1) + b.sum(axis=1)) / (2 * n)
        v = (np.einsum("ij,ij->i", a, a) + np.einsum("ij,ij->i", b, b)) / (2 * n) - mean ** 2
        v = np.where(v > 0.0, v, np.nan)              # a resample of equal values: no index
        for j, ab_all in enumerate(ab_rows):
            ab = ab_all[rows]
            s1_boot[start:start + count, j] = np.mean(b * (ab - a), axis=1) / v
            st_boot[start:start + count, j] = 0.5 * np.mean((a - ab) ** 2, axis=1) / v
        del rows, a, b
    z = float(norm.ppf(0.5 + CONFIDENCE / 2))

    def half_width(column):
        column = column[np.isfinite(column)]
        return float(z * column.std(ddof=1)) if column.size > 1 else 0.0

    return {k: {"S1": s1[j], "S1_conf": half_width(s1_boot[:, j]),
                "ST": st[j], "ST_conf": half_width(st_boot[:, j])}
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
