"""Moving-block residual bootstrap of a trace fit (``[fit] bootstrap``)."""
from __future__ import annotations

import numpy as np

from ._problem import _optimise, _Problem
from .spec import FitSpec, Trace


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
    from .._console import progress_bar

    samples = []
    bar = progress_bar(spec.bootstrap, "bootstrap", progress, unit="refit")
    for _ in range(spec.bootstrap):
        starts = rng.integers(0, n - block + 1, size=int(np.ceil(n / block)))
        index = (starts[:, None] + np.arange(block)[None, :]).ravel()[:n]
        data = {q: fitted[q] + resid[q][index] for q in fitted}
        replica = _Problem(problem.model, problem.space, lambda v, d=data: residual(v, d))
        samples.append(_optimise(replica, u_best, spec).x)
        bar.update(1)
    bar.close()
    values = np.array([list(problem.space.values(u).values()) for u in samples])
    out = {"replicas": spec.bootstrap, "block_samples": block,
           "rule": "moving-block residual bootstrap, blocks of a quarter period, refits "
                   "started at the optimum"}
    for k, name in enumerate(problem.space.names):
        col = values[:, k]
        out[name] = {"standard_deviation": float(np.std(col, ddof=1)) if col.size > 1 else None,
                     "p16": float(np.percentile(col, 16)), "p84": float(np.percentile(col, 84))}
    return out
