"""Regime of the steady window: pure functions on sampled states and impacts.

Definitions (also in docs/dynamics.md). The steady window is
``[t0 + settle_periods T, t_end]``; it holds ``K`` whole excitation periods.

* Poincare section: the state (z, dz/dt) at ``t_w + k T``, k = 0..K.
  The period is the smallest p in 1..MAX_PERIOD with
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
  (max gap < REST_GAP and no impact); ``chaos`` when aperiodic;
  otherwise ``bounce`` without upper contacts, ``regular-contact`` with at
  least one upper contact per excitation period and an upper impact that
  would have overshot by >= CRITICAL_OVERSHOOT dh (``v^2 / 2g``) or sticking
  to the upper plate, else ``critical-contact`` (the ball just reaches the
  upper plate, or not in every period).
"""
from __future__ import annotations

import math

import numpy as np

from .result import Regime

MAX_PERIOD = 16
PERIOD_TOL = 1e-3
SAMPLES_PER_PERIOD = 64
REST_GAP = 1e-9          # [m]
CRITICAL_OVERSHOOT = 0.1  # fraction of the stroke
CONTACT_MERGE_HEIGHT = 0.01  # fraction of the stroke


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


def _refined_max(sampler, t: np.ndarray, z: np.ndarray, rounds: int = 3,
                 points: int = 33) -> float:
    """Max of z(t): the best sample, then ``rounds`` zooms of ``points`` samples around it.

    Each zoom shrinks the bracket by (points - 1) / 2, so three rounds of 33
    resolve the apex to (T/64) / 16^3 in time.
    """
    k = int(np.argmax(z))
    lo = t[max(k - 1, 0)]
    hi = t[min(k + 1, t.size - 1)]
    best = float(z[k])
    for _ in range(rounds):
        tt = np.linspace(lo, hi, points)
        zz = sampler(tt)[0]
        j = int(np.argmax(zz))
        best = max(best, float(zz[j]))
        lo, hi = tt[max(j - 1, 0)], tt[min(j + 1, points - 1)]
    return best


def count_contacts(impact_time: np.ndarray, impact_plate: np.ndarray, dense_t: np.ndarray,
                   z_dense: np.ndarray, stroke: float, plate: int, merge_height: float) -> int:
    """Contacts at ``plate`` (0 lower, 1 upper) among time-ordered impacts.

    An impact continues the previous contact when the previous impact was at
    the same plate and the ball stayed within ``merge_height`` [m] of that
    plate in between (judged on the samples ``z_dense`` at ``dense_t``).
    """
    if impact_time.size == 0:
        return 0
    distance = z_dense if plate == 0 else stroke - z_dense
    cut = np.minimum(np.searchsorted(dense_t, impact_time), dense_t.size - 1)
    # largest distance from the plate between consecutive impacts (0 if no sample between)
    between = np.zeros(impact_time.size)
    if impact_time.size > 1:
        gaps = np.maximum.reduceat(distance, cut[:-1]) if cut.size > 1 else np.zeros(0)
        gaps = np.where(cut[1:] > cut[:-1], gaps, 0.0)
        between[1:] = gaps
    same = np.zeros(impact_time.size, dtype=bool)
    same[1:] = impact_plate[1:] == impact_plate[:-1]
    continued = same & (between < merge_height)
    return int(np.count_nonzero((impact_plate == plate) & ~continued))


def classify(sampler, impact_time: np.ndarray, impact_plate: np.ndarray,
             impact_speed: np.ndarray, *, window_start: float, t_end: float, period: float,
             stroke: float, g: float, upper_stuck: bool = False) -> Regime:
    """Regime of [window_start, t_end]; ``sampler(times) -> (z, v, y)``.

    ``impact_plate`` holds 0 (lower) / 1 (upper), ``impact_speed`` the
    relative impact speeds [m/s]; ``upper_stuck`` says whether the ball was pressed to the upper plate in
    the window.
    """
    n_periods = int(math.floor((t_end - window_start) / period + 1e-9))
    if n_periods < 1:
        return Regime("rest", 0, 0.0, 0.0, 0.0)
    section_t = window_start + period * np.arange(n_periods + 1)
    z_sec, v_sec, _ = sampler(section_t)
    dense_t = np.linspace(window_start, window_start + n_periods * period,
                          SAMPLES_PER_PERIOD * n_periods + 1)
    z_dense, _, _ = sampler(dense_t)
    in_window = (impact_time >= window_start) & (impact_time <= window_start + n_periods * period)
    lower = in_window & (impact_plate == 0)
    upper = in_window & (impact_plate == 1)
    n_lower = int(np.count_nonzero(lower))
    n_upper = int(np.count_nonzero(upper))
    merge = CONTACT_MERGE_HEIGHT * stroke
    contacts_lower = count_contacts(impact_time[in_window], impact_plate[in_window], dense_t,
                                    z_dense, stroke, 0, merge)
    contacts_upper = count_contacts(impact_time[in_window], impact_plate[in_window], dense_t,
                                    z_dense, stroke, 1, merge)
    max_gap = _refined_max(sampler, dense_t, z_dense)
    if n_upper or upper_stuck:
        max_gap = stroke
    period_p = detect_period(z_sec, v_sec, stroke, g)
    lower_pp = contacts_lower / n_periods
    upper_pp = contacts_upper / n_periods
    if max_gap < REST_GAP and n_lower == 0 and n_upper == 0:
        name = "rest"
        period_p = 1
    elif period_p == 0:
        name = "chaos"
    elif n_upper == 0 and not upper_stuck:
        name = "bounce"
    else:
        overshoot = (float(np.max(impact_speed[upper])) ** 2 / (2.0 * g) if n_upper else 0.0)
        strong = upper_stuck or overshoot >= CRITICAL_OVERSHOOT * stroke
        name = "regular-contact" if (upper_pp >= 1.0 - 1e-12 and strong) else "critical-contact"
    return Regime(name, period_p, lower_pp, upper_pp, max_gap)
