"""Event-driven impact map (rigid plates, Newton restitution): Python side.

The compiled kernel lives in :mod:`._kernel`; this module sizes its output
arrays, turns its status codes into :class:`DynamicsError` messages and
wraps the stored segments in a :class:`Trajectory` that evaluates the exact
motion at any time.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass

import numpy as np

from ..errors import DynamicsError
from ..scene import G
from . import _kernel as K
from .regime import classify
from .result import DynamicsResult, Impacts, run_span
from .table import PPOLY, TableMotion, table_from_scene

#: More events (impacts, lift-offs, releases) per excitation period than this
#: raise DynamicsError instead of running for ever.
MAX_EVENTS_PER_PERIOD = 20_000

PLATE_NAMES = np.array(["lower", "upper"])


@dataclass(frozen=True)
class Restitution:
    """Newton restitution: ``e`` or ``min(1, e (v / v_ref)^-exponent)``."""
    e: float
    power_law: bool = False
    reference_speed: float = 0.1   # [m/s]
    exponent: float = 0.0

    @classmethod
    def from_contact(cls, contact) -> "Restitution":
        return cls(contact.restitution, contact.restitution_model == "power-law",
                   contact.restitution_reference_speed, contact.restitution_exponent)


@dataclass(frozen=True)
class Trajectory:
    """Segments of the exact piecewise motion (see :mod:`._kernel`)."""
    table: TableMotion
    stroke: float
    g: float
    seg_t: np.ndarray
    seg_mode: np.ndarray
    seg_z: np.ndarray
    seg_v: np.ndarray
    seg_y: np.ndarray
    seg_yd: np.ndarray

    def __call__(self, times: np.ndarray):
        """(z, dz/dt, y) at ``times`` [s]."""
        tb = self.table
        return K.sample_segments(np.ascontiguousarray(times, dtype=float), self.seg_t.size,
                                 self.seg_t, self.seg_mode, self.seg_z, self.seg_v, self.seg_y,
                                 self.seg_yd, self.g, self.stroke, tb.kind, tb.params,
                                 tb.breaks, tb.coeffs)

    def gap_on_grid(self, start: float, step: float, count: int) -> np.ndarray:
        """z at ``start + i * step``, i < count, in one compiled pass (same values as
        ``self(times)[0]`` to a few ulp of the table motion)."""
        tb = self.table
        return K.gap_on_grid(float(start), float(step), int(count), self.seg_t.size, self.seg_t,
                             self.seg_mode, self.seg_z, self.seg_v, self.seg_y, self.seg_yd,
                             self.g, self.stroke, tb.kind, tb.params, tb.breaks, tb.coeffs)

    def upper_stuck_between(self, t_a: float, t_b: float) -> bool:
        """Was the ball pressed to the upper plate at some time in [t_a, t_b]?"""
        ends = np.append(self.seg_t[1:], np.inf)
        hit = (self.seg_mode == K.STUCK_UPPER) & (ends > t_a) & (self.seg_t < t_b)
        return bool(np.any(hit))


def integrate(table: TableMotion, stroke: float, restitution: Restitution, *, t_start: float,
              t_end: float, gap0: float = 0.0, velocity0: float = 0.0, period: float,
              g: float = G, max_events_per_period: int = MAX_EVENTS_PER_PERIOD):
    """Run the impact map on [t_start, t_end].

    Returns ``(trajectory, impacts_arrays, n_events)`` where impacts_arrays is
    ``(time, plate 0/1, speed_before, speed_after)``. Raises DynamicsError if
    the event bound is exceeded.
    """
    if t_end < t_start:
        raise DynamicsError(f"end time {t_end:g} s is before the start time {t_start:g} s")
    if table.kind == PPOLY and (t_start < table.t_first or t_end > table.t_last):
        raise DynamicsError(
            f"the run [{t_start:g}, {t_end:g}] s is outside the recorded excitation "
            f"[{table.t_first:g}, {table.t_last:g}] s: shorten [run] duration_s or move "
            "[initial] time_s")
    n_periods = (t_end - t_start) / period
    capacity = int(min(16 * n_periods + 64, 5e7))
    while True:
        seg = [np.empty(capacity) for _ in range(6)]
        seg[1] = np.empty(capacity, dtype=np.int64)
        imp = [np.empty(capacity), np.empty(capacity, dtype=np.int64), np.empty(capacity),
               np.empty(capacity)]
        status, n_seg, n_imp, t_reached = K.run_impact_map(
            table.kind, table.params, table.breaks, table.coeffs, g, stroke, t_start, t_end,
            gap0, velocity0, restitution.e, restitution.power_law, restitution.reference_speed,
            restitution.exponent, period, max_events_per_period, table.acc_bound,
            table.jerk_bound, table.snap_bound, *seg, *imp)
        if status != K.CAPACITY:
            break
        capacity *= 4
    if status == K.EVENT_BOUND:
        raise DynamicsError(
            f"more than {max_events_per_period} events per excitation period near "
            f"t = {t_reached:.9g} s (unresolved chatter or grazing); the run was stopped. "
            "Check [contact] restitution (power-law restitution with a tiny exponent behaves "
            "like e -> 1 at low speed) and [excitation]")
    if status == K.STEP_BOUND:
        raise DynamicsError(f"the contact search did not converge near t = {t_reached:.9g} s")
    traj = Trajectory(table, stroke, g, *(a[:n_seg].copy() for a in seg))
    impacts = tuple(a[:n_imp].copy() for a in imp)
    return traj, impacts, n_seg + n_imp


def simulate_impact(scene, *, duration: float | None = None) -> DynamicsResult:
    """Impact-map trajectory of ``scene`` (see :func:`tengfield.dynamics.simulate`)."""
    wall0 = _time.perf_counter()
    table = table_from_scene(scene)
    period = scene.excitation.period
    duration, t0, t_end = run_span(scene, duration)
    stroke = scene.device.stroke
    traj, (it, ip, ivb, iva), n_events = integrate(
        table, stroke, Restitution.from_contact(scene.contact), t_start=t0, t_end=t_end,
        gap0=scene.initial.gap, velocity0=scene.initial.velocity, period=period)
    window_start = min(t0 + scene.run.settle_periods * period, t_end)
    regime = classify(traj, it, ip, ivb, window_start=window_start, t_end=t_end, period=period,
                      stroke=stroke, g=G,
                      upper_stuck=traj.upper_stuck_between(window_start, t_end))
    n_samples = int(math.floor(duration * scene.run.sample_rate + 1e-9)) + 1
    t = t0 + np.arange(n_samples) / scene.run.sample_rate
    z, v, y = traj(t)
    impacts = Impacts(it, PLATE_NAMES[ip] if ip.size else np.zeros(0, dtype="<U5"), ivb, iva)
    return DynamicsResult(status=0, message="ok", t=t, gap=z, gap_velocity=v, table=y,
                          impacts=impacts, regime=regime, n_events=n_events,
                          wall_time=_time.perf_counter() - wall0, model="impact",
                          stroke=stroke, period=period, window_start=window_start,
                          _sampler=traj)
