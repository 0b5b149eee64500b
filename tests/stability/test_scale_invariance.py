"""Scale invariance of the impact map at extreme frequencies (0.1 Hz, 2 kHz).

The motion depends only on Γ, e and Δh ω²/g: a run at any frequency with
the gap scaled by 1/f² is the same dimensionless problem as the run at
20 Hz, so its impacts (phase ωt, plate, speed ω v / g) must agree to
round-off. A solver tolerance in absolute units (metres, seconds) breaks
this at the micro-scale of a 2 kHz drive.
"""
import math

import numpy as np
import pytest

from tengfield.dynamics.impact import Restitution, integrate
from tengfield.dynamics.table import sine_table
from tengfield.scene import G


def dimensionless_run(frequency, gamma, stroke_ref=3e-3, f_ref=20.0, periods=10,
                      restitution=0.5):
    """Run at ``frequency`` in dimensionless form: (phases ωt of impacts, plates, speeds
    ω v / g, heights ω² h / g (at most) of the flights ending in them, gap / Δh on a
    common phase grid).

    The motion depends only on Γ, e and Δh ω²/g: the gap is scaled with 1/f²
    so that every frequency solves the same dimensionless problem.
    """
    omega = 2 * math.pi * frequency
    stroke = stroke_ref * (f_ref / frequency) ** 2
    table = sine_table(gamma * G / omega**2, omega, 0.0)
    trajectory, (t, plate, vb, va), n = integrate(
        table, stroke, Restitution(restitution), t_start=0.0, t_end=periods / frequency,
        period=1.0 / frequency)
    assert n <= periods * 20_000
    phases = np.linspace(0.0, 2 * math.pi * periods, 200001)
    gap = trajectory(phases / omega)[0] / stroke
    # height of the flight ending in the impact, against the largest pressing
    # acceleration (1 + Γ) g
    height = vb**2 / (2 * (1 + gamma) * G) * omega**2 / G
    return omega * t, plate, omega * vb / G, height, gap


@pytest.mark.parametrize("frequency", [0.1, 2000.0])
@pytest.mark.parametrize("gamma", [1.5, 4.0, 1e3])
def test_extreme_frequencies_solve_the_same_dimensionless_problem(frequency, gamma):
    """Impacts ending a flight higher than 1e-4 of the length scale g/ω² agree to 1e-8
    in phase; the gap agrees to 1e-5 Δh everywhere (the kernel merges rebounds lower than
    REST_HEIGHT = 1 pm into sticking, an absolute length: at 2 kHz, where g/ω² = 62 nm,
    that ends a chatter sequence a few sub-picometre hops earlier)."""
    ref = dimensionless_run(20.0, gamma)
    got = dimensionless_run(frequency, gamma)
    assert np.max(np.abs(got[4] - ref[4])) < 1e-5

    def significant(run):
        keep = run[3] > 1e-4
        return run[0][keep][:30], run[1][keep][:30], run[2][keep][:30]
    ref_phase, ref_plate, ref_speed = significant(ref)
    phase, plate, speed = significant(got)
    assert ref_phase.size >= 5
    assert np.array_equal(plate, ref_plate)
    assert phase == pytest.approx(ref_phase, rel=1e-8)
    assert speed == pytest.approx(ref_speed, rel=1e-6)
