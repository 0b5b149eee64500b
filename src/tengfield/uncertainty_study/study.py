"""One study: sample the inputs, evaluate, and summarise (``uncertainty.json``'s data).

:func:`run_study` is the Python face of ``tengfield uncertainty``; :func:`candidate_percentile`
scores one design candidate by a percentile of its objective over ``[uncertainty.vary]``
(``[design] aggregate = "p10"``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .._args import checked_write
from .evaluation import Evaluations, evaluate_study, main_outputs
from .sampling import study_values
from .spec import UncertaintySpec, check_study_combination, uncertainty_spec
from .statistics import (distribution_statistics, dominant_input, percentile_interval,
                         percentile_score, regime_fractions, sobol_indices)


@dataclass
class Study:
    """A finished study: the spec, the sampled values ``(evaluations, D)``, the
    evaluations and the JSON-ready ``summary`` (``uncertainty.json``)."""
    spec: UncertaintySpec
    values: np.ndarray
    evaluations: Evaluations
    summary: dict
    scene: Any = field(default=None, repr=False, compare=False)   # the scene studied

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield uncertainty -o out_dir`` writes; returns the paths."""
        from pathlib import Path

        from .output import write_outputs

        return write_outputs(self, Path(out_dir), plots=plots)

    @property
    def output_keys(self) -> list[str]:
        return self.summary["output_keys"]

    @property
    def main(self) -> list[str]:
        return self.summary.get("main_outputs", main_outputs(self.output_keys))

    def plot(self):
        """The study's figure (a matplotlib Figure): per main output its distribution over
        the evaluations with the 5-95 % band, the median and the nominal value, and (Sobol
        method) its S1 / ST indices per input; ``tengfield uncertainty`` saves this figure
        as uncertainty.png."""
        from ..plotting.uncertainty import uncertainty_figure   # the edge, imported on use

        return uncertainty_figure(self.evaluations.rows, self.summary)


def output_keys(evaluations: Evaluations) -> list[str]:
    """Every output any evaluation (or the nominal run) has, in order of appearance."""
    keys = dict.fromkeys(evaluations.nominal)
    for row in evaluations.rows:
        keys.update(dict.fromkeys(row))
    return list(keys)


def summarise(scene, spec: UncertaintySpec, values, evaluations: Evaluations) -> dict:
    """``uncertainty.json``: per output mean, std, percentiles (and Sobol indices),
    regimes with Clopper-Pearson intervals, the field solves, the study's settings."""
    keys = output_keys(evaluations)
    outputs, notes = {}, {}
    for name in keys:
        column = [row.get(name) for row in evaluations.rows]
        block = distribution_statistics(column)
        block["nominal"] = evaluations.nominal.get(name)
        if spec.method == "sobol":
            try:
                block["sobol"] = sobol_indices(spec.keys, column, seed=spec.seed)
                block["dominant_input"] = dominant_input(block["sobol"])[0]
            except ValueError as exc:
                block["sobol"] = None
                notes[name] = f"no Sobol indices: {exc}"
        outputs[name] = block
    return {
        "scene": scene.source,
        "samples": spec.samples, "evaluations": len(evaluations.rows),
        "method": spec.method, "seed": spec.seed,
        "distributions": {d.key: d.as_dict() for d in spec.inputs},
        "nominal_inputs": nominal_inputs(scene, spec),
        "field_solves": evaluations.field_solves,
        "geometries": evaluations.geometries,
        "dynamics_runs": evaluations.dynamics_runs,
        "beyond_breakdown": evaluations.beyond_breakdown,
        "output_keys": keys, "main_outputs": shown_outputs(keys, evaluations),
        "outputs": outputs, "notes": notes,
        "regimes": regime_fractions(evaluations.regimes),
        "nominal_regime": evaluations.nominal_regime,
        "rules": {
            "sampling": ("Saltelli's scheme on a scrambled Sobol sequence (SALib), N (D + 2) "
                         "evaluations" if spec.method == "sobol" else
                         "scrambled Sobol sequence (scipy.stats.qmc), N evaluations"),
            "sobol": "S1 (Saltelli 2010), ST (Jansen), SALib's estimators; *_conf: half-width "
                     "of the bootstrap 95 % interval (1000 resamples up to N = 32768, beyond "
                     "max(100, 2^25 / N))",
            "percentiles": "numpy.percentile (linear) over the evaluations",
            "regimes": "exact binomial (Clopper-Pearson) 95 % interval",
            "cost": "evaluations grouped by their dynamics-relevant inputs: one dynamics run and "
                    "one cached surrogate per group; sigma scales the table, circuit keys rerun "
                    "the electrical stage only; field_solves counts the distinct field hashes "
                    "whose surrogate was not in the cache"},
    }


def shown_outputs(keys, evaluations: Evaluations) -> list[str]:
    """The main outputs shown (figure, terminal): :func:`main_outputs`, with a ``peak.X``
    left out where it equals ``peak_to_peak.X`` (to 1e-6) in every evaluation and the nominal run
    (a quantity that starts from 0, e.g. Q_SC: its peak is its peak-to-peak)."""
    main = main_outputs(keys)
    out = []
    for name in main:
        twin = "peak_to_peak." + name[len("peak."):] if name.startswith("peak.") else None
        if twin in main:
            pairs = [(row.get(name), row.get(twin)) for row in [*evaluations.rows,
                                                               evaluations.nominal]]
            if all(a is not None and b is not None and math.isclose(a, b, rel_tol=1e-6,
                                                                    abs_tol=0.0)
                   for a, b in pairs):
                continue
        out.append(name)
    return out


def nominal_inputs(scene, spec: UncertaintySpec) -> dict:
    """The scene's own value of every varied key (file units): a deprecated key the
    scene does not give (``circuit.parallel_capacitance_pF``, left out of its printed
    form) at the schema's default."""
    from ..scene.schema import SCHEMA

    full = scene.to_dict()
    return {d.key: full[d.section].get(d.name, SCHEMA[d.section][d.name].default)
            for d in spec.inputs}


def run_study(scene, spec: UncertaintySpec | None = None, *, comm=None, jobs: int | None = None,
              cache_dir=None, solve: Callable | None = None, simulate: Callable | None = None,
              progress: bool = False) -> Study:
    """``tf.uncertainty(scene)``: the study of ``scene``'s ``[uncertainty]`` section (or
    ``spec``). Its work is counted first
    (:func:`~tengfield.uncertainty_study.cost.study_cost`) and refused past
    ``[uncertainty] max_field_solves`` or the memory at hand; with ``progress`` the count
    is printed (stderr, rank 0) before the work starts."""
    import sys

    from .._args import check_instance, check_jobs_argument
    from .._mpi import rank_of
    from ..scene import as_scene
    from .cost import check_cost, study_cost

    function = "tengfield.uncertainty"   # the verb, as the user calls it
    scene = as_scene(scene, "uncertainty")
    check_instance(function, spec, "spec", UncertaintySpec, "an UncertaintySpec "
                   "(tengfield.uncertainty_study.uncertainty_spec(scene)) or None", allow_none=True)
    jobs = check_jobs_argument(function, jobs, comm)
    if spec is None and "uncertainty" not in scene.raw:   # as ``tengfield uncertainty``
        from .spec import default_uncertainty_section
        section, said = default_uncertainty_section(scene)
        scene = scene.with_values(uncertainty=section)
        if progress and rank_of(comm) == 0:
            print(f"tengfield: {said}", file=sys.stderr, flush=True)
    spec = spec or uncertainty_spec(scene)
    check_study_combination(scene)
    values = study_values(spec)
    cost = study_cost(scene, spec, values)
    check_cost(cost, field_limit=spec.max_field_solves,
               field_key="[uncertainty] max_field_solves",
               size_key=f"[uncertainty] samples = {spec.samples}")
    if progress and rank_of(comm) == 0:
        print(cost.line(), file=sys.stderr, flush=True)
    evaluations = evaluate_study(scene, spec, values, comm=comm, jobs=jobs, cache_dir=cache_dir,
                                 solve=solve, simulate=simulate, progress=progress)
    return Study(spec, values, evaluations, summarise(scene, spec, values, evaluations),
                 scene=scene)


def candidate_percentile(candidate, spec: UncertaintySpec, objective: str, percentile: float, *,
                         cache_dir=None, solve=None, simulate=None) -> tuple[float, int]:
    """``(score, evaluations)``: the ``percentile``-th percentile of the output
    ``objective`` (an :func:`~tengfield.uncertainty_study.evaluation.output_quantities` name,
    e.g. ``"load.mean_power_W"``) of the design candidate's scene over the study
    ``spec`` (Monte Carlo or Sobol points alike), on this process (``comm=None``,
    one job: the design farms the candidates)."""
    out = candidate_percentiles(candidate, spec, [objective], percentile, cache_dir=cache_dir,
                                solve=solve, simulate=simulate)
    return out["scores"][objective], out["evaluations"]


def candidate_percentiles(candidate, spec: UncertaintySpec, objectives, percentile: float, *,
                          cache_dir=None, solve=None, simulate=None) -> dict:
    """One study of the candidate's scene, several outputs scored: ``{"scores": {name:
    percentile}, "intervals": {name: (low, high)} (the distribution-free 95 % interval of
    that percentile, :func:`percentile_interval`), "nominal": {name: the scene's own
    value}, "evaluations", "field_solves", "dynamics_runs", "missing": {name: evaluations
    without the output}}``. Only the evaluations are run (no Sobol indices, nothing
    written); on this process (``comm=None``, one job)."""
    values = study_values(spec)
    ev = evaluate_study(candidate, spec, values, jobs=1, cache_dir=cache_dir, solve=solve,
                        simulate=simulate)
    scores, intervals, missing = {}, {}, {}
    for name in objectives:
        column = [row.get(name) for row in ev.rows]
        scores[name] = percentile_score(column, percentile)
        intervals[name] = percentile_interval(column, percentile)
        missing[name] = sum(v is None or v != v for v in column)
    return {"scores": scores, "intervals": intervals,
            "nominal": {name: ev.nominal.get(name) for name in objectives},
            "evaluations": len(ev.rows), "field_solves": ev.field_solves,
            "dynamics_runs": ev.dynamics_runs, "missing": missing}
