"""Table motion y(t) in the form the compiled kernel evaluates.

Two kinds (the constants ``SINE``, ``PPOLY`` of the compiled kernel, :mod:`._kernel`),
one representation (:class:`TableMotion`):

* ``SINE``: ``y = A sin(w t + phase)`` with ``params = (A, w, phase)``.
* ``PPOLY``: a C^4 piecewise quintic ``y(t)`` on breakpoints ``breaks``
  with coefficients ``coeffs[m, i]`` of ``(t - breaks[i])**(5 - m)``
  (scipy's ``PPoly`` layout), built from a recorded signal:

  - displacement data: the interpolating quintic spline (C^4);
  - acceleration data: the interpolating cubic spline of ``a(t)`` (C^2)
    integrated twice, so ``y`` is C^4 and ``y'' = a`` exactly at the
    samples. Drift removal: the mean of ``a`` is subtracted before
    integrating (a constant offset is sensor bias or tilt, not motion), and
    the least-squares straight line ``c0 + c1 t`` is subtracted from ``y``
    afterwards (the unknown initial position and velocity). Neither step
    changes the table acceleration up to the constant, which is all the
    ball feels.

The kernel also needs bounds valid on the whole record:
``acc_bound >= max|y''|``, ``jerk_bound >= max|y'''|``,
``snap_bound >= max|y''''|`` (SI). For the sine they are exact
(``A w^2, A w^3, A w^4``); for a spline they are guaranteed upper bounds
(``sum_k |c_k| h^k`` per piece).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import DynamicsError
from ._kernel import PPOLY, SINE, table_state_many  # kinds of TableMotion: the kernel's constants

SMOOTHING_ORDER = 4   # Butterworth order of [excitation] smoothing_hz (run twice: zero phase)


@dataclass(frozen=True)
class TableMotion:
    """Table displacement y(t) [m] for the kernel (see module docstring)."""
    kind: int
    params: np.ndarray       # (A [m], w [rad/s], phase [rad]) for SINE
    breaks: np.ndarray       # [s], PPOLY only (length n+1)
    coeffs: np.ndarray       # (6, n), PPOLY only
    acc_bound: float         # >= max |y''| [m/s^2]
    jerk_bound: float        # >= max |y'''| [m/s^3]
    snap_bound: float        # >= max |y''''| [m/s^4]
    t_first: float = -math.inf   # domain of the motion [s]
    t_last: float = math.inf

    def evaluate(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y [m], y' [m/s], y'' [m/s^2]) at ``times`` [s]."""
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(times, dtype=float)))
        return table_state_many(t, self.kind, self.params, self.breaks, self.coeffs)


_EMPTY_BREAKS = np.zeros(2)
_EMPTY_COEFFS = np.zeros((6, 1))


def sine_table(amplitude: float, omega: float, phase: float) -> TableMotion:
    """``y = amplitude sin(omega t + phase)``; amplitude [m], omega [rad/s], phase [rad]."""
    a = float(amplitude)
    w = float(omega)
    return TableMotion(kind=SINE, params=np.array([a, w, float(phase)]),
                       breaks=_EMPTY_BREAKS, coeffs=_EMPTY_COEFFS,
                       acc_bound=a * w**2, jerk_bound=a * w**3, snap_bound=a * w**4)


def _piece_bound(coeffs: np.ndarray, widths: np.ndarray) -> float:
    """Guaranteed bound of max |p_i(x)| over x in [0, h_i] for PPoly coefficients."""
    k = coeffs.shape[0] - 1
    powers = np.stack([widths ** (k - m) for m in range(k + 1)])
    return float(np.max(np.sum(np.abs(coeffs) * powers, axis=0)))


def sine_phase_at(frequency: float, phase: float, origin: float) -> float:
    """Phase [rad] of ``sin(2 pi f t + phase)`` at ``t = origin``, reduced exactly.

    ``f * origin`` is taken modulo 1 in exact rational arithmetic, so a run
    that starts at ``origin = 1e12 s`` sees the same table phase as the
    product of the two doubles says (a double ``2 pi f origin`` would carry
    an error of ~1e-2 rad there).
    """
    from fractions import Fraction
    cycles = (Fraction(frequency) * Fraction(origin)) % 1
    return math.fmod(phase + 2.0 * math.pi * float(cycles), 2.0 * math.pi)


def smooth_record(times: np.ndarray, values: np.ndarray, cutoff_hz: float) -> np.ndarray:
    """Zero-phase low-pass of a recorded signal: Butterworth of order SMOOTHING_ORDER run
    forwards and backwards (``scipy.signal.sosfiltfilt``), so the amplitude response is
    ``1 / (1 + (f / cutoff)^(2 N))`` with N = 2 SMOOTHING_ORDER and no phase shift.

    The samples are taken as uniform at their mean spacing; ``cutoff_hz`` must lie below
    the Nyquist frequency of that spacing. The record is extended by odd reflection
    at both ends (10 filter time constants), so a smooth signal passes unchanged.
    """
    from scipy.signal import butter, sosfiltfilt

    duration = float(times[-1] - times[0])
    dt = duration / (times.size - 1)
    nyquist = 0.5 / dt
    if not 1.0 / duration <= cutoff_hz < nyquist:
        # below 1 / duration the filter keeps nothing of the motion but its trend (and
        # far below it the filter's matrices are singular: LinAlgError at 1e-6 Hz)
        raise DynamicsError(f"[excitation] smoothing_hz = {cutoff_hz:.12g}: allowed "
                            f"[{1.0 / duration:.6g}, {nyquist:.6g}) Hz (from 1 / the record's "
                            f"duration {duration:.6g} s to the Nyquist frequency of its "
                            "sampling; 0 = no smoothing)")
    sos = butter(SMOOTHING_ORDER, cutoff_hz / nyquist, output="sos")
    # odd extension over ~10 time constants of the filter: the ends stay undistorted
    # (the default 27 samples left edge transients of 20x the drive's acceleration)
    pad = min(values.size - 1, int(math.ceil(10.0 / (cutoff_hz * dt))))
    return sosfiltfilt(sos, values, padtype="odd", padlen=pad)


#: a displacement sample off the mean of its neighbours by more than this many times the
#: record's median such offset, its neighbours off the other way (a spike, not a kink),
#: is a glitch: the quintic spline through it swings, and the contact search through the
#: swing fails ("did not converge") far from the cause
GLITCH_FACTOR = 100.0


def check_glitches(times: np.ndarray, values: np.ndarray) -> None:
    """DynamicsError naming the data row and time of the first single-sample spike of a
    displacement record (see GLITCH_FACTOR); ``smoothing_hz`` low-passes it instead."""
    if values.size < 5:
        return
    r = values[1:-1] - 0.5 * (values[:-2] + values[2:])      # offset from the neighbours
    a = np.abs(r)
    scale = max(float(np.median(a)), 1e-12 * float(np.ptp(values)), 1e-300)
    mid = np.arange(1, r.size - 1)
    spike = ((a[mid] > GLITCH_FACTOR * scale) & (r[mid - 1] * r[mid] < 0)
             & (r[mid + 1] * r[mid] < 0) & (a[mid - 1] > 0.25 * a[mid])
             & (a[mid + 1] > 0.25 * a[mid]))
    hits = mid[spike]
    if hits.size:
        i = int(hits[0]) + 1                                    # index into values
        more = f" (and {hits.size - 1} more)" if hits.size > 1 else ""
        raise DynamicsError(
            f"[excitation] file: the recorded displacement at data row {i + 1} "
            f"(t = {times[i]:.9g} s) is {values[i] - 0.5 * (values[i - 1] + values[i + 1]):.3g} m "
            f"off its neighbours, {a[i - 1] / scale:.3g} x the record's typical offset{more}: "
            f"a single-sample glitch (allowed {GLITCH_FACTOR:g} x): fix or remove the row, or "
            "low-pass the record with [excitation] smoothing_hz")


def recorded_table(times: np.ndarray, values: np.ndarray, signal: str, *,
                   origin: float = 0.0, smoothing_hz: float = 0.0) -> TableMotion:
    """C^4 table motion from samples; ``signal`` is "displacement" [m] or "acceleration" [m/s^2].

    The table runs on the time axis ``t - origin`` (default: the record's own
    axis); the spline is built on ``times - times[0]`` (exact in floating
    point), so with ``origin`` near the record a file stamped with epoch times
    (1.7e9 s + t) is as precise as one starting at 0. Stamps within 4 ulp of a
    uniform grid (rounded epoch times) are put back on that grid. ``smoothing_hz`` > 0 low-passes the samples first
    (:func:`smooth_record`).
    """
    times = np.asarray(times, dtype=float)
    first = float(times[0]) if times.size else 0.0
    rel = times - first
    if rel.size > 2:
        # a uniformly sampled record whose stamps were rounded (epoch times 1.7e9 s + t
        # carry 2.4e-7 s of rounding): back onto its uniform grid
        grid = np.arange(rel.size) * (rel[-1] / (rel.size - 1))
        if np.max(np.abs(rel - grid)) <= 4.0 * np.spacing(max(abs(first), abs(times[-1]))):
            rel = grid
    if smoothing_hz > 0.0 and times.size >= 6:
        values = smooth_record(rel, np.asarray(values, dtype=float), smoothing_hz)
    elif signal == "displacement":
        check_glitches(times, np.asarray(values, dtype=float))
    table = _recorded_table(rel, values, signal)
    shift = first - float(origin)
    if shift == 0.0:
        return table
    import dataclasses
    x = table.breaks + shift
    return dataclasses.replace(table, breaks=x, t_first=float(x[0]), t_last=float(x[-1]))


def _recorded_table(times: np.ndarray, values: np.ndarray, signal: str) -> TableMotion:
    """C^4 table motion from samples; ``signal`` is "displacement" [m] or "acceleration" [m/s^2]."""
    from scipy.interpolate import PPoly, make_interp_spline

    t = np.asarray(times, dtype=float)
    v = np.asarray(values, dtype=float)
    if t.size < 6:
        raise DynamicsError(f"recorded excitation: {t.size} samples; a C^4 table motion needs >= 6")
    if signal == "displacement":
        pp = PPoly.from_spline(make_interp_spline(t, v, k=5))
    elif signal == "acceleration":
        acc = PPoly.from_spline(make_interp_spline(t, v - v.mean(), k=3))
        pp = acc.antiderivative(2)
        # remove the straight line (unknown initial position/velocity) fitted to y
        y = pp(t)
        slope, intercept = np.polyfit(t - t[0], y, 1)
        pp.c[-1] -= intercept + slope * (pp.x[:-1] - t[0])
        pp.c[-2] -= slope
    else:
        raise DynamicsError(f"recorded excitation: signal = {signal!r}; allowed 'displacement', "
                            "'acceleration'")
    # keep only the pieces inside the record (make_interp_spline adds none, but be explicit)
    x = np.ascontiguousarray(pp.x, dtype=float)
    c = np.ascontiguousarray(pp.c, dtype=float)
    if c.shape[0] < 6:  # pad to degree 5
        c = np.vstack([np.zeros((6 - c.shape[0], c.shape[1])), c])
    widths = np.diff(x)
    d2 = np.stack([(5 - m) * (4 - m) * c[m] for m in range(4)])           # degree 3
    d3 = np.stack([(5 - m) * (4 - m) * (3 - m) * c[m] for m in range(3)])  # degree 2
    d4 = np.stack([(5 - m) * (4 - m) * (3 - m) * (2 - m) * c[m] for m in range(2)])
    return TableMotion(kind=PPOLY, params=np.zeros(3), breaks=x, coeffs=c,
                       acc_bound=_piece_bound(d2, widths), jerk_bound=_piece_bound(d3, widths),
                       snap_bound=_piece_bound(d4, widths), t_first=float(x[0]),
                       t_last=float(x[-1]))

