"""Checks of a measured trace and of a fit's residual: a trace without a signal is refused,
a residual as large as the signal is noted (and warned about)."""
from __future__ import annotations

import numpy as np

from .result import FitError, FitResult
from .spec import Trace

#: a column whose peak-to-peak is below this many noise levels carries no signal
NO_SIGNAL_NOISE_FACTOR = 2.0
#: residual RMS / signal RMS (about its mean) above which the fit explains nothing useful
RESIDUAL_AS_LARGE_AS_SIGNAL = 0.9


def _check_signal(trace: Trace) -> None:
    """FitError when no measured column carries a signal: constant (peak-to-peak 0 or at
    round-off of its level) or, with a given noise level, below twice that noise. A fit to
    it reported σ as identifiable with χ²/ν ≈ 1 (issue #21)."""
    from .spec import MAX_TRACE_VALUE

    for c in trace.columns:
        y = trace.values[c.quantity]
        limit = MAX_TRACE_VALUE[c.quantity]
        if not np.all(np.isfinite(y)) or float(np.max(np.abs(y))) > limit:
            raise FitError(f"{trace.source!r}: {c.quantity} reaches {float(np.max(np.abs(y))):.3g} "
                           f"(SI): allowed |x| <= {limit:g} (check the column's unit)")
    reasons, constant, signal = [], [], []
    for c in trace.columns:
        y = trace.values[c.quantity]
        pp = float(np.ptp(y))
        level = float(np.max(np.abs(y)))
        if pp <= 64 * np.spacing(level) or pp == 0.0:
            reasons.append(f"{c.quantity} (column {c.column!r}) is constant "
                           f"({y[0] / c.factor:g} {c.unit})")
            constant.append(reasons[-1])
        elif c.noise is not None and pp < NO_SIGNAL_NOISE_FACTOR * c.noise:
            reasons.append(f"{c.quantity} (column {c.column!r}) has peak-to-peak "
                           f"{pp / c.factor:.3g} {c.unit}, below {NO_SIGNAL_NOISE_FACTOR:g} x "
                           f"its noise {c.noise / c.factor:.3g} {c.unit}")
        else:
            signal.append(c.column)
    if not signal:
        raise FitError(f"--measured {trace.source!r} carries no signal to fit: "
                       + "; ".join(reasons) + " (check the column names and the recording)")
    if constant:   # beside a signal it drags the fit to zero charge and weights the rest out
        raise FitError(f"--measured {trace.source!r}: " + "; ".join(constant)
                       + ": a flat column has no waveform to fit (a probe not connected?); "
                       "list only the columns with a signal in [fit.columns] ("
                       + ", ".join(map(repr, signal)) + ")")


def _explained_note(result: FitResult, trace: Trace, loss: str = "linear") -> None:
    """A note (and a warning) when the residual is about as large as the signal: the fitted
    values then describe noise, or the model/units do not match the data. Robust losses
    compare robust spreads (1.4826 x MAD), so a few outliers do not trigger it."""
    import warnings

    poor = []
    for c in trace.columns:
        y = trace.values[c.quantity]
        r = y - np.asarray(result.fitted[c.quantity])
        if loss == "linear":
            signal = float(np.std(y))
            rms = float(np.sqrt(np.mean(r ** 2)))
        else:
            signal = float(1.4826 * np.median(np.abs(y - np.median(y))))
            rms = float(1.4826 * np.median(np.abs(r - np.median(r))))
        if signal > 0 and rms >= RESIDUAL_AS_LARGE_AS_SIGNAL * signal:
            poor.append(f"{c.quantity}: residual RMS {rms:.3g} vs signal RMS {signal:.3g} (SI)")
    if len(poor) == len(trace.columns) and poor:
        note = ("the residual is as large as the signal (" + "; ".join(poor) + "): the model "
                "does not explain these data, so the fitted values and their errors describe "
                "noise or a mismatch; check the columns' units, the scene (excitation, "
                "regime) and the parameter bounds")
        result.notes.append(note)
        for name in result.names:
            result.identifiable[name] = False
        warnings.warn(f"fit: {note}", stacklevel=2)
