"""Result objects of the dynamics (in the spirit of scipy's ``OdeResult``)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar

import numpy as np

from .._args import checked_write
from .._face import Summary

#: plate index of a contact -> its name
PLATE_NAMES = np.array(["lower", "upper"])

REGIMES = ("rest", "bounce", "chaos", "not-settled", "critical-contact", "regular-contact")


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
    #: the settling check (:func:`tengfield.dynamics.regime.settled_regime`): the run's
    #: length [s] from which the regime no longer changed (None: not checked, or not
    #: settled), and the longest run the check simulated [s] (0: not checked)
    settled_by_s: float | None = None
    checked_to_s: float = 0.0
    #: the length of the run itself [s] (0: not checked)
    run_s: float = 0.0

    def as_dict(self) -> dict:
        return {"regime": self.name, "period": self.period,
                "lower_contacts_per_period": self.lower_contacts_per_period,
                "upper_contacts_per_period": self.upper_contacts_per_period,
                "max_gap_m": self.max_gap, "settled_by_s": self.settled_by_s,
                "regime_checked_to_s": self.checked_to_s, "regime_run_s": self.run_s}


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

    A run of more than :data:`tengfield.dynamics.columns.LAZY_ROWS` samples (2^20) holds
    no whole-record arrays: ``t``, ``elapsed``, ``gap``, ``gap_velocity`` and ``table``
    are :class:`~tengfield.dynamics.columns.SampledColumn` objects, sampled on request
    (slices cost what they return; ``np.asarray`` builds the whole column; the same
    numbers, bit for bit).
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
    scene: Any = field(default=None, repr=False, compare=False)   # the scene simulated
    #: the ball moves sideways (the 3D model): trajectory.csv has more columns, contacts.csv
    lateral: ClassVar[bool] = False

    def sample(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(gap [m], gap_velocity [m/s], table [m]) exactly at absolute ``times`` [s]."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        return self.sample_elapsed(t - self.time_origin)

    def sample_elapsed(self, elapsed) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(gap [m], gap_velocity [m/s], table [m]) at ``elapsed`` [s] after time_origin."""
        s = np.ascontiguousarray(np.atleast_1d(np.asarray(elapsed, dtype=float)))
        return self._sampler(s)

    def plot(self, *, max_periods: float | None = None, title: str | None = None):
        """The trajectory figure (a matplotlib Figure; ``tengfield dynamics`` saves it as
        trajectory.png): table, plates and ball against time, the gap z(t), impacts
        marked; ``max_periods``: the last that many excitation periods."""
        from ..plotting.dynamics import trajectory_figure, trajectory_plot   # the edge, on use

        return trajectory_plot(trajectory_figure(self, title=title, max_periods=max_periods))

    @property
    def summary(self) -> dict:
        """JSON-ready summary (the CLI's summary.json, without its ``scene`` path)."""
        return Summary(self._summary_fields())

    @checked_write
    def write(self, out_dir, plots: bool = True, *, figures=None) -> list:
        """Write what ``tengfield dynamics -o out_dir`` writes (summary.json, trajectory.csv,
        impacts.csv and, with ``plots``, trajectory.png); returns the paths. ``figures``: a
        :class:`tengfield.plotting.process.FigureProcess` drawing the figure (complete after
        its ``finish()``), as the CLI passes."""
        from pathlib import Path

        from ..files import write_json
        from .output import write_dynamics_files

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        summary = dict(self.summary)
        summary["scene"] = getattr(self.scene, "source", None)
        paths = [write_json(out / "summary.json", summary)]
        return paths + list(write_dynamics_files(self, self.scene, out, plots=plots,
                                                 figures=figures))

    def _summary_fields(self) -> dict:
        plates = self.impacts.plate
        return {
            "model": self.model,
            "regime": self.regime.name,
            "period": self.regime.period,
            "max_gap_mm": self.regime.max_gap * 1e3,
            "upper_contacts_per_period": self.regime.upper_contacts_per_period,
            "lower_contacts_per_period": self.regime.lower_contacts_per_period,
            "settled_by_s": self.regime.settled_by_s,
            "regime_checked_to_s": self.regime.checked_to_s,
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
