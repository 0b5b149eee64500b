"""The output sets of the commands: which CSV and JSON files, with which columns.

* ``waveforms.csv`` (:func:`write_waveforms_csv`), ``summary.json`` and the
  plots of ``tengfield run`` (:func:`write_run_outputs`);
* ``trajectory.csv``, ``impacts.csv`` (3D: ``contacts.csv``) and the trajectory
  figures of the dynamics (:func:`write_dynamics_files`);
* ``map.csv`` (:func:`write_map_csv`, from :mod:`tengfield.dynamics.output`),
  ``sweep.csv`` (:func:`write_sweep_csv`, with its columns :data:`SWEEP_COLUMNS`).

* ``report.csv`` and ``report.json`` (:func:`write_report_csv`,
  :func:`write_report_json`; the report's other files: :mod:`tengfield.accuracy_report.output`).

Numbers are SI with the unit in the column name. The time column of
``waveforms.csv`` is written with 17 significant digits (``%.17g``, exact
round trip) so that the samples of a long run stay distinct; the other
waveform columns with 10. The dynamics files (1D and 3D trajectories,
impacts, contacts) hold every double as its shortest round-trip decimal.

How one file is written is :mod:`tengfield.files` (its :func:`atomic_path`,
:func:`writable_target`, :func:`write_csv` and :func:`write_json` are importable
from here too): the tables of numbers (waveforms, dynamics, ensemble) by
:func:`write_csv`, Apache Arrow's compiled writer, in place after
:func:`writable_target` (inside the staging directory of ``-o DIR``); JSON,
``map.csv``, ``sweep.csv`` and ``report.csv`` (:func:`~tengfield.files.write_rows`)
atomically.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .quantities import TERMINAL, column_name

from .files import (atomic_path, figure_file, writable_target, write_csv,  # noqa: F401
                     write_figure, write_json, write_rows)
from .electrical import READ_COLUMN, READ_COLUMNS, WAVEFORM_COLUMNS, all_columns  # noqa: F401
from .plotting.waveforms import run_title
from .dynamics.output import (EXTRA_COLUMNS, MAP_COLUMNS, _trajectory_without,  # noqa: F401
                               dynamics_tables, trajectory_columns, write_contacts_csv,
                               write_dynamics_files, write_impacts_csv, write_map_csv,
                               write_trajectory3d_csv, write_trajectory_csv)

#: format of a time column: every double round-trips
TIME_FORMAT = "%.17g"
#: format of the other waveform columns
VALUE_FORMAT = "%.10g"


# ---------------------------------------------------------------------------
# tengfield run
def write_waveforms_csv(path: str | Path, waveforms: dict) -> Path:
    """CSV with the columns of :func:`waveform_columns` (those run.h5 holds too); a
    streamed run's a chunk at a time."""
    columns = waveform_columns(waveforms)
    formats = {c: TIME_FORMAT if i == 0 else VALUE_FORMAT for i, c in enumerate(columns)}
    if hasattr(waveforms, "chunks"):   # a streamed run (tengfield.electrical.stream)
        for k, chunk in enumerate(waveforms.chunks()):
            data = np.column_stack([chunk[c] for c in columns])
            write_csv(path, columns, list(data.T), formats=formats, append=k > 0)
        return Path(path)
    data = np.column_stack([waveforms[c] for c in columns])   # one dtype, as numpy.savetxt
    return write_csv(path, columns, list(data.T), formats=formats)


def waveform_columns(waveforms) -> list[str]:
    """The columns of a run's waveforms table, in order, for waveforms.csv and run.h5
    alike: ``WAVEFORM_COLUMNS``, the read ones present (``V_read_V``, ``Q_read_C``,
    ``I_read_A``: through C_p or an ``[instrument]``), the circuit's present (the
    registry's order, :func:`tengfield.electrical.all_columns`)."""
    read = [column for column, _ in READ_COLUMNS.values()]
    source = ["q_ball_C"]   # the ball's charge, where the contacts make it ([charge])
    return WAVEFORM_COLUMNS + [c for c in read + all_columns() + source if c in waveforms]


def write_run_outputs(result, out_dir: str | Path, *, plots: bool = True,
                      figures=None) -> list[Path]:
    """waveforms.csv, summary.json and, with ``plots``, waveforms.png and surrogate.png
    of a :class:`tengfield.pipeline.RunResult` (see also :func:`write_dynamics_outputs`);
    a streamed long run (:mod:`tengfield.electrical.stream`) also record.png, the whole
    run as a min/max envelope, and its tables a chunk at a time.

    With ``figures`` (a :class:`tengfield.plotting.process.FigureProcess`) the figures
    are sent to it and complete after ``figures.finish()``, which the caller calls."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    if plots:
        from .plotting.waveforms import plot_waveforms, visited_positions
        shown = 5.0 * result.scene.excitation.period       # the last 5 periods, readable
        # a streamed run (tengfield.electrical.stream) kept them: its columns are not held
        source = getattr(result.waveforms, "tail", None) or result.waveforms
        t = np.asarray(source["time_s"])
        last = t >= t[-1] - shown                          # sent, not the whole run
        waveforms = {k: np.asarray(v)[last] for k, v in source.items()}
        written.append(_figure(
            figures, plot_waveforms, waveforms, path=out / figure_file("waveforms"),
            title=run_title(result) + ", last 5 periods",
            parallel_capacitance_pF=result.scene.circuit.parallel_capacitance * 1e12))
        envelope = (getattr(result, "extras", None) or {}).get("_envelope")
        if envelope is not None:      # a streamed run: the whole record, min/max per bin
            from .plotting.record import plot_record
            written.append(_figure(
                figures, plot_record, envelope, path=out / figure_file("record"),
                title=run_title(result) + ", whole run: min/max per time bin",
                parallel_capacitance_pF=result.scene.circuit.parallel_capacitance * 1e12))
        if result.curves is not None:
            from .surrogate.output import write_surrogate_figure
            written.append(write_surrogate_figure(
                result.table, result.curves, out, cells=result.scene.device.cells,
                visited=visited_positions(result.dynamics), figures=figures,
                error_estimate=result.summary.get("surrogate_error_estimate")))
        written += write_harvest_plots(result, out, figures=figures)
    rows = (getattr(result, "extras", None) or {}).get("ensemble_rows")
    if rows:
        from .ensemble import ENSEMBLE_COLUMNS
        columns = [[r[c] for r in rows] if c == "regime"
                   else np.array([np.nan if r.get(c) is None else r[c] for r in rows], dtype=float)
                   if c not in ("realisation", "seed") else [int(r[c]) for r in rows]
                   for c in ENSEMBLE_COLUMNS]
        written.append(write_csv(writable_target(out / "ensemble.csv"), ENSEMBLE_COLUMNS,
                                 columns))
        if plots:
            from .plotting.ensemble import plot_ensemble
            written.append(_figure(figures, plot_ensemble, rows, result.summary["ensemble"],
                                   path=out / figure_file("ensemble")))
    if run_tables_format(result, warn=True) == "hdf5":
        written.insert(0, write_run_hdf5(writable_target(out / HDF5_FILE), result))
    else:
        written.insert(0, write_waveforms_csv(writable_target(out / "waveforms.csv"),
                                              result.waveforms))
    written.append(write_json(out / "summary.json", result.summary))
    return written


def run_tables_format(result, *, warn: bool = False) -> str:
    """``"hdf5"`` (one run.h5 holding waveforms, trajectory and impacts) if ``[run]
    output_format = "hdf5"`` or the run has more samples than a CSV table may
    (:data:`tengfield.files.hdf5.MAX_CSV_ROWS`; with ``warn``, one warning says so), else
    ``"csv"``."""
    from .files.hdf5 import MAX_CSV_ROWS

    if result.scene.run.output_format == "hdf5":
        return "hdf5"
    rows = len(result.waveforms["time_s"])
    if rows > MAX_CSV_ROWS:
        if warn:
            import warnings
            warnings.warn(f"{rows:.3g} samples ([run] duration_s x sample_rate_hz) pass the "
                          f"CSV bound of {MAX_CSV_ROWS:.0e} rows: the tables go to {HDF5_FILE} "
                          "(waveforms, trajectory, impacts; set [run] output_format = "
                          "'hdf5' to choose it)", RuntimeWarning, stacklevel=2)
        return "hdf5"
    return "csv"


#: the HDF5 file of ``[run] output_format = "hdf5"`` (tengfield.files.hdf5)
HDF5_FILE = "run.h5"


def write_run_hdf5(path: str | Path, result) -> Path:
    """run.h5 of a :class:`tengfield.pipeline.RunResult`: groups ``waveforms`` (the
    columns of waveforms.csv), ``trajectory`` (the dynamics' columns; those equal to a
    waveform column are hard links to it), ``impacts`` (3D: and ``contacts``), every
    column with its ``units``; summary.json and the scene text as file attributes
    (:mod:`tengfield.files.hdf5`)."""
    from ._json import jsonable
    from .files.hdf5 import write_tables
    from . import __version__

    waveforms = result.waveforms
    columns = waveform_columns(waveforms)
    if hasattr(waveforms, "chunks"):   # a streamed run: written a chunk at a time
        tables = {"waveforms": _Columns(waveforms, columns)}
    else:
        tables = {"waveforms": {c: waveforms[c] for c in columns}}
    tables.update(dynamics_tables(result.dynamics, result.scene))
    return write_tables(path, tables, attrs={
        "tengfield_version": __version__, "scene_text": result.scene.text or "",
        "summary_json": json.dumps(jsonable(result.summary)),
        "layout": "one group per table (waveforms, trajectory, impacts[, contacts]), one "
                  "dataset per column with its 'units' attribute; trajectory columns equal "
                  "to waveform columns are hard links"})


class _Columns:
    """The chunked columns of a streamed run that run.h5 writes (``columns``, in order)."""

    def __init__(self, waveforms, columns):
        self._w, self._columns = waveforms, [c for c in columns if c in waveforms]
        self.rows = waveforms.rows

    def __iter__(self):
        return iter(self._columns)

    def __contains__(self, name) -> bool:
        return name in self._columns

    def source_of(self, name):
        return self._w.source_of(name)

    def chunks(self):
        for chunk in self._w.chunks():
            yield {c: chunk[c] for c in self._columns}


def _figure(figures, function, *data, path: Path, **kwargs) -> Path:
    """:func:`tengfield.files.write_figure` (drawn here or sent to ``figures``)."""
    return write_figure(function, *data, path=path, figures=figures, **kwargs)


def write_harvest_plots(result, out: Path, *, figures=None) -> list[Path]:
    """charging.png (rectifier), vq.png (load or rectifier) and array.png (an
    ``[array]`` run) of a :class:`tengfield.pipeline.RunResult`, where they apply
    (``figures``: as for :func:`write_run_outputs`): the store record's and the array's
    through the writers their own ``.write`` calls (:mod:`tengfield.harvest.output`)."""
    from .harvest.output import write_array_figure, write_charging_figure
    from .plotting import harvest as hp

    extras = getattr(result, "extras", {}) or {}
    written = []
    if extras.get("_fine") is not None:
        written.append(write_charging_figure(extras["_fine"], out, scene=result.scene,
                                             title=run_title(result), figures=figures))
    if extras.get("_charge_record") is not None:   # [charge] model = "contact"
        from .plotting.ball_charge import plot_ball_charge
        written.append(_figure(figures, plot_ball_charge, extras["_charge_record"],
                               result.summary.get("charge", {}),
                               path=out / figure_file("ball_charge"), title=run_title(result)))
    if extras.get("_vq"):
        written.append(_figure(figures, hp.plot_vq, extras["_vq"],
                               result.summary.get("energy_per_cycle", {}), path=out / figure_file("vq"),
                               title=run_title(result)))
    if extras.get("_array") is not None:
        written.append(write_array_figure(extras["_array"], out,
                                          summary=result.summary.get("array", {}),
                                          title=run_title(result), figures=figures))
    return written


# ---------------------------------------------------------------------------
# dynamics


def write_dynamics_outputs(result, out_dir: str | Path, *, plots: bool,
                           figures=None) -> list[Path]:
    """:func:`write_dynamics_files` of a :class:`tengfield.pipeline.RunResult` (the figure
    shows the last 5 periods, as waveforms.png does). Its trajectory.csv does not repeat
    the columns of waveforms.csv (``time_s`` joins the two; a 1-D run's trajectory.csv is
    then ``time_s`` alone, the motion being in waveforms.csv); in run.h5 the repeated
    columns are hard links."""
    csv_tables = run_tables_format(result) == "csv"
    same_times = csv_tables and _same_times(result)
    return write_dynamics_files(result.dynamics, result.scene, out_dir, plots=plots,
                                max_periods=5, figures=figures, tables=csv_tables,
                                written_elsewhere=_waveform_columns(result) if same_times
                                else ())


def _waveform_columns(result) -> list[str]:
    """The columns :func:`write_waveforms_csv` writes for ``result``."""
    return waveform_columns(result.waveforms)


def _same_times(result) -> bool:
    """waveforms.csv and the trajectory share their time samples (and so their rows)."""
    a, b = result.waveforms["time_s"], result.dynamics.t
    if a is b:                     # e.g. a long run's column sampled on request
        return True
    a, b = np.asarray(a), np.asarray(b)
    return a is b or (a.shape == b.shape and bool(np.array_equal(a, b)))


# ---------------------------------------------------------------------------
# tengfield sweep
#: the terminal statistics of a sweep row: (column, statistic, short name), names from
#: :mod:`tengfield.quantities` (``V_oc_pp_V``, ..., ``I_sc_peak_A``, ``V_read_pp_V``)
TERMINAL_COLUMNS = [(column_name(name, stat), stat, name[:name.rindex("_")])
                    for stat in ("peak_to_peak", "peak") for name in (*TERMINAL, "V_read_V")]
#: the load columns of sweep.csv (a --load-ohm axis): the numbers `tengfield run
#: --set circuit.kind=load` reports at that load (its summary's ``load`` block), and the
#: rms of the resistor's voltage and current, sqrt(P_mean R) and sqrt(P_mean / R)
LOAD_SWEEP_COLUMNS = ["V_load_pp_V", "I_load_pp_A", "V_load_rms_V", "I_load_rms_A"]
#: columns of ``sweep.csv`` (one row per grid point and load); ``V_read_*`` empty without
#: an instrument (``[circuit] parallel_capacitance_pF`` = 0)
SWEEP_COLUMNS = (["frequency_hz", "amplitude_mm", "load_ohm", "regime", "period"]
                 + [column_name(n, "peak_to_peak") for n in TERMINAL]   # the first columns,
                 + ["P_mean_W", "power_density_W_per_m3"]                # kept in place
                 + [c for c, _, _ in TERMINAL_COLUMNS if c not in
                    [column_name(n, "peak_to_peak") for n in TERMINAL]]
                 + LOAD_SWEEP_COLUMNS)


def write_sweep_csv(path, rows, columns=None):
    """``sweep.csv``: ``columns`` (default :data:`SWEEP_COLUMNS`) of every row (None ->
    an empty cell), atomically; returns the path."""
    from .files import write_rows

    columns = SWEEP_COLUMNS if columns is None else columns
    return write_rows(path, columns, (["" if row.get(k) is None else row[k] for k in columns]
                                      for row in rows))


# ---------------------------------------------------------------------------
# tengfield report
REPORT_COLUMNS = ["stage", "setting", "wall_time_s", "error_max", "error_V_oc", "error_Q_sc",
                  "error_I_sc", "error_P_load", "error_V_load", "error_position", "knobs",
                  "reference", "note"]


def format_number(x) -> str:
    """4 significant digits; empty for None, NaN and inf."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return ""
    return f"{x:.4g}"


def report_row_record(row) -> dict:
    """A CSV/JSON record of one :class:`tengfield.accuracy_report.Row`."""
    rec = {"stage": row.stage, "setting": row.setting, "wall_time_s": row.wall_time_s,
           "error_max": row.error, "error_position": row.error_position,
           "knobs": json.dumps(row.knobs, sort_keys=True), "reference": row.reference,
           "note": row.note}
    for q in ("V_oc", "Q_sc", "I_sc", "P_load", "V_load"):
        rec[f"error_{q}"] = row.errors.get(q, math.nan)
    return rec


def write_report_csv(path: str | Path, report) -> Path:
    """``report.csv``: one line per measured row of a :class:`tengfield.accuracy_report.Report`."""
    records = (report_row_record(row) for row in report.rows)
    return write_rows(path, REPORT_COLUMNS, ([format_number(v) if isinstance(v, float) else v
                                              for v in (rec[k] for k in REPORT_COLUMNS)]
                                             for rec in records))


def write_report_json(path: str | Path, report) -> Path:
    """``report.json``: rows (with knobs and errors), references and recommendations."""
    import dataclasses

    data = {"scene": report.scene.source, "fast": report.fast, "wall_time_s": report.wall_time_s,
            "references": report.references, "trajectory": report.trajectory,
            "rows": [report_row_record(r) | {"knobs": r.knobs, "errors": r.errors}
                     for r in report.rows],
            "recommendations": [dataclasses.asdict(r) for r in report.recommendations]}
    return write_json(path, data)


# ---------------------------------------------------------------------------
# a 3D run (tengfield.dynamics.motion3d): trajectory.csv with its extra columns, contacts.csv


