"""Start values of a trace fit from a scan: the time shift (cross-correlation-like score with
the best common charge scale) over a coarse grid of the restitution / amplitude scale."""
from __future__ import annotations

import math

import numpy as np

from ..errors import TengfieldError
from ..scene.schema import SURFACE_CHARGE_KEY

#: grid sizes of the start scan over the parameters that change the dynamics
SCAN_POINTS = {"restitution": 13, "amplitude_scale": 9}


def _start_scan(model, trace, params, start, weights, quantities, candidates: int = 240,
                progress: bool = False):
    """Start values from a scan: the time shift over its bounds (a least-squares
    cross-correlation with the best common charge scale when σ is free) for every
    point of a coarse grid of the restitution / amplitude scale (the impact map has
    local minima there), keeping the best. Returns (start, description). ``progress``:
    a bar over the grid's points on a terminal (:func:`tengfield._console.progress_bar`)."""
    from .._console import progress_bar

    by_name = {p.name: p for p in params}
    shift = by_name.get("time_shift_s")
    scan_shift = shift is not None and not shift.start_given
    sigma = by_name.get(SURFACE_CHARGE_KEY)
    grids = []
    for name, points in SCAN_POINTS.items():
        if name in by_name:
            p = by_name[name]
            grids.append((name, np.unique(np.append(np.linspace(p.lo, p.hi, points), start[name]))))
    combos = [dict()]
    for name, values in grids:
        combos = [{**c, name: float(v)} for c in combos for v in values]
    period = model.scene.excitation.period
    step = min(float(np.median(np.diff(trace.time))), period / 200.0)
    lo, hi = (shift.lo, shift.hi) if scan_shift else ((start.get("time_shift_s", 0.0),) * 2)
    shifts = np.linspace(lo, hi, candidates) if scan_shift else np.array([lo])
    grid = model.window_start + lo + np.arange(0.0, trace.span + (hi - lo) + step, step)
    pick = np.linspace(0, trace.time.size - 1, min(trace.time.size, 2000)).round().astype(int)
    t_rel = trace.time[pick] - trace.time[0]
    measured = {q: trace.values[q][pick] / weights[q] for q in quantities}
    best = (math.inf, None, None, None)
    bar = progress_bar(len(combos), "fit start scan", progress, unit="point")
    for combo in combos:
        values = {p.name: start[p.name] for p in params if p.name != "time_shift_s"}
        values.update(combo)
        try:
            dense = model.waveforms(values, grid, quantities)
        except TengfieldError:
            continue
        finally:
            bar.update(1)
        for s in shifts:
            f = {q: np.interp(model.window_start + s + t_rel, grid, dense[q]) / weights[q]
                 for q in quantities}
            mf = sum(float(measured[q] @ f[q]) for q in quantities)
            ff = sum(float(f[q] @ f[q]) for q in quantities)
            a = (mf / ff if ff > 0 else 1.0) if sigma is not None else 1.0
            score = sum(float(np.sum((measured[q] - a * f[q]) ** 2)) for q in quantities)
            if score < best[0]:
                best = (score, combo, float(s), a)
    bar.close()
    if best[1] is None:
        return start, {"rule": "start scan failed: the given start values are used"}
    _, combo, s, a = best
    out = {**start, **combo}
    note = {"rule": f"least-squares scan at the start values: {len(shifts)} time shifts in "
                    f"[{lo:g}, {hi:g}] s" + (" x " + " x ".join(
                        f"{len(v)} {n}" for n, v in grids) if grids else "")
                    + (", best common charge scale" if sigma is not None else "")}
    if scan_shift:
        out["time_shift_s"] = s
        note["time_shift_start_s"] = s
    for name in combo:
        note[f"{name}_start"] = combo[name]
    if sigma is not None and a != 0:
        out[sigma.name] = float(np.clip(start[sigma.name] * a, sigma.lo, sigma.hi))
        note["surface_charge_start_uC_per_m2"] = out[sigma.name]
    return out, note
