"""End-to-end run of one scene: dynamics -> surrogate (cached) -> circuit (DESIGN §1).

:func:`run` returns a :class:`RunResult`: waveform columns as arrays
(``r.waveforms``, also ``r.t``, ``r.V_oc``, ``r.Q_sc``, ``r.I_sc``), the
peak-to-peak values (``r.peaks``; ``r.peak_to_peak`` is the same dict), the peaks
max |x| (``r.peak``), what each stage did (``r.stages``) and a
JSON-ready summary (``r.summary``). The electrical numbers come from
:mod:`tengfield.electrical`; :func:`tengfield.io.write_run_outputs` writes
``waveforms.csv``, ``summary.json`` and the plots. Units are SI; sign
conventions are those of :mod:`tengfield.terminals` (V = V_lower - V_upper,
Q_SC and currents counted lower -> upper through the external circuit,
reference state z = 0).

Stages a scene does not need are left out, and ``summary["stages"]`` says
why: no field solve (and no dolfinx/gmsh import) when a valid cached
surrogate exists or when Q_SC is identically zero (uncharged ball, or a
ball that never leaves the lower electrode); no load ODE unless
``[circuit] kind = "load"``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ._args import checked_write
from . import electrical, terminals
from ._json import jsonable as _jsonable
from ._json import regime_dict
from .electrical import LOAD_COLUMNS, WAVEFORM_COLUMNS  # noqa: F401 - the columns of r.waveforms
from .ensemble import ensemble_block, realisation_row, realisation_seeds
from .scene import check_field
from .source import Source
from .surrogate import (AnchoredTerminalCurves, SurrogateTable, TerminalCurves, leaves_axis,
                        obtain_radial_table)
from .scene.schema import SURFACE_CHARGE_KEY


@dataclass
class Stage:
    """What one stage did: ``status`` is "ran", "cached" or "skipped"."""
    status: str
    reason: str = ""
    wall_time_s: float = 0.0
    details: dict = field(default_factory=dict)


def _column(name: str, doc: str) -> property:
    """A read-only attribute of :class:`RunResult` giving ``waveforms[name]``."""
    return property(lambda self: self.waveforms[name], doc=doc)


@dataclass
class RunResult:
    """Outcome of :func:`run`.

    ``waveforms``: the ``WAVEFORM_COLUMNS`` (+ ``LOAD_COLUMNS`` with a load)
    as arrays, SI (``V_read_V`` too with ``parallel_capacitance_pF`` > 0); ``peaks``:
    peak-to-peak ``V_oc`` [V], ``Q_sc`` [C], ``I_sc`` [A] (and ``V_read`` [V]) over the
    steady window (:func:`tengfield.electrical.terminal_extremes`; kept under this name,
    also ``peak_to_peak``); ``peak``: max |x| of the same over the same instants;
    ``stages``: what each stage did (:class:`Stage`); ``summary``: all of it
    as JSON-ready data (``summary.json``); ``dynamics``, ``table``,
    ``curves``: the pieces the plots need (``table``/``curves`` None when
    the field was not needed). ``t``, ``V_oc``, ``Q_sc``, ``I_sc`` are the
    waveform columns by short name.

    A long run (more than :data:`tengfield.electrical.stream.STREAM_ROWS` samples, 2^20;
    every circuit kind, the ball on the axis, no ``[array]``) computes its electrical stage a chunk at a
    time (:mod:`tengfield.electrical.stream`): its ``waveforms`` is then a read-only
    mapping, not a dict of arrays. The trajectory columns are the dynamics' arrays; the
    first request of another column (``r.V_oc``, ``r.waveforms["I_sc_A"]``,
    ``to_dataframe()``) computes the columns again, whole (memory proportional to the run,
    as before); ``r.waveforms.chunks()`` yields them a chunk at a time, ``.tail`` holds
    the last 5 periods (``plot()``), ``.envelope`` a min/max envelope of the run
    (docs/long_runs.md). ``summary``, ``peaks``, ``peak`` are the same numbers either way.
    """
    scene: Any
    waveforms: dict[str, np.ndarray]
    summary: dict
    dynamics: Any
    table: SurrogateTable | None
    curves: TerminalCurves | None
    peaks: dict[str, float] = field(default_factory=dict)
    stages: dict[str, Stage] = field(default_factory=dict)
    #: max |x| of V_oc [V], Q_sc [C], I_sc [A] (and V_read [V]) over the steady window
    peak: dict[str, float] = field(default_factory=dict)
    #: what the harvesting plots need (V-Q loops, the fine rectifier record, the array)
    extras: dict = field(default_factory=dict)

    t = _column("time_s", "Output times [s].")
    V_oc = _column("V_oc_V", "Ideal open-circuit voltage [V] (no instrument; what an "
                             "instrument of capacitance C_p reads is ``V_read``).")
    Q_sc = _column("Q_sc_C", "Short-circuit charge [C], lower -> upper, zero at the reference.")
    I_sc = _column("I_sc_A", "Short-circuit current [A], lower -> upper through the circuit.")

    @property
    def harvest(self):
        """The rectifier's store record (:class:`tengfield.harvest.HarvestResult`, its
        ``.write`` gives charging.png), or None without a rectifier."""
        return self.extras.get("_fine")

    @property
    def array(self):
        """The ``[array]``'s :class:`tengfield.array.ArrayResult` (its ``.write`` gives
        array.png), or None without an array."""
        return self.extras.get("_array")

    @property
    def peak_to_peak(self) -> dict[str, float]:
        """Peak-to-peak values (the same dict as ``peaks``)."""
        return self.peaks

    @property
    def V_read(self):
        """The voltage [V] an instrument of capacitance C_p reads (with a load: across
        R || C_p); only with ``[circuit] parallel_capacitance_pF`` > 0 (else KeyError)."""
        return self.waveforms[electrical.READ_COLUMN]

    @checked_write
    def write(self, out_dir, plots: bool = True, *, spice: bool = False,
              spice_start_up: bool = False, figures=None) -> list:
        """Write what ``tengfield run -o out_dir`` writes (waveforms.csv, summary.json,
        trajectory/impacts files and, with ``plots``, the PNGs; with ``spice`` teng.lib, as
        ``--spice``: the steady period repeated; ``spice_start_up`` also the run's start-up
        before it, as ``--spice-start-up``); returns the paths. ``figures``: a
        :class:`tengfield.plotting.process.FigureProcess` drawing the figures (complete
        after its ``finish()``), as the CLI passes."""
        from ._args import flag
        from .io import write_dynamics_outputs, write_run_outputs

        where = "tengfield.RunResult.write"
        spice, spice_start_up = flag(where, spice, "spice"), flag(where, spice_start_up,
                                                                   "spice_start_up")
        written = write_run_outputs(self, out_dir, plots=plots, figures=figures)
        written += write_dynamics_outputs(self, out_dir, plots=plots, figures=figures)
        if spice or spice_start_up:
            from pathlib import Path

            from .spice import export
            written.append(export(self, Path(out_dir) / "teng.lib", start_up=spice_start_up))
        return written

    def plot(self, *, last_periods: float | None = 5.0):
        """The waveforms figure (a matplotlib Figure; a notebook shows it): V_OC, Q_SC, I_SC
        (and the load's V and P) against time with the gap, over the last ``last_periods``
        excitation periods (None: the whole run). ``tengfield run`` saves this figure as
        waveforms.png (5 periods)."""
        from ._args import number
        from .plotting.waveforms import run_title, waveforms_figure   # the edge, on use

        last_periods = number("tengfield.RunResult.plot", last_periods, "last_periods", low=0.0,
                              low_open=True, allow_none=True)

        waveforms, title = self.waveforms, run_title(self)
        tail = getattr(waveforms, "tail", None)     # a streamed run kept its last 5 periods
        if tail is not None and last_periods is not None and last_periods <= 5.0:
            waveforms = tail
        if last_periods is not None:
            t = np.asarray(waveforms["time_s"])
            last = t >= t[-1] - last_periods * self.scene.excitation.period
            waveforms = {k: np.asarray(v)[last] for k, v in waveforms.items()}
            title += f", last {last_periods:g} periods"
        return waveforms_figure(waveforms, title=title, parallel_capacitance_pF=(
            self.scene.circuit.parallel_capacitance * 1e12))

    @property
    def ensemble(self) -> dict | None:
        """``[run] realisations`` > 1: summary.json's ``ensemble`` block (per quantity the
        mean, std and Student-t 95 % interval over the realisations; regime fractions);
        None for a single run."""
        return self.summary.get("ensemble")

    @property
    def ensemble_rows(self) -> list[dict] | None:
        """``[run] realisations`` > 1: the rows of ensemble.csv (one per realisation, its
        seed and outputs); None for a single run."""
        return self.extras.get("ensemble_rows")

    def to_dataframe(self):
        """The waveforms as a pandas DataFrame (the columns of waveforms.csv, SI), when
        pandas is installed (it is not a dependency of tengfield)."""
        try:
            import pandas
        except ImportError:
            raise ImportError("RunResult.to_dataframe() needs pandas, which tengfield does not "
                              "install: pip install pandas (RunResult.waveforms holds the same "
                              "columns as a dict of numpy arrays)") from None
        order = [c for c in WAVEFORM_COLUMNS if c in self.waveforms]
        order += [c for c in self.waveforms if c not in order]
        return pandas.DataFrame({c: np.asarray(self.waveforms[c]) for c in order})


def _default_simulate():
    from .dynamics import simulate
    return simulate


def run(scene, *, comm=None, cache_dir=None, solve: Callable | None = None,
        simulate: Callable | None = None, progress: bool = False,
        command_line: str = "", write_cache: bool = True,
        jobs: int | None = None, radial_settings: dict | None = None) -> RunResult:
    """Dynamics, surrogate and circuit for ``scene``; with ``[run] realisations`` = N > 1
    also the other N - 1 noise realisations (:func:`run_ensemble`: ``result.ensemble``,
    ``result.ensemble_rows``, what ``tengfield run`` writes as ensemble.csv).

    ``simulate(scene)`` defaults to :func:`tengfield.dynamics.simulate`,
    ``solve(scene, z, comm=...)`` to :func:`tengfield.field.solve_position`
    (only called when no valid cached surrogate exists); ``comm`` spreads
    the field solves (and the realisations) over its ranks, ``jobs`` the realisations
    over worker processes (default: all cores). ``scene``: a :class:`~tengfield.Scene`, or
    a dict of sections with file-level keys (``{"excitation": {"frequency_hz": 30.0}}``).
    ``radial_settings``: ``mesh_size_mm``, ``degree``, ``tolerance`` of the (z, r)
    surrogate a ball leaving the axis needs (default: its 1.5 mm, P2; a different
    setting is a different cache file).
    """
    from ._args import check_jobs_argument, path
    from .scene import as_scene
    scene = as_scene(scene, "run")
    jobs = check_jobs_argument("tengfield.run", jobs, comm)   # before any work
    cache_dir = path("tengfield.run", cache_dir, "cache_dir", allow_none=True,
                     what="a folder name")
    result = run_one(scene, comm=comm, cache_dir=cache_dir, solve=solve, simulate=simulate,
                     progress=progress, command_line=command_line, write_cache=write_cache,
                     radial_settings=radial_settings)
    _matched_load_summary(result)
    if scene.run.realisations > 1:
        rows, block = run_ensemble(scene, result, comm=comm, jobs=jobs, cache_dir=cache_dir,
                                   progress=progress, solve=solve)
        result.summary["ensemble"] = block
        result.extras["ensemble_rows"] = rows
    return result


def _matched_load_summary(result) -> None:
    """summary.json's ``matched_load``: the resistor that takes the most mean power from
    this run's own Q_SC(t), C_T(t) and motion, and that power (no field solve, no new
    dynamics: :func:`tengfield.electrical.matched.matched_load`, the scan ``tengfield
    design`` makes), or None with ``matched_load_reason``."""
    summary = result.summary
    reason = None
    if result.curves is None:
        reason = "no charge moves (Q_SC = 0): no load takes power"
    elif result.scene.array.cells > 0:
        reason = "an [array]: its cells' loads are the array's (array.png, summary array)"
    elif hasattr(result.waveforms, "chunks"):
        reason = ("a long run streamed a chunk at a time: the load scan would hold the whole "
                  "run; run a shorter duration_s for it")
    if reason is not None:
        summary["matched_load"] = None
        summary["matched_load_reason"] = reason
        return
    from .electrical.matched import matched_load

    start = time.perf_counter()
    scene = result.scene
    load, (power,) = matched_load([scene], [result.dynamics], result.curves, "mean")
    volume = scene.device.cell_volume * scene.device.cells
    summary["matched_load"] = _jsonable({
        "load_ohm": load, "mean_power_W": power,
        "power_density_W_per_m3": power / volume,
        "rule": "the resistor (with the circuit's C_p across it) taking the most mean power "
                "over the steady window of this run's own Q_SC(t), C_T(t) (no field solve): "
                "a log grid around 1 / (2 pi f C_T), then a bounded scalar search to 0.01 "
                "decade (the load circuit's integrator at each R)",
        "wall_time_s": time.perf_counter() - start})


def run_one(scene, *, comm=None, cache_dir=None, solve: Callable | None = None,
            simulate: Callable | None = None, progress: bool = False,
            command_line: str = "", write_cache: bool = True,
            radial_settings: dict | None = None) -> RunResult:
    """One realisation of ``scene`` (its own seed), in four stages: dynamics, field and
    surrogate, circuit, summary (arguments as :func:`run`)."""
    stages: dict[str, Stage] = {}
    if scene.device.ball_charge != 0.0:   # a field stage will run: refuse bad [field] values
        check_field(scene)                # before the dynamics, not after
    electrical.circuit_for(scene).check(scene)   # e.g. a store the step cannot resolve

    if scene.charge.from_contacts:
        check_contact_charge(scene, off_axis=True)   # run: the (z, r) curves
    dynamics = _dynamics_stage(scene, simulate or _default_simulate(), stages)
    hashed = scene   # as loaded: its field hash, its σ (may be "breakdown")
    field_options = dict(cache_dir=cache_dir, comm=comm, solve=solve, progress=progress,
                         command_line=command_line, write_cache=write_cache,
                         radial_settings=radial_settings)
    charged = cell_contact = contact_run = None
    whole = dynamics   # the electrical stage's may be its last periods (a contact run)
    if scene.charge.from_contacts:
        scene, table, curves, limit, charged, cell_contact, contact_run = \
            _contact_charge_stage(scene, dynamics, stages, **field_options)
    else:
        scene, table, curves, limit = _field_stage(scene, dynamics, stages, **field_options)
    if scene.array.cells > 0:
        return _run_array(scene, dynamics, curves, table, stages, comm, progress,
                          contact=cell_contact,
                          window=0 if contact_run is None else contact_run.window)
    if contact_run is not None:
        dynamics = contact_run.dynamics
    stage = electrical_stage(scene, dynamics, curves, table, stages)
    if charged is not None:
        _with_contact_charge(stage, dynamics, charged)
    result = _summary_stage(scene, hashed, dynamics, table, curves, limit, stage, stages,
                            whole=whole)
    if charged is not None and isinstance(result.summary.get("breakdown"), dict) \
            and "sigma_from" in result.summary["breakdown"]:
        result.summary["breakdown"]["sigma_from"] = "contacts (the steady charge)"
    return result


# ---------------------------------------------------------------------------
# [charge] model = "contact" (issue #52; tengfield.source)
#: the waveforms column of the ball's charge [C] (a run whose contacts make it)
from .electrical.stream import BALL_CHARGE_COLUMN  # noqa: E402


from .contact_run import check_contact_charge  # noqa: E402,F401 - the run's own check


def _contact_charge_stage(scene, dynamics, stages, **field_options):
    """``(scene, table, curves, limit, charged, cell)`` of a run whose contacts charge the
    ball:
    the surrogate at a reference charge (sigma_eq, :func:`tengfield.contact_run.field_scene`),
    then :func:`tengfield.contact_run.contact_source`: the air-breakdown cap of ``[charge]
    discharge`` (the band of the run's own trajectory, no field solve more), the charge
    history along the impacts (``stages["charge"]``), the scene at its steady charge
    (what the summary's sigma-dependent blocks use) and :class:`ContactCurves`; ``cell``:
    the same for another trajectory (an ``[array]`` cell's dynamics -> its
    :class:`~tengfield.contact_run.ContactRun`: the same law, table and limit, its own
    impacts and breakdown band)."""
    import warnings

    from .contact_run import contact_source, field_scene

    with warnings.catch_warnings():   # sigma_eq beyond the limit is expected: the cap holds
        warnings.filterwarnings("ignore", message=".*exceeds the air-breakdown limit.*")
        _, table, curves, limit = _field_stage(field_scene(scene), dynamics, stages,
                                               **field_options)
    period = _contact_period(scene)
    run = contact_source(scene, dynamics, table, limit, period=period, curves=curves)
    stages["charge"] = Stage("ran", f"{run.history.contacts} contacts, [charge] model = "
                             "'contact'", run.wall_time_s, {"contacts": run.history.contacts})

    def cell(cell_dynamics):
        return contact_source(scene, cell_dynamics, table, run.limit, period=period)
    return run.scene, run.table, run.curves, run.limit, run.charged, cell, run


def _contact_period(scene) -> float:
    """The period [s] the contacts repeat with: the drive's where the table motion repeats
    each period (a sine; harmonics of one fundamental, no noise); 0 otherwise."""
    from .dynamics.excitation import repeats_each_period
    return float(scene.excitation.period) if repeats_each_period(scene) else 0.0


def _with_contact_charge(stage, dynamics, charged) -> None:
    """The ball's charge column and summary.json's ``charge`` block."""
    history, block = charged
    if BALL_CHARGE_COLUMN not in stage.waveforms:   # the loop's chunks carry it
        stage.waveforms[BALL_CHARGE_COLUMN] = history.at(electrical.elapsed_times(dynamics))
    stage.summary["charge"] = _jsonable(block)
    stage.extras["_charge_history"] = history
    stage.extras["_charge_record"] = _charge_figure_record(history, block, dynamics)


def _charge_figure_record(history, block, dynamics) -> dict:
    """ball_charge.png's record of ``history`` to the end of ``dynamics`` (the electrical
    stage's trajectory), with the window its waveforms cover (``window_s``) where that is
    not the whole run."""
    from .source.contacts import charge_record

    elapsed = electrical.elapsed_times(dynamics)
    record = charge_record(history, block["ball_area_m2"], float(elapsed[-1]))
    if not block.get("waveforms", {}).get("whole_run", True):
        record["window_s"] = (float(elapsed[0]), float(elapsed[-1]))
    return record


def _dynamics_stage(scene, simulate, stages):
    """The ball's motion (``stages["dynamics"]``)."""
    start = time.perf_counter()
    dynamics = simulate(scene)
    stages["dynamics"] = Stage("ran", f"[contact] model = {scene.contact.model!r}",
                               time.perf_counter() - start,
                               {"solver_wall_time_s": getattr(dynamics, "wall_time", None)})
    return dynamics


def _summary_stage(scene, hashed, dynamics, table, curves, limit, stage, stages, *,
                   whole=None) -> RunResult:
    """summary.json's breakdown and measured blocks, and the :class:`RunResult`;
    ``whole``: the whole run's trajectory where ``dynamics`` (the electrical stage's) is
    its last periods (the breakdown band is the whole run's, as the contacts' cap)."""
    summary = stage.summary
    if table is not None:
        _breakdown_summary(summary, scene, hashed, limit, dynamics if whole is None else whole)
    _measured_comparison(summary, scene)
    result = RunResult(scene=scene, waveforms=stage.waveforms, summary=summary,
                       dynamics=dynamics, table=table, curves=curves,
                       peaks=stage.peak_to_peak, stages=stages, peak=stage.peak)
    result.extras = _with_scene(stage.extras, scene)
    return result


def _radial_settings(scene) -> dict:
    """The (z, r) surrogate's settings from ``[field] radial_mesh_size_mm``,
    ``radial_degree``, ``radial_tolerance`` (issue #40)."""
    fld = scene.field
    return {"mesh_size_mm": fld.radial_mesh_size * 1e3, "degree": fld.radial_degree,
            "tolerance": fld.radial_tolerance}


def _field_stage(scene, dynamics, stages, *, cache_dir, comm, solve, progress, command_line,
                 write_cache, radial_settings=None):
    """``(scene, table, curves, limit)``: the surrogate (cached or solved) at the charge the
    run uses (``scene`` at −σ_max for "breakdown"), the terminal curves (with the off-axis
    change of a ball that leaves the axis), the breakdown limit; Nones when Q_SC = 0."""
    gap = dynamics.gap       # a long run's sampled on request: read a chunk at a time
    table = curves = limit = None
    needs_field, why_not = _needs_field(scene, gap)
    if needs_field:
        from .run_surrogate import surrogate_for_run   # "breakdown": at -sigma_max
        scene, table, outcome, limit = surrogate_for_run(
            scene, cache_dir=cache_dir, comm=comm, solve=solve, progress=progress,
            command_line=command_line, write=write_cache)
        if outcome.status == "cached":
            stages["field"] = Stage("cached", outcome.reason, outcome.wall_time,
                                    {"path": outcome.path})
        else:
            stages["field"] = Stage("ran", outcome.reason, outcome.wall_time, {
                "path": outcome.path, "positions": table.count,
                "sum_of_solve_wall_times_s": table.total_solve_wall_time})
        stages["field"].details.update({
            "method": table.method, "degree": table.degree,
            "max_relative_error_estimate": float(np.nanmax(table.field_error)),
            "max_dofs": int(table.dofs.max())})
        curves = TerminalCurves(table, scene.circuit.reference, scene.device.ball_charge)
        if leaves_axis(scene, dynamics):   # [contact] model = "3d", off the axis
            zr_table, zr_outcome = obtain_radial_table(
                scene, cache_dir=cache_dir, comm=comm, solve=solve, progress=progress,
                command_line=command_line, write=write_cache,
                **(radial_settings or _radial_settings(scene)))
            curves = AnchoredTerminalCurves(
                zr_table.curves(scene.circuit.reference, scene.device.ball_charge), curves)
            stages["field_zr"] = Stage(
                "cached" if zr_outcome.status == "cached" else "ran", zr_outcome.reason,
                zr_outcome.wall_time, {
                    "path": zr_outcome.path, "grid": list(zr_table.shape),
                    "mesh_size_mm": zr_table.mesh_size * 1e3, "degree": zr_table.degree,
                    "interpolation_error_estimate": zr_table.interpolation_error,
                    "converged": zr_table.converged,
                    "max_relative_error_estimate": float(np.nanmax(zr_table.field_error)),
                    "sum_of_solve_wall_times_s": zr_table.total_solve_wall_time,
                    "curves": "1-D surrogate on the axis + the 3D change with r"})
        stages["surrogate"] = Stage(
            "cached" if outcome.status == "cached" else "ran",
            f"{table.count} positions, cubic splines of Q_SC and C_T",
            0.0, {"interpolation_error_estimate": table.interpolation_error,
                  "tolerance": table.tolerance, "converged": table.converged,
                  "error_history": table.error_history})
    else:
        stages["field"] = Stage("skipped", why_not)
        stages["surrogate"] = Stage("skipped", why_not)
    return scene, table, curves, limit


# ---------------------------------------------------------------------------
# [run] realisations
def _realisation_task(task):
    index, seed, scene, cache_dir = task
    result = run_one(scene.with_values(excitation={"seed": seed}), cache_dir=cache_dir,
                     write_cache=False)
    return realisation_row(index, seed, result.summary)


def run_ensemble(scene, first, *, comm=None, jobs: int | None = None, cache_dir=None,
                 progress: bool = False, solve=None) -> tuple[list[dict], dict]:
    """Rows of ensemble.csv and the ``ensemble`` block for ``[run] realisations`` = N:
    ``first`` is the run of realisation 0 (the scene's own seed, already done); the other
    N - 1 are farmed over the ranks of ``comm`` (``mpirun -n N``) or ``jobs`` worker
    processes, each reading the surrogate the first run left in the cache. The rows and
    the block do not depend on how the work was spread (:mod:`tengfield.ensemble`: the
    seeds and the statistics). (A scene whose realisations could not differ is refused
    where it is built: ``[run] realisations`` needs noise.)

    If realisation 0 rested (no field stage: the ball never left the lower plate) the
    surrogate is built here once, with ``solve`` (default the field solver), before the
    others run: each of them that moves would otherwise solve the field for itself."""
    from ._console import progress_bar
    from ._farm import run_tasks

    seeds = realisation_seeds(scene.excitation.seed, scene.run.realisations)
    if len(seeds) > 1 and first.table is None and scene.device.ball_charge != 0.0:
        from .run_surrogate import surrogate_for_run   # the surrogate run_one would cache
        surrogate_for_run(scene, cache_dir=cache_dir, comm=comm, solve=solve, progress=progress)
    rows = [realisation_row(0, seeds[0], first.summary)]
    tasks = [(k, seeds[k], scene, cache_dir) for k in range(1, len(seeds))]
    bar = progress_bar(len(seeds), "realisations", progress, unit="run", comm=comm, initial=1)
    try:
        rows += run_tasks(_realisation_task, tasks, comm=comm, jobs=jobs, progress=bar.update)
    finally:
        bar.close()
    return rows, ensemble_block(rows)


@dataclass
class ElectricalStage:
    """What :func:`electrical_stage` computed: the waveform columns (SI), summary.json's
    blocks, peak-to-peak and peak values by short name, and the figures' extras."""
    waveforms: dict
    summary: dict
    peak_to_peak: dict
    peak: dict
    extras: dict


def electrical_stage(scene, dynamics, curves, table, stages: dict | None = None
                     ) -> ElectricalStage:
    """The circuit stage of :func:`run` for ``scene`` with ``dynamics`` and ``curves``
    (``table``/``curves`` None: no field needed): waveforms, summary (with the energy
    per cycle), peaks. ``stages`` (if given) gets its ``"circuit"`` entry. Used by
    :func:`run`, the sweeps and the uncertainty study (one electrical stage, not a copy).

    The one electrical loop (:class:`tengfield.electrical.loop.Loop`) drives the circuit
    over the source's chunks: a whole run is one chunk, a long one
    (:func:`tengfield.electrical.stream.streams`) many, its waveforms a
    :class:`~tengfield.electrical.stream.StreamedWaveforms`. The instrument, the peaks,
    the summary and the energy per cycle are done once, here and in the loop."""
    stages = {} if stages is None else stages
    from .electrical import stream
    from .electrical.loop import Loop

    start = time.perf_counter()
    streamed = stream.streams(scene, dynamics, curves)
    source = Source.of_scene(scene, curves, dynamics)
    loop = stream.StreamedRun(scene, source) if streamed else Loop(scene, source)
    reduced = loop.reduce()
    entry = loop.entry
    details: dict = {}
    if streamed:
        waveforms = stream.StreamedWaveforms(loop, reduced)
        ran = loop.finish(reduced, f" (streamed: {loop.chunk_count} chunks of "
                                   f"{loop.chunk_rows} rows)")
        details["streamed_chunks"] = loop.chunk_count
        t, mask = reduced["tail"]["_elapsed"], None     # the cycle's: the last periods
    else:
        waveforms = reduced["columns"]
        ran = loop.finish(reduced)
        t = loop.elapsed                  # the run's own axis: exact step lengths
        mask, _ = electrical.steady_window(t, scene)
    stages["circuit"] = Stage(ran.status, ran.reason, time.perf_counter() - start,
                              {**ran.details, **details})
    extremes = reduced["extremes"]
    summary = _summary(scene, dynamics, waveforms, stages, table, extremes=extremes,
                       circuit_blocks=lambda window: entry.summary(scene, ran, waveforms,
                                                                   window),
                       entry=entry)
    extras: dict = {"_envelope": reduced["envelope"]} if streamed else {}
    if curves is not None:
        max_gap = reduced["max_gap"]
        out: dict = {"energy_per_cycle": electrical.cmeo(scene, curves, max_gap)}
        added = entry.cycle(scene, source, ran, t, mask, max_gap)
        out["energy_per_cycle"].update(added.pop("energy_per_cycle", {}))
        out.update(added)
        extras.update(out)
        summary.update(_jsonable({k: v for k, v in out.items() if not k.startswith("_")}))
    return ElectricalStage(waveforms, summary, extremes["peak_to_peak"], extremes["peak"], extras)


def _run_array(scene, dynamics, curves, table, stages, comm, progress,
               contact=None, window: int = 0) -> RunResult:
    """``[array]``: every cell its own dynamics (tengfield.array), one surrogate. The
    nominal cell's columns are whole arrays (a long run's sampled ones are built:
    tengfield.array holds its outputs whole). ``contact``: ``[charge] model = "contact"``,
    one cell's dynamics -> its :class:`~tengfield.contact_run.ContactRun` (each cell
    charged by its own impacts); ``window``: the first sample the outputs cover
    (:func:`tengfield.contact_run.electrical_window`)."""
    from .array import run_array
    from .dynamics.columns import tail, with_arrays

    start = time.perf_counter()
    whole = with_arrays(dynamics)   # the cells' charge over the whole run, the outputs
    arr = run_array(scene, curves, whole, comm=comm, progress=progress, contact=contact,
                    window=window)                      # over its window
    dynamics = tail(whole, window)
    waveforms = arr.columns
    block = dict(arr.summary)
    rect = block.pop("rectifier", None)
    stages["circuit"] = Stage(
        "ran", f"[array] {scene.array.cells} cells, connection = {scene.array.connection!r}, "
        f"[circuit] kind = {scene.circuit.kind!r}", time.perf_counter() - start,
        {"dynamics_wall_time_s": block["dynamics_wall_time_s"],
         "distinct_dynamics": block["distinct_dynamics"]})
    peaks = dict(arr.peaks)      # the one rule: samples and every cell's impact instants
    peak = dict(arr.peak)
    entry = electrical.circuit_for(scene)
    if electrical.READ_COLUMN in waveforms and entry.read_column in waveforms:
        # the instrument across the array's load reads its voltage (continuous: samples)
        waveforms[electrical.READ_COLUMN] = waveforms[entry.read_column]
        mask, _ = electrical.steady_window(electrical.elapsed_times(dynamics), scene)
        read = np.asarray(waveforms[entry.read_column])[mask]
        peaks["V_read"] = float(np.max(read) - np.min(read))
        peak["V_read"] = float(np.max(np.abs(read)))
    if scene.instrument.given:     # what the [instrument] records of the array's terminals
        if electrical.READ_COLUMN not in waveforms:
            waveforms[electrical.READ_COLUMN] = waveforms["Q_sc_C"] / (
                waveforms["C_T_F"] + scene.circuit.parallel_capacitance)
        electrical.read_instrument(scene, dynamics, waveforms,
                                   loaded=entry.read_column not in waveforms)
        mask, _ = electrical.steady_window(electrical.elapsed_times(dynamics), scene)
        for name, (column, _) in electrical.READ_COLUMNS.items():
            read = np.asarray(waveforms[column])[mask]
            peaks[name] = float(np.max(read) - np.min(read))
            peak[name] = float(np.max(np.abs(read)))
    summary = _summary(scene, dynamics, waveforms, stages, table,
                       extremes={"peak_to_peak": peaks, "peak": peak},
                       circuit_blocks=lambda mask: electrical.no_load(scene), entry=entry)
    summary["cells"] = scene.array.cells
    if arr.load is not None:
        summary["load"] = {"mean_power_W": arr.load["mean_power_W"]}
        summary.pop("load_reason", None)
    if rect is not None:
        summary["rectifier"] = rect
    summary["array"] = block
    extras = {"_array": arr, "_fine": arr.fine}
    if arr.charge is not None:      # each cell's ball charged by its own impacts
        summary["charge"] = arr.charge.block()
        extras.update(_array_charge_record(arr.charge, dynamics))
    _measured_comparison(summary, scene)
    result = RunResult(scene=scene, waveforms=waveforms, summary=_jsonable(summary),
                       dynamics=dynamics, table=table, curves=curves, peaks=peaks,
                       stages=stages, peak=peak)
    result.extras = _with_scene(extras, scene)
    return result


#: at most this many other distinct cells' charge histories drawn in an array's
#: ball_charge.png (beside the reported cell's)
ARRAY_CHARGE_LINES = 24


def _array_charge_record(charge, dynamics) -> dict:
    """ball_charge.png's record of an ``[array]``: the reported cell's (the median steady
    charge, :class:`tengfield.array.CellCharges`) with the other distinct cells' sigma(t)
    (up to :data:`ARRAY_CHARGE_LINES`, evenly chosen) drawn beside it."""
    j = charge.representative
    area = charge.runs[j].block["ball_area_m2"]
    record = _charge_figure_record(charge.runs[j].history, charge.runs[j].block, dynamics)
    others = [k for k in range(len(charge.runs)) if k != j]
    if len(others) > ARRAY_CHARGE_LINES:
        others = [others[int(i)] for i in np.linspace(0, len(others) - 1, ARRAY_CHARGE_LINES)]
    record["cells"] = [charge.runs[k].history.at(record["grid_s"]) / area * 1e6
                       for k in others]
    record["cell_count"] = int(charge.inverse.size)
    return {"_charge_history": charge.runs[j].history, "_charge_record": record}


def _with_scene(extras: dict, scene) -> dict:
    """``extras`` with the store record (``_fine``, a HarvestResult) knowing the scene it
    ran with (its ``.scene``, which ``.write`` draws charging.png with)."""
    import dataclasses

    fine = extras.get("_fine")
    if (dataclasses.is_dataclass(fine) and getattr(fine, "scene", False) is None
            and "scene" in {f.name for f in dataclasses.fields(fine)}):
        extras = {**extras, "_fine": dataclasses.replace(fine, scene=scene)}
    return extras


def _measured_comparison(summary, scene) -> None:
    """summary["measured_comparison"]: the ``[reference]`` values beside the tool's
    (:func:`tengfield.quantities.compare_measured`), when the scene gives any."""
    from .quantities import compare_measured

    block = compare_measured(summary, scene.reference.given())
    if block is not None:
        summary["measured_comparison"] = _jsonable(block)


def _breakdown_summary(summary, scene, hashed, limit, dynamics=None) -> None:
    """summary["breakdown"] (with the band and the trajectory's V_gap/V_b at the scene's
    σ), ``breakdown_band`` (σ = "breakdown": each main output at the band's three σ) and
    the breakdown-limited CMEO / FOM beside the ideal ones."""
    from . import air_breakdown

    summary["field_hash"] = hashed.field_hash()     # the surrogate's (σ = "breakdown" too)
    summary["breakdown"] = _jsonable(air_breakdown.summary_block(limit, scene, hashed))
    if limit is not None and dynamics is not None:
        summary["breakdown"].update(_jsonable(air_breakdown.band_summary(
            summary, scene, hashed, limit, dynamics)))
        if "outputs" in summary["breakdown"]:
            summary["breakdown_band"] = summary["breakdown"].pop("outputs")
    if limit is not None and summary.get("energy_per_cycle"):
        summary["energy_per_cycle"].update(_jsonable(air_breakdown.limited_energy(
            summary["energy_per_cycle"], limit, scene.device.surface_charge)))


def _leaves_zero(gap) -> bool:
    """Whether any sample of ``gap`` is not 0 (a column sampled on request: a chunk at a
    time, stopping at the first)."""
    if isinstance(gap, np.ndarray) or not hasattr(gap, "chunks"):
        return not np.all(np.asarray(gap) == 0.0)
    return any(np.any(values != 0.0) for _, _, values in gap.chunks())


def _needs_field(scene, gap) -> tuple[bool, str]:
    if scene.device.ball_charge == 0.0:
        return False, f"ball charge is zero ([device] {SURFACE_CHARGE_KEY} = 0): Q_SC = 0"
    if not _leaves_zero(gap) and not _cells_differ(scene):
        return False, "the ball never leaves the lower electrode: Q_SC = 0 (reference state)"
    return True, ""


def _cells_differ(scene) -> bool:
    """Whether an ``[array]``'s cells may move unlike the nominal cell (any spread): a
    nominal ball at rest then does not mean Q_SC = 0 (a cell launched by its initial
    velocity bounces)."""
    arr = scene.array
    return arr.cells > 0 and (arr.phase_spread > 0.0 or arr.restitution_spread > 0.0
                              or arr.velocity_spread > 0.0)


def _rest_reason(regime: dict | None, scene) -> None:
    """A ball at rest under a sine below lift-off: ``regime["reason"]`` (why, and the
    lift-off amplitude and frequency) and ``regime["liftoff"]`` (the numbers;
    :func:`tengfield.dynamics.mapping.below_liftoff`)."""
    if not regime or regime.get("regime") != "rest":
        return
    from .dynamics.mapping import below_liftoff

    block = below_liftoff(scene)
    if block is not None:
        regime["reason"] = block.pop("reason")
        regime["liftoff"] = block


def _summary(scene, dynamics, waveforms, stages, table, *, extremes, circuit_blocks,
             entry) -> dict:
    """summary.json; ``extremes``: ``{"peak_to_peak": {...}, "peak": {...}}`` by short
    name (``V_oc``), written by column name (``V_oc_V``); ``circuit_blocks(mask)``: the
    circuit's ``load`` block (and ``load_reason``) over the steady window ``mask``;
    ``entry``: the circuit's registry entry (``load_ohm`` only where it has a load)."""
    columns = electrical.peak_quantities(scene)
    blocks = {stat: {columns[name]: value for name, value in values.items()}
              for stat, values in extremes.items()}
    circuit_block = {"kind": scene.circuit.kind,
                     "parallel_capacitance_F": scene.circuit.parallel_capacitance}
    if entry.has_load:
        circuit_block["load_ohm"] = scene.circuit.load
    t = waveforms["time_s"]
    first, window_reason = electrical.steady_window_index(t, scene)
    # the steady window over the rows (a streamed run: a slice, no n-sized mask)
    mask = slice(first, None) if hasattr(waveforms, "chunks") else \
        electrical.steady_window(t, scene)[0]
    summary: dict[str, Any] = {
        "scene": scene.source,
        # no field stage ran for a scene whose field values are refused (uncharged ball)
        "field_hash": None if scene.field_problems else scene.field_hash(),
        "reference": terminals.of_scene(scene).name,
        "sign_convention": ("V = V_lower - V_upper; Q_SC and currents lower -> upper through "
                            "the external circuit; reference state: ball on the lower electrode")
        if len(scene.device.electrode_names) == 2 else
        ("V = V_lower (the ground at 0 V); Q_SC and currents lower electrode -> ground "
         "through the external circuit; reference state: ball on the lower electrode"),
        "cells": scene.device.cells,
        "circuit": circuit_block,
        "window": {"start_s": float(t[first]), "end_s": float(t[-1]),
                   "rule": window_reason},
        "peak_to_peak": blocks["peak_to_peak"],
        "peak_to_peak_rule": "over the output samples of the steady window and just before "
                             "and after every impact (exact extremes of I_SC)",
        "peak": blocks["peak"],
        "peak_rule": "max |x| over the same instants as peak_to_peak",
        "regime": regime_dict(getattr(dynamics, "regime", None)),
        "load": None,
        "stages": stages,
    }
    _rest_reason(summary["regime"], scene)
    if electrical.READ_COLUMN in waveforms:
        summary["V_read_rule"] = (
            "V_read_V: what an instrument of capacitance C_p = "
            f"{scene.circuit.parallel_capacitance * 1e12:g} pF reads"
            + (f" across the circuit ({entry.read_column})" if entry.read_column in waveforms
               else ": Q_SC / (C_T + C_p) of the open terminal")
            + "; V_oc_V is the ideal open-circuit voltage")
    if table is not None:
        summary["surrogate_error_estimate"] = table.interpolation_error
        zr = stages.get("field_zr")
        if zr is not None and zr.details:   # the (z, r) table governs off the axis (#42)
            governing = max(float(zr.details.get("interpolation_error_estimate", 0.0)),
                            float(zr.details.get("max_relative_error_estimate", 0.0)),
                            float(table.interpolation_error))
            summary["surrogate_error_estimate"] = governing
            summary["surrogate_error_rule"] = (
                "the largest of the axis table's interpolation estimate and the (z, r) "
                "table's interpolation and field error estimates")
    summary.update(circuit_blocks(mask))
    return _jsonable(summary)
