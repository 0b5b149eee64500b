"""Regime maps: the impact map run on a grid of sine excitations (frequency x amplitude).

Each grid point starts from ``scene.initial`` and runs ``periods`` excitation
periods; the first ``settle_periods`` are the transient left out of the
regime analysis (:func:`tengfield.dynamics.regime.classify`). Points are
independent: they are spread over ``jobs`` worker processes (all cores by
default), each running the compiled kernel.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._args import checked_write
from ..errors import DynamicsError, SceneError
from .._mpi import check_jobs, farm, size_of
from ..scene.constants import G
from .impact import Restitution, integrate
from .regime import classify
from .result import REGIMES, Regime
from ..files import figure_file

#: At most this many grid points in one map (result arrays ~130 bytes per point).
MAX_MAP_POINTS = 4_000_000
#: At most this many excitation periods per map point.
MAX_MAP_PERIODS = 1_000_000
#: At most this many simulated periods in one map (points x periods; ~10 us each).
MAX_MAP_WORK = 10_000_000_000


def check_map_size(n_points: int, periods: int) -> None:
    """Refuse a map before anything is allocated when it is too large to finish."""
    if not 2 <= periods <= MAX_MAP_PERIODS:
        raise SceneError(f"map periods = {periods}: allowed [2, {MAX_MAP_PERIODS}]")
    if n_points > MAX_MAP_POINTS:
        raise SceneError(f"map points = {n_points:.3g} (frequencies x amplitudes): allowed <= "
                         f"{MAX_MAP_POINTS:.0e}")
    if n_points * periods > MAX_MAP_WORK:
        raise SceneError(f"map points x periods = {n_points:.3g} x {periods} = "
                         f"{n_points * periods:.3g}: allowed <= {MAX_MAP_WORK:.0e}")
from .table import sine_phase_at, sine_table


@dataclass(frozen=True)
class MapResult:
    """Regimes on the grid; 2-D arrays are indexed [amplitude, frequency]."""
    frequency: np.ndarray        # [Hz], shape (nf,)
    amplitude: np.ndarray        # [m], shape (na,)
    regime: np.ndarray           # names, shape (na, nf)
    period: np.ndarray           # excitation periods, 0 = aperiodic
    max_gap: np.ndarray          # [m]
    lower_contacts_per_period: np.ndarray
    upper_contacts_per_period: np.ndarray
    error: np.ndarray            # message where a point failed, else ''
    scene: Any = field(default=None, repr=False, compare=False)   # the scene mapped
    periods: int = 0             # excitation periods simulated per point

    @property
    def summary(self) -> dict:
        """JSON-ready counts: grid size, periods per point and points per regime."""
        names, counts = np.unique(self.regime, return_counts=True)
        return {"points": int(self.regime.size), "frequencies": int(self.frequency.size),
                "amplitudes": int(self.amplitude.size), "periods": int(self.periods),
                "regimes": {str(n): int(c) for n, c in zip(names, counts)},
                "failed": int(np.sum(self.error != ""))}

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield map -o out_dir`` writes: map.csv and, with ``plots``,
        map.png; returns the paths."""
        from pathlib import Path

        from ..files import writable_target
        from .output import write_map_csv
        from ..plotting.dynamics import plot_regime_map

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        write_map_csv(self, out / "map.csv")
        paths = [out / "map.csv"]
        if plots:
            plot_regime_map(self, writable_target(out / figure_file("map")), title=self.plot_title())
            paths.append(out / figure_file("map"))
        return paths

    def plot_title(self) -> str:
        """map.png's title (restitution, stroke, periods per point)."""
        if self.scene is None:
            return f"regimes, {self.periods} periods per point"
        return (f"regimes, restitution {self.scene.contact.restitution:g}, "
                f"Δh = {self.scene.device.stroke * 1e3:g} mm, {self.periods} periods per point")

    def plot(self, *, title: str | None = None):
        """The regime map (a matplotlib Figure; ``tengfield map`` saves it as map.png)."""
        from ..plotting.dynamics import regime_map_figure   # the edge, imported on use

        return regime_map_figure(self, title=title)

    def records(self) -> list[dict]:
        """One dict per grid point (frequency-fastest), SI units."""
        out = []
        for i, amp in enumerate(self.amplitude):
            for j, freq in enumerate(self.frequency):
                out.append({"frequency_hz": float(freq), "amplitude_m": float(amp),
                            "regime": str(self.regime[i, j]), "period": int(self.period[i, j]),
                            "max_gap_m": float(self.max_gap[i, j]),
                            "lower_contacts_per_period": float(self.lower_contacts_per_period[i, j]),
                            "upper_contacts_per_period": float(self.upper_contacts_per_period[i, j]),
                            "error": str(self.error[i, j])})
        return out

    def regime_index(self) -> np.ndarray:
        """Integer code of each regime (index into REGIMES, -1 for failed points)."""
        lookup = {name: k for k, name in enumerate(REGIMES)}
        return np.vectorize(lambda s: lookup.get(s, -1))(self.regime)


@dataclass(frozen=True)
class PointSetup:
    """Everything but the excitation that a map point needs (SI, from the scene)."""
    stroke: float
    restitution: Restitution
    phase: float
    t_start: float
    gap0: float
    velocity0: float
    periods: int
    settle_periods: int


def point_regime(setup: PointSetup, frequency: float, amplitude: float) -> Regime:
    """Regime of one sine excitation (frequency [Hz], amplitude [m]).

    Integrated on the time since ``setup.t_start`` (the table phase there is
    reduced exactly), so the absolute start time does not change the result.
    """
    period = 1.0 / frequency
    table = sine_table(amplitude, 2.0 * math.pi * frequency,
                       sine_phase_at(frequency, setup.phase, setup.t_start))
    t_end = setup.periods * period
    traj, (it, ip, ivb, iva), _ = integrate(
        table, setup.stroke, setup.restitution, t_start=0.0, t_end=t_end,
        gap0=setup.gap0, velocity0=setup.velocity0, period=period, time_origin=setup.t_start)
    window_start = setup.settle_periods * period
    return classify(traj, it, ip, ivb, window_start=window_start, t_end=t_end, period=period,
                    stroke=setup.stroke, g=G,
                    upper_stuck=traj.upper_stuck_between(window_start, t_end),
                    gap_on_grid=traj.gap_on_grid)


def _chunk(args):
    """Worker: regimes of a list of (row, column, frequency, amplitude) points."""
    setup, points = args
    out = []
    for i, j, f, a in points:
        try:
            out.append((i, j, point_regime(setup, float(f), float(a)), ""))
        except DynamicsError as exc:
            out.append((i, j, None, str(exc)))
    return out


def regime_map(scene, frequencies_hz, amplitudes_m, *, jobs: int | None = None,
               progress: bool = True, periods: int = 200,
               settle_periods: int | None = None, comm=None) -> MapResult:
    """Regime, period, max gap and contacts per period on a frequency x amplitude grid.

    ``frequencies_hz`` [Hz] and ``amplitudes_m`` [m] are 1-D; ``jobs``
    worker processes (default: all cores), or the MPI task farm over ``comm``
    when it has more than one rank (every rank gets the whole map, identical to
    a serial run; ``jobs`` must then be None or 1); ``periods`` excitation periods
    per point of which ``settle_periods`` (default: the scene's, at most
    half of ``periods``) are transient. A point whose integration fails gets
    regime ``'error'`` and its message in ``error``.
    """
    freqs = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    amps = np.atleast_1d(np.asarray(amplitudes_m, dtype=float))
    if freqs.ndim != 1 or freqs.size == 0 or not np.all(np.isfinite(freqs)) or np.any(freqs <= 0):
        raise SceneError(f"map frequencies {freqs!r}: need at least one finite value > 0 Hz")
    if amps.ndim != 1 or amps.size == 0 or not np.all(np.isfinite(amps)) or np.any(amps < 0):
        raise SceneError(f"map amplitudes {amps!r}: need at least one finite value >= 0 m")
    check_map_size(freqs.size * amps.size, int(periods))
    settle = scene.run.settle_periods if settle_periods is None else int(settle_periods)
    settle = max(0, min(settle, periods // 2))
    setup = PointSetup(scene.device.stroke, Restitution.from_contact(scene.contact),
                        scene.excitation.phase, scene.initial.time, scene.initial.gap,
                        scene.initial.velocity, int(periods), settle)
    check_jobs(jobs, comm)
    jobs = (os.cpu_count() or 1) if jobs is None else int(jobs)
    workers = size_of(comm) if size_of(comm) > 1 else jobs
    points = [(i, j, f, a) for i, a in enumerate(amps) for j, f in enumerate(freqs)]
    chunk = max(1, min(64, len(points) // (8 * workers)))
    tasks = [(setup, points[k:k + chunk]) for k in range(0, len(points), chunk)]
    shape = (amps.size, freqs.size)
    names = np.full(shape, "error", dtype="<U16")
    per = np.zeros(shape, dtype=int)
    gapmax = np.full(shape, np.nan)
    low = np.full(shape, np.nan)
    up = np.full(shape, np.nan)
    errors = np.full(shape, "", dtype=object)

    from .._console import progress_bar
    bar = progress_bar(amps.size * freqs.size, "regime map", progress, unit="point", comm=comm)
    _chunk((setup, [(0, 0, 1.0, 0.0)]))   # load the compiled kernel once, before forking

    def store(results):
        for i, j, reg, msg in results:
            if reg is None:
                errors[i, j] = msg
                continue
            names[i, j] = reg.name
            per[i, j] = reg.period
            gapmax[i, j] = reg.max_gap
            low[i, j] = reg.lower_contacts_per_period
            up[i, j] = reg.upper_contacts_per_period
        bar.update(len(results))

    try:
        if size_of(comm) > 1:
            for results in farm(comm, tasks, _chunk):
                store(results)
        elif jobs == 1 or len(tasks) == 1:
            for task in tasks:
                store(_chunk(task))
        else:
            from .._pool import process_pool   # a worker that fails ends it (one line)
            with process_pool(min(jobs, len(tasks))) as pool:
                for results in pool.map(_chunk, tasks):
                    store(results)
    finally:
        bar.close()
    return MapResult(freqs, amps, names, per, gapmax, low, up, errors.astype(str),
                     scene=scene, periods=periods)


def liftoff_amplitude(frequency_hz, g: float = G):
    """Analytic lift-off threshold A = g / w^2 [m] (Gamma = A w^2 / g = 1)."""
    w = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    return g / w**2


def liftoff_frequency(amplitude_m, g: float = G):
    """Analytic lift-off frequency f = sqrt(g / A) / (2 pi) [Hz] of an amplitude [m]
    (the inverse of :func:`liftoff_amplitude`)."""
    return np.sqrt(g / np.asarray(amplitude_m, dtype=float)) / (2.0 * np.pi)


def below_liftoff(scene, g: float = G) -> dict | None:
    """Why a sine-driven ball stays at rest, or None: the table's peak acceleration
    A (2 pi f)^2 below g (Gamma < 1: the plate never pulls away from the ball), with the
    lift-off amplitude at this frequency and the lift-off frequency at this amplitude.
    Only for a periodic excitation kind (one frequency, one amplitude)."""
    from .excitation import excitation_kind

    exc = scene.excitation
    if not excitation_kind(scene).periodic or exc.frequency <= 0.0:
        return None
    peak = exc.amplitude * (2.0 * math.pi * exc.frequency) ** 2
    if peak >= g:
        return None
    a_lift = float(liftoff_amplitude(exc.frequency, g))
    f_lift = float(liftoff_frequency(exc.amplitude, g)) if exc.amplitude > 0 else None
    reason = (f"the ball never lifts off: the table's peak acceleration A (2 pi f)^2 = "
              f"{peak:.3g} m/s^2 is below g = {g:.3g} m/s^2 (Gamma = {peak / g:.3g}); it "
              f"lifts off at amplitude_mm > {a_lift * 1e3:.3g} at {exc.frequency:g} Hz"
              + (f" or at frequency_hz > {f_lift:.3g} at {exc.amplitude * 1e3:g} mm"
                 if f_lift is not None else ""))
    return {"reason": reason, "peak_table_acceleration_m_per_s2": peak, "gamma": peak / g,
            "liftoff_amplitude_mm": a_lift * 1e3, "liftoff_frequency_hz": f_lift}


def _file_axis(values, scale: float, name: str) -> np.ndarray:
    """A grid axis in file units (a list, one number or ``"START:STOP:N"``) -> SI."""
    if isinstance(values, str) and values.count(":") == 2:
        start, stop, count = values.split(":")
        try:
            n = int(count)
            axis = np.linspace(float(start), float(stop), n)
        except ValueError:
            raise SceneError(f"{name} = {values!r}: expected START:STOP:N (N a whole "
                             "number >= 1)") from None
        if n < 1:
            raise SceneError(f"{name} = {values!r}: N = {n} is out of range: allowed >= 1")
    else:
        try:
            axis = np.atleast_1d(np.asarray(values, dtype=float))
        except (TypeError, ValueError):
            raise SceneError(f"{name} = {values!r}: expected START:STOP:N, a number or a "
                             "list of numbers") from None
    return axis * scale


def map_study(scene, *, frequency_hz, amplitude_mm, periods: int = 200,
              jobs: int | None = None, progress: bool = False, comm=None) -> MapResult:
    """``tf.map``, ``tengfield map`` from Python: the regime on a frequency x amplitude
    grid in file units (``frequency_hz`` [Hz], ``amplitude_mm`` [mm]: a list, one number
    or ``"START:STOP:N"``); ``scene``: a path, TOML text or Scene. Returns the
    :class:`MapResult` (``.summary``, ``.plot()``, ``.write(out_dir)``)."""
    from ..scene import load_scene

    frequencies = _file_axis(frequency_hz, 1.0, "frequency_hz")
    amplitudes = _file_axis(amplitude_mm, 1e-3, "amplitude_mm")
    check_map_size(frequencies.size * amplitudes.size, periods)
    return regime_map(load_scene(scene), frequencies, amplitudes, jobs=jobs, progress=progress,
                      periods=periods, comm=comm)
