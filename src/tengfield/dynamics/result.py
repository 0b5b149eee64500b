"""Result objects of the dynamics (in the spirit of scipy's ``OdeResult``)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..scene.limits import MAX_SAMPLES  # the scene's limit, also for simulate(duration=)

#: plate index of a contact -> its name
PLATE_NAMES = np.array(["lower", "upper"])

REGIMES = ("rest", "bounce", "chaos", "critical-contact", "regular-contact")


@dataclass(frozen=True)
class Impacts:
    """Impacts in time order. Speeds are relative to the table [m/s], both >= 0.

    For the soft-contact model an "impact" is one contact episode: ``time`` is
    its entry, ``speed_before`` the entry speed, ``speed_after`` the exit speed.
    """
    time: np.ndarray           # [s]
    plate: np.ndarray          # 'lower' / 'upper'
    speed_before: np.ndarray   # [m/s]
    speed_after: np.ndarray    # [m/s]

    def __len__(self) -> int:
        return int(self.time.size)


@dataclass(frozen=True)
class Regime:
    """Motion regime of the steady window (definitions: docs/dynamics.md).

    ``period`` is in excitation periods (0 if aperiodic), contacts per period
    count impacts per excitation period at each plate, ``max_gap`` [m].
    """
    name: str
    period: int
    lower_contacts_per_period: float
    upper_contacts_per_period: float
    max_gap: float

    def as_dict(self) -> dict:
        return {"regime": self.name, "period": self.period,
                "lower_contacts_per_period": self.lower_contacts_per_period,
                "upper_contacts_per_period": self.upper_contacts_per_period,
                "max_gap_m": self.max_gap}


@dataclass
class DynamicsResult:
    """Trajectory of the ball relative to the table, SI units.

    ``gap`` = z, the gap between the ball's bottom and the lower plate
    (0 <= z <= Delta h for the impact model; the soft model may penetrate
    slightly), ``gap_velocity`` = dz/dt (positive up, relative to the
    table), ``table`` = y(t) the table displacement, all sampled at ``t``.
    A result exists only for a run that reached its end: failures raise
    :class:`tengfield.errors.DynamicsError` (there is no status code).

    Runs integrate on the elapsed time ``t - time_origin`` (``time_origin`` =
    ``[initial] time_s``), so their precision does not depend on the absolute
    time; ``elapsed`` holds the sample times on that axis (exact even where
    ``t`` = time_origin + elapsed is rounded, e.g. at t ~ 1e12 s).
    ``sample(times)`` evaluates the exact trajectory at absolute times,
    ``sample_elapsed(s)`` at elapsed times.
    """
    t: np.ndarray
    gap: np.ndarray
    gap_velocity: np.ndarray
    table: np.ndarray
    impacts: Impacts
    regime: Regime
    n_events: int
    wall_time: float
    model: str = "impact"
    stroke: float = 0.0                  # Delta h [m]
    period: float = 0.0                  # excitation period [s]
    window_start: float = 0.0            # start of the steady window [s] (absolute)
    time_origin: float = 0.0             # [s] start of the run, [initial] time_s
    elapsed: np.ndarray | None = None    # t - time_origin [s], exact
    _sampler: Callable | None = field(default=None, repr=False)

    def sample(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(gap [m], gap_velocity [m/s], table [m]) exactly at absolute ``times`` [s]."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        return self.sample_elapsed(t - self.time_origin)

    def sample_elapsed(self, elapsed) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(gap [m], gap_velocity [m/s], table [m]) at ``elapsed`` [s] after time_origin."""
        s = np.ascontiguousarray(np.atleast_1d(np.asarray(elapsed, dtype=float)))
        return self._sampler(s)

    def summary(self) -> dict:
        """JSON-ready summary (the CLI's summary.json)."""
        plates = self.impacts.plate
        return {
            "model": self.model,
            "regime": self.regime.name,
            "period": self.regime.period,
            "max_gap_mm": self.regime.max_gap * 1e3,
            "upper_contacts_per_period": self.regime.upper_contacts_per_period,
            "lower_contacts_per_period": self.regime.lower_contacts_per_period,
            "impacts": len(self.impacts),
            "impacts_lower": int(np.sum(plates == "lower")),
            "impacts_upper": int(np.sum(plates == "upper")),
            "events": self.n_events,
            "time_origin_s": self.time_origin,
            "steady_window_start_s": self.window_start,
            "duration_s": (float(self.elapsed[-1]) if self.elapsed is not None
                           and self.elapsed.size else 0.0),
            "wall_time_s": self.wall_time,
        }




def run_span(scene, duration: float | None) -> tuple[float, float, float]:
    """(duration, start, end) [s] of a run: ``duration`` None means ``[run] duration_s``;
    the run starts at ``[initial] time_s``."""
    import math

    from ..errors import DynamicsError
    from ..scene.limits import check_steady_window

    if duration is not None:
        duration = float(duration)
        if not (duration > 0 and math.isfinite(duration)):
            raise DynamicsError(f"duration = {duration!r} s: allowed (0, inf)")
        # the scene file's rule for [run] duration_s, for the duration asked for here
        check_steady_window(scene.excitation, scene.run.settle_periods, duration,
                            name="the duration asked for")
    else:
        duration = scene.run.duration
    t0 = scene.initial.time
    return duration, t0, t0 + duration


def _sample_count(scene, duration: float) -> int:
    import math
    return int(math.floor(duration * scene.run.sample_rate + 1e-9)) + 1


def check_samples(scene, duration: float) -> None:
    """Refuse a run whose samples would not fit (MAX_SAMPLES), before integrating."""
    from ..errors import SceneError

    count = duration * scene.run.sample_rate
    if not count < MAX_SAMPLES:
        raise SceneError(f"duration_s x sample_rate_hz = {duration:g} x "
                         f"{scene.run.sample_rate:g} = {count:.3g} samples: allowed <= "
                         f"{MAX_SAMPLES:.0e} (lower [run] sample_rate_hz or duration_s)")


def sample_times(scene, duration: float) -> np.ndarray:
    """Elapsed sample times [s]: 0, 1/rate, ... up to ``duration``."""
    return np.arange(_sample_count(scene, duration)) / scene.run.sample_rate


def prepare_run(scene, duration: float | None):
    """``(duration [s], t0 [s], table)`` of a run of ``scene``: :func:`run_span`, the
    samples checked (:func:`check_samples`), the excitation table on ``t - t0``."""
    from .table import table_from_scene

    duration, t0, _ = run_span(scene, duration)
    check_samples(scene, duration)
    return duration, t0, table_from_scene(scene, origin=t0)


def run_result(scene, traj, contacts, n_events: int, *, model: str, t0: float, duration: float,
               wall0: float, upper_stuck=None) -> DynamicsResult:
    """The :class:`DynamicsResult` of a run integrated on ``t - t0`` over [0, duration] s.

    ``traj(elapsed)`` gives (gap [m], gap velocity [m/s], table position [m]);
    ``contacts`` = (times [s], plate index 0 lower / 1 upper, speeds before and after
    [m/s]); the regime is classified over the settled window ([run] settle_periods);
    ``upper_stuck(window_start, t_end)``: whether the ball rests on the upper plate
    (None: it never does, as in the soft model); ``wall0``: ``time.perf_counter()`` at
    the start."""
    import time

    from ..scene.constants import G
    from .regime import classify

    times, plates, before, after = contacts
    period = scene.excitation.period
    stroke = scene.device.stroke
    window = min(scene.run.settle_periods * period, duration)
    stuck = bool(upper_stuck(window, duration)) if upper_stuck is not None else False
    regime = classify(traj, times, plates, before, window_start=window, t_end=duration,
                      period=period, stroke=stroke, g=G, upper_stuck=stuck)
    elapsed = sample_times(scene, duration)
    z, v, y = traj(elapsed)
    names = PLATE_NAMES[plates] if plates.size else np.zeros(0, dtype="<U5")
    return DynamicsResult(t=t0 + elapsed, gap=z, gap_velocity=v, table=y,
                          impacts=Impacts(t0 + times, names, before, after), regime=regime,
                          n_events=n_events, wall_time=time.perf_counter() - wall0, model=model,
                          stroke=stroke, period=period, window_start=t0 + window,
                          time_origin=t0, elapsed=elapsed, _sampler=traj)
