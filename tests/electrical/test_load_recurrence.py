"""The load ODE's linear recurrence (:func:`tengfield.lumped.load_response`, issue #41):
a compiled kernel warmed by ``python -m tengfield._warmup`` (it was a Python loop, ~1 µs a
sample: 5 s of a 4.8e6-sample run), giving the documented scheme's numbers bit for bit."""
from __future__ import annotations

import numpy as np

from tengfield import _lumped_kernel, _warmup, lumped


def reference_deficit(t, q_sc, i_sc, c_total, load_ohm, initial_load_charge=0.0):
    """D_{k+1} = e^{-x} D_k + x [f_k ψ + f_{k+1} (φ1 - ψ)], step by step in Python (the
    scheme of load_response's docstring; φ1, ψ its own accurate forms)."""
    rate = 1.0 / (load_ohm * c_total)
    forcing = i_sc / rate
    x = 0.5 * (rate[:-1] + rate[1:]) * np.diff(t)
    phi1, psi = lumped._phi1(x), lumped._psi(x)
    deficit = [q_sc[0] - initial_load_charge]
    for k in range(x.size):
        source = x[k] * psi[k] * forcing[k] + x[k] * (phi1[k] - psi[k]) * forcing[k + 1]
        deficit.append(np.exp(-x[k]) * deficit[-1] + source)
    return np.array(deficit)


def test_the_recurrence_is_a_compiled_kernel_the_warm_up_compiles():
    from numba.core.registry import CPUDispatcher

    assert isinstance(_lumped_kernel.deficit_recurrence, CPUDispatcher)
    assert "tengfield._lumped_kernel" in _warmup.KERNEL_MODULES
    assert _lumped_kernel.deficit_recurrence in _warmup.kernels()


def test_load_response_is_the_scheme_bit_for_bit_across_impacts():
    """Random Q_SC, I_SC, C_T on a grid with repeated times (impacts: a zero-length step)
    and R C from far below to far above the step: the same numbers as the loop."""
    rng = np.random.default_rng(41)
    t = np.sort(rng.uniform(0.0, 0.05, 1000))
    t[400:403] = t[400]                                    # an impact, a repeated time
    q_sc = 1e-9 * np.sin(2 * np.pi * 20.0 * t) + 1e-11 * rng.standard_normal(t.size)
    i_sc = 2e-9 * np.pi * 20.0 * np.cos(2 * np.pi * 20.0 * t)
    i_sc[401:] *= -0.5                                     # the current jumps at the impact
    c_t = 4e-13 * (1.0 + 0.1 * rng.random(t.size))
    for load_ohm, c_p, q0 in ((1e3, 0.0, 0.0), (1e9, 5e-12, 2e-10), (1e15, 1e-10, -1e-10)):
        got = lumped.load_response(t, q_sc, i_sc, c_t, load_ohm, c_p, initial_load_charge=q0)
        deficit = reference_deficit(t, q_sc, i_sc, c_t + c_p, load_ohm, q0)
        np.testing.assert_array_equal(got.charge, q_sc - deficit)
        np.testing.assert_array_equal(got.voltage, deficit / (c_t + c_p))
