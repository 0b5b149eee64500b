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
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from ..errors import TengfieldError
from ._model import ForwardModel
from .spec import PARAMETERS, FitSpec, Parameter, Target, Trace

#: |correlation| above which two parameters are reported as not separately identifiable
NOT_SEPARABLE = 0.995
#: |correlation| above which a pair is reported as strongly correlated
STRONGLY_CORRELATED = 0.95
#: normalised-Jacobian singular-value ratio below which the data are degenerate
DEGENERATE = 1e-6


class FitError(TengfieldError, RuntimeError):
    """The fit could not be carried out (e.g. the model gives no signal)."""


@dataclass
class FitResult:
    """Outcome of :func:`fit_trace` / :func:`fit_targets` (file units for parameters)."""
    mode: str                                   # "trace" or "targets"
    names: list[str]
    values: dict[str, float]
    start: dict[str, float]
    bounds: dict[str, tuple[float, float]]
    standard_errors: dict[str, float]
    correlation: np.ndarray
    identifiable: dict[str, bool]
    notes: list[str]
    residual_rms: dict[str, float]              # per column / target, SI
    chi2_reduced: float
    noise: dict[str, dict]                      # per column: value [SI] and "given"/"estimated"
    evaluations: int
    jacobian_evaluations: int
    dynamics_runs: int
    status: int
    message: str
    wall_time: float
    alignment: dict = field(default_factory=dict)
    profiles: dict = field(default_factory=dict)
    bootstrap: dict = field(default_factory=dict)
    measured: dict = field(default_factory=dict)    # plotting: time, values
    fitted: dict = field(default_factory=dict)
    loss: str = "linear"

    def as_dict(self) -> dict:
        """JSON-ready summary (fit.json)."""
        def finite(x):
            return None if x is None or not math.isfinite(x) else float(x)
        return {
            "mode": self.mode,
            "parameters": {n: {"value": self.values[n], "standard_error": finite(
                self.standard_errors[n]), "start": self.start[n], "min": self.bounds[n][0],
                "max": self.bounds[n][1], "identifiable": self.identifiable[n],
                "unit": PARAMETERS[n][2], "meaning": PARAMETERS[n][3]} for n in self.names},
            "correlation": {"names": self.names,
                            "matrix": [[finite(v) for v in row] for row in self.correlation]},
            "identifiability_notes": self.notes,
            "residual_rms": self.residual_rms,
            "chi2_reduced": finite(self.chi2_reduced),
            "noise": self.noise,
            "loss": self.loss,
            "iterations": {"function_evaluations": self.evaluations,
                           "jacobian_evaluations": self.jacobian_evaluations,
                           "dynamics_runs": self.dynamics_runs},
            "status": self.status, "message": self.message,
            "wall_time_s": self.wall_time,
            "alignment": self.alignment,
            "profiles": self.profiles,
            "bootstrap": self.bootstrap,
            "uncertainty_rule": "covariance s^2 (J^T J)^-1 at the optimum, J the Jacobian of the "
                                "weighted residuals; s^2 = reduced chi^2 when the noise is "
                                "estimated, max(1, reduced chi^2) when it is given; assumes "
                                "independent noise between samples",
        }


# ---------------------------------------------------------------------------
class _Space:
    """Normalised coordinates u <-> parameter values (file units)."""

    def __init__(self, params: list[Parameter]):
        self.params = params
        self.names = [p.name for p in params]
        self.log = np.array([p.transform == "log" for p in params])
        self.scale = np.array([1.0 if p.transform == "log" else (p.hi - p.lo) / 10.0
                               for p in params])
        self.origin = np.array([math.log10(p.lo) if p.transform == "log" else p.lo
                                for p in params])
        self.lower = self.to_u([p.lo for p in params])
        self.upper = self.to_u([p.hi for p in params])

    def to_u(self, values) -> np.ndarray:
        v = np.asarray(values, dtype=float)
        v = np.where(self.log, np.log10(np.where(self.log, v, 1.0)), v)
        return (v - self.origin) / self.scale

    def values(self, u) -> dict:
        v = self.origin + self.scale * np.asarray(u, dtype=float)
        v = np.where(self.log, 10.0 ** np.where(self.log, v, 0.0), v)
        return dict(zip(self.names, map(float, v)))

    def value_per_u(self, u) -> np.ndarray:
        """d(value)/du at ``u`` (for standard errors in file units)."""
        vals = np.array(list(self.values(u).values()))
        return np.where(self.log, vals * math.log(10.0), self.scale)


class _Problem:
    """Weighted residuals of one fit and their Jacobian."""

    def __init__(self, model: ForwardModel, space: _Space, residual, fixed: dict | None = None):
        self.model = model
        self.space = space
        self._residual = residual      # values -> weighted residual vector
        self.fixed = fixed or {}
        self.evaluations = 0
        self.jacobians = 0

    def values(self, u) -> dict:
        return {**self.fixed, **self.space.values(u)}

    def __call__(self, u) -> np.ndarray:
        self.evaluations += 1
        return self._residual(self.values(u))

    def jacobian(self, u) -> np.ndarray:
        self.jacobians += 1
        u = np.asarray(u, dtype=float)
        r0 = self._residual(self.values(u))
        J = np.empty((r0.size, u.size))
        h = 1e-4
        for k, name in enumerate(self.space.names):
            if name == "surface_charge_uC_per_m2":
                sigma = self.values(u)[name]
                if sigma != 0.0:
                    # exact: the model is linear in σ (peak values in |σ|), so the secant
                    # from σ = 0 is the derivative
                    zero = self._residual({**self.values(u), name: 0.0})
                    J[:, k] = (r0 - zero) / sigma * self.space.scale[k]
                    continue
            up, down = u.copy(), u.copy()
            step_up = min(h, self.space.upper[k] - u[k])
            step_down = min(h, u[k] - self.space.lower[k])
            up[k] += step_up
            down[k] -= step_down
            if step_up + step_down <= 0:
                J[:, k] = 0.0
                continue
            J[:, k] = (self._residual(self.values(up)) - self._residual(self.values(down))) \
                / (step_up + step_down)
        return J


def _optimise(problem: _Problem, u0, spec: FitSpec, max_nfev=None):
    return least_squares(problem, u0, jac=problem.jacobian,
                         bounds=(problem.space.lower, problem.space.upper),
                         loss=spec.loss, f_scale=spec.loss_scale, method="trf",
                         max_nfev=max_nfev or spec.max_evaluations, x_scale=1.0)


# ---------------------------------------------------------------------------
def _uncertainty(problem: _Problem, u, residual, noise_given: bool, loss: str):
    """(standard errors [file units], correlation, chi2_red, identifiable, notes)."""
    space = problem.space
    names = space.names
    J = problem.jacobian(u)
    n, p = J.shape
    dof = max(n - p, 1)
    if loss == "linear":
        chi2_red = float(residual @ residual) / dof
    else:   # robust: the MAD of the residuals, not their sum of squares
        chi2_red = float((1.4826 * np.median(np.abs(residual - np.median(residual)))) ** 2)
    s2 = max(1.0, chi2_red) if noise_given else chi2_red
    norms = np.linalg.norm(J, axis=0)
    notes: list[str] = []
    identifiable = {name: True for name in names}
    active = norms > 1e-12 * max(float(norms.max(initial=0.0)), 1e-300)
    for k in np.flatnonzero(~active):
        identifiable[names[k]] = False
        notes.append(f"{names[k]} has no effect on these data: it is not identifiable "
                     "(fix it, or measure a quantity it changes)")
    cov_u = np.full((p, p), np.nan)
    for k in np.flatnonzero(~active):
        cov_u[k, k] = np.inf
    if active.any():
        Jn = J[:, active] / norms[active]
        _, sv, vt = np.linalg.svd(Jn, full_matrices=False)
        ratio = sv[-1] / sv[0] if sv[0] > 0 else 0.0
        inv = np.where(sv > DEGENERATE * sv[0], 1.0 / np.maximum(sv, 1e-300) ** 2, np.inf)
        with np.errstate(invalid="ignore"):
            cov_n = (vt.T * inv) @ vt if np.all(np.isfinite(inv)) else \
                np.linalg.pinv(Jn.T @ Jn)
        idx = np.flatnonzero(active)
        cov_u[np.ix_(idx, idx)] = cov_n / np.outer(norms[active], norms[active]) * s2
        if ratio < DEGENERATE:
            involved = [names[idx[i]] for i in np.flatnonzero(np.abs(vt[-1]) > 0.2)]
            for name in involved:
                identifiable[name] = False
                cov_u[names.index(name), :] = np.nan
                cov_u[:, names.index(name)] = np.nan
                cov_u[names.index(name), names.index(name)] = np.inf
            notes.append(f"{', '.join(involved)}: the data are degenerate in this combination "
                         f"(normalised Jacobian condition {1 / max(ratio, 1e-300):.2g}); only a "
                         "combination is fixed")
    variance = np.diag(cov_u)
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.sqrt(variance)
        corr = cov_u / np.outer(sd, sd)
    np.fill_diagonal(corr, 1.0)
    standard_errors = dict(zip(names, map(float, sd * space.value_per_u(u))))
    for i in range(p):
        for j in range(i + 1, p):
            c = corr[i, j]
            if not math.isfinite(c):
                continue
            pair = f"{names[i]} and {names[j]}"
            if abs(c) > NOT_SEPARABLE:
                identifiable[names[i]] = identifiable[names[j]] = False
                hint = ""
                if {names[i], names[j]} == {"surface_charge_uC_per_m2", "parallel_capacitance_pF"}:
                    hint = (": a voltage read through C_p fixes only sigma / (C_T + C_p); "
                            "add a charge-mode (Q) trace or fix C_p")
                notes.append(f"{pair} are not separately identifiable from these data "
                             f"(correlation {c:+.5f}){hint or '; fix one of them or add data'}")
            elif abs(c) > STRONGLY_CORRELATED:
                notes.append(f"{pair} are strongly correlated ({c:+.3f}): their standard "
                             "errors are large together, their combination is better determined")
    if noise_given and chi2_red > 4.0 and n > p:
        notes.append(f"reduced chi^2 = {chi2_red:.3g} with the given noise levels: the data are "
                     "not consistent with the model at the fitted values (or "
                     "the noise is understated); standard errors are scaled by sqrt(chi^2)")
    for k, par in enumerate(space.params):
        se = standard_errors[par.name]
        if identifiable[par.name] and math.isfinite(se) and se > 0.25 * (par.hi - par.lo) \
                and par.transform == "linear":
            identifiable[par.name] = False
            notes.append(f"{par.name}: standard error {se:.3g} exceeds a quarter of its bounds "
                         f"[{par.lo:g}, {par.hi:g}]: poorly determined by these data")
    return standard_errors, corr, chi2_red, identifiable, notes


def _best_charge_scale(problem: _Problem, u) -> np.ndarray:
    """``u`` with σ (if free) set to its least-squares value at the other parameters
    (closed form: the residual is affine in σ)."""
    name = "surface_charge_uC_per_m2"
    space = problem.space
    if name not in space.names:
        return u
    values = problem.values(u)
    if values[name] == 0.0:
        return u
    r = problem._residual(values)
    r0 = problem._residual({**values, name: 0.0})
    m = r - r0
    mm = float(m @ m)
    if mm == 0.0:
        return u
    best = values[name] * -float(r0 @ m) / mm
    k = space.names.index(name)
    par = space.params[k]
    values = dict(space.values(u))
    values[name] = float(np.clip(best, par.lo, par.hi))
    return np.clip(space.to_u([values[n] for n in space.names]), space.lower, space.upper)


def _profile(problem: _Problem, u_best, spec: FitSpec, cost_best: float, s2: float,
             name: str, standard_error: float, points: int = 13,
             whole_range: bool = False) -> dict:
    """Δχ² = 2 (cost - cost_best) / s² along ``name``, the others re-optimised.

    The grid spans ±3 standard errors, or the whole bounds (``whole_range``, for a
    parameter the data do not identify; geometric for a non-negative one)."""
    space = problem.space
    k = space.names.index(name)
    par = space.params[k]
    scale = space.value_per_u(u_best)[k]
    half = 3.0 * standard_error / scale if math.isfinite(standard_error) and standard_error > 0 \
        else np.inf
    if whole_range or not math.isfinite(half):
        if par.transform == "linear" and par.lo >= 0.0 and par.hi > 0.0:
            # non-negative scale parameters (C_p): geometric grid, the decades matter
            values = np.concatenate([[par.lo], np.geomspace(max(par.lo, 1e-3 * par.hi),
                                                            par.hi, points - 1)])
            grid = space.to_u(np.where(np.arange(len(u_best))[:, None] == k, values[None, :],
                                       np.array(list(space.values(u_best).values()))[:, None]).T)[:, k]
        else:
            grid = np.linspace(space.lower[k], space.upper[k], points)
    else:
        grid = np.linspace(max(space.lower[k], u_best[k] - half),
                           min(space.upper[k], u_best[k] + half), points)
    others = [n for n in space.names if n != name]
    sub = _Space([p for p in space.params if p.name != name])
    # continuation: walk outwards from the optimum, each refit starting from its neighbour
    centre = int(np.argmin(np.abs(grid - u_best[k])))
    order = list(range(centre, -1, -1)) + list(range(centre + 1, grid.size))
    rows: list = [None] * grid.size
    u_prev = {}
    for i in order:
        value = space.values(np.where(np.arange(len(u_best)) == k, grid[i], u_best))[name]
        fixed = {**problem.fixed, name: value}
        if others:
            sub_problem = _Problem(problem.model, sub, problem._residual, fixed=fixed)
            neighbour = i + 1 if i < centre else i - 1
            u0 = u_prev.get(neighbour, np.delete(u_best, k))
            u0 = _best_charge_scale(sub_problem, np.clip(u0, sub.lower, sub.upper))
            res = _optimise(sub_problem, u0, spec, max_nfev=100)
            u_prev[i] = res.x
            cost = float(res.cost)
        else:
            r = problem._residual(fixed)
            cost = 0.5 * float(r @ r)
        rows[i] = {"value": value, "delta_chi2": 2.0 * (cost - cost_best) / s2}
    delta = np.array([r["delta_chi2"] for r in rows])
    values = np.array([r["value"] for r in rows])
    inside = values[delta <= 1.0]
    interval = [float(inside.min()), float(inside.max())] if inside.size else None
    open_ends = []
    if interval is not None:
        if delta[0] <= 1.0:
            open_ends.append("lower")
        if delta[-1] <= 1.0:
            open_ends.append("upper")
    flat = [side for side, a, b in (("lower", delta[0], delta[1]), ("upper", delta[-1], delta[-2]))
            if abs(a - b) < 1.0 and min(a, b) < 25.0]
    return {"points": rows, "interval_delta_chi2_le_1": interval,
            "open_ends": open_ends, "flat_towards": flat,
            "rule": "others re-optimised at each grid value; an open end (delta chi^2 <= 1 at the "
                    "scan's end) or a flat end (delta chi^2 changes by < 1 over the last grid "
                    "step) means the data do not bound the parameter on that side"}


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
    for k, par in enumerate(params):
        if par.lo < values[par.name] < par.hi:
            continue
        notes.append(f"{par.name} = {values[par.name]:.6g} sits on its bound "
                     f"[{par.lo:g}, {par.hi:g}]: widen the bound or check the model")
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
        start, scan = _start_scan(model, trace, params, start, weights, quantities)
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
    _explained_note(result, trace, spec.loss)
    if spec.bootstrap:
        result.bootstrap = _bootstrap(problem, res.x, residual, result.fitted, trace, spec,
                                      progress=progress)
    result.wall_time = time.perf_counter() - t0
    return result


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
    reasons = []
    for c in trace.columns:
        y = trace.values[c.quantity]
        pp = float(np.ptp(y))
        level = float(np.max(np.abs(y)))
        if pp <= 64 * np.spacing(level) or pp == 0.0:
            reasons.append(f"{c.quantity} (column {c.column!r}) is constant "
                           f"({y[0] / c.factor:g} {c.unit})")
        elif c.noise is not None and pp < NO_SIGNAL_NOISE_FACTOR * c.noise:
            reasons.append(f"{c.quantity} (column {c.column!r}) has peak-to-peak "
                           f"{pp / c.factor:.3g} {c.unit}, below {NO_SIGNAL_NOISE_FACTOR:g} x "
                           f"its noise {c.noise / c.factor:.3g} {c.unit}")
        else:
            return
    raise FitError(f"--measured {trace.source!r} carries no signal to fit: "
                   + "; ".join(reasons) + " (check the column names and the recording)")


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


def _bootstrap(problem: _Problem, u_best, residual, fitted: dict, trace: Trace,
               spec: FitSpec, seed: int = 12345, progress: bool = False) -> dict:
    """Moving-block residual bootstrap: ``spec.bootstrap`` refits (from the optimum, no
    scan) to fitted + residuals resampled in blocks of a quarter period (keeps the
    correlation of hum and drift within a block). Standard deviation and 16/84 %
    percentiles per parameter (file units)."""
    rng = np.random.default_rng(seed)
    period = problem.model.scene.excitation.period
    n = trace.time.size
    step = float(np.median(np.diff(trace.time)))
    block = int(min(max(1, round(0.25 * period / step)), max(1, n // 4)))
    resid = {q: trace.values[q] - fitted[q] for q in fitted}
    import sys

    from tqdm import tqdm

    samples = []
    for _ in tqdm(range(spec.bootstrap), desc="bootstrap", unit="refit", file=sys.stderr,
                  disable=not (progress and sys.stderr.isatty())):
        starts = rng.integers(0, n - block + 1, size=int(np.ceil(n / block)))
        index = (starts[:, None] + np.arange(block)[None, :]).ravel()[:n]
        data = {q: fitted[q] + resid[q][index] for q in fitted}
        replica = _Problem(problem.model, problem.space, lambda v, d=data: residual(v, d))
        samples.append(_optimise(replica, u_best, spec).x)
    values = np.array([list(problem.space.values(u).values()) for u in samples])
    out = {"replicas": spec.bootstrap, "block_samples": block,
           "rule": "moving-block residual bootstrap, blocks of a quarter period, refits "
                   "started at the optimum"}
    for k, name in enumerate(problem.space.names):
        col = values[:, k]
        out[name] = {"standard_deviation": float(np.std(col, ddof=1)) if col.size > 1 else None,
                     "p16": float(np.percentile(col, 16)), "p84": float(np.percentile(col, 84))}
    return out


#: grid sizes of the start scan over the parameters that change the dynamics
SCAN_POINTS = {"restitution": 13, "amplitude_scale": 9}


def _start_scan(model, trace, params, start, weights, quantities, candidates: int = 240):
    """Start values from a scan: the time shift over its bounds (a least-squares
    cross-correlation with the best common charge scale when σ is free) for every
    point of a coarse grid of the restitution / amplitude scale (the impact map has
    local minima there), keeping the best. Returns (start, description)."""
    by_name = {p.name: p for p in params}
    shift = by_name.get("time_shift_s")
    scan_shift = shift is not None and not shift.start_given
    sigma = by_name.get("surface_charge_uC_per_m2")
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
    for combo in combos:
        values = {p.name: start[p.name] for p in params if p.name != "time_shift_s"}
        values.update(combo)
        try:
            dense = model.waveforms(values, grid, quantities)
        except TengfieldError:
            continue
        for s in shifts:
            f = {q: np.interp(model.window_start + s + t_rel, grid, dense[q]) / weights[q]
                 for q in quantities}
            mf = sum(float(measured[q] @ f[q]) for q in quantities)
            ff = sum(float(f[q] @ f[q]) for q in quantities)
            a = (mf / ff if ff > 0 else 1.0) if sigma is not None else 1.0
            score = sum(float(np.sum((measured[q] - a * f[q]) ** 2)) for q in quantities)
            if score < best[0]:
                best = (score, combo, float(s), a)
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

    def residual_parts(values):
        scalars = model.scalars(values)
        return {t.label: float(scalars[t.key] - t.value) for t in targets}

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
    result.wall_time = time.perf_counter() - t0
    return result
