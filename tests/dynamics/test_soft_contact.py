"""Soft contact (Eq. 1 with c from Eq. 3) converges to the impact map as k grows."""
import math

import numpy as np
import pytest

from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.soft import damping_ratio, integrate_soft
from tengfield.dynamics.table import sine_table


def test_damping_ratio_eq3_limits():
    assert damping_ratio(1.0) == 0.0
    assert damping_ratio(0.0) == 1.0
    # free linear oscillator with this damping rebounds with exactly e
    for e in (0.2, 0.6, 0.9):
        z = damping_ratio(e)
        assert math.exp(-z * math.pi / math.sqrt(1 - z * z)) == pytest.approx(e, rel=1e-12)


@pytest.mark.slow
def test_soft_contact_converges_to_impact_map():
    f, amplitude, e, stroke, mass = 20.0, 1.5e-3, 0.6, 3e-3, 3.95e-4
    table = sine_table(amplitude, 2 * math.pi * f, 0.0)
    t_end = 0.12
    ref, imp, _ = integrate(table, stroke, Restitution(e), t_start=0.0, t_end=t_end,
                            period=1 / f)
    t = np.linspace(0.05, t_end, 400)
    z_ref, _, _ = ref(t)
    stiffness = np.array([1e4, 1e5, 1e6])
    errors = []
    for k in stiffness:
        soft, contacts, _ = integrate_soft(table, stroke, e, mass, k, t_start=0.0, t_end=t_end,
                                           period=1 / f, rtol=1e-9)
        z, _, _ = soft(t)
        errors.append(np.max(np.abs(z - z_ref)))
    errors = np.array(errors)
    rate = -np.polyfit(np.log(stiffness), np.log(errors), 1)[0]
    print(f"soft -> impact: max |z_soft - z_impact| = {errors} m at k = {stiffness} N/m; "
          f"observed rate k^-{rate:.3f} (expected 1/2: error ~ contact time ~ k^-1/2)")
    assert np.all(np.diff(errors) < 0)
    assert 0.35 < rate < 0.8
    assert errors[-1] < 1e-4
