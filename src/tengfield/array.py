"""Arrays of cells that each run their own dynamics (``[array]``, issue #11).

Every cell of an ``[array]`` bounces on the same table but with its own
draw (uniform, full widths, one ``numpy.random.default_rng(seed)`` stream,
three numbers per cell whatever is spread):

* ``initial_phase_spread_deg``: the excitation phase the cell sees,
  ``phase_deg + spread (u - 1/2)`` (cells at different places on a vibrating
  structure; for a sine table this is a persistent phase offset);
* ``restitution_spread``: ``restitution + spread (u - 1/2)``, clipped to [0, 1];
* ``initial_velocity_spread_m_per_s``: ``[initial] velocity_m_per_s + spread u``
  (upwards, so a ball starting on the lower plate leaves it).

The cells' trajectories come from the compiled impact map
(:func:`tengfield.dynamics.impact.integrate`, the kernel of
:func:`tengfield.dynamics.simulate`), spread over processes or over the ranks
of an MPI communicator (:func:`tengfield._mpi.farm`); only their compact
segment lists are kept. The electrical stage then walks the output times in
chunks (``CHUNK_VALUES`` cell-samples at a time), evaluates the one shared
surrogate for every cell and feeds the circuit:

* ``connection = "parallel"``: the cells' terminals wired in parallel
  (Q_SC, C_T and I_SC add), then ``[circuit]`` as for one cell (open, short,
  load, or one bridge for the whole array);
* ``"rectified-parallel"``: a bridge per cell, all into ONE store (and chip);
* ``"rectified-per-cell"``: a bridge, store and chip per cell (N independent
  harvesters; energies add, ``V_store_V`` is the cells' mean).

Cells with identical draws share one trajectory (weight = their count), so
an array without spread costs one cell and is exactly ``[device] cells = N``:
its electrical stage is then the single-cell one of :mod:`tengfield.electrical`
with ``cells = N``. With spread, the array's grid is the output samples (the
impact instants of the individual cells are not added to it).
"""
from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._args import checked_write
from . import electrical
from .errors import SceneError
from .source import Source

#: cell-samples evaluated per chunk of the electrical stage (bounds the memory)
CHUNK_VALUES = 1_000_000
#: at most this many cell evaluations at the cells' impact instants for the peaks of an
#: array with spread (every cell at every other cell's impacts grows as cells^2); above
#: it, the instants in the output steps nearest the sampled extremes are kept
PEAK_EVALUATIONS = 20_000_000


# ---------------------------------------------------------------------------
# draws and dynamics
def draw_cells(scene) -> np.ndarray:
    """(cells, 3) array: excitation phase [rad], restitution, initial velocity [m/s]."""
    arr = scene.array
    n = arr.cells
    rng = np.random.default_rng(arr.seed)
    u = rng.random((n, 3))
    draws = np.empty((n, 3))
    draws[:, 0] = scene.excitation.phase + arr.phase_spread * (u[:, 0] - 0.5)
    draws[:, 1] = np.clip(scene.contact.restitution + arr.restitution_spread * (u[:, 1] - 0.5),
                          0.0, 1.0)
    draws[:, 2] = scene.initial.velocity + arr.velocity_spread * u[:, 2]
    if arr.phase_spread == 0.0:
        draws[:, 0] = scene.excitation.phase
    if arr.restitution_spread == 0.0:
        draws[:, 1] = scene.contact.restitution
    if arr.velocity_spread == 0.0:
        draws[:, 2] = scene.initial.velocity
    return draws


def check_array_scene(scene) -> None:
    """One-line SceneErrors for what arrays do not support."""
    from .dynamics.excitation import excitation_kind
    from .dynamics.models import model_of

    if not model_of(scene).event_map:
        raise SceneError(f"[contact] model = {scene.contact.model!r}: [array] runs need the "
                         "impact map (model = 'impact')")
    if not excitation_kind(scene).phased and scene.array.phase_spread > 0:
        raise SceneError("[array] initial_phase_spread_deg needs [excitation] kind = 'sine'")


def cell_trajectory(scene, draw, impacts: bool = False, contacts: bool = False):
    """(Trajectory, number of impacts) of one cell with ``draw`` = (phase, e, v0), and
    with ``impacts`` its impact times [s] as a third element; with ``contacts`` too its
    :class:`~tengfield.dynamics.result.Impacts` (absolute times, plates, speeds: what
    ``[charge] model = "contact"`` charges the cell's ball with) as a fourth. The
    trajectory and the times are on the run's own axis (seconds after ``[initial]
    time_s``, as :func:`tengfield.dynamics.simulate` integrates: the precision does not
    depend on the absolute time)."""
    from .dynamics.impact import Restitution, integrate
    from .dynamics.run import run_span
    from .dynamics.excitation import table_from_scene

    exc = scene.excitation
    duration, t0, _ = run_span(scene, None)
    table = table_from_scene(scene, origin=t0, phase=float(draw[0]))
    restitution = dataclasses.replace(Restitution.from_contact(scene.contact), e=float(draw[1]))
    impacts_wanted = impacts
    traj, impacts, _ = integrate(table, scene.device.stroke, restitution, t_start=0.0,
                                 t_end=duration, gap0=scene.initial.gap,
                                 velocity0=float(draw[2]), period=exc.period, time_origin=t0)
    times = impacts[0]
    if contacts:
        from .dynamics.result import PLATE_NAMES, Impacts
        plates = np.asarray(impacts[1])
        names = PLATE_NAMES[plates] if plates.size else np.zeros(0, dtype="<U5")
        record = Impacts(t0 + np.asarray(times, dtype=float), names,
                         np.asarray(impacts[2], dtype=float).copy(),
                         np.asarray(impacts[3], dtype=float).copy())
        return traj, int(times.size), np.asarray(times, dtype=float).copy(), record
    if impacts_wanted:
        return traj, int(times.size), np.asarray(times, dtype=float).copy()
    return traj, int(times.size)


def _simulate_block(args):
    scene, draws, impacts, contacts = args
    return [cell_trajectory(scene, d, impacts, contacts) for d in draws]


def simulate_cells(scene, draws, *, jobs: int | None = None, comm=None,
                   progress: bool = False, impacts: bool = False,
                   contacts: bool = False) -> list:
    """(trajectory, number of impacts) of the distinct ``draws`` (rows), on ``jobs``
    processes (default: the machine's cores) or over the ranks of ``comm`` (size > 1);
    ``progress``: a tqdm bar on stderr when it is a terminal; ``impacts``: each with
    its impact times as a third element, ``contacts``: and its impacts' record as a
    fourth (:func:`cell_trajectory`)."""
    from ._mpi import farm, rank_of, size_of

    n = len(draws)
    bar = None
    if progress and sys.stderr.isatty() and rank_of(comm) == 0 and n >= 8:
        from tqdm import tqdm
        bar = tqdm(total=n, desc="cell dynamics", unit="cell", file=sys.stderr, leave=False)

    def done(block):
        if bar is not None:
            bar.update(len(block))
        return block

    try:
        if size_of(comm) > 1:
            blocks = _blocks(draws, 4 * size_of(comm))
            parts = farm(comm, [(scene, b, impacts, contacts) for b in blocks], _simulate_block,
                         progress=(lambda k: bar.update(k * len(blocks[0])))
                         if bar is not None else None)
        else:
            jobs = min(jobs or os.cpu_count() or 1, n)
            if jobs <= 1 or n < 8:
                return _simulate_block((scene, draws, impacts, contacts))
            from ._pool import process_pool
            blocks = _blocks(draws, 4 * jobs)
            with process_pool(jobs) as pool:
                parts = [done(p) for p in pool.map(_simulate_block,
                                                   [(scene, b, impacts, contacts)
                                                    for b in blocks])]
    finally:
        if bar is not None:
            bar.close()
    return [cell for part in parts for cell in part]


def _blocks(rows, count):
    count = max(1, min(count, len(rows)))
    return [b for b in np.array_split(np.asarray(rows), count) if len(b)]


# ---------------------------------------------------------------------------
@dataclass
class ArrayResult:
    """Electrical outputs of an array at the output ``time`` [s] (SI).

    ``columns``: the waveform columns (array sums; with a rectifier also the
    store's); ``output``/``reference``: what ``array.png`` compares (the array
    and N x one cell without spread, ``output_label``); ``phases_deg``: each
    cell's phase of the fundamental of its Q_SC over the steady window minus
    the array's mean phase; ``summary``: the JSON block; ``fine``: the store
    record (:class:`tengfield.harvest.HarvestResult`) of a shared store.
    """
    time: np.ndarray
    columns: dict
    output: np.ndarray
    reference: np.ndarray
    output_label: str
    phases_deg: np.ndarray
    period: float
    summary: dict
    fine: object = None
    load: dict | None = None
    stages: dict = field(default_factory=dict)
    #: peak-to-peak V_oc [V], Q_sc [C], I_sc [A] of the array over the steady window, by
    #: the one rule of :func:`tengfield.electrical.terminal_peaks`: the output samples and
    #: just before and after every cell's impacts
    peaks: dict = field(default_factory=dict)
    #: peak max |x| of the same quantities over the same instants
    peak: dict = field(default_factory=dict)
    #: the scene run (set by :func:`run_array`), else None
    scene: Any = field(default=None, repr=False, compare=False)
    #: the cells' contact charge (:class:`CellCharges`, ``[charge] model = "contact"``)
    charge: Any = field(default=None, repr=False, compare=False)

    @property
    def t(self) -> np.ndarray:
        """The output times [s] (``time``, the older name)."""
        return self.time

    def plot(self):
        """array.png's figure (phase histogram; the array against N x one cell)."""
        from .plotting.harvest import array_figure

        return array_figure(self, self.summary)

    @checked_write
    def write(self, out_dir, plots: bool = True, *, title: str = "") -> list:
        """Write what ``tengfield run`` writes of the array beside the run's tables:
        array.png (with ``plots``); returns the paths."""
        from .harvest.output import write_array_files

        return write_array_files(self, out_dir, plots=plots, title=title)


def run_array(scene, curves, nominal, *, jobs: int | None = None, comm=None,
              progress: bool = False, contact=None, window: int = 0) -> ArrayResult:
    """The ``[array]`` of ``scene`` with the shared surrogate ``curves`` (None: Q_SC = 0)
    and the nominal cell's dynamics ``nominal`` (the unperturbed scene, whose
    output times are the array's grid). ``contact``: with ``[charge] model = "contact"``,
    a function of one cell's dynamics giving its
    :class:`~tengfield.contact_run.ContactRun` (the charge its own impacts make); each
    cell's terminals then follow its own charge history (``curves``: the nominal cell's,
    the reference of array.png), and :attr:`ArrayResult.charge` holds the cells' runs.
    ``window``: the first sample of ``nominal`` the outputs cover (a contact run's
    :func:`~tengfield.contact_run.electrical_window`; the charge follows every impact)."""
    check_array_scene(scene)
    n = scene.array.cells
    start = time.perf_counter()
    draws = draw_cells(scene)
    distinct, inverse = np.unique(draws, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    weights = np.bincount(inverse, minlength=len(distinct)).astype(float)
    trajectories = simulate_cells(scene, distinct, jobs=jobs, comm=comm, progress=progress,
                                  impacts=True, contacts=contact is not None)
    dynamics_time = time.perf_counter() - start
    start = time.perf_counter()
    one = scene.with_values(device={"cells": 1}, array={"cells": 0, "connection": "parallel",
                                                      "initial_phase_spread_deg": 0.0,
                                                      "restitution_spread": 0.0,
                                                      "initial_velocity_spread_m_per_s": 0.0})
    scaled = one.with_values(device={"cells": n})
    t = np.asarray(nominal.t, dtype=float)
    elapsed = electrical.elapsed_times(nominal)     # the run's own axis (cells integrate on it)
    paths = [cell[0] for cell in trajectories]
    cell_curves = charge = None
    if contact is not None:      # each distinct cell charged by its own impacts
        runs = [contact(_Sampled(cell[0], elapsed, electrical.time_origin(nominal), cell[3],
                                 absolute=nominal.t)) for cell in trajectories]
        cell_curves = [r.curves for r in runs]
        shaped = next((c for c in cell_curves + [curves] if c is not None), None)
        if shaped is None:
            cell_curves = None   # no field, or no ball ever charged: Q_SC = 0 everywhere
        else:                    # a cell that never charges: Q_SC = 0, its C_T(z)
            cell_curves = [_Uncharged(shaped) if c is None else c for c in cell_curves]
        charge = CellCharges(runs, inverse, weights)
    if window:
        from .dynamics.columns import tail
        nominal = tail(nominal, window)
        t, elapsed = t[window:], elapsed[window:]
    if len(distinct) == 1:       # one cell's curves: the single-cell run's
        result = _identical(scaled, nominal, runs[0].curves if contact is not None
                            else curves, paths[0], n)
    else:
        result = _spread(scene, nominal, curves, paths, weights, elapsed,
                         [cell[2] for cell in trajectories], cells=cell_curves)
    phases = (_phase_of(result["fundamental"]) if "fundamental" in result and curves is not None
              else _phases(scene, cell_curves or curves, paths, elapsed))
    cell_phases = phases[inverse]
    unit = np.exp(1j * np.deg2rad(cell_phases[np.isfinite(cell_phases)]))
    mean = np.angle(unit.mean()) if unit.size else 0.0
    relative = np.rad2deg(np.angle(np.exp(1j * (np.deg2rad(cell_phases) - mean))))
    coherence = float(abs(unit.mean())) if unit.size else math.nan
    ratio = result["value"] / result["reference_value"] if result["reference_value"] else math.nan
    arr = scene.array
    result["summary"].update({
        "cells": n, "connection": arr.connection,
        "initial_phase_spread_deg": math.degrees(arr.phase_spread),
        "restitution_spread": arr.restitution_spread,
        "initial_velocity_spread_m_per_s": arr.velocity_spread, "seed": arr.seed,
        "distinct_dynamics": int(len(distinct)),
        "impacts_per_cell_mean": float(np.average([cell[1] for cell in trajectories],
                                                  weights=weights)),
        "compared": result["compared"], "array_value": result["value"],
        "N_x_one_cell_value": result["reference_value"], "array_over_N_cells": ratio,
        "loss_to_phase_spread": 1.0 - ratio if math.isfinite(ratio) else math.nan,
        "phase_coherence": coherence,
        "phase_std_deg": float(np.nanstd(relative)) if np.isfinite(relative).any()
        else math.nan,           # no cell with a fundamental (all at rest in the window)
        "phases_deg": [float(p) for p in relative],
        "phase_rule": "phase of the fundamental (excitation frequency) of each cell's Q_SC "
                      "over the steady window, minus the array's circular mean",
        "dynamics_wall_time_s": dynamics_time,
        "electrical_wall_time_s": time.perf_counter() - start,
    })
    return ArrayResult(time=t, columns=result["columns"], output=result["output"],
                       reference=result["reference"], output_label=result["label"],
                       phases_deg=relative, period=scene.excitation.period,
                       summary=result["summary"], fine=result.get("fine"),
                       load=result.get("load"), peaks=result["peaks"]["peak_to_peak"],
                       peak=result["peaks"]["peak"], scene=scene, charge=charge)


class _Uncharged:
    """The curves of an array cell whose ball never charges (no contacts, no initial
    charge): Q_SC = I_SC = 0, C_T(z) of ``shaped`` (any cell's curves: C_T does not
    depend on the charge)."""

    def __init__(self, shaped):
        self.shaped = shaped

    def evaluate_many(self, z, z_rate, *, times=None):
        zc = np.clip(np.asarray(z, dtype=float), 0.0, self.shaped.stroke)
        zero = np.zeros_like(zc)
        return zero, zero.copy(), self.shaped.capacitance(zc), \
            self.shaped.capacitance_derivative(zc) * np.asarray(z_rate, dtype=float)


class CellCharges:
    """The contact charge of an array's cells (``[charge] model = "contact"``): ``runs``
    (one :class:`~tengfield.contact_run.ContactRun` per distinct cell dynamics),
    ``inverse`` (each cell's index into ``runs``) and ``weights`` (the cells of each)."""

    def __init__(self, runs, inverse, weights):
        self.runs, self.inverse, self.weights = runs, np.asarray(inverse), weights

    @property
    def representative(self) -> int:
        """The distinct cell whose steady charge is the cells' median (the lower middle
        one for an even count; the lowest cell index among equal charges)."""
        steady = np.array([self.runs[j].block["steady_uC_per_m2"] for j in self.inverse])
        order = np.argsort(steady, kind="stable")
        return int(self.inverse[order[(steady.size - 1) // 2]])

    def block(self) -> dict:
        """summary.json's ``charge`` block of the array: the representative cell's block
        (:attr:`representative`: every cell's when they share one dynamics), and
        ``cells``: each cell's steady charge, rise time, contacts and what binds, and their
        mean, min and max over the cells."""
        j = self.representative
        out = dict(self.runs[j].block)
        per = [self.runs[k].block for k in self.inverse]
        steady = np.array([b["steady_uC_per_m2"] for b in per], dtype=float)
        first = int(np.flatnonzero(self.inverse == j)[0])
        out["cells"] = {
            "count": int(self.inverse.size), "distinct": len(self.runs),
            "reported_cell": first,
            "rule": "the block above is the cell (index reported_cell, from 0) whose steady "
                    "charge is the cells' median; each cell's charge follows its own "
                    "impacts with the same contact law",
            "steady_mean_uC_per_m2": float(np.mean(steady)),
            "steady_min_uC_per_m2": float(np.min(steady)),
            "steady_max_uC_per_m2": float(np.max(steady)),
            "steady_uC_per_m2": [float(v) for v in steady],
            "rise_time_90_s": [b["rise_time_90_s"] for b in per],
            "contacts": [int(b["contacts"]) for b in per],
            "binds": [b["binds"] for b in per],
        }
        return out


class _Sampled:
    """A cell's trajectory (on the run's own axis) with the attributes the electrical
    functions read: output times ``t`` (absolute) and ``elapsed``, ``time_origin``,
    ``impacts`` (absolute, as a DynamicsResult)."""

    def __init__(self, trajectory, elapsed, origin=0.0, impacts=None, absolute=None):
        self._traj = trajectory
        self.elapsed = np.asarray(elapsed, dtype=float)
        self.time_origin = float(origin)
        self.t = origin + self.elapsed if absolute is None else np.asarray(absolute)
        self.gap, self.gap_velocity, self.table = trajectory(self.elapsed)
        self.impacts = impacts

    def sample_elapsed(self, elapsed):
        return self._traj(np.ascontiguousarray(np.atleast_1d(elapsed), dtype=float))

    def sample(self, times):
        return self.sample_elapsed(np.asarray(times, dtype=float) - self.time_origin)


def _identical(scaled, nominal, curves, trajectory, n) -> dict:
    """No spread: the single-cell electrical stage with [device] cells = N."""
    dyn = _Sampled(trajectory, electrical.elapsed_times(nominal), electrical.time_origin(nominal),
                   getattr(nominal, "impacts", None), absolute=nominal.t)
    waves = electrical.scene_waveforms(scaled, dyn, curves)
    out = {"columns": waves, "summary": {},
           "peaks": electrical.terminal_extremes(scaled, dyn, curves, waves)}
    out.update(electrical.circuit_for(scaled).array_identical(scaled, dyn, curves, waves))
    return out


def _evaluate(curves, trajectories, times):
    """(Q_SC, C_T, I_SC) of every trajectory at ``times``: (rows, cells) arrays.
    ``trajectories``: a :class:`TrajectoryBundle` (one compiled call) or a list of
    callables (one call each). ``curves``: the one surrogate of every cell, or a list of
    one contact-charged cell's curves per trajectory (each follows its own charge
    history: :class:`~tengfield.source.terminal.ContactCurves` at ``times`` on the run's
    own axis)."""
    from .dynamics.impact import TrajectoryBundle

    if isinstance(trajectories, TrajectoryBundle):
        z, v = trajectories(times)
    else:
        z = np.empty((times.size, len(trajectories)))
        v = np.empty_like(z)
        for j, traj in enumerate(trajectories):
            z[:, j], v[:, j], _ = traj(times)
    if curves is None:
        zero = np.zeros_like(z)
        return zero, np.full_like(z, 1e-15), zero
    if isinstance(curves, (list, tuple)):     # each cell its own source (its charge history)
        q, c, i = np.empty_like(z), np.empty_like(z), np.empty_like(z)
        for j, cell in enumerate(curves):
            q[:, j:j + 1], c[:, j:j + 1], i[:, j:j + 1] = Source(cell).each_cell(
                times, z[:, j:j + 1], v[:, j:j + 1])
        return q, c, i
    return Source(curves).each_cell(times, z, v)


def _spread(scene, nominal, curves, trajectories, weights, t, impacts, cells=None) -> dict:
    """Cells with different dynamics, walked in time chunks; ``t``: the output times on
    the run's own axis (``nominal``'s elapsed times), ``impacts``: each trajectory's
    impact times on that axis; ``cells``: each trajectory's own curves (the contact
    charge), else None (``curves`` for every cell; ``curves`` is the nominal cell's)."""
    from .dynamics.impact import TrajectoryBundle

    n = float(np.sum(weights))
    c_p = scene.circuit.parallel_capacitance
    g = len(trajectories)
    rows = max(2, CHUNK_VALUES // max(g, 1))
    sums = {k: np.empty(t.size) for k in ("Q", "C", "I")}
    ref = {k: np.empty(t.size) for k in ("Q", "C", "I")}
    window, _ = electrical.steady_window(t, scene)
    basis = np.where(window, np.exp(-1j * scene.excitation.omega * t), 0.0)
    fundamental = np.zeros(g, dtype=complex)
    wired = electrical.circuit_for(scene).spread(scene, t, weights,
                                                 electrical.time_origin(nominal))
    bundle = TrajectoryBundle(trajectories)      # every cell sampled in one call per chunk
    for lo in range(0, t.size, rows):
        times = t[lo:lo + rows]
        q, c, i = _evaluate(cells or curves, bundle, times)
        rq, rc, ri = _evaluate(curves, [lambda x: electrical.sample_elapsed(nominal, x)], times)
        block = slice(lo, lo + times.size)
        fundamental += basis[block] @ q
        for key, value in zip(("Q", "C", "I"), (q, c, i)):
            sums[key][block] = value @ weights
        for key, value in zip(("Q", "C", "I"), (rq, rc, ri)):
            ref[key][block] = value[:, 0] * n
        wired.chunk(block, times, q, c, sums, rq[:, 0], rc[:, 0])
    mask, _ = electrical.steady_window(t, scene)
    gap, vel, table = nominal.gap, nominal.gap_velocity, nominal.table
    columns = {"time_s": np.asarray(nominal.t, dtype=float), "gap_m": np.asarray(gap), "gap_velocity_m_per_s": np.asarray(vel),
               "table_m": np.asarray(table), "V_oc_V": sums["Q"] / sums["C"],
               "Q_sc_C": sums["Q"], "I_sc_A": sums["I"], "C_T_F": sums["C"]}
    if c_p > 0.0:
        columns[electrical.READ_COLUMN] = sums["Q"] / (sums["C"] + c_p)
    out = {"columns": columns, "fundamental": fundamental,
           "summary": {"grid": "output samples (no per-cell impact instants)"},
           "peaks": _spread_peaks(scene, cells or curves, bundle, weights, impacts, t,
                                  columns)}
    compared = wired.finish(sums, ref, columns, mask)
    out["summary"].update(compared.pop("summary", {}))
    out.update(compared)
    return out


def _spread_peaks(scene, curves, bundle, weights, impacts, t, columns) -> dict:
    """``{"peak_to_peak": ..., "peak": ...}`` of V_oc, Q_sc, I_sc (and V_read with
    C_p > 0) of the array's terminals over the steady window:
    the output samples (``columns``) and just before and after every impact of every
    cell (``IMPACT_OFFSET_PERIODS``), where that cell's I_SC jumps; all cells are
    evaluated there (the rule of :func:`tengfield.electrical.terminal_peaks`). Costs
    cells x (all cells' impacts) evaluations; beyond ``PEAK_EVALUATIONS`` only the
    instants in the output steps whose samples are nearest a sampled extreme are taken.
    ``t`` and ``impacts`` are on the run's own axis."""
    mask, _ = electrical.steady_window(t, scene)
    names = {k: c for k, c in electrical.peak_quantities(scene).items() if c in columns}
    low = {k: float(np.min(columns[c][mask])) for k, c in names.items()}
    high = {k: float(np.max(columns[c][mask])) for k, c in names.items()}
    instants = np.unique(np.concatenate([np.asarray(i, dtype=float) for i in impacts]))
    instants = instants[(instants > t[mask][0]) & (instants < t[-1])]
    budget = max(1, PEAK_EVALUATIONS // (2 * max(len(weights), 1)))
    if instants.size > budget:
        # too many to evaluate every cell at each: keep the instants whose output step
        # has an end sample closest to a sampled extreme (of any quantity)
        k = np.clip(np.searchsorted(t, instants) - 1, 0, t.size - 2)
        closeness = np.full(instants.size, np.inf)
        for key, col in names.items():
            x = np.asarray(columns[col])
            span = max(high[key] - low[key], 1e-300)
            ends = np.stack([x[k], x[k + 1]])
            closeness = np.minimum(closeness, np.min(np.minimum(high[key] - ends,
                                                                ends - low[key]), axis=0) / span)
        instants = np.sort(instants[np.argsort(closeness, kind="stable")[:budget]])
    if curves is not None and instants.size:
        eps = electrical.IMPACT_OFFSET_PERIODS * scene.excitation.period
        times = np.sort(np.concatenate([instants - eps, instants + eps]))
        c_p = scene.circuit.parallel_capacitance
        rows = max(2, CHUNK_VALUES // max(len(weights), 1))
        for lo in range(0, times.size, rows):
            q, c, i = _evaluate(curves, bundle, times[lo:lo + rows])
            q, c, i = q @ weights, c @ weights, i @ weights
            values = {"V_oc": q / c, "Q_sc": q, "I_sc": i}
            if "V_read" in names:
                values["V_read"] = q / (c + c_p)
            for key, value in values.items():
                low[key] = min(low[key], float(np.min(value)))
                high[key] = max(high[key], float(np.max(value)))
    return {"peak_to_peak": {k: high[k] - low[k] for k in names},
            "peak": {k: max(abs(high[k]), abs(low[k])) for k in names}}


def _phases(scene, curves, trajectories, t) -> np.ndarray:
    """Phase [deg] of the fundamental of each trajectory's Q_SC over the steady window."""
    window, _ = electrical.steady_window(t, scene)
    if curves is None or np.count_nonzero(window) < 4:
        return np.full(len(trajectories), math.nan)
    basis = np.where(window, np.exp(-1j * scene.excitation.omega * t), 0.0)
    q, _, _ = _evaluate(curves, trajectories, t)
    return _phase_of(basis @ q)


def _phase_of(fundamental) -> np.ndarray:
    phase = np.rad2deg(np.angle(fundamental))
    phase[np.abs(fundamental) == 0.0] = math.nan
    return phase
