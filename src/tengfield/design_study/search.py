"""The design search: space-filling start, then shrinking boxes around the best.

Every candidate is a point ``u`` of the unit cube (one axis per varied key; ``load_ohm``
on a log scale), snapped to a grid of ``[design] resolution`` so that a repeated
geometry is a repeated candidate (scored once, its surrogate cached by field hash).

1. Space filling: a scrambled Sobol' sequence (``scipy.stats.qmc``, seeded by
   ``[design] seed``) of ``DesignSpec.initial_count()`` points covers the whole box,
   so every regime (no contact, chaotic, regular contact) is sampled before any
   refinement: the objective jumps where the regime changes, which defeats
   gradient-based optimisers.
2. Refinement: rounds of ``[design] batch`` Sobol' points (seed, round) in a box
   around the best feasible candidate; the box halves after a round that does not
   improve the best beyond its error bar, else shrinks by 0.8; it stops at the budget,
   at the resolution, or after three rounds without a new candidate.

Each round's candidates are farmed (:func:`tengfield.sweeps.run_tasks`: the MPI task
farm over ``comm``'s ranks; on one machine ``jobs`` worker processes that live for the
whole search, so dolfinx and the JIT caches load once per worker, not once per round)
and every rank takes the same next decision from the gathered rows: the result depends
on the seed, never on the number of ranks or processes.
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .._args import checked_write
from .candidate import evaluate
from .spec import LOG_KEYS, OBJECTIVES, DesignSpec, parse_design_section, vary_spec

#: box half-width (unit cube) of the first refinement round; shrink factors
FIRST_HALF_WIDTH = 0.25
SHRINK_IMPROVED = 0.8
SHRINK_STALLED = 0.5
STALL_ROUNDS = 3

_TABLES: dict = {}   # this process's surrogates by field hash (cleared per design run)


@dataclass
class DesignResult:
    """Outcome of :func:`design`.

    ``rows``: every candidate in evaluation order (``index``, ``phase``, ``values`` (the
    varied keys, file units), ``status`` "ok" / "infeasible" / "skipped", ``reason``,
    ``objective`` and ``objective_error`` (SI; the error bar is the field + surrogate
    error estimate times the objective's sensitivity), ``objectives`` (every objective),
    ``band_values`` (per band point), ``regimes``, ``upper_contact_fraction``,
    ``load_ohm``, field and timing details); ``ranking``: indices of the feasible rows,
    best first; ``best``: the best row (None if none is feasible).
    """
    scene: object
    spec: DesignSpec
    rows: list
    ranking: list
    wall_time: float = 0.0
    ranks: int = 1
    jobs: int | None = None
    rounds: list = field(default_factory=list)
    #: the cache the candidates' surrogates went to (the best's band reads it back)
    cache_dir: object = None

    @property
    def best(self) -> dict | None:
        return self.rows[self.ranking[0]] if self.ranking else None

    def breakdown_band(self) -> dict | None:
        """With σ = "breakdown": the best design's objective over its breakdown band
        (:func:`tengfield.design_study.answer.best_breakdown_band`; None otherwise), what
        the terminal prints and design.json's ``best_breakdown_band``; computed once."""
        if not hasattr(self, "_breakdown_band"):
            from .answer import best_breakdown_band

            self._breakdown_band = best_breakdown_band(self, cache_dir=self.cache_dir)
        return self._breakdown_band

    def best_scene(self):
        """The base scene with the best candidate's geometry (``[design]`` dropped)."""
        from .output import best_scene_dict
        from ..scene import Scene
        return Scene.from_dict(best_scene_dict(self), source=f"best of {self.scene.source}")

    @property
    def summary(self) -> dict:
        """JSON-ready: design.json's content."""
        from .output import design_summary

        return design_summary(self)

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield design -o out_dir`` writes; returns the paths."""
        from .output import write_design_outputs

        return write_design_outputs(self, out_dir, plots=plots)

    def plot(self):
        """design.png's figure (a matplotlib Figure, not saved): the objective over the
        varied keys with error bars, the best marked; with several objectives the Pareto
        plot of the first two (``tengfield design`` saves the same figure)."""
        from ..plotting.design import design_figure   # the edge, imported on use
        from .output import plot_options

        return design_figure(self, **plot_options(self))

    def pareto(self) -> list[int]:
        """Indices of the feasible rows no other row beats in both objectives (two objectives)."""
        if len(self.spec.objectives) < 2:
            return list(self.ranking[:1])
        a, b = self.spec.objectives[:2]
        pts = [(i, self.rows[i]["objectives"][a]["value"], self.rows[i]["objectives"][b]["value"])
               for i in self.ranking]
        return [i for i, x, y in pts
                if not any((x2 >= x and y2 >= y) and (x2 > x or y2 > y) for _, x2, y2 in pts)]

    def confidence(self) -> dict:
        """How sure the best is: its margin over the runner-up against both error bars."""
        if not self.ranking:
            return {}
        best = self.rows[self.ranking[0]]
        out = {"objective": best["objective"], "error": best["objective_error"],
               "relative_error": best.get("relative_error", math.nan)}
        if len(self.ranking) > 1:
            second = self.rows[self.ranking[1]]
            margin = best["objective"] - second["objective"]
            bars = best["objective_error"] + second["objective_error"]
            ties = [i for i in self.ranking[1:]
                    if best["objective"] - self.rows[i]["objective"]
                    <= best["objective_error"] + self.rows[i]["objective_error"]]
            ratio = margin / bars if bars > 0 else (None if margin == 0 else math.inf)
            out.update({"runner_up_index": second["index"], "margin": margin,
                        "margin_over_error_bars": ratio, "tie": margin == 0 and bars == 0,
                        "candidates_within_error_bars": len(ties),
                        "within_error_bars": [self.rows[i]["index"] for i in ties[:20]]})
        return out


class _Space:
    """Unit cube <-> varied values (file units), snapped to the resolution grid."""

    def __init__(self, spec: DesignSpec):
        self.keys = list(spec.vary)
        self.bounds = [spec.vary[k] for k in self.keys]
        self.resolution = spec.resolution
        self.integer = [vary_spec(k)[1][1] is int for k in self.keys]

    def snap(self, u: np.ndarray) -> np.ndarray:
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        if self.resolution > 0:
            u = np.round(u / self.resolution) * self.resolution
        return np.clip(u, 0.0, 1.0)

    def values(self, u) -> dict:
        out = {}
        for key, (lo, hi), x, integer in zip(self.keys, self.bounds, u, self.integer):
            if key in LOG_KEYS:
                v = 10.0 ** (math.log10(lo) + float(x) * (math.log10(hi) - math.log10(lo)))
            else:
                v = lo + float(x) * (hi - lo)
            out[key] = int(round(v)) if integer else float(f"{v:.10g}")
        return out

    def key(self, values: dict) -> tuple:
        return tuple(values[k] for k in self.keys)


def fresh_candidates(space: _Space, units, seen: dict, room: int) -> list[dict]:
    """The varied values of ``units`` (unit-cube points, snapped) not in ``seen`` (keys of
    the candidates scored so far) nor earlier in ``units``, at most ``room`` of them, in
    order. One :meth:`_Space.key` per unit and a set lookup: linear in ``len(units)``
    (``[design] candidates = 100000`` de-duplicates in a moment)."""
    fresh: list[dict] = []
    keys: set = set()
    for u in units:
        if len(fresh) >= room:
            break
        values = space.values(space.snap(u))
        k = space.key(values)
        if k in seen or k in keys:
            continue
        keys.add(k)
        fresh.append(values)
    return fresh


def _sobol(d: int, n: int, seed) -> np.ndarray:
    from scipy.stats import qmc

    sampler = qmc.Sobol(d, scramble=True, seed=np.random.default_rng(seed))
    m = int(math.ceil(math.log2(max(n, 1))))
    return sampler.random_base2(m)[:n]


def _evaluate_task(task):
    base, spec, values, cache_dir, solve, simulate = task
    return evaluate(base, spec, values, cache_dir=cache_dir, solve=solve, simulate=simulate,
                    tables=_TABLES)


def _evaluate_bundle(tasks):
    """:func:`_evaluate_task` of each task of one bundle (:func:`bundles`), in order."""
    return [_evaluate_task(task) for task in tasks]


def bundles(keys: list, workers: int) -> list[list[int]]:
    """The indices ``0..len(keys)-1`` in bundles for ``workers`` processes: indices of
    one key (:func:`tengfield.field.mapping_group`: the candidates whose meshes are mapped
    from one canonical geometry, which a process meshes once) together, each bundle at
    most ``ceil(n / workers)`` long (no process gets more than its share), the largest
    first (the farm deals the dearest first); a key of None is a bundle of its own.
    Every index once; within a bundle in increasing order."""
    n = len(keys)
    share = max(1, -(-n // max(workers, 1)))
    groups: dict = {}
    out: list[list[int]] = []
    for i, key in enumerate(keys):
        if key is None:
            out.append([i])
        else:
            groups.setdefault(key, []).append(i)
    for members in groups.values():
        out.extend(members[j:j + share] for j in range(0, len(members), share))
    return sorted(out, key=lambda b: (-len(b), b[0]))


def _mapping_group(base, spec, values):
    """:func:`tengfield.field.mapping_group` of a candidate's scene (None when the
    candidate is impossible: evaluate says why)."""
    from ..errors import TengfieldError
    from ..field import mapping_group
    from .candidate import candidate_scene

    try:
        return mapping_group(candidate_scene(base, spec, values))
    except (TengfieldError, ValueError):
        return None


def _quiet_worker() -> None:
    """A worker's stderr carries tengfield's lines only (no ffcx/setuptools JIT chatter)."""
    from .._console import configure_output
    configure_output()


class _Workers:
    """``[work(t) for t in tasks]`` per round: the MPI farm (``comm`` with several ranks),
    a process pool kept for every round (``jobs`` > 1), or a loop."""

    def __init__(self, comm, jobs):
        import os

        from .._mpi import size_of

        self.comm, self.pool, self._stack = comm, None, None
        self.jobs = 1 if size_of(comm) > 1 else max(1, jobs or os.cpu_count() or 1)
        #: how many processes evaluate candidates at once
        self.count = max(size_of(comm), self.jobs)

    def __enter__(self):
        if self.jobs > 1:   # spawned (fresh interpreters); an interrupted or failed study
            import contextlib   # terminates them (_pool.process_pool)

            from .._pool import process_pool
            self._stack = contextlib.ExitStack()
            self.pool = self._stack.enter_context(
                process_pool(self.jobs, "spawn", initializer=_quiet_worker))
        return self

    def __exit__(self, *exc):
        if self._stack is not None:
            self._stack.__exit__(*exc)

    def map(self, work, tasks, progress):
        from .._farm import run_tasks

        if self.pool is None:   # the MPI farm over comm's ranks, or a loop
            return run_tasks(work, tasks, comm=self.comm, jobs=1, progress=progress)
        results = []
        for result in self.pool.map(work, tasks):
            results.append(result)
            progress(1)
        return results


def _bundle_progress(update, sizes: list[int]):
    """A farm's progress callback (``n`` more tasks started; the farm deals them in
    order) that advances ``update`` by the candidates of those bundles."""
    started = 0

    def advance(n: int) -> None:
        nonlocal started
        first, started = started, min(started + int(n), len(sizes))
        update(sum(sizes[first:started]))
    return advance


def progress_bar(total: int, enabled: bool):
    """THE progress display of a design (done/total, rate, ETA; the current best as its
    postfix): the shared bar of :func:`tengfield._console.progress_bar` (on a terminal
    only; silent when piped, with ``--quiet``; the caller passes ``enabled`` False on
    ranks other than 0)."""
    from .._console import progress_bar as bar

    return bar(total, "design", enabled, unit="candidate")


def show_best(bar, spec: DesignSpec, row: dict) -> None:
    """The current best on the progress display."""
    from .answer import readable_unit

    label, factor = readable_unit(OBJECTIVES[spec.objective][0], row["objective"])
    bar.set_postfix_str(f"best {row['objective'] * factor:.4g} {label}", refresh=True)


def _ranking(rows: list) -> list[int]:
    ok = [i for i, r in enumerate(rows) if r["status"] == "ok" and np.isfinite(r["objective"])]
    return sorted(ok, key=lambda i: (-rows[i]["objective"], i))


def design(scene, *, comm=None, jobs: int | None = None, cache_dir=None,
           solve: Callable | None = None, simulate: Callable | None = None,
           progress: bool = False, overrides: dict | None = None) -> DesignResult:
    """Search the ``[design.vary]`` box of ``scene`` for the best ``[design] objective``
    over the ``[design.excitation]`` band (module docstring). ``comm``: spread each round
    over its ranks (every rank returns the same result); else ``jobs`` worker processes.
    ``solve``/``simulate`` replace the field solver and the dynamics (tests);
    ``overrides`` sets ``[design]`` keys (e.g. ``{"candidates": 40}``)."""
    from .._args import check_jobs_argument
    from .._console import progress_shown
    from ..scene.parse import check_scene_argument
    from .._mpi import rank_of, size_of

    start = time.perf_counter()
    check_scene_argument("tengfield.design", scene)
    jobs = check_jobs_argument("tengfield.design", jobs, comm)
    if "design" not in scene.raw:   # the default study, as ``tengfield design`` runs it
        from .spec import default_design_section
        section, said = default_design_section(scene, (overrides or {}).get("candidates"))
        scene = scene.with_values(design=section)
        if progress_shown(progress, comm):
            print(f"tengfield: {said}", file=sys.stderr, flush=True)
    spec = parse_design_section(scene, overrides)
    check_design_combination(scene, spec)
    announce_cost(scene, spec, progress_shown(progress, comm))
    _TABLES.clear()
    space = _Space(spec)
    rows: list[dict] = []
    seen: dict[tuple, int] = {}
    rounds: list[dict] = []
    bar = progress_bar(spec.candidates, progress and rank_of(comm) == 0)

    def run_round(units: np.ndarray, phase: str) -> int:
        fresh = fresh_candidates(space, units, seen, spec.candidates - len(rows))
        if not fresh:
            return 0
        tasks = [(scene, spec, v, cache_dir, solve, simulate) for v in fresh]
        if workers.count > 1:
            # one canonical geometry's candidates in one process: its templates are
            # meshed once (the rows do not depend on where a candidate ran)
            groups = bundles([_mapping_group(scene, spec, v) for v in fresh], workers.count)
            done = workers.map(_evaluate_bundle, [[tasks[i] for i in b] for b in groups],
                               _bundle_progress(bar.update, [len(b) for b in groups]))
            results = [None] * len(tasks)
            for members, outcome in zip(groups, done):
                for i, row in zip(members, outcome):
                    results[i] = row
        else:
            results = workers.map(_evaluate_task, tasks, bar.update)
        for values, row in zip(fresh, results):
            row = {"index": len(rows), "phase": phase, **row}
            seen[space.key(values)] = row["index"]
            rows.append(row)
        ranking = _ranking(rows)
        if ranking:
            show_best(bar, spec, rows[ranking[0]])
        return len(fresh)

    def unit_of(row) -> np.ndarray:
        u = []
        for key, (lo, hi) in zip(space.keys, space.bounds):
            v = row["values"][key]
            if key in LOG_KEYS:
                u.append((math.log10(v) - math.log10(lo)) / (math.log10(hi) - math.log10(lo)))
            else:
                u.append((v - lo) / (hi - lo))
        return np.array(u)

    workers = _Workers(comm, jobs).__enter__()
    failure = (None, None, None)
    try:
        d = len(space.keys)
        n0 = spec.initial_count()
        added = run_round(_sobol(d, n0, [spec.seed, 0]), "space-filling")
        rounds.append({"phase": "space-filling", "candidates": added})
        half = FIRST_HALF_WIDTH
        stalled = 0
        k = 0
        while len(rows) < spec.candidates:
            ranking = _ranking(rows)
            if not ranking:   # nothing feasible yet: keep filling the space
                units = _sobol(d, spec.batch, [spec.seed, 1, k])
                phase = "space-filling"
            else:
                centre = unit_of(rows[ranking[0]])
                units = centre + (2.0 * _sobol(d, spec.batch, [spec.seed, 1, k]) - 1.0) * half
                phase = f"refine {k + 1}"
            before = rows[ranking[0]] if ranking else None
            added = run_round(units, phase)
            k += 1
            after = _ranking(rows)
            improved = bool(after) and (before is None or (
                rows[after[0]]["objective"] - before["objective"] > before["objective_error"]))
            rounds.append({"phase": phase, "candidates": added, "half_width": half,
                           "improved_beyond_error_bar": improved,
                           "best_index": rows[after[0]]["index"] if after else None})
            stalled = stalled + 1 if added == 0 else 0
            if stalled >= STALL_ROUNDS:
                break
            if ranking:
                half *= SHRINK_IMPROVED if improved else SHRINK_STALLED
                if half < max(spec.resolution, 1e-6):
                    break
    except BaseException:
        failure = sys.exc_info()
        raise
    finally:
        workers.__exit__(*failure)
        bar.close()
    return DesignResult(scene=scene, spec=spec, rows=rows, ranking=_ranking(rows),
                        wall_time=time.perf_counter() - start, ranks=size_of(comm), jobs=jobs,
                        rounds=rounds, cache_dir=cache_dir)


def check_design_combination(scene, spec) -> None:
    """Refuse in one line, before the first solve, what no candidate can run: σ =
    "breakdown" (or breakdown-band draws of a percentile aggregate) without the gap
    lines of the field solver (:func:`tengfield.air_breakdown.check_gap_lines`, the
    check ``run`` makes), instead of skipping every candidate."""
    from ..air_breakdown import check_gap_lines, uses_breakdown_charge
    from ..quantities import SURFACE_CHARGE_KEY
    from ..scene.shapes import NUMERIC_SIGMA
    from ..uncertainty_study.spec import check_study_combination

    if not any(OBJECTIVES[o][2] for o in spec.objectives):   # no field: no charge needed
        return
    if uses_breakdown_charge(scene):
        check_gap_lines(scene, f'[device] {SURFACE_CHARGE_KEY} = "breakdown"', NUMERIC_SIGMA)
    if spec.percentile is not None:       # each candidate's [uncertainty] draws
        check_study_combination(scene)
    if scene.charge.from_contacts:
        from ..errors import SceneError
        from ..contact_run import check_contact_charge

        check_contact_charge(scene)      # what a contact run refuses (the ball off the axis)
        if spec.percentile is not None:
            raise SceneError(
                f'[design] aggregate = "p{spec.percentile:g}" with [charge] model = '
                '"contact": not supported yet (a candidate is scored at the steady charge '
                'its contacts make, a percentile study at the run\'s); use aggregate = '
                '"mean" or "min", or [charge] model = "constant"')
        if scene.charge.discharge != "none":
            from ..air_breakdown import check_gap_lines
            check_gap_lines(scene, f'[charge] discharge = {scene.charge.discharge!r}',
                            '[charge] discharge = "none"')


def announce_cost(scene, spec, say: bool) -> None:
    """Count the design's work before any of it (:func:`~tengfield.design_study.spec.design_cost`),
    refuse it in one line past ``[design] max_field_solves`` or the memory at hand, and
    with ``say`` (where the progress bar shows: a terminal, rank 0, not quiet) print the
    count on stderr (issue #43.6)."""
    from ..uncertainty_study.cost import check_cost
    from .spec import design_cost

    cost = design_cost(scene, spec)
    check_cost(cost, field_limit=spec.max_field_solves, field_key="[design] max_field_solves",
               size_key=f"[design] candidates = {spec.candidates}", what="design")
    if say:
        print(cost.line("design"), file=sys.stderr, flush=True)


def narrowed_scene(result: DesignResult, fraction: float = 0.2, candidates: int = 24):
    """The scene of a check of the optimum: every varied range narrowed to ``fraction`` of
    its width around the best (clipped to the original range), ``candidates`` candidates,
    another seed."""
    best = result.best
    if best is None:
        raise ValueError("no feasible candidate to check")
    vary = {}
    for key, (lo, hi) in result.spec.vary.items():
        v = best["values"][key]
        if key in LOG_KEYS:
            span = (math.log10(hi) - math.log10(lo)) * fraction / 2
            a, b = 10 ** max(math.log10(lo), math.log10(v) - span), \
                10 ** min(math.log10(hi), math.log10(v) + span)
        else:
            span = (hi - lo) * fraction / 2
            a, b = max(lo, v - span), min(hi, v + span)
        vary[key] = [float(a), float(b)] if a < b else [float(lo), float(hi)]
    raw = dict(result.scene.raw.get("design", {}))
    raw.update({"vary": vary, "candidates": candidates, "seed": result.spec.seed + 1,
                "initial_candidates": 0})
    return result.scene.with_values(design=raw)


def check_optimum(result: DesignResult, *, fraction: float = 0.2, candidates: int = 24,
                  **kwargs) -> dict:
    """A narrower search around the best (:func:`narrowed_scene`): is anything better beyond
    the error bars? Returns both bests and the verdict ``confirmed``."""
    from .._args import check_count, check_fraction, check_instance

    check_instance("check_optimum", result, "result", DesignResult,
                   "a DesignResult (tengfield.design(scene))")
    fraction = check_fraction("check_optimum", fraction, "fraction")
    candidates = check_count("check_optimum", candidates, "candidates")
    narrow = design(narrowed_scene(result, fraction, candidates), **kwargs)
    best, other = result.best, narrow.best
    gain = (other["objective"] - best["objective"]) if other else -math.inf
    bars = best["objective_error"] + (other["objective_error"] if other else 0.0)
    return {"best": best["values"], "objective": best["objective"],
            "error": best["objective_error"],
            "narrow_best": other["values"] if other else None,
            "narrow_objective": other["objective"] if other else None,
            "narrow_error": other["objective_error"] if other else None,
            "gain": gain, "error_bars": bars, "confirmed": bool(gain <= bars),
            "narrow_candidates": len(narrow.rows), "fraction": fraction,
            "wall_time_s": narrow.wall_time, "result": narrow}


__all__ = ["design", "DesignResult", "check_optimum", "narrowed_scene", "OBJECTIVES"]
