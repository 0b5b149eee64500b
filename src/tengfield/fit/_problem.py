"""The problem of one fit: normalised parameter coordinates (:class:`_Space`), the
weighted residuals and their Jacobian (:class:`_Problem`, σ's column exact), the bounded
least-squares call and the closed-form best charge scale (docs/fit.md)."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from ._model import ForwardModel
from .spec import FitSpec, Parameter
from ..scene.schema import SURFACE_CHARGE_KEY


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
            if name == SURFACE_CHARGE_KEY:
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


def _best_charge_scale(problem: _Problem, u) -> np.ndarray:
    """``u`` with σ (if free) set to its least-squares value at the other parameters
    (closed form: the residual is affine in σ)."""
    name = SURFACE_CHARGE_KEY
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
