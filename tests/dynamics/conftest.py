import math

import pytest

from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.table import sine_table
from tengfield.scene import default_scene


def run_sine(amplitude, frequency, *, restitution=0.6, stroke=3e-3, phase=0.0, t_start=0.0,
             periods=20.0, gap0=0.0, velocity0=0.0):
    """Impact map for a sine table; returns (trajectory, impacts (t, plate, vb, va), n)."""
    table = sine_table(amplitude, 2 * math.pi * frequency, phase)
    period = 1.0 / frequency
    return integrate(table, stroke, Restitution(restitution), t_start=t_start,
                     t_end=t_start + periods * period, gap0=gap0, velocity0=velocity0,
                     period=period)


@pytest.fixture
def small_scene():
    """The default device with a short run (fast CLI tests)."""
    return default_scene().with_values(run={"duration_s": 0.25, "settle_periods": 2,
                                            "sample_rate_hz": 2000.0})
