"""One run of a 1-D model: its span, its samples and its result (shared by every model)."""
from __future__ import annotations

import math
import time

import numpy as np

from ..errors import DynamicsError, SceneError
from ..scene.constants import G
from ..scene.limits import MAX_SAMPLES, check_steady_window, run_samples  # noqa: F401 - MAX_SAMPLES: also for simulate(duration=)
from . import columns as _columns
from .excitation import table_from_scene
from .regime import classify
from .result import PLATE_NAMES, DynamicsResult, Impacts


def run_span(scene, duration: float | None) -> tuple[float, float, float]:
    """(duration, start, end) [s] of a run: ``duration`` None means ``[run] duration_s``;
    the run starts at ``[initial] time_s``."""
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
    return int(math.floor(duration * scene.run.sample_rate + 1e-9)) + 1


def check_samples(scene, duration: float) -> None:
    """Refuse a run whose samples would not fit (MAX_SAMPLES, the scene's own bound:
    :func:`~tengfield.scene.limits.run_samples`), before integrating."""
    run_samples(scene.run, duration)


def sample_times(scene, duration: float) -> np.ndarray:
    """Elapsed sample times [s]: 0, 1/rate, ... up to ``duration``."""
    return np.arange(_sample_count(scene, duration)) / scene.run.sample_rate


def prepare_run(scene, duration: float | None):
    """``(duration [s], t0 [s], table)`` of a run of ``scene``: :func:`run_span`, the
    samples checked (:func:`check_samples`), the excitation table on ``t - t0``."""
    duration, t0, _ = run_span(scene, duration)
    check_samples(scene, duration)
    return duration, t0, table_from_scene(scene, origin=t0)


def run_result(scene, traj, contacts, n_events: int, *, model: str, t0: float, duration: float,
               wall0: float, upper_stuck=None, gap_on_grid=None) -> DynamicsResult:
    """The :class:`DynamicsResult` of a run integrated on ``t - t0`` over [0, duration] s.

    ``traj(elapsed)`` gives (gap [m], gap velocity [m/s], table position [m]);
    ``contacts`` = (times [s], plate index 0 lower / 1 upper, speeds before and after
    [m/s]); the regime is classified over the settled window ([run] settle_periods);
    ``upper_stuck(window_start, t_end)``: whether the ball rests on the upper plate
    (None: it never does, as in the soft model); ``gap_on_grid(start, step, count)``: the
    gap on a uniform grid in one pass, if the model has one (:func:`.regime.classify`);
    ``wall0``: ``time.perf_counter()`` at the start. A run of more than
    :data:`~.columns.LAZY_ROWS` samples keeps ``traj`` and samples its columns on request
    (:class:`~.columns.SampledColumn`: the same numbers, memory bounded)."""
    times, plates, before, after = contacts
    period = scene.excitation.period
    stroke = scene.device.stroke
    window = min(scene.run.settle_periods * period, duration)
    stuck = bool(upper_stuck(window, duration)) if upper_stuck is not None else False
    regime = classify(traj, times, plates, before, window_start=window, t_end=duration,
                      period=period, stroke=stroke, g=G, upper_stuck=stuck,
                      gap_on_grid=gap_on_grid)
    count = _sample_count(scene, duration)
    if count > _columns.LAZY_ROWS:
        cols = _columns.sampled_columns(count, scene.run.sample_rate, t0, traj)
        elapsed, t, z, v, y = (cols[c] for c in ("elapsed", "t", "gap", "gap_velocity",
                                                   "table"))
    else:
        elapsed = sample_times(scene, duration)
        z, v, y = traj(elapsed)
        t = t0 + elapsed
    names = PLATE_NAMES[plates] if plates.size else np.zeros(0, dtype="<U5")
    return DynamicsResult(t=t, gap=z, gap_velocity=v, table=y,
                          impacts=Impacts(t0 + times, names, before, after), regime=regime,
                          n_events=n_events, wall_time=time.perf_counter() - wall0, model=model,
                          stroke=stroke, period=period, window_start=t0 + window,
                          time_origin=t0, elapsed=elapsed, _sampler=traj)
