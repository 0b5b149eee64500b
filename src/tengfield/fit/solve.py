"""Least-squares calibration of a scene to a measured trace or to scalar targets.

Method (docs/fit.md): ``scipy.optimize.least_squares`` (trust-region
reflective, bounds) on weighted residuals ``(model - measured) / noise`` in
normalised coordinates (linear parameters scaled by a tenth of their bounds'
width, ``load_ohm`` in decades). The Jacobian is central differences except
for σ, whose column is exact (the model is linear in σ). The time shift starts
from a scan of one cross-correlation-like score over its bounds (with the best
common σ scale), so the phase does not get stuck in a local minimum.

Uncertainty: covariance ``s² (JᵀJ)⁻¹`` at the optimum (s² = reduced χ² when no
noise level is given, else max(1, reduced χ²)); standard errors, the
correlation matrix, and identifiability notes from the column-normalised
Jacobian (a parameter with no effect, pairs with |correlation| > 0.995, a
near-null direction). ``profile`` re-optimises the others along a grid of
each poorly determined parameter and reports the Δχ² ≤ 1 interval.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ._bootstrap import _bootstrap
from ._identify import _profile, _uncertainty
from ._model import ForwardModel
from ._problem import _optimise, _Problem, _Space
from ._residuals import bound_notes, on_bound, target_residuals, trace_residuals
from ._scan import SCAN_POINTS, _start_scan
from ._signal import _check_signal, _explained_note
from .compared import compared
from .result import FitError, FitResult
from .spec import FitSpec, Target, Trace


# ---------------------------------------------------------------------------
def _finish(mode, problem, res, spec, params, start, residual_parts, noise, noise_given,
            t0, alignment) -> FitResult:
    u = res.x
    standard_errors, corr, chi2_red, identifiable, notes = _uncertainty(
        problem, u, res.fun, noise_given, spec.loss)
    values = problem.space.values(u)
    profiles = {}
    if spec.profile:
        s2 = max(1.0, chi2_red) if noise_given else chi2_red
        for name in problem.space.names:
            if not identifiable[name] or not math.isfinite(standard_errors[name]):
                profiles[name] = _profile(problem, u, spec, float(res.cost), max(s2, 1e-300),
                                          name, standard_errors[name], whole_range=True)
    return FitResult(
        mode=mode, names=problem.space.names, values=values, start=start,
        bounds={p.name: (p.lo, p.hi) for p in params}, standard_errors=standard_errors,
        correlation=corr, identifiable=identifiable, notes=notes,
        residual_rms=residual_parts(values), chi2_reduced=chi2_red, noise=noise,
        evaluations=problem.evaluations, jacobian_evaluations=problem.jacobians,
        dynamics_runs=problem.model.dynamics_runs, status=int(res.status),
        message=str(res.message), wall_time=time.perf_counter() - t0, alignment=alignment,
        profiles=profiles, loss=spec.loss)


def fit_trace(scene, curves, reference_sigma: float, trace: Trace, spec: FitSpec, *,
              simulate=None, progress: bool = False) -> FitResult:
    """Fit ``spec.parameters`` of ``scene`` to a measured ``trace``.

    ``curves`` is the surrogate's ``TerminalCurves`` at surface charge
    ``reference_sigma`` [C/m²] (reused for every σ).
    """
    t0 = time.perf_counter()
    params = spec.parameters
    if not params:
        raise FitError("no free parameters: list some in [fit.parameters]")
    if trace.time.size <= len(params):
        raise FitError(f"{trace.time.size} samples cannot fix {len(params)} parameters")
    shift_param = next((p for p in params if p.name == "time_shift_s"), None)
    max_shift = shift_param.hi if shift_param else 0.0
    if shift_param and shift_param.lo < -scene.run.settle_periods * scene.excitation.period:
        raise FitError(f"[fit.parameters] time_shift_s.min = {shift_param.lo:g} reaches before "
                       "the start of the dynamics: allowed >= -settle_periods / frequency_hz")
    model = ForwardModel(scene, curves, reference_sigma, span=trace.span + max(max_shift, 0.0),
                         simulate=simulate)
    quantities = [c.quantity for c in trace.columns]
    _check_signal(trace)
    weights = {c.quantity: c.noise for c in trace.columns}
    for q in quantities:       # a provisional scale for the columns without a noise level
        if weights[q] is None:
            y = trace.values[q]
            weights[q] = float(np.std(y)) or float(np.max(np.abs(y))) or 1.0

    start = {p.name: p.start for p in params}
    alignment = {}
    fixed_shift = 0.0
    if shift_param is None:
        alignment = {"rule": "no time shift fitted: the trace's first sample is the "
                             "steady-window start"}
    if (shift_param is not None and not shift_param.start_given) or \
            any(p.name in SCAN_POINTS for p in params):
        start, scan = _start_scan(model, trace, params, start, weights, quantities,
                                  progress=progress)
        alignment.update(scan)

    def residual(values, data=None):
        data = trace.values if data is None else data
        shift = values.get("time_shift_s", fixed_shift)
        wave = model.waveforms(values, model.model_times(trace.time, shift), quantities)
        return np.concatenate([(wave[q] - data[q]) / weights[q] for q in quantities])

    space = _Space(params)
    problem = _Problem(model, space, residual)
    u0 = np.clip(space.to_u([start[p.name] for p in params]), space.lower, space.upper)
    at_start = model.waveforms(problem.values(u0), model.model_times(
        trace.time, problem.values(u0).get("time_shift_s", fixed_shift)), quantities)
    if not any(np.any(at_start[q] != 0.0) for q in quantities):
        raise FitError("the model gives no signal at the start values (ball at rest or "
                       "zero charge): change the start values or the scene")
    res = _optimise(problem, u0, spec)
    noise = {}
    estimated = [q for q in quantities if next(c for c in trace.columns
                                                if c.quantity == q).noise is None]
    if estimated:   # reweight: a column's noise is its residual RMS, refit from the optimum
        values = problem.values(res.x)
        wave = model.waveforms(values, model.model_times(
            trace.time, values.get("time_shift_s", fixed_shift)), quantities)
        for q in estimated:
            rms = float(np.sqrt(np.mean((wave[q] - trace.values[q]) ** 2)))
            weights[q] = rms if rms > 0 else weights[q]
        res = _optimise(problem, res.x, spec)
    for q in quantities:
        noise[q] = {"value_SI": weights[q], "how": "estimated from the residuals"
                    if q in estimated else "given in [fit.columns]"}

    def residual_parts(values):
        shift = values.get("time_shift_s", fixed_shift)
        wave = model.waveforms(values, model.model_times(trace.time, shift), quantities)
        return {q: float(np.sqrt(np.mean((wave[q] - trace.values[q]) ** 2))) for q in quantities}

    result = _finish("trace", problem, res, spec, params, start, residual_parts, noise,
                     not estimated, t0, alignment)
    shift = result.values.get("time_shift_s", fixed_shift)
    result.measured = {"time": trace.time, **trace.values,
                       "units": {c.quantity: c.unit for c in trace.columns}}
    result.fitted = model.waveforms(result.values, model.model_times(trace.time, shift),
                                    quantities)
    c_p, _ = model.circuit(result.values)
    result.residuals = trace_residuals(trace, result.fitted, {
        c.quantity: compared(c.quantity, "", scene, c_p) for c in trace.columns})
    from ..dynamics.excitation import excitation_kind

    periodic = excitation_kind(scene).periodic
    bound_notes(result, on_bound(problem.space, res.x),
                period=scene.excitation.period if periodic else None)
    _explained_note(result, trace, spec.loss)
    if spec.bootstrap:
        result.bootstrap = _bootstrap(problem, res.x, residual, result.fitted, trace, spec,
                                      progress=progress)
    result.wall_time = time.perf_counter() - t0
    return result


def fit_targets(scene, curves, reference_sigma: float, targets: list[Target], spec: FitSpec, *,
                simulate=None) -> FitResult:
    """Fit ``spec.parameters`` to scalar targets (peak-to-peak / peak of V, Q, I over the
    steady window of ``scene``)."""
    t0 = time.perf_counter()
    params = [p for p in spec.parameters]
    if any(p.name == "time_shift_s" for p in params):
        raise FitError("time_shift_s needs a measured trace: scalar targets have no phase; "
                       "drop it from the free parameters")
    if not params:
        raise FitError("no free parameters: list some in [fit.parameters] or --free")
    period = scene.excitation.period
    span = max(scene.run.duration - scene.run.settle_periods * period, 5.0 * period)
    model = ForwardModel(scene, curves, reference_sigma, span=span - period, simulate=simulate)

    def residual(values):
        scalars = model.scalars(values)
        return np.array([(scalars[t.key] - t.value) / t.uncertainty for t in targets])

    space = _Space(params)
    problem = _Problem(model, space, residual)
    start = {p.name: p.start for p in params}
    u0 = np.clip(space.to_u([start[p.name] for p in params]), space.lower, space.upper)
    res = _optimise(problem, u0, spec)

    def residual_parts(values):   # |fitted - measured| [SI]: one number's RMS
        scalars = model.scalars(values)
        return {t.label: abs(float(scalars[t.key] - t.value)) for t in targets}

    noise = {t.label: {"value_SI": t.uncertainty, "relative": t.uncertainty / t.value,
                       "how": "given (+-)" if t.uncertainty_given
                       else "default: 5 % of the value"} for t in targets}
    result = _finish("targets", problem, res, spec, params, start, residual_parts, noise,
                     True, t0, {})
    if spec.bootstrap:
        result.notes.append("bootstrap skipped: it resamples a trace's residuals, targets have "
                            "none (see the standard errors)")
    if len(targets) <= len(params):
        result.notes.append(f"{len(targets)} targets for {len(params)} parameters: no degrees "
                            "of freedom left, the residual says nothing about the model's error")
    scalars = model.scalars(result.values)
    result.measured = {t.label: t.value / t.factor for t in targets}
    result.fitted = {t.label: scalars[t.key] / t.factor for t in targets}
    c_p, _ = model.circuit(result.values)
    result.residuals = target_residuals(targets, scalars, {
        t.label: compared(t.quantity, t.statistic, scene, c_p) for t in targets})
    bound_notes(result, on_bound(problem.space, res.x))
    result.wall_time = time.perf_counter() - t0
    return result
