"""Ensemble statistics over independent realisations (pure functions).

For N realisations x_1..x_N of one output (a peak-to-peak value, a mean power,
a regime fraction): the sample mean, the sample standard deviation (ddof = 1)
and the two-sided 95 % confidence interval of the mean from Student's t with
N - 1 degrees of freedom, ``mean +- t_{0.975, N-1} s / sqrt(N)``. The
interval's half-width shrinks as 1/sqrt(N). With N = 1 the spread is unknown
and reported as None. The fraction of realisations in a regime gets the exact
binomial (Clopper-Pearson) interval instead (:func:`fraction_statistics`).

The realisations are run by :func:`tengfield.pipeline.run` (``[run] realisations``,
:func:`tengfield.pipeline.run_ensemble`); this module gives their seeds, rows and
statistics.
"""
from __future__ import annotations

import math

import numpy as np

from .quantities import TERMINAL, column_name

CONFIDENCE = 0.95
#: a spread (sample standard deviation) at most this fraction of |mean| is round-off of
#: one value, not a spread of the realisations: such a quantity is reported as the same
#: in every realisation (its ``equal_within_round_off``), e.g. the ideal V_OC, which the
#: excitation's noise does not change (the ball reaches the same gaps)
ROUNDOFF_RELATIVE = 1e-9


def statistics(values) -> dict:
    """``{"n", "mean", "std", "ci95_low", "ci95_high", "ci95_half_width",
    "equal_within_round_off"}`` of ``values`` (NaN entries are left out and counted in
    ``"missing"``); ``equal_within_round_off``: the standard deviation is at most
    :data:`ROUNDOFF_RELATIVE` x |mean| (the values are one value up to round-off)."""
    x = np.asarray(values, dtype=float).ravel()
    finite = x[np.isfinite(x)]
    n = int(finite.size)
    out = {"n": n, "missing": int(x.size - n), "mean": None, "std": None,
           "ci95_low": None, "ci95_high": None, "ci95_half_width": None,
           "equal_within_round_off": False}
    if n == 0:
        return out
    mean = float(finite.mean())
    out["mean"] = mean
    if n < 2:
        return out
    from scipy.stats import t as student_t
    std = float(finite.std(ddof=1))
    half = float(student_t.ppf(0.5 + CONFIDENCE / 2.0, n - 1)) * std / math.sqrt(n)
    out.update(std=std, ci95_low=mean - half, ci95_high=mean + half, ci95_half_width=half,
               equal_within_round_off=bool(std <= ROUNDOFF_RELATIVE * abs(mean)))
    return out


def fraction_statistics(indicator) -> dict:
    """The keys of :func:`statistics` for the fraction of realisations in a regime
    (``indicator``: 1 in it, 0 not): ``mean`` k / N and the exact binomial
    (Clopper-Pearson) 95 % interval of the probability,
    ``[B(0.025; k, N - k + 1), B(0.975; k + 1, N - k)]`` (B: the beta distribution's
    quantile; 0 or 1 at k = 0 or N). It covers the probability at least 95 % of the
    time for every N and probability, and stays in [0, 1]; a Student interval of the
    0/1 values does neither (4 of 4 gave [1, 1]). It is not symmetric:
    ``ci95_half_width`` is half its length."""
    x = np.asarray(indicator, dtype=float).ravel()
    n = int(x.size)
    out = {"n": n, "missing": 0, "mean": None, "std": None,
           "ci95_low": None, "ci95_high": None, "ci95_half_width": None}
    if n == 0:
        return out
    from scipy.stats import beta

    k = int(np.count_nonzero(x))
    alpha = 1.0 - CONFIDENCE
    low = 0.0 if k == 0 else float(beta.ppf(alpha / 2.0, k, n - k + 1))
    high = 1.0 if k == n else float(beta.ppf(1.0 - alpha / 2.0, k + 1, n - k))
    out.update(mean=k / n, ci95_low=low, ci95_high=high, ci95_half_width=0.5 * (high - low))
    if n > 1:
        out["std"] = float(x.std(ddof=1))
    return out


def realisation_seeds(seed: int, count: int) -> list[int]:
    """Seeds of ``count`` realisations: ``seed + k`` (mod 2^32), k = 0..count-1.
    Realisation 0 is the scene's own run; numpy's generator hashes each seed through
    SeedSequence, so neighbouring integers give independent streams; N realisations
    are the first N of any larger ensemble."""
    return [(int(seed) + k) % 2**32 for k in range(int(count))]


#: columns of ensemble.csv (one row per realisation)
#: (the terminal ones named by :func:`tengfield.quantities.column_name`; ``V_read_*``
#: empty without an instrument)
ENSEMBLE_COLUMNS = (["realisation", "seed", "regime"]
                    + [column_name(n, "peak_to_peak") for n in TERMINAL]
                    + ["mean_power_W", "power_density_W_per_m3", "average_harvested_power_W",
                       "final_stored_energy_J", "array_value"]
                    + [column_name(n, stat) for stat, names in (
                        ("peak_to_peak", ("V_read_V",)), ("peak", (*TERMINAL, "V_read_V")))
                       for n in names])
#: the quantities whose statistics summary.json -> ensemble reports
QUANTITIES = ENSEMBLE_COLUMNS[3:]


def realisation_row(index: int, seed: int, summary: dict) -> dict:
    """One row of ensemble.csv from a run's summary (None where the circuit has no such
    number: no load, no rectifier). An ``[array]`` run reports its output as
    ``summary -> array -> array_value`` (what it is: ``compared``, e.g. the energy into
    the stores): the column ``array_value``."""
    p2p = summary["peak_to_peak"]
    load = summary.get("load") or {}
    rect = summary.get("rectifier") or {}
    regime = summary.get("regime") or {}
    arr = summary.get("array") or {}
    peak = summary.get("peak") or {}
    terminal = {column_name(n, stat): values.get(n)
                for stat, values in (("peak_to_peak", p2p), ("peak", peak))
                for n in (*TERMINAL, "V_read_V")}
    return {"realisation": index, "seed": seed, "regime": regime.get("regime", ""),
            **terminal,
            "mean_power_W": load.get("mean_power_W"),
            "power_density_W_per_m3": load.get("power_density_W_per_m3"),
            "average_harvested_power_W": rect.get("average_harvested_power_W"),
            "final_stored_energy_J": rect.get("final_stored_energy_J"),
            "array_value": arr.get("array_value"),
            "array_quantity": arr.get("compared")}


class EnsembleBlock(dict):
    """``summary.json -> ensemble`` (``RunResult.ensemble``): a dict, written as it is,
    that also keeps the realisations' ``rows`` (ensemble.csv's) for :meth:`plot`."""

    def __init__(self, data=(), rows=()):
        super().__init__(data)
        self.rows = list(rows)

    def plot(self):
        """The ensemble figure (a matplotlib Figure): each output over the realisations
        with its running mean and 95 % interval, and the regime fractions; ``tengfield
        run`` saves this figure as ensemble.png."""
        from .plotting.ensemble import ensemble_figure   # the edge, imported on use

        return ensemble_figure(self.rows, self)


def ensemble_block(rows: list[dict]) -> EnsembleBlock:
    """``summary.json -> ensemble``: per quantity its statistics (:func:`statistics`),
    and per regime the fraction of realisations in it with its exact binomial interval
    (:func:`fraction_statistics`); an :class:`EnsembleBlock` (a dict holding ``rows`` too:
    ``block.plot()``)."""
    block = {"realisations": len(rows), "confidence": CONFIDENCE,
             "seeds": [r["seed"] for r in rows],
             "seed_rule": "realisation k uses [excitation] seed + k",
             "interval_rule": "mean +- t(0.975, N-1) s / sqrt(N) (Student); s with ddof = 1",
             "fraction_interval_rule": "exact binomial (Clopper-Pearson): [beta.ppf(0.025, k, "
                                       "N-k+1), beta.ppf(0.975, k+1, N-k)]",
             "round_off_rule": f"std <= {ROUNDOFF_RELATIVE:g} x |mean|: the same value in "
                               "every realisation (equal_within_round_off)",
             "quantities": {}, "regime_fractions": {}}
    labels = {r.get("array_quantity") for r in rows} - {None}
    if labels:   # [array]: what array_value is (one circuit: one label)
        block["array_quantity"] = ", ".join(sorted(labels))
    for name in QUANTITIES:
        values = [r.get(name) for r in rows]
        if all(v is None for v in values):
            continue
        block["quantities"][name] = statistics([np.nan if v is None else v for v in values])
    for label in sorted({r["regime"] for r in rows}):
        block["regime_fractions"][label] = fraction_statistics(
            [1.0 if r["regime"] == label else 0.0 for r in rows])
    return EnsembleBlock(block, rows)
