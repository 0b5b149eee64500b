"""The sampling and estimator of a study on functions with known answers (issue #34)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tengfield.uncertainty_study.sampling import input_values, unit_samples
from tengfield.uncertainty_study.spec import Distribution, UncertaintySpec
from tengfield.uncertainty_study.statistics import (distribution_statistics, parse_percentile,
                                              percentile_score, regime_fractions,
                                              sobol_indices)

#: Ishigami a = 7, b = 0.1 (Saltelli et al., Global Sensitivity Analysis, 2008)
ISHIGAMI_S1 = (0.3139, 0.4424, 0.0)
ISHIGAMI_ST = (0.5576, 0.4424, 0.2437)


def ishigami(x, a=7.0, b=0.1):
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def uniform_spec(d, samples, seed=0, low=-math.pi, high=math.pi, method="sobol"):
    return UncertaintySpec(samples=samples, method=method, seed=seed, inputs=tuple(
        Distribution(f"test.x{j + 1}", "uniform", {"low": low, "high": high}) for j in range(d)))


@pytest.mark.slow
def test_ishigami_indices_lie_in_the_reported_intervals():
    spec = uniform_spec(3, 1024, seed=7)
    x = input_values(spec, unit_samples(spec))
    assert x.shape == (1024 * 5, 3)
    assert x.min() >= -math.pi and x.max() <= math.pi
    result = sobol_indices(spec.keys, ishigami(x), seed=7)
    for j, key in enumerate(spec.keys):
        r = result[key]
        assert abs(r["S1"] - ISHIGAMI_S1[j]) <= r["S1_conf"], (key, r)
        assert abs(r["ST"] - ISHIGAMI_ST[j]) <= r["ST_conf"], (key, r)
        assert r["S1_conf"] < 0.1 and r["ST_conf"] < 0.1


def test_an_additive_function_has_first_order_equal_total_and_sum_one():
    spec = uniform_spec(2, 512, seed=1, low=0.0, high=1.0)
    x = input_values(spec, unit_samples(spec))
    result = sobol_indices(spec.keys, 3.0 * x[:, 0] + x[:, 1])   # variances 9 : 1
    assert result["test.x1"]["S1"] == pytest.approx(0.9, abs=result["test.x1"]["S1_conf"])
    assert result["test.x2"]["ST"] == pytest.approx(0.1, abs=result["test.x2"]["ST_conf"])


def test_distributions_map_the_unit_cube_to_their_quantiles():
    spec = UncertaintySpec(4096, "monte-carlo", 3, inputs=(
        Distribution("a.n", "normal", {"mean": -20.0, "std": 2.0}),
        Distribution("a.l", "lognormal", {"median": 2.0, "factor": 1.5}),
        Distribution("a.t", "triangular", {"low": 1.0, "mode": 2.0, "high": 4.0})))
    x = input_values(spec, unit_samples(spec))
    assert x.shape == (4096, 3)
    assert x[:, 0].mean() == pytest.approx(-20.0, abs=0.02)
    assert x[:, 0].std() == pytest.approx(2.0, rel=0.01)
    assert np.median(x[:, 1]) == pytest.approx(2.0, rel=0.01)
    assert np.std(np.log(x[:, 1])) == pytest.approx(math.log(1.5), rel=0.01)
    assert x[:, 2].mean() == pytest.approx((1.0 + 2.0 + 4.0) / 3.0, rel=0.01)
    again = input_values(spec, unit_samples(spec))
    assert np.array_equal(x, again)      # the seed fixes the points


def test_percentiles_regimes_and_the_design_score():
    stats = distribution_statistics([1.0, 2.0, None, 3.0, 4.0, 5.0])
    assert stats["missing"] == 1 and stats["mean"] == 3.0
    assert stats["percentiles"]["50"] == 3.0 and stats["percentiles"]["5"] == pytest.approx(1.2)
    fractions = regime_fractions(["bounce"] * 3 + ["chaos"])
    assert fractions["bounce"]["fraction"] == 0.75
    assert 0.0 < fractions["bounce"]["ci95_low"] < 0.75 < fractions["bounce"]["ci95_high"] < 1.0
    assert parse_percentile("p10") == 10.0 and parse_percentile("min") is None
    with pytest.raises(ValueError):
        parse_percentile("p0")
    assert percentile_score(list(range(101)), 10.0) == pytest.approx(10.0)


def test_an_output_that_does_not_vary_has_no_indices():
    with pytest.raises(ValueError, match="does not vary"):
        sobol_indices(["a", "b"], np.ones(64))


def test_percentile_interval_covers_the_true_percentile_95_percent_of_the_time():
    """The order-statistic interval of the 10th percentile (design's p10 error bar):
    over 2000 iid normal samples of 64 points, it holds the true 10th percentile in at
    least 95 % of them (binomial ranks: conservative), and narrows with more points."""
    from scipy import stats

    from tengfield.uncertainty_study.statistics import percentile_interval

    rng = np.random.default_rng(4)
    true = stats.norm.ppf(0.10)
    hits = 0
    for _ in range(2000):
        lo, hi = percentile_interval(rng.standard_normal(64), 10.0)
        hits += lo <= true <= hi
    assert 0.95 <= hits / 2000 <= 0.99
    wide = np.subtract(*percentile_interval(rng.standard_normal(64), 10.0)[::-1])
    narrow = np.subtract(*percentile_interval(rng.standard_normal(4096), 10.0)[::-1])
    assert 0 < narrow < wide / 4
    assert np.isnan(percentile_interval([1.0], 10.0)[0])
