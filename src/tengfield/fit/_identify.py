"""Uncertainty and identifiability at the optimum: covariance ``s² (JᵀJ)⁻¹``, standard
errors, correlations and the notes on what the data cannot determine; the Δχ² profile of
a poorly determined parameter (continuation along a grid, the others re-optimised)."""
from __future__ import annotations

import math

import numpy as np

from ._problem import _best_charge_scale, _optimise, _Problem, _Space
from .spec import FitSpec
from ..scene.schema import SURFACE_CHARGE_KEY

#: |correlation| above which two parameters are reported as not separately identifiable
NOT_SEPARABLE = 0.995
#: |correlation| above which a pair is reported as strongly correlated
STRONGLY_CORRELATED = 0.95
#: normalised-Jacobian singular-value ratio below which the data are degenerate
DEGENERATE = 1e-6


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
                if {names[i], names[j]} == {SURFACE_CHARGE_KEY, "parallel_capacitance_pF"}:
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
