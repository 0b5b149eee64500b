"""Regime of the steady window: pure functions on sampled states and impacts.

Definitions (also in docs/dynamics.md). The steady window is
``[t0 + settle_periods T, t_end]``; it holds ``K`` whole excitation periods.

* Poincare section: the state (z, dz/dt) at ``t_w + theta T + k T``,
  k = 0..K-1, at the section phase ``theta`` in the middle of the largest
  phase interval free of impacts (impact phases ``(t_i - t_w) / T mod 1``
  of the second half of the window; theta = 0 without impacts). A section
  at an impact instant would see the velocity before or after the impact
  depending on round-off. The period is the smallest p in 1..MAX_PERIOD with
  ``|z_{k+p} - z_k| / dh + |v_{k+p} - v_k| / sqrt(2 g dh) <= PERIOD_TOL``
  for every section point k in the second half of the window; 0 if none.
* contacts per period: contacts at that plate in the window / K. A contact
  starts with an impact; the following impacts at the same plate belong to
  the same contact while the ball stays within CONTACT_MERGE_HEIGHT dh of
  that plate in between (on the 64-per-period samples), so a chatter
  sequence ending in sticking is one contact.
* max gap: the largest z at SAMPLES_PER_PERIOD samples per period in the
  window, refined by a golden-section search around the largest sample
  (error below ``g (1+Gamma) (T/64)^2 / 8`` only if two different apexes
  differ by less than that), dh if the upper plate was reached.
* names: ``rest`` when the ball never leaves the lower plate
  (max gap < REST_GAP and no impact); ``chaos`` when aperiodic over a window of at
  least CHAOS_MIN_PERIODS excitation periods, ``not-settled`` when aperiodic over a
  shorter one (a transient is aperiodic too: too short a window cannot tell);
  otherwise ``bounce`` without upper contacts, ``regular-contact`` with at
  least one upper contact per excitation period and an upper impact that
  would have overshot by >= CRITICAL_OVERSHOOT dh (``v^2 / 2g``) or sticking
  to the upper plate, else ``critical-contact`` (the ball just reaches the
  upper plate, or not in every period).
* settled (:func:`settled_regime`, what :func:`tengfield.simulate` reports for a
  periodic excitation): the run is continued to twice, four times, ... its length, at
  most to SETTLE_BOUND_PERIODS excitation periods (and never shorter than the run),
  and the regime of each length's window is compared with the next one's: the first
  periodic regime that the next, twice as long run repeats (same name and period) is
  the regime, settled by that length; if none repeats within the bound, the last
  window's regime: ``chaos`` (aperiodic over >= CHAOS_MIN_PERIODS), or periodic over
  the second half of that long window (settled by its length).
"""
from __future__ import annotations

import math

import numpy as np

from .result import Regime

MAX_PERIOD = 16
SECTION_BINS = 4096      # phase bins of section_phase
PERIOD_TOL = 1e-3
SAMPLES_PER_PERIOD = 64
REST_GAP = 1e-9          # [m]
CRITICAL_OVERSHOOT = 0.1  # fraction of the stroke
CONTACT_MERGE_HEIGHT = 0.01  # fraction of the stroke
CHAOS_MIN_PERIODS = 100  # an aperiodic window this long (excitation periods) is chaos
SETTLE_BOUND_PERIODS = 400  # the settling check runs at most this many periods


def detect_period(z_section: np.ndarray, v_section: np.ndarray, stroke: float, g: float,
                  max_period: int = MAX_PERIOD, tol: float = PERIOD_TOL) -> int:
    """Smallest period (in section steps) of the tail of a Poincare sequence, 0 if none."""
    n = z_section.size
    v_scale = math.sqrt(2.0 * g * stroke)
    first = n // 2
    for p in range(1, max_period + 1):
        if n - first - p < max(2, p):   # need at least max(2, p) comparisons
            break
        dz = np.abs(z_section[first + p:] - z_section[first:n - p]) / stroke
        dv = np.abs(v_section[first + p:] - v_section[first:n - p]) / v_scale
        if np.all(dz + dv <= tol):
            return p
    return 0


def _refined_max(sampler, start: float, step: float, z: np.ndarray, rounds: int = 3,
                 points: int = 33) -> float:
    """Max of z(t): the best sample, then ``rounds`` zooms of ``points`` samples around it.

    Each zoom shrinks the bracket by (points - 1) / 2, so three rounds of 33
    resolve the apex to (T/64) / 16^3 in time.
    """
    k = int(np.argmax(z))
    lo = start + step * max(k - 1, 0)
    hi = start + step * min(k + 1, z.size - 1)
    best = float(z[k])
    for _ in range(rounds):
        tt = np.linspace(lo, hi, points)
        zz = sampler(tt)[0]
        j = int(np.argmax(zz))
        best = max(best, float(zz[j]))
        lo, hi = tt[max(j - 1, 0)], tt[min(j + 1, points - 1)]
    return best


def count_contacts(impact_time: np.ndarray, impact_plate: np.ndarray, start: float,
                   step: float, z_grid: np.ndarray, stroke: float,
                   merge_height: float) -> tuple[int, int]:
    """(lower, upper) contacts among time-ordered impacts (plate 0 lower, 1 upper).

    An impact continues the previous contact when the previous impact was at
    the same plate and the ball stayed within ``merge_height`` [m] of that
    plate in between, judged on the samples ``z_grid`` at ``start + i step``.
    """
    from ._kernel import count_contacts_on_grid
    counts = count_contacts_on_grid(np.ascontiguousarray(impact_time, dtype=float),
                                    np.ascontiguousarray(impact_plate, dtype=np.int64),
                                    float(start), float(step), z_grid, float(stroke),
                                    float(merge_height))
    return int(counts[0]), int(counts[1])


def section_phase(impact_time: np.ndarray, start: float, period: float,
                  bins: int = SECTION_BINS) -> float:
    """Phase in [0, 1) in the middle of the longest impact-free run of phase bins.

    Impact phases ``(t - start) / period mod 1`` are counted in ``bins`` equal
    bins (O(n), no sort); the section goes to the middle of the longest
    circular run of empty bins, at least half a bin from every impact. 0
    without impacts; the emptiest bin if every bin holds an impact (then the
    motion has no repeating impact phases: it is not periodic anyway).
    """
    if impact_time.size == 0:
        return 0.0
    index = np.floor(np.mod((impact_time - start) / period, 1.0) * bins).astype(np.int64)
    counts = np.bincount(np.minimum(index, bins - 1), minlength=bins)
    empty = counts == 0
    if not empty.any():
        return (int(np.argmin(counts)) + 0.5) / bins
    # longest circular run of empty bins: unroll twice
    twice = np.concatenate([empty, empty]).astype(np.int8)
    edges = np.diff(np.concatenate([[0], twice, [0]]))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)
    k = int(np.argmax(np.minimum(ends - starts, bins)))
    middle = 0.5 * (starts[k] + min(ends[k], starts[k] + bins))
    return float(np.mod(middle / bins, 1.0))


def _grid_gap(sampler, start: float, step: float, count: int, gap_on_grid=None) -> np.ndarray:
    """z at ``start + i step`` (by ``gap_on_grid(start, step, count)`` when given)."""
    if gap_on_grid is not None:
        return gap_on_grid(start, step, count)
    return sampler(start + step * np.arange(count))[0]


def regime_label(name: str, period: int, *, settled_by_s: float | None = None,
                 checked_to_s: float = 0.0, duration_s: float | None = None) -> str:
    """How a regime is said in one line: ``"bounce, period 2"``, ``"chaos (aperiodic)"``
    (a chaotic window has no period: ``period`` 0), ``"rest"``, ``"not settled in 20 s
    (aperiodic)"``; with the settling check's lengths [s] (:func:`settled_regime`) and
    the run's ``duration_s``, how it was checked: the runs compared (``"this run's regime:
    the same on a run of 2 s"``; ``"found on a run of 2 s, the same on 4 s; the 1 s run is
    still settling"``)."""
    if name == "not-settled":
        within = checked_to_s or duration_s
        return (f"not settled in {within:g} s (aperiodic)" if within
                else "not settled (aperiodic)")
    if name == "chaos" or not period:
        text = f"{name} (aperiodic)" if name == "chaos" else name
    elif name == "rest":
        text = name
    else:
        text = f"{name}, period {period}"
    if name == "chaos" and checked_to_s:
        text += f", over a run of {checked_to_s:g} s"
    elif settled_by_s is not None and checked_to_s:
        # settled_by_s is the length of the run whose window shows the regime (the run or
        # a doubling of it), not a settling time: said as the runs compared
        if duration_s is not None and settled_by_s <= duration_s * (1 + 1e-9):
            text += (f" (this run's regime: the same on a run of {checked_to_s:g} s)")
        else:
            text += (f" (found on a run of {settled_by_s:g} s, the same on {checked_to_s:g} s"
                     + (f"; the {duration_s:g} s run is still settling: raise [run] "
                        "duration_s" if duration_s is not None else "") + ")")
    return text


def contacts_text(lower: float, upper: float, period: int) -> str:
    """The contacts per excitation period, said so that they do not read as the period:
    ``"contacts per excitation period: lower 2.1, upper 1 (a period-1 motion may touch a
    plate more than once per period; averaged over the window)"``."""
    why = (f" (a period-{period} motion repeats every {period} excitation period"
           f"{'s' if period != 1 else ''}; a contact is an impact or a chatter sequence "
           "ending on the plate, averaged over the window)" if period else
           " (averaged over the window)")
    return f"contacts per excitation period: lower {lower:.3g}, upper {upper:.3g}{why}"


def settled_regime(regime_of, duration: float, period: float, *,
                   bound_periods: int = SETTLE_BOUND_PERIODS) -> Regime:
    """The regime of a run of ``duration`` [s], checked for settling (module doc).

    ``regime_of(length)``: the :class:`Regime` of the same run continued to ``length``
    [s] (its window after the same settle periods); ``regime_of(duration)`` is the run's
    own. Lengths double from ``duration`` up to ``max(duration, bound_periods *
    period)``. Returns the regime with ``settled_by_s`` (None if not settled) and
    ``checked_to_s`` (the longest length simulated)."""
    from dataclasses import replace

    bound = max(duration, bound_periods * period) * (1 + 1e-12)
    length, current = duration, regime_of(duration)
    while 2.0 * length <= bound:
        following = regime_of(2.0 * length)
        if current.period > 0 and (following.name, following.period) == (current.name,
                                                                         current.period):
            return replace(current, settled_by_s=length, checked_to_s=2.0 * length,
                           run_s=duration)
        length, current = 2.0 * length, following
    if current.period == 0 or current.name == "not-settled":
        return replace(current, settled_by_s=None, checked_to_s=length, run_s=duration)
    # periodic over the second half of a window of at least bound_periods / 2 periods
    # (or of the run itself when it is that long already): repeating over that many
    return replace(current, settled_by_s=length, checked_to_s=length, run_s=duration)


def regime_table(counts: dict, order=()) -> str:
    """The points of a regime map per regime as a text table (regime, points, share);
    ``counts`` {regime: points}, rows in ``order`` first, then the others."""
    total = sum(counts.values()) or 1
    names = [n for n in order if n in counts] + sorted(n for n in counts if n not in order)
    width = max([len("regime")] + [len(n) for n in names])
    lines = [f"{'regime':<{width}}  {'points':>8}  {'share':>7}"]
    lines += [f"{n:<{width}}  {counts[n]:>8d}  {100.0 * counts[n] / total:>6.1f}%"
              for n in names]
    return "\n".join(lines)


def classify(sampler, impact_time: np.ndarray, impact_plate: np.ndarray,
             impact_speed: np.ndarray, *, window_start: float, t_end: float, period: float,
             stroke: float, g: float, upper_stuck: bool = False, gap_on_grid=None) -> Regime:
    """Regime of [window_start, t_end]; ``sampler(times) -> (z, v, y)``.

    ``impact_plate`` holds 0 (lower) / 1 (upper), ``impact_speed`` the
    relative impact speeds [m/s]; ``upper_stuck`` says whether the ball was pressed to the upper plate in
    the window; ``gap_on_grid(start, step, count)``: z on a uniform grid in one pass (a
    compiled trajectory's, e.g. :meth:`tengfield.dynamics.impact.Trajectory.gap_on_grid`),
    the same values as ``sampler`` there.
    """
    n_periods = int(math.floor((t_end - window_start) / period + 1e-9))
    if n_periods < 1:
        return Regime("rest", 0, 0.0, 0.0, 0.0)
    window_end = window_start + n_periods * period
    in_window = (impact_time >= window_start) & (impact_time <= window_end)
    late = impact_time[in_window & (impact_time >= window_start + 0.5 * n_periods * period)]
    theta = section_phase(late, window_start, period)
    section_t = window_start + period * (theta + np.arange(n_periods))
    z_sec, v_sec, _ = sampler(section_t)
    step = period / SAMPLES_PER_PERIOD
    count = SAMPLES_PER_PERIOD * n_periods + 1
    z_dense = _grid_gap(sampler, window_start, step, count, gap_on_grid)
    n_lower = int(np.count_nonzero(in_window & (impact_plate == 0)))
    upper = in_window & (impact_plate == 1)
    n_upper = int(np.count_nonzero(upper))
    contacts_lower, contacts_upper = count_contacts(
        impact_time[in_window], impact_plate[in_window], window_start, step, z_dense, stroke,
        CONTACT_MERGE_HEIGHT * stroke)
    max_gap = _refined_max(sampler, window_start, step, z_dense)
    if n_upper or upper_stuck:
        max_gap = stroke
    period_p = detect_period(z_sec, v_sec, stroke, g)
    lower_pp = contacts_lower / n_periods
    upper_pp = contacts_upper / n_periods
    if max_gap < REST_GAP and n_lower == 0 and n_upper == 0:
        name = "rest"
        period_p = 1
    elif period_p == 0:
        name = "chaos" if n_periods >= CHAOS_MIN_PERIODS else "not-settled"
    elif n_upper == 0 and not upper_stuck:
        name = "bounce"
    else:
        overshoot = (float(np.max(impact_speed[upper])) ** 2 / (2.0 * g) if n_upper else 0.0)
        strong = upper_stuck or overshoot >= CRITICAL_OVERSHOOT * stroke
        name = "regular-contact" if (upper_pp >= 1.0 - 1e-12 and strong) else "critical-contact"
    return Regime(name, period_p, lower_pp, upper_pp, max_gap)
