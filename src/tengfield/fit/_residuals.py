"""What a fit missed, in the data's own units and as a percentage (never a signed SI
"RMS"), parameters that end on a bound, and the warnings both give (issue #28, #30.3).

* :func:`trace_residuals`: per measured column, the residual RMS in the column's unit
  and as a % of the measured signal's RMS (about its mean);
* :func:`target_residuals`: per scalar target, measured and fitted in the target's
  unit, their difference and the difference as a % of the measured value;
* :func:`on_bound`: the parameters within ``BOUND_TOLERANCE`` of their bounds' width
  of a bound (the optimiser stops ~1e-9 inside: a strict ``lo < v < hi`` never fired);
* :func:`bound_notes`: their notes, and one warning when the residual is also large.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

from .spec import UNITS

#: a parameter this fraction of its bounds' width (normalised coordinates: decades for
#: load_ohm) from a bound sits on it
BOUND_TOLERANCE = 1e-4
#: a trace's residual RMS above this fraction of the signal RMS is large
LARGE_TRACE_RESIDUAL = 0.1
#: a target missed by more than this many of its uncertainties is missed by a lot
LARGE_TARGET_MISS = 2.0


def display_unit(quantity: str, unit: str, magnitude: float) -> str:
    """``unit`` as given, except the SI base unit of a run's CSV (V, C, A), replaced by the
    largest unit of :data:`UNITS` not above ``magnitude`` (3e-10 C -> pC)."""
    units = UNITS[quantity]
    if units.get(unit) != 1.0 or not math.isfinite(magnitude) or magnitude <= 0:
        return unit
    fitting = [u for u, f in sorted(units.items(), key=lambda kv: kv[1]) if f <= magnitude]
    return fitting[-1] if fitting else min(units, key=units.get)


def trace_residuals(trace, fitted: dict, tools: dict | None = None) -> dict:
    """``{quantity: {unit, residual_rms, signal_rms, percent_of_signal_rms, column}}``, with
    ``tools[quantity]`` (:func:`tengfield.fit.compared.compared`: the tool quantity the
    column is compared with, its words and unit) merged in."""
    out = {}
    tools = tools or {}
    for c in trace.columns:
        y = np.asarray(trace.values[c.quantity], dtype=float)
        rms = float(np.sqrt(np.mean((np.asarray(fitted[c.quantity]) - y) ** 2)))
        signal = float(np.std(y))
        unit = display_unit(c.quantity, c.unit, max(rms, signal))
        factor = UNITS[c.quantity][unit]
        out[c.quantity] = {"column": c.column, "unit": unit, "residual_rms": rms / factor,
                           "signal_rms": signal / factor,
                           # a flat column is refused before the fit (_check_signal)
                           "percent_of_signal_rms": 100.0 * rms / signal if signal > 0
                           else None, **tools.get(c.quantity, {})}
    return out


def target_residuals(targets, scalars: dict, tools: dict | None = None) -> dict:
    """``{label: {unit, measured, fitted, difference, percent, uncertainty}}`` (the
    target's unit; ``difference`` = fitted − measured), with ``tools[label]`` (the tool
    quantity the target is compared with: ``tool_key``, ``tool_label``, ``tool_unit``)."""
    out = {}
    tools = tools or {}
    for t in targets:
        fitted = float(scalars[t.key])
        out[t.label] = {**tools.get(t.label, {}), "unit": t.unit, "measured": t.value / t.factor,
                        "fitted": fitted / t.factor,
                        "difference": (fitted - t.value) / t.factor,
                        "percent": 100.0 * (fitted - t.value) / t.value,
                        "uncertainty": t.uncertainty / t.factor,
                        "misses_by_uncertainties": abs(fitted - t.value) / t.uncertainty}
    return out


def residual_lines(mode: str, residuals: dict) -> list[str]:
    """What ``tengfield fit`` prints for the residuals, one line per column / target."""
    def tool(r, before, after=""):   # the tool quantity compared with (tengfield.quantities)
        return f"{before}tool: {r['tool_label']}{after}" if r.get("tool_label") else ""

    if mode == "targets":
        return [f"{label}{tool(r, ' (', ')')}: measured "
                f"{r['measured']:.4g}, fitted {r['fitted']:.4g} {r['unit']} "
                f"({r['percent']:+.3g} %)" for label, r in residuals.items()]
    return [f"{q} (column {r['column']!r}{tool(r, '; ')}): residual RMS "
            f"{r['residual_rms']:.3g} {r['unit']} "
            + (f"= {r['percent_of_signal_rms']:.3g} % of " if r["percent_of_signal_rms"]
               is not None else "beside ")
            + f"the signal RMS {r['signal_rms']:.3g} {r['unit']}" for q, r in residuals.items()]


def large_residuals(mode: str, residuals: dict) -> list[str]:
    """The columns / targets the fit misses by a lot (empty: a good fit)."""
    if mode == "targets":
        return [f"{label} {r['percent']:+.3g} %" for label, r in residuals.items()
                if r["misses_by_uncertainties"] > LARGE_TARGET_MISS]
    return [f"{q} residual RMS {r['percent_of_signal_rms']:.3g} % of the signal RMS"
            for q, r in residuals.items()
            if (r["percent_of_signal_rms"] or 0.0) > 100.0 * LARGE_TRACE_RESIDUAL]


def on_bound(space, u) -> dict:
    """``{name: bound}`` of the parameters within :data:`BOUND_TOLERANCE` of a bound
    (measured in the normalised coordinates of ``space``)."""
    u = np.asarray(u, dtype=float)
    out = {}
    for k, par in enumerate(space.params):
        width = float(space.upper[k] - space.lower[k])
        tol = BOUND_TOLERANCE * width
        if u[k] - space.lower[k] <= tol:
            out[par.name] = par.lo
        elif space.upper[k] - u[k] <= tol:
            out[par.name] = par.hi
    return out


def bound_notes(result, bounds_hit: dict, period: float | None = None) -> None:
    """A note per parameter on its bound (``bounds_hit`` from :func:`on_bound`) and,
    when the residual is large too, one warning naming them. ``period`` [s]: the
    excitation's period when it is periodic; a ``time_shift_s`` whose bounds are at
    least a period apart wraps (a shift on a bound is the shift a whole number of
    periods inside): a note says so, no alarm."""
    if not bounds_hit:
        return
    named = []
    for name, bound in bounds_hit.items():
        lo, hi = result.bounds[name]
        if name == "time_shift_s" and period and hi - lo >= period * (1 - 1e-9):
            result.notes.append(f"time_shift_s = {result.values[name]:.6g} s is on its bound "
                                f"{bound:g} s of [{lo:g}, {hi:g}] s, which spans whole periods "
                                f"of the periodic excitation (T = {period:.6g} s): the shift "
                                "wraps (the same as a whole number of periods inside), "
                                "not a limit of the fit")
            continue
        named.append(f"{name} = {result.values[name]:.6g}")
        result.notes.append(f"{name} = {result.values[name]:.6g} sits on its bound {bound:g} "
                            f"(of [{lo:g}, {hi:g}]): the best value may lie outside; widen "
                            "the bound or check the model")
    large = large_residuals(result.mode, result.residuals)
    if large and named:
        warnings.warn(f"fit: {', '.join(named)} ended on {'its bound' if len(named) == 1 else 'their bounds'}"
                      f" and the fit misses the data ({'; '.join(large)}): widen the "
                      "bound in [fit.parameters] or check the model", RuntimeWarning,
                      stacklevel=3)
