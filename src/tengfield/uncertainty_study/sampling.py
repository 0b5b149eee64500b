"""The study's points: unit-cube samples (SALib's Saltelli scheme on a scrambled Sobol
sequence, or a scrambled Sobol sequence of scipy.stats.qmc for Monte Carlo) turned into
input values by each distribution's inverse CDF.

Sobol indices do not change under a monotone map of each input, so the Saltelli matrices
are drawn on [0, 1]^D and mapped afterwards; the order of the rows is SALib's (A, AB_1 ..
AB_D, B per base sample), which :func:`tengfield.uncertainty_study.statistics.sobol_indices`
expects back.
"""
from __future__ import annotations

import warnings

import numpy as np

from .spec import TAIL, UncertaintySpec


def unit_samples(spec: UncertaintySpec) -> np.ndarray:
    """``(evaluations, D)`` points in (0, 1)^D for ``spec`` (same seed: same points)."""
    d = len(spec.inputs)
    if spec.method == "sobol":
        from SALib.sample import sobol as saltelli

        problem = {"num_vars": d, "names": spec.keys, "bounds": [[0.0, 1.0]] * d}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # SALib's notes on skip_values, pandas' FutureWarning
            return np.asarray(saltelli.sample(problem, spec.samples, calc_second_order=False,
                                              scramble=True, seed=spec.seed), dtype=float)
    from scipy.stats import qmc

    sampler = qmc.Sobol(d=d, scramble=True, seed=spec.seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # "balance properties" for a count not a power of 2
        return np.asarray(sampler.random(spec.samples), dtype=float)


def unit_range(dist) -> tuple[float, float]:
    """The probabilities a draw of ``dist`` is clipped to: the TAIL quantiles the spec
    checked against the key's range for normal and lognormal (a scrambled Sobol point in
    the first 1e-6 stratum drew parallel_capacitance_pF = -11.1: issue #43.12), (1e-12,
    1 - 1e-12) for the bounded distributions (their ends are their checked support)."""
    if dist.kind in ("normal", "lognormal"):
        return TAIL, 1.0 - TAIL
    return 1e-12, 1.0 - 1e-12


def input_values(spec: UncertaintySpec, unit: np.ndarray) -> np.ndarray:
    """The input values (file units) at the unit-cube points ``unit``, one column per
    input; each rounded to 12 significant digits so that the CSV, the scene built from
    it and a re-read give the same number."""
    unit = np.asarray(unit, dtype=float)
    columns = [dist.ppf(np.clip(unit[:, j], *unit_range(dist)))
               for j, dist in enumerate(spec.inputs)]
    values = np.column_stack(columns) if columns else np.empty((len(unit), 0))
    return np.vectorize(lambda x: float(f"{x:.12g}"))(values) if values.size else values


def study_values(spec: UncertaintySpec) -> np.ndarray:
    """The values of every evaluation of the study, ``(evaluations, D)``, file units."""
    return input_values(spec, unit_samples(spec))
