"""Event-driven impact map (rigid plates, Newton restitution): Python side.

The compiled kernel lives in :mod:`._kernel`; this module sizes its output
arrays, turns its status codes into :class:`DynamicsError` messages and
wraps the stored segments in a :class:`Trajectory` that evaluates the exact
motion at any time.
"""
from __future__ import annotations

import time as _time
from dataclasses import dataclass

import numpy as np

from ..errors import DynamicsError
from ..scene.constants import G
from ..scene.limits import MAX_PERIODS  # MAX_PERIODS: the scene's limit, also for simulate(duration=)
from . import _kernel as K
from ._kernel import PPOLY
from .result import DynamicsResult
from .run import prepare_run, run_result
from .table import TableMotion

#: More events (impacts, lift-offs, releases) per excitation period than this
#: raise DynamicsError instead of running for ever.
MAX_EVENTS_PER_PERIOD = 20_000
#: More stored events (segments + impacts, 80 bytes each) than this raise
#: DynamicsError (about 1.6 GB of trajectory).
MAX_STORED_EVENTS = 20_000_000
#: A recorded table whose acceleration crosses -g more often than this in the
#: period before the event bound was hit is blamed on noise in the data.
NOISY_CROSSINGS = 20



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


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    return a is b or (a.shape == b.shape and bool(np.array_equal(a, b)))


class TrajectoryBundle:
    """Many :class:`Trajectory` objects sampled together: ``bundle(times)`` gives the
    (z, dz/dt) arrays of shape (times, trajectories) in one compiled call (the same values
    as calling each; an ``[array]`` of N cells is sampled chunk by chunk without N Python
    calls per chunk). The trajectories must share the stroke, g and the table kind (and,
    for a recorded table, its data); sine tables may differ in amplitude, frequency and
    phase."""

    def __init__(self, trajectories):
        trajectories = list(trajectories)
        if not trajectories:
            raise ValueError("TrajectoryBundle needs at least one trajectory")
        first = trajectories[0]
        for tr in trajectories[1:]:
            same = (tr.stroke == first.stroke and tr.g == first.g
                    and tr.table.kind == first.table.kind
                    and tr.table.params.shape == first.table.params.shape
                    and _same_array(tr.table.breaks, first.table.breaks)
                    and _same_array(tr.table.coeffs, first.table.coeffs))
            if not same:
                raise ValueError("TrajectoryBundle: the trajectories differ in stroke, g or "
                                 "table data")
        sizes = np.array([tr.seg_t.size for tr in trajectories], dtype=np.int64)
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        for name in ("seg_t", "seg_mode", "seg_z", "seg_v", "seg_y", "seg_yd"):
            setattr(self, name, np.concatenate([getattr(tr, name) for tr in trajectories]))
        self.pars = np.ascontiguousarray(np.stack([tr.table.params for tr in trajectories]))
        self.count = len(trajectories)
        self._first = first

    def __call__(self, times: np.ndarray):
        """(z, dz/dt) at the sorted ``times`` [s]: arrays (times, trajectories)."""
        times = np.ascontiguousarray(times, dtype=float)
        z = np.empty((self.count, times.size))     # filled row by row (one trajectory each)
        v = np.empty_like(z)
        tb = self._first.table
        K.sample_many(times, self.offsets, self.seg_t, self.seg_mode, self.seg_z, self.seg_v,
                      self.seg_y, self.seg_yd, self._first.g, self._first.stroke, tb.kind,
                      self.pars, tb.breaks, tb.coeffs, z, v)
        return z.T, v.T


def integrate(table: TableMotion, stroke: float, restitution: Restitution, *, t_start: float,
              t_end: float, gap0: float = 0.0, velocity0: float = 0.0, period: float,
              g: float = G, max_events_per_period: int = MAX_EVENTS_PER_PERIOD,
              time_origin: float = 0.0):
    """Run the impact map on [t_start, t_end] (times on the table's axis).

    Returns ``(trajectory, impacts_arrays, n_events)`` where impacts_arrays is
    ``(time, plate 0/1, speed_before, speed_after)``. Raises DynamicsError if
    the event bound is exceeded or the run would be too long (MAX_PERIODS,
    MAX_STORED_EVENTS). ``time_origin`` [s] is added to times in messages.
    """
    if t_end < t_start:
        raise DynamicsError(f"end time {t_end:g} s is before the start time {t_start:g} s")
    if table.kind == PPOLY and (t_start < table.t_first or t_end > table.t_last):
        raise DynamicsError(
            f"the run [{t_start + time_origin:.17g}, {t_end + time_origin:.17g}] s is outside "
            f"the recorded excitation [{table.t_first + time_origin:.17g}, "
            f"{table.t_last + time_origin:.17g}] s: shorten [run] duration_s or move "
            "[initial] time_s")
    n_periods = (t_end - t_start) / period
    if n_periods > MAX_PERIODS:
        raise DynamicsError(
            f"duration x frequency = {n_periods:.3g} excitation periods: allowed <= "
            f"{MAX_PERIODS:.0e} (shorten [run] duration_s or lower [excitation] frequency_hz)")
    capacity = int(min(16 * n_periods + 64, MAX_STORED_EVENTS))
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
        if capacity >= MAX_STORED_EVENTS:
            raise DynamicsError(
                f"more than {MAX_STORED_EVENTS:.0e} events (impacts, lift-offs) before "
                f"t = {t_reached + time_origin:.17g} s: allowed <= {MAX_STORED_EVENTS:.0e}; "
                "shorten [run] duration_s")
        capacity = min(4 * capacity, MAX_STORED_EVENTS)
    if status == K.EVENT_BOUND:
        near = f"t = {t_reached + time_origin:.17g} s"
        if table.kind == PPOLY:
            crossings = acceleration_crossings(table, max(t_reached - period, table.t_first),
                                               min(t_reached + period, table.t_last), g)
            cause = (f"the recorded acceleration crosses -g {crossings} times within one "
                     f"period of {near}: the record is noisy (rounding or measurement noise "
                     "makes the ball lift off and land again and again); low-pass it with "
                     "[excitation] smoothing_hz (e.g. 10 to 50 x frequency_hz)"
                     if crossings > NOISY_CROSSINGS else
                     "check [contact] restitution, and the record: noise in it shows up as "
                     "endless micro-bounces ([excitation] smoothing_hz low-passes it)")
        else:
            cause = ("check [contact] restitution (power-law restitution with a tiny exponent "
                     "behaves like e -> 1 at low speed) and [excitation]")
        raise DynamicsError(
            f"more than {max_events_per_period} events per excitation period near {near} "
            f"(unresolved chatter or grazing); the run was stopped: {cause}")
    if status == K.STEP_BOUND:
        raise DynamicsError(f"the contact search did not converge near "
                            f"t = {t_reached + time_origin:.17g} s")
    traj = Trajectory(table, stroke, g, *(_trimmed(a, n_seg) for a in seg))
    impacts = tuple(_trimmed(a, n_imp) for a in imp)
    return traj, impacts, n_seg + n_imp


def _trimmed(array: np.ndarray, count: int) -> np.ndarray:
    """The first ``count`` entries: a view when that is most of the array, else a copy."""
    return array[:count] if 2 * count >= array.size else array[:count].copy()


def acceleration_crossings(table: TableMotion, t_a: float, t_b: float, g: float = G,
                           limit: int = 10_000) -> int:
    """How often ``g + y''`` changes sign in [t_a, t_b] (lift-off / release instants)."""
    count = 0
    for falling in (True, False):
        t = t_a
        while count < limit:
            t = K.next_crossing(t, falling, g, table.kind, table.params, table.breaks,
                                table.coeffs, t_b)
            if not t < t_b:
                break
            count += 1
    return count


def simulate_impact(scene, *, duration: float | None = None) -> DynamicsResult:
    """Impact-map trajectory of ``scene`` (see :func:`tengfield.dynamics.simulate`)."""
    wall0 = _time.perf_counter()
    duration, t0, table = prepare_run(scene, duration)
    traj, contacts, n_events = integrate(
        table, scene.device.stroke, Restitution.from_contact(scene.contact), t_start=0.0,
        t_end=duration, gap0=scene.initial.gap, velocity0=scene.initial.velocity,
        period=scene.excitation.period, time_origin=t0)
    return run_result(scene, traj, contacts, n_events, model="impact", t0=t0,
                      duration=duration, wall0=wall0, upper_stuck=traj.upper_stuck_between,
                      gap_on_grid=traj.gap_on_grid)
