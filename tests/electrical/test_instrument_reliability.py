"""Issue 54, the instrument (items 3, 5, 6, 8): the first-order front end exact at every
bandwidth, an input resistance down to the smallest the scene allows read as its limit,
the impact extremes kept for a quantity the reader leaves unchanged, and the peaks of a
scene whose instrument has not read yet (sweep, report). The field is the analytic plate
model; the CLI cases run the base scene of the issue."""
from __future__ import annotations

import math
import warnings

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import tengfield as tf
from tengfield import electrical
from tengfield.electrical.instrument import FirstOrder, time_constant
from tengfield.surrogate import TerminalCurves

import plate_model as fx

RUN = {"duration_s": 0.4, "settle_periods": 3, "sample_rate_hz": 5000.0}
BASE = ("[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 5000\n"
        "[field]\ndegree = 1\nmesh_size_mm = 1.5\ntolerance = 1e-2\n")


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


# ---------------------------------------------------------------------------
# item 5: the first-order filter at small (and large) bandwidths
def _exact_first_order(t, x, tau):
    """τ y' = x - y for x linear between the samples, from rest (y = x[0]), in 60 digits."""
    mpmath.mp.dps = 60
    tau = mpmath.mpf(tau)
    y = mpmath.mpf(x[0])
    out = [float(y)]
    for k in range(1, len(t)):
        h = mpmath.mpf(t[k]) - mpmath.mpf(t[k - 1])
        x0, x1 = mpmath.mpf(x[k - 1]), mpmath.mpf(x[k])
        s = (x1 - x0) / h
        y = x1 - s * tau + (y - x0 + s * tau) * mpmath.exp(-h / tau)
        out.append(float(y))
    return np.array(out)


@settings(max_examples=60, deadline=None)
@given(log_bandwidth=st.floats(-12.0, 9.0), steps=st.integers(2, 40),
       seed=st.integers(0, 2**31 - 1))
def test_the_first_order_filter_is_its_closed_form_at_any_bandwidth(log_bandwidth, steps,
                                                                    seed):
    """1e-12 ... 1e9 Hz: the filtered samples of a piecewise-linear input agree with the
    exact solution to a few ulp of the input (they lost 1e-4 of it at 1e-9 Hz)."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-5, 1e-3, steps))
    x = rng.normal(0.0, 1.0, steps)
    tau = time_constant(10.0 ** log_bandwidth)
    y = FirstOrder(tau)(t, x)
    exact = _exact_first_order(t, x, tau)
    # rounding: a few ulp of the largest term of a step (y itself, or the input times
    # the step's weight h / τ, below 1)
    bound = 1e-13 * (np.max(np.abs(exact)) + np.max(np.abs(x)) * min(1.0, np.max(np.diff(t)) / tau))
    assert np.max(np.abs(y - exact)) <= bound


def test_a_slow_front_end_reads_the_integral_of_a_sine():
    """f_c = 1e-9 Hz reading a 20 Hz unit sine from rest: y ≈ ∫ x dt / τ, at most
    2 / (ω τ) = 1.0e-10 ... the issue's 3.4e-4 V against an exact 7.6e-10 V at a 1 V scale."""
    t = np.linspace(0.0, 0.3, 1501)
    w = 2 * math.pi * 20.0
    for f_c in (1e-9, 1e-6):
        tau = time_constant(f_c)
        y = FirstOrder(tau)(t, np.sin(w * t))
        exact = _exact_first_order(t, np.sin(w * t), tau)
        np.testing.assert_allclose(y, exact, rtol=1e-9, atol=1e-12 * np.max(np.abs(exact)))
        assert np.max(np.abs(y)) == pytest.approx(2.0 / (w * tau), rel=1e-2)
