"""Checks shared by the stability suite (imported by the test modules; no tests here).

Every case of the suite asserts the same things about a run: it ends within a
bounded number of events, every number is finite, the gap stays in
[0, Δh] (impact model), and the physical invariants of the case hold.
"""
from __future__ import annotations

import math

import numpy as np

from tengfield.scene import G, default_scene


def scene_with(**sections):
    """The default scene with file-level overrides, validated like a scene file."""
    return default_scene().with_values(**sections)


def amplitude_mm_for(gamma: float, frequency_hz: float) -> float:
    """Table amplitude [mm] of a sine with intensity Γ = A ω² / g at ``frequency_hz``."""
    return 1e3 * gamma * G / (2.0 * math.pi * frequency_hz) ** 2


def assert_finite(*arrays) -> None:
    for a in arrays:
        a = np.asarray(a, dtype=float)
        assert np.all(np.isfinite(a)), f"{np.count_nonzero(~np.isfinite(a))} NaN/inf values"


def assert_sane_dynamics(res, *, max_events: int, penetration: float = 0.0) -> None:
    """Bounded events, finite numbers, ``-penetration <= gap <= Δh + penetration``,
    impacts in time order with non-negative speeds."""
    assert 0 < res.n_events <= max_events, f"{res.n_events} events (bound {max_events})"
    assert_finite(res.t, res.gap, res.gap_velocity, res.table, res.impacts.time,
                  res.impacts.speed_before)
    exit_speeds = res.impacts.speed_after
    if res.model == "soft" and len(exit_speeds) and res.gap[-1] <= 0.0:
        # the soft model's contact still open at the end has no exit speed yet (NaN)
        exit_speeds = exit_speeds[:-1]
    assert_finite(exit_speeds)
    assert res.gap.min() >= -penetration, res.gap.min()
    assert res.gap.max() <= res.stroke + penetration, res.gap.max() - res.stroke
    assert np.all(np.diff(res.impacts.time) >= 0.0)
    assert np.all(res.impacts.speed_before >= 0.0) and np.all(exit_speeds >= 0.0)


def still_table_energy(gap, gap_velocity) -> np.ndarray:
    """Mechanical energy per unit mass [J/kg] on a still table: g z + v²/2."""
    return G * np.asarray(gap) + 0.5 * np.asarray(gap_velocity) ** 2


def fitted_slope(x, y) -> float:
    """Slope of log y against log x (least squares, np.polyfit)."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])
