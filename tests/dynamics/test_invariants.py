"""Property-based invariants of the impact map over random scenes."""
import math

import numpy as np
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from .conftest import run_sine


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(amplitude_mm=st.floats(0.0, 6.0), frequency=st.floats(3.0, 90.0),
       restitution=st.floats(0.0, 1.0), stroke_mm=st.floats(0.5, 8.0),
       phase=st.floats(0.0, 2 * math.pi), start=st.floats(0.0, 1.0),
       velocity0=st.floats(-1.0, 1.0))
# cases hypothesis once found: a vanishing rebound, and a vanishing launch speed
@example(amplitude_mm=0.0, frequency=3.0, restitution=1.3e-68, stroke_mm=1.0, phase=0.0,
         start=0.0, velocity0=1.0)
@example(amplitude_mm=1.0, frequency=20.5, restitution=0.0, stroke_mm=1.0, phase=0.0,
         start=0.0, velocity0=1.2e-89)
def test_gap_bounded_finite_and_events_ordered(amplitude_mm, frequency, restitution, stroke_mm,
                                               phase, start, velocity0):
    stroke = stroke_mm * 1e-3
    traj, imp, _ = run_sine(amplitude_mm * 1e-3, frequency, restitution=restitution,
                            stroke=stroke, phase=phase, gap0=start * stroke,
                            velocity0=velocity0, periods=15)
    t = np.linspace(0.0, 15.0 / frequency, 3001)
    z, v, y = traj(t)
    assert np.all(np.isfinite(z)) and np.all(np.isfinite(v)) and np.all(np.isfinite(y))
    assert np.all(z >= 0.0) and np.all(z <= stroke)
    assert np.all(np.diff(traj.seg_t) >= 0.0)
    assert np.all(np.diff(imp[0]) > 0.0)                 # impacts strictly ordered
    assert np.all(imp[2] >= 0) and np.all(imp[3] <= imp[2] * (1 + 1e-12))
    # stored segment starts lie on or between the plates
    assert np.all((traj.seg_z >= 0.0) & (traj.seg_z <= stroke))
