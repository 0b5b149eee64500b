"""Jump and contact onsets (the paper's Figs. 4c, 4f, 6d) by bisection on the excitation.

The *jump height* of an excitation is the largest gap z reached during the
first ``periods`` excitation periods of a ball starting at rest on the
lower plate at phase ``phase`` (transient included, as in the paper's
ADAMS runs, where the table starts at y = 0 moving up). It equals the
stroke once the upper plate is reached. An onset is the smallest amplitude
(at a fixed frequency) or frequency (at a fixed amplitude) whose jump
height reaches ``height``; it is found by bisection, which assumes the jump
height grows with the excitation near the onset (true for the first
flight, whose height grows with the launch speed of Eq. 10).
"""
from __future__ import annotations

import math

import numpy as np

from ..scene.constants import G
from .impact import Restitution, integrate
from .table import sine_table

SAMPLES_PER_PERIOD = 400


def jump_height(amplitude: float, frequency: float, restitution: Restitution, stroke: float,
                *, periods: int = 30, phase: float = 0.0, g: float = G) -> float:
    """Max gap [m] over the first ``periods`` periods from rest (amplitude [m], frequency [Hz])."""
    table = sine_table(amplitude, 2.0 * math.pi * frequency, phase)
    t_end = periods / frequency
    traj, impacts, _ = integrate(table, stroke, restitution, t_start=0.0, t_end=t_end,
                                 period=1.0 / frequency, g=g)
    if np.any(impacts[1] == 1):
        return stroke
    t = np.linspace(0.0, t_end, SAMPLES_PER_PERIOD * periods + 1)
    return float(np.max(traj(t)[0]))


def _bisect(predicate, lo: float, hi: float, rel_tol: float) -> float:
    """Smallest x in [lo, hi] with predicate(x) (predicate(hi) must hold), to rel_tol."""
    if not predicate(hi):
        return math.nan
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        if predicate(mid):
            hi = mid
        else:
            lo = mid
    return hi


def onset_amplitude(frequency: float, height: float, restitution: Restitution, stroke: float,
                    *, periods: int = 30, max_amplitude: float = 0.05,
                    rel_tol: float = 1e-4) -> float:
    """Smallest amplitude [m] at ``frequency`` [Hz] with jump height >= ``height`` [m]."""
    lift_off = G / (2.0 * math.pi * frequency) ** 2      # Gamma = 1: nothing below this
    return _bisect(lambda a: jump_height(a, frequency, restitution, stroke,
                                         periods=periods) >= height,
                   lift_off, max(max_amplitude, 2 * lift_off), rel_tol)


def onset_frequency(amplitude: float, height: float, restitution: Restitution, stroke: float,
                    *, periods: int = 30, max_frequency: float = 200.0,
                    rel_tol: float = 1e-4) -> float:
    """Smallest frequency [Hz] at ``amplitude`` [m] with jump height >= ``height`` [m]."""
    lift_off = math.sqrt(G / amplitude) / (2.0 * math.pi)
    return _bisect(lambda f: jump_height(amplitude, f, restitution, stroke,
                                         periods=periods) >= height,
                   lift_off, max(max_frequency, 2 * lift_off), rel_tol)
