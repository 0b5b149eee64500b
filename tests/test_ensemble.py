"""Ensemble statistics: coverage of the 95 % interval, 1/sqrt(N) shrinkage, seeds."""
import math

import numpy as np
import pytest

from tengfield.ensemble import realisation_seeds, statistics


def test_known_sample():
    s = statistics([1.0, 2.0, 3.0, 4.0])
    assert s["mean"] == 2.5 and s["std"] == pytest.approx(math.sqrt(5 / 3))
    # t_{0.975, 3} = 3.182446305284263
    assert s["ci95_half_width"] == pytest.approx(3.182446305284263 * math.sqrt(5 / 3) / 2)


def test_one_value_has_no_spread_and_nan_is_counted():
    s = statistics([2.0, float("nan")])
    assert s["n"] == 1 and s["missing"] == 1 and s["mean"] == 2.0
    assert s["std"] is None and s["ci95_low"] is None


def test_interval_covers_the_mean_95_percent_of_the_time():
    rng = np.random.default_rng(0)
    hits = 0
    trials = 2000
    for _ in range(trials):
        s = statistics(rng.normal(3.0, 2.0, 10))
        hits += s["ci95_low"] <= 3.0 <= s["ci95_high"]
    # binomial sd of the coverage: sqrt(0.95 0.05 / 2000) = 0.0049
    assert abs(hits / trials - 0.95) < 0.02


def test_half_width_shrinks_as_one_over_sqrt_n():
    rng = np.random.default_rng(1)
    ns = np.array([8, 32, 128, 512])
    widths = [np.mean([statistics(rng.normal(0, 1, n))["ci95_half_width"] for _ in range(200)])
              for n in ns]
    slope = np.polyfit(np.log(ns), np.log(widths), 1)[0]
    assert slope == pytest.approx(-0.5, abs=0.05)


def test_seeds_are_a_prefix_and_distinct():
    assert realisation_seeds(5, 3) == realisation_seeds(5, 10)[:3] == [5, 6, 7]
    seeds = realisation_seeds(5, 1000)
    assert len(set(seeds)) == 1000
    assert realisation_seeds(6, 3) != realisation_seeds(5, 3)
