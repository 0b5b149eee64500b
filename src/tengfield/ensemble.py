"""Ensemble statistics over independent realisations (pure functions).

For N realisations x_1..x_N of one output (a peak-to-peak value, a mean power,
a regime fraction): the sample mean, the sample standard deviation (ddof = 1)
and the two-sided 95 % confidence interval of the mean from Student's t with
N - 1 degrees of freedom, ``mean +- t_{0.975, N-1} s / sqrt(N)``. The
interval's half-width shrinks as 1/sqrt(N). With N = 1 the spread is unknown
and reported as None.
"""
from __future__ import annotations

import math

import numpy as np

CONFIDENCE = 0.95


def statistics(values) -> dict:
    """``{"n", "mean", "std", "ci95_low", "ci95_high", "ci95_half_width"}`` of ``values``
    (NaN entries are left out and counted in ``"missing"``)."""
    x = np.asarray(values, dtype=float).ravel()
    finite = x[np.isfinite(x)]
    n = int(finite.size)
    out = {"n": n, "missing": int(x.size - n), "mean": None, "std": None,
           "ci95_low": None, "ci95_high": None, "ci95_half_width": None}
    if n == 0:
        return out
    mean = float(finite.mean())
    out["mean"] = mean
    if n < 2:
        return out
    from scipy.stats import t as student_t
    std = float(finite.std(ddof=1))
    half = float(student_t.ppf(0.5 + CONFIDENCE / 2.0, n - 1)) * std / math.sqrt(n)
    out.update(std=std, ci95_low=mean - half, ci95_high=mean + half, ci95_half_width=half)
    return out


def realisation_seeds(seed: int, count: int) -> list[int]:
    """``count`` independent 32-bit seeds derived from ``seed`` (numpy's SeedSequence:
    realisation k's seed does not depend on ``count``, so N realisations are the
    first N of any larger ensemble)."""
    children = np.random.SeedSequence(int(seed)).spawn(int(count))
    return [int(c.generate_state(1, dtype=np.uint32)[0]) for c in children]
