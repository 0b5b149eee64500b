"""The evaluations of a study, as cheap as the physics allows.

Samples are grouped by their dynamics-relevant inputs (every varied key except σ and
``[circuit]`` keys): one group runs the dynamics once and obtains
its surrogate once (cached by the field hash; per unit ball charge). Every
evaluation in the group then only runs the electrical stage with the table's curves at its
own σ (every charge is linear in σ, C does not depend on it) and its own circuit values:
σ alone is a scaling, no field solve and no new dynamics. Geometry keys give one field
solve per distinct geometry (phase 1, farmed over the workers before the groups, so two
workers never solve the same geometry).

Nothing is written: an evaluation returns the run summary's numeric quantities
(:func:`output_quantities`) and its regime.
"""
from __future__ import annotations

import uuid
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import electrical
from .._json import regime_dict
from ..quantities import summary_keys
from ..surrogate.cache import solved_scene
from .spec import UncertaintySpec, band_sigma, draws_from_band, sections_of
from ..scene.schema import (SURFACE_CHARGE_KEY, SURFACE_CHARGE_SETTING,
                            stated_surface_charge)

#: sections whose keys change neither the dynamics nor the field: the electrical stage only
#: (a [breakdown] key can change σ itself, with σ = "breakdown": it
#: forms groups like a dynamics key)
ELECTRICAL_SECTIONS = ("circuit", "charge")
#: summary blocks whose numeric leaves are an evaluation's outputs (``block.name``), and
#: numeric top-level summary keys; the quantity table (tengfield/quantities.py) can
#: replace both through :func:`output_quantities`
OUTPUT_BLOCKS = ("peak_to_peak", "peak", "load", "energy_per_cycle", "rectifier")
OUTPUT_TOP_LEVEL = ("V_read_V",)
#: outputs drawn and printed first (when present)
#: the outputs shown in the figure and the terminal, in this order: the quantity table's
#: summary keys (peak-to-peak and peak of V_OC, Q_SC, I_SC, V read through C_p, then the
#: block numbers such as the load's mean power)
MAIN_OUTPUTS = (*summary_keys(instrument=True),
                # [charge] model = "contact": the steady charge and how long it takes
                "charge.steady_uC_per_m2", "charge.rise_time_90_s")


#: the outputs of the ``charge`` block (``[charge] model = "contact"``): the steady σ
#: [µC/m²], the rise time to 90 % of it [s], the shares of σ_eq and of the cap reached,
#: the mean gain per contact [C] (its inputs, η, τ, σ_eq, are not outputs)
OUTPUT_CHARGE = ("steady_uC_per_m2", "rise_time_90_s", "share_of_equilibrium",
                 "share_of_cap", "mean_delta_per_contact_C")


def output_quantities(summary: dict) -> dict[str, float]:
    """The numeric outputs of one run summary: ``{"peak_to_peak.Q_sc_C": ..., ...}``
    (the numeric leaves of :data:`OUTPUT_BLOCKS`, nested blocks joined with dots, and
    :data:`OUTPUT_TOP_LEVEL`). The one place that decides which outputs a study has."""
    out: dict[str, float] = {}

    def walk(prefix, value):
        if isinstance(value, dict):
            for k, v in value.items():
                if not str(k).startswith("_"):
                    walk(f"{prefix}.{k}", v)
        elif isinstance(value, (int, float, np.number)) and not isinstance(value, (bool, np.bool_)):
            out[prefix] = float(value)

    for name in OUTPUT_TOP_LEVEL:
        walk(name, summary.get(name))
    for block in OUTPUT_BLOCKS:
        if isinstance(summary.get(block), dict):
            walk(block, summary[block])
    charge = summary.get("charge")
    if isinstance(charge, dict):
        for name in OUTPUT_CHARGE:
            walk(f"charge.{name}", charge.get(name))
    return out


def main_outputs(keys) -> list[str]:
    """The outputs shown in the figure and the terminal: :data:`MAIN_OUTPUTS` present."""
    keys = list(keys)
    return [k for k in MAIN_OUTPUTS if k in keys]


def is_field_key(key: str, shape: str = "tube") -> bool:
    """True when the ``"section.key"`` is one the field hash of a cell of ``shape``
    depends on: :data:`tengfield.scene.schema.FIELD_KEYS`, and the shape's own keys
    (:data:`tengfield.scene.shapes.SHAPE_KEYS`: a shell's cavity_diameter_mm)."""
    from ..scene.schema import FIELD_KEYS
    from ..scene.shapes import SHAPE_KEYS

    sec, name = key.split(".", 1)
    return name in FIELD_KEYS.get(sec, ()) or (sec == "device"
                                               and name in SHAPE_KEYS.get(shape, ()))


def changes_field(values: dict, shape: str = "tube") -> bool:
    """True when a ``"section.key"`` of ``values`` is one the field hash depends on
    (:func:`is_field_key`); else the scene's own geometry."""
    return any(is_field_key(key, shape) for key in values)


def is_electrical(key: str) -> bool:
    """True for a key that changes only the electrical stage (σ, circuit)."""
    return key == SURFACE_CHARGE_SETTING or key.split(".", 1)[0] in ELECTRICAL_SECTIONS


@dataclass
class Group:
    """Evaluations sharing their dynamics: ``dynamic`` the dynamics-relevant values,
    ``members`` (evaluation index, its electrical values); index -1: the nominal run."""
    dynamic: dict
    members: list = field(default_factory=list)


#: evaluations of one task at most: a group larger than this (a σ- or circuit-only study
#: is ONE group of every evaluation: 98k electrical stages on one worker, issue #43.21) is
#: split into chunks of this many members, each its own task, so that --jobs and mpirun
#: share it. A fixed size: the tasks, and so the files, do not depend on the workers
CHUNK_EVALUATIONS = 128


def chunked(groups: list[Group], size: int = CHUNK_EVALUATIONS) -> list[Group]:
    """``groups`` with every group of more than ``size`` members split into consecutive
    chunks of at most ``size`` (same dynamics inputs; the members in their order)."""
    out = []
    for group in groups:
        for start in range(0, max(len(group.members), 1), size):
            out.append(Group(group.dynamic, group.members[start:start + size]))
    return out


def groups_of(keys: list[str], values: np.ndarray) -> list[Group]:
    """The evaluations grouped by their dynamics-relevant values, in order of first
    appearance (the same on every worker)."""
    dyn = [j for j, k in enumerate(keys) if not is_electrical(k)]
    ele = [j for j, k in enumerate(keys) if is_electrical(k)]
    groups: dict[tuple, Group] = {}
    for i, row in enumerate(values):
        key = tuple(float(row[j]) for j in dyn)
        group = groups.setdefault(key, Group({keys[j]: float(row[j]) for j in dyn}))
        group.members.append((i, {keys[j]: float(row[j]) for j in ele}))
    return list(groups.values())


#: surrogates this process has obtained: (cache dir, field hash, breakdown values, σ as
#: given) -> (the σ the table is at [C/m²], table, σ_max); groups that differ only in
#: dynamics keys share one (each keeps its own scene: excitation, run, contact...)
_OBTAINED: dict = {}
_OBTAINED_MAX = 64


def _obtain(scene, cache_dir, solve):
    """``(scene at its charge, table, status, σ_max [C/m²] or None)`` of ``scene``'s
    surrogate (σ_max: its air-breakdown limit, None without gap lines): from this
    process's memory when an earlier group had the same field (status "cached"), else
    from the cache or a field solve (:func:`tengfield.run_surrogate.surrogate_for_run`)."""
    import json

    from ..run_surrogate import surrogate_for_run

    raw = scene.to_dict()
    key = (str(cache_dir), scene.field_hash(), json.dumps(raw["breakdown"], sort_keys=True),
           repr(stated_surface_charge(scene)),
           solve is None)
    if key in _OBTAINED:   # the same field and charge rule: THIS scene at that charge
        sigma, table, sigma_max = _OBTAINED[key]
        resolved = scene if scene.device.surface_charge == sigma and not \
            isinstance(stated_surface_charge(scene), str) \
            else scene.with_values(device={SURFACE_CHARGE_KEY: sigma * 1e6})
        return resolved, table, "cached", sigma_max
    resolved, table, outcome, limit = surrogate_for_run(scene, cache_dir=cache_dir, solve=solve)
    sigma_max = None if limit is None else float(limit.sigma_max)
    if len(_OBTAINED) >= _OBTAINED_MAX:
        _OBTAINED.clear()
    # the charge, not the scene: groups sharing a field differ in their other keys
    _OBTAINED[key] = (float(resolved.device.surface_charge), table, sigma_max)
    return resolved, table, outcome.status, sigma_max


def _field_task(task):
    """Phase 1: obtain one geometry's surrogate; its field hash and cache status (an
    error names the draw of the first group with this geometry)."""
    scene, cache_dir, solve, values = task
    with warnings.catch_warnings(record=True) as caught, _tagged(values, None):
        if scene.charge.from_contacts:   # at σ_eq, which the cap may hold below
            warnings.filterwarnings("ignore", message=".*exceeds the air-breakdown limit.*")
        _, _, status, _ = _obtain(scene, cache_dir, solve)
    return scene.field_hash(), status, _caught(caught)


def _caught(caught) -> list:
    """Recorded warnings as picklable ``(category, message)`` pairs (the filters in force
    decided which were recorded; the driver shows each distinct one once)."""
    return [(w.category, str(w.message)) for w in caught]


def _outputs(scene, dynamics, table, curves=None, charge=None) -> tuple[dict, str]:
    """The run's electrical stage and summary for ``scene`` with ``dynamics`` and
    ``table`` (per unit ball charge, its curves at the scene's σ; None: no field needed), as
    :func:`tengfield.pipeline.run` computes them after its field stage; ``curves``:
    the terminal curves where they are not the table's (a contact run's), ``charge``:
    its ``charge`` block."""
    from ..pipeline import electrical_stage
    from ..surrogate import TerminalCurves

    if curves is None and table is not None:
        curves = TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge)
    electrical.circuit_for(scene).check(scene)
    summary = electrical_stage(scene, dynamics, curves, table).summary
    if charge is not None:
        summary["charge"] = charge
    regime = (regime_dict(getattr(dynamics, "regime", None)) or {}).get("regime", "")
    return output_quantities(summary), regime


def _group_task(task):
    """Phase 2: one group's dynamics and surrogate, then each member's electrical stage.
    Returns ``(rows, field hash or None, cache status, warnings)``; a row is
    ``(index, outputs, regime, above)``, ``above``: |σ| beyond the air-breakdown limit
    of its geometry (None when the table has no gap lines)."""
    scene, group, cache_dir, solve, simulate, study = task
    simulate = simulate or _default_simulate()
    rows, digest, status = [], None, "skipped"
    with warnings.catch_warnings(record=True) as caught, _tagged(group.dynamic,
                                                                 group.members):
        base = scene.with_values(**sections_of(group.dynamic)) if group.dynamic else scene
        memo = (study, tuple(group.dynamic.items()))
        if memo in _DYNAMICS:          # an earlier chunk of this group, on this worker
            dynamics = _DYNAMICS[memo]
        else:
            dynamics = simulate(base)
            _DYNAMICS.clear()          # chunks of a group are consecutive tasks: keep one
            _DYNAMICS[memo] = dynamics
        table, at, sigma_max = None, base, None
        contact = base.charge.from_contacts
        charged = base.device.ball_charge != 0.0 or contact or any(
            SURFACE_CHARGE_SETTING in v for _, v in group.members)
        if charged and np.any(np.asarray(dynamics.gap, dtype=float) != 0.0):
            if contact:     # the geometry's table at a reference charge (σ_eq)
                from ..contact_run import field_scene
                ref = solved_scene(field_scene(base))
                warnings.filterwarnings("ignore", message=".*exceeds the air-breakdown.*")
            else:
                ref = solved_scene(base)
            digest = ref.field_hash()
            ref_at, table, status, sigma_max = _obtain(ref, cache_dir, solve)
            at = ref_at if ref is base else base     # σ = "breakdown": at -σ_max
        if contact:
            for index, values in group.members:
                with _tagged({**group.dynamic, **values}, [(index, values)]):
                    rows.append((index, *_contact_outputs(at, values, dynamics, table), None))
            return rows, digest, status, _caught(caught)
        band = _group_band(scene, at, table, dynamics)   # σ from the breakdown band
        for index, values in group.members:
            with _tagged({**group.dynamic, **values}, [(index, values)]):
                if band is not None and SURFACE_CHARGE_SETTING in values:
                    values = {**values, SURFACE_CHARGE_SETTING: band_sigma(
                        band, values[SURFACE_CHARGE_SETTING])}
                point = at.with_values(**sections_of(values)) if values else at
                field = table if point.device.ball_charge != 0.0 else None   # none uncharged
                above = None if sigma_max is None or table is None or band is not None else \
                    bool(abs(point.device.surface_charge) > sigma_max)
                rows.append((index, *_outputs(point, dynamics, field), above))
    return rows, digest, status, _caught(caught)


def _contact_outputs(at, values, dynamics, table) -> tuple[dict, str]:
    """One evaluation of a scene whose contacts make the charge: the charge history of
    its ``[charge]`` draws along the group's trajectory, then the run's electrical stage
    at it (:func:`tengfield.contact_run.contact_source`, what ``tengfield run`` does)."""
    from ..contact_run import contact_source

    point = at.with_values(**sections_of(values)) if values else at
    run = contact_source(point, dynamics, table)
    return _outputs(run.scene, run.dynamics, run.table, run.curves, run.block)


def _group_band(scene, at, table, dynamics):
    """The breakdown band of the group's geometry and trajectory when ``[uncertainty.vary]``
    draws σ from it (docs/breakdown.md), else None."""
    if not draws_from_band(scene) or table is None:
        return None
    from ..air_breakdown import compute_band, lines_from_table, scene_states
    from ..air_breakdown.band import Seeds, trajectory_of
    from ..paschen import Paschen

    if table.line_potential is None:
        from ..errors import TengfieldError
        raise TengfieldError(f'[uncertainty.vary] "{SURFACE_CHARGE_SETTING}" = {{ distribution = '
                             '"breakdown-band" }: the surrogate has no breakdown lines (3D '
                             'solver); use [field] method = "axisymmetric"')
    return compute_band(lines_from_table(table, at), Paschen.from_scene(at), scene_states(at),
                        at.circuit.reference, trajectory_of(dynamics, at),
                        at.breakdown.gamma_range, Seeds.from_scene(at))



@contextmanager
def _tagged(values: dict, members: list):
    """Re-raise a :class:`~tengfield.errors.TengfieldError` of the evaluations
    ``members`` (None: the field phase) with the draw that led to it: ``evaluation 17 of the study
    ([uncertainty.vary] draws 'circuit.uvlo_falling_V' = 4.8): ...`` (issue #43.11: a
    mid-study error named values nobody wrote and no word of the study). Tagged once."""
    from ..errors import TengfieldError

    try:
        yield
    except TengfieldError as exc:
        text = str(exc)
        if text.startswith(_TAG) or not values and (members is None or members[0][0] < 0):
            raise
        if members is None:          # the field phase: a geometry, before any evaluation
            which = "the field solve"
        else:
            indices = [i for i, _ in members if i >= 0]
            which = (f"evaluation {indices[0]}" if len(indices) == 1 else
                     f"evaluations {indices[0]}.. ({len(indices)} sharing these draws)")
        drawn = ", ".join(f"{k!r} = {v:.12g}" for k, v in values.items()) or \
            "only electrical keys; the dynamics at the scene's own values"
        raise type(exc)(f"{_TAG}{which} of the study ([uncertainty.vary] draws {drawn}): "
                        f"{text}") from None


_TAG = "uncertainty: "


#: the dynamics of the last group this process ran, keyed by (study token, its dynamic
#: values): the next chunk of the same group reuses it (the same dynamics, not rerun)
_DYNAMICS: dict = {}


def _default_simulate():
    from ..dynamics import simulate
    return simulate


@dataclass
class Evaluations:
    """Outputs of every evaluation (``rows[i]``: dict of outputs; ``regimes[i]``), the
    nominal run's outputs, the field solves the study needed and its warnings."""
    rows: list[dict]
    regimes: list[str]
    nominal: dict
    nominal_regime: str
    field_solves: int
    geometries: int
    dynamics_runs: int
    warnings: list[tuple]
    #: evaluations whose |σ| exceeds their geometry's air-breakdown limit (None: unknown,
    #: no surrogate with gap lines)
    beyond_breakdown: int | None = None
    #: tasks the evaluations were farmed as (the nominal run, the groups split into
    #: chunks of at most CHUNK_EVALUATIONS): what --jobs and mpirun share
    tasks: int = 0


def evaluate_study(scene, spec: UncertaintySpec, values: np.ndarray, *, comm=None,
                   jobs: int | None = None, cache_dir=None, solve: Callable | None = None,
                   simulate: Callable | None = None, progress: bool = False) -> Evaluations:
    """Every evaluation of ``values`` (``(evaluations, D)``, file units, columns in
    ``spec.keys`` order) and the scene's nominal run, spread over the ranks of ``comm``
    (``mpirun -n N``, :func:`tengfield.sweeps.run_tasks`) or ``jobs`` processes; the
    outcome does not depend on how the work was spread.

    ``field_solves``: the distinct field hashes whose surrogate was not in the cache."""
    import contextlib

    from .._console import progress_bar
    from .._farm import run_tasks
    from .._mpi import size_of

    keys = spec.keys
    groups = groups_of(keys, values)
    nominal = Group({}, [(-1, {})])
    # phase 1: each distinct geometry's surrogate once (at the group's reference σ)
    geometry: dict[str, object] = {}
    contact = scene.charge.from_contacts
    if scene.device.ball_charge != 0.0 or SURFACE_CHARGE_SETTING in keys or contact:
        from ..contact_run import field_scene
        for group in [nominal, *groups]:
            if group.dynamic and not changes_field(group.dynamic, scene.device.shape):
                continue       # the nominal geometry (no field key varied): no scene built
            at = scene.with_values(**sections_of(group.dynamic)) if group.dynamic else scene
            ref = solved_scene(field_scene(at) if contact else at)   # contacts: at σ_eq
            geometry.setdefault(ref.field_hash(), (ref, group.dynamic))
    if geometry and solve is None and size_of(comm) > 1:
        # every rank, before the farm: PETSc's initialisation (dolfinx's import) is
        # collective on COMM_WORLD, and a geometry's solve runs in one rank's task (the
        # others waited for it at the farm's end: mpirun -n 2 hung on a cold cache)
        with contextlib.suppress(ImportError):
            from ..field import _dolfinx  # noqa: F401
    bar = progress_bar(len(geometry), "uncertainty: field solves", progress and len(geometry) > 1,
                       unit="geometry", comm=comm)
    try:
        field_results = run_tasks(_field_task, [(s, cache_dir, solve, drawn)
                                                  for s, drawn in geometry.values()],
                                  comm=comm, jobs=jobs, progress=bar.update)
    finally:
        bar.close()
    solved = {digest for digest, status, _ in field_results if status != "cached"}
    messages = [m for _, _, caught in field_results for m in caught]
    # phase 2: the groups (the nominal run first)
    study = uuid.uuid4().hex       # this study's dynamics memo key (workers included)
    tasks = [(scene, g, cache_dir, solve, simulate, study) for g in [nominal, *chunked(groups)]]
    bar = progress_bar(len(tasks), "uncertainty", progress, unit="task", comm=comm)
    try:
        results = run_tasks(_group_task, tasks, comm=comm, jobs=jobs, progress=bar.update)
    finally:
        bar.close()
    rows: list[dict | None] = [None] * len(values)
    regimes = [""] * len(values)
    nominal_out, nominal_regime, beyond = {}, "", None
    for group_rows, digest, status, caught in results:
        if digest is not None and status != "cached":
            solved.add(digest)
        messages.extend(caught)
        for index, outputs, regime, above in group_rows:
            if above is not None and index >= 0:
                beyond = (beyond or 0) + int(above)
            if index < 0:
                nominal_out, nominal_regime = outputs, regime
            else:
                rows[index], regimes[index] = outputs, regime
    if beyond:
        messages.append((RuntimeWarning, f"{beyond} of {len(values)} evaluations have |sigma| "
                         "above the air-breakdown limit sigma_max of their geometry (the gap "
                         "would discharge first; tengfield breakdown): keep the draws of "
                         f"{SURFACE_CHARGE_SETTING} within it"))
    distinct = list(dict.fromkeys(messages))
    return Evaluations(rows=rows, regimes=regimes, nominal=nominal_out,
                       nominal_regime=nominal_regime, field_solves=len(solved),
                       geometries=len(geometry), dynamics_runs=1 + len(groups),
                       warnings=distinct,
                       beyond_breakdown=beyond, tasks=len(tasks))
