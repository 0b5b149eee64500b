"""The Sobol bootstrap's memory does not grow with N x resamples (issue #43.3): N = 32768
drew an (N x 1000) index array and its gathers (262 MB each) and ended in a numpy
allocation traceback at larger N; the spec allows N = 262144."""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from tengfield.uncertainty_study.sampling import input_values, unit_samples
from tengfield.uncertainty_study.spec import Distribution, UncertaintySpec
from tengfield.uncertainty_study.statistics import (BOOTSTRAP_RESAMPLES, bootstrap_bytes,
                                              sobol_indices)


def _spec(d, samples, seed=5):
    return UncertaintySpec(samples=samples, method="sobol", seed=seed, inputs=tuple(
        Distribution(f"test.x{j + 1}", "uniform", {"low": 0.0, "high": 1.0}) for j in range(d)))


@pytest.mark.slow
def test_the_bootstrap_of_a_large_study_stays_within_its_stated_bound():
    n = 32768
    spec = _spec(1, n)
    rng = np.random.default_rng(0)
    y = rng.normal(size=n * 3)            # any output: the memory is what is measured
    y[1::3] += 3.0 * np.arange(n) / n
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        sobol_indices(spec.keys, y, seed=1)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    whole = n * BOOTSTRAP_RESAMPLES * 8          # one (N x resamples) array: 262 MB
    assert bootstrap_bytes(n) < whole / 4
    assert peak <= 1.5 * bootstrap_bytes(n) + 20 * y.nbytes, (peak, bootstrap_bytes(n))


def test_indices_match_salib_and_the_intervals_its_bootstrap():
    """The point estimates are SALib's (same estimators); the bootstrap's half-widths
    agree with SALib's to sampling error (another stream of resamples)."""
    import warnings

    from SALib.analyze import sobol

    spec = _spec(2, 1024, seed=3)
    x = input_values(spec, unit_samples(spec))
    y = 3.0 * x[:, 0] + x[:, 1] ** 2 + x[:, 0] * x[:, 1]
    ours = sobol_indices(spec.keys, y, seed=3)
    problem = {"num_vars": 2, "names": spec.keys, "bounds": [[0.0, 1.0]] * 2}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = sobol.analyze(problem, y, calc_second_order=False, num_resamples=1000,
                            print_to_console=False, seed=3)
    for j, key in enumerate(spec.keys):
        assert ours[key]["S1"] == pytest.approx(ref["S1"][j], rel=1e-9, abs=1e-12)
        assert ours[key]["ST"] == pytest.approx(ref["ST"][j], rel=1e-9, abs=1e-12)
        assert ours[key]["S1_conf"] == pytest.approx(ref["S1_conf"][j], rel=0.15)
        assert ours[key]["ST_conf"] == pytest.approx(ref["ST_conf"][j], rel=0.15)
    assert sobol_indices(spec.keys, y, seed=3) == ours      # the seed fixes the intervals


def test_the_resamples_follow_the_stated_rule():
    from tengfield.uncertainty_study.statistics import bootstrap_resamples

    assert bootstrap_resamples(16) == bootstrap_resamples(32768) == 1000
    assert bootstrap_resamples(65536) == 512
    assert bootstrap_resamples(262144) == 128
    assert bootstrap_resamples(10**7) == 100
    assert bootstrap_bytes(262144) <= bootstrap_bytes(1024) * 2    # blocks, not N x R
